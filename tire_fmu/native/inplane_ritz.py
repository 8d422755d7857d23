"""The Ritz basis of the reduced in-plane step built in C (``native/c/inplane_ritz.c``), through
ctypes.

:func:`c_ritz_basis` spans what :func:`~tire_fmu.core.inplane_contact.ritz_basis` spans (the
held ring's modes at rest up to ``f_max_hz`` and the zone nodes' static shapes, orthonormal, of
scipy.linalg.orth's rank), from the ring's M and K built in C (:mod:`.inplane_ring`); the
columns differ (modes by Fourier order, then the statics' remainder), the subspace does not:
tests/test_inplane_ritz_c.py holds the two to rounding. :func:`c_ritz_basis_of` takes the
matrices from elsewhere (the Python ring's, for what the C ring does not build yet). The library
is the step kernel's (:mod:`.kernel`).
"""

from __future__ import annotations

import ctypes

import numpy as np

from ..core.inplane import InPlaneTire
from .inplane_ring import c_inplane_ring, n_fields
from .kernel import load_library

_WHY_SIZE = 1024


def _declare(lib) -> None:
    if getattr(lib, "_inplane_ritz_declared", False):
        return
    lib.inplane_ritz_work_doubles.restype = ctypes.c_size_t
    lib.inplane_ritz_work_doubles.argtypes = [ctypes.c_int] * 3
    lib.inplane_ritz_build.restype = ctypes.c_int
    lib.inplane_ritz_build.argtypes = [
        ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int, ctypes.c_int, ctypes.c_void_p,
        ctypes.c_int, ctypes.c_double, ctypes.c_int, ctypes.c_void_p,
        ctypes.POINTER(ctypes.c_int), ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t]
    lib._inplane_ritz_declared = True


def c_ritz_basis_of(mass: np.ndarray, stiffness: np.ndarray, n_elements: int, fields: int,
                    zone_nodes, f_max_hz: float, library=None) -> np.ndarray:
    """The basis (DOFs x rank) of the held ring at rest whose dense ``mass`` and ``stiffness``
    are given (``fields`` N x ``fields`` N); ValueError with the C's sentence (parameter, value,
    allowed) when it refuses them."""
    lib = load_library() if library is None else library
    _declare(lib)
    nodes = np.ascontiguousarray(np.asarray(zone_nodes).ravel(), dtype=np.intc)
    mass = np.ascontiguousarray(mass, dtype=float)
    stiffness = np.ascontiguousarray(stiffness, dtype=float)
    n_dof = int(fields) * int(n_elements)
    if mass.shape != (n_dof, n_dof) or stiffness.shape != (n_dof, n_dof):
        raise ValueError(f"mass {mass.shape}, stiffness {stiffness.shape}: allowed "
                         f"({n_dof}, {n_dof}) each (fields x n_elements DOFs)")
    work = np.empty(max(lib.inplane_ritz_work_doubles(int(n_elements), int(fields),
                                                      nodes.size), 1))
    basis = np.empty((max(n_dof, 1), max(n_dof, 1)))  # the rank is at most n_dof
    count = ctypes.c_int(-1)
    why = ctypes.create_string_buffer(_WHY_SIZE)
    status = lib.inplane_ritz_build(
        mass.ctypes.data, stiffness.ctypes.data, int(n_elements), int(fields),
        nodes.ctypes.data if nodes.size else None, nodes.size, float(f_max_hz), n_dof,
        basis.ctypes.data, ctypes.byref(count), work.ctypes.data, why, _WHY_SIZE)
    if status:
        raise ValueError(f"inplane_ritz_build refused the basis (status {status}): "
                         f"{why.value.decode(errors='replace')}")
    return basis[: count.value].T.copy()


def c_ritz_basis(model: InPlaneTire, n_elements: int, zone_nodes, f_max_hz: float,
                 library=None) -> np.ndarray:
    """:func:`~tire_fmu.core.inplane_contact.ritz_basis`'s subspace, from the C ring's M and K
    at rest with the rim held (the hysteretic loss has no share at rest)."""
    ring = c_inplane_ring(model, n_elements, 0.0, False, hysteresis=False, library=library)
    return c_ritz_basis_of(ring.mass, ring.stiffness, n_elements, n_fields(model), zone_nodes,
                           f_max_hz, library)
