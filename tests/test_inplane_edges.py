"""The tread elements' field at its ends: where the elements enter (the road's edge between
two points) and where the sticking stops. Checked against the field's closed form (a linear
field carried by a shift is the same line moved) and against steady_rolling, which the
step's settled state must reach as the step shrinks."""

from __future__ import annotations

import numpy as np
import pytest

from tire_fmu.core.inplane import InPlaneTire
from tire_fmu.core.inplane_contact import (
    MIN_ENTERING_FRACTION,
    InPlaneSimulator,
    carry_edges,
    carry_matrix,
    carry_stencil,
    deflection_for_load,
    entering_fraction_slopes,
    entering_fractions,
    steady_rolling,
)

THETA = np.linspace(-0.3, 0.3, 31)
SPACING = THETA[1] - THETA[0]


def test_the_edge_is_where_the_penetration_crosses_zero():
    pen = np.array([-3.0, -1.0, 1.0, 2.0, 2.5, -0.5, -1.0, 0.5, 1.5])
    contact = pen > 0
    delta = entering_fractions(pen, contact)
    # runs start at 2 (zero a third of a spacing ahead of it... 1/(1+1) = 1/2) and at 7
    assert delta[2] == pytest.approx(1.0 / 2.0)
    assert delta[7] == pytest.approx(0.5 / 1.5)
    assert np.all(np.delete(delta, [2, 7]) == 1.0)
    # the zone's first point has nothing ahead to tell: half a spacing
    assert entering_fractions(np.array([1.0, 1.0]), np.array([True, True]))[0] == 0.5
    # a point barely pressed: the least fraction, not zero
    assert entering_fractions(np.array([-1.0, 1e-9]), np.array([False, True]))[1] == (
        MIN_ENTERING_FRACTION)
    # the slopes are the fraction's derivatives (central differences)
    slopes = entering_fraction_slopes(pen, contact)
    for j, k in ((2, 0), (2, 1), (7, 0), (7, 1)):
        bump = np.zeros_like(pen)
        bump[j - 1 + k] = 1e-6
        numeric = (entering_fractions(pen + bump, contact)[j]
                   - entering_fractions(pen - bump, contact)[j]) / 2e-6
        assert slopes[j, k] == pytest.approx(numeric, rel=1e-6)


@pytest.mark.parametrize("shift", [0.05, 0.3, 0.9])
@pytest.mark.parametrize("delta_first", [0.5, 0.2, 0.95])
def test_a_linear_field_is_carried_exactly_across_both_ends(shift, delta_first):
    """A field linear from zero at the edge (δ spacings ahead of the first point in contact)
    to the last sticking point, carried by a shift under one spacing, is that line moved:
    the cubic is exact on a line once the stencils read it past the ends. Read as zero
    there (the carry alone), the points next to the ends are wrong by a share of the field."""
    first, last = 8, 20
    contact = np.zeros(THETA.size, dtype=bool)
    contact[first: last + 1] = True
    stick = contact.copy()
    edge = THETA[first] - delta_first * SPACING
    slope = 3.0
    e = np.where(contact, slope * (THETA - edge), 0.0)
    delta = np.ones(THETA.size)
    delta[first] = max(delta_first, shift)
    base, weights = carry_stencil(THETA, shift * SPACING)
    carried = carry_matrix(THETA, shift * SPACING) @ e
    corrected = carried + carry_edges(e, contact, stick, base, weights, delta)
    expected = slope * (THETA - shift * SPACING - edge)
    rows = slice(first, last + 1)
    if delta_first >= shift:  # the departure points are behind the edge: exact
        np.testing.assert_allclose(corrected[rows], expected[rows], rtol=0, atol=1e-12)
    assert np.max(np.abs(carried[rows] - expected[rows])) > 1e-3 * slope * SPACING


def test_a_sliding_point_behind_does_not_bend_the_sticking_field():
    """Behind the last sticking point the field is the sliding points' (held at a limit,
    here far below the line): the sticking points carry their own line on."""
    contact = np.zeros(THETA.size, dtype=bool)
    contact[5:25] = True
    stick = contact.copy()
    stick[18:25] = False
    e = np.where(contact, 2.0 * (THETA - THETA[5] + 0.5 * SPACING), 0.0)
    e[18:25] = 0.1 * e[18]  # the sliding elements at their limit
    delta = entering_fractions(np.where(contact, 1.0, -1.0), contact)
    base, weights = carry_stencil(THETA, 0.4 * SPACING)
    corrected = carry_matrix(THETA, 0.4 * SPACING) @ e + carry_edges(e, contact, stick, base,
                                                                       weights, delta)
    expected = 2.0 * (THETA - 0.4 * SPACING - THETA[5] + 0.5 * SPACING)
    np.testing.assert_allclose(corrected[5:18], expected[5:18], rtol=0, atol=1e-12)


def test_the_settled_step_reaches_the_steady_rolling_as_the_step_shrinks():
    """A -3 kN m brake at 10 m/s, wheel free, N = 100, 10 mm points (the first point in
    contact pressed by a few µm, its edge a few hundredths of a spacing ahead): the run's
    settled spin goes to steady_rolling's as the step is halved, at least linearly (the
    entering fraction is held at the step's shift at least, an error of the order of h), and
    its sliding points are the steady solve's."""
    model = InPlaneTire()
    deflection = deflection_for_load(model, 27700.0, 100, point_spacing_m=0.01)
    gaps = []
    for step_s in (2e-4, 1e-4, 5e-5):
        sim = InPlaneSimulator(model, 100, 10.0, deflection, point_spacing_m=0.01,
                               wheel="free", step_s=step_s)
        steady = steady_rolling(sim, -3000.0)
        run = sim.run(0.5, torque_n_m=-3000.0, record_every=int(round(1e-3 / step_s)))
        assert run.sliding_points[-1] == steady.sliding_points
        gaps.append(abs(run.spin_rad_s[-1] - steady.spin_rad_s))
    assert gaps[1] < 0.6 * gaps[0] and gaps[2] < 0.6 * gaps[1], gaps
    # and small against the brake's own slip (spin R/V - 1 = -1.2 %: 0.18 rad/s)
    assert gaps[2] < 0.01 * abs(steady.spin_rad_s - 10.0 / model.tire.R), gaps
