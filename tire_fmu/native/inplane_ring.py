"""The in-plane ring's matrices built in C (``native/c/inplane_ring.c``), through ctypes.

:func:`c_inplane_ring` gives what :class:`~tire_fmu.core.inplane.InPlaneRing` gives for
``.mass``, ``.stiffness``, ``.damping`` and ``.hysteretic_stiffness`` (the radial sidewall's
tie and the hysteretic loss included), from the C a native in-plane FMU builds them with at
initialisation; tests/test_inplane_ring_c.py holds the two to rounding. The library is the step
kernel's (:mod:`.kernel`).
"""

from __future__ import annotations

import ctypes
from typing import NamedTuple

import numpy as np

from ..core.inplane import InPlaneTire
from .kernel import load_library

#: The struct's fields, in inplane_ring.h's order: TireParameters' the ring reads, then every
#: TangentialParameters field.
TIRE_FIELDS = ("R", "b", "inflation_pressure", "rhoA", "m_s", "k_r1", "k_r2", "EI", "alpha",
               "beta", "sidewall_pressure_exponent", "reference_pressure", "sidewall_max_order")
TANGENTIAL_FIELDS = ("EA", "k_t1", "k_t2", "rim_radius_m", "wheel_mass_kg",
                     "wheel_inertia_kg_m2", "k_tx", "friction_coefficient", "loss_factor")
_WHY_SIZE = 512


class InPlaneRingData(ctypes.Structure):
    _fields_ = [(name, ctypes.c_double) for name in TIRE_FIELDS + TANGENTIAL_FIELDS]


class RingMatrices(NamedTuple):
    """The C's matrices, named as InPlaneRing's attributes (each n_dof x n_dof)."""

    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    #: the hysteretic loss at full share (zero without one); the stiffness holds its share
    hysteretic_stiffness: np.ndarray


def _declare(lib) -> None:
    if getattr(lib, "_inplane_ring_declared", False):
        return
    lib.inplane_ring_n_dof.restype = ctypes.c_size_t
    lib.inplane_ring_n_dof.argtypes = [ctypes.c_int] * 3
    lib.inplane_ring_work_doubles.restype = ctypes.c_size_t
    lib.inplane_ring_work_doubles.argtypes = [ctypes.c_int] * 2
    lib.inplane_ring_build.restype = ctypes.c_int
    lib.inplane_ring_build.argtypes = [
        ctypes.POINTER(InPlaneRingData), ctypes.c_int, ctypes.c_int, ctypes.c_double,
        ctypes.c_int, ctypes.c_int] + [ctypes.c_void_p] * 5 + [ctypes.c_char_p,
                                                                ctypes.c_size_t]
    lib._inplane_ring_declared = True


def n_fields(model: InPlaneTire) -> int:
    """inplane_ring.h's field count of the model's sidewall: 2 massless, 3 tied, 4 lumped."""
    if not model.sidewall_mass:
        return 2
    return 3 if model.sidewall_tangential == "tied" else 4


def ring_data(model: InPlaneTire) -> InPlaneRingData:
    values = [getattr(model.tire, name) for name in TIRE_FIELDS]
    values += [getattr(model.tangential, name) for name in TANGENTIAL_FIELDS]
    return InPlaneRingData(*(float(v) for v in values))


def c_inplane_ring(model: InPlaneTire, n_elements: int, spin_rad_s: float = 0.0,
                   rim_free: bool = False, hysteresis: bool = True,
                   library=None) -> RingMatrices:
    """The matrices of ``InPlaneRing(model, n_elements, spin_rad_s, rim_free, hysteresis)``
    built by the C; ValueError with the C's sentence (parameter, value, allowed) when it
    refuses them."""
    lib = load_library() if library is None else library
    _declare(lib)
    fields = n_fields(model)
    n = lib.inplane_ring_n_dof(int(n_elements), fields, int(bool(rim_free)))
    work_size = lib.inplane_ring_work_doubles(int(n_elements), fields)
    work = np.empty(max(work_size, 1))
    matrices = [np.empty((max(n, 1), max(n, 1))) for _ in range(4)]
    why = ctypes.create_string_buffer(_WHY_SIZE)
    status = lib.inplane_ring_build(
        ctypes.byref(ring_data(model)), int(n_elements), fields, float(spin_rad_s),
        int(bool(rim_free)), int(bool(hysteresis)), *(m.ctypes.data for m in matrices),
        work.ctypes.data, why, _WHY_SIZE)
    if status:
        raise ValueError(f"inplane_ring_build refused the ring (status {status}): "
                         f"{why.value.decode(errors='replace')}")
    return RingMatrices(*matrices)
