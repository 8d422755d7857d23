"""The in-plane tire's linear input/output model and its balanced reduction
(core/inplane_io.py, ``tire-fmu inplane-frf`` / ``inplane-reduce``), against what is written
apart from it: steady_rolling's direct solves at neighbouring operating points (the static
gains), the simulator's own time steps from a smooth sine of each input (the whole
response, sets free), loaded_modes at rest, a quadrature of the road's windows and the
simulator's road reader; and the reduced model against the full one, and both files back."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
import scipy.io
import scipy.signal

from tire_fmu.cli import main
from tire_fmu.core.inplane import InPlaneTire
from tire_fmu.core.inplane_contact import (
    InPlaneSimulator,
    deflection_for_load,
    loaded_modes,
    steady_rolling,
)
from tire_fmu.core.inplane_io import (
    TYPICAL_INPUT,
    InPlaneReductionSettings,
    all_responses,
    linear_model,
    pair_errors,
    reduce_linear_model,
    road_window_response,
)
from tire_fmu.core.inplane_rolling_modes import rolling_modes
from tire_fmu.core.obstacles import SampledRoad
from tire_fmu.core.parameters import DEFAULT_LOAD_N, ParameterError
from tire_fmu.model_files import (
    ModelFileError,
    load_inplane_npz,
    save_inplane_mat,
    save_inplane_npz,
)

MODEL = InPlaneTire()
N, SPACING, F_RING = 100, 0.01, 300.0


@functools.cache
def deflection(load_n: float = DEFAULT_LOAD_N) -> float:
    return deflection_for_load(MODEL, load_n, N, point_spacing_m=SPACING)


def simulator(speed=10.0, wheel="free", d=None, **kw) -> InPlaneSimulator:
    return InPlaneSimulator(MODEL, N, speed, deflection() if d is None else d, wheel=wheel,
                            point_spacing_m=SPACING, f_max_hz=F_RING, **kw)


@functools.cache
def rolling(wheel: str = "free"):
    sim = simulator(wheel=wheel)
    return sim, linear_model(sim)


@functools.cache
def reduced():
    return reduce_linear_model(rolling()[1])


def steady_outputs(sim, torque=0.0) -> np.ndarray:
    s = steady_rolling(sim, torque)
    return np.array([s.rim_fx_n, s.rim_fz_n, s.rim_my_n_m, s.spin_rad_s - sim.spin_rad_s])


# ----- static gains against steady_rolling -----

def test_static_gains_are_steady_rollings_slopes():
    """A constant rim lift is the tire pressed less, a constant torque another steady
    rolling: the static gains are steady_rolling's central differences (its own solve,
    sets iterated) to 1e-5 of the largest."""
    sim, linear = rolling()
    gain = linear.static_gain()
    step = 1e-5
    pressed = [steady_outputs(simulator(d=deflection() + sign * step)) for sign in (-1, 1)]
    lift = -(pressed[1] - pressed[0]) / (2 * step)
    # the moment is zero in both (a push along a ray has no moment): judged on the forces'
    # scale times the radius
    scale = np.array([1.0, 1.0, MODEL.tire.R, 0.0]) * np.abs(lift[:2]).max()
    assert np.all(np.abs(gain[:, linear.input_names.index("rim_z")] - lift)
                  <= 1e-5 * np.maximum(np.abs(lift), scale))
    torques = [steady_outputs(sim, t) for t in (-20.0, 20.0)]
    per_torque = (torques[1] - torques[0]) / 40.0
    np.testing.assert_allclose(gain[:, linear.input_names.index("torque")], per_torque,
                               rtol=1e-5, atol=1e-6)
    # the road under every point lifted together is the rim lowered by as much
    roads = [i for i, name in enumerate(linear.input_names) if name.startswith("road_")]
    assert np.all(np.abs(gain[:, roads].sum(axis=1) + lift)
                  <= 1e-5 * np.maximum(np.abs(lift), scale))


def test_the_operating_point_is_the_steady_rolling():
    sim, linear = rolling()
    op = linear.operating_point["static_outputs"]
    expected = steady_outputs(sim)
    np.testing.assert_allclose([op["rim_Fx"], op["rim_Fz"], op["rim_My"], op["wheel_rate"]],
                               expected, rtol=1e-9, atol=1e-9 * expected[1])


def test_at_rest_the_system_is_the_loaded_tires():
    """Speed 0: the linearisation is the static footprint with the elements as springs,
    whose modes loaded_modes solves from its own stiffness (K + J_xᵀ k_x J_x)."""
    sim = simulator(speed=0.0)
    ours = rolling_modes(sim, f_max_hz=150.0)
    theirs = loaded_modes(sim, f_max_hz=150.0)
    tire = np.array([k != "transport" for k in ours.kinds])
    np.testing.assert_allclose(np.sort(ours.frequencies_hz[tire])[:12],
                               np.sort(theirs.frequencies_hz)[:12], rtol=2e-3)
    with pytest.raises(ParameterError, match="torque_n_m"):
        linear_model(sim, -100.0)


# ----- against the simulator stepping -----

def smooth_sine(amplitude: float, frequency_hz: float, ramp_s: float = 0.05):
    """u, u̇, ü of a sine faded in by a half cosine (all three 0 at t = 0)."""
    w = 2 * np.pi * frequency_hz

    def signal(t):
        t = np.asarray(t, dtype=float)
        on = t < ramp_s
        r = np.where(on, 0.5 * (1 - np.cos(np.pi * t / ramp_s)), 1.0)
        r1 = np.where(on, 0.5 * np.pi / ramp_s * np.sin(np.pi * t / ramp_s), 0.0)
        r2 = np.where(on, 0.5 * (np.pi / ramp_s) ** 2 * np.cos(np.pi * t / ramp_s), 0.0)
        s, c = np.sin(w * t), np.cos(w * t)
        return (amplitude * r * s, amplitude * (r1 * s + r * w * c),
                amplitude * (r2 * s + 2 * r1 * w * c - r * w * w * s))

    return signal


def linear_run(model, columns: list[int], time_s, u, u_rate, u_accel) -> np.ndarray:
    """(times, outputs): the state-space model from rest under the inputs (columns of u)."""
    system = scipy.signal.StateSpace(model.a, model.b[:, columns], model.c,
                                     model.d0[:, columns])
    t = np.concatenate([[0.0], time_s])
    inputs = np.vstack([np.zeros((1, len(columns))), u])
    _, y, _ = scipy.signal.lsim(system, inputs, t)
    return y[1:] + u_rate @ model.d1[:, columns].T + u_accel @ model.d2[:, columns].T


def rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


CASES = {  # input, amplitude, frequency, the output it drives most
    "rim_z at 90 Hz": ("rim_z", 1e-4, 90.0, 1),
    "rim_x at 60 Hz": ("rim_x", 1e-4, 60.0, 0),
    "torque at 20 Hz": ("torque", 100.0, 20.0, 0),
    # 0.2 mm of a 25 cm road already slides the footprint's edges (2-7 % off, 10x less
    # at 20 µm: the sets, not the linearisation)
    "road at 40 Hz": ("road", 2e-5, 40.0, 1),
}


@functools.cache
def base_run():
    return simulator().run(0.3)


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_the_simulator_stepping_follows_the_linear_model(case):
    """From the steady state, a smooth sine of one input (0.3 s, 10 m/s, the wheel free):
    the run less the same run without it against the linear model and its reduction, from
    rest under the same input. Rim forces within 1 % rms of the largest force the input
    drives, My within 1 % of its own; what differs is the step's semi-Lagrangian transport
    of the elements beside the box scheme, and the sets left free."""
    name, amplitude, frequency, main_output = CASES[case]
    sim, linear = rolling()
    signal = smooth_sine(amplitude, frequency)
    if name == "road":
        # a sampled sine road that reaches the zone's front at t = 0
        wavelength = sim.speed_m_s / frequency
        s = np.arange(0.0, 4.0, 1e-3)
        ramp = np.clip(s / (0.05 * sim.speed_m_s), 0, 1)
        heights = (amplitude * 0.5 * (1 - np.cos(np.pi * ramp))
                   * np.sin(2 * np.pi * s / wavelength))
        front = float(np.max(sim._zone.road_windows_m(sim.deflection_m)))
        road_sim = simulator(obstacle=SampledRoad(1e-3, heights), obstacle_ahead_m=front)
        run = road_sim.run(0.3)
        t = run.time_s
        reads = [road_sim.road(time) for time in t]
        u = np.array([r[0] for r in reads])
        u_rate = np.array([r[1] for r in reads])
        columns = [i for i, n in enumerate(linear.input_names) if n.startswith("road_")]
        u_accel = np.zeros_like(u)
    else:
        if name == "torque":
            run = sim.run(0.3, torque_n_m=lambda t: float(signal(t)[0]))
        else:
            lead = (0, 0, 0) if name == "rim_z" else ()
            tail = () if name == "rim_z" else (0, 0, 0)
            run = sim.run(0.3, rim_motion=lambda t: (*lead, *map(float, signal(t)), *tail))
        t = run.time_s
        u, u_rate, u_accel = (x[:, None] for x in signal(t))
        columns = [linear.input_names.index(name)]
    base = base_run()
    stepped = np.stack([run.rim_fx_n - base.rim_fx_n, run.rim_fz_n - base.rim_fz_n,
                        run.rim_my_n_m - base.rim_my_n_m], axis=1)
    for model in (linear, reduced()):
        y = linear_run(model, columns, t, u, u_rate, u_accel)[:, :3]
        forces = max(rms(y[:, 0]), rms(y[:, 1]))
        assert rms(y[:, main_output]) == pytest.approx(forces)
        for k in (0, 1):
            assert rms(stepped[:, k] - y[:, k]) < 0.01 * forces, (case, k)
        assert rms(stepped[:, 2] - y[:, 2]) < 0.01 * rms(y[:, 2]) + 1e-3 * forces * sim.model.tire.R


def test_the_road_windows_are_their_means():
    """A point's road is the mean of the road at the front over its window of delays: the
    closed form against a quadrature, and a plate where the window is a point."""
    delays = np.array([[0.0, 0.002], [0.004, 0.0065], [0.01, 0.01]])
    omega = np.array([0.0, 30.0, 600.0, 2000.0])
    got = road_window_response(delays, omega)
    tau = [np.linspace(a, b, 20001) for a, b in delays]
    for j, taus in enumerate(tau):
        for i, w in enumerate(omega):
            expected = (np.trapezoid(np.exp(-1j * w * taus), taus) / (taus[-1] - taus[0])
                        if taus[-1] > taus[0] else np.exp(-1j * w * taus[0]))
            assert abs(got[i, j] - expected) < 1e-6


# ----- the reduction -----

def test_the_reduction_meets_its_target_between_its_frequencies():
    """The report's error is at most the target; on frequencies it was not chosen on the
    reduced model stays within twice it; the static gain is kept (residualised: to 1e-6 of
    each output's largest response to the inputs at their typical amplitudes, the rounding
    of the balancing);
    it is stable and a small part of the full model."""
    _, linear = rolling()
    small = reduced()
    report = small.report
    assert report["max_relative_error"] <= report["target_error"] == 0.01
    assert small.n_states < linear.n_states / 4
    assert np.linalg.eigvals(small.a).real.max() < 0
    # each input at its typical amplitude, as the balancing weighs them
    typical = np.array([TYPICAL_INPUT["road" if n.startswith("road_") else n]
                        for n in linear.input_names])
    full_gain = linear.static_gain() * typical
    rows = np.abs(full_gain).max(axis=1, keepdims=True)
    assert np.all(np.abs(small.static_gain() * typical - full_gain) <= 1e-6 * rows)
    freqs = np.geomspace(0.6, 290.0, 211)  # between the error grid's
    errors = pair_errors(all_responses(small, freqs), all_responses(linear, freqs),
                         linear.output_names)
    assert max(errors.values()) <= 2 * report["target_error"]


def test_a_tighter_target_keeps_more_states():
    _, linear = rolling()
    loose = reduce_linear_model(linear, InPlaneReductionSettings(target_error=0.05))
    tight = reduce_linear_model(linear, InPlaneReductionSettings(target_error=0.002))
    assert loose.n_states < reduced().n_states < tight.n_states
    assert tight.report["max_relative_error"] <= 0.002


def test_bad_settings_are_named_all_at_once():
    with pytest.raises(ParameterError) as error:
        InPlaneReductionSettings(target_error=0.0, band_hz=(10.0, 1.0), n_states=0)
    text = str(error.value)
    assert "target_error" in text and "band_hz" in text and "n_states" in text


def test_a_driven_wheel_is_refused():
    with pytest.raises(ParameterError, match="wheel"):
        linear_model(simulator(wheel="driven"))


# ----- files -----

def test_npz_round_trip_and_a_changed_file_is_refused(tmp_path):
    model = reduced()
    path = save_inplane_npz(model, tmp_path / "tire.npz")
    back = load_inplane_npz(path)
    for name in ("a", "b", "c", "d0", "d1", "d2", "road_delays_s"):
        np.testing.assert_array_equal(getattr(back, name), getattr(model, name))
    assert back.input_names == model.input_names and back.output_names == model.output_names
    freqs = [1.0, 50.0, 200.0]
    np.testing.assert_array_equal(back.frequency_response("road", freqs),
                                  model.frequency_response("road", freqs))
    with np.load(path) as archive:
        contents = dict(archive)
    contents["a"] = contents["a"] * (1 + 1e-12)
    np.savez(tmp_path / "changed.npz", **contents)
    with pytest.raises(ModelFileError, match="'a' does not match its checksum"):
        load_inplane_npz(tmp_path / "changed.npz")


def test_mat_holds_the_state_space_with_the_inputs_derivatives(tmp_path):
    model = reduced()
    data = scipy.io.loadmat(save_inplane_mat(model, tmp_path / "tire.mat"))
    m = len(model.input_names)
    np.testing.assert_array_equal(data["A"], model.a)
    np.testing.assert_array_equal(data["B"][:, :m], model.b)
    assert not data["B"][:, m:].any()
    np.testing.assert_array_equal(data["D"], np.hstack([model.d0, model.d1, model.d2]))
    meta = json.loads(str(np.squeeze(data["metadata_json"])))
    assert meta["inputs"] == list(model.input_names)


# ----- the commands -----

def test_frf_command_is_the_models_response(capsys, tmp_path):
    plot = tmp_path / "bode.png"
    assert main(["inplane-frf", "--input", "torque", "--output", "rim_Fx", "--points", "5",
                 "--ring-f-max", "300", "--point-spacing", "0.01", "--reduced", "--json",
                 "--plot", str(plot)]) == 0
    data = json.loads(capsys.readouterr().out)
    full, small = data["responses"]
    assert full["unit"] == "N/(N m)" and len(full["magnitude"]) == 5
    assert data["max_relative_error"] <= 0.01 and data["reduction"]["n_states"] < 100
    assert plot.stat().st_size > 10_000


def test_reduce_command_writes_a_model_that_loads(capsys, tmp_path):
    out = tmp_path / "tire.npz"
    assert main(["inplane-reduce", "--ring-f-max", "300", "--point-spacing", "0.01",
                 "--wheel", "held", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    model = load_inplane_npz(out)
    assert f"{model.n_states} of" in text and "torque" not in model.input_names
    assert model.output_names == ("rim_Fx", "rim_Fz", "rim_My")


@pytest.mark.parametrize("args, named", [
    (["--target-error", "0"], "--target-error"), (["--band", "5,1"], "--band"),
    (["--out", "x.csv"], "--out"), (["--torque", "-100", "--wheel", "held"], "--torque"),
    (["--speed", "90"], "--speed")])
def test_bad_options_are_one_line_errors(capsys, args, named):
    assert main(["inplane-reduce", *args]) != 0
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err
