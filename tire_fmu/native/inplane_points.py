"""The in-plane simulator's point Jacobians and point data computed in C
(``native/c/inplane_points.c``), through ctypes.

:func:`c_point_data` gives what
:class:`~tire_fmu.core.inplane_contact.InPlaneSimulator` builds for its contact points (its
``_jn``, ``_jx``, ``_jnw``, ``_jxw``, ``_jl``, ``_kn``, ``_cn``, ``_kx``, ``_cx``, ``_pen0``,
``_sec`` and ``_s0``) from the simulator's inputs alone: the mesh, the tire's k_cw, β, k_tx,
the zone, the spacing, the deflection, the wheel, the speed and spin, and the basis it steps
on. tests/test_inplane_points_c.py holds the two together. The library is the step kernel's
(:mod:`.kernel`).
"""

from __future__ import annotations

import ctypes

import numpy as np

from ..core.inplane_contact import InPlaneSimulator
from .kernel import load_library

_WHY_SIZE = 512
_DOUBLE_P = ctypes.POINTER(ctypes.c_double)
#: the Jacobians (points x coordinates) and the per-point data, in InPlanePoints' order
JACOBIANS = ("jn", "jx", "jnw", "jxw", "jl")
POINT_DATA = ("kn", "cn", "kx", "cx", "pen0", "sec", "s0")


class InPlanePointsInput(ctypes.Structure):
    """inplane_points.h's InPlanePointsInput."""

    _fields_ = [("n_elements", ctypes.c_int), ("n_fields", ctypes.c_int),
                ("wheel_free", ctypes.c_int), ("n_coords", ctypes.c_int),
                ("basis", _DOUBLE_P)] + [(name, ctypes.c_double) for name in (
                    "radius_m", "k_cw", "beta", "k_tx", "zone_length_m", "point_spacing_m",
                    "deflection_m", "speed_m_s", "spin_rad_s")]


class InPlanePoints(ctypes.Structure):
    """inplane_points.h's InPlanePoints."""

    _fields_ = [("n_points", ctypes.c_int)] + [(name, _DOUBLE_P)
                                               for name in JACOBIANS + POINT_DATA]


def _declare(lib) -> None:
    if getattr(lib, "_inplane_points_declared", False):
        return
    lib.inplane_points_count.restype = ctypes.c_int
    lib.inplane_points_count.argtypes = [ctypes.POINTER(InPlanePointsInput),
                                         ctypes.POINTER(ctypes.c_int), ctypes.c_char_p,
                                         ctypes.c_size_t]
    lib.inplane_points_build.restype = ctypes.c_int
    lib.inplane_points_build.argtypes = [ctypes.POINTER(InPlanePointsInput),
                                         ctypes.POINTER(InPlanePoints), ctypes.c_void_p,
                                         ctypes.c_char_p, ctypes.c_size_t]
    lib._inplane_points_declared = True


def simulator_inputs(sim: InPlaneSimulator) -> dict:
    """The C's inputs read off a built simulator (the basis: its own, or the identity on
    every DOF when it steps them all)."""
    t, tang, ring = sim.model.tire, sim.model.tangential, sim._ring
    free = sim._free_spin
    rows = ring.n_ring_dof + (1 if free else 0)
    basis = np.eye(rows) if sim._basis is None else sim._basis
    return {"n_elements": sim.n_elements, "n_fields": ring.n_fields, "wheel_free": int(free),
            "basis": basis, "radius_m": t.R, "k_cw": t.k_cw, "beta": t.beta,
            "k_tx": tang.k_tx, "zone_length_m": sim.zone_length_m,
            "point_spacing_m": sim.point_spacing_m, "deflection_m": sim.deflection_m,
            "speed_m_s": sim._speed_now, "spin_rad_s": sim._spin_now}


def c_points(n_elements: int, n_fields: int, wheel_free: int, basis, radius_m: float,
             k_cw: float, beta: float, k_tx: float, zone_length_m: float,
             point_spacing_m: float, deflection_m: float, speed_m_s: float, spin_rad_s: float,
             library=None) -> dict:
    """The C's point Jacobians (on ``basis``'s columns) and point data, by name. ValueError
    with the C's sentence for bad input."""
    lib = load_library() if library is None else library
    _declare(lib)
    basis = np.ascontiguousarray(basis, dtype=float)
    if basis.ndim != 2:
        raise ValueError(f"basis: {basis.ndim} dimensions; must be a matrix (DOFs x coords)")
    rows = n_fields * n_elements + wheel_free
    if basis.shape[0] != rows:
        raise ValueError(f"basis: {basis.shape[0]} rows; must be {rows} (n_fields x "
                         "n_elements, plus the turn's when the wheel is free)")
    inputs = InPlanePointsInput(int(n_elements), int(n_fields), int(wheel_free),
                                int(basis.shape[1]), basis.ctypes.data_as(_DOUBLE_P),
                                *(float(x) for x in (radius_m, k_cw, beta, k_tx, zone_length_m,
                                                     point_spacing_m, deflection_m, speed_m_s,
                                                     spin_rad_s)))
    why = ctypes.create_string_buffer(_WHY_SIZE)
    count = ctypes.c_int(0)
    status = lib.inplane_points_count(ctypes.byref(inputs), ctypes.byref(count), why,
                                      _WHY_SIZE)
    if status:
        raise ValueError(f"inplane_points_count refused the input (status {status}): "
                         f"{why.value.decode(errors='replace')}")
    p, r = count.value, basis.shape[1]
    out = {name: np.empty((p, r)) for name in JACOBIANS}
    out.update({name: np.empty(p) for name in POINT_DATA})
    points = InPlanePoints(p, *(out[name].ctypes.data_as(_DOUBLE_P)
                                for name in JACOBIANS + POINT_DATA))
    status = lib.inplane_points_build(ctypes.byref(inputs), ctypes.byref(points), None, why,
                                      _WHY_SIZE)
    if status:
        raise ValueError(f"inplane_points_build refused the input (status {status}): "
                         f"{why.value.decode(errors='replace')}")
    return out


def c_point_data(sim: InPlaneSimulator, library=None) -> dict:
    """The C's jn, jx, jnw, jxw, jl, kn, cn, kx, cx, pen0, sec and s0 for ``sim`` (named as
    its attributes without the underscore), from the simulator's inputs."""
    return c_points(**simulator_inputs(sim), library=library)
