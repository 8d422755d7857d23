"""The TireModal slave in plain Python (no FMU build): lifecycle, validation, refusals, state.

The slave is driven the way pythonfmu's C wrapper drives it: constructed with the wrapper's
keyword arguments, then its lifecycle methods, with value references; what it logs is read
from its log queue. Results are compared with the core's simulator built directly.
"""

import math
from xml.etree import ElementTree

import numpy as np
import pytest
from pythonfmu.enums import Fmi2Status

from tire_fmu.core import DEFAULT_LOAD_N, build_model, validate
from tire_fmu.core.contact_dynamics import (
    INPUT_NAMES,
    OUTPUT_NAMES,
    ContactSimulator,
    build_contact_model,
)
from tire_fmu.fmu.slave import TireModal

N = 40  # elements: enough for every check here, cheap to reduce


def new_slave(name="tire"):
    return TireModal(instance_name=name, resources=".", visible=False)


def vr(slave, name):
    return slave._index[name]


def messages(slave, status=None):
    found = [m.msg for m in slave.log_queue if status is None or m.status == status]
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
    tire, op = validate({}, {"n_elements": N, "load_n": load, "speed_m_s": speed})
    return ContactSimulator(build_contact_model(tire, op))


def set_inputs(slave, rim_z=0.0, rim_vz=0.0, road_z=0.0, road_vz=0.0):
    slave.set_real([vr(slave, n) for n in INPUT_NAMES], [rim_z, rim_vz, road_z, road_vz])


def outputs(slave):
    return slave.get_real([vr(slave, n) for n in OUTPUT_NAMES])


@pytest.fixture(scope="module")
def running():
    """One initialised slave at the defaults (N = 40) with its core twin."""
    return initialised(), core_simulator()


def test_construction_is_cheap_and_builds_nothing():
    slave = new_slave()
    assert slave._simulator is None
    assert slave.get_real([vr(slave, "rim_Fz")]) == [pytest.approx(DEFAULT_LOAD_N)]
    slave.set_real([vr(slave, "load")], [20_000.0])  # before initialisation: echoed
    assert slave.get_real([vr(slave, "rim_Fz"), vr(slave, "contact_Fz")]) == [20_000.0] * 2


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
        t = slave._running.time
        u = rng.normal(scale=[1e-3, 1e-2, 1e-3, 1e-2])
        set_inputs(slave, *u)
        assert slave.do_step(t, h) is True
        expected = core.step(h, *u)
        np.testing.assert_allclose(outputs(slave), expected, rtol=1e-12,
                                   atol=1e-12 * DEFAULT_LOAD_N)
    assert slave.get_boolean([vr(slave, "in_contact")]) == [True]
    ready = [m for m in slave.log_queue if "ready" in m.msg]
    assert ready and f"N = {N}" in ready[0].msg


def test_rejected_parameters_are_all_logged_and_every_step_is_discarded():
    slave = initialised(R=-1.0, n_elements=3, beta=math.nan, n_modes=-2, load=-5.0)
    errors = messages(slave, Fmi2Status.error)
    text = "\n".join(errors)
    for fragment in ("R = -1", "n_elements = 3", "beta = nan", "n_modes = -2", "load = -5"):
        assert fragment in text, fragment
    assert sum("parameter problem" in e for e in errors) == 5
    assert "load_n" not in text and "or None" not in text  # in the FMU's own words
    for _ in range(2):
        assert slave.do_step(0.0, 1e-3) is False
        (refusal,) = messages(slave, Fmi2Status.discard)
        assert "rejected" in refusal and "R = -1" in refusal


def test_a_load_the_model_cannot_carry_is_reported_with_the_other_problems():
    slave = initialised(load=1e7, f_max=-1.0)  # the load check needs the assembled model
    problems = [m for m in messages(slave, Fmi2Status.error) if "parameter problem" in m]
    assert len(problems) == 2
    assert "f_max = -1" in problems[0] and "or 0 for no frequency cut" in problems[0]
    assert "load = 1e+07 N" in problems[1] and "end of the contact zone" in problems[1]
    assert slave.do_step(0.0, 1e-3) is False


def test_critical_speed_is_refused_unless_allowed_and_its_approach_warned():
    slave = initialised(speed=500.0)
    assert any("critical (standing-wave) speed" in m for m in messages(slave, Fmi2Status.error))
    assert slave.do_step(0.0, 1e-3) is False
    critical = build_model(*validate({}, {"n_elements": N})).critical_speed_m_s
    near = initialised(speed=0.85 * critical)
    assert any("% of the critical speed" in m for m in messages(near, Fmi2Status.warning))
    assert near.do_step(0.0, 1e-4) is True


@pytest.mark.parametrize("case", ["early time", "late time", "zero h", "negative h", "nan h",
                                  "nan input", "inf input"])
def test_bad_steps_are_discarded_with_a_message_and_change_nothing(case):
    slave = initialised()
    set_inputs(slave, rim_z=1e-3)
    assert slave.do_step(0.0, 1e-3)
    before = outputs(slave), slave._simulator.get_state()
    t, h = 1e-3, 1e-3
    expected = {"early time": "last communication point", "late time": "last communication",
                "zero h": "step size h = 0.0 s", "negative h": "step size h = -0.001 s",
                "nan h": "step size h = nan s", "nan input": "rim_vz = nan m/s: must be in",
                "inf input": "road_z = inf m: must be in"}[case]
    if case == "early time":
        t = 0.0
    elif case == "late time":
        t = 2e-3
    elif case.endswith(" h"):
        h = {"zero h": 0.0, "negative h": -1e-3, "nan h": math.nan}[case]
    else:
        set_inputs(slave, rim_z=1e-3, rim_vz=math.nan if case == "nan input" else 0.0,
                   road_z=math.inf if case == "inf input" else 0.0)
    messages(slave)
    assert slave.do_step(t, h) is False
    (message,) = messages(slave, Fmi2Status.discard)
    assert expected in message and "state unchanged" in message
    after = slave._simulator.get_state()
    assert outputs(slave) == before[0]
    assert after.time == before[1].time and np.array_equal(after.q, before[1].q)
    set_inputs(slave, rim_z=1e-3)  # the host fixes its call and retries: accepted
    assert slave.do_step(1e-3, 1e-3) is True


def test_a_communication_point_within_rounding_is_accepted_and_becomes_the_clock():
    slave = initialised()
    assert slave.do_step(0.0, 0.1)
    assert slave.do_step(0.1 * (1 + 1e-12), 0.1)  # within 1e-9 relative: the host's clock
    assert slave._simulator.time == 0.1 * (1 + 1e-12) + 0.1


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


def test_parameters_are_fixed_after_initialisation(running):
    slave, _ = running
    load = vr(slave, "load")
    slave.set_real([load], [1.0])
    slave.set_integer([vr(slave, "n_elements")], [50])
    assert slave.get_real([load]) == [pytest.approx(DEFAULT_LOAD_N)]
    assert slave.get_integer([vr(slave, "n_elements")]) == [N]
    errors = messages(slave, Fmi2Status.error)
    assert len(errors) == 2 and all("fixed after initialisation" in e for e in errors)


def test_bad_references_and_types_are_logged_never_raised(running):
    slave, _ = running
    assert math.isnan(slave.get_real([9999])[0])
    slave.set_real([9999], [1.0])
    slave.set_real([vr(slave, "n_elements")], [3.0])  # an Integer set as a Real
    slave.set_real([vr(slave, "rim_Fz")], [0.0])  # an output
    assert slave.get_string([0]) == [""]
    slave.set_string([0], ["x"])
    assert len(messages(slave, Fmi2Status.error)) == 6
    assert slave.get_integer([vr(slave, "n_elements")]) == [N]


def test_terminate_stops_stepping():
    slave = initialised()
    slave.terminate()
    assert slave.do_step(0.0, 1e-3) is False
    assert "terminated" in messages(slave, Fmi2Status.discard)[0]


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
    assert data == TireModal._fmu_state_to_bytes(TireModal._fmu_state_from_bytes(data))
    slave._set_fmu_state(TireModal._fmu_state_from_bytes(data))
    assert _run(slave, future) == first
    # into a fresh instance that was never initialised: the state brings its model along
    fresh = new_slave("fresh")
    fresh._set_fmu_state(TireModal._fmu_state_from_bytes(data))
    assert _run(fresh, future) == first
    assert not messages(fresh, Fmi2Status.error)


def test_a_state_of_other_parameters_rebuilds_its_model():
    light = initialised(load=15_000.0)
    _run(light, [(1e-3, 0, 0, 0)] * 5)
    state = TireModal._fmu_state_to_bytes(light._get_fmu_state())
    expected = _run(light, [(0, 0, 0, 0)] * 3)
    heavy = initialised()
    heavy._set_fmu_state(TireModal._fmu_state_from_bytes(state))
    assert heavy.get_real([vr(heavy, "load")]) == [15_000.0]
    assert _run(heavy, [(0, 0, 0, 0)] * 3) == expected


@pytest.mark.parametrize("data", [b"", b"garbage", b'{"format": "other"}\n',
                                  b'{"format": "tire_fmu.fmu-state/1", "values": [1]}\n'])
def test_bad_state_bytes_are_refused_at_set_and_stepping_stops(data):
    slave = initialised()
    state = TireModal._fmu_state_from_bytes(data)  # never raises
    slave._set_fmu_state(state)
    (error,) = messages(slave, Fmi2Status.error)
    assert "fmi2SetFMUstate refused" in error
    assert slave.do_step(0.0, 1e-3) is False
    assert "could not be restored" in messages(slave, Fmi2Status.discard)[0]
    slave._set_fmu_state(initialised()._get_fmu_state())  # a valid state heals it
    assert slave.do_step(0.0, 1e-3) is True


def test_instances_are_independent():
    light, heavy = initialised(load=15_000.0), initialised(load=30_000.0)
    for slave in (light, heavy):
        set_inputs(slave, rim_z=-1e-3)
    assert light.do_step(0.0, 1e-3) and heavy.do_step(0.0, 1e-3)
    for slave, load in ((light, 15_000.0), (heavy, 30_000.0)):
        core = core_simulator(load=load)
        np.testing.assert_allclose(outputs(slave), core.step(1e-3, -1e-3, 0, 0, 0),
                                   rtol=1e-12)
