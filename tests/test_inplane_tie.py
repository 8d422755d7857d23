"""The radial sidewall's tie in the in-plane ring (sidewall_max_order > 0): above that order
the sidewall rides at its static share of the tread's radial displacement (the radial ring's
tie), so the sidewall's band, which has no wave speed, no longer sets a critical speed that
falls as the mesh is refined."""

from dataclasses import replace

import numpy as np
import pytest

from tire_fmu.core.inplane import InPlaneRing, InPlaneTire
from tire_fmu.core.inplane_contact import deflection_for_load
from tire_fmu.core.inplane_modes import critical_speed, order_matrices
from tire_fmu.core.parameters import ParameterError

TOP = 8.0


def tire(top: float) -> InPlaneTire:
    base = InPlaneTire()
    return InPlaneTire(replace(base.tire, sidewall_max_order=top), base.tangential)


def test_orders_up_to_the_top_are_the_lumped_sidewalls_and_above_it_tied():
    """The tie acts on orders above sidewall_max_order only: below, the order's matrices are
    the lumped sidewall's (to rounding); above, its radial sidewall stiffness is stiffer, and
    the tread-sidewall coupling carries the static share r = k_r1/(k_r1 + k_r2)."""
    n = 64
    lumped, tied = (InPlaneRing(tire(top), n, 15.0) for top in (0.0, TOP))
    t = tire(0.0).tire
    share = t.effective_k_r1 / (t.effective_k_r1 + t.effective_k_r2)
    w, w_s = 0, 2  # fields (w, v, w_s)
    for order in range(n // 2 + 1):
        k_l, k_t = (order_matrices(ring, order)[2] for ring in (lumped, tied))
        scale = np.abs(k_l).max()
        for a, b in zip(order_matrices(lumped, order)[:2], order_matrices(tied, order)[:2]):
            np.testing.assert_allclose(a, b, atol=1e-12 * np.abs(a).max())  # mass, damping
        if order <= TOP:
            np.testing.assert_allclose(k_t, k_l, atol=1e-12 * scale)
        else:
            added = k_t - k_l
            p = added[w_s, w_s].real
            assert p > 0.1 * scale
            np.testing.assert_allclose(added[w, w].real, share**2 * p, rtol=1e-9)
            np.testing.assert_allclose(added[w, w_s].real, -share * p, rtol=1e-9)
            assert np.abs(np.delete(np.delete(added, [w, w_s], 0), [w, w_s], 1)).max() < 1e-9 * p


def test_the_static_footprint_is_the_lumped_sidewalls():
    """Every static state has w_s = r w, where the tie stores nothing: the deflection that
    carries the load is the lumped sidewall's to solver precision."""
    deflections = [deflection_for_load(tire(top), 27700.0, 64, point_spacing_m=0.01)
                   for top in (0.0, TOP)]
    assert deflections[1] == pytest.approx(deflections[0], rel=1e-9)


def test_rigid_motions_meet_no_tie_force():
    ring = InPlaneRing(tire(TOP), 48, 20.0, rim_free=True)
    scale = np.abs(ring.stiffness).max()
    for motion in (dict(x_m=1.0), dict(z_m=1.0), dict(psi_rad=1.0)):
        q = ring.rigid_motion(**motion)
        assert np.abs(ring.stiffness @ q).max() < 1e-9 * scale


def test_the_critical_speed_converges_with_the_mesh():
    """Tied above order 8 the critical speed of N = 100 and 200 agree within 5 % (set by the
    highest free sidewall order); with the paper's lumped sidewall it halves."""
    tied = [critical_speed(tire(TOP), n).speed_m_s for n in (100, 200)]
    lumped = [critical_speed(tire(0.0), n).speed_m_s for n in (100, 200)]
    assert tied[1] == pytest.approx(tied[0], rel=0.05)
    assert lumped[1] / lumped[0] == pytest.approx(0.5, rel=0.05)
    assert tied[1] > 3 * lumped[1]


def test_a_sidewall_shear_is_refused_with_the_tie_as_remedy():
    base = InPlaneTire()
    with pytest.raises(ParameterError) as error:
        InPlaneTire(replace(base.tire, sidewall_shear=1e4), base.tangential)
    assert "sidewall_shear" in str(error.value) and "sidewall_max_order" in str(error.value)
