"""The simulator's fast paths against the plain formulas they replace: the fused per-h step
(FusedStep) against DiagonalStepper.step/output, the road delay line against the history
search, and the step-size jitter hosts produce."""

import numpy as np
import pytest

from tire_fmu.core import build_model, validate
from tire_fmu.core.reduction import reduce
from tire_fmu.core.simulation import SimulatorState, StepError, TireSimulator
from tire_fmu.core.stepping import DiagonalStepper


@pytest.fixture(scope="module")
def reduced():
    def make(speed):
        tire, op = validate({}, {"n_elements": 40, "speed_m_s": speed})
        return reduce(build_model(tire, op), report=False)

    return {0.0: make(0.0), 15.0: make(15.0)}


@pytest.mark.parametrize("speed", [0.0, 15.0])
def test_fused_step_equals_the_diagonal_stepper(reduced, speed):
    """Rim input only, so the delayed road plays no part: the outputs and the modal state
    of the fused path are the stepper's, step after step, with the step size changing."""
    model = reduced[speed]
    sim, stepper = TireSimulator(model), DiagonalStepper.from_reduced(model)
    q = np.zeros(model.n_modes, complex)
    m = model.n_inputs
    rng = np.random.default_rng(1)
    for i in range(150):
        h = (1e-4, 2.5e-4, 1e-3)[i % 3]
        rim_z, rim_vz = rng.normal(scale=(1e-3, 1e-2))
        y = sim.step(h, rim_z, rim_vz, 0.0, 0.0)
        u = np.zeros(2 * m)
        u[0], u[m] = rim_z, rim_vz
        q = stepper.step(q, u, h)
        u[0] += rim_vz * h  # the outputs are read at the ramp's end
        expected = sim.static + stepper.output(q, u)
        np.testing.assert_allclose(y, expected, rtol=1e-13, atol=1e-13 * sim.static[0])
    np.testing.assert_allclose(sim.q, q, rtol=1e-12, atol=1e-14 * np.abs(q).max())


def _road(t):
    w = 2 * np.pi * 30
    return 1e-3 * np.sin(w * t), 1e-3 * w * np.cos(w * t)


def test_the_delay_line_equals_the_history_search(reduced):
    model = reduced[15.0]
    line, search = TireSimulator(model), TireSimulator(model)
    steps = [1e-4] * 250 + [2e-4] * 150 + [1e-4] * 250
    t, used = 0.0, []
    for h in steps:
        search._delay_line_samples = 10**9  # never hands over to a delay line
        inputs = (1e-4 * np.sin(50 * t), 0.0, *_road(t))
        np.testing.assert_allclose(line.step(h, *inputs), search.step(h, *inputs),
                                   rtol=1e-12, atol=1e-12 * line.static[0])
        used.append(line._delay_line is not None)
        t += h
    assert search._delay_line is None
    # on after a full reach of uniform steps, off when h changes, on again later
    assert used[200] and not used[260] and used[390] and not used[410] and used[-1]


@pytest.mark.parametrize("steps_before", [10, 200])
def test_restoring_a_state_takes_the_same_path_bit_for_bit(reduced, steps_before):
    """Before the delay line starts and after it: a restored state, also in a fresh
    simulator, reproduces the steps exactly."""
    sim = TireSimulator(reduced[15.0])
    for i in range(steps_before):
        sim.step(1e-4, 0.0, 0.0, *_road(i * 1e-4))
    saved = sim.get_state().to_bytes()
    future = [_road(j * 3e-4) for j in range(30)]
    first = [sim.step(1e-4, 0.0, 0.0, *road) for road in future]
    for target in (sim, TireSimulator(reduced[15.0])):
        target.set_state(SimulatorState.from_bytes(saved))
        assert [target.step(1e-4, 0.0, 0.0, *road).tolist() for road in future] == \
            [y.tolist() for y in first]


def test_step_size_jitter_of_a_host_reuses_the_coefficients(reduced):
    """fmpy steps by differences of communication points, h jitters in the last bits."""
    model = reduced[15.0]
    fixed, jittered = TireSimulator(model), TireSimulator(model)
    h, start = 1e-4, 7.0
    fixed.reset(start)
    jittered.reset(start)
    for n in range(300):
        inputs = (0.0, 0.0, *_road(n * h))
        a = fixed.step(h, *inputs)
        t, t_next = start + n * h, start + (n + 1) * h
        jittered.time = t
        b = jittered.step(t_next - t, *inputs)
        np.testing.assert_allclose(b, a, rtol=1e-11, atol=1e-12 * fixed.static[0])
    assert len(jittered._kernels) == 1 and jittered._delay_line is not None


def test_finite_inputs_whose_sum_overflows_are_accepted(reduced):
    sim = TireSimulator(reduced[0.0])
    sim.step(1e-4, 1e308, 0.0, 1e308, 0.0)  # the quick test says no, the exact one yes
    with pytest.raises(StepError, match="road_z = inf"):
        sim.step(1e-4, 0.0, 0.0, np.inf, 0.0)
