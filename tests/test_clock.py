"""The simulator's clock (core.clock): time since the start, summed without drift, so the
time-invariant tire gives the same outputs whenever a run starts; steps the clock cannot
resolve are refused. And what a simulator state must mean to be set (state_problems)."""

import math

import numpy as np
import pytest

from tire_fmu.core import OperatingPoint, TireParameters, clock
from tire_fmu.core.contact_dynamics import (
    MAX_STATE_DISPLACEMENT_M,
    ContactSimulator,
    StateError,
    StepError,
    build_contact_model,
)


@pytest.fixture(scope="module")
def rolling():
    return build_contact_model(TireParameters(), OperatingPoint(n_elements=40, speed_m_s=20.0))


def _road(t):
    """A 15 Hz road of 5 mm and a 1 cm step up at 20 ms."""
    w = 2 * math.pi * 15
    return (0.005 * math.sin(w * t) + (0.01 if t >= 0.02 else 0.0),
            0.005 * w * math.cos(w * t))


def _run(model, start, steps, h):
    sim = ContactSimulator(model, start)
    rows = [sim.step_values(h, 0.0, 0.0, *_road(k * h)) for k in range(steps)]
    return sim, np.array(rows)


# -- the clock itself ---------------------------------------------------------------------------

@pytest.mark.parametrize("h", [1e-4, 2.5e-4, 1e-3 / 3])
def test_a_million_steps_sum_to_k_h_without_drift(h):
    """Issue 19: time accumulated over 1e6 steps against k·h. A plain sum of 1e-4 drifts by
    2.2e-9 s over them; the compensated one stays within an ulp of k·h all along."""
    elapsed = carry = plain = 0.0
    worst = 0.0
    for k in range(1, 1_000_001):
        elapsed, carry = clock.advance(elapsed, carry, h)
        plain += h
        if k % 1000 == 0:
            worst = max(worst, abs(elapsed - k * h) / math.ulp(k * h))
            assert abs(carry) <= math.ulp(elapsed)  # what a state's clock is checked for
    assert worst <= 1.0
    assert abs(plain - 1e6 * h) > 100 * math.ulp(1e6 * h)  # what the old clock did


def test_what_the_clock_resolves():
    """A step is resolved while the spacing of doubles at its end is at most h: h = 1e-4 s
    up to 2^39 s = 5.5e11 s (at 1e12 s the spacing is 1.22e-4 s, and from 2.2e12 s t + h is
    t), h = 2.5e-4 s up to 2^41 s."""
    assert clock.resolved_until(1e-4) == 2.0**39
    assert clock.resolves(2.0**39 - 1.0, 1e-4) and not clock.resolves(2.0**39, 1e-4)
    assert not clock.resolves(1e12, 1e-4) and clock.resolves(1e12, 2.5e-4)
    assert clock.resolves(-1.7e9, 1e-4) and clock.resolves(1.7e9, 1e-4)
    assert 3e12 + 1e-4 == 3e12 and not clock.resolves(3e12, 1e-4)
    assert not clock.resolves(math.nan, 1e-4) and not clock.resolves(0.0, math.nan)
    for t, h in ((1e12, 1e-4), (1.7e9, 1e-12), (-5e15, 0.5)):
        spacing = math.ulp(abs(t) + h)
        assert spacing > h  # the step is below the resolution: refused
        assert clock.resolves(t, spacing) or clock.resolves(t, 2 * spacing)


# -- the simulator on it --------------------------------------------------------------------------

@pytest.mark.parametrize("start", [1e6, 1.7e9, 1e12, -1.7e9])
def test_outputs_do_not_depend_on_the_start_time(rolling, start):
    """Issue 19: at 20 m/s the outputs depended on the start time (0.76 N apart at 1e6 s,
    1.3-4 kN at 1.7e9 s, 13 kN at 1e12 s): the road history was indexed by the absolute time.
    Indexed by the time since the start, a run is the same run, bit for bit."""
    h = 2.5e-4  # resolved at 1e12 s (1e-4 s is not: the test below)
    reference, expected = _run(rolling, 0.0, 300, h)
    sim, rows = _run(rolling, start, 300, h)
    np.testing.assert_array_equal(rows, expected)
    assert sim.elapsed_s == reference.elapsed_s == reference.time
    assert sim.time == start + reference.elapsed_s


def test_a_step_the_clock_cannot_resolve_is_refused_and_changes_nothing(rolling):
    sim = ContactSimulator(rolling, 1e12)
    sim.step_values(2.5e-4, 0.0, 0.0, 0.0, 0.0)
    before = sim.get_state().to_bytes()
    with pytest.raises(StepError) as refused:
        sim.step_values(1e-4, 0.0, 0.0, 0.0, 0.0)
    message = str(refused.value)
    assert message.startswith("step size h = 0.0001 s at t = 1000000000000.0") and \
        "take steps of at least 0.000122 s, or run at times below 5.498e+11 s" in message
    assert sim.get_state().to_bytes() == before
    with pytest.raises(StepError, match="at t = 1e\\+16 s"):  # the clock would stop
        ContactSimulator(rolling, 1e16).step_values(1e-4, 0.0, 0.0, 0.0, 0.0)


def test_a_long_run_from_an_epoch_start_keeps_time_and_outputs(rolling):
    """50 000 steps (5 s) from an epoch start: the clock reads start + k·h to a rounding of
    the absolute time, and the last outputs are those of the same run from 0."""
    h, steps = 1e-4, 50_000
    late, late_rows = _run(rolling, 1.7e9, steps, h)
    early, early_rows = _run(rolling, 0.0, steps, h)
    assert abs(late.elapsed_s - steps * h) <= math.ulp(steps * h)
    assert late.time == 1.7e9 + late.elapsed_s
    np.testing.assert_array_equal(late_rows[-100:], early_rows[-100:])


# -- what a state must mean ------------------------------------------------------------------------

@pytest.fixture(scope="module")
def stepped(rolling):
    """A simulator 60 ms into a run at 20 m/s: its road delay line runs."""
    sim, _ = _run(rolling, 0.0, 600, 1e-4)
    return sim


def _refused(sim, **changes):
    state = sim.get_state().replaced(**changes)
    before = sim.get_state().to_bytes()
    with pytest.raises(StateError) as refused:
        sim.set_state(state)
    assert sim.get_state().to_bytes() == before  # nothing changed
    return str(refused.value)


def test_a_true_state_is_accepted_and_resumes_exactly(stepped, rolling):
    state = stepped.get_state()
    assert stepped.state_problems(state) == []
    other = ContactSimulator(rolling)
    other.set_state(state)
    assert other.step_values(1e-4, 0.0, 0.0, 0.0, 0.0) == \
        stepped.step_values(1e-4, 0.0, 0.0, 0.0, 0.0)


def test_a_clock_no_run_reaches_is_refused(stepped):
    """Issue 19: time was only checked to be finite (1e300 was accepted and the clock
    stalled)."""
    assert "where the clock does not resolve it" in _refused(stepped, start_time=1e300)
    assert "its clock reads -1.0 s since the start" in _refused(stepped, elapsed_s=-1.0)
    assert "only steps advance the clock" in _refused(stepped, last_step_s=math.nan)
    assert "its carry below one rounding" in _refused(stepped, carry_s=1e-6)


def test_a_road_history_the_reader_would_not_hold_is_refused(stepped):
    """Issue 19: a road history with wrong times, or 2e6 samples, ran. (The state holds the
    recorded history alone: a kernel rebuilds its delay line from it.)"""
    state = stepped.get_state()
    t, z = state.history_t, state.history_z
    assert t.size > 2
    assert "newest road sample is at" in _refused(stepped, history_t=t + 1.0)
    assert "do not increase" in _refused(stepped, history_t=t[::-1].copy())
    many = 2_000_000
    far = np.linspace(-1e3, float(t[-1]), many)
    message = _refused(stepped, history_t=far, history_z=np.zeros(many),
                       history_v=np.zeros(many))
    assert "the FMU keeps at most" in message
    few = np.linspace(-1e3, float(t[-1]), 1000)
    message = _refused(stepped, history_t=few, history_z=np.zeros(1000),
                       history_v=np.zeros(1000))
    assert "before the start" in message and "reaches back" in message
    assert "beyond the inputs' limits" in _refused(stepped, history_z=z + 20.0)


def test_modal_states_and_forces_beyond_a_tires_are_refused(stepped):
    """Issue 19: modal states of 1e300 gave outputs of 3e307 with status OK."""
    state = stepped.get_state()
    q = state.q.copy()
    q[0] = 1e300
    assert f"beyond the {MAX_STATE_DISPLACEMENT_M:g} m a state may hold" in _refused(
        stepped, q=q)
    assert "pull on the tread" in _refused(stepped, df=state.df - 1e6)
    assert "exceed what the zone springs give" in _refused(stepped, df=state.df + 1e30)
    assert "rim forces exceed" in _refused(stepped, ring_out=state.ring_out + [1e30, 0, 0])
    outputs = state.outputs.copy()
    outputs[0] = 3e307
    assert "rim_Fz = 3e+307, but the state gives" in _refused(stepped, outputs=outputs)
