"""The loaded modes of the rolling tire (core/inplane_rolling_modes.py).

References written apart from the linearisation: the loaded modes at rest (its limit as the
speed goes to zero), the steady rolling solved directly (its equilibrium), the simulator's
own stepping (the ringing after a brake step at speed), and the linear system integrated by
its matrix exponential (the modal step response).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from tire_fmu.core.inplane import InPlaneTire
from tire_fmu.core.inplane_contact import InPlaneSimulator, deflection_for_load, loaded_modes
from tire_fmu.core.inplane_rolling_modes import (
    fit_ringing,
    rolling_modes,
    rolling_system,
    torque_step,
)
from tire_fmu.core.parameters import DEFAULT_LOAD_N, ParameterError

MODEL = InPlaneTire()
SPACING = 0.01


@pytest.fixture(scope="module")
def deflection():
    return deflection_for_load(MODEL, DEFAULT_LOAD_N, 100, point_spacing_m=SPACING)


def rotational(modes):
    (k,) = [i for i, kind in enumerate(modes.kinds) if kind == "rotational"]
    return modes.frequencies_hz[k], modes.damping_ratios[k], modes.decay_rates_1_s[k]


@pytest.mark.parametrize("wheel", ["free", "held"])
@pytest.mark.parametrize("torque", [0.0, -3000.0])
def test_the_equilibrium_is_the_steady_rolling(deflection, wheel, torque):
    """steady_rolling's state (its own solve, sets iterated) zeroes ẋ = A x + b to round-off:
    the box scheme's steady state is its trapezoidal transport, sliding points included."""
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING, wheel=wheel)
    system = rolling_system(sim, torque)
    residual = system.a @ system.steady_x + system.b
    scale = np.abs(system.a) @ np.abs(system.steady_x) + np.abs(system.b)
    assert np.all(np.abs(residual) <= 1e-11 * scale)
    if wheel == "free" and torque != 0.0:
        assert np.sum(system.contact & ~system.stick) >= 1  # a sliding point is in the test


def test_other_frozen_sets_are_not_the_steady_rolling(deflection):
    """The steady rolling's own sets handed in give the same system; the first point in
    contact frozen off the road gives another, whose equilibrium steady_rolling's state is
    not (the equilibrium test above can fail)."""
    from tire_fmu.core.inplane_contact import steady_rolling
    from tire_fmu.core.inplane_rolling_modes import steady_sets

    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING)
    contact, stick, sign = steady_sets(sim, steady_rolling(sim, -3000.0))
    same = rolling_system(sim, -3000.0, (contact, stick, sign))
    np.testing.assert_array_equal(same.a, rolling_system(sim, -3000.0).a)
    off = contact.copy()
    off[np.flatnonzero(contact)[0]] = False
    other = rolling_system(sim, -3000.0, (off, stick, sign))
    residual = other.a @ other.steady_x + other.b
    assert np.abs(residual).max() > 1e-6 * np.abs(other.b).max()
    assert rotational(rolling_modes(sim, -3000.0, 90.0, (off, stick, sign)))[0] != (
        pytest.approx(rotational(rolling_modes(sim, -3000.0, 90.0))[0], rel=2e-3))


@pytest.mark.parametrize("wheel", ["free", "held"])
def test_slow_rolling_has_the_loaded_modes_at_rest(deflection, wheel):
    """As the speed goes to zero the elements stop being renewed and stick as springs: the
    rolling modes become loaded_modes' (measured within 0.04 % at 0.05 m/s)."""
    at_rest = loaded_modes(InPlaneSimulator(MODEL, 100, 0.0, deflection,
                                            point_spacing_m=SPACING, wheel=wheel), 90.0)
    slow = rolling_modes(InPlaneSimulator(MODEL, 100, 0.05, deflection,
                                          point_spacing_m=SPACING, wheel=wheel), 0.0, 90.0)
    tire = [i for i, kind in enumerate(slow.kinds) if kind != "transport"]
    np.testing.assert_allclose(slow.frequencies_hz[tire][:5], at_rest.frequencies_hz[:5],
                               rtol=2e-3)
    f_rest, zeta_rest = [(f, z) for f, z, k in zip(at_rest.frequencies_hz,
                                                    at_rest.damping_ratios, at_rest.kinds)
                         if k == "rotational"][0]
    f_slow, zeta_slow, _ = rotational(slow)
    assert f_slow == pytest.approx(f_rest, rel=1e-3)
    assert zeta_slow == pytest.approx(zeta_rest, rel=0.05)


def test_rolling_damps_the_rotational_mode(deflection):
    """At 10 m/s the renewed elements damp the wheel's turn like a slip damper: the rotational
    mode's damping ratio is many times the one at rest."""
    slow = rolling_modes(InPlaneSimulator(MODEL, 100, 0.05, deflection,
                                          point_spacing_m=SPACING), -3000.0, 90.0)
    fast = rolling_modes(InPlaneSimulator(MODEL, 100, 10.0, deflection,
                                          point_spacing_m=SPACING), -3000.0, 90.0)
    assert rotational(fast)[1] > 10 * rotational(slow)[1]
    assert fast.sliding_points >= 1 and fast.points_in_contact > 10


def test_the_reduced_ring_rolls_with_the_same_modes(deflection):
    """On the Ritz basis of InPlaneSimulator(f_max_hz=...) the linearisation has nearly half
    the states and the same low modes (at 300 Hz measured within 2e-5 in frequency and
    decay)."""
    full, reduced = (rolling_modes(InPlaneSimulator(MODEL, 100, 10.0, deflection,
                                                    point_spacing_m=SPACING, f_max_hz=f),
                                   -3000.0, 70.0) for f in (None, 300.0))
    assert reduced.shapes.shape[0] < 0.6 * full.shapes.shape[0]
    np.testing.assert_allclose(reduced.frequencies_hz, full.frequencies_hz, rtol=1e-3)
    np.testing.assert_allclose(reduced.decay_rates_1_s, full.decay_rates_1_s, rtol=1e-2)
    assert reduced.kinds == full.kinds


def test_the_modal_step_response_is_the_linear_system(deflection):
    """Fx after a brake step by the modes (left and right eigenvectors) against the same
    linear system stepped exactly by its matrix exponential."""
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING)
    step = torque_step(sim, 0.0, -3000.0)
    before = rolling_system(sim, 0.0)
    system = rolling_system(sim, -3000.0)
    nr, ny = system.n_ring, system.n_rate
    x = np.concatenate([before.steady_x[:nr + ny],
                        sim_steady_elements(sim, 0.0)[system.stick_points]])
    from tire_fmu.core.inplane_rolling_modes import fx_rows

    c, c0 = fx_rows(sim, system)
    dt = 1e-3
    carry = scipy.linalg.expm(system.a * dt)
    exact = []
    for _ in range(60):
        exact.append(c @ x + c0)
        x = system.steady_x + carry @ (x - system.steady_x)
    modal = step.fx(dt * np.arange(60))
    assert step.fx_after_n == pytest.approx(c @ system.steady_x + c0, rel=1e-12)
    np.testing.assert_allclose(modal, exact, atol=1e-6 * np.ptp(exact))
    assert np.ptp(exact) > 3000.0  # a step that rings


def sim_steady_elements(sim, torque):
    from tire_fmu.core.inplane_contact import steady_rolling

    return steady_rolling(sim, torque).element_deflection_m


def test_a_brake_step_at_speed_rings_at_the_rolling_rotational_mode():
    """A -3 kN m brake step at 10 m/s (wheel free, axle held; N = 100, 5 mm points): Fx rings
    at rolling_modes' rotational frequency and decay, read by a fit of damped cosines seeded
    by the linear step response's four largest modes (bench_inplane_brake_ringing.py records
    what they are); the bounds leave room for the run's sets, which are not frozen."""
    spacing = 0.005
    deflection = deflection_for_load(MODEL, DEFAULT_LOAD_N, 100, point_spacing_m=spacing)
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=spacing)
    at = 0.05
    run = sim.run(at + 0.1, torque_n_m=lambda t: -3000.0 if t >= at else 0.0)
    step = torque_step(sim, 0.0, -3000.0)
    f_rot, _, decay_rot = rotational(rolling_modes(sim, -3000.0, 100.0))
    seeds = step.dominant(4)
    assert seeds[0][0] == pytest.approx(f_rot, rel=1e-12)  # the rotational mode leads Fx
    after = run.time_s > at + 0.005
    t, fx = run.time_s[after] - at, run.rim_fx_n[after]
    (fitted, *_), rms = fit_ringing(t, fx, seeds)
    assert fitted[0] == pytest.approx(f_rot, rel=0.01)
    assert fitted[1] == pytest.approx(decay_rot, rel=0.05)
    assert rms < 0.05 * fx.std()
    # the whole response, not only its frequency: the linear one follows the run
    assert np.sqrt(np.mean((step.fx(t) - fx) ** 2)) < 0.1 * np.ptp(fx)


def test_without_sliding_the_run_is_the_linearisation(deflection):
    """A -1 kN m brake step at 10 m/s (wheel free, N = 100, 10 mm points), which leaves every
    point sticking: with no set to change, the run is the linear system the rolling modes
    come from, so Fx rings at their rotational mode and decays at its rate within a per cent,
    and the linear step response follows the run to a small share of its swing. (At -3 kN m
    a point slides on and off through the ringing and the run decays faster than any frozen
    set: bench_inplane_brake_ringing.py.)"""
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING)
    at = 0.05
    run = sim.run(at + 0.1, torque_n_m=lambda t: -1000.0 if t >= at else 0.0)
    modes = rolling_modes(sim, -1000.0, 100.0)
    assert modes.sliding_points == 0
    after = run.time_s > at + 0.005
    assert run.sliding_points[after].max() == 0
    f_rot, _, decay_rot = rotational(modes)
    step = torque_step(sim, 0.0, -1000.0)
    t, fx = run.time_s[after] - at, run.rim_fx_n[after]
    (fitted, *_), _ = fit_ringing(t, fx, step.dominant(4))
    assert fitted[0] == pytest.approx(f_rot, rel=0.005)
    assert fitted[1] == pytest.approx(decay_rot, rel=0.02)
    assert np.sqrt(np.mean((step.fx(t) - fx) ** 2)) < 0.01 * np.ptp(fx)


def test_bad_inputs_are_named(deflection):
    sim = InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=SPACING)
    with pytest.raises(ParameterError, match="f_max_hz"):
        rolling_modes(sim, 0.0, f_max_hz=-1.0)
    # at rest the tire has its static footprint (the loaded modes), under no torque
    with pytest.raises(ParameterError, match="torque_n_m"):
        rolling_modes(InPlaneSimulator(MODEL, 100, 0.0, deflection, point_spacing_m=SPACING),
                      -100.0)


def test_command_reports_the_rolling_modes(capsys, deflection):
    import json

    from tire_fmu.cli import main

    assert main(["inplane-modes", "--load", str(DEFAULT_LOAD_N), "--speed", "10", "--rim-free",
                 "--torque", "-3000", "--point-spacing", "0.01", "--max-frequency", "60",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["deflection_m"] == pytest.approx(deflection, rel=1e-12)
    modes = rolling_modes(InPlaneSimulator(MODEL, 100, 10.0, deflection, point_spacing_m=0.01),
                          -3000.0, f_max_hz=60)
    tire = [k != "transport" for k in modes.kinds]
    np.testing.assert_allclose([m["frequency_hz"] for m in data["modes"]],
                               modes.frequencies_hz[tire], rtol=1e-9)
    assert [m["kind"] for m in data["modes"]].count("rotational") == 1
    assert data["slip_ratio"] < 0 and data["sliding_points"] == modes.sliding_points
    # a held wheel's torque is what holds it: refused, not ignored
    assert main(["inplane-modes", "--load", "27700", "--speed", "10", "--torque", "-3000"]) == 2
    assert "--torque" in capsys.readouterr().err
