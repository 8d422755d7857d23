"""The native FMU's dense eigen-solver (numerics.c: cx_eig, canonical_modes) and the free ring's
orders built with it (ring.c: ring_order_modes), called through ctypes from a shared library
compiled here from the package's C, against scipy and the core's own builder."""

from __future__ import annotations

import ctypes
import dataclasses
import shutil
import subprocess

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import linear_sum_assignment

from tire_fmu.core.discretisation import Grid
from tire_fmu.core.free_ring import momentum_matrices, order_matrices, order_modes
from tire_fmu.core.modal_form import MODE_TIE_TOLERANCE, canonical_modes
from tire_fmu.core.parameters import TireParameters
from tire_fmu.native.builder import c_folder

EPS = np.finfo(float).eps
TIRE_FIELDS = [f.name for f in dataclasses.fields(TireParameters)]


class _Tire(ctypes.Structure):  # tire.h's Tire: the core's fields in their order
    _fields_ = [(name, ctypes.c_double) for name in TIRE_FIELDS]


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    if shutil.which("gcc") is None:
        pytest.fail("the native FMU's tests need gcc")
    folder = c_folder()
    target = tmp_path_factory.mktemp("eig") / "libring.so"
    subprocess.run(["gcc", "-std=c99", "-O2", "-shared", "-fPIC", "-I", str(folder), "-o",
                    str(target), str(folder / "numerics.c"), str(folder / "ring.c"),
                    str(folder / "memory.c"), "-lm"],
                   check=True, capture_output=True)
    library = ctypes.CDLL(str(target))
    pointer = ctypes.c_void_p
    library.cx_eig.argtypes = [pointer, ctypes.c_int, ctypes.c_int, pointer, pointer]
    library.canonical_modes.argtypes = [ctypes.c_int, pointer, pointer, ctypes.c_double]
    library.canonical_modes.restype = None
    library.ring_order_modes.argtypes = [ctypes.POINTER(_Tire), ctypes.c_int, ctypes.c_double,
                                         ctypes.c_int, pointer, pointer, pointer]
    return library


def c_eig(lib, a, real=False):
    a = np.ascontiguousarray(a, dtype=complex)
    n = a.shape[0]
    values = np.zeros(n, dtype=complex)
    vectors = np.zeros((n, n), dtype=complex)
    status = lib.cx_eig(a.ctypes.data, n, int(real), values.ctypes.data, vectors.ctypes.data)
    return status, values, vectors


def c_canonical(lib, values, vectors):
    values = np.array(values, dtype=complex)  # copies: the C works in place
    vectors = np.array(vectors, dtype=complex, order="C")
    lib.canonical_modes(values.size, values.ctypes.data, vectors.ctypes.data,
                        MODE_TIE_TOLERANCE)
    return values, vectors


# -- the solver on its own ----------------------------------------------------------------------

def _matrices():
    """(name, matrix, real, block): the largest Jordan block is 'block' (1: diagonalisable)."""
    rng = np.random.default_rng(20)
    cplx = lambda n: rng.normal(size=(n, n)) + 1j * rng.normal(size=(n, n))  # noqa: E731
    cases = []
    for n in range(1, 17):
        q, _ = np.linalg.qr(cplx(n))
        for trial in range(3):
            cases.append((f"random {n}.{trial}", cplx(n), False, 1))
        cases.append((f"real {n}", rng.normal(size=(n, n)), True, 1))
        cases += [
            (f"zero {n}", np.zeros((n, n)), False, 1),
            (f"identity {n}", np.eye(n), False, 1),
            (f"diagonal repeated {n}", np.diag(rng.integers(0, 3, n) + 1j), False, 1),
            (f"upper {n}", np.triu(cplx(n)), False, 1),
            (f"lower {n}", np.tril(cplx(n)), False, 1),
            (f"clustered {n}", q @ np.diag(1 + 1e-9 * rng.normal(size=n)) @ q.conj().T, False, 1),
            (f"hermitian {n}", cplx(n) + cplx(n).conj().T, False, 1),
            # the shift-0 QR step leaves a cyclic permutation as it is: exceptional shifts
            (f"cyclic {n}", np.roll(np.eye(n), 1, axis=0), False, 1),
            (f"graded {n}", np.outer(10.0 ** np.linspace(-100, 100, n),
                                     10.0 ** -np.linspace(-100, 100, n)) * cplx(n), False, 1),
            (f"huge {n}", 1e300 * cplx(n), False, 1),
            (f"tiny {n}", 1e-300 * cplx(n), False, 1),
            (f"jordan {n}", (2 + 1j) * np.eye(n) + np.eye(n, k=1), False, n),
            (f"defective {n}", q @ (3 * np.eye(n) + np.eye(n, k=1)) @ q.conj().T, False, n),
        ]
        if n > 1:
            companion = np.eye(n, k=-1)
            companion[0] = -rng.normal(size=n)
            cases.append((f"companion {n}", companion, True, 1))
    return cases


CASES = _matrices()


@pytest.mark.parametrize("name, a, real, block", CASES, ids=[c[0] for c in CASES])
def test_eigenpairs_satisfy_a_v_equals_v_lambda_and_equal_scipys(lib, name, a, real, block):
    status, values, vectors = c_eig(lib, a, real)
    assert status == 0
    scale = np.abs(a).max() or 1.0
    scaled = a / scale  # the residual of a huge or tiny matrix without over- or underflow
    norm = np.linalg.norm(scaled, 2) or 1.0
    residual = np.linalg.norm(scaled @ vectors - vectors * (values / scale), axis=0) / norm
    assert residual.max() < 1e-13 * max(1, a.shape[0] / 4), residual.max()
    assert np.allclose(np.linalg.norm(vectors, axis=0), 1.0, rtol=0, atol=1e-14)
    reference = sla.eigvals(scaled)  # (scipy 1.17 returns 1e138 for the eigenvalue of [[1e300]])
    gaps = np.abs((values / scale)[:, None] - reference[None, :])
    rows, cols = linear_sum_assignment(gaps)
    if block == 1:  # a first-order bound: eps |A| times each eigenvalue's condition number
        left, right = sla.eig(scaled, left=True, right=True)[1:]
        cosine = np.abs(np.sum(left.conj() * right, axis=0)) / (
            np.linalg.norm(left, axis=0) * np.linalg.norm(right, axis=0))
        bound = 1e-13 * norm + 50 * EPS * norm / np.maximum(cosine, EPS)
        assert (gaps[rows, cols] <= bound[cols]).all(), gaps[rows, cols].max()
    else:  # a Jordan block of size m: eigenvalues to (eps |A|)^(1/m)
        assert gaps[rows, cols].max() < 10 * (EPS * norm) ** (1 / block) * norm


@pytest.mark.parametrize("n", range(1, 17))
def test_a_real_matrix_keeps_its_structure(lib, n):
    """real: pairs exactly conjugate (values and vectors), real eigenvalues exactly real with
    real eigenvectors, as LAPACK's dgeev returns them; the same real ones as dgeev finds."""
    rng = np.random.default_rng(n)
    a = rng.normal(size=(n, n))
    a[:, 0] = 0.0  # at least one real eigenvalue (0) whatever n
    status, values, vectors = c_eig(lib, a, real=True)
    assert status == 0
    real = values.imag == 0
    assert np.all(vectors[:, real].imag == 0)
    for k in np.flatnonzero(~real):
        partner = np.flatnonzero(values == np.conj(values[k]))
        assert partner.size == 1
        assert np.array_equal(vectors[:, partner[0]], np.conj(vectors[:, k]))
    assert real.sum() == (sla.eigvals(a).imag == 0).sum()


def test_bad_input_is_an_error_not_a_result(lib):
    assert c_eig(lib, np.zeros((0, 0)))[0] == -1
    assert c_eig(lib, np.eye(17))[0] == -1
    nan = np.eye(3)
    nan[1, 2] = np.nan
    assert c_eig(lib, nan)[0] == -1
    infinite = np.eye(3)
    infinite[0, 0] = np.inf
    assert c_eig(lib, infinite, real=True)[0] == -1


# -- the canonical rule, the same in both runtimes ----------------------------------------------

def _rule_cases():
    rng = np.random.default_rng(7)
    cases = []
    for n in (1, 2, 4, 8, 16):
        values = rng.normal(size=n) + 1j * rng.normal(size=n)
        vectors = rng.normal(size=(n, n)) + 1j * rng.normal(size=(n, n))
        cases.append((f"random {n}", values, vectors))
    # Im tied within the tolerance (rounding dust of a real eigenvalue): Re decides
    cases.append(("dust", np.array([3 + 1e-12j, 1 - 1e-12j, -2 + 0j, 1j]),
                  rng.normal(size=(4, 4)) + 1j * rng.normal(size=(4, 4))))
    # equal eigenvalues keep the solver's order; equal-magnitude components: the first wins
    tied = np.array([[1, 1j, 0.5], [-1j * (1 + 1e-9), 1, 0.5], [0.1, 0.2, -0.5 + 0.5j]])
    cases.append(("ties", np.array([2 + 1j, 2 + 1j, 2 - 1j]), tied))
    return cases


@pytest.mark.parametrize("name, values, vectors", _rule_cases(), ids=[c[0] for c in _rule_cases()])
def test_the_c_and_the_core_apply_one_canonical_rule(lib, name, values, vectors):
    lam, v = canonical_modes(values, vectors)
    c_lam, c_v = c_canonical(lib, values, vectors)
    assert np.array_equal(lam, c_lam)
    assert np.allclose(v, c_v, rtol=0, atol=4 * EPS)
    assert np.allclose(np.linalg.norm(v, axis=0), 1.0, rtol=0, atol=4 * EPS)
    size = np.abs(v)
    pivot = np.argmax(size >= (1 - MODE_TIE_TOLERANCE) * size.max(axis=0), axis=0)
    assert np.all(v[pivot, range(v.shape[1])].imag == 0)
    assert np.all(v[pivot, range(v.shape[1])].real > 0)
    # the same columns, each times a unit phase
    for k, value in enumerate(lam):
        source = np.flatnonzero(values == value)
        ratios = [v[:, k] @ vectors[:, j].conj() / np.linalg.norm(vectors[:, j]) for j in source]
        assert np.isclose(np.abs(ratios), 1.0, rtol=0, atol=1e-12).any()


def test_the_canonical_order_is_im_then_re_with_a_tie():
    values = np.array([3 + 1e-12j, 1 - 1e-12j, -2 + 0j, 1j, -1j, 1e-3 + 1j])
    lam, _ = canonical_modes(values, np.eye(values.size))
    assert lam.tolist() == [-1j, -2 + 0j, 1 - 1e-12j, 3 + 1e-12j, 1j, 1e-3 + 1j]
    # the first of the components within the tie of the largest is made real and positive
    _, v = canonical_modes(np.zeros(1), np.array([[0.6j], [-0.6j * (1 + 1e-9)], [0.1]]))
    assert v[0, 0].imag == 0 and v[0, 0].real > 0
    assert np.isclose(v[1, 0], -v[0, 0] * (1 + 1e-9))


# -- the free ring's orders: the C's against the core's ----------------------------------------

def _order_bounds(a, values):
    """First-order perturbation bounds of each (canonical) eigenvalue (relative) and
    eigenvector (2-norm of the unit vector) for a backward error of eps |A| after balancing,
    the one that both LAPACK and the C make."""
    balanced, transform = sla.matrix_balance(a, permute=False)
    d = np.diag(transform)
    lam, left, right = sla.eig(balanced, left=True, right=True)
    left /= np.linalg.norm(left, axis=0)
    right /= np.linalg.norm(right, axis=0)
    cosine = np.abs(np.sum(left.conj() * right, axis=0))
    norm = np.linalg.norm(balanced, 2)
    shown = np.linalg.norm(d[:, None] * right, axis=0)  # the unbalanced vectors' lengths
    m = lam.size
    value_bound = EPS * norm / (cosine * np.abs(lam))
    vector_bound = np.array([
        EPS * norm * sum(shown[j] / (abs(lam[k] - lam[j]) * cosine[j])
                         for j in range(m) if j != k) / shown[k] for k in range(m)])
    match = [np.argmin(np.abs(lam - x)) for x in values]
    return value_bound[match], vector_bound[match]


@pytest.mark.parametrize("speed", [0.0, 20.0])
@pytest.mark.parametrize("n_elements, m_s", [(100, 10.0), (400, 10.0), (800, 10.0),
                                             (1600, 10.0), (100, 1e-5), (400, 1e-5),
                                             (800, 1e-5), (1600, 1e-5)])
def test_every_order_has_the_cores_modes(lib, n_elements, m_s, speed):
    """Every order n = 0..N/2 of the default tire (and of sidewalls 1e-6 as heavy): the same A_n
    as free_ring builds, and the same eigenvalues and canonical eigenvectors as scipy's LAPACK
    gives the core, to 1e-12 relative or, for modes whose conditioning does not allow that of
    any two backward-stable solvers, to 50 times their first-order perturbation bound (light
    sidewalls: eigenvalue condition numbers to 1e7). The modes come in the same order."""
    tire = dataclasses.replace(TireParameters(), m_s=m_s)
    spin = speed / tire.R
    orders = np.arange(n_elements // 2 + 1)
    mass, damping, stiffness = order_matrices(tire, Grid(n_elements, tire.R), spin, orders)
    a_n = momentum_matrices(mass, damping, stiffness)
    real_orders = (orders == 0) | (2 * orders == n_elements)
    values, vectors = order_modes(a_n, real_orders)
    c_tire = _Tire(*(getattr(tire, name) for name in TIRE_FIELDS))
    a = np.zeros((4, 4), dtype=complex)
    c_values = np.zeros(4, dtype=complex)
    c_vectors = np.zeros((4, 4), dtype=complex)
    worst = [0.0, 0.0]
    for n in orders:
        status = lib.ring_order_modes(ctypes.byref(c_tire), n_elements, spin, int(n),
                                      a.ctypes.data, c_values.ctypes.data, c_vectors.ctypes.data)
        assert status == 0, n
        expected = a_n[n].real if real_orders[n] else a_n[n]
        assert np.array_equal(a, expected), n
        value_bound, vector_bound = _order_bounds(expected, values[n])
        value_error = np.abs(c_values - values[n]) / np.abs(values[n])
        vector_error = np.linalg.norm(c_vectors - vectors[n], axis=0)
        assert (value_error <= np.maximum(1e-12, 50 * value_bound)).all(), (n, value_error)
        assert (vector_error <= np.maximum(1e-12, 50 * vector_bound)).all(), (n, vector_error)
        worst = [max(worst[0], value_error.max()), max(worst[1], vector_error.max())]
        if real_orders[n]:
            assert np.array_equal(c_values.imag == 0, values[n].imag == 0), n
    if m_s == 10.0:  # the default tire is well conditioned: eigenvalues to 1e-12 everywhere,
        assert worst[0] < 1e-12  # eigenvectors to 1e-11 (bounds to 5e-10 at N = 1600)
        assert worst[1] < 1e-11
