"""The TireModal slave in plain Python (no FMU build): what only the slave has.

The slave is driven the way pythonfmu's C wrapper drives it: constructed with the wrapper's
keyword arguments, then its lifecycle methods, with value references; what it logs is read
from its log queue (as printf formats, the way the host gets them, turned back into text).
Results are compared with the core's simulator built directly. What both FMUs must do alike
(the state machine, refusals, states, limits) is tests/test_fmi_behaviour.py, through fmpy.
"""

import math
import struct
from xml.etree import ElementTree

import numpy as np
import pytest
from pythonfmu.enums import Fmi2Status

from tire_fmu.core import DEFAULT_LOAD_N, build_model, kernel_numpy, validate
from tire_fmu.core.contact_dynamics import (
    INPUT_NAMES,
    OUTPUT_NAMES,
    ContactSimulator,
    build_contact_model,
)
from tire_fmu.fmu.slave import TireModal, fmi_message
from tire_fmu.fmu.spec import MESSAGES, PHASES, Phase, state_pack, state_unpack

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


@pytest.fixture(scope="module")
def running():
    """One initialised slave at the defaults (N = 40) with its core twin."""
    return initialised(), core_simulator()


# -- construction and variables ------------------------------------------------------------

def test_construction_is_cheap_and_builds_nothing():
    slave = new_slave()
    assert slave._simulator is None
    assert not slave.log_queue  # nothing is logged before a call that pythonfmu drains
    slave.set_real([vr(slave, "load")], [20_000.0])  # before initialisation: echoed
    slave.setup_experiment(0.0)
    slave.enter_initialization_mode()  # where FMI first allows a getter
    assert slave.get_real([vr(slave, "rim_Fz"), vr(slave, "contact_Fz")]) == [20_000.0] * 2
    slave.set_real([vr(slave, "load")], [math.nan])  # accepted, refused at initialisation,
    assert slave.get_real([vr(slave, "rim_Fz")]) == [20_000.0]  # and never echoed
    assert slave._simulator is None and not messages(slave)


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
                "alpha", "beta", "sidewall_shear", "sidewall_max_order",
                "sidewall_pressure_exponent", "reference_pressure", "allow_supercritical",
                "contact_zone_length", "contact_point_spacing", "linear_contact", *INPUT_NAMES,
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
    # pythonfmu reads the start values through the getters, which refuse while instantiated
    # (FMI): the builder's instance reads them all the same, and logs nothing
    assert variables["R"].find("Real").get("start") == "0.65"
    assert variables["static_correction"].find("Boolean").get("start") == "true"


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
    reason = errors[-1].split("fmi2ExitInitializationMode refused: ")[1]
    for _ in range(2):
        assert slave.do_step(0.0, 1e-3) is False
        (refusal,) = messages(slave, Fmi2Status.error)
        assert refusal == MESSAGES["REFUSED"] % ("fmi2DoStep", reason) and "R = -1" in refusal


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


# -- steps -----------------------------------------------------------------------------------

def test_lift_off_is_physics_not_a_warning():
    slave = initialised()
    lift, ramp = 0.05, 0.5  # rim up 5 cm, smoothly: the tire leaves the road

    def rim(t):  # up, hold, down, hold, up again: two episodes without contact
        phase = min(t % 2.0, 1.5)
        s = np.clip(min(phase, 1.5 - phase) / ramp, 0.0, 1.0)
        slope = (np.pi / 2 * np.sin(np.pi * s) / ramp if 0 < s < 1 else 0.0)
        return lift * (1 - np.cos(np.pi * s)) / 2, slope * lift * (1 if phase < 0.75 else -1)

    t, h, warnings, contact, forces, events = 0.0, 1e-3, [], [], [], []
    while t < 3.5:
        set_inputs(slave, *rim(t))
        assert slave.do_step(t, h)
        t += h
        events += [m for m in slave.log_queue if m.category == "logEvents"]
        warnings += messages(slave, Fmi2Status.warning)
        forces.append(slave.get_real([vr(slave, "contact_Fz")])[0])
        contact.append(slave.get_boolean([vr(slave, "in_contact")])[0])
        assert contact[-1] == (forces[-1] > 0)
    episodes = np.count_nonzero(np.diff(np.array(contact, int)) == -1)
    assert episodes == 2 and not warnings
    assert min(forces) == 0.0  # the road never pulls
    # each lift-off and landing an information line (as the native FMU logs them)
    assert [m.status for m in events] == [Fmi2Status.ok] * 4
    assert [printed(m.msg).split(": ")[1] for m in events] == [
        "the tread left the road (in_contact = false)",
        "the tread is back on the road (in_contact = true)"] * 2


# -- FMU state: the slave's own parts -----------------------------------------------------------

def test_the_numpy_kernel_checks_a_state_as_the_compiled_one():
    """In plain Python (and in an FMU built without a C compiler) the slave steps with the
    numpy reference kernel: a state's kernel part is then checked by
    kernel_numpy.state_problems, in the C kernel's words (tests/test_fmi_behaviour.py checks
    the C kernel's through both FMUs)."""
    slave = initialised(speed=10.0)
    assert slave._simulator.backend == "numpy"
    for k in range(20):
        set_inputs(slave, 1e-3)
        assert slave.do_step(k * 1e-3, 1e-3)
    data = slave._get_fmu_state()
    f = state_unpack(data, len(slave._table))
    kernel = kernel_numpy.state_fields(f["model"][8:])
    q = kernel["q"].copy()
    q[0] = 1e300
    forged = state_pack(f["phase"], f["guid"], f["time"], f["start_time"], f["stale"],
                        f["values"], f["model"][:8] + kernel_numpy.state_data({**kernel, "q": q}))
    messages(slave)
    slave._set_fmu_state(forged)
    (refusal,) = messages(slave, Fmi2Status.error)
    assert refusal.startswith("fmi2SetFMUstate refused: the tread's excursion at the zone "
                              "nodes from a mode reach ")
    slave._set_fmu_state(data)  # the state as taken: set, nothing said
    assert not messages(slave) and slave._phase == Phase.RUNNING


def test_a_state_is_its_bytes_and_deserializing_copies_them():
    """pythonfmu calls the serialization on the class (no instance, no GUID): the state
    object is its bytes, checked in full when set. Outside an FMU the GUID is empty."""
    slave = initialised()
    state = slave._get_fmu_state()
    assert isinstance(state, bytes) and TireModal._fmu_state_to_bytes(state) == state
    assert TireModal._fmu_state_from_bytes(bytearray(state)) == state
    assert state_unpack(state, len(slave._table))["guid"] == ""
    assert struct.unpack_from("<I", state, 12)[0] == Phase.NAMES.index("running")
    assert list(PHASES)[Phase.RUNNING] == "running"


def test_instances_are_independent():
    light, heavy = initialised(load=15_000.0), initialised(load=30_000.0)
    for slave in (light, heavy):
        set_inputs(slave, rim_z=-1e-3)
    assert light.do_step(0.0, 1e-3) and heavy.do_step(0.0, 1e-3)
    for slave, load in ((light, 15_000.0), (heavy, 30_000.0)):
        core = core_simulator(load=load)
        np.testing.assert_allclose(outputs(slave), core.step(1e-3, -1e-3, 0, 0, 0),
                                   rtol=1e-12)
