"""native/c/inplane_terms.c against InPlaneSimulator._build: for N 50 and 100, the wheel free
and held, reduced (f_max 300 Hz) and on every DOF, for the default tire, the radially tied one
and GL073A_inplane_hysteretic, the spin terms, the mass, to_abs, the rim's inertia and the
rim's rows the C builds on the simulator's basis are the simulator's own.

The tolerance: 1e-12 (the C ring's, tests/test_inplane_ring_c.py) of the largest entry of the
matrix of the array's kind at rest on the coordinates (K terms: k0; C terms: c0; the rest:
their own), since k1, k2 and c1 are differences of the rings at 0, 1, 2 rad/s and lose to the
cancellation what the ring's rounding is of K at rest. Seen over these 24 cases, of each array's
own largest entry: k0 4e-15, k1 1.2e-11, k2 1.2e-7 (K at rest is 2e7 times k2), c0 7e-16, c1
7e-12, kh 4e-15, m 2.5e-16, to_abs 0, rim_inertia 1.3e-15; the rim's rows k0 8.7e-13, k1
3.2e-9, k2 5.7e-7, kh 3.9e-13, c0 1.1e-13, c1 1.7e-16, m 0, m_translation 3.5e-16; of K at
rest on the coordinates each of the K terms is within 1e-14. The C refuses bad input with a
sentence naming the parameter, its value and the allowed range, and writes nothing."""

from __future__ import annotations

import ctypes
import functools
import itertools

import numpy as np
import pytest

from tire_fmu.core.inplane import InPlaneTire
from tire_fmu.core.inplane_contact import InPlaneSimulator
from tire_fmu.core.parameters import TireParameters
from tire_fmu.native.inplane_ring import n_fields, ring_data
from tire_fmu.native.inplane_terms import (
    OUTPUT_FIELDS,
    InPlaneTermsOutput,
    _declare,
    c_spin_terms,
    c_spin_terms_of,
)
from tire_fmu.native.kernel import load_library
from tire_fmu.tire_files import read_tire_file

TOLERANCE = 1e-12
#: Each array's kind: the matrix at rest whose largest entry scales its tolerance.
K_KIND = ("k0", "k1", "k2", "kh")
C_KIND = ("c0", "c1")


@functools.cache
def model(name: str) -> InPlaneTire:
    if name == "tied":
        return InPlaneTire(TireParameters(sidewall_max_order=8.0))
    if name == "hysteretic":
        file = read_tire_file("GL073A_inplane_hysteretic", warn=False)
        return InPlaneTire(tire=file.tire, tangential=file.tangential)
    return InPlaneTire()


CASES = list(itertools.product(("default", "tied", "hysteretic"), (50, 100), ("free", "held"),
                               (None, 300.0)))


def compared(sim) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
    """(name, C, Python, scale) for every array, scale its kind's largest entry at rest."""
    c = c_spin_terms(sim)
    terms = sim._spin_terms
    scale = {"k": np.abs(terms["k0"]).max(), "c": np.abs(terms["c0"]).max()}

    def kind(name, python):
        if name in K_KIND:
            return scale["k"]
        if name in C_KIND:
            return scale["c"]
        return np.abs(python).max()

    rows = [(name, c[name], terms[name], kind(name, terms[name])) for name in terms]
    rows += [(name, c[name], getattr(sim, "_" + name), np.abs(getattr(sim, "_" + name)).max())
             for name in ("m", "to_abs", "rim_inertia")]
    rows += [(f"rim {name}", c["rim_rows"][name], python, kind(name, python))
             for name, python in sim._rim_rows.items()]
    return rows


@pytest.mark.parametrize(("tire", "n", "wheel", "f_max"), CASES)
def test_the_terms_are_the_simulators(tire, n, wheel, f_max):
    sim = InPlaneSimulator(model(tire), n, 10.0, 0.01, wheel=wheel, f_max_hz=f_max)
    rows = compared(sim)
    assert {name for name, *_ in rows} >= set(sim._spin_terms) | {f"rim {k}" for k in
                                                                  sim._rim_rows}
    failures = []
    for name, c, python, scale in rows:
        assert c.shape == python.shape, f"{name}: C {c.shape}, Python {python.shape}"
        worst = np.abs(c - python).max()
        if not worst <= TOLERANCE * max(scale, 0.0) and worst:
            failures.append(f"{name}: {worst:.3g}, {worst / scale:.3g} of its kind's largest")
    assert not failures, f"{tire} N={n} {wheel} f_max={f_max}: " + "; ".join(failures)


def test_the_hysteretic_loss_and_the_turn_are_there():
    """The comparison is not of zeros: the loss is carried, and the turn's coordinate couples
    to the ring (P_psi's column in to_abs, R on the tangential fields)."""
    sim = InPlaneSimulator(model("hysteretic"), 50, 10.0, 0.01, wheel="free")
    c = c_spin_terms(sim)
    assert np.abs(c["kh"]).max() > 1e-3 * np.abs(c["k0"]).max()
    v = slice(50, 100)
    assert np.allclose(c["to_abs"][v, -1], sim.model.tire.R, rtol=0, atol=0)
    assert c["m"][-1, -1] > 0.0


def _call(model_, n, fields, free, basis, n_basis, sentinel=7.0):
    lib = load_library()
    _declare(lib)
    size = max(n_fields(model_) * max(n, 8) + 3, 8)
    arrays = {name: np.full(size * size, sentinel) for name in OUTPUT_FIELDS}
    out = InPlaneTermsOutput(*(arrays[name].ctypes.data for name in OUTPUT_FIELDS))
    work = np.full(4 * size * size * 8 + 10**6, sentinel)
    why = ctypes.create_string_buffer(512)
    status = lib.inplane_terms_build(ctypes.byref(ring_data(model_)), n, fields, free,
                                     None if basis is None else basis.ctypes.data, n_basis,
                                     ctypes.byref(out), work.ctypes.data, why, 512)
    untouched = all((a == sentinel).all() for a in arrays.values())
    return status, why.value.decode(), untouched


@pytest.mark.parametrize(("n", "free", "basis_shape", "n_basis", "words"), [
    (4, 1, None, 0, ["n_elements = 4", "[8, 1600]"]),
    (16, 2, None, 0, ["free_spin = 2", "0", "1"]),
    (16, 1, None, 3, ["n_basis = 3", "0 without one"]),
    (16, 1, (48, 4), 0, ["n_basis = 0", "[1, 48]"]),
    (16, 0, (48, 4), 49, ["n_basis = 49", "[1, 48]"]),
    (16, 0, (48, 4), 4, ["basis[3, 1] = nan", "finite"]),
])
def test_bad_input_is_refused_and_nothing_written(n, free, basis_shape, n_basis, words):
    m = InPlaneTire()  # three fields: 48 ring DOFs at N = 16
    assert n_fields(m) * 16 == 48
    basis = None
    if basis_shape is not None:
        basis = np.zeros(basis_shape)
        basis[3, 1] = np.nan
        if n_basis != 4:
            basis[3, 1] = 0.0
    status, why, untouched = _call(m, n, n_fields(m), free, basis, n_basis)
    assert status != 0
    assert untouched
    for word in words:
        assert word in why, why


def test_the_wrapper_refuses_a_basis_of_the_wrong_rows():
    with pytest.raises(ValueError, match="allowed"):
        c_spin_terms_of(InPlaneTire(), 16, True, np.eye(10))


def test_a_missing_output_is_refused():
    lib = load_library()
    _declare(lib)
    m = InPlaneTire()
    out = InPlaneTermsOutput()  # every pointer NULL
    work = np.zeros(lib.inplane_terms_work_doubles(16, n_fields(m), 1, 0))
    why = ctypes.create_string_buffer(512)
    status = lib.inplane_terms_build(ctypes.byref(ring_data(m)), 16, n_fields(m), 1, None, 0,
                                     ctypes.byref(out), work.ctypes.data, why, 512)
    assert status != 0 and "missing" in why.value.decode()
    assert lib.inplane_terms_ny(16, n_fields(m), 1, 0) == n_fields(m) * 16 + 1
    assert lib.inplane_terms_ny(4, n_fields(m), 1, 0) == 0
