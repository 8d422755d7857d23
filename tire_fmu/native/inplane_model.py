"""The reduced in-plane step's whole set-up in one C call (``native/c/inplane_model.c``),
through ctypes.

:func:`c_inplane_model` runs what tests/test_inplane_c_assembly.py's CAssembled assembles
brick by brick (zone nodes, Ritz basis, spin terms, points at rest, deflection for the load,
points at it, the step's matrices at the spin) as the one call a native FMU makes at
initialisation, and returns copies of every array it built (the C model is freed before it
returns); tests/test_inplane_model_c.py holds them to CAssembled's. The library is the step
kernel's (:mod:`.kernel`).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from ..core.inplane import InPlaneTire
from .inplane_build import _RING, _TREAD, InPlaneBuildInput, InPlaneBuildOutput
from .inplane_points import JACOBIANS, POINT_DATA, InPlanePoints
from .inplane_ring import InPlaneRingData, n_fields, ring_data
from .inplane_terms import OUTPUT_FIELDS, InPlaneTermsOutput
from .kernel import load_library

_WHY_SIZE = 2048
_P = ctypes.POINTER(ctypes.c_double)


class InPlaneModelInput(ctypes.Structure):
    """inplane_model.h's InPlaneModelInput."""
    _fields_ = ([("tire", InPlaneRingData), ("k_cw", ctypes.c_double)]
                + [(name, ctypes.c_int) for name in ("n_elements", "n_fields", "wheel_free")]
                + [(name, ctypes.c_double) for name in (
                    "f_max_hz", "zone_length_m", "point_spacing_m", "load_n", "speed_m_s",
                    "spin_rad_s", "step_s")]
                + [("driven", ctypes.c_int)])


class InPlaneModel(ctypes.Structure):
    """inplane_model.h's InPlaneModel."""
    _fields_ = ([(name, ctypes.c_int) for name in ("n_elements", "n_fields", "wheel_free",
                                                   "n_dof", "n_basis", "ny", "np", "n_zone")]
                + [("zone_nodes", ctypes.POINTER(ctypes.c_int)), ("basis", _P),
                   ("terms", InPlaneTermsOutput), ("deflection_m", ctypes.c_double),
                   ("secant_iterations", ctypes.c_int), ("static_y", _P), ("rim_fz_row", _P),
                   ("points", InPlanePoints), ("point_theta", _P),
                   ("build_in", InPlaneBuildInput), ("build", InPlaneBuildOutput),
                   ("mem", ctypes.c_void_p)])


@dataclass(frozen=True)
class ModelArrays:
    """Copies of the one call's arrays: ``terms`` by inplane_terms.h's names (rim rows as
    ``rim_<name>``), ``points`` by inplane_points.h's, ``build`` by inplane_build.h's output
    names (with carry_base, and the scalars ring_spin, ring_share, carry_shift, spin_now)."""
    zone_nodes: np.ndarray
    basis: np.ndarray
    deflection_m: float
    secant_iterations: int
    static_y: np.ndarray
    rim_fz_row: np.ndarray
    point_theta: np.ndarray
    terms: dict
    points: dict
    build: dict
    n_ring_coords: int


def _declare(lib) -> None:
    if getattr(lib, "_inplane_model_declared", False):
        return
    lib.inplane_model_build.restype = ctypes.c_int
    lib.inplane_model_build.argtypes = [ctypes.POINTER(InPlaneModelInput),
                                        ctypes.POINTER(InPlaneModel), ctypes.c_void_p,
                                        ctypes.c_char_p, ctypes.c_size_t]
    lib.inplane_model_free.restype = None
    lib.inplane_model_free.argtypes = [ctypes.POINTER(InPlaneModel)]
    lib._inplane_model_declared = True


def _copy(pointer, shape, dtype=np.float64) -> np.ndarray:
    count = int(np.prod(shape))
    kind = ctypes.c_int if dtype == np.int32 else ctypes.c_double
    buffer = ctypes.cast(pointer, ctypes.POINTER(kind * count)).contents
    return np.frombuffer(buffer, dtype=dtype, count=count).reshape(shape).copy()


def model_input(model: InPlaneTire, n_elements: int, *, f_max_hz: float, zone_length_m: float,
                point_spacing_m: float, load_n: float, speed_m_s: float, spin_rad_s: float,
                step_s: float, wheel_free: bool, driven: bool = False) -> InPlaneModelInput:
    return InPlaneModelInput(ring_data(model), float(model.tire.k_cw), int(n_elements),
                             n_fields(model), int(bool(wheel_free or driven)), float(f_max_hz),
                             float(zone_length_m), float(point_spacing_m), float(load_n),
                             float(speed_m_s), float(spin_rad_s), float(step_s),
                             int(bool(driven)))


def build_model(inputs: InPlaneModelInput, library=None) -> tuple[int, str, InPlaneModel]:
    """The raw call: (status, why, the model); the caller frees a built model with
    ``library.inplane_model_free``."""
    lib = load_library() if library is None else library
    _declare(lib)
    out = InPlaneModel()
    why = ctypes.create_string_buffer(_WHY_SIZE)
    status = lib.inplane_model_build(ctypes.byref(inputs), ctypes.byref(out), None, why,
                                     _WHY_SIZE)
    return status, why.value.decode(errors="replace"), out


def c_inplane_model(model: InPlaneTire, n_elements: int, *, f_max_hz: float,
                    zone_length_m: float, point_spacing_m: float, load_n: float,
                    speed_m_s: float, spin_rad_s: float, step_s: float, wheel_free: bool,
                    library=None) -> ModelArrays:
    """The one call's arrays (copies). ValueError with the refusing brick's sentence
    (parameter, value, allowed)."""
    lib = load_library() if library is None else library
    inputs = model_input(model, n_elements, f_max_hz=f_max_hz, zone_length_m=zone_length_m,
                         point_spacing_m=point_spacing_m, load_n=load_n, speed_m_s=speed_m_s,
                         spin_rad_s=spin_rad_s, step_s=step_s, wheel_free=wheel_free)
    status, why, out = build_model(inputs, lib)
    if status:
        raise ValueError(f"inplane_model_build refused the model (status {status}): {why}")
    try:
        return _arrays(out)
    finally:
        lib.inplane_model_free(ctypes.byref(out))


def _arrays(out: InPlaneModel) -> ModelArrays:
    ny, p, r, nd = out.ny, out.np, out.n_basis, out.n_dof
    nd3 = nd + 3
    shapes = {name: (ny, ny) for name in ("m", "c0", "c1", "k0", "k1", "k2", "kh")}
    shapes |= {"to_abs": (nd3, ny), "rim_inertia": (ny, 2), "rim_m_translation": (3, 2)}
    terms = {name: _copy(getattr(out.terms, name), shapes.get(name, (3, nd3)))
             for name in OUTPUT_FIELDS}
    points = {name: _copy(getattr(out.points, name), (p, ny)) for name in JACOBIANS}
    points |= {name: _copy(getattr(out.points, name), (p,)) for name in POINT_DATA}
    sizes = {"yy": (ny, ny), "yp": (ny, p), "py": (p, ny), "pp": (p, p), "p4": (p, 4)}
    build = {name: _copy(getattr(out.build, name), sizes[shape]) for name, shape in
             _RING + _TREAD}
    build["carry_base"] = _copy(out.build.carry_base, (p,), np.int32)
    for name in ("ring_spin", "ring_share", "carry_shift", "spin_now"):
        build[name] = getattr(out.build, name)
    return ModelArrays(
        zone_nodes=_copy(out.zone_nodes, (out.n_zone,), np.int32),
        basis=_copy(out.basis, (nd + out.wheel_free, ny)), deflection_m=out.deflection_m,
        secant_iterations=out.secant_iterations, static_y=_copy(out.static_y, (r,)),
        rim_fz_row=_copy(out.rim_fz_row, (r,)), point_theta=_copy(out.point_theta, (p,)),
        terms=terms, points=points, build=build, n_ring_coords=r)
