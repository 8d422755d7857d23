"""The unilateral contact: the static footprint against an independent solve, the free ring
per order against the assembled ring, and the time stepping (lift-off, landing, energy,
substeps, state) against the linearised model and an unreduced integration."""

import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.optimize as so
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from contact_points_reference import reference_points, zone_length_rounding_to_node

from tire_fmu.core import OperatingPoint, TireParameters, build_model
from tire_fmu.core.contact import (
    DEFAULT_CONTACT_POINT_SPACING_M,
    MAX_CONTACT_POINTS,
    contact_zone,
    point_count_problems,
)
from tire_fmu.core.contact_dynamics import (
    OUTPUT_NAMES,
    ContactSettings,
    ContactSimulator,
    ContactState,
    StateError,
    build_contact_model,
)
from tire_fmu.core.discretisation import Grid
from tire_fmu.core.free_ring import RingTruncation, free_ring_model
from tire_fmu.core.io_model import build_io_model
from tire_fmu.core.model import structural_matrices, translation_pattern
from tire_fmu.core.parameters import DEFAULT_LOAD_N

LOADS = (10e3, DEFAULT_LOAD_N, 60e3)


# -- the static footprint ---------------------------------------------------------------------

def independent_footprint(tire, n_elements, load_n, spacing_m=DEFAULT_CONTACT_POINT_SPACING_M):
    """The same ring pressed on a flat road, solved on the assembled system: contact points
    built apart from the core (tests/contact_points_reference.py) on the lower third of the
    ring, a plain active-set iteration on them, brentq on δ. (theta of the pushing points.)"""
    grid = Grid(n_elements, tire.R)
    k_s = structural_matrices(tire, grid).stiffness.tocsc()
    n_dof = k_s.shape[0]
    theta, interp, m = reference_points(n_elements, tire.R, spacing_m, np.pi / 3)
    on_dofs = sp.csr_matrix(np.hstack([interp, np.zeros((theta.size, n_dof - n_elements))]))
    k_point = tire.k_cw * grid.node_arc_m / m
    cos_nodes = np.r_[np.cos(grid.theta), np.zeros(n_dof - n_elements)]

    def state(delta):
        gap = (tire.R - delta) / np.cos(theta) - tire.R
        active = gap < 0
        for _ in range(200):
            springs = sp.diags(np.where(active, k_point, 0.0))
            lhs = k_s + on_dofs.T @ springs @ on_dofs
            w = spla.spsolve(lhs.tocsc(), on_dofs.T @ (springs @ gap))
            pen = on_dofs @ w - gap  # positive into the road
            new = pen > 0
            if np.array_equal(new, active):
                break
            active = new
        force = np.where(active, k_point * pen, 0.0)
        return float(cos_nodes @ (on_dofs.T @ force)), theta[active]

    delta = so.brentq(lambda d: state(d)[0] - load_n, 1e-6, 0.2, xtol=1e-14, rtol=1e-13)
    load, pushing = state(delta)
    return delta, load, pushing


def test_the_zone_and_its_point_limit_count_the_same_carrying_nodes(tire):
    """The carrying nodes are those whose angle |j|·δθ is at most the zone's half angle
    (1 + 1e-12). At a zone length whose limit/δθ rounds up to node 7 of 100 while node 7's
    angle lies beyond the limit, the zone counted floor(limit/δθ) (15 carrying nodes) and its
    point limit the angles (13): a spacing the limit accepted built more points than
    MAX_CONTACT_POINTS, and the Python FMU's zone (its front, where road_z is read) was not the
    native FMU's (test_native_fmu.py runs both at this length)."""
    n, node = 100, 7
    grid = Grid(n, tire.R)
    length = zone_length_rounding_to_node(n, tire.R, node)
    limit = min(math.atan(0.5 * length / tire.R), math.pi / 3) * (1 + 1e-12)
    carrying = sum(1 for j in range(-(n // 2), n // 2 + 1) if abs(j) * grid.dtheta <= limit)
    assert carrying == 2 * node - 1
    assert contact_zone(grid, tire.k_cw, tire.beta, length, 1.0).n_nodes == carrying
    # m points per node that the carrying nodes take and one more node each side would not
    m = MAX_CONTACT_POINTS // carrying
    m -= 1 - m % 2
    assert carrying * m <= MAX_CONTACT_POINTS < (carrying + 2) * m
    spacing = grid.node_arc_m / (m - 0.5)
    fine = contact_zone(grid, tire.k_cw, tire.beta, length, spacing)
    assert fine.points_per_node == m and fine.n_points == carrying * m
    assert fine.n_nodes == carrying + 4  # the stencils reach two nodes beyond each end
    assert point_count_problems(grid, length, spacing) == []
    # one odd step finer is refused, counting the same carrying nodes
    (problem,) = point_count_problems(grid, length, grid.node_arc_m / (m + 1.5))
    assert f"{m + 2} points on each of its {carrying} carrying nodes" in problem.reason


@pytest.mark.parametrize("spacing_m", [DEFAULT_CONTACT_POINT_SPACING_M, 1.0])
@pytest.mark.parametrize("n_elements", [100, 200, 400])
@pytest.mark.parametrize("load_n", LOADS)
def test_footprint_matches_an_independent_active_set_solve(tire, n_elements, load_n, spacing_m):
    patch = build_model(tire, OperatingPoint(n_elements=n_elements, load_n=load_n,
                                             contact_point_spacing_m=spacing_m)).patch
    delta, load, pushing = independent_footprint(tire, n_elements, load_n, spacing_m)
    fp = patch.footprint
    assert fp.load_n == pytest.approx(load, rel=5e-3)
    assert fp.deflection_m == pytest.approx(delta, rel=1e-2)
    np.testing.assert_allclose(fp.zone.point_theta[fp.active], pushing, rtol=0, atol=1e-12)
    # much closer than the acceptance asks: the two solve the same equations
    assert fp.deflection_m == pytest.approx(delta, rel=1e-8)


@pytest.mark.parametrize("load_n", LOADS)
def test_footprint_converges_with_the_mesh(tire, load_n):
    meshes = (100, 200, 400, 800)

    def footprints(spacing_m):
        return [build_model(tire, OperatingPoint(n_elements=n, load_n=load_n,
                                                 contact_point_spacing_m=spacing_m)
                            ).patch.footprint for n in meshes]

    points, nodes = footprints(DEFAULT_CONTACT_POINT_SPACING_M), footprints(1.0)
    length = np.array([f.length_m for f in points])
    deflection = np.array([f.deflection_m for f in points])
    # with contact points the footprint is that of the ring, not of the node spacing:
    # N = 100 within 5 % of N = 800 in length (the acceptance), and the deflection closer
    assert np.max(np.abs(length / length[-1] - 1)) < 0.05
    assert np.max(np.abs(deflection / deflection[-1] - 1)) < 0.01
    assert abs(length[-2] / length[-1] - 1) < 0.01
    # one point per node gains a node's length now and then: not monotone, and coarse
    node_length = np.array([f.length_m for f in nodes])
    assert abs(node_length[0] / node_length[-1] - 1) > 2 * abs(length[0] / length[-1] - 1)
    # the same footprint at N = 800 whichever the contact points (5 mm node arcs)
    assert node_length[-1] == pytest.approx(length[-1], rel=0.01)
    if load_n == DEFAULT_LOAD_N:
        # the model's own footprint: far shorter and softer than the chord rule's 0.27 m / 14 mm
        assert 0.08 < length[-1] < 0.15 and 0.017 < deflection[-1] < 0.02


def test_load_deflection_path_and_its_stiffnesses(tire):
    model = build_model(tire, OperatingPoint(load_n=DEFAULT_LOAD_N))
    fp = model.patch.footprint
    from tire_fmu.core.contact import FootprintPath, point_compliance
    from tire_fmu.core.free_ring import ring_static_gain, zone_compliance

    zone = model.patch.zone
    path = FootprintPath(zone, point_compliance(zone, zone_compliance(ring_static_gain(
        tire, model.grid, 0.0, zone.nodes))), 0.3)
    again = path.at_deflection(fp.deflection_m)  # the inverse: load for a deflection
    assert again.load_n == pytest.approx(DEFAULT_LOAD_N, rel=1e-12)
    assert fp.secant_stiffness_n_per_m == pytest.approx(DEFAULT_LOAD_N / fp.deflection_m)
    h = 1e-7
    slope = (path.at_deflection(fp.deflection_m + h).load_n
             - path.at_deflection(fp.deflection_m - h).load_n) / (2 * h)
    assert fp.tangent_stiffness_n_per_m == pytest.approx(slope, rel=1e-6)
    # the tangent is the linearised model's rim force per rim travel
    dc = build_io_model(model).static_gain()
    assert -dc[0, 0] == pytest.approx(fp.tangent_stiffness_n_per_m, rel=1e-9)
    # the load grows with the deflection, and so does the footprint
    loads = [path.at_deflection(d).load_n for d in np.linspace(0, 0.05, 60)]
    lengths = [path.at_deflection(d).length_m for d in np.linspace(0, 0.05, 60)]
    assert np.all(np.diff(loads) > 0) and np.all(np.diff(lengths) >= 0)


def test_footprint_pushes_and_nodes_outside_clear_the_road(tire):
    fp = build_model(tire, OperatingPoint(n_elements=200, load_n=60e3)).patch.footprint
    assert np.all(fp.forces_n >= 0)
    assert np.all(fp.penetration_m[~fp.active] <= 1e-15)
    np.testing.assert_allclose(fp.forces_n[fp.active],
                               fp.zone.stiffness_n_per_m[fp.active] * fp.penetration_m[fp.active],
                               rtol=1e-9)
    assert fp.load_n == pytest.approx(60e3, rel=1e-12)
    # symmetric at rest; the edges lie between the outer active node and its neighbour
    np.testing.assert_allclose(fp.forces_n, fp.forces_n[::-1], rtol=1e-9, atol=1e-9)
    x = fp.zone.road_positions_m(fp.deflection_m)
    outer = np.flatnonzero(fp.active)[0]
    assert x[outer] <= fp.front_edge_m <= x[outer - 1]


def test_rolling_footprint_is_asymmetric_and_pushes_back(tire):
    fp = build_model(tire, OperatingPoint(load_n=DEFAULT_LOAD_N, speed_m_s=20.0)).patch.footprint
    assert fp.load_n == pytest.approx(DEFAULT_LOAD_N, rel=1e-12)
    # material damping makes a rolling resistance: the road pushes the tire backwards
    assert fp.longitudinal_force_n < 0
    assert abs(fp.front_edge_m + fp.rear_edge_m) > 1e-4  # shifted, not centred


# -- the free ring, order by order ----------------------------------------------------------

@pytest.mark.parametrize("n_elements, speed", [(40, 0.0), (40, 15.0), (37, 20.0)])
def test_free_ring_per_order_equals_the_assembled_ring(tire, n_elements, speed):
    grid = Grid(n_elements, tire.R)
    zone = contact_zone(grid, tire.k_cw, tire.beta, 1.0)
    ring = free_ring_model(tire, grid, speed / tire.R, zone.nodes)
    st = structural_matrices(tire, grid, speed / tire.R)
    k, d, m = st.stiffness.toarray(), st.damping.toarray(), st.mass.toarray()
    t = translation_pattern(grid)
    s = -np.r_[np.sin(grid.theta), np.sin(grid.theta)]
    n, z = 2 * n_elements, zone.n_nodes
    b_z, b_v = np.zeros((n, 1 + z)), np.zeros((n, 1 + z))
    b_z[:, 0], b_v[:, 0] = k @ t, d @ t
    b_z[zone.nodes, 1 + np.arange(z)] = -1.0
    l_u, l_v = np.zeros((3 + 2 * z, n)), np.zeros((3 + 2 * z, n))
    direct_r, direct_v = np.zeros((3 + 2 * z, 1 + z)), np.zeros((3 + 2 * z, 1 + z))
    for row, pattern in ((0, t), (1, s)):
        l_u[row], l_v[row] = pattern @ k, pattern @ d
        direct_r[row, 0], direct_v[row, 0] = -pattern @ k @ t, -pattern @ d @ t
    l_u[2, 0], direct_r[2, 0] = -1.0, t[0]
    l_u[3 + np.arange(z), zone.nodes] = 1.0
    l_v[3 + z + np.arange(z), zone.nodes] = 1.0
    direct_r[3:3 + z, 0] = -t[zone.nodes]
    direct_v[3 + z:, 0] = -t[zone.nodes]
    freqs = (3.0, 57.0, 160.0, 300.0, 900.0)
    assembled, modal = [], ring.frequency_response(2 * np.pi * np.array(freqs))
    for f in freqs:
        w = 2 * np.pi * f
        u = np.linalg.solve(k - w * w * m + 1j * w * d, b_z + 1j * w * b_v)
        assembled.append((l_u + 1j * w * l_v) @ u + direct_r + 1j * w * direct_v)
    assembled = np.stack(assembled, axis=-1)
    # relative to each input-output pair's size over the band, with a floor at the input's
    # largest response (pairs zero by symmetry carry only rounding)
    # (the tied sidewall's dense blocks, far stiffer than the ring, raise that rounding by
    # the ratio of their largest entry to the lumped ring's)
    size = np.abs(assembled).max(axis=2, keepdims=True)
    lumped = structural_matrices(replace(tire, sidewall_max_order=0.0), grid, speed / tire.R)
    rounding = 1e-7 * np.abs(k).max() / np.abs(lumped.stiffness.toarray()).max()
    scale = np.maximum(size, rounding * size.max(axis=0, keepdims=True))
    assert np.max(np.abs(modal - assembled) / scale) < 1e-6
    dc = np.linalg.solve(k, b_z)
    np.testing.assert_allclose(ring.static_gain[3:], (l_u @ dc + direct_r)[3:], rtol=1e-9,
                               atol=1e-7 * rounding)
    assert ring.n_states == 4 * n_elements  # every mode of the 2N-DOF ring, O(N) to build


def test_truncated_ring_keeps_the_static_compliance(tire):
    grid = Grid(200, tire.R)
    zone = contact_zone(grid, tire.k_cw, tire.beta)
    full = free_ring_model(tire, grid, 10.0 / tire.R, zone.nodes)
    cut = free_ring_model(tire, grid, 10.0 / tire.R, zone.nodes, RingTruncation(f_max_hz=1500))
    assert cut.n_modes < full.n_modes
    np.testing.assert_allclose(cut.frequency_response([0.0])[3:, :, 0],
                               full.static_gain[3:], rtol=1e-9, atol=1e-12)
    # below the cut the truncated ring stays close to the full one
    low, high = cut.frequency_response([2 * np.pi * 150]), full.frequency_response(
        [2 * np.pi * 150])
    assert np.max(np.abs(low - high)[3:]) < 1e-3 * np.max(np.abs(high)[3:])


# -- time stepping ----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def contact_models():
    return {speed: build_contact_model(TireParameters(), OperatingPoint(speed_m_s=speed))
            for speed in (0.0, 10.0)}


def ramp(t, start, duration, height):
    """Height and rate of a linear ramp from 0 to ``height`` over [start, start + duration]."""
    s = np.clip((t - start) / duration, 0.0, 1.0)
    rate = height / duration if start <= t < start + duration else 0.0
    return height * s, rate


def drop_and_return(t, down=0.02, up=0.12, depth=0.05, duration=0.01):
    a, da = ramp(t, down, duration, -depth)
    b, db = ramp(t, up, duration, depth)
    return a + b, da + db


def run(sim, road, n, h=1e-4, rim=lambda t: (0.0, 0.0)):
    out = np.empty((n, len(OUTPUT_NAMES)))
    for i in range(n):
        t = sim.time
        out[i] = sim.step_values(h, *rim(t), *road(t))
    return out


@pytest.mark.parametrize("speed", [0.0, 10.0])
def test_at_rest_in_equilibrium_nothing_moves(contact_models, speed):
    sim = ContactSimulator(contact_models[speed])
    out = run(sim, lambda t: (0.0, 0.0), 200)
    static = contact_models[speed].static_outputs
    for col, name in enumerate(OUTPUT_NAMES):
        assert np.allclose(out[:, col], static[name], rtol=1e-9, atol=1e-9 * DEFAULT_LOAD_N)


@pytest.mark.parametrize("speed", [0.0, 10.0])
def test_rim_and_road_moving_together_change_no_force(contact_models, speed):
    """A slow common heave of rim and road: only the tire's inertia (121 kg x z̈) acts (and at
    speed the road's small lag across the footprint), where a rim coupled to absolute
    displacements would add a spring of about 0.5 MN/m: 5 kN at the 10 mm peak."""
    model = contact_models[speed]
    sim = ContactSimulator(model)
    amplitude, omega, start = 5e-3, 2 * np.pi * 1.0, 0.06
    # at speed the road reaches the footprint later than it passes the zone front
    late = float(np.mean(model.windows.early_s[sim.static_active]
                         + model.windows.late_s[sim.static_active]) / 2)

    def heave(t):
        if t < start:
            return 0.0, 0.0
        phase = omega * (t - start)
        return amplitude * (1 - np.cos(phase)), amplitude * omega * np.sin(phase)

    out = run(sim, lambda t: heave(t + late), 5000, rim=heave)
    static = contact_models[speed].static_outputs
    inertia = 121.0 * amplitude * omega**2  # about 24 N
    assert np.max(np.abs(out[:, 0] - static["rim_Fz"])) < 10 * inertia
    assert np.max(np.abs(out[:, 2] - static["contact_Fz"])) < 10 * inertia


@pytest.mark.parametrize("speed", [0.0, 10.0])
def test_lift_off_releases_the_tire_and_it_lands_without_pulling(contact_models, speed):
    model = contact_models[speed]
    sim = ContactSimulator(model)
    n = 3500
    out = run(sim, drop_and_return, n)
    # at speed the road reaches the footprint's nodes between these delays after the front
    first = float(model.windows.early_s[sim.static_active].min())
    last = float(model.windows.late_s[sim.static_active].max())
    t = (np.arange(n) + 1) * 1e-4
    contact = out[:, 2]
    assert contact.min() >= -1.0  # never a pull (it is exactly 0 while airborne)
    airborne = contact == 0.0
    assert airborne.any() and not airborne[-1]
    off = t[airborne]
    # the road leaves the tire during the drop, meets it again during the return
    assert 0.02 + first < off[0] < 0.03 + last
    assert 0.12 + first < off[-1] < 0.14 + last  # it may bounce once before it settles
    # while airborne the road exerts nothing: the rim feels the free tire's own vibration
    released = (t > off[0] + 0.02) & (t < off[-1] - 0.005) & airborne
    assert abs(out[released, 0].mean()) < 0.05 * DEFAULT_LOAD_N
    assert not np.any(out[airborne, 4])  # no footprint while airborne
    # landing: the tire was pressed by the road at 5 m/s; the force stays within what an
    # impact of the tread mass explains, and the tire settles back to its static state
    assert contact[t > 0.12].max() < 3 * DEFAULT_LOAD_N
    assert np.allclose(out[-100:, 2], DEFAULT_LOAD_N, rtol=5e-2)



def test_repeated_drops_do_not_gain_energy(contact_models):
    sim = ContactSimulator(contact_models[0.0])
    period = 0.04

    def cycles(t):
        phase = t % period
        return drop_and_return(phase, down=0.005, up=0.02, depth=0.03, duration=0.004)

    out = run(sim, cycles, 100 * int(round(period / 1e-4)))
    per_cycle = out[:, 0].reshape(100, -1)
    swing = per_cycle.max(axis=1) - per_cycle.min(axis=1)
    assert np.all(np.isfinite(out))
    assert swing[-10:].max() <= 1.02 * swing[10:20].max()  # steady, not growing


def full_model_drop(tire, n_elements, t_end, road):
    """The unreduced ring (every DOF, assembled matrices) with the same contact law on contact
    points built apart from the core, the rim held, integrated by an explicit high-order
    method with small steps."""
    from scipy.integrate import solve_ivp

    model = build_model(tire, OperatingPoint(n_elements=n_elements))
    st = structural_matrices(tire, model.grid)
    k, d, m = st.stiffness.tocsr(), st.damping.tocsr(), st.mass.diagonal()
    n_dof = k.shape[0]
    # contact points built apart from the core, on the whole lower third of the ring
    theta, interp, m_points = reference_points(n_elements, tire.R,
                                               DEFAULT_CONTACT_POINT_SPACING_M, np.pi / 3)
    on_dofs = np.hstack([interp, np.zeros((theta.size, n_dof - n_elements))])
    kz = np.full(theta.size, tire.k_cw * model.grid.node_arc_m / m_points)
    cz = tire.beta * kz
    cos = np.cos(theta)
    vertical = on_dofs @ np.r_[np.cos(model.grid.theta), np.zeros(n_dof - n_elements)]
    delta, radius = model.patch.deflection_m, tire.R
    # the static tread on those points: an active-set solve at the model's deflection
    gap = (radius - delta) / cos - radius
    active = gap < 0
    for _ in range(200):
        springs = np.where(active, kz, 0.0)
        w0 = np.linalg.solve(k.toarray() + (on_dofs.T * springs) @ on_dofs,
                             on_dofs.T @ (springs * gap))
        new = on_dofs @ w0 - gap > 0
        if np.array_equal(new, active):
            break
        active = new

    def contact(t, w, v):
        h, hv = road(t)
        pen = radius + on_dofs @ w - (radius - delta - h) / cos
        push = kz * pen + cz * (on_dofs @ v + hv / cos)
        return np.where(pen > 0, np.maximum(push, 0.0), 0.0)

    def rhs(t, x):
        w, v = x[:n_dof], x[n_dof:]
        f = -on_dofs.T @ contact(t, w, v)
        return np.concatenate([v, (f - k @ w - d @ v) / m])

    sol = solve_ivp(rhs, (0, t_end), np.concatenate([w0, np.zeros(n_dof)]),
                    method="DOP853", rtol=1e-9, atol=1e-12, max_step=1e-5, dense_output=True)
    assert sol.status == 0

    def contact_fz(times):
        x = sol.sol(times)
        return np.array([vertical @ contact(t, x[:n_dof, i], x[n_dof:, i])
                         for i, t in enumerate(times)])

    return model, contact_fz


@pytest.mark.slow
def test_airborne_time_and_landing_force_match_an_unreduced_integration(tire):
    n_el, t_end = 40, 0.08

    def road(t):
        return drop_and_return(t, down=0.005, up=0.045, depth=0.05, duration=0.01)

    model, reference = full_model_drop(tire, n_el, t_end, road)
    sim = ContactSimulator(build_contact_model(tire, OperatingPoint(n_elements=n_el)))
    h = 2.5e-5
    n = int(round((t_end - 1e-4) / h))
    out = run(sim, road, n, h)
    t = (np.arange(n) + 1) * h
    ref = reference(t)
    sim_off, ref_off = t[out[:, 2] == 0], t[ref == 0]
    # the road's rate jumps at a communication point, which the step after it sees
    assert sim_off[0] == pytest.approx(ref_off[0], abs=3 * h)  # lift-off
    assert sim_off[-1] == pytest.approx(ref_off[-1], abs=3 * h)  # touch-down
    landing = t > 0.045
    assert out[landing, 2].max() == pytest.approx(ref[landing].max(), rel=0.05)
    # before the first touch (whose steep rise a step's shift magnifies) the two are close
    touch = t[(t > ref_off[0]) & (ref > 0)][0]
    # (away from the lift-off instant, which the two may place a step apart, as above)
    before = (t < touch - 1e-3) & (np.abs(t - ref_off[0]) > 3 * h)
    assert np.max(np.abs(out[before, 2] - ref[before])) < 0.02 * model.patch.load_n


def test_a_road_step_at_rest_rings_without_pulling(contact_models):
    sim = ContactSimulator(contact_models[0.0])
    out = run(sim, lambda t: (1e-3, 0.0), 2000)  # a 1 mm step at the first point
    contact = out[:, 2]
    assert contact.min() >= 0.0
    # the tire ends up carrying the static load (rim held, the road 1 mm higher: more)
    assert contact[-1] > DEFAULT_LOAD_N


def test_long_communication_steps_are_substepped_exactly(contact_models):
    model = contact_models[0.0]
    assert model.substep_s == pytest.approx(1e-4)
    coarse, fine = ContactSimulator(model), ContactSimulator(model)

    def road(t):  # a ramp: inputs exact for the step, so no correction at the points
        return 1e-3 * t / 0.05, 1e-3 / 0.05

    for _ in range(50):
        a = coarse.step_values(1e-3, 0.0, 0.0, *road(coarse.time))
        for _ in range(10):
            b = fine.step_values(1e-4, 0.0, 0.0, *road(fine.time))
    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-6)


@pytest.mark.parametrize("speed", [0.0, 10.0])
def test_state_round_trip_resumes_bit_for_bit(contact_models, speed):
    model = contact_models[speed]
    sim = ContactSimulator(model)
    run(sim, drop_and_return, 250)
    saved = sim.get_state().to_bytes()
    expected = run(sim, drop_and_return, 300)
    other = ContactSimulator(model)
    other.set_state(ContactState.from_bytes(saved))
    again = run(other, drop_and_return, 300)
    np.testing.assert_array_equal(again, expected)


def test_damaged_states_are_refused(contact_models):
    sim = ContactSimulator(contact_models[0.0])
    run(sim, drop_and_return, 50)
    data = bytearray(sim.get_state().to_bytes())
    for position in (len(data) - 1, len(data) // 2, data.index(b"\n") + 3):
        bad = bytearray(data)
        bad[position] ^= 0x40
        with pytest.raises(StateError):
            ContactState.from_bytes(bytes(bad))
    ContactState.from_bytes(bytes(data))  # the undamaged bytes are fine
    with pytest.raises(StateError):
        ContactState.from_bytes(bytes(data) + b"\x00")  # trailing bytes
    other = ContactSimulator(build_contact_model(TireParameters(),
                                                 OperatingPoint(n_elements=60)))
    with pytest.raises(StateError, match="another model"):
        other.set_state(ContactState.from_bytes(bytes(data)))


def test_linear_contact_is_the_linearised_model(contact_models):
    """Two-sided springs on the static footprint: a deep drop pulls the road (what the
    unilateral contact exists to prevent)."""
    model = contact_models[0.0]
    linear = ContactSimulator(build_contact_model(
        TireParameters(), OperatingPoint(), settings=ContactSettings(law="linear")))
    out = run(linear, drop_and_return, 400)
    assert out[:, 2].min() < -DEFAULT_LOAD_N  # pulls
    small = ContactSimulator(model), ContactSimulator(build_contact_model(
        TireParameters(), OperatingPoint(), settings=ContactSettings(law="linear")))
    sine = lambda t: (1e-5 * np.sin(300 * t), 3e-3 * np.cos(300 * t))  # noqa: E731
    a, b = (run(s, sine, 400) for s in small)
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9)  # same while nothing lifts


def _window_average(signal, times, early, late, points=48):
    """The road under a node at each of ``times``: ``signal`` averaged over
    [t - late, t - early] (Gauss-Legendre)."""
    if late <= early:
        return signal(times - early)
    x, w = np.polynomial.legendre.leggauss(points)
    mid, half = times - 0.5 * (early + late), 0.5 * (late - early)
    return 0.5 * signal(mid[:, None] + half * x[None, :]) @ w


@pytest.mark.parametrize("speed", [0.0, 15.0])
def test_linear_contact_steps_match_scipy_on_the_linearised_model(speed):
    """The two-sided contact is the linearised loaded model; stepped through its interface
    solve at h = 1e-4 s, the forces follow that model's state space solved by scipy on a
    ten times finer step, fed the road each node sees (its window average of the signal)."""
    import scipy.signal as ss

    contact = build_contact_model(TireParameters(),
                                  OperatingPoint(n_elements=60, speed_m_s=speed),
                                  settings=ContactSettings(law="linear"))
    io = build_io_model(contact.model)
    h, fine = 1e-4, 1e-5
    duration, f0, f1 = 0.12, 5.0, 200.0
    k = (f1 / f0) ** (1 / duration)

    def height(time):  # a smooth sweep that starts at rest
        time = np.clip(time, 0.0, None)
        return 1e-3 * (1 - np.cos(2 * np.pi * f0 * (k**time - 1) / np.log(k)))

    def rate(time):
        time = np.clip(time, 0.0, None)
        phase = 2 * np.pi * f0 * (k**time - 1) / np.log(k)
        return 1e-3 * np.sin(phase) * 2 * np.pi * f0 * k**time

    t = np.arange(0.0, duration, h)
    sim = ContactSimulator(contact)
    static = np.array([contact.static_outputs[n] for n in ("rim_Fz", "rim_Fx", "contact_Fz")])
    ours = [np.zeros(3)]
    for i in range(t.size - 1):
        sim.step_values(h, 0.0, 0.0, height(t[i]), rate(t[i]))
        ours.append(np.array(sim.outputs_with(0.0, 0.0, height(t[i + 1]),
                                              rate(t[i + 1]))[:3]) - static)
    ours = np.array(ours)
    windows = io.road_windows
    t_ref = np.arange(0.0, duration - h / 2, fine)
    pairs = list(zip(windows.early_s, windows.late_s))
    r = np.column_stack([np.zeros_like(t_ref)]
                        + [_window_average(height, t_ref, a, b) for a, b in pairs])
    rdot = np.column_stack([np.zeros_like(t_ref)]
                           + [_window_average(rate, t_ref, a, b) for a, b in pairs])
    _, full, _ = ss.lsim(ss.StateSpace(io.a.toarray(), io.b, io.c, io.d), r, t_ref,
                         interp=True)
    full = (full + rdot @ io.e.T)[np.round(t / fine).astype(int)]
    for row in (0, 1, 2) if speed else (0, 2):  # rim_Fx is zero by symmetry at rest
        scale = np.abs(full[:, row]).max()
        error = np.abs(ours[:, row] - full[:, row]).max() / scale
        assert error < 2e-3, (row, error)
