"""The in-plane step's spin terms built in C (``native/c/inplane_terms.c``), through ctypes.

:func:`c_spin_terms` gives what :class:`~tire_fmu.core.inplane_contact.InPlaneSimulator`'s
``_build`` makes between the ring and the points: the spin's polynomial terms on the step's
coordinates (``_spin_terms``), the mass (``_m``), ``_to_abs``, the rim's inertia
(``_rim_inertia``) and the rim's rows (``_rim_rows``), from the C ring at spins 0, 1, 2 rad/s
projected on the simulator's basis; tests/test_inplane_terms_c.py holds the two to rounding.
The library is the step kernel's (:mod:`.kernel`).
"""

from __future__ import annotations

import ctypes

import numpy as np

from ..core.inplane import InPlaneTire
from .inplane_ring import InPlaneRingData, n_fields, ring_data
from .kernel import load_library

_WHY_SIZE = 512
#: InPlaneTermsOutput's fields in inplane_terms.h's order; "rim_" ones are _rim_rows' entries
OUTPUT_FIELDS = ("m", "c0", "c1", "k0", "k1", "k2", "kh", "to_abs", "rim_inertia", "rim_k0",
                 "rim_k1", "rim_k2", "rim_kh", "rim_c0", "rim_c1", "rim_m",
                 "rim_m_translation")
SPIN_TERMS = ("c0", "c1", "k0", "k1", "k2", "kh")
RIM_ROWS = ("k0", "k1", "k2", "kh", "c0", "c1", "m", "m_translation")


class InPlaneTermsOutput(ctypes.Structure):
    _fields_ = [(name, ctypes.c_void_p) for name in OUTPUT_FIELDS]


def _declare(lib) -> None:
    if getattr(lib, "_inplane_terms_declared", False):
        return
    lib.inplane_terms_ny.restype = ctypes.c_size_t
    lib.inplane_terms_ny.argtypes = [ctypes.c_int] * 4
    lib.inplane_terms_work_doubles.restype = ctypes.c_size_t
    lib.inplane_terms_work_doubles.argtypes = [ctypes.c_int] * 4
    lib.inplane_terms_build.restype = ctypes.c_int
    lib.inplane_terms_build.argtypes = [
        ctypes.POINTER(InPlaneRingData), ctypes.c_int, ctypes.c_int, ctypes.c_int,
        ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(InPlaneTermsOutput), ctypes.c_void_p,
        ctypes.c_char_p, ctypes.c_size_t]
    lib._inplane_terms_declared = True


def c_spin_terms_of(model: InPlaneTire, n_elements: int, free_spin: bool,
                    basis: np.ndarray | None = None, library=None) -> dict:
    """The terms on ``basis`` (ring DOFs x columns, psi not in it: it is appended with the
    wheel free) or on every ring DOF (None): a dict with the simulator's ``_spin_terms`` keys,
    'm', 'to_abs', 'rim_inertia' and 'rim_rows' (the ``_rim_rows`` dict). ValueError with the
    C's sentence (parameter, value, allowed) when it refuses them."""
    lib = load_library() if library is None else library
    _declare(lib)
    fields, n = n_fields(model), int(n_elements)
    free = int(bool(free_spin))
    if basis is not None:
        basis = np.ascontiguousarray(basis, dtype=float)
        if basis.ndim != 2 or basis.shape[0] != fields * n:
            raise ValueError(f"basis of shape {basis.shape}: allowed ({fields * n}, columns) "
                             "(the ring's rim-relative DOFs)")
    n_basis = 0 if basis is None else basis.shape[1]
    ny = lib.inplane_terms_ny(n, fields, free, n_basis)
    n_dof = fields * n + 3
    shapes = {name: (ny, ny) for name in ("m",) + SPIN_TERMS}
    shapes |= {"to_abs": (n_dof, ny), "rim_inertia": (ny, 2), "rim_m_translation": (3, 2)}
    shapes |= {f"rim_{name}": (3, n_dof) for name in RIM_ROWS[:-1]}
    arrays = {name: np.zeros(tuple(max(s, 1) for s in shapes[name])) for name in OUTPUT_FIELDS}
    out = InPlaneTermsOutput(*(arrays[name].ctypes.data for name in OUTPUT_FIELDS))
    work = np.empty(max(lib.inplane_terms_work_doubles(n, fields, free, n_basis), 1))
    why = ctypes.create_string_buffer(_WHY_SIZE)
    status = lib.inplane_terms_build(
        ctypes.byref(ring_data(model)), n, fields, free,
        None if basis is None else basis.ctypes.data, n_basis, ctypes.byref(out),
        work.ctypes.data, why, _WHY_SIZE)
    if status:
        raise ValueError(f"inplane_terms_build refused the terms (status {status}): "
                         f"{why.value.decode(errors='replace')}")
    terms = {name: arrays[name] for name in ("m", "to_abs", "rim_inertia") + SPIN_TERMS}
    terms["rim_rows"] = {name: arrays[f"rim_{name}"] for name in RIM_ROWS}
    return terms


def c_spin_terms(sim, library=None) -> dict:
    """:func:`c_spin_terms_of` for a built InPlaneSimulator: its model, mesh, wheel and basis
    (``sim._basis`` less the psi it appends)."""
    basis = None
    if sim._basis is not None:
        nr = n_fields(sim.model) * sim.n_elements
        basis = sim._basis[:nr, : sim._n_ring_coords]
    return c_spin_terms_of(sim.model, sim.n_elements, sim.wheel == "free", basis, library)
