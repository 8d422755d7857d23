"""The hysteretic rolling loss of the in-plane ring (TangentialParameters.loss_factor): a
rate-independent loss of the ring's elastic forces in rolling, η K H with H the discrete
Hilbert transform along the ring, at a share of the spin that ramps up from rest."""

import math
from dataclasses import replace

import numpy as np
import pytest

from tire_fmu.core.inplane import (
    HYSTERESIS_FULL_SPEED_M_S,
    InPlaneRing,
    InPlaneTire,
    hilbert_circulant,
    hysteresis_share,
)
from tire_fmu.core.inplane_contact import InPlaneSimulator, deflection_for_load, steady_rolling

N = 48


def tire(loss_factor: float, beta: float | None = None) -> InPlaneTire:
    base = InPlaneTire()
    radial = base.tire if beta is None else replace(base.tire, beta=beta)
    return InPlaneTire(radial, replace(base.tangential, loss_factor=loss_factor))


def test_the_hilbert_circulant_turns_every_order_by_a_quarter():
    """H e^{inθ} = i sign(sin nδθ) e^{inθ}, written apart with the waves themselves."""
    for n in (8, 9, 48):
        h, theta = hilbert_circulant(n), 2 * np.pi * np.arange(n) / n
        for order in range(n):
            wave = np.exp(1j * order * theta)
            sign = np.sign(round(math.sin(2 * math.pi * order / n), 12))
            np.testing.assert_allclose(h @ wave, 1j * sign * wave, atol=1e-12)


def test_the_share_ramps_up_from_rest_and_leaves_the_paper_model_alone():
    radius = InPlaneTire().tire.R
    full = HYSTERESIS_FULL_SPEED_M_S / radius
    assert hysteresis_share(0.0, radius) == 0.0
    assert hysteresis_share(0.5 * full, radius) == pytest.approx(0.5)
    assert hysteresis_share(3 * full, radius) == 1.0 and hysteresis_share(-3 * full, radius) == -1
    # at rest, and without a loss factor, the stiffness is the paper model's to the bit
    at_rest = InPlaneRing(tire(0.1), N, 0.0, rim_free=True).stiffness
    assert np.array_equal(at_rest, InPlaneRing(tire(0.0), N, 0.0, rim_free=True).stiffness)
    spin = 20.0
    lossy = InPlaneRing(tire(0.1), N, spin, rim_free=True)
    plain = InPlaneRing(tire(0.0), N, spin, rim_free=True)
    np.testing.assert_allclose(lossy.stiffness - plain.stiffness, lossy.hysteretic_stiffness,
                               atol=1e-9 * np.abs(plain.stiffness).max())


def test_rigid_motions_meet_no_hysteretic_force():
    """Translation (order 1) is turned into translation and rotation (order 0) into nothing:
    K takes both to zero, so the tire moved or turned with its rim feels no loss."""
    ring = InPlaneRing(tire(0.1), N, 30.0, rim_free=True)
    scale = np.abs(ring.hysteretic_stiffness).max()
    assert scale > 0
    for motion in (dict(x_m=1.0), dict(z_m=1.0), dict(psi_rad=1.0)):
        q = ring.rigid_motion(**motion)
        assert np.abs(ring.hysteretic_stiffness @ q).max() < 1e-9 * scale * np.abs(q).max()


def test_the_loss_only_dissipates():
    """In steady rolling a material point moves at Ω D1 u through the ring's deformation u:
    the loss's power (Ω D1 u)·(η K H u) is >= 0 for every u (D1ᵀ K H is |D1| K order by
    order), checked on the ring's matrices as built, sidewall included."""
    ring = InPlaneRing(tire(0.1), N, 10.0)
    built = ring._built_hysteretic
    d1 = np.kron(np.eye(ring._n_built), ring._ops["d1"])
    power = d1.T @ built
    symmetric = 0.5 * (power + power.T)
    assert np.linalg.eigvalsh(symmetric).min() > -1e-9 * np.abs(symmetric).max()
    assert np.linalg.eigvalsh(symmetric).max() > 0


def _coefficient(model, speed_m_s, load_n=27700.0):
    deflection = deflection_for_load(model, load_n, N, point_spacing_m=0.01)
    steady = steady_rolling(InPlaneSimulator(model, N, speed_m_s, deflection,
                                             point_spacing_m=0.01))
    return -steady.rim_fx_n / steady.rim_fz_n


def test_the_rolling_resistance_of_the_loss_does_not_depend_on_speed():
    """Without viscous damping (β = 0) the free wheel's rolling resistance from the loss is
    the same at 5 and 20 m/s within 2 % (the ring's inertia moves it a little), where the
    paper's viscous β alone gives four times as much at four times the speed; it grows with
    the loss factor."""
    hysteretic = [_coefficient(tire(0.1, beta=0.0), v) for v in (5.0, 20.0)]
    viscous = [_coefficient(tire(0.0), v) for v in (5.0, 20.0)]
    assert hysteretic[0] > 0.003
    assert hysteretic[1] == pytest.approx(hysteretic[0], rel=0.02)
    assert viscous[1] / viscous[0] == pytest.approx(4.0, rel=0.05)
    assert 1.7 < _coefficient(tire(0.1, beta=0.0), 10.0) / _coefficient(
        tire(0.05, beta=0.0), 10.0) < 2.1
