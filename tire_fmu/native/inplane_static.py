"""The in-plane tire's static footprint computed in C (``native/c/inplane_static.c``), through
ctypes.

:func:`c_static_state`, :func:`c_static_load_n` and :func:`c_deflection_for_load` give what
:meth:`~tire_fmu.core.inplane_contact.InPlaneSimulator.static_state`,
:meth:`~tire_fmu.core.inplane_contact.InPlaneSimulator.static_load_n` and
:func:`~tire_fmu.core.inplane_contact.deflection_for_load` give, from a built simulator's
matrices at rest (its ring coordinates' K, Jn, the points' kn and sec θ, R and the rim's Fz
row); tests/test_inplane_static_c.py holds the two to 1e-12. The library is the step
kernel's (:mod:`.kernel`).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from ..core.inplane_contact import MAX_SET_PASSES, ContactSetError, InPlaneSimulator
from .kernel import load_library

#: inplane_static.h's status for a set that did not settle
UNSETTLED = 7
_WHY_SIZE = 512
_DOUBLE_P = ctypes.POINTER(ctypes.c_double)


class InPlaneStaticData(ctypes.Structure):
    """inplane_static.h's InPlaneStaticData."""

    _fields_ = [("n_coords", ctypes.c_int), ("n_points", ctypes.c_int),
                ("stiffness", _DOUBLE_P), ("jn", _DOUBLE_P), ("kn", _DOUBLE_P),
                ("sec", _DOUBLE_P), ("rim_fz_row", _DOUBLE_P), ("radius_m", ctypes.c_double),
                ("max_passes", ctypes.c_int)]


@dataclass(frozen=True)
class StaticFootprint:
    """The C's static state: the ring coordinates' y, the points pushing, the rim's load (N)
    and the active-set passes taken."""

    y: np.ndarray
    active: np.ndarray
    load_n: float
    passes: int


@dataclass(frozen=True)
class DeflectionSearch:
    """The C's deflection for a load (m), the secant's iterations, and the static state at
    the deflection (as :class:`StaticFootprint`'s y and active)."""

    deflection_m: float
    iterations: int
    y: np.ndarray
    active: np.ndarray


def _declare(lib) -> None:
    if getattr(lib, "_inplane_static_declared", False):
        return
    for name in ("inplane_static_work_doubles", "inplane_static_work_ints"):
        getattr(lib, name).restype = ctypes.c_size_t
        getattr(lib, name).argtypes = [ctypes.c_int] * 2
    lib.inplane_static_state.restype = ctypes.c_int
    lib.inplane_static_state.argtypes = [
        ctypes.POINTER(InPlaneStaticData), ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p,
        ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_int), ctypes.c_void_p,
        ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t]
    lib.inplane_deflection_for_load.restype = ctypes.c_int
    lib.inplane_deflection_for_load.argtypes = [
        ctypes.POINTER(InPlaneStaticData), ctypes.c_double, ctypes.POINTER(ctypes.c_double),
        ctypes.POINTER(ctypes.c_int), ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
        ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t]
    lib._inplane_static_declared = True


class _Footprint:
    """The simulator's arrays at rest, laid out for the C (kept alive with the struct)."""

    def __init__(self, sim: InPlaneSimulator, lib):
        nr = sim._n_ring_coords
        rest = sim.spin_total_rad_s(np.zeros(sim._ny))  # the spin static_load_n reads at
        self.arrays = [np.ascontiguousarray(a, dtype=float) for a in (
            sim._k[:nr, :nr], sim._jn[:, :nr], sim._kn, sim._sec,
            sim.rim_force_rows(rest)[0][1, :nr])]
        self.n_coords, self.n_points = nr, len(sim._kn)
        pointers = [a.ctypes.data_as(_DOUBLE_P) for a in self.arrays]
        self.data = InPlaneStaticData(nr, self.n_points, *pointers, float(sim.model.tire.R),
                                      MAX_SET_PASSES)
        self.work = np.empty(max(lib.inplane_static_work_doubles(nr, self.n_points), 1))
        self.iwork = np.empty(max(lib.inplane_static_work_ints(nr, self.n_points), 1),
                              dtype=np.intc)


def _raise(status: int, why, function: str):
    text = why.value.decode(errors="replace")
    if status == UNSETTLED:
        raise ContactSetError("the static footprint did not settle")
    raise ValueError(f"{function} refused the input (status {status}): {text}")


def c_static_footprint(sim: InPlaneSimulator, deflection_m: float | None = None,
                       library=None) -> StaticFootprint:
    """The C's static state of ``sim`` at ``deflection_m`` (default: the simulator's): y on
    the ring coordinates, the set, the load and the passes. ValueError with the C's sentence
    for bad input; ContactSetError, as the core's, for a set that does not settle."""
    lib = load_library() if library is None else library
    _declare(lib)
    foot = _Footprint(sim, lib)
    d = sim.deflection_m if deflection_m is None else deflection_m
    y = np.empty(foot.n_coords)
    active = np.empty(foot.n_points, dtype=np.intc)
    load, passes = ctypes.c_double(np.nan), ctypes.c_int(0)
    why = ctypes.create_string_buffer(_WHY_SIZE)
    status = lib.inplane_static_state(ctypes.byref(foot.data), float(d), y.ctypes.data,
                                      active.ctypes.data, ctypes.byref(load),
                                      ctypes.byref(passes), foot.work.ctypes.data,
                                      foot.iwork.ctypes.data, why, _WHY_SIZE)
    if status:
        _raise(status, why, "inplane_static_state")
    return StaticFootprint(y, active.astype(bool), load.value, passes.value)


def c_static_state(sim: InPlaneSimulator, deflection_m: float | None = None,
                   library=None) -> np.ndarray:
    """``sim.static_state(deflection_m)`` computed by the C (on all the simulator's
    coordinates: a free wheel's turn is 0)."""
    out = np.zeros(sim._ny)
    out[: sim._n_ring_coords] = c_static_footprint(sim, deflection_m, library).y
    return out


def c_static_load_n(sim: InPlaneSimulator, deflection_m: float | None = None,
                    library=None) -> float:
    """``sim.static_load_n(deflection_m)`` computed by the C (N)."""
    return c_static_footprint(sim, deflection_m, library).load_n


def c_deflection_search(sim: InPlaneSimulator, load_n: float, library=None
                        ) -> DeflectionSearch:
    """The deflection carrying ``load_n`` at rest on ``sim`` (built at rest, as
    ``deflection_for_load`` builds its own) by the C's secant, with its iterations and the
    static state there."""
    lib = load_library() if library is None else library
    _declare(lib)
    foot = _Footprint(sim, lib)
    deflection, iterations = ctypes.c_double(np.nan), ctypes.c_int(0)
    y = np.empty(foot.n_coords)
    active = np.empty(foot.n_points, dtype=np.intc)
    why = ctypes.create_string_buffer(_WHY_SIZE)
    status = lib.inplane_deflection_for_load(ctypes.byref(foot.data), float(load_n),
                                             ctypes.byref(deflection),
                                             ctypes.byref(iterations), y.ctypes.data,
                                             active.ctypes.data, foot.work.ctypes.data,
                                             foot.iwork.ctypes.data, why, _WHY_SIZE)
    if status:
        _raise(status, why, "inplane_deflection_for_load")
    return DeflectionSearch(deflection.value, iterations.value, y, active.astype(bool))


def c_deflection_for_load(sim: InPlaneSimulator, load_n: float, library=None) -> float:
    """``deflection_for_load`` computed by the C on ``sim`` (m)."""
    return c_deflection_search(sim, load_n, library).deflection_m
