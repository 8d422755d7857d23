"""native/c/inplane_ring.c against core/inplane.py: the in-plane ring's M, K and C built in C
equal the Python's to rounding over random tires, meshes, spins and sidewall models; a rigid
motion of tire and rim meets no elastic or damping force in either (the Coriolis load of a spin
change apart, written here); the C refuses bad input with a sentence and writes nothing."""

from __future__ import annotations

import ctypes
import math
from dataclasses import replace

import numpy as np
import pytest

from tire_fmu.core.inplane import InPlaneRing, InPlaneTire, TangentialParameters
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
N_RANDOM = 30


def random_case(seed: int) -> dict:
    """A tire, mesh, spin and rim of one seed. The rim radius is drawn as a share of R (x2 of
    the default share) so that it always sits inside the tread; the pressure law (exponent 0
    by default) is on in half the tires; meshes are log-uniform in 8-160, the costly 400 comes
    from the fixed cases (the Python's dense products are O(n^3))."""
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
    return dict(
        sidewall=sidewall, n=int(round(8 * 20 ** rng.uniform(0.0, 1.0))),
        spin=0.0 if seed % 4 == 0 else float(rng.uniform(0.0, 100.0)),
        rim_free=bool((seed // 3) % 2), tire=tire, tangential=tangential)


def model_of(case: dict) -> InPlaneTire:
    sidewall = case["sidewall"]
    return InPlaneTire(case["tire"], case["tangential"], sidewall_mass=sidewall != "massless",
                       sidewall_tangential="lumped" if sidewall == "lumped" else "tied")


def fixed_case(sidewall, n, spin, rim_free, **tire) -> dict:
    return dict(sidewall=sidewall, n=n, spin=spin, rim_free=rim_free,
                tire=TireParameters(sidewall_max_order=0.0, **tire),
                tangential=TangentialParameters())


CASES = {f"random{seed}": random_case(seed) for seed in range(N_RANDOM)}
CASES.update({
    "tied_400_rolling_free": fixed_case("tied", 400, 100.0, True),
    "lumped_400_rest_held": fixed_case("lumped", 400, 0.0, False),
    "massless_8_rolling_free": fixed_case("massless", 8, 37.0, True),
    "tied_8_no_pressure": fixed_case("tied", 8, 5.0, True, inflation_pressure=0.0),
})


def worst_entries(case: dict):
    """Per matrix (name, worst |C - Python| over the largest |Python| entry, (row, column),
    C's value, Python's value)."""
    model = model_of(case)
    ring = InPlaneRing(model, case["n"], spin_rad_s=case["spin"], rim_free=case["rim_free"])
    built = c_inplane_ring(model, case["n"], case["spin"], case["rim_free"])
    out = []
    for name, c, py in zip(("mass", "stiffness", "damping"), built,
                           (ring.mass, ring.stiffness, ring.damping)):
        assert c.shape == py.shape, f"{name}: C {c.shape}, Python {py.shape}"
        difference = np.abs(c - py)
        index = np.unravel_index(int(np.argmax(difference)), difference.shape)
        out.append((name, float(difference[index] / np.abs(py).max()),
                    tuple(int(i) for i in index), float(c[index]), float(py[index])))
    return out


@pytest.mark.parametrize("label", list(CASES))
def test_c_matrices_equal_the_python_ones(label):
    case = CASES[label]
    failures = [f"{name} differs most at (row, column) = {index}: C {c!r}, Python {py!r}, "
                f"{worst:.3g} of its largest entry"
                for name, worst, index, c, py in worst_entries(case) if not worst <= TOLERANCE]
    assert not failures, (f"{label} ({case['sidewall']}, N = {case['n']}, spin "
                          f"{case['spin']:g} rad/s, rim {'free' if case['rim_free'] else 'held'}"
                          "): " + "; ".join(failures))


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


# ----- rigid motions, written apart from both builders -----

@pytest.mark.parametrize("sidewall", SIDEWALLS)
@pytest.mark.parametrize("spin", [0.0, 70.0])
def test_rigid_motion_with_the_rim_meets_no_force(sidewall, spin):
    """Tire and rim moved rigidly (x, z, ψ): K q vanishes, and so does C q for a translation;
    a rotation rate at speed meets the Coriolis force of a spin change, 2Ω ρA R κ₁ inwards on
    every tread node (2Ω m_s R κ₁ on each sidewall mass) and nothing else, κ₁ = sin δθ/δθ the
    discrete L's weight of a rigid rotation."""
    case = fixed_case(sidewall, 36, spin, True)
    case["tire"] = replace(case["tire"], m_s=7.5, alpha=3e-3)  # damping well above rounding
    model = model_of(case)
    ring = InPlaneRing(model, 36, spin_rad_s=spin, rim_free=True)
    n, tire = 36, model.tire
    arc, kappa = tire.R * 2 * math.pi / n, math.sin(2 * math.pi / n) / (2 * math.pi / n)
    for source, (mass, stiffness, damping) in (
            ("C", c_inplane_ring(model, n, spin, True)),
            ("Python", (ring.mass, ring.stiffness, ring.damping))):
        for motion in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)):
            q = ring.rigid_motion(*motion)
            scale = np.abs(q).max()
            elastic = np.abs(stiffness @ q).max() / (np.abs(stiffness).max() * scale)
            assert elastic < 1e-9, f"{source}: K q for {motion} is {elastic:.3g} of K's scale"
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
    matrices = [np.full((size, size), 7.0) for _ in range(3)]
    work = np.zeros(max(lib.inplane_ring_work_doubles(n, fields), 1))
    why = ctypes.create_string_buffer(512)
    status = lib.inplane_ring_build(ctypes.byref(data), n, fields, spin, rim_free,
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
    status, why, (mass, _, _) = _build(data, 16, n_fields(model), rim_free=0)
    assert status == 0, why
    np.testing.assert_array_equal(mass, InPlaneRing(model, 16).mass)


def test_the_wrapper_raises_the_c_sentence():
    with pytest.raises(ValueError, match=r"n_elements = 4: allowed an integer in \[8, 1600\]"):
        c_inplane_ring(InPlaneTire(), 4)


def test_what_the_c_does_not_build_yet_is_refused_not_built_wrong():
    """The hysteretic loss and the radial tie are the Python ring's only (for now): the
    wrapper names them rather than returning the ring without them."""
    lossy = InPlaneTire(tangential=TangentialParameters(loss_factor=0.05))
    tied = InPlaneTire(TireParameters(sidewall_max_order=8.0))
    with pytest.raises(ValueError, match=r"hysteretic loss \(loss_factor = 0\.05\)"):
        c_inplane_ring(lossy, 32)
    with pytest.raises(ValueError, match=r"sidewall's tie \(sidewall_max_order = 8\)"):
        c_inplane_ring(tied, 32)
    # a top order at or above N/2 ties nothing: that ring is the lumped one, which the C builds
    mass, _, _ = c_inplane_ring(tied, 16)
    np.testing.assert_array_equal(mass, InPlaneRing(tied, 16).mass)
