"""native/c/inplane_ring.c against core/inplane.py: the in-plane ring's M, K, C and hysteretic
stiffness built in C equal the Python's to rounding over random tires, meshes, spins, sidewall
models, hysteretic losses and radial ties; a rigid motion of tire and rim meets no elastic,
hysteretic or damping force in either (the Coriolis load of a spin change apart, written here);
the C refuses bad input with a sentence and writes nothing."""

from __future__ import annotations

import ctypes
import math
from dataclasses import replace

import numpy as np
import pytest

from tire_fmu.core.inplane import (
    HYSTERESIS_FULL_SPEED_M_S,
    InPlaneRing,
    InPlaneTire,
    TangentialParameters,
    hysteresis_share,
)
from tire_fmu.core.parameters import TireParameters
from tire_fmu.native.inplane_ring import _declare, c_inplane_ring, n_fields, ring_data
from tire_fmu.native.kernel import load_library

#: Agreement asked of the C: rounding, relative to each matrix's largest entry.
TOLERANCE = 1e-12
#: Fields of TireParameters the ring reads, varied within x2 of their defaults.
TIRE_SCALED = ("R", "b", "inflation_pressure", "rhoA", "m_s", "k_r1", "k_r2", "EI", "alpha",
               "beta", "reference_pressure")
TANGENTIAL_SCALED = ("EA", "k_t1", "k_t2", "wheel_mass_kg", "wheel_inertia_kg_m2")
SIDEWALLS = ("massless", "tied", "lumped")
MATRICES = ("mass", "stiffness", "damping", "hysteretic_stiffness")
N_RANDOM = 30


def random_case(seed: int) -> dict:
    """A tire, mesh, spin and rim of one seed. The rim radius is drawn as a share of R (x2 of
    the default share) so that it always sits inside the tread; the pressure law (exponent 0
    by default) is on in half the tires; meshes are log-uniform in 8-160, the costly 400 comes
    from the fixed cases (the Python's dense products are O(n^3)). A quarter of the spins are
    0, a quarter within the hysteretic loss's ramp (either direction), the rest up to 100
    rad/s; four tires in five have a loss; the radial tie's top order is 0, 4, 8, one drawn
    below N/2 or one at or above N/2 (no tie)."""
    rng = np.random.default_rng(seed)

    def factor():
        return 2.0 ** rng.uniform(-1.0, 1.0)

    base, tang = TireParameters(sidewall_max_order=0.0), TangentialParameters()
    tire = replace(base, **{k: getattr(base, k) * factor() for k in TIRE_SCALED},
                   sidewall_pressure_exponent=float(rng.uniform(0.5, 2.0)) if seed % 2 else 0.0)
    share = tang.rim_radius_m / base.R * factor()
    tangential = replace(tang, **{k: getattr(tang, k) * factor() for k in TANGENTIAL_SCALED},
                         rim_radius_m=share * tire.R)
    sidewall = SIDEWALLS[seed % 3]
    n = int(round(8 * 20 ** rng.uniform(0.0, 1.0)))
    spin = 0.0 if seed % 4 == 0 else float(rng.uniform(0.0, 100.0))
    # drawn after the rest, so that the lossless, untied cases keep their tires
    if seed % 4 == 1:
        spin = float(rng.uniform(-1.0, 1.0)) * HYSTERESIS_FULL_SPEED_M_S / tire.R
    loss = 0.0 if seed % 5 == 0 else float(rng.uniform(0.005, 0.3))
    top = (0, 4, 8, int(rng.integers(1, n // 2)), n // 2 + int(rng.integers(0, 4)))[
        (seed // 2) % 5]
    return dict(
        sidewall=sidewall, n=n, spin=spin, rim_free=bool((seed // 3) % 2),
        tire=replace(tire, sidewall_max_order=float(top)),
        tangential=replace(tangential, loss_factor=loss))


def model_of(case: dict) -> InPlaneTire:
    sidewall = case["sidewall"]
    return InPlaneTire(case["tire"], case["tangential"], sidewall_mass=sidewall != "massless",
                       sidewall_tangential="lumped" if sidewall == "lumped" else "tied")


def fixed_case(sidewall, n, spin, rim_free, loss_factor=0.0, sidewall_max_order=0.0,
               **tire) -> dict:
    return dict(sidewall=sidewall, n=n, spin=spin, rim_free=rim_free,
                tire=TireParameters(sidewall_max_order=sidewall_max_order, **tire),
                tangential=TangentialParameters(loss_factor=loss_factor))


#: The spin at which the hysteretic loss reaches its full share on the default tire.
FULL_SHARE_SPIN = HYSTERESIS_FULL_SPEED_M_S / TireParameters().R

CASES = {f"random{seed}": random_case(seed) for seed in range(N_RANDOM)}
CASES.update({
    "tied_400_rolling_free": fixed_case("tied", 400, 100.0, True),
    "lumped_400_rest_held": fixed_case("lumped", 400, 0.0, False),
    "massless_8_rolling_free": fixed_case("massless", 8, 37.0, True),
    "tied_8_no_pressure": fixed_case("tied", 8, 5.0, True, inflation_pressure=0.0),
    # the GL073A_inplane_hysteretic loss with the GL073A_tied tie
    "tied_400_lossy_tie8_rolling_free": fixed_case("tied", 400, 100.0, True, 0.05, 8.0),
    "lumped_400_lossy_tie4_ramp_held": fixed_case("lumped", 400, 0.4 * FULL_SHARE_SPIN,
                                                  False, 0.05, 4.0),
    "massless_8_lossy_backwards_free": fixed_case("massless", 8, -0.7 * FULL_SHARE_SPIN, True,
                                                  0.3),
    "tied_16_top_at_half_free": fixed_case("tied", 16, 20.0, True, 0.05, 8.0),
    "lumped_17_tie7_free": fixed_case("lumped", 17, 3.0, True, 0.05, 7.0),
    "tied_17_top_8_held": fixed_case("tied", 17, 3.0, False, 0.05, 8.0),
})


def tie_applies(case: dict) -> bool:
    """Whether InPlaneRing ties the radial sidewall above sidewall_max_order in this case."""
    top = case["tire"].sidewall_max_order
    return case["sidewall"] != "massless" and 0 < top < case["n"] // 2


def share(case: dict) -> float:
    return hysteresis_share(case["spin"], case["tire"].R)


def worst_entries(case: dict):
    """Per matrix (name, worst |C - Python| over the largest |Python| entry, (row, column),
    C's value, Python's value)."""
    model = model_of(case)
    ring = InPlaneRing(model, case["n"], spin_rad_s=case["spin"], rim_free=case["rim_free"])
    built = c_inplane_ring(model, case["n"], case["spin"], case["rim_free"])
    out = []
    for name in MATRICES:
        c, py = getattr(built, name), getattr(ring, name)
        assert c.shape == py.shape, f"{name}: C {c.shape}, Python {py.shape}"
        difference = np.abs(c - py)
        index = np.unravel_index(int(np.argmax(difference)), difference.shape)
        # the hysteretic stiffness is zero without a loss: then C's must be zero too
        scale = np.abs(py).max() or 1.0
        out.append((name, float(difference[index] / scale), tuple(int(i) for i in index),
                    float(c[index]), float(py[index])))
    return out


@pytest.mark.parametrize("label", list(CASES))
def test_c_matrices_equal_the_python_ones(label):
    case = CASES[label]
    failures = [f"{name} differs most at (row, column) = {index}: C {c!r}, Python {py!r}, "
                f"{worst:.3g} of its largest entry"
                for name, worst, index, c, py in worst_entries(case) if not worst <= TOLERANCE]
    assert not failures, (f"{label} ({case['sidewall']}, N = {case['n']}, spin "
                          f"{case['spin']:g} rad/s, rim {'free' if case['rim_free'] else 'held'}"
                          f", loss_factor {case['tangential'].loss_factor:g}, sidewall_max_order"
                          f" {case['tire'].sidewall_max_order:g}): " + "; ".join(failures))


def test_the_random_cases_cover_every_option():
    cases = list(CASES.values())
    assert {c["sidewall"] for c in cases} == set(SIDEWALLS)
    assert {c["rim_free"] for c in cases} == {True, False}
    assert min(c["n"] for c in cases) == 8 and max(c["n"] for c in cases) == 400
    spins = [c["spin"] for c in cases]
    assert 0.0 in spins and max(spins) > 90.0
    for sidewall in SIDEWALLS:
        for rim_free in (True, False):
            assert any(c["sidewall"] == sidewall and c["rim_free"] == rim_free
                       and c["spin"] > 0 for c in cases)
    # the loss at rest, within its ramp (both directions) and at full share, random and fixed
    lossy = [c for c in cases if c["tangential"].loss_factor > 0]
    assert any(c["spin"] == 0 for c in lossy)
    assert any(0 < share(c) < 1 for c in lossy) and any(-1 < share(c) < 0 for c in lossy)
    assert any(share(c) == 1 for c in lossy) and any(c["n"] == 400 for c in lossy)
    assert any(c["tangential"].loss_factor == 0 and c["spin"] > 0 for c in cases)
    # the tie at orders 4 and 8 and others, with either sidewall mass, rim free and held; and
    # top orders at or above N/2, which tie nothing
    tied = [c for c in cases if tie_applies(c)]
    assert {c["tire"].sidewall_max_order for c in tied} > {4.0, 8.0}
    assert {c["sidewall"] for c in tied} == {"tied", "lumped"}
    assert {c["rim_free"] for c in tied} == {True, False}
    assert any(c["n"] == 400 for c in tied)
    assert any(c["sidewall"] != "massless" and c["tire"].sidewall_max_order >= c["n"] // 2
               for c in cases)


# ----- rigid motions, written apart from both builders -----

@pytest.mark.parametrize("sidewall", SIDEWALLS)
@pytest.mark.parametrize("spin", [0.0, 0.5 * FULL_SHARE_SPIN, 70.0])
@pytest.mark.parametrize("loss_and_tie", [(0.0, 0.0), (0.1, 4.0)], ids=["plain", "lossy_tied"])
def test_rigid_motion_with_the_rim_meets_no_force(sidewall, spin, loss_and_tie):
    """Tire and rim moved rigidly (x, z, ψ): K q vanishes (with the radial tie and the
    hysteretic loss's share in it), so does the hysteretic stiffness at full share, and so
    does C q for a translation; a rotation rate at speed meets the Coriolis force of a spin
    change, 2Ω ρA R κ₁ inwards on every tread node (2Ω m_s R κ₁ on each sidewall mass) and
    nothing else, κ₁ = sin δθ/δθ the discrete L's weight of a rigid rotation."""
    case = fixed_case(sidewall, 36, spin, True, *loss_and_tie)
    case["tire"] = replace(case["tire"], m_s=7.5, alpha=3e-3)  # damping well above rounding
    model = model_of(case)
    ring = InPlaneRing(model, 36, spin_rad_s=spin, rim_free=True)
    n, tire = 36, model.tire
    arc, kappa = tire.R * 2 * math.pi / n, math.sin(2 * math.pi / n) / (2 * math.pi / n)
    for source, (mass, stiffness, damping, hysteretic) in (
            ("C", c_inplane_ring(model, n, spin, True)),
            ("Python", (ring.mass, ring.stiffness, ring.damping, ring.hysteretic_stiffness))):
        if loss_and_tie[0]:
            assert np.abs(hysteretic).max() > 0
        for motion in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)):
            q = ring.rigid_motion(*motion)
            scale = np.abs(q).max()
            elastic = np.abs(stiffness @ q).max() / (np.abs(stiffness).max() * scale)
            assert elastic < 1e-9, f"{source}: K q for {motion} is {elastic:.3g} of K's scale"
            lost = np.abs(hysteretic @ q).max() / ((np.abs(hysteretic).max() or 1.0) * scale)
            assert lost < 1e-9, f"{source}: the loss's K q for {motion} is {lost:.3g} of its scale"
            expected = np.zeros(ring.n_dof)
            if motion[2] and spin:
                expected[:n] = -2.0 * spin * tire.rhoA * arc * tire.R * kappa
                if sidewall != "massless":
                    expected[2 * n: 3 * n] = -2.0 * spin * tire.m_s * arc * tire.R * kappa
            rate = np.abs(damping @ q - expected).max() / (np.abs(damping).max() * scale)
            assert rate < 1e-9, f"{source}: C q for {motion} is off by {rate:.3g} of C's scale"
        assert np.all(np.diag(mass) > 0)


# ----- refusals -----

def _build(data, n, fields, spin=0.0, rim_free=1):
    lib = load_library()
    _declare(lib)
    size = max(lib.inplane_ring_n_dof(n, fields, rim_free), 1)
    matrices = [np.full((size, size), 7.0) for _ in MATRICES]
    work = np.zeros(max(lib.inplane_ring_work_doubles(n, fields), 1))
    why = ctypes.create_string_buffer(512)
    status = lib.inplane_ring_build(ctypes.byref(data), n, fields, spin, rim_free, 1,
                                    *(m.ctypes.data for m in matrices), work.ctypes.data,
                                    why, 512)
    return status, why.value.decode(), matrices


@pytest.mark.parametrize("change, n, fields, spin, words", [
    ({}, 4, 3, 0.0, ["n_elements = 4", "[8, 1600]"]),
    ({}, 24, 5, 0.0, ["n_fields = 5"]),
    ({}, 24, 3, math.inf, ["spin_rad_s = inf"]),
    ({"EI": math.nan}, 24, 3, 0.0, ["EI = nan", "(0, 1e+08] N*m^2"]),
    ({"R": 5.0}, 24, 2, 0.0, ["R = 5 m", "(0.1, 3] m"]),
    ({"m_s": 0.0}, 24, 3, 0.0, ["m_s = 0 kg/m", "[1e-06, 10000] kg/m"]),
    ({"rim_radius_m": 0.7}, 24, 3, 0.0, ["rim_radius_m = 0.7 m", "below the tread radius"]),
    ({"sidewall_pressure_exponent": 1.0, "inflation_pressure": 10.0}, 24, 3, 0.0,
     ["inflation_pressure = 10 Pa", "sidewall_pressure_exponent = 0"]),
    ({"loss_factor": 1.5}, 24, 3, 10.0, ["loss_factor = 1.5: allowed a finite number in [0, 1]"]),
    ({"loss_factor": -0.01}, 24, 2, 10.0, ["loss_factor = -0.01: allowed", "[0, 1]"]),
    ({"loss_factor": math.nan}, 24, 4, 10.0, ["loss_factor = nan: allowed", "[0, 1]"]),
    ({"sidewall_max_order": 2.5}, 24, 3, 0.0,
     ["sidewall_max_order = 2.5: allowed an integer in [0, 100000]"]),
    ({"sidewall_max_order": -1.0}, 24, 4, 0.0, ["sidewall_max_order = -1: allowed an integer"]),
    ({"sidewall_max_order": 2e5}, 24, 3, 0.0, ["sidewall_max_order = 200000", "[0, 100000]"]),
])
def test_bad_input_is_refused_with_a_sentence_and_nothing_written(change, n, fields, spin,
                                                                  words):
    data = ring_data(InPlaneTire())
    for name, value in change.items():
        setattr(data, name, value)
    status, why, matrices = _build(data, n, fields, spin)
    assert status != 0
    for word in words:
        assert word in why, why
    assert all(np.all(m == 7.0) for m in matrices)


def test_the_massless_ring_does_not_read_m_s():
    model = InPlaneTire(sidewall_mass=False)
    data = ring_data(model)
    data.m_s = 0.0  # a massless sidewall may say so
    status, why, (mass, *_) = _build(data, 16, n_fields(model), rim_free=0)
    assert status == 0, why
    np.testing.assert_array_equal(mass, InPlaneRing(model, 16).mass)


def test_the_wrapper_raises_the_c_sentence():
    with pytest.raises(ValueError, match=r"n_elements = 4: allowed an integer in \[8, 1600\]"):
        c_inplane_ring(InPlaneTire(), 4)


def test_the_loss_is_left_out_of_the_stiffness_as_the_python_leaves_it():
    """hysteresis=False (the simulator's three polynomial spins) drops the loss from K as the
    Python does, and K with it holds the loss at its share: C's K with it less C's K without
    it is the share of C's own hysteretic stiffness, which does not depend on the spin."""
    case = fixed_case("tied", 40, 0.0, True, 0.1, 8.0)
    model = model_of(case)
    full = c_inplane_ring(model, 40, 0.0, True).hysteretic_stiffness
    assert np.abs(full).max() > 0
    for spin in (0.3 * FULL_SHARE_SPIN, -0.8 * FULL_SHARE_SPIN, 2.0 * FULL_SHARE_SPIN, 60.0):
        without = c_inplane_ring(model, 40, spin, True, hysteresis=False)
        python = InPlaneRing(model, 40, spin, rim_free=True, hysteresis=False).stiffness
        scale = np.abs(python).max()
        assert np.abs(without.stiffness - python).max() <= TOLERANCE * scale
        with_loss = c_inplane_ring(model, 40, spin, True)
        np.testing.assert_array_equal(with_loss.hysteretic_stiffness, full)
        added = with_loss.stiffness - without.stiffness
        expected = hysteresis_share(spin, model.tire.R) * full
        assert np.abs(added - expected).max() <= TOLERANCE * scale


def test_the_tie_stores_nothing_on_the_sidewall_static_share_and_ends_below_half_the_mesh():
    """The tie ½p(w_s - r w)², r = k_r1/(k_r1 + k_r2), adds nothing to K's forces on any w
    with w_s = r w, and acts on the orders above its top one alone: an order-10 wave of w_s
    alone meets it at top order 8 and not at top order 12 (then K is the untied one); a top
    order at or above N/2 ties nothing (bit for bit the untied ring)."""
    n = 32
    plain = fixed_case("lumped", n, 25.0, False)
    tire = plain["tire"]
    k_r1, k_r2 = tire.effective_k_r1, tire.effective_k_r2
    untied = c_inplane_ring(model_of(plain), n, 25.0).stiffness
    theta = 2 * np.pi * np.arange(n) / n
    w = np.random.default_rng(3).standard_normal(n)
    q = np.zeros(4 * n)
    q[:n], q[2 * n: 3 * n] = w, k_r1 / (k_r1 + k_r2) * w
    wave = np.zeros(4 * n)
    wave[2 * n: 3 * n] = np.cos(10 * theta)
    scale = np.abs(untied).max()
    for top, acts in ((8.0, True), (12.0, False)):
        tied = c_inplane_ring(model_of(fixed_case("lumped", n, 25.0, False, 0.0, top)), n,
                              25.0).stiffness
        rounding = 1e-12 * np.abs(tied).max()
        assert np.abs((tied - untied) @ q).max() <= rounding * np.abs(q).max()
        on_wave = np.abs((tied - untied) @ wave).max()
        assert on_wave > 1e-3 * scale if acts else on_wave <= rounding, (top, on_wave, scale)
    for size in (16, 17):  # N/2 = 8 either way: order 8 is the highest, and it is not above 8
        base = fixed_case("tied", size, 25.0, True, 0.05)
        top_at_half = fixed_case("tied", size, 25.0, True, 0.05, 8.0)
        for a, b in zip(c_inplane_ring(model_of(base), size, 25.0, True),
                        c_inplane_ring(model_of(top_at_half), size, 25.0, True)):
            np.testing.assert_array_equal(a, b)


def test_the_full_share_loss_is_built_only_when_asked_for():
    """A NULL hysteretic matrix skips it (a native FMU that steps at one spin needs only K):
    the other three are those built with it."""
    model = model_of(fixed_case("lumped", 24, 0.5 * FULL_SHARE_SPIN, True, 0.1, 4.0))
    lib = load_library()
    _declare(lib)
    size = lib.inplane_ring_n_dof(24, 4, 1)
    matrices = [np.empty((size, size)) for _ in range(3)]
    work = np.empty(lib.inplane_ring_work_doubles(24, 4))
    why = ctypes.create_string_buffer(512)
    status = lib.inplane_ring_build(ctypes.byref(ring_data(model)), 24, 4,
                                    0.5 * FULL_SHARE_SPIN, 1, 1, *(m.ctypes.data for m in matrices),
                                    None, work.ctypes.data, why, 512)
    assert status == 0, why.value.decode()
    for a, b in zip(matrices, c_inplane_ring(model, 24, 0.5 * FULL_SHARE_SPIN, True)):
        np.testing.assert_array_equal(a, b)
