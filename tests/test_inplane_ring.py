"""The in-plane ring (radial and tangential motion, the rim's rotation) against closed forms.

References written apart from the FDM code: the per-order continuum forms of
core/inplane_analytic.py, the two-inertia torsion of order 0 written here, Huang & Soedel's
split of an inextensible ring, and exact rigid-body motions.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg

from tire_fmu.core.inplane import InPlaneRing, InPlaneTire, TangentialParameters
from tire_fmu.core.inplane_analytic import inextensible_split_factor, inplane_analytic_modes
from tire_fmu.core.inplane_modes import (
    order_frequencies_at_rest_hz,
    order_frequencies_hz,
    order_matrices,
    quadratic_eigenvalues,
    tire_modes,
)
from tire_fmu.core.parameters import DEFAULT_LOAD_N, ParameterError, TireParameters

PAPER = TireParameters(sidewall_max_order=0.0)
ORDERS = range(11)


def classical(**tangential) -> InPlaneTire:
    """The classical extensible ring on radial and tangential foundations: no pressure, a
    massless sidewall (springs in series)."""
    return InPlaneTire(replace(PAPER, inflation_pressure=0.0),
                       TangentialParameters(**tangential), sidewall_mass=False)


MODELS = {
    "classical": classical(),
    "tied sidewall": InPlaneTire(),
    "lumped sidewall": InPlaneTire(sidewall_tangential="lumped"),
}


def max_order_error(model: InPlaneTire, n_elements: int) -> np.ndarray:
    exact = inplane_analytic_modes(model, ORDERS).frequencies_hz
    ring = InPlaneRing(model, n_elements)
    return np.array([np.max(np.abs(order_frequencies_at_rest_hz(ring, n) / exact[n] - 1.0))
                     for n in ORDERS])


@pytest.mark.parametrize("name", MODELS)
def test_every_order_and_branch_within_half_a_percent_at_n400(name):
    assert max_order_error(MODELS[name], 400).max() < 5e-3


@pytest.mark.parametrize("name", MODELS)
def test_frequencies_converge_at_second_order(name):
    errors = [max_order_error(MODELS[name], n)[1:].max() for n in (100, 200, 400)]
    rates = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    assert all(1.9 < rate < 2.1 for rate in rates), rates


@pytest.mark.parametrize("name", MODELS)
def test_assembled_spectrum_is_the_union_of_the_orders(name):
    """The per-order Fourier blocks are an exact block-diagonalisation of the assembled ring."""
    ring = InPlaneRing(MODELS[name], 24)
    full = np.sqrt(scipy.linalg.eigvalsh(ring.stiffness, ring.mass)) / (2 * np.pi)
    per_order = np.sort(np.concatenate([order_frequencies_at_rest_hz(ring, n)
                                        for n in range(-11, 13)]))
    np.testing.assert_allclose(per_order, full, rtol=1e-9)


def test_order_zero_separates_into_breathing_and_torsion():
    model = classical()
    k_r, k_t = model.series_foundation()
    t, ea = model.tire, model.tangential.EA
    ring = InPlaneRing(model, 100)
    breathing = math.sqrt((ea / t.R**2 + k_r) / t.rhoA) / (2 * np.pi)
    torsion = math.sqrt(k_t / t.rhoA) / (2 * np.pi)
    np.testing.assert_allclose(order_frequencies_at_rest_hz(ring, 0), [torsion, breathing],
                               rtol=1e-10)


def test_translation_of_order_one_rides_on_the_foundation_alone():
    """With a membrane too stiff to stretch the order-1 translation stores no membrane or
    bending energy: sqrt((k_r + k_t)/(2ρA))."""
    model = classical(EA=1e12, k_t1=1.0e6, k_t2=3.0e6)  # k_t != k_r: no accidental symmetry
    k_r, k_t = model.series_foundation()
    expected = math.sqrt((k_r + k_t) / (2 * model.tire.rhoA)) / (2 * np.pi)
    lowest = order_frequencies_at_rest_hz(InPlaneRing(model, 400), 1)[0]
    assert lowest == pytest.approx(expected, rel=1e-3)


# ----- rigid motions -----

@pytest.mark.parametrize("sidewall", ["tied", "lumped"])
@pytest.mark.parametrize("speed_m_s", [0.0, 20.0])
def test_rigid_translation_and_rotation_give_no_force(sidewall, speed_m_s):
    """The whole tire moved with its rim (1 mm, 1 mrad): forces on every DOF and on the rim
    below 1e-6 of the static load, at rest and rolling; a rigid translation at constant rate
    meets no damping or gyroscopic force."""
    model = InPlaneTire(sidewall_tangential=sidewall)
    ring = InPlaneRing(model, 100, spin_rad_s=speed_m_s / model.tire.R, rim_free=True)
    bound = 1e-6 * DEFAULT_LOAD_N
    for motion in [(1e-3, 0, 0), (0, 1e-3, 0), (0, 0, 1e-3)]:
        q = ring.rigid_motion(*motion)
        assert np.abs(ring.stiffness @ q).max() < bound
        assert np.abs(ring.rim_force(q, q)).max() < bound
    for motion in [(1e-3, 0, 0), (0, 1e-3, 0)]:
        assert np.abs(ring.damping @ ring.rigid_motion(*motion)).max() < bound


def test_spin_up_is_a_uniform_radial_load_with_no_net_force():
    """A change of spin rate ψ̇ at speed loads the ring through Coriolis as the extra
    centrifugal force 2Ωψ̇ R ρA per metre, outwards and uniform: no force or moment."""
    model = InPlaneTire(sidewall_mass=False)
    spin = 30.0
    ring = InPlaneRing(model, 64, spin_rad_s=spin, rim_free=True)
    rate = ring.rigid_motion(psi_rad=1.0)  # ψ̇ = 1 rad/s
    force = ring.damping @ rate
    w = force[ring.field_slice("w")]
    # the discrete L turns a rotation into κ₁ of it (κ₁ = sin δθ/δθ)
    expected = 2 * spin * model.tire.rhoA * ring.node_arc_m * model.tire.R * ring.kappa1
    np.testing.assert_allclose(-w, expected, rtol=1e-12)  # M q̈ + C q̇: -C q̇ is outwards
    np.testing.assert_allclose(ring.rim_patterns.T @ force[: ring.n_ring_dof], 0, atol=1e-9)


# ----- rolling -----

@pytest.mark.parametrize("order", [2, 3, 4, 5, 6])
def test_rolling_split_is_huang_and_soedel_for_a_stiff_membrane(order):
    model = InPlaneTire(replace(PAPER, alpha=0.0, beta=0.0), TangentialParameters(EA=1e11),
                        sidewall_mass=False)
    spin = 2.0
    f = order_frequencies_hz(InPlaneRing(model, 400, spin_rad_s=spin), order)
    lowest = np.sort(np.abs(f))[:2]
    split = (lowest[1] - lowest[0]) * 2 * np.pi
    expected = 2 * spin * inextensible_split_factor(order)
    assert split == pytest.approx(expected, rel=0.03)


def order_one_split_hz(model: InPlaneTire, n_elements: int, spin_rad_s: float) -> float:
    """The n = 1 pair's ground-frame split to first order in the spin, written here from the
    mode's amplitudes at rest: with w = W cos θ, v = V sin θ, the tied sidewall's w_s = W_s cos
    θ and v_s = r v (masses ρA, ρA + r² m_s on v, m_s on w_s), the gyroscopic 2Ω M L on the
    mode gives 2Ω (ñ T - κ₁ X) / T, T = ρA W² + (ρA + r² m_s) V² + m_s W_s² (the mode's mass),
    X = 2 V (ρA W + r m_s W_s) (the Coriolis coupling of the radial and tangential motion of
    tread and sidewall), ñ = sin δθ/δθ the central difference's wavenumber and κ₁ the same:
    zero for a rigid translation (V = W and W_s = r W) and, with the sidewall stretched
    against the tread (k_r ≠ k_t), the little left of it."""
    m, _, k = order_matrices(InPlaneRing(model, n_elements), 1)
    _, vectors = scipy.linalg.eigh(0.5 * (k + k.conj().T), 0.5 * (m + m.conj().T))
    phi = vectors[:, 0] / vectors[0, 0]
    w, v, w_s = phi[0].real, phi[1].imag, phi[2].real
    t, r = model.tire, model.tangential_share
    mass = t.rhoA * w * w + (t.rhoA + r * r * t.m_s) * v * v + t.m_s * w_s * w_s
    coupling = 2.0 * v * (t.rhoA * w + r * t.m_s * w_s)
    wavenumber = np.sin(2 * np.pi / n_elements) / (2 * np.pi / n_elements)
    return abs(2.0 * spin_rad_s * wavenumber * (mass - coupling) / mass) / (2 * np.pi)


@pytest.mark.parametrize("speed, rel", [(5.0, 0.01), (40.8, 0.03)])
def test_order_one_pair_splits_as_derived(speed, rel):
    """n(n²-1)/(n²+1) = 0 at n = 1: a rigid translation does not split (the radial-only ring
    splits it 47.3 / 67.3 Hz at 40.8 m/s). The default tire's pair splits by what is left
    of it, derived above from the mode at rest: within 1 % at 5 m/s (first order in the spin),
    3 % at 40.8 m/s; and that is a few tenths of a per cent of its frequency."""
    model = InPlaneTire(replace(PAPER, alpha=0.0, beta=0.0))
    at_rest = order_frequencies_at_rest_hz(InPlaneRing(model, 200), 1)[0]
    spin = speed / model.tire.R
    f = order_frequencies_hz(InPlaneRing(model, 200, spin_rad_s=spin), 1)
    pair = np.sort(np.abs(f))[:2]
    derived = order_one_split_hz(model, 200, spin)
    assert pair[1] - pair[0] == pytest.approx(derived, rel=rel)
    assert pair[1] - pair[0] < 0.005 * at_rest
    assert np.abs(pair - at_rest).max() < 0.01 * at_rest


def test_rolling_undamped_ring_is_stable_and_real():
    """Gyroscopic only (K > 0 at every speed for the tread): every root on the imaginary
    axis at 30 m/s."""
    model = InPlaneTire(replace(PAPER, alpha=0.0, beta=0.0), sidewall_mass=False)
    ring = InPlaneRing(model, 64, spin_rad_s=30.0 / model.tire.R)
    for n in range(6):
        s = quadratic_eigenvalues(*order_matrices(ring, n))
        assert np.abs(s.real).max() < 1e-6 * np.abs(s.imag).max()


# ----- the rotational mode -----

def torsion_closed_form_hz(model: InPlaneTire) -> tuple[float, float]:
    """Order 0 tangential with the tied sidewall, written here: the tread turns by φ
    (v = Rφ), the rim by ψ, the sidewall at v_s = R(rφ + (1 - r)ψ); the series spring k_t on
    R(φ - ψ). Returns (rim held, rim free) in Hz."""
    t, tang = model.tire, model.tangential
    r = model.tangential_share
    k_t = tang.k_t1 * tang.k_t2 / (tang.k_t1 + tang.k_t2)
    length = 2 * np.pi * t.R
    inertia = length * t.R**2
    mass = np.array([[inertia * (t.rhoA + t.m_s * r**2), inertia * t.m_s * r * (1 - r)],
                     [inertia * t.m_s * r * (1 - r),
                      inertia * t.m_s * (1 - r) ** 2 + tang.wheel_inertia_kg_m2]])
    stiffness = length * k_t * t.R**2 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    held = math.sqrt(stiffness[0, 0] / mass[0, 0]) / (2 * np.pi)
    free = math.sqrt(scipy.linalg.eigvalsh(stiffness, mass)[1]) / (2 * np.pi)
    return held, free


def test_rotational_mode_with_rim_held_and_free():
    model = InPlaneTire()
    held, free = torsion_closed_form_hz(model)
    modes_held = tire_modes(InPlaneRing(model, 100), f_max_hz=120)
    modes_free = tire_modes(InPlaneRing(model, 100, rim_free=True), f_max_hz=120)
    (rot_held,) = modes_held.select(kind="rotational")
    (rot_free,) = modes_free.select(kind="rotational")
    assert rot_held.frequency_hz == pytest.approx(held, rel=1e-9)
    assert rot_free.frequency_hz == pytest.approx(free, rel=1e-9)
    assert len(modes_free.select(kind="rigid")) == 3  # x, z and the free spin


def test_a_heavier_wheel_lowers_the_free_rotational_mode_towards_the_held_one():
    def free_hz(inertia):
        model = InPlaneTire(tangential=TangentialParameters(wheel_inertia_kg_m2=inertia))
        (mode,) = tire_modes(InPlaneRing(model, 32, rim_free=True), 200).select(
            kind="rotational")
        return mode.frequency_hz
    held, _ = torsion_closed_form_hz(InPlaneTire())
    values = [free_hz(i) for i in (2.0, 8.0, 1e5)]
    assert values[0] > values[1] > values[2]
    assert values[2] == pytest.approx(held, rel=1e-3)  # I_ring/I_w = 4e-4


# ----- parameters -----

def test_every_tangential_problem_is_reported_at_once():
    with pytest.raises(ParameterError) as error:
        InPlaneTire(tangential=TangentialParameters(EA=-1.0, rim_radius_m=0.9))
    text = str(error.value)
    assert "EA = -1 N: must be a number in [1000, 1e+12] N" in text
    assert "rim_radius_m = 0.9 m: must be below the tread radius R = 0.65 m" in text


# ----- the command -----

def test_command_reports_the_modes_the_core_computes(capsys):
    import json

    from tire_fmu.cli import main

    assert main(["inplane-modes", "--rim-free", "--elements", "40", "--max-frequency", "80",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    expected = tire_modes(InPlaneRing(InPlaneTire(), 40, rim_free=True), f_max_hz=80)
    assert [m["kind"] for m in data["modes"]] == [m.kind for m in expected.modes]
    np.testing.assert_allclose([m["frequency_hz"] for m in data["modes"]],
                               expected.frequencies_hz(), rtol=1e-12, atol=1e-9)
    held, free = torsion_closed_form_hz(InPlaneTire())
    (rotational,) = [m for m in data["modes"] if m["kind"] == "rotational"]
    assert rotational["frequency_hz"] == pytest.approx(free, rel=1e-9)
    # at speed: the per-order waves and the mesh's critical speed
    from tire_fmu.core.inplane_modes import critical_speed

    assert main(["inplane-modes", "--elements", "40", "--speed", "10", "--nmax", "2",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["critical_speed"]["critical_speed_m_s"] == pytest.approx(
        critical_speed(InPlaneTire(), 40).speed_m_s, rel=1e-12)


def test_command_refuses_bad_tangential_data_in_one_line(capsys):
    from tire_fmu.cli import main

    assert main(["inplane-modes", "--tangential", "EA=-3", "--tangential", "k_t2=0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "EA = -3 N" in err and "k_t2 = 0 N/m^2" in err
    assert main(["inplane-modes", "--tangential", "EA"]) == 2
    assert "expected NAME=VALUE" in capsys.readouterr().err


@pytest.mark.parametrize("n_elements", [60, 100])
def test_the_critical_speed_is_where_a_wave_stands_still(n_elements):
    """inplane_modes.critical_speed solves K_n(Ω) singular exactly. Checked on the rolling
    ring built at the speed itself (no polynomial in the spin): below it every order has as
    many ground-frame waves against θ as with it (each frequency of the ring at rest, shifted
    but not through zero); just above it one wave of the critical order has passed through
    zero, so it stands still in between. With the lumped radial sidewall it is the radial
    ring's mesh-bound critical speed (its sidewall band standing still), which the tangential
    motion barely moves."""
    from tire_fmu.core.inplane_modes import critical_speed, quadratic_eigenvalues
    from tire_fmu.core.standing_waves import critical_speed as radial_critical_speed

    model = InPlaneTire()
    found = critical_speed(model, n_elements)
    assert found.branch == "radial"
    assert found.speed_m_s == pytest.approx(
        radial_critical_speed(model.tire, n_elements).speed_m_s, rel=0.01)
    undamped = replace(model, tire=replace(model.tire, alpha=0.0, beta=0.0))

    def against_theta(ring, n):
        return int(np.sum(quadratic_eigenvalues(*order_matrices(ring, n)).imag > 0))

    below, above = (InPlaneRing(undamped, n_elements, spin_rad_s=f * found.spin_rad_s)
                    for f in (0.99, 1.01))
    assert all(against_theta(below, n) == below.n_fields for n in range(n_elements // 2 + 1))
    assert against_theta(above, found.order) != above.n_fields


@pytest.mark.parametrize("spin", [0.0, 40.0])
@pytest.mark.parametrize("top_order", [0.0, 6.0])
def test_the_order_matrices_are_the_ring_projected_on_each_wave(spin, top_order):
    """order_matrices reads each order off one FFT per circulant block: it must be the dense
    ring projected on the unit Fourier vectors e^{inθ}/√N of each field, every order, with the
    rolling's terms, the lumped sidewall and the radial tie (which is per order, so stays
    circulant)."""
    model = InPlaneTire(TireParameters(sidewall_max_order=top_order),
                        replace(InPlaneTire().tangential, loss_factor=0.05))
    for sidewall in ("tied", "lumped"):
        ring = InPlaneRing(replace(model, sidewall_tangential=sidewall), 24, spin_rad_s=spin)
        wave = np.exp(1j * np.outer(ring.theta, np.arange(-12, 13))) / math.sqrt(24)
        for n, column in zip(range(-12, 13), wave.T):
            f = np.kron(np.eye(ring.n_fields), column[:, None])
            for dense, fast in zip((ring.mass, ring.damping, ring.stiffness),
                                   order_matrices(ring, n)):
                projected = f.conj().T @ dense @ f
                assert np.abs(fast - projected).max() <= 1e-13 * np.abs(dense).max(), (
                    sidewall, n)
