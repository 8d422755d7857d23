"""The TireModal slave in plain Python (no FMU build): lifecycle, validation, refusals, state.

The slave is driven the way pythonfmu's C wrapper drives it: constructed with the wrapper's
keyword arguments, then its lifecycle methods, with value references; what it logs is read
from its log queue (as printf formats, the way the host gets them, turned back into text).
Results are compared with the core's simulator built directly.
"""

import dataclasses
import math
from xml.etree import ElementTree

import numpy as np
import pytest
from pythonfmu.enums import Fmi2Status

from tire_fmu.core import DEFAULT_LOAD_N, build_model, validate
from tire_fmu.core.contact_dynamics import (
    INPUT_NAMES,
    MAX_DISPLACEMENT_M,
    MAX_VELOCITY_M_S,
    OUTPUT_NAMES,
    ContactSimulator,
    build_contact_model,
)
from tire_fmu.fmu.interface import MAX_DELAY_STEPS
from tire_fmu.fmu.slave import Phase, TireModal, _Snapshot, fmi_message

N = 40  # elements: enough for every check here, cheap to reduce


def new_slave(name="tire"):
    return TireModal(instance_name=name, resources=".", visible=False)


def vr(slave, name):
    return slave._index[name]


def printed(format_text):
    """What a host's printf makes of a message the slave logged."""
    return format_text.replace("%%", "%").replace("##", "#")


def messages(slave, status=None):
    found = [printed(m.msg) for m in slave.log_queue if status is None or m.status == status]
    slave.log_queue.clear()
    return found


def initialised(**parameters):
    """A slave through setup, initialisation mode and its exit, with these parameters."""
    slave = new_slave()
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    parameters.setdefault("n_elements", N)
    for name, value in parameters.items():
        setter = {int: slave.set_integer, bool: slave.set_boolean}.get(type(value),
                                                                        slave.set_real)
        setter([vr(slave, name)], [value])
    slave.exit_initialization_mode()
    return slave


def core_simulator(load=DEFAULT_LOAD_N, speed=0.0):
    """The core's simulator on the kernel the slave runs here: the numpy reference (in plain
    Python the slave is in no FMU, so it has no compiled kernel of its own to load)."""
    tire, op = validate({}, {"n_elements": N, "load_n": load, "speed_m_s": speed})
    return ContactSimulator(build_contact_model(tire, op), backend="numpy")


def set_inputs(slave, rim_z=0.0, rim_vz=0.0, road_z=0.0, road_vz=0.0):
    slave.set_real([vr(slave, n) for n in INPUT_NAMES], [rim_z, rim_vz, road_z, road_vz])


def outputs(slave):
    return slave.get_real([vr(slave, n) for n in OUTPUT_NAMES])


def observable(slave):
    """Everything a host can see of the slave, and the simulator's state."""
    state = slave._simulator.get_state() if slave._simulator is not None else None
    arrays = None if state is None else list(state.fields().values())
    return list(slave._values), slave._phase, slave._start_time, arrays


def _same(a, b):
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a)
                      and math.isnan(b))


def assert_unchanged(before, after):
    values, phase, start, arrays = before
    assert len(after[0]) == len(values) and all(map(_same, values, after[0]))
    assert after[1:3] == (phase, start)
    if arrays is None:
        assert after[3] is None
    else:
        assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(arrays, after[3]))


@pytest.fixture(scope="module")
def running():
    """One initialised slave at the defaults (N = 40) with its core twin."""
    return initialised(), core_simulator()


# -- construction and variables ------------------------------------------------------------

def test_construction_is_cheap_and_builds_nothing():
    slave = new_slave()
    assert slave._simulator is None
    assert slave.get_real([vr(slave, "rim_Fz")]) == [pytest.approx(DEFAULT_LOAD_N)]
    slave.set_real([vr(slave, "load")], [20_000.0])  # before initialisation: echoed
    assert slave.get_real([vr(slave, "rim_Fz"), vr(slave, "contact_Fz")]) == [20_000.0] * 2
    slave.set_real([vr(slave, "load")], [math.nan])  # accepted, refused at initialisation,
    assert slave.get_real([vr(slave, "rim_Fz")]) == [20_000.0]  # and never echoed
    assert not slave.log_queue  # nothing is logged before a call that pythonfmu drains


def test_every_variable_has_unit_description_and_legal_attributes():
    from tire_fmu.fmu.builder import complete_model_description
    from tire_fmu.fmu.interface import CAPABILITIES, fmu_variables

    # the slave's description as the builder completes it (pythonfmu writes no units)
    units = {v.name: v.unit for v in fmu_variables() if v.unit}
    xml = ElementTree.tostring(new_slave().to_xml())
    root = ElementTree.fromstring(complete_model_description(xml, CAPABILITIES, units))
    variables = {v.get("name"): v for v in root.iter("ScalarVariable")}
    expected = {"load", "speed", "inflation_pressure", "n_elements", "f_max", "n_modes",
                "static_correction", "R", "b", "rhoA", "m_s", "k_r1", "k_r2", "EI", "k_cw",
                "alpha", "beta", "sidewall_shear", "sidewall_pressure_exponent",
                "reference_pressure", "allow_supercritical", "contact_zone_length",
                "linear_contact", *INPUT_NAMES,
                *OUTPUT_NAMES, "in_contact"}
    assert set(variables) == expected
    units = {"load": "N", "speed": "m/s", "f_max": "Hz", "inflation_pressure": "Pa",
             "R": "m", "EI": "N*m^2", "k_r1": "N/m^2", "rim_z": "m", "rim_vz": "m/s",
             "rim_Fz": "N", "deflection": "m"}
    for name, unit in units.items():
        assert variables[name].find("Real").get("unit") == unit, name
    for name, v in variables.items():
        assert v.get("description"), name
        if v.get("causality") == "parameter":
            assert (v.get("variability"), v.get("initial")) == ("fixed", "exact"), name
            assert list(v)[0].get("start") is not None, name
        if v.get("causality") == "output":
            assert v.get("initial") == "calculated" and list(v)[0].get("start") is None
    assert variables["in_contact"].get("variability") == "discrete"
    assert float(variables["load"].find("Real").get("start")) == pytest.approx(DEFAULT_LOAD_N)
    assert variables["n_elements"].find("Integer").get("start") == "100"
    ElementTree.tostring(root)  # serialisable as it stands


def test_steps_equal_the_core_simulator(running):
    slave, core = running
    rng = np.random.default_rng(3)
    h = 1e-4
    for _ in range(300):
        t = slave._simulator.time
        u = rng.normal(scale=[1e-3, 1e-2, 1e-3, 1e-2])
        set_inputs(slave, *u)
        assert slave.do_step(t, h) is True
        expected = core.step(h, *u)
        np.testing.assert_allclose(outputs(slave), expected, rtol=1e-12,
                                   atol=1e-12 * DEFAULT_LOAD_N)
    assert slave.get_boolean([vr(slave, "in_contact")]) == [True]
    ready = [m for m in messages(slave) if "ready" in m]
    assert ready and f"N = {N}" in ready[0]


# -- messages --------------------------------------------------------------------------------

def test_messages_are_formats_that_print_the_text():
    assert fmi_message("86 % of #r3# at 100%s") == "86 %% of ##r3## at 100%%s"
    critical = build_model(*validate({}, {"n_elements": N})).critical_speed_m_s
    near = initialised(speed=0.85 * critical)
    [warning] = [m.msg for m in near.log_queue if m.status == Fmi2Status.warning]
    assert "85 %% of the critical speed" in warning  # printf shows "85 % of"
    assert "%" not in warning.replace("%%", "")


# -- parameters ------------------------------------------------------------------------------

def test_rejected_parameters_are_all_logged_and_every_step_is_refused():
    slave = initialised(R=-1.0, n_elements=3, beta=math.nan, n_modes=-2, load=-5.0)
    errors = messages(slave, Fmi2Status.error)
    text = "\n".join(errors)
    for fragment in ("R = -1 m", "n_elements = 3", "beta = nan", "n_modes = -2", "load = -5 N"):
        assert fragment in text, fragment
    assert sum("parameter problem" in e for e in errors) == 5
    assert "load_n" not in text and "or None" not in text  # in the FMU's own words
    assert "fmi2ExitInitializationMode refused" in errors[-1]
    assert slave._phase == Phase.ERROR
    for _ in range(2):
        assert slave.do_step(0.0, 1e-3) is False
        (refusal,) = messages(slave, Fmi2Status.error)
        assert "fmi2DoStep refused" in refusal and "R = -1" in refusal


def test_a_load_the_model_cannot_carry_is_reported_with_the_other_problems():
    slave = initialised(load=1e7, f_max=-1.0)  # the load check needs the assembled model
    problems = [m for m in messages(slave, Fmi2Status.error) if "parameter problem" in m]
    assert len(problems) == 2
    assert "f_max = -1 Hz" in problems[0] and "or 0 for no limit" in problems[0]
    assert "load = 1e+07 N" in problems[1] and "end of the contact zone" in problems[1]
    assert slave.do_step(0.0, 1e-3) is False


def test_masses_the_arithmetic_cannot_resolve_are_refused_not_run_to_nan():
    # each value inside its field's range, but the light sidewall on stiff springs, damped
    # with beta = 0.1 s, decays 1e12 times faster than the slowest mode: that mode is lost
    # in rounding, which gave nan outputs with status OK before
    slave = initialised(m_s=1e-3, k_r2=1e11, beta=0.1)
    [problem] = [m for m in messages(slave, Fmi2Status.error) if "parameter problem" in m]
    assert "m_s = 0.001 kg/m: must be larger" in problem and "eigenvalues span" in problem
    assert slave.do_step(0.0, 1e-3) is False


def test_critical_speed_is_refused_unless_allowed_and_its_approach_warned():
    from tire_fmu.fmu.interface import fmu_variables

    slave = initialised(speed=500.0)
    [refusal] = [m for m in messages(slave, Fmi2Status.error) if "parameter problem" in m]
    assert "critical (standing-wave) speed" in refusal
    # the way out it names is a parameter of this FMU (the CLI names its flag instead)
    assert "allow_supercritical runs anyway" in refusal
    assert "allow_supercritical" in {v.name for v in fmu_variables() if v.causality ==
                                     "parameter"}
    assert slave.do_step(0.0, 1e-3) is False
    critical = build_model(*validate({}, {"n_elements": N})).critical_speed_m_s
    near = initialised(speed=0.85 * critical)
    assert any("% of the critical speed" in m for m in messages(near, Fmi2Status.warning))
    assert near.do_step(0.0, 1e-4) is True


def test_parameters_are_fixed_after_initialisation_and_a_set_is_all_or_nothing(running):
    slave, _ = running
    load, n = vr(slave, "load"), vr(slave, "n_elements")
    messages(slave)
    rim_z = slave.get_real([vr(slave, "rim_z")])
    slave.set_real([load], [1.0])
    slave.set_integer([n], [50])
    slave.set_real([vr(slave, "rim_z"), load], [1e-3, 1.0])  # an input with a parameter
    assert slave.get_real([load]) == [pytest.approx(DEFAULT_LOAD_N)]
    assert slave.get_integer([n]) == [N]
    assert slave.get_real([vr(slave, "rim_z")]) == rim_z  # the whole call was refused
    errors = messages(slave, Fmi2Status.error)
    assert len(errors) == 3 and all("fixed after initialisation" in e for e in errors)
    assert "load = 1 N" in errors[0] and "n_elements = 50" in errors[1]


def test_bad_references_and_types_are_logged_never_raised(running):
    slave, _ = running
    messages(slave)
    assert slave.get_real([9999]) == [0.0]
    assert slave.get_integer([vr(slave, "rim_z")]) == [0]  # a Real read as an Integer
    slave.set_real([9999], [1.0])
    slave.set_real([vr(slave, "n_elements")], [3.0])  # an Integer set as a Real
    slave.set_real([vr(slave, "rim_Fz")], [0.0])  # an output
    assert slave.get_string([0]) == [""]
    slave.set_string([0], ["x"])
    errors = messages(slave, Fmi2Status.error)
    assert len(errors) == 7
    assert "value reference 9999" in errors[0] and "does not exist" in errors[0]
    assert "rim_Fz = 0 N: it is an output" in errors[4]
    assert slave.get_integer([vr(slave, "n_elements")]) == [N]


# -- steps -----------------------------------------------------------------------------------

STEP_CASES = {  # case: (t, h, inputs, what the message says)
    "early time": (0.0, 1e-3, None, "t = 0.0 s: must be the last communication point"),
    "late time": (2e-3, 1e-3, None, "t = 0.002 s: must be the last communication point"),
    "nan time": (math.nan, 1e-3, None, "t = nan s: must be the last communication point"),
    "inf time": (math.inf, 1e-3, None, "t = inf s: must be the last"),
    "zero h": (1e-3, 0.0, None, "step size h = 0.0 s: must be in (0, 1] s"),
    "huge h": (1e-3, 1e300, None, "step size h = 1e+300 s: must be in (0, 1] s"),
    "negative h": (1e-3, -1e-3, None, "step size h = -0.001 s"),
    "nan h": (1e-3, math.nan, None, "step size h = nan s"),
    "nan input": (1e-3, 1e-3, (1e-3, math.nan, 0, 0), "rim_vz = nan m/s: must be in"),
    "inf input": (1e-3, 1e-3, (1e-3, 0, math.inf, 0), "road_z = inf m: must be in"),
    "huge input": (1e-3, 1e-3, (1e-3, 0, 0, 1e300), "road_vz = 1e+300 m/s: must be in"),
}


@pytest.mark.parametrize("case", STEP_CASES)
def test_bad_steps_are_refused_with_a_message_and_change_nothing(case):
    slave = initialised()
    set_inputs(slave, rim_z=1e-3)
    assert slave.do_step(0.0, 1e-3)
    t, h, inputs, expected = STEP_CASES[case]
    if inputs:
        set_inputs(slave, *inputs)
    messages(slave)
    before = observable(slave)
    assert slave.do_step(t, h) is False
    (message,) = messages(slave, Fmi2Status.error)
    assert message.startswith("fmi2DoStep(t = ") and expected in message
    assert message.endswith("nothing changed")
    assert_unchanged(before, observable(slave))
    set_inputs(slave, rim_z=1e-3)  # the host fixes its call and retries: accepted
    assert slave.do_step(1e-3, 1e-3) is True


def test_a_step_too_short_for_the_road_history_at_a_crawl_is_refused():
    # at 1 mm/s the road takes minutes to cross the patch: 1e-4 s steps would need millions
    # of samples of road history (a denormal speed crashed the step before: inf delays)
    slave = initialised(speed=1e-3)
    reach = slave._simulator.contact.windows.horizon_s
    assert slave.do_step(0.0, 1e-4) is False
    (error,) = messages(slave, Fmi2Status.error)
    assert "step size h = 0.0001 s: must be at least" in error and "steps of its history" in error
    h = 1.01 * reach / MAX_DELAY_STEPS
    assert slave.do_step(0.0, h) is True and slave.do_step(h, h) is True


def test_inputs_up_to_the_limit_keep_every_output_finite():
    slave = initialised()
    set_inputs(slave, MAX_DISPLACEMENT_M, -MAX_VELOCITY_M_S, -MAX_DISPLACEMENT_M,
               MAX_VELOCITY_M_S)
    for k in range(200):
        assert slave.do_step(k * 1e-3, 1e-3)
        assert all(math.isfinite(y) for y in outputs(slave))


def test_outputs_read_after_non_finite_inputs_are_the_last_steps_with_an_error():
    slave = initialised()
    set_inputs(slave, rim_z=1e-3)
    assert slave.do_step(0.0, 1e-3)
    last = outputs(slave)
    messages(slave)
    set_inputs(slave, rim_z=math.nan)
    assert outputs(slave) == last
    (error,) = messages(slave, Fmi2Status.error)
    assert "rim_z = nan" in error and "those of the last step" in error


def test_a_communication_point_within_rounding_is_accepted_and_the_fmus_clock_goes_on():
    """The host's t within rounding of the FMU's is that point; the FMU keeps its own clock
    (it used to take the host's, and with it the host's rounding into the road history)."""
    slave = initialised()
    assert slave.do_step(0.0, 0.1)
    assert slave.do_step(0.1 * (1 + 1e-12), 0.1)  # within 1e-9 relative
    assert slave._simulator.time == 0.2


def test_lift_off_is_physics_not_a_warning():
    slave = initialised()
    lift, ramp = 0.05, 0.5  # rim up 5 cm, smoothly: the tire leaves the road

    def rim(t):  # up, hold, down, hold, up again: two episodes without contact
        phase = min(t % 2.0, 1.5)
        s = np.clip(min(phase, 1.5 - phase) / ramp, 0.0, 1.0)
        slope = (np.pi / 2 * np.sin(np.pi * s) / ramp if 0 < s < 1 else 0.0)
        return lift * (1 - np.cos(np.pi * s)) / 2, slope * lift * (1 if phase < 0.75 else -1)

    t, h, warnings, contact, forces = 0.0, 1e-3, [], [], []
    while t < 3.5:
        set_inputs(slave, *rim(t))
        assert slave.do_step(t, h)
        t += h
        warnings += messages(slave, Fmi2Status.warning)
        forces.append(slave.get_real([vr(slave, "contact_Fz")])[0])
        contact.append(slave.get_boolean([vr(slave, "in_contact")])[0])
        assert contact[-1] == (forces[-1] > 0)
    episodes = np.count_nonzero(np.diff(np.array(contact, int)) == -1)
    assert episodes == 2 and not warnings
    assert min(forces) == 0.0  # the road never pulls


def test_a_footprint_reaching_the_zone_end_is_warned_once():
    slave = initialised(contact_zone_length=0.2, n_elements=100)  # 5 zone nodes
    t, h, warnings = 0.0, 1e-3, []
    for _ in range(200):  # push the rim down 6 cm: the footprint grows past the zone
        depth = -0.06 * min(t / 0.1, 1.0)
        set_inputs(slave, depth, -0.6 if t < 0.1 else 0.0)
        assert slave.do_step(t, h)
        t += h
        warnings += messages(slave, Fmi2Status.warning)
    assert len(warnings) == 1 and "end of the contact zone" in warnings[0]


# -- the FMI state machine -------------------------------------------------------------------

def test_a_second_exit_from_initialisation_is_refused_running_or_terminated():
    slave = initialised()
    set_inputs(slave, rim_z=1e-3)
    for k in range(3):
        assert slave.do_step(k * 1e-3, 1e-3)
    simulator = slave._simulator
    messages(slave)
    before = observable(slave)
    slave.exit_initialization_mode()  # used to rebuild, reset the time and keep running
    (error,) = messages(slave, Fmi2Status.error)
    assert "fmi2ExitInitializationMode refused: the FMU is running" in error
    assert slave._simulator is simulator
    assert_unchanged(before, observable(slave))
    slave.terminate()
    slave.exit_initialization_mode()  # used to un-terminate
    assert "the FMU is terminated" in messages(slave, Fmi2Status.error)[0]
    assert slave._phase == Phase.TERMINATED
    assert slave.do_step(3e-3, 1e-3) is False
    assert "fmi2DoStep refused: the FMU is terminated" in messages(slave, Fmi2Status.error)[0]


@pytest.mark.parametrize("call, phase_text", [
    ("do_step", "instantiated"), ("exit_initialization_mode", "instantiated"),
    ("terminate", "instantiated")])
def test_calls_out_of_order_are_refused_before_initialisation(call, phase_text):
    slave = new_slave()
    result = getattr(slave, call)(*((0.0, 1e-3) if call == "do_step" else ()))
    assert result in (None, False)
    (error,) = messages(slave, Fmi2Status.error)
    assert f"the FMU is {phase_text}" in error and slave._phase == Phase.INSTANTIATED


def test_setup_and_initialisation_mode_only_once_and_in_order():
    slave = new_slave()
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()
    slave.setup_experiment(1.0)
    slave.enter_initialization_mode()
    errors = messages(slave, Fmi2Status.error)
    assert len(errors) == 2 and all("in initialisation mode" in e for e in errors)
    assert slave._start_time == 0.0


@pytest.mark.parametrize("args, fragment", [
    ((math.nan,), "startTime = nan s: must be finite"),
    ((math.inf,), "startTime = inf s"),
    ((0.0, -1.0), "stopTime = -1.0 s: must be finite and >= startTime"),
    ((0.0, math.nan), "stopTime = nan s"),
    ((0.0, None, -1e-6), "tolerance = -1e-06")])
def test_a_non_finite_start_time_or_bad_stop_time_is_refused(args, fragment):
    slave = new_slave()
    slave.setup_experiment(*args)
    (error,) = messages(slave, Fmi2Status.error)
    assert error.startswith("fmi2SetupExperiment refused") and fragment in error
    assert slave._start_time == 0.0 and slave._phase == Phase.INSTANTIATED


# -- FMU state -------------------------------------------------------------------------------

def _run(slave, inputs, h=1e-3):
    out = []
    for u in inputs:
        set_inputs(slave, *u)
        assert slave.do_step(slave._simulator.time, h)
        out.append(outputs(slave))
    return out


def test_state_rollback_and_serialisation_reproduce_steps_exactly():
    slave = initialised()
    rng = np.random.default_rng(5)
    _run(slave, rng.normal(scale=1e-3, size=(20, 4)))
    future = rng.normal(scale=1e-3, size=(10, 4))
    state = slave._get_fmu_state()
    first = _run(slave, future)
    slave._set_fmu_state(state)
    assert _run(slave, future) == first
    data = TireModal._fmu_state_to_bytes(state)
    again = TireModal._fmu_state_from_bytes(data)
    assert isinstance(again, _Snapshot) and again.values == state.values
    slave._set_fmu_state(again)
    assert _run(slave, future) == first
    # into a fresh instance that was never initialised: the state brings its model along
    fresh = new_slave("fresh")
    fresh._set_fmu_state(TireModal._fmu_state_from_bytes(data))
    assert _run(fresh, future) == first
    assert not messages(fresh, Fmi2Status.error)


def test_inputs_set_after_a_step_feed_through_after_a_rollback_too():
    slave = initialised()
    _run(slave, [(1e-3, 0, 0, 0)] * 3)
    set_inputs(slave, 1e-3, 0.0, 0.0, 0.5)  # the road velocity acts at once (the damper)
    state = slave._get_fmu_state()
    expected = outputs(slave)
    slave._set_fmu_state(state)
    assert outputs(slave) == expected


def test_a_state_of_other_parameters_rebuilds_its_model():
    light = initialised(load=15_000.0)
    _run(light, [(1e-3, 0, 0, 0)] * 5)
    state = TireModal._fmu_state_to_bytes(light._get_fmu_state())
    expected = _run(light, [(0, 0, 0, 0)] * 3)
    heavy = initialised()
    heavy._set_fmu_state(TireModal._fmu_state_from_bytes(state))
    assert heavy.get_real([vr(heavy, "load")]) == [15_000.0]
    assert _run(heavy, [(0, 0, 0, 0)] * 3) == expected


def _valid_state():
    slave = initialised()
    _run(slave, [(1e-3, 0, 0, 0)] * 3)
    return slave._get_fmu_state()


def _with(state, **changes):
    return TireModal._fmu_state_to_bytes(dataclasses.replace(state, **changes))


def _bad_states():
    """Serialized states that must be refused, each with what the refusal says."""
    state = _valid_state()
    good = TireModal._fmu_state_to_bytes(state)
    values = list(state.values)
    flipped = bytearray(good)
    flipped[-20] ^= 1
    nan_q = state.simulator.q.copy()
    nan_q[0] = complex(math.nan, 0)
    named = {
        "empty": (b"", "not a TireModal state"),
        "garbage": (b"garbage", "not a TireModal state"),
        "printf formats": (b"%s%s%s%s%s%s%s%s%s%s", "not a TireModal state"),
        "version 1": (b'{"format": "tire_fmu.fmu-state/1", "values": [1]}\n', "this version"),
        "trailing bytes": (good + b"\x00extra", "checksum does not match"),
        "cut short": (good[:-100], "checksum does not match"),
        "one bit flipped": (bytes(flipped), "checksum does not match"),
        "no simulator part": (_with(state, simulator=None),
                              "'running' needs a simulator state"),
        "a word for a number": (_with(state, values=tuple(["x"] + values[1:])),
                                "rim_z = 'x': must be a number"),
        "too few values": (_with(state, values=tuple(values[:5])), "5 values"),
        "an integer C cannot hold": (
            _with(state, values=tuple(10**30 if i == vr(new_slave(), "n_elements") else x
                                      for i, x in enumerate(values))),
            "n_elements = 1000000000000000000000000000000: must be an integer of 32 bits"),
        "nan output": (_with(state, values=tuple(values[:4] + [math.nan] + values[5:])),
                       "rim_Fz = nan: an output must be finite"),
        "nan modal state": (_with(state, simulator=state.simulator.replaced(q=nan_q)),
                            "of its model part is not finite"),
        "nan time": (_with(state, simulator=state.simulator.replaced(elapsed_s=math.nan)),
                     "of its model part is not finite"),
        "unknown phase": (_with(state, phase="flying"), "phase = 'flying'"),
        # issue 19: a state is checked for what it means, not only for its checksum
        "error phase without its reason": (
            _with(state, phase=Phase.ERROR, why_not_running=""),
            "its phase is 'error' without the reason (why_not_running is empty)"),
        "a start time not its simulator's": (_with(state, start_time=5.0),
                                             "its start time is 5.0 s, but its simulator "
                                             "started at 0.0 s"),
        "outputs not its simulator's": (
            _with(state, values=tuple(values[:4] + [3e307] + values[5:])),
            "the outputs it shows, [3e+307,"),
    }
    return named


BAD_STATES = list(_bad_states())


@pytest.mark.parametrize("case", BAD_STATES)
def test_bad_state_bytes_are_refused_and_leave_the_instance_unchanged(case):
    data, fragment = _bad_states()[case]
    slave = initialised()
    _run(slave, [(2e-3, 0, 0, 0)] * 2)
    messages(slave)
    before = observable(slave)
    state = TireModal._fmu_state_from_bytes(data)  # never raises
    slave._set_fmu_state(state)
    (error,) = messages(slave, Fmi2Status.error)
    assert error.startswith("fmi2SetFMUstate refused: ") and fragment in error, error
    assert_unchanged(before, observable(slave))
    assert slave.do_step(2e-3, 1e-3) is True  # it runs on where it was


def test_a_state_in_the_error_phase_carries_its_reason_into_every_refusal():
    """Issue 19: a state in phase "error" was refused with an empty reason. A true one
    (parameters refused) brings its reason along; an empty one is refused when set, and the
    FMU never refuses a call without saying why."""
    broken = initialised(m_s=1e-20)
    assert broken._phase == Phase.ERROR
    data = TireModal._fmu_state_to_bytes(broken._get_fmu_state())
    fresh = new_slave("fresh")
    fresh._set_fmu_state(TireModal._fmu_state_from_bytes(data))
    assert not messages(fresh, Fmi2Status.error)
    assert fresh.do_step(0.0, 1e-3) is False
    (refusal,) = messages(fresh, Fmi2Status.error)
    assert refusal.startswith("fmi2DoStep refused: the parameters were refused") and \
        "m_s = 1e-20 kg/m" in refusal
    fresh._why_not_running = ""  # however it came about
    fresh.do_step(0.0, 1e-3)
    (refusal,) = messages(fresh, Fmi2Status.error)
    assert refusal == ("fmi2DoStep refused: the FMU is in the error state; reset it or set an "
                       "FMU state; nothing changed")


def test_a_state_whose_parameters_do_not_build_is_refused_unchanged():
    state = _valid_state()
    values = list(state.values)
    values[vr(new_slave(), "m_s")] = 1e-20
    slave = initialised(load=20_000.0)
    messages(slave)
    before = observable(slave)
    slave._set_fmu_state(TireModal._fmu_state_from_bytes(_with(state, values=tuple(values))))
    (error,) = messages(slave, Fmi2Status.error)
    assert "its parameters do not build a model: m_s = 1e-20 kg/m" in error
    assert_unchanged(before, observable(slave))


def test_instances_are_independent():
    light, heavy = initialised(load=15_000.0), initialised(load=30_000.0)
    for slave in (light, heavy):
        set_inputs(slave, rim_z=-1e-3)
    assert light.do_step(0.0, 1e-3) and heavy.do_step(0.0, 1e-3)
    for slave, load in ((light, 15_000.0), (heavy, 30_000.0)):
        core = core_simulator(load=load)
        np.testing.assert_allclose(outputs(slave), core.step(1e-3, -1e-3, 0, 0, 0),
                                   rtol=1e-12)
