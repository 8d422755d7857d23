"""The rim load over a cleat, rim held at its static height: against an unreduced integration
written here, converged in the mesh with the contact points, and free of the node-passing
chatter that drops the contact force to zero at node spacing (issue 21).

The unreduced integration uses only the assembled structural matrices (model.structure: M,
D, K of tread and sidewall, no contact springs), the contact points as the contact-point
definition gives them (built here from its text, and compared with the zone's own arrays),
the exact window average of the cleat under each point, and an implicit trapezoidal rule with
a semismooth Newton solve of the contact law of its own; it never calls the simulator, the
modal ring or the step kernel.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tire_fmu.core import OperatingPoint, build_model
from tire_fmu.core.obstacles import cleat
from tire_fmu.core.studies import (
    CLEAT_POINT_SPACING_M,
    cleat_convergence,
    richardson,
)

#: A spacing above any node arc the tests use: every node is its own contact point (the node
#: contact of before the contact points).
NODE_SPACING_M = 1.0
CLEAT = cleat(0.02, 0.02)
SPEED_M_S = 10.0
#: The contact force's line at the node-passing frequency while the cleat is under the tire
#: stays below this fraction of the static load with the contact points (docs/theory.md).
LINE_LEVEL = 0.1


# -- the unreduced model and its integration, written here ------------------------------------


def spec_points(n_elements: int, radius: float, zone_length: float, spacing: float):
    """Contact points as the definition states them: angles θ_p, the ring nodes each reads
    and the cubic Lagrange weights, and m (points per node arc)."""
    dtheta = 2 * math.pi / n_elements
    arc = radius * dtheta
    half_angle = min(math.atan(0.5 * zone_length / radius), math.pi / 3)
    h = sum(1 for j in range(1, n_elements // 2 + 1) if j * dtheta <= half_angle * (1 + 1e-12))
    carrying = np.arange(-h, h + 1)
    m = 1
    while arc / m > spacing * (1 + 1e-9):
        m += 2
    if m == 1:
        return carrying * dtheta, carrying[:, None] % n_elements, np.ones((carrying.size, 1)), 1
    theta, support, weight = [], [], []
    for j in carrying:
        for i in range(m):
            u = j * m + i - (m - 1) // 2
            b = u // m
            s = (u - b * m) / m
            theta.append(u * dtheta / m)
            support.append([(b + o) % n_elements for o in (-1, 0, 1, 2)])
            weight.append([-s * (s - 1) * (s - 2) / 6, (s + 1) * (s - 1) * (s - 2) / 2,
                           -(s + 1) * s * (s - 2) / 2, (s + 1) * s * (s - 1) / 6])
    return np.array(theta), np.array(support), np.array(weight), m


class UnreducedCleatRun:
    """M ẅ + D ẇ + K w = -Eᵀ f on all 2N DOFs, f = max(0, k p + c ṗ) where p > 0 at the
    contact points, p = R + (E w)_p - (H - h_p)/cos θ_p, rim held at H = R - δ."""

    def __init__(self, tire, n_elements: int, speed: float, spacing: float, deflection: float,
                 zone_length: float):
        op = OperatingPoint(n_elements=n_elements, patch_length_m=0.0, speed_m_s=speed)
        structure = build_model(tire, op).structure  # the ring alone: no contact springs
        n = n_elements
        self.n = n
        self.mass = structure.mass.diagonal()
        self.stiffness = structure.stiffness.toarray()
        self.damping = structure.damping.toarray()
        theta_nodes = 2 * np.pi / n * np.where(2 * np.arange(n) <= n, np.arange(n),
                                               np.arange(n) - n)
        self.translation = -np.cos(np.r_[theta_nodes, theta_nodes])
        self.theta, self.support, self.weight, self.m = spec_points(
            n, tire.R, zone_length, spacing)
        points = self.theta.size
        self.interp = np.zeros((points, 2 * n))
        for p in range(points):
            np.add.at(self.interp[p], self.support[p], self.weight[p])
        self.sec = 1.0 / np.cos(self.theta)
        self.point_cos = self.interp[:, :n] @ np.cos(theta_nodes)
        self.k = tire.k_cw * tire.R * 2 * np.pi / n / self.m * np.ones(points)
        self.c = tire.beta * self.k
        self.radius, self.height = tire.R, tire.R - deflection
        self.speed = speed
        half = np.pi / n / self.m
        self.x_lo = -self.height * np.tan(self.theta + half)
        self.x_hi = -self.height * np.tan(self.theta - half)

    def gap_free(self, road, road_rate):
        """p and ṗ less their (E w, E ẇ) parts."""
        return self.radius - (self.height - road) * self.sec, road_rate * self.sec

    def forces(self, w, v, road, road_rate):
        p0, r0 = self.gap_free(road, road_rate)
        p, rate = p0 + self.interp @ w, r0 + self.interp @ v
        push = self.k * p + self.c * rate
        active = (p > 0) & (push > 0)
        return np.where(active, push, 0.0), active

    def static(self):
        """K w = -Eᵀ k p on the pushing points: an active-set iteration from the flat gap."""
        p0, _ = self.gap_free(0.0, 0.0)
        active = p0 > 0
        for _ in range(100):
            ek = self.interp[active].T * self.k[active]
            w = np.linalg.solve(self.stiffness + ek @ self.interp[active], -ek @ p0[active])
            p = p0 + self.interp @ w
            new = p > 0
            if np.array_equal(new, active):
                return w
            active = new
        raise AssertionError("static active set did not settle")

    def road(self, first_edge_x, obstacle):
        """Exact window average of a rectangular obstacle [X, X + L] under each point, and
        its rate (the obstacle moves at -V)."""
        lo, hi = first_edge_x, first_edge_x + obstacle.length_m
        width = self.x_hi - self.x_lo
        overlap = np.minimum(self.x_hi, hi) - np.maximum(self.x_lo, lo)
        on = overlap > 0
        height = np.where(on, obstacle.height_m * overlap / width, 0.0)
        d_overlap = ((self.x_lo < hi) & (hi < self.x_hi)).astype(float) \
            - ((self.x_lo < lo) & (lo < self.x_hi)).astype(float)
        rate = np.where(on, -self.speed * obstacle.height_m * d_overlap / width, 0.0)
        return height, rate

    def rim_fz(self, w, v):
        return float(self.translation @ (self.stiffness @ w + self.damping @ v))

    def run(self, obstacle, times, substeps: int):
        """rim_Fz and contact_Fz at ``times`` (first edge at x = -V t), trapezoidal rule with
        ``substeps`` steps between samples, each solved by semismooth Newton."""
        w = self.static()
        v = np.zeros_like(w)
        m_diag = np.diag(self.mass)
        h = (times[1] - times[0]) / substeps
        system = m_diag + 0.5 * h * self.damping + 0.25 * h * h * self.stiffness
        t = times[0]
        road, rate = self.road(-self.speed * t, obstacle)
        f, _ = self.forces(w, v, road, rate)
        accel = -self.damping @ v - self.stiffness @ w - self.interp.T @ f
        rim, contact = [self.rim_fz(w, v)], [float(self.point_cos @ f)]
        for _ in range(times.size - 1):
            for _ in range(substeps):
                t += h
                road, rate = self.road(-self.speed * t, obstacle)
                rhs = self.mass * v + 0.5 * h * accel \
                    - 0.5 * h * (self.stiffness @ (w + 0.5 * h * v))
                v1 = v.copy()
                for _ in range(50):
                    w1 = w + 0.5 * h * (v + v1)
                    f1, active = self.forces(w1, v1, road, rate)
                    residual = system @ v1 + 0.5 * h * (self.interp.T @ f1) - rhs
                    gain = (0.5 * h * self.k + self.c) * active
                    jacobian = system + 0.5 * h * (self.interp.T * gain) @ self.interp
                    step = np.linalg.solve(jacobian, residual)
                    v1 = v1 - step
                    if np.max(np.abs(step)) <= 1e-12 * (1 + np.max(np.abs(v1))):
                        break
                else:
                    raise AssertionError("semismooth Newton did not converge")
                w = w + 0.5 * h * (v + v1)
                v = v1
                f, _ = self.forces(w, v, road, rate)
                accel = -self.damping @ v - self.stiffness @ w - self.interp.T @ f
            rim.append(self.rim_fz(w, v))
            contact.append(float(self.point_cos @ f))
        return np.array(rim), np.array(contact)


# -- 1. the production simulator against the unreduced integration ----------------------------


@pytest.fixture(scope="module")
def coarse(tire):
    """The study on N = 50 (points at the default spacing, where the core has them)."""
    return cleat_convergence(tire, CLEAT, SPEED_M_S, n_elements=(50,), settle_s=0.0)


def test_simulator_matches_an_unreduced_integration(tire, coarse):
    op = OperatingPoint(n_elements=50, speed_m_s=SPEED_M_S,
                        contact_zone_length_m=float(coarse.contact_zone_length_m[0]))
    patch = build_model(tire, op).patch
    reference = UnreducedCleatRun(tire, 50, SPEED_M_S, CLEAT_POINT_SPACING_M,
                                  patch.deflection_m, float(coarse.contact_zone_length_m[0]))
    assert reference.m == coarse.points_per_node[0] > 1
    # the points built here are the zone's
    zone = patch.zone
    np.testing.assert_allclose(zone.point_theta, reference.theta, rtol=0, atol=1e-15)
    on_ring = np.zeros((zone.n_points, 50))
    np.add.at(on_ring, (slice(None), zone.nodes), zone.interpolation)
    np.testing.assert_allclose(on_ring, reference.interp[:, :50], rtol=0, atol=1e-14)
    # from the zone front until the cleat is 15 cm behind the contact centre
    span = coarse.time_s <= 0.015
    times = coarse.time_s[span]
    rim, contact = reference.run(CLEAT, times, substeps=2)
    # statics: the reference's own footprint carries the load the model was built for
    assert rim[0] == pytest.approx(coarse.static_rim_fz_n[0], rel=1e-9)
    produced = coarse.rim_fz_n[0, span]
    deviation = produced - coarse.static_rim_fz_n[0]
    rms = np.sqrt(np.mean(deviation**2))
    assert np.sqrt(np.mean((produced - rim) ** 2)) < 3e-3 * rms
    assert (produced.max() - rim.max()) == pytest.approx(0.0, abs=3e-3 * deviation.max())
    # the road's push (the points' vertical share of the forces): its impulse over the run.
    # The simulator's contact_Fz is the force at the step's end, which the points' entry and
    # exit at the cleat's edges bias high by O(h), about 4 % here (8 x at the FMU's 1e-4 s);
    # the ring receives the step's mean, which the rim force above shows right.
    impulse = np.sum(coarse.contact_fz_n[0, span] - coarse.static_rim_fz_n[0])
    assert impulse == pytest.approx(np.sum(contact - rim[0]), rel=0.15)


# -- 2. mesh convergence at the acceptance thresholds -----------------------------------------


@pytest.fixture(scope="module")
def meshes(tire):
    return cleat_convergence(tire, CLEAT, SPEED_M_S, n_elements=(100, 200, 400))


def test_peak_rise_converges_with_the_mesh(meshes):
    rise = meshes.peak_rise_n
    converged, _ = meshes.extrapolated_rise()
    assert abs(rise[0] / converged - 1) < 0.05, (rise, converged)
    assert abs(rise[1] / rise[2] - 1) < 0.02, rise
    assert meshes.history_difference()[0] < 0.10


def test_step_is_converged(tire, meshes):
    """Halving the communication step moves the coarse mesh's answer by far less than the
    mesh does."""
    half = cleat_convergence(tire, CLEAT, SPEED_M_S, n_elements=(100,),
                             step_s=0.5 * meshes.step_s)
    assert half.peak_rise_n[0] == pytest.approx(meshes.peak_rise_n[0], rel=5e-3)
    # every other sample of the half step is a sample of the step
    common = (meshes.time_s >= half.time_s[0]) & (meshes.time_s <= half.time_s[-1])
    times = meshes.time_s[common]
    on_half = np.searchsorted(half.time_s, times - 1e-12)
    np.testing.assert_allclose(half.time_s[on_half], times, rtol=0, atol=1e-12)
    full, halved = meshes.rim_fz_n[0, common], half.rim_fz_n[0, on_half]
    scale = np.sqrt(np.mean((full - meshes.static_rim_fz_n[0]) ** 2))
    assert np.sqrt(np.mean((full - halved) ** 2)) < 5e-3 * scale


# -- 3. no chatter with the points, and the chatter at node spacing ---------------------------


@pytest.fixture(scope="module")
def node_contact(tire):
    return cleat_convergence(tire, CLEAT, SPEED_M_S, n_elements=(100, 200),
                             point_spacing_m=NODE_SPACING_M)


def test_node_contact_lets_go_under_the_cleat(node_contact):
    """The check below can fail: at node spacing the road's push falls to zero between
    nodes while the cleat is under the tire, with a line at the node-passing rate."""
    assert node_contact.points_per_node.tolist() == [1, 1]
    assert node_contact.min_contact_fz_n[1] == 0.0
    assert np.all(node_contact.node_line_n > LINE_LEVEL * node_contact.static_rim_fz_n)


def test_contact_force_never_lets_go_with_points(meshes, node_contact):
    assert np.all(meshes.points_per_node > 1)
    assert np.all(meshes.min_contact_fz_n > 0.5 * meshes.static_rim_fz_n)
    # no line at the node-passing frequency above the level stated
    assert np.all(meshes.node_line_n < LINE_LEVEL * meshes.static_rim_fz_n)


# -- the pieces ------------------------------------------------------------------------------


def test_richardson_recovers_a_known_order():
    n = np.array([100, 200, 400])
    values = 5.0 - 3.0 / n**2
    extrapolated, order = richardson(1.0 / n, values)
    assert order == pytest.approx(2.0, rel=1e-6)
    assert extrapolated == pytest.approx(5.0, rel=1e-9)
    assert math.isnan(richardson(1.0 / n, [1.0, 2.0, 1.5])[1])  # not monotone: no order


def test_result_serialises(meshes):
    import json

    data = json.loads(json.dumps(meshes.to_dict(histories=False), allow_nan=True))
    assert [row["n_elements"] for row in data["meshes"]] == [100, 200, 400]
