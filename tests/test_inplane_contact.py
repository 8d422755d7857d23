"""The in-plane ring on the road: balance of forces, free rolling, braking, a cleat.

References written apart from the stepping: the frictionless steady state solved statically,
the wheel's moment balance, the time step halved.
"""

from __future__ import annotations

import numpy as np
import pytest

from tire_fmu.core.inplane import InPlaneRing, InPlaneTire, TangentialParameters
from tire_fmu.core.inplane_contact import (
    InPlaneSimulator,
    deflection_for_load,
    loaded_modes,
    steady_rolling,
)
from tire_fmu.core.obstacles import cleat
from tire_fmu.core.parameters import DEFAULT_LOAD_N, ParameterError

MODEL = InPlaneTire()
SPACING = 0.01


@pytest.fixture(scope="module")
def deflection():
    return deflection_for_load(MODEL, DEFAULT_LOAD_N, 100, point_spacing_m=SPACING)


def point_normal_forces(sim, y):
    """The road's push on each point (along its ray) in the static state y."""
    pen = sim._pen0 + sim._jn @ y
    return np.where(pen > 0, sim._kn * pen, 0.0)


def test_the_deflection_carries_the_load(deflection):
    sim = InPlaneSimulator(MODEL, 100, 0.0, deflection, point_spacing_m=SPACING)
    assert sim.static_load_n() == pytest.approx(DEFAULT_LOAD_N, rel=1e-9)


@pytest.mark.parametrize("sidewall", ["tied", "lumped"])
@pytest.mark.parametrize("speed", [0.0, 10.0])
def test_rim_force_balances_the_road_force(deflection, sidewall, speed):
    """Statically the rim carries what the road pushes (1e-6: the interpolation of the
    rigid patterns to the points), and at rest nothing pushes sideways or turns the rim."""
    sim = InPlaneSimulator(InPlaneTire(sidewall_tangential=sidewall), 100, speed, deflection,
                           point_spacing_m=SPACING)
    y = sim.static_state()
    fx, fz, my = sim.rim_force(y, np.zeros_like(y))
    push = point_normal_forces(sim, y)
    zone = sim._zone  # the pushes reach the nodes radially: their vertical and fore-aft parts
    assert fz == pytest.approx(push @ zone.force_cos, rel=1e-9)
    assert fx == pytest.approx(push @ zone.force_sin, abs=1e-9 * fz)
    assert abs(my) < 1e-9 * fz * MODEL.tire.R  # a push along the ray turns nothing
    if speed == 0.0:
        assert abs(fx) < 1e-9 * fz


def test_at_rest_the_pressed_tire_stays_put(deflection):
    sim = InPlaneSimulator(MODEL, 100, 0.0, deflection, point_spacing_m=SPACING)
    run = sim.run(0.01, record_every=10)
    np.testing.assert_allclose(run.rim_fz_n, DEFAULT_LOAD_N, rtol=1e-6)
    assert np.abs(run.rim_fx_n).max() < 1e-6 * DEFAULT_LOAD_N


@pytest.fixture(scope="module")
def free_rolling(deflection):
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING)
    return sim, sim.run(0.3, record_every=10)


def test_free_rolling_resistance_is_the_pressure_asymmetry(free_rolling):
    """A free wheel turns no moment into the rim, so the road's drag on the tread elements
    sums to no moment either, and the rolling resistance is the fore-aft resultant of the
    pressure, which material damping shifts forward: the frictionless steady state (a static
    solve of the rolling ring) gives it, within 5 %."""
    sim, run = free_rolling
    settled = run.time_s > 0.15
    y = sim.static_state()
    fx_frictionless, _, my_frictionless = sim.rim_force(y, np.zeros_like(y))
    assert fx_frictionless < 0  # a drag
    assert abs(my_frictionless) < 1e-9 * DEFAULT_LOAD_N
    assert run.rim_fx_n[settled].mean() == pytest.approx(fx_frictionless, rel=0.05)
    assert abs(run.rim_my_n_m[settled].mean()) < 0.05 * abs(fx_frictionless) * MODEL.tire.R
    assert run.sliding_points[settled].max() == 0


def test_brake_torque_is_carried_by_the_road(deflection):
    """A brake torque at 10 m/s: once settled the tire holds the rim against it and the
    road's drag times the loaded radius carries it (within the rolling resistance)."""
    torque = -3000.0
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING)
    run = sim.run(0.45, torque_n_m=lambda t: torque if t > 0.05 else 0.0, record_every=10)
    settled = run.time_s > 0.3
    my = run.rim_my_n_m[settled].mean()
    assert my == pytest.approx(-torque, rel=0.01)
    loaded_radius = MODEL.tire.R - deflection
    drag = -run.rim_fx_n[settled].mean()
    assert drag * loaded_radius == pytest.approx(-torque, rel=0.05)
    spin = run.spin_rad_s[settled].mean()
    assert spin < sim.spin_rad_s  # a braked wheel turns slower than it rolls free
    slip = 1.0 - spin / sim.spin_rad_s
    stiffness_per_load = drag / slip / DEFAULT_LOAD_N
    assert 5 < stiffness_per_load < 30  # truck tires' C_Fκ/Fz (the k_tx default's source)


def test_cleat_forces_converge_with_the_time_step(deflection):
    runs = []
    for step in (1e-4, 5e-5):
        sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, step_s=step,
                               point_spacing_m=SPACING, obstacle=cleat(0.02, 0.02),
                               obstacle_ahead_m=0.6)
        runs.append(sim.run(0.1, record_every=int(round(1e-4 / step))))
    coarse, fine = runs
    rise = fine.rim_fz_n - DEFAULT_LOAD_N
    assert rise.max() > 0.5 * DEFAULT_LOAD_N  # the cleat is felt
    assert np.sqrt(np.mean((coarse.rim_fz_n - fine.rim_fz_n) ** 2)) < 0.03 * np.sqrt(
        np.mean(rise**2))
    assert np.sqrt(np.mean((coarse.rim_fx_n - fine.rim_fx_n) ** 2)) < 0.1 * np.sqrt(
        np.mean(fine.rim_fx_n**2))
    assert fine.rim_fx_n.min() < -0.05 * DEFAULT_LOAD_N  # the cleat pushes the tire back


def test_bad_simulator_inputs_are_reported_at_once():
    with pytest.raises(ParameterError) as error:
        InPlaneSimulator(MODEL, 100, -1.0, 0.5, step_s=1.0, wheel="loose")
    text = str(error.value)
    for name in ("speed_m_s = -1", "step_s = 1", "wheel = 'loose'", "deflection_m = 0.5"):
        assert name in text


def test_no_friction_means_no_drive(deflection):
    """μ = 0: the road cannot pull the tread, so a torque spins the whole wheel up (rim, tread
    and sidewall turning together) as if it were off the ground: the pushes along the rays
    have no moment."""
    model = InPlaneTire(tangential=TangentialParameters(friction_coefficient=0.0))
    sim = InPlaneSimulator(model, 64, 10.0, deflection, point_spacing_m=SPACING)
    run = sim.run(0.3, torque_n_m=100.0, record_every=10)
    assert np.abs(run.contact_fx_n).max() < 1e-9
    t = model.tire
    tire_inertia = 2 * np.pi * t.R**3 * (t.rhoA + t.m_s)
    inertia = model.tangential.wheel_inertia_kg_m2 + tire_inertia
    late = run.time_s > 0.1  # the torsional mode's ringing from the torque's onset averages out
    accel = np.polyfit(run.time_s[late], run.spin_rad_s[late], 1)[0]
    assert accel == pytest.approx(100.0 / inertia, rel=0.01)
    # the rim turns the tire: the tire's moment on the rim is its inertia's reaction
    assert run.rim_my_n_m[late].mean() == pytest.approx(-tire_inertia * accel, rel=0.01)


def test_loaded_rotational_mode_rings_at_the_frequency_modes_report(deflection):
    """At rest on the road a short torque on the free wheel sets the tire ringing; its
    spectrum peaks at the loaded rotational mode of the linearised footprint, within 2 %."""
    from scipy.signal import periodogram

    sim = InPlaneSimulator(MODEL, 100, 0.0, deflection, point_spacing_m=SPACING)
    modes = loaded_modes(sim, f_max_hz=120)
    (rotational,) = [f for f, k in zip(modes.frequencies_hz, modes.kinds) if k == "rotational"]
    run = sim.run(0.4, torque_n_m=lambda t: 200.0 if t < 2e-3 else 0.0)
    late = run.time_s > 0.01
    signal = run.spin_rad_s[late]
    freq, power = periodogram(signal - signal.mean(), fs=1 / sim.step_s, nfft=2**18)
    assert freq[np.argmax(power)] == pytest.approx(rotational, rel=0.02)


def test_footprint_holds_the_tread_by_its_elements_alone(deflection):
    """With the rim held, the road's pushes act along the rays and so cannot resist the
    tread's turn (v = const moves no surface): without tread elements (k_tx = 0) the loaded
    rotational mode is the unloaded one exactly; the elements stiffen it."""
    from tire_fmu.core.inplane import InPlaneRing
    from tire_fmu.core.inplane_modes import tire_modes

    def held_rotational(model):
        sim = InPlaneSimulator(model, 100, 0.0, deflection, point_spacing_m=SPACING,
                               wheel="held")
        modes = loaded_modes(sim, f_max_hz=120)
        return [f for f, k in zip(modes.frequencies_hz, modes.kinds) if k == "rotational"][0]

    bare = InPlaneTire(tangential=TangentialParameters(k_tx=0.0))
    (unloaded,) = tire_modes(InPlaneRing(bare, 100), f_max_hz=120).select(kind="rotational")
    assert held_rotational(bare) == pytest.approx(unloaded.frequency_hz, rel=1e-9)
    assert held_rotational(MODEL) > 1.1 * unloaded.frequency_hz


def test_command_reports_the_loaded_modes(capsys):
    import json

    from tire_fmu.cli import main

    assert main(["inplane-modes", "--load", "27700", "--rim-free", "--point-spacing", "0.01",
                 "--max-frequency", "60", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    deflection = deflection_for_load(MODEL, 27700.0, 100, point_spacing_m=0.01)
    assert data["deflection_m"] == pytest.approx(deflection, rel=1e-12)
    modes = loaded_modes(InPlaneSimulator(MODEL, 100, 0.0, deflection, point_spacing_m=0.01),
                         f_max_hz=60)
    np.testing.assert_allclose([m["frequency_hz"] for m in data["modes"]],
                               modes.frequencies_hz, rtol=1e-9)
    assert [m["kind"] for m in data["modes"]].count("rotational") == 1


def test_steady_free_rolling_is_where_the_run_settles(free_rolling):
    """The steady state solved directly (no time stepping, its own transport of the tread
    elements' field) and the settled run agree on the drag and the spin."""
    from tire_fmu.core.inplane_contact import steady_rolling

    sim, run = free_rolling
    settled = run.time_s > 0.15
    steady = steady_rolling(sim)
    assert steady.rim_fx_n == pytest.approx(run.rim_fx_n[settled].mean(), rel=0.02)
    assert abs(steady.rim_my_n_m) < 1e-6 * DEFAULT_LOAD_N
    assert steady.spin_rad_s == pytest.approx(run.spin_rad_s[settled].mean(), rel=1e-4)


@pytest.mark.parametrize("spacing_m", [0.01, 0.005, 0.0025])
def test_brake_slip_settles_where_the_steady_solve_says(deflection, spacing_m):
    """A brake torque step at 10 m/s: the slip the run settles at is the steady solve's within
    2 % at every point spacing (the elements enter at the road's edge in both), the drag
    within 0.5 %. The step's C (numpy's to 1e-9, test_inplane_host.py) keeps it quick."""
    from tire_fmu.core.inplane_contact import steady_rolling

    torque = -3000.0
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=spacing_m,
                           backend="auto")
    steady = steady_rolling(sim, torque)
    run = sim.run(0.4, torque_n_m=lambda t: torque if t > 0.02 else 0.0, record_every=10)
    settled = run.time_s > 0.3
    slip = run.spin_rad_s[settled].mean() * MODEL.tire.R / sim.speed_m_s - 1.0
    assert steady.slip_ratio < 0
    assert slip == pytest.approx(steady.slip_ratio, rel=0.02)
    assert run.rim_fx_n[settled].mean() == pytest.approx(steady.rim_fx_n, rel=0.005)
    assert steady.rim_my_n_m == pytest.approx(-torque, rel=1e-9)


@pytest.mark.parametrize("f_max_hz, bound", [(300.0, 0.005), (150.0, 0.05)])
def test_reduced_ring_follows_the_unreduced_one_over_a_cleat(deflection, f_max_hz, bound):
    """The 20 mm cleat at 10 m/s, axle held: the ring reduced to its modes up to f_max with
    the zone nodes' static shapes gives Fx, Fz and My within 5 % rms of every DOF stepped
    (0.5 % at 300 Hz), on a basis a third (or a sixth) the size."""
    runs = []
    for f_max in (None, f_max_hz):
        sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING,
                               obstacle=cleat(0.02, 0.02), obstacle_ahead_m=0.6, f_max_hz=f_max)
        runs.append((sim, sim.run(0.12, record_every=2)))
    (full_sim, full), (reduced_sim, reduced) = runs
    assert reduced_sim._ny < full_sim._ny / 1.8
    for name, offset in (("rim_fz_n", DEFAULT_LOAD_N), ("rim_fx_n", 0.0), ("rim_my_n_m", 0.0)):
        exact, approx = getattr(full, name), getattr(reduced, name)
        scale = np.sqrt(np.mean((exact - offset) ** 2))
        assert np.sqrt(np.mean((approx - exact) ** 2)) < bound * scale, name


def test_a_change_of_speed_settles_where_the_tire_built_at_the_new_speed_rolls(deflection):
    """The road slows from 20 to 10 m/s during the run: the step follows the wheel's spin
    (its speed terms rebuilt as it changes), and once settled the drag and spin are those of
    the tire built at 10 m/s from the start."""
    def ramp(t):
        return 20.0 - 10.0 * min(max(t - 0.1, 0.0) / 0.2, 1.0)

    changing = InPlaneSimulator(MODEL, 100, 20.0, deflection, point_spacing_m=SPACING,
                                f_max_hz=150.0)
    run = changing.run(1.0, speed_m_s=ramp, record_every=10)
    built = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING,
                             f_max_hz=150.0)
    reference = built.run(0.6, record_every=10)
    late, settled = run.time_s > 0.8, reference.time_s > 0.3
    assert run.rim_fx_n[late].mean() == pytest.approx(reference.rim_fx_n[settled].mean(),
                                                      rel=0.01)
    assert run.spin_rad_s[late].mean() == pytest.approx(reference.spin_rad_s[settled].mean(),
                                                        rel=1e-5)


def test_braking_from_20_m_s_to_rest_rolls_as_the_full_tire_built_at_each_speed(deflection):
    """The road slows from 20 m/s at 25 m/s² to 5 m/s, stays there, and slows to rest: the
    step follows the wheel's spin down (the reduced ring's speed terms rebuilt as it moves).
    At 5 m/s it rolls with the drag and spin of the steady solve of the full tire (every DOF)
    built at 5 m/s, and at rest it carries the static load: the wheel still, the tread's
    elements holding what the stop left in them (less than 1e-3 of the load)."""
    from tire_fmu.core.inplane_contact import steady_rolling

    def road(t):
        if t < 0.1:
            return 20.0
        if t < 0.7:
            return 20.0 - 25.0 * (t - 0.1)
        return 5.0 if t < 1.9 else max(5.0 - 25.0 * (t - 1.9), 0.0)

    sim = InPlaneSimulator(MODEL, 100, 20.0, deflection, point_spacing_m=SPACING,
                           f_max_hz=150.0, backend="auto")
    run = sim.run(2.8, speed_m_s=road, record_every=10)
    full = steady_rolling(InPlaneSimulator(MODEL, 100, 5.0, deflection,
                                           point_spacing_m=SPACING, backend="auto"))
    at_5 = (run.time_s > 1.5) & (run.time_s < 1.9)
    assert run.rim_fx_n[at_5].mean() == pytest.approx(full.rim_fx_n, rel=0.01)
    assert run.spin_rad_s[at_5].mean() == pytest.approx(full.spin_rad_s, rel=1e-5)
    at_rest = run.time_s > 2.5
    assert run.speed_m_s[-1] == 0.0
    load = sim.static_load_n()
    assert run.rim_fz_n[at_rest].mean() == pytest.approx(load, rel=1e-4)
    assert abs(run.rim_fx_n[at_rest].mean()) < 1e-3 * load
    assert abs(run.spin_rad_s[at_rest].mean()) * MODEL.tire.R < 0.01  # below 1 cm/s


def test_a_decelerating_road_brakes_the_free_wheel_through_the_footprint(deflection):
    """The road slows at 20 m/s² from 10 m/s: the free wheel follows it, decelerating at
    a/R, and the road's pull on the footprint is what turns its inertia, I α / R."""
    decel = 20.0
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING,
                           f_max_hz=150.0)
    run = sim.run(0.5, speed_m_s=lambda t: 10.0 - decel * max(t - 0.1, 0.0), record_every=10)
    during = (run.time_s > 0.2) & (run.time_s < 0.5)
    alpha = np.polyfit(run.time_s[during], run.spin_rad_s[during], 1)[0]
    t = MODEL.tire
    assert alpha == pytest.approx(-decel / t.R, rel=0.01)
    inertia = MODEL.tangential.wheel_inertia_kg_m2 + 2 * np.pi * t.R**3 * (t.rhoA + t.m_s)
    assert run.rim_fx_n[during].mean() == pytest.approx(-inertia * alpha / t.R, rel=0.03)


def test_cleat_command_runs_the_cleat_test_of_the_core(capsys, tmp_path):
    import json

    from tire_fmu.cli import main

    argv = ["inplane-cleat", "--point-spacing", "0.01", "--f-max", "150", "--speed", "15"]
    assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    summary = data["summary"]
    deflection = deflection_for_load(MODEL, DEFAULT_LOAD_N, 100, point_spacing_m=0.01)
    assert summary["deflection_m"] == pytest.approx(deflection, rel=1e-12)
    sim = InPlaneSimulator(MODEL, 100, 15.0, deflection, point_spacing_m=0.01,
                           obstacle=cleat(0.02, 0.02), obstacle_ahead_m=0.4, f_max_hz=150.0)
    run = sim.run(len(data["run"]["time_s"]) * sim.step_s)
    assert max(data["run"]["rim_fz_n"]) == pytest.approx(run.rim_fz_n.max(), rel=1e-9)
    # the cleat pushes the tire back, then forward, ringing at the loaded rotational mode
    assert summary["fx_min_n"] < -0.05 * 27700 and summary["fx_max_n"] > 0.05 * 27700
    modes = loaded_modes(InPlaneSimulator(MODEL, 100, 0.0, deflection, point_spacing_m=0.01),
                         f_max_hz=60)
    (rotational,) = [f for f, k in zip(modes.frequencies_hz, modes.kinds) if k == "rotational"]
    assert summary["fx_dominant_hz"] == pytest.approx(rotational, rel=0.25)
    assert main([*argv, "--plot", str(tmp_path / "cleat.png")]) == 0
    assert (tmp_path / "cleat.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["inplane-cleat", "--speed", "0", "--height", "1"]) == 2
    err = capsys.readouterr().err
    assert "--speed = 0 m/s: must be in [0.5, 60] m/s" in err and "--height = 1 m" in err


def test_a_braked_quarter_car_decelerates_as_its_moment_balance_says(deflection):
    """The fore-aft quarter car: the vehicle's 2820 kg driven by the tire's force on the axle,
    a 6 kN m brake on the wheel. Once the slip has settled the vehicle decelerates at
    a = T/(m R + I/R), the wheel's and the vehicle's balance with the road's drag acting at
    R (within 3 %: the pressure's own fore-aft resultant under braking, the slip's share of
    the wheel's deceleration); the slip is the steady solve's for the torque the road
    carries, within 10 % (10 mm points: the two transports of the elements differ by 5 % at
    this spacing at a constant speed, 1.5 % at 2.5 mm, tested above)."""
    from tire_fmu.core.inplane_contact import steady_rolling

    torque, mass = -6000.0, 2820.0
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING,
                           f_max_hz=150.0)
    run = sim.run(0.8, torque_n_m=lambda t: torque if t > 0.05 else 0.0,
                  vehicle_mass_kg=mass, record_every=20)
    settled = run.time_s > 0.4
    decel = np.polyfit(run.time_s[settled], run.speed_m_s[settled], 1)[0]
    t = MODEL.tire
    inertia = MODEL.tangential.wheel_inertia_kg_m2 + 2 * np.pi * t.R**3 * (t.rhoA + t.m_s)
    assert decel == pytest.approx(torque / (mass * t.R + inertia / t.R), rel=0.03)
    assert decel == pytest.approx(run.rim_fx_n[settled].mean() / mass, rel=1e-3)
    # the road carries the brake less what decelerates the wheel's inertia
    slip = run.spin_rad_s[settled] * t.R / run.speed_m_s[settled] - 1.0
    speed = run.speed_m_s[settled].mean()
    steady = steady_rolling(InPlaneSimulator(MODEL, 100, speed, deflection,
                                             point_spacing_m=SPACING, f_max_hz=150.0),
                            torque - inertia * decel / t.R)
    assert slip.mean() == pytest.approx(steady.slip_ratio, rel=0.1)


# -- the rim moved by the host ------------------------------------------------------------------

def smooth_motion(axis: int, amplitude_m: float, rise_s: float):
    """rim_motion moving the rim along x (axis 0) or z (axis 3) to ``amplitude_m`` with a
    smoothstep over ``rise_s`` (position, velocity and acceleration exact)."""
    def motion(t):
        x = min(t / rise_s, 1.0)
        out = [0.0] * 6
        out[axis] = amplitude_m * x * x * (3 - 2 * x)
        out[axis + 1] = amplitude_m * 6 * x * (1 - x) / rise_s
        out[axis + 2] = amplitude_m * (6 - 12 * x) / rise_s**2 if t < rise_s else 0.0
        return tuple(out)

    return motion


@pytest.mark.parametrize("speed_m_s, wheel", [(0.0, "held"), (10.0, "free")])
@pytest.mark.parametrize("axis", [0, 3])
def test_a_rim_accelerating_in_the_air_carries_the_tires_inertia(speed_m_s, wheel, axis):
    """Off the road, a rim accelerating at a steadily (fore-aft or up): once the ringing has
    decayed the tire moves with it and pulls on it with -m a, m the tire's mass without the
    wheel (from the ring's mass matrix: the rigid translation's kinetic energy)."""
    n, a = 60, 5.0
    ring = InPlaneRing(MODEL, n, rim_free=True)
    pattern = ring.rigid_motion(z_m=1.0)
    tire_mass = pattern @ ring.mass @ pattern - MODEL.tangential.wheel_mass_kg
    sim = InPlaneSimulator(MODEL, n, speed_m_s, 0.0, wheel=wheel)

    def motion(t):
        out = [0.0] * 6
        out[3] = 0.005  # held 5 mm clear of the road (a step in position only)
        out[axis] += 0.5 * a * t * t
        out[axis + 1], out[axis + 2] = a * t, a
        return tuple(out)

    run = sim.run(0.8, rim_motion=motion, record_every=10)
    assert run.contact_fz_n.max() == 0.0
    late = run.time_s > 0.7
    force = (run.rim_fx_n if axis == 0 else run.rim_fz_n)[late].mean()
    assert force == pytest.approx(-tire_mass * a, rel=5e-3)
    other = (run.rim_fz_n if axis == 0 else run.rim_fx_n)[late].mean()
    assert abs(other) < 1e-3 * tire_mass * a


def test_a_rim_raised_slowly_unloads_the_tire_as_the_static_solve_says():
    """At rest the rim raised 3 mm over 0.1 s: the footprint settles at the static state of
    the tire pressed 3 mm less, solved directly."""
    n, lift = 60, 0.003
    deflection = deflection_for_load(MODEL, DEFAULT_LOAD_N, n, point_spacing_m=SPACING)
    sim = InPlaneSimulator(MODEL, n, 0.0, deflection, point_spacing_m=SPACING, wheel="held")
    run = sim.run(0.6, rim_motion=smooth_motion(3, lift, 0.1), record_every=10)
    lower = InPlaneSimulator(MODEL, n, 0.0, deflection - lift, point_spacing_m=SPACING,
                             wheel="held")
    settled = run.time_s > 0.5
    assert run.rim_fz_n[settled].mean() == pytest.approx(lower.static_load_n(), rel=2e-3)
    assert lower.static_load_n() < 0.95 * DEFAULT_LOAD_N


def test_a_rim_moving_forward_rolls_as_the_tire_on_a_faster_road():
    """Rolling at 10 m/s, the rim speeds up by 0.5 m/s (axle moving forward): the free wheel
    settles at the spin and drag of the tire on a 10.5 m/s road (its steady solve)."""
    n, extra = 60, 0.5
    deflection = deflection_for_load(MODEL, DEFAULT_LOAD_N, n, point_spacing_m=SPACING)
    sim = InPlaneSimulator(MODEL, n, 10.0, deflection, point_spacing_m=SPACING)

    def motion(t):  # the rim's speed rises smoothly by `extra` over 0.05 s, then holds
        x = min(t / 0.05, 1.0)
        v = extra * x * x * (3 - 2 * x)
        a = extra * 6 * x * (1 - x) / 0.05 if t < 0.05 else 0.0
        distance = extra * 0.05 * (x**3 - x**4 / 2) if t < 0.05 else (
            extra * 0.025 + extra * (t - 0.05))
        return (distance, v, a, 0.0, 0.0, 0.0)

    run = sim.run(0.6, rim_motion=motion, record_every=10)
    faster = steady_rolling(InPlaneSimulator(MODEL, n, 10.0 + extra, deflection,
                                             point_spacing_m=SPACING), 0.0)
    settled = run.time_s > 0.45
    assert run.spin_rad_s[settled].mean() == pytest.approx(faster.spin_rad_s, rel=2e-4)
    assert run.rim_fx_n[settled].mean() == pytest.approx(faster.rim_fx_n, rel=0.03)


def test_a_host_stepping_the_tire_gets_the_runs_forces():
    """InPlaneStepper, given the rim's position and velocity at the START of each
    communication step (as every master gives them), follows the run told the motion itself
    over a cleat with a brake torque, the wheel hopping 3 mm at 15 Hz: within half a per cent
    of each force's range at a 1 ms host step, and closer as the host step shrinks (the
    extension of input_path); a step off the tire's grid is taken."""
    from tire_fmu.core.inplane_contact import InPlaneStepper

    n = 60
    deflection = deflection_for_load(MODEL, DEFAULT_LOAD_N, n, point_spacing_m=SPACING)

    def sim():
        return InPlaneSimulator(MODEL, n, 10.0, deflection, point_spacing_m=SPACING,
                                obstacle=cleat(0.02, 0.02), obstacle_ahead_m=0.6)

    w = 2 * np.pi * 15.0

    def smooth(t):  # up 3 mm and forward 0.6 mm, from rest (its acceleration starts at 0)
        s, co = np.sin(w * t), np.cos(w * t)
        z = (0.003 * s**3, 0.009 * w * s * s * co, 0.009 * w * w * (2 * s * co * co - s**3))
        return (*(0.2 * v for v in z), *z)

    run = sim().run(0.15, rim_motion=smooth, torque_n_m=-1000.0)
    errors = {}
    for h in (1e-3, 1e-4):
        host = InPlaneStepper(sim(), torque_n_m=-1000.0)
        steps = int(round(0.15 / h))
        outputs = []
        for k in range(steps):
            m = smooth(k * h)
            outputs.append(host.advance(h, m[0], m[1], m[3], m[4], torque_n_m=-1000.0))
        every = int(round(h / 1e-4))
        for name in ("rim_fx_n", "rim_fz_n", "rim_my_n_m"):
            hosted = np.array([getattr(o, name) for o in outputs])
            told = getattr(run, name)[every - 1::every]
            errors[h, name] = np.max(np.abs(hosted - told)) / np.ptp(told)
    for name in ("rim_fx_n", "rim_fz_n", "rim_my_n_m"):
        assert errors[1e-3, name] < 5e-3, (name, errors)
        assert errors[1e-4, name] < errors[1e-3, name] / 3.0, (name, errors)
    time = host.time_s
    host.advance(1.5e-4)
    assert host.time_s == pytest.approx(time + 1.5e-4, abs=1e-15)


def test_the_slip_stiffness_is_the_brush_models(deflection):
    """The tread elements are a brush model's bristles: at small slip they stick but at the
    footprint's rear, where the pressure vanishes, and the longitudinal slip stiffness dFx/dκ
    is the brush's 2 k_tx a² (a the footprint's half length, whatever the pressure along it)
    within 2 %; stiffened fourfold, the ring's own compliance takes a share of the slip and
    keeps it below 2 k_tx a²."""
    from dataclasses import replace

    from tire_fmu.core.inplane_contact import steady_rolling

    def stiffness_and_brush(factor):
        model = replace(MODEL, tangential=replace(MODEL.tangential,
                                                  k_tx=factor * MODEL.tangential.k_tx))
        sim = InPlaneSimulator(model, 100, 10.0, deflection, point_spacing_m=0.005)
        free, small = steady_rolling(sim, 0.0), steady_rolling(sim, -300.0)
        assert small.sliding_points <= 1  # the rearmost, as a brush's under any slip
        # the footprint's edges: where the static penetration crosses zero between points
        pen = sim._pen0 + sim._jn @ sim.static_state()
        x = (MODEL.tire.R - deflection) * np.tan(sim._zone.point_theta)
        on = np.flatnonzero(pen > 0)
        ends = [x[i] + pen[i] / (pen[i] - pen[j]) * (x[j] - x[i])
                for i, j in ((on[0], on[0] - 1), (on[-1], on[-1] + 1))]
        half = 0.5 * abs(ends[1] - ends[0])
        stiffness = (small.rim_fx_n - free.rim_fx_n) / (small.slip_ratio - free.slip_ratio)
        return stiffness, 2.0 * model.tangential.k_tx * half**2

    stiffness, brush = stiffness_and_brush(1.0)
    assert stiffness == pytest.approx(brush, rel=0.02)
    stiffer, brush4 = stiffness_and_brush(4.0)
    assert brush4 == pytest.approx(4 * brush, rel=1e-9)  # the footprint is the same
    assert 3.5 * stiffness < stiffer < brush4
