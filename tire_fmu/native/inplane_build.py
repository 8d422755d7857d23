"""The in-plane step's matrices at a spin built in C (``native/c/inplane_build.c``), through
ctypes.

:func:`c_step_matrices` builds what an
:class:`~tire_fmu.core.inplane_contact.InPlaneSimulator`'s ``_set_spin`` builds (the ring's
C, K, the step's inverse and the points' responses; the tread's gain, force and carry) from
the inputs its ``_build`` prepared, with the C a native in-plane FMU can rebuild its step with
as the wheel's spin moves; tests/test_inplane_build_c.py holds the two together. The library
is the step kernel's (:mod:`.kernel`).
"""

from __future__ import annotations

import ctypes

import numpy as np

from .kernel import load_library

_P = ctypes.POINTER(ctypes.c_double)
_WHY_SIZE = 512
#: the input's arrays, in inplane_build.h's order: on the simulator, with their source
_TERMS = ("c0", "c1", "k0", "k1", "k2", "kh")
_POINT_MATRICES = ("jn", "jnw", "jxw", "jl")
#: the output's arrays (name, shape: "yy", "yp", "py", "pp", "p4")
_RING = (("c", "yy"), ("k", "yy"), ("c1", "yy"), ("k1s", "yy"), ("k2", "yy"), ("kh", "yy"),
         ("a0_inv", "yy"), ("yn", "yp"), ("yx", "yp"), ("wnn", "pp"), ("wnx", "pp"),
         ("kg_a", "py"), ("kg_b", "py"), ("kgn_a", "pp"), ("kgn_b", "pp"), ("kgx_a", "pp"),
         ("kgx_b", "pp"))
_TREAD = (("gain", "py"), ("kg", "py"), ("kgn", "pp"), ("kgx", "pp"), ("carry", "pp"),
          ("carry_weights", "p4"))


class InPlaneBuildInput(ctypes.Structure):
    _fields_ = ([(name, ctypes.c_int) for name in ("ny", "np", "hysteretic")]
                + [(name, ctypes.c_double) for name in ("h", "radius_m")]
                + [(name, _P) for name in ("m", *_TERMS, *_POINT_MATRICES, "kx", "cx",
                                           "point_theta")]
                + [("driven", ctypes.c_int)])


class InPlaneBuildOutput(ctypes.Structure):
    _fields_ = ([(name, _P) for name, _ in _RING]
                + [(name, ctypes.c_double) for name in ("ring_spin", "ring_share")]
                + [(name, _P) for name, _ in _TREAD]
                + [("carry_base", ctypes.POINTER(ctypes.c_int))]
                + [(name, ctypes.c_double) for name in ("carry_shift", "spin_now")]
                + [("a0_psi", _P)])


def _declare(lib) -> None:
    if getattr(lib, "_inplane_build_declared", False):
        return
    lib.inplane_build_work_doubles.restype = ctypes.c_size_t
    lib.inplane_build_work_doubles.argtypes = [ctypes.c_int] * 2
    lib.inplane_build_work_ints.restype = ctypes.c_size_t
    lib.inplane_build_work_ints.argtypes = [ctypes.c_int]
    for name, scratch in (("inplane_build", True), ("inplane_build_ring", True),
                          ("inplane_build_tread", False)):
        function = getattr(lib, name)
        function.restype = ctypes.c_int
        function.argtypes = ([ctypes.POINTER(InPlaneBuildInput), ctypes.c_double,
                              ctypes.POINTER(InPlaneBuildOutput)]
                             + [ctypes.c_void_p] * (2 if scratch else 0)
                             + [ctypes.c_char_p, ctypes.c_size_t])
    lib._inplane_build_declared = True


def build_input(sim) -> tuple[InPlaneBuildInput, list]:
    """The C's input from a simulator's attributes, and the arrays it points into (keep them
    alive as long as the input)."""
    terms = sim._spin_terms
    arrays = [np.ascontiguousarray(a, dtype=np.float64) for a in (
        sim._m, *(terms[name] for name in _TERMS),
        sim._jn, sim._jnw, sim._jxw, sim._jl, sim._kx, sim._cx, sim._zone.point_theta)]
    data = InPlaneBuildInput(int(sim._ny), int(sim._zone.n_points),
                             int(bool(sim.model.tangential.loss_factor)), float(sim.step_length_s),
                             float(sim.model.tire.R), *(a.ctypes.data_as(_P) for a in arrays),
                             int(getattr(sim, "_driven", False)))
    return data, arrays


def output_arrays(ny: int, n_points: int) -> dict:
    """Zeroed arrays for every output (the C writes all of them)."""
    shapes = {"yy": (ny, ny), "yp": (ny, n_points), "py": (n_points, ny),
              "pp": (n_points, n_points), "p4": (n_points, 4)}
    arrays = {name: np.zeros(shapes[shape]) for name, shape in _RING + _TREAD}
    arrays["carry_base"] = np.zeros(n_points, dtype=np.int32)
    arrays["a0_psi"] = np.zeros(ny)
    return arrays


def build_output(arrays: dict) -> InPlaneBuildOutput:
    out = InPlaneBuildOutput()
    for name, _ in _RING + _TREAD:
        setattr(out, name, arrays[name].ctypes.data_as(_P))
    out.carry_base = arrays["carry_base"].ctypes.data_as(ctypes.POINTER(ctypes.c_int))
    if "a0_psi" in arrays:  # read with a driven wheel only
        out.a0_psi = arrays["a0_psi"].ctypes.data_as(_P)
    return out


def c_step_matrices(sim, spin_rad_s: float, library=None) -> dict:
    """What ``sim._set_spin(spin_rad_s, speed)`` builds, computed by the C from ``sim``'s
    inputs: a dict named as the simulator's attributes without the underscore (c, k, c1, k1s,
    k2, kh, a0_inv, yn, yx, wnn, wnx, kg_parts, kgn_parts, kgx_parts, ring_spin, ring_share,
    gain, kg, kgn, kgx, carry, carry_base, carry_weights, carry_shift, spin_now; a0_psi for a
    driven wheel). ValueError
    with the C's sentence (parameter, value, allowed) when it refuses the input."""
    lib = load_library() if library is None else library
    _declare(lib)
    data, keep = build_input(sim)
    arrays = output_arrays(data.ny, data.np)
    out = build_output(arrays)
    work = np.zeros(max(lib.inplane_build_work_doubles(data.ny, data.np), 1))
    iwork = np.zeros(max(lib.inplane_build_work_ints(data.ny), 1), dtype=np.int32)
    why = ctypes.create_string_buffer(_WHY_SIZE)
    status = lib.inplane_build(ctypes.byref(data), float(spin_rad_s), ctypes.byref(out),
                               work.ctypes.data, iwork.ctypes.data, why, _WHY_SIZE)
    del keep
    if status:
        raise ValueError(f"inplane_build refused the step's inputs (status {status}): "
                         f"{why.value.decode(errors='replace')}")
    result = {name: arrays[name] for name, _ in _RING + _TREAD if name[-2:] not in ("_a", "_b")}
    for name in ("kg", "kgn", "kgx"):
        result[name + "_parts"] = (arrays[name + "_a"], arrays[name + "_b"])
    result["carry_base"] = arrays["carry_base"]
    if data.driven:
        result["a0_psi"] = arrays["a0_psi"]
    for name in ("ring_spin", "ring_share", "carry_shift", "spin_now"):
        result[name] = getattr(out, name)
    return result
