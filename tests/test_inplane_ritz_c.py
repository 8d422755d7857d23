"""native/c/inplane_ritz.c against core/inplane_contact.py's ritz_basis: the C basis, built order
by order from the circulant blocks of the held ring at rest, spans the Python's subspace (same
rank, principal angles, the reduced problem's eigenvalues) over random tires, meshes of 8 to
400 nodes, every sidewall model (the radial tie too), several f_max and zone node sets; it is
orthonormal; it keeps or drops a degenerate pair whole; it refuses bad input with a sentence
and writes nothing.

The Python solves K s = e densely: at N = 400 its static shapes carry errors of up to about
4e-12 of their size (K's condition is ~5e5; the C refines its own to ~1e-15), which turn the
span of 81 neighbouring nodes' nearly dependent shapes by up to ~1e-8. So the C is held against
the Python's own steps with the static solve refined (the residual in extended precision), and
against ritz_basis as it is to that plus ritz_basis's own distance from it. And a span is only
as well defined as its columns make it: rounding of size eps s_max in the columns turns it by
up to ~eps s_max / (s_r - s_{r+1}) (Wedin), s the columns' singular values and r the rank; a
zone of neighbouring nodes' static shapes has singular values falling through orth's threshold,
so where that gap is small the 1e-9 is widened by 1e-14 s_max / (s_r - s_{r+1}) (most cases
have a gap above 1e-5 s_max, where this adds at most 1e-9).
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg
from test_inplane_ring_c import model_of, random_case

from tire_fmu.core.contact import contact_zone
from tire_fmu.core.discretisation import Grid
from tire_fmu.core.inplane import InPlaneRing, InPlaneTire, TangentialParameters
from tire_fmu.core.inplane_contact import ritz_basis
from tire_fmu.core.inplane_modes import tire_modes
from tire_fmu.core.parameters import TireParameters
from tire_fmu.native.inplane_ring import c_inplane_ring, n_fields
from tire_fmu.native.inplane_ritz import _declare, c_ritz_basis, c_ritz_basis_of
from tire_fmu.native.kernel import load_library

#: Largest principal angle (rad) allowed between the C's span and the refined Python's.
ANGLE = 1e-9
#: The reduced problem's eigenvalues, relative.
EIGENVALUES = 1e-10
#: Rounding of the columns (relative to s_max) that the span's conditioning widens both by.
COLUMN_ROUNDING = 1e-14
#: Orthonormality of the C basis.
ORTHONORMAL = 1e-12
#: Relative gap (in frequency) around f_max free of modes: a mode within rounding of f_max is
#: kept by one and dropped by the other, and one close to it is an eigenvector computed to
#: only eps ||K|| / gap.
F_MAX_GAP = 0.03
N_RANDOM = 24


def _f_max_in_a_gap(frequencies: np.ndarray, target: float) -> float:
    """f_max near ``target`` in the middle of a gap of the spectrum at least F_MAX_GAP wide:
    the nearest such gap's midpoint (geometric), or above the spectrum."""
    f = np.unique(np.round(frequencies, 9))
    edges = np.concatenate([[0.5], f, [f[-1] * 4.0]])
    mids = np.sqrt(edges[:-1] * edges[1:])
    wide = edges[1:] / edges[:-1] > 1.0 + 2.0 * F_MAX_GAP
    mids = mids[wide & (mids >= 1.0) & (mids <= 1e5)]
    return float(mids[np.argmin(np.abs(np.log(mids / target)))])


def _zone(kind: str, n: int, rng, model: InPlaneTire) -> np.ndarray:
    if kind == "none":
        return np.zeros(0, dtype=int)
    if kind == "contact":  # the simulator's zone at its default length and spacing
        t = model.tire
        return contact_zone(Grid(n, t.R), t.k_cw, t.beta).nodes
    if kind == "scattered":
        return rng.choice(n, size=int(rng.integers(1, max(2, n // 4))), replace=False)
    if kind == "repeated":  # the same node twice: a dependent column orth must drop
        nodes = rng.choice(n, size=3, replace=False)
        return np.concatenate([nodes, nodes[:1]])
    half = int(rng.integers(0, max(1, n // 8)))
    return np.arange(-half, half + 1) % n


ZONES = ("contact", "scattered", "block", "repeated", "none")


def ritz_case(seed: int) -> dict:
    """A random tire, mesh and sidewall (test_inplane_ring_c's draw, at rest, rim held), a
    zone kind and an f_max log-uniform in 30 Hz - 3 kHz moved into a gap of the spectrum."""
    case = random_case(seed)
    rng = np.random.default_rng(1000 + seed)
    case["zone"] = ZONES[seed % len(ZONES)]
    case["target_hz"] = float(30.0 * 100.0 ** rng.uniform(0.0, 1.0))
    case["seed"] = seed
    return case


def fixed(sidewall, n, zone, target_hz, tie_order=0.0, loss_factor=0.0, seed=0) -> dict:
    return dict(sidewall=sidewall, n=n, zone=zone, target_hz=target_hz, seed=seed,
                tire=TireParameters(sidewall_max_order=tie_order),
                tangential=TangentialParameters(loss_factor=loss_factor))


CASES = {f"random{seed}": ritz_case(seed) for seed in range(N_RANDOM)}
CASES.update({
    "tied_400_contact": fixed("tied", 400, "contact", 300.0),
    "lumped_400_contact": fixed("lumped", 400, "contact", 300.0),
    "massless_400_block": fixed("massless", 400, "block", 1000.0, seed=3),
    "massless_8_everything": fixed("massless", 8, "scattered", 1e5, seed=1),
    "lumped_16_every_mode": fixed("lumped", 16, "block", 9e4, seed=2),
    "tied_24_repeated": fixed("tied", 24, "repeated", 200.0, seed=4),
    # the radial tie: the C ring does not build it yet; the C basis reads the Python's ring
    "radial_tie_tied_100": fixed("tied", 100, "contact", 300.0, tie_order=8.0),
    "radial_tie_lumped_64": fixed("lumped", 64, "block", 500.0, tie_order=5.0, seed=5),
    # the hysteretic loss acts with the rolling only: at rest it is the lossless basis
    "lossy_tied_100": fixed("tied", 100, "contact", 300.0, loss_factor=0.05),
})


def _with_tie(case: dict) -> bool:
    return case["sidewall"] != "massless" and 0 < case["tire"].sidewall_max_order < case["n"] // 2


def refined_ritz_basis(ring: InPlaneRing, zone_nodes: np.ndarray, f_max_hz: float):
    """ritz_basis's steps on ``ring`` with the static solve refined twice from a residual in
    extended precision (numpy's long double); and s_max / (s_r - s_{r+1}) of its columns."""
    modes = tire_modes(ring, f_max_hz=f_max_hz)
    k = 0.5 * (ring.stiffness + ring.stiffness.T)
    loads = np.zeros((ring.n_ring_dof, 2 * zone_nodes.size))
    w, v = ring.field_slice("w"), ring.field_slice("v")
    for i, node in enumerate(zone_nodes):
        loads[w.start + node, 2 * i] = 1.0
        loads[v.start + node, 2 * i + 1] = 1.0
    lu = scipy.linalg.lu_factor(k)
    static = scipy.linalg.lu_solve(lu, loads)
    wide = k.astype(np.longdouble)
    for _ in range(2):
        residual = loads - wide @ static.astype(np.longdouble)
        static = static + scipy.linalg.lu_solve(lu, residual.astype(float))
    shapes = np.hstack([modes.shapes, static / np.abs(static).max(axis=0)]) if zone_nodes.size \
        else modes.shapes
    basis = scipy.linalg.orth(shapes, rcond=1e-10)
    sigma = np.append(scipy.linalg.svdvals(shapes), 0.0) if shapes.size else np.ones(2)
    rank = basis.shape[1]
    return basis, sigma[0] / (sigma[max(rank, 1) - 1] - sigma[rank])


def _reduced_eigenvalues(basis, ring):
    k = 0.5 * (ring.stiffness + ring.stiffness.T)
    return scipy.linalg.eigh(basis.T @ k @ basis, basis.T @ ring.mass @ basis, eigvals_only=True)


@pytest.fixture(scope="module")
def extended_precision():
    assert np.finfo(np.longdouble).eps < 1e-18, (
        "the refined reference needs numpy's long double wider than a double (x86's 80 bits)")


@pytest.mark.parametrize("label", list(CASES))
def test_c_basis_spans_the_python_subspace(label, extended_precision):
    case = CASES[label]
    model, n = model_of(case), case["n"]
    ring = InPlaneRing(model, n)
    zone = _zone(case["zone"], n, np.random.default_rng(case["seed"]), model)
    frequencies = np.array([m.frequency_hz for m in tire_modes(ring).modes])
    f_max = _f_max_in_a_gap(frequencies, case["target_hz"])
    python = ritz_basis(model, n, zone, f_max)
    refined, conditioning = refined_ritz_basis(ring, zone, f_max)
    built = c_ritz_basis(model, n, zone, f_max)
    where = (f"{label} ({case['sidewall']}, N = {n}, {zone.size} zone nodes ({case['zone']}), "
             f"f_max {f_max:.6g} Hz, s_max / (s_r - s_r+1) = {conditioning:.3g})")
    widening = COLUMN_ROUNDING * conditioning
    assert built.shape == python.shape == refined.shape, (
        f"{where}: rank C {built.shape[1]}, Python {python.shape[1]}, refined "
        f"{refined.shape[1]} of {ring.n_ring_dof} DOFs")
    if built.shape[1] == 0:
        return
    gram = np.abs(built.T @ built - np.eye(built.shape[1])).max()
    assert gram < ORTHONORMAL, f"{where}: BᵀB - I up to {gram:.3g}"
    to_refined = scipy.linalg.subspace_angles(built, refined).max()
    python_drift = scipy.linalg.subspace_angles(python, refined).max()
    to_python = scipy.linalg.subspace_angles(built, python).max()
    assert to_refined < ANGLE + widening, (
        f"{where}: {to_refined:.3g} rad from the refined Python's span")
    # the largest principal angle is a metric: the C is no further from ritz_basis than
    # ritz_basis is from its refined self, plus the C's own distance
    assert to_python <= python_drift + ANGLE + widening, (
        f"{where}: {to_python:.3g} rad from ritz_basis, which is {python_drift:.3g} from the "
        "refined span")
    ours, theirs = _reduced_eigenvalues(built, ring), _reduced_eigenvalues(refined, ring)
    worst = float(np.max(np.abs(ours - theirs) / np.abs(theirs)))
    assert worst < EIGENVALUES + widening, (
        f"{where}: reduced eigenvalues differ by {worst:.3g} relative")


def test_the_cases_cover_every_option():
    cases = list(CASES.values())
    assert {c["sidewall"] for c in cases} == {"massless", "tied", "lumped"}
    assert {c["zone"] for c in cases} == set(ZONES)
    assert min(c["n"] for c in cases) == 8 and max(c["n"] for c in cases) == 400
    assert any(_with_tie(c) and c["sidewall"] == s for c in cases for s in ("tied", "lumped"))


@pytest.mark.parametrize("sidewall", ["massless", "tied", "lumped"])
@pytest.mark.parametrize("tie_order", [0.0, 6.0])
def test_the_held_ring_at_rest_is_circulant_field_block_by_block(sidewall, tie_order):
    """What the C builds on: every field block of M and K (Python's and C's ring, with the
    radial tie too) is circulant and K symmetric, to rounding. At speed with damping K is still
    circulant but not symmetric (the circulatory Ω C D1): the C refuses it."""
    case = fixed(sidewall, 40, "none", 0.0, tie_order=tie_order)
    model, n = model_of(case), 40
    ring = InPlaneRing(model, n)
    c_ring = c_inplane_ring(model, n)
    rings = {"Python": (ring.mass, ring.stiffness), "C": (c_ring.mass, c_ring.stiffness)}
    index = (np.arange(n)[:, None] - np.arange(n)[None, :]) % n
    for source, matrices in rings.items():
        for name, matrix in zip(("mass", "stiffness"), matrices):
            scale = np.abs(matrix).max()
            for a in range(ring.n_fields):
                for b in range(ring.n_fields):
                    block = matrix[a * n:(a + 1) * n, b * n:(b + 1) * n]
                    worst = np.abs(block - block[:, 0][index]).max() / scale
                    assert worst < 1e-15, f"{source} {name} block ({a}, {b}): {worst:.3g}"
            assert np.abs(matrix - matrix.T).max() / scale < 1e-15
    rolling = InPlaneRing(replace(model, tire=replace(model.tire, beta=1e-3)), n,
                          spin_rad_s=50.0).stiffness
    assert np.abs(rolling - rolling.T).max() > 1e-6 * np.abs(rolling).max()
    with pytest.raises(ValueError, match="symmetric circulant field blocks"):
        c_ritz_basis_of(ring.mass, rolling, n, ring.n_fields, [0], 300.0)


def test_the_matrices_given_apart_give_the_c_rings_basis():
    """c_ritz_basis_of on the Python ring's matrices spans what c_ritz_basis builds from the C
    ring's (the radial tie and a hysteretic tire among them)."""
    model = InPlaneTire(TireParameters(sidewall_max_order=8.0),
                        replace(InPlaneTire().tangential, loss_factor=0.05))
    n, f_max = 64, 300.0
    zone = np.arange(-4, 5) % n
    ring = InPlaneRing(model, n)
    given = c_ritz_basis_of(ring.mass, ring.stiffness, n, ring.n_fields, zone, f_max)
    built = c_ritz_basis(model, n, zone, f_max)
    assert built.shape == given.shape == ritz_basis(model, n, zone, f_max).shape
    assert scipy.linalg.subspace_angles(built, given).max() < ANGLE


@pytest.mark.parametrize("sidewall", ["massless", "lumped"])
def test_a_degenerate_pair_is_kept_or_dropped_whole(sidewall):
    """f_max at a pair's frequency (either member's, as eigh gives them): the C's one
    frequency per pair keeps both members or neither, never one. The Python compares eigh's
    two members apart, whose frequencies differ in the last digits: there it may keep one
    (inplane_ritz.h states the rule)."""
    case = fixed(sidewall, 48, "none", 0.0)
    model, n = model_of(case), 48
    frequencies = np.array([m.frequency_hz for m in tire_modes(InPlaneRing(model, n)).modes])
    pairs = np.flatnonzero(np.isclose(frequencies[1:], frequencies[:-1], rtol=1e-10))
    assert pairs.size > 5
    for i in pairs[:: max(1, pairs.size // 6)]:
        pair = frequencies[i: i + 2]
        below = int(np.sum(frequencies < pair.min() * (1.0 - 1e-9)))
        for f_max in (pair.min(), pair.max(), pair.mean()):
            kept = c_ritz_basis(model, n, [], f_max).shape[1]
            assert kept in (below, below + 2), (
                f"f_max {f_max!r} at the pair {pair.tolist()}: {kept} modes kept, {below} below")
            python = ritz_basis(model, n, np.zeros(0, dtype=int), f_max).shape[1]
            # both within rounding of the pair: the Python may split it, the C never does
            assert python in (below, below + 1, below + 2)


# ----- refusals -----

def _build(mass, stiffness, n, fields, zone, f_max, max_columns):
    lib = load_library()
    _declare(lib)
    zone = np.ascontiguousarray(zone, dtype=np.intc)
    work = np.zeros(max(lib.inplane_ritz_work_doubles(n, fields, max(0, min(zone.size, n))), 1))
    basis = np.full((max(max_columns, 1), max(mass.shape[0], 1)), 7.0)
    count = ctypes.c_int(-7)
    why = ctypes.create_string_buffer(1024)
    status = lib.inplane_ritz_build(
        np.ascontiguousarray(mass).ctypes.data, np.ascontiguousarray(stiffness).ctypes.data,
        n, fields, zone.ctypes.data, zone.size, f_max, max_columns, basis.ctypes.data,
        ctypes.byref(count), work.ctypes.data, why, 1024)
    return status, why.value.decode(), basis, count.value


def _held(sidewall="tied", n=16):
    ring = InPlaneRing(model_of(fixed(sidewall, n, "none", 0.0)), n)
    return ring.mass, 0.5 * (ring.stiffness + ring.stiffness.T), ring.n_fields


def _spinning():
    model = model_of(fixed("tied", 16, "none", 0.0))
    ring = InPlaneRing(replace(model, tire=replace(model.tire, beta=1e-3)), 16, spin_rad_s=50.0)
    return ring.mass, ring.stiffness, 3


def _bumped(matrix):
    """One node's entry and its mirror changed: symmetric, no longer circulant."""
    out = matrix.copy()
    out[3, 4] = out[4, 3] = matrix[3, 4] + 1e-6 * np.abs(matrix).max()
    return out


M16, K16, F16 = _held()


@pytest.mark.parametrize("inputs, words", [
    ((M16, K16, 4, F16, [0], 300.0, 64), ["n_elements = 4", "[8, 1600]"]),
    ((M16, K16, 16, 5, [0], 300.0, 64), ["n_fields = 5", "2 (massless sidewall)"]),
    ((M16, K16, 16, F16, [0], 0.5, 64), ["f_max_hz = 0.5 Hz", "[1, 100000] Hz"]),
    ((M16, K16, 16, F16, [0], math.nan, 64), ["f_max_hz = nan Hz"]),
    ((M16, K16, 16, F16, [0, 16], 300.0, 64), ["zone_nodes[1] = 16", "[0, 15]"]),
    ((M16, K16, 16, F16, [-1], 300.0, 64), ["zone_nodes[0] = -1"]),
    ((M16, K16, 16, F16, list(range(16)) * 2, 300.0, 64), ["n_zone = 32", "n_elements = 16"]),
    ((M16, K16, 16, F16, [0], 300.0, -1), ["max_columns = -1", ">= 0"]),
    ((M16, K16, 16, F16, [0, 3], 300.0, 2), ["max_columns = 2", "modes up to 300 Hz"]),
    ((M16, -K16, 16, F16, [0], 300.0, 64), ["stiffness: allowed a positive definite matrix"]),
    ((M16, _bumped(K16), 16, F16, [0], 300.0, 64),
     ["stiffness[", "symmetric circulant field blocks"]),
    ((*_spinning()[:2], 16, 3, [0], 300.0, 64), ["stiffness[", "the ring at rest"]),
    ((np.where(np.eye(48) > 0, np.nan, M16), K16, 16, F16, [0], 300.0, 64),
     ["mass[0, 0] = nan", "finite"]),
])
def test_bad_input_is_refused_with_a_sentence_and_nothing_written(inputs, words):
    status, why, basis, count = _build(*inputs)
    assert status != 0
    for word in words:
        assert word in why, why
    assert np.all(basis == 7.0) and count == -7


def test_the_wrapper_raises_the_c_sentence():
    with pytest.raises(ValueError, match=r"zone_nodes\[0\] = 20: allowed a node in \[0, 15\]"):
        c_ritz_basis(InPlaneTire(), 16, [20], 300.0)
    with pytest.raises(ValueError,
                       match=r"f_max_hz = 200000 Hz: allowed a finite number in \[1, 100000\] Hz"):
        c_ritz_basis(InPlaneTire(), 16, [0], 2e5)


def test_the_wrapper_reads_the_field_count_of_the_sidewall():
    for model in (InPlaneTire(sidewall_mass=False), InPlaneTire(),
                  InPlaneTire(sidewall_tangential="lumped")):
        built = c_ritz_basis(model, 12, [0], 50.0)
        assert built.shape[0] == n_fields(model) * 12
