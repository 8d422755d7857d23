"""One FMI-behaviour suite, run against both FMUs through fmpy: the Python FMU (pythonfmu) and
the native C FMU. What a host sees of the FMI layer is written once, in tire_fmu/fmu/spec.py
(the state machine, every message, the FMU-state format), and both FMUs must give exactly it:
every call in every phase, the refusals of bad values, references, steps and states, the
state round trip, and every limit of the spec. Expected messages are rendered from the spec
and the core here, never taken from either FMU; the two FMUs' texts differ only by their
model identifier and GUID (``same_text``)."""

from __future__ import annotations

import math
import re
import struct
import subprocess
import sys
import textwrap
from ctypes import byref, c_char_p, c_size_t

import numpy as np
import pytest
from fmpy.fmi2 import (
    fmi2Boolean,
    fmi2FMUstate,
    fmi2Integer,
    fmi2Real,
    fmi2String,
    fmi2ValueReference,
)
from native_support import Instance, Opened, declared_dependencies, relative_errors, road_drop

from tire_fmu.core import clock, kernel_numpy
from tire_fmu.core.parameters import ParameterError, TireParameters
from tire_fmu.fmu.interface import MAX_HISTORY_SAMPLES, fmu_variables
from tire_fmu.fmu.spec import (
    CALLS,
    CONSTANTS,
    MESSAGES,
    PHASES,
    PYTHONFMU_ANSWERS,
    STATE_MAGIC,
    STATE_MODEL_FLAGS,
    STATE_VERSION,
    Phase,
    fmu_message,
    phase_refusal,
    state_checksum,
    state_pack,
    state_reseal,
    state_unpack,
)

pytestmark = pytest.mark.fmu

OK, ERROR = 0, 3
N = 40  # elements: every message is the same on any mesh, and this one builds fast
H = 1e-4
TIMEOUT_S = 180
M = MESSAGES
LAST_SUCCESSFUL_TIME, TERMINATED = 2, 3  # fmi2StatusKind
N_VALUES = len(fmu_variables())


@pytest.fixture(scope="module", params=["python", "native"])
def fmu(request, python_fmu_path, native_fmu_path):
    return Opened.of(python_fmu_path if request.param == "python" else native_fmu_path)


@pytest.fixture(scope="module")
def both(python_fmu_path, native_fmu_path):
    return Opened.of(python_fmu_path), Opened.of(native_fmu_path)


def identifier(fmu: Opened) -> str:
    return fmu.model_description.coSimulation.modelIdentifier


def same_text(fmu: Opened, text: str) -> str:
    """A message with this FMU's own names (model identifier, GUID) as placeholders."""
    return text.replace(fmu.model_description.guid, "<guid>").replace(identifier(fmu), "<id>")


def errors(instance: Instance) -> list[str]:
    """The error messages logged so far, with the FMU's names as placeholders; cleared."""
    found = [same_text(instance.fmu, m) for s, _, m in instance.log if s >= ERROR]
    instance.log.clear()
    return found


def refusal(call: str, why: str) -> str:
    return M["REFUSED"] % (call, why)


def step_refusal(t: float, h: float, why: str) -> str:
    return refusal(M["STEP_CALL"] % (repr(t), repr(h)), why)


def core_problem(make) -> str:
    """The core's first problem for what ``make`` builds, in the FMU's words."""
    with pytest.raises(ParameterError) as caught:
        make()
    return fmu_message(caught.value.problems[0])


R_PROBLEM = core_problem(lambda: TireParameters(R=-1.0))
#: the reason every refusal gives in the error state reached with R = -1
ERROR_REASON = M["PARAMETERS_REFUSED"] % (1, R_PROBLEM)


def started(fmu: Opened, start_time: float = 0.0, **parameters) -> Instance:
    instance = Instance(fmu)
    status = instance.initialise(start_time, **{"n_elements": N, **parameters})
    assert status == OK, instance.errors()
    instance.log.clear()
    return instance


def in_phase(fmu: Opened, phase: str) -> Instance:
    """An instance in ``phase`` of the state machine (error: parameters refused)."""
    instance = Instance(fmu)
    if phase != "instantiated":
        instance.slave.setupExperiment(startTime=0.0)
        instance.slave.enterInitializationMode()
        instance.set(n_elements=N)
    if phase == "error":
        instance.set(R=-1.0)
        assert instance.call("fmi2ExitInitializationMode") == ERROR
    elif phase in ("running", "terminated"):
        assert instance.call("fmi2ExitInitializationMode") == OK
        if phase == "terminated":
            instance.slave.terminate()
    instance.log.clear()
    return instance


def state_bytes(instance: Instance) -> bytes:
    state = instance.slave.getFMUstate()
    data = bytes(instance.slave.serializeFMUstate(state))
    instance.slave.freeFMUstate(state)
    return data


def run_on(instance: Instance, t0: float, steps: int, signal=road_drop, h: float = H
           ) -> np.ndarray:
    rows = []
    for k in range(steps):
        t = t0 + k * h
        instance.slave.setReal(instance.inputs, list(signal(t)))
        assert instance.step(t, h) == OK, instance.errors()
        rows.append(instance.outputs_now())
    return np.array(rows)


# -- the state machine: every call in every phase --------------------------------------------

def _vrs(*refs):
    return (fmi2ValueReference * len(refs))(*refs)


def _call(instance: Instance, call: str) -> int:
    """``call`` with arguments it accepts in a phase that allows it."""
    vr = instance.vr
    arguments = {
        "fmi2SetupExperiment": (False, 0.0, 0.0, False, 0.0),
        "fmi2EnterInitializationMode": (),
        "fmi2ExitInitializationMode": (),
        "fmi2Terminate": (),
        "fmi2Reset": (),
        "fmi2GetReal": (_vrs(vr["rim_Fz"]), 1, (fmi2Real * 1)()),
        "fmi2GetInteger": (_vrs(vr["n_elements"]), 1, (fmi2Integer * 1)()),
        "fmi2GetBoolean": (_vrs(vr["in_contact"]), 1, (fmi2Boolean * 1)()),
        "fmi2GetString": (_vrs(), 0, (fmi2String * 1)()),
        "fmi2SetReal": (_vrs(vr["rim_z"]), 1, (fmi2Real * 1)(0.0)),
        # no Integer or Boolean variable may change while running: none is set
        "fmi2SetInteger": (_vrs(), 0, (fmi2Integer * 1)()),
        "fmi2SetBoolean": (_vrs(), 0, (fmi2Boolean * 1)()),
        "fmi2SetString": (_vrs(), 0, (fmi2String * 1)()),
        "fmi2DoStep": (0.0, H, True),
    }
    if call in arguments:
        return instance.call(call, *arguments[call])
    if call == "fmi2GetFMUstate":
        state = fmi2FMUstate()
        status = instance.call(call, byref(state))
        instance.slave.freeFMUstate(state)
        return status
    state = instance.slave.getFMUstate()  # allowed in every phase
    try:
        if call == "fmi2SetFMUstate":
            return instance.call(call, state)
        if call == "fmi2DeSerializeFMUstate":
            data = bytes(instance.slave.serializeFMUstate(state))
            made = fmi2FMUstate()
            status = instance.call(call, data, len(data), byref(made))
            instance.slave.freeFMUstate(made)
            return status
        if call == "fmi2SerializeFMUstate":
            instance.slave.serializeFMUstate(state)
            return OK
        if call == "fmi2SerializedFMUstateSize":
            return instance.call(call, state, byref(c_size_t()))
        if call == "fmi2FreeFMUstate":
            return instance.call(call, byref(state))
    finally:
        instance.slave.freeFMUstate(state)
    raise KeyError(call)


#: The calls whose phases both FMUs decide (the others are pythonfmu's in the Python FMU)
SHARED_CALLS = [call for call in CALLS if call not in PYTHONFMU_ANSWERS
                or call.endswith("FMUstate") or call.endswith("FMUstateSize")
                or call == "fmi2Reset"]


@pytest.mark.parametrize("phase", list(PHASES))
@pytest.mark.parametrize("call", SHARED_CALLS)
def test_every_call_in_every_phase_is_allowed_or_refused_as_the_spec_says(fmu, call, phase):
    """spec.CALLS (FMI 2.0.4's state table) decides: a call its phase allows succeeds, any
    other is refused with fmi2Error and the spec's message naming the phase (in the error
    state, why the FMU is there), and changes nothing: the FMU's state reads the same, byte
    for byte. fmi2GetReal while instantiated is refused (the Python FMU used to answer)."""
    instance = in_phase(fmu, phase)
    before = state_bytes(instance)
    status = _call(instance, call)
    said = errors(instance)
    if phase in CALLS[call]:
        assert status == OK and said == [], said
    else:
        number = Phase.NAMES.index(phase)
        why = phase_refusal(number, ERROR_REASON if phase == "error" else "")
        assert status == ERROR and said == [refusal(call, why)]
        assert state_bytes(instance) == before
    instance.slave.freeInstance()


@pytest.mark.parametrize("phase", list(PHASES))
def test_calls_the_native_fmu_alone_decides_follow_the_spec(native_fmu_path, phase):
    """The status, cancel and derivative calls, and fmi2SetDebugLogging: in the Python FMU
    pythonfmu's wrapper answers them (spec.PYTHONFMU_ANSWERS); the native FMU follows
    spec.CALLS, then refuses what it does not provide for that reason."""
    fmu = Opened.of(native_fmu_path)
    instance = in_phase(fmu, phase)
    value = (fmi2Real * 1)()
    real = fmi2Real()
    cases = {
        "fmi2SetDebugLogging": (lambda: instance.call("fmi2SetDebugLogging", True, 0, None),
                                None),
        "fmi2GetRealStatus": (lambda: instance.call("fmi2GetRealStatus", LAST_SUCCESSFUL_TIME,
                                                    byref(real)), None),
        "fmi2GetBooleanStatus": (lambda: instance.call("fmi2GetBooleanStatus", TERMINATED,
                                                       byref(fmi2Boolean())), None),
        "fmi2CancelStep": (lambda: instance.call("fmi2CancelStep"),
                           refusal("fmi2CancelStep", M["NO_STEP_PENDING"])),
        "fmi2GetDirectionalDerivative": (
            lambda: instance.call("fmi2GetDirectionalDerivative", _vrs(), 0, _vrs(), 0,
                                  value, value), "the FMU provides no directional derivatives"),
    }
    for call, (make, own_refusal) in cases.items():
        status = make()
        said = errors(instance)
        if phase not in CALLS[call]:
            number = Phase.NAMES.index(phase)
            why = phase_refusal(number, ERROR_REASON if phase == "error" else "")
            assert status == ERROR and said == [refusal(call, why)], call
        elif own_refusal is None:
            assert status == OK and said == [], call
        else:
            assert status == ERROR and len(said) == 1 and own_refusal in said[0], call
    instance.slave.freeInstance()


def test_a_second_exit_from_initialisation_running_or_terminated_changes_nothing(fmu):
    instance = started(fmu, speed=10.0)
    rows = run_on(instance, 0.0, 3)
    before = state_bytes(instance)
    assert instance.call("fmi2ExitInitializationMode") == ERROR
    assert instance.call("fmi2EnterInitializationMode") == ERROR
    running = M["PHASE"] % PHASES["running"]
    assert errors(instance) == [refusal("fmi2ExitInitializationMode", running),
                                refusal("fmi2EnterInitializationMode", running)]
    assert state_bytes(instance) == before and instance.outputs_now() == list(rows[-1])
    assert instance.step(3 * H) == OK  # still running, at the same point
    instance.slave.terminate()
    assert instance.call("fmi2ExitInitializationMode") == ERROR
    assert instance.step(4 * H) == ERROR
    terminated = M["PHASE"] % PHASES["terminated"]
    assert errors(instance) == [refusal("fmi2ExitInitializationMode", terminated),
                                refusal("fmi2DoStep", terminated)]
    instance.slave.freeInstance()


# -- parameters ------------------------------------------------------------------------------

def test_refused_parameters_put_both_fmus_in_the_error_state_with_every_problem(fmu):
    """Every problem is logged, fmi2ExitInitializationMode is refused and the FMU is in FMI's
    error state: each later call but reset, getters and FMU states is refused with the same
    reason, listing the problems; reset and valid parameters then run. (The native FMU used
    to stay in initialisation mode.)"""
    instance = Instance(fmu)
    problems = [core_problem(lambda: TireParameters(R=-1.0)),
                M["ELEMENTS_RANGE"] % (3, CONSTANTS["MIN_ELEMENTS"], CONSTANTS["MAX_ELEMENTS"]),
                M["NOT_NONNEGATIVE"] % ("load", "nan", "N")]
    assert instance.initialise(R=-1.0, n_elements=3, load=math.nan) == ERROR
    reason = M["PARAMETERS_REFUSED"] % (3, "; ".join(problems))
    assert errors(instance) == [M["PROBLEM_LINE"] % (i + 1, 3, p) for i, p in
                                enumerate(problems)] + [M["EXIT_REFUSED"] % reason]
    assert instance.step(0.0) == ERROR
    assert instance.call("fmi2SetReal", _vrs(instance.vr["load"]), 1, (fmi2Real * 1)(1e4)) \
        == ERROR
    assert instance.call("fmi2ExitInitializationMode") == ERROR
    assert errors(instance) == [refusal(call, reason) for call in (
        "fmi2DoStep", "fmi2SetReal", "fmi2ExitInitializationMode")]
    assert math.isnan(instance.slave.getReal([instance.vr["load"]])[0])  # getters answer
    instance.slave.reset()
    assert instance.initialise(n_elements=N) == OK and not errors(instance)
    assert instance.step(0.0) == OK
    instance.free()


def test_a_speed_at_the_critical_speed_is_refused_alike(fmu):
    instance = Instance(fmu)
    assert instance.initialise(n_elements=N, speed=1000.0) == ERROR
    [line, exit_refusal] = errors(instance)
    assert line.startswith("parameter problem 1/1: speed = 1000 m/s: must be below the "
                           "critical (standing-wave) speed")
    assert exit_refusal == M["EXIT_REFUSED"] % (M["PARAMETERS_REFUSED"] % (
        1, line.split(": ", 1)[1]))
    instance.slave.freeInstance()


def test_parameters_are_fixed_after_initialisation_and_a_set_is_all_or_nothing(fmu):
    instance = started(fmu)
    vr = instance.vr
    before = state_bytes(instance)
    assert instance.call("fmi2SetReal", _vrs(vr["rim_z"], vr["load"]), 2,
                         (fmi2Real * 2)(1e-3, 1.0)) == ERROR
    assert instance.call("fmi2SetInteger", _vrs(vr["n_elements"]), 1,
                         (fmi2Integer * 1)(50)) == ERROR
    assert instance.call("fmi2SetBoolean", _vrs(vr["linear_contact"]), 1,
                         (fmi2Boolean * 1)(True)) == ERROR
    assert errors(instance) == [
        refusal("fmi2SetReal", M["PARAMETER_FIXED"] % ("load", "1 N")),
        refusal("fmi2SetInteger", M["PARAMETER_FIXED"] % ("n_elements", "50")),
        refusal("fmi2SetBoolean", M["PARAMETER_FIXED"] % ("linear_contact", "True"))]
    assert state_bytes(instance) == before  # rim_z was not set either
    instance.free()


def test_bad_references_types_outputs_and_strings_are_refused_alike(fmu):
    instance = started(fmu)
    vr, n = instance.vr, N_VALUES
    before = state_bytes(instance)
    calls = [
        ("fmi2GetReal", (_vrs(999), 1, (fmi2Real * 1)()),
         M["REFERENCE_MISSING"] % (999, "<id>", n)),
        ("fmi2GetInteger", (_vrs(vr["rim_z"]), 1, (fmi2Integer * 1)()),
         M["REFERENCE_TYPE"] % (vr["rim_z"], "rim_z", "Real", "Real", "Real")),
        ("fmi2SetReal", (_vrs(999), 1, (fmi2Real * 1)(1.0)),
         M["REFERENCE_MISSING"] % (999, "<id>", n)),
        ("fmi2SetReal", (_vrs(vr["n_elements"]), 1, (fmi2Real * 1)(3.0)),
         M["REFERENCE_TYPE"] % (vr["n_elements"], "n_elements", "Integer", "Integer",
                                "Integer")),
        ("fmi2SetReal", (_vrs(vr["rim_Fz"]), 1, (fmi2Real * 1)(0.0)),
         M["OUTPUT_SET"] % ("rim_Fz", "0 N")),
        ("fmi2GetString", (_vrs(0), 1, (fmi2String * 1)()), M["NO_STRINGS"] % "<id>"),
        ("fmi2SetString", (_vrs(0), 1, (c_char_p * 1)(b"x")), M["NO_STRINGS"] % "<id>"),
    ]
    for call, arguments, why in calls:
        assert instance.call(call, *arguments) == ERROR, call
        assert errors(instance) == [refusal(call, why)], call
    assert state_bytes(instance) == before
    instance.free()


# -- steps and inputs ------------------------------------------------------------------------

def test_the_input_range_message_is_the_cores_step_error():
    """spec INPUT_RANGE, filled in as both FMUs fill it, is the core's StepError text for the
    same input (the core refuses it at a step, the FMUs at the set)."""
    from tire_fmu.core import validate
    from tire_fmu.core.contact_dynamics import ContactSimulator, StepError, build_contact_model

    simulator = ContactSimulator(build_contact_model(*validate({}, {"n_elements": N})),
                                 backend="numpy")
    for name, value, unit, limit in (("rim_z", math.nan, "m", CONSTANTS["MAX_DISPLACEMENT_M"]),
                                     ("road_vz", -1e300, "m/s", CONSTANTS["MAX_VELOCITY_M_S"])):
        inputs = {"rim_z": 0.0, "rim_vz": 0.0, "road_z": 0.0, "road_vz": 0.0, name: value}
        with pytest.raises(StepError) as caught:
            simulator._check(None, tuple(inputs.values()))
        assert str(caught.value) == M["INPUT_RANGE"] % (name, repr(value), unit, limit, limit,
                                                        unit)


def test_both_fmus_declare_the_tables_start_values(both):
    """pythonfmu reads a slave's start values through its getters, which FMI does not allow
    while instantiated: the Python FMU's model description has them all the same."""
    for fmu in both:
        starts = {v.name: v.start for v in fmu.model_description.modelVariables}
        for v in fmu_variables():
            if v.causality != "output":
                assert starts[v.name] is not None and (
                    float(starts[v.name]) == float(v.start) if v.type != "Boolean"
                    else starts[v.name] in ("true", "false", True, False)), (fmu.path, v.name)


@pytest.mark.parametrize("bad, name", [
    (math.nan, "rim_z"), (math.inf, "road_z"), (-math.inf, "rim_vz"), (1e308, "rim_z"),
    (math.nan, "road_vz")])
def test_an_input_that_is_not_finite_or_beyond_its_limit_is_refused_at_the_set(fmu, bad, name):
    """Both FMUs refuse it at fmi2SetReal (the Python FMU used to take it and refuse the
    step), set none of the call's values, and run on exactly as before."""
    instance = started(fmu)
    run_on(instance, 0.0, 10)
    before = state_bytes(instance)
    v = next(x for x in fmu_variables() if x.name == name)
    limit = CONSTANTS["MAX_VELOCITY_M_S" if v.unit == "m/s" else "MAX_DISPLACEMENT_M"]
    values = [0.01, 0.0, 0.0, 0.0]
    values[instance.inputs.index(instance.vr[name])] = bad
    assert instance.call("fmi2SetReal", _vrs(*instance.inputs), 4, (fmi2Real * 4)(*values)) \
        == ERROR
    assert errors(instance) == [refusal("fmi2SetReal", M["INPUT_RANGE"] % (
        name, repr(bad), v.unit, limit, limit, v.unit))]
    assert state_bytes(instance) == before
    assert instance.slave.getRealStatus(LAST_SUCCESSFUL_TIME) == pytest.approx(10 * H)
    instance.free()


def test_inputs_at_their_limits_are_taken_and_keep_every_output_finite(fmu):
    instance = started(fmu)
    d, v = CONSTANTS["MAX_DISPLACEMENT_M"], CONSTANTS["MAX_VELOCITY_M_S"]
    instance.slave.setReal(instance.inputs, [d, -v, -d, v])
    for k in range(50):
        assert instance.step(k * 1e-3, 1e-3) == OK
        assert all(math.isfinite(y) for y in instance.outputs_now())
    assert not errors(instance)
    instance.free()


def _bad_steps(fmu):
    """(t, h, why) of refused steps from t = 1e-3 s, the last point, at 10 m/s."""
    last, longest = 1e-3, math.nextafter(CONSTANTS["MAX_STEP_S"], math.inf)
    not_last = lambda t: M["NOT_LAST_POINT"] % (repr(t), repr(last))  # noqa: E731
    size = lambda h: M["STEP_RANGE"] % (repr(h), CONSTANTS["MAX_STEP_S"])  # noqa: E731
    return [(0.0, 1e-3, not_last(0.0)), (2e-3, 1e-3, not_last(2e-3)),
            (0.5, 1e-3, not_last(0.5)), (math.nan, 1e-3, not_last(math.nan)),
            (math.inf, 1e-3, not_last(math.inf)), (last, 0.0, size(0.0)),
            (last, -1e-3, size(-1e-3)), (last, math.nan, size(math.nan)),
            (last, math.inf, size(math.inf)), (last, 1e300, size(1e300)),
            (last, longest, size(longest))]


def test_bad_steps_are_refused_alike_change_nothing_and_the_host_retries(fmu):
    """A t other than the last communication point (NaN and infinities included) or h not in
    (0, MAX_STEP_S]: fmi2Error with the spec's message; the FMU's state reads the same byte
    for byte, the last successful time stays, the FMU does not ask to terminate, and the run
    then goes on exactly as one that never saw them."""
    undisturbed, disturbed = started(fmu, speed=10.0), started(fmu, speed=10.0)
    for instance in (undisturbed, disturbed):
        instance.slave.setReal(instance.inputs, [1e-3, 0.0, 0.0, 0.0])
        assert instance.step(0.0, 1e-3) == OK
    # taking a state settles the kernel's pending force ramp into its modes (a rounding of
    # its own, kernel_state_write): the undisturbed run takes one at the same point
    state_bytes(undisturbed)
    before = state_bytes(disturbed)
    for t, h, why in _bad_steps(fmu):
        assert disturbed.step(t, h) == ERROR
        assert errors(disturbed) == [step_refusal(t, h, why)], (t, h)
    assert state_bytes(disturbed) == before
    assert disturbed.slave.getRealStatus(LAST_SUCCESSFUL_TIME) == 1e-3
    assert disturbed.slave.getBooleanStatus(TERMINATED) is False
    a = run_on(undisturbed, 1e-3, 100)
    b = run_on(disturbed, 1e-3, 100)
    assert np.array_equal(a, b)
    undisturbed.free()
    disturbed.free()


def test_a_communication_point_within_the_time_tolerance_is_that_point(fmu):
    """TIME_ABS_TOLERANCE_S and TIME_REL_TOLERANCE: a t within them of the last point is
    that point (the FMU's clock goes on from its own), one just beyond is refused."""
    instance = started(fmu)
    assert instance.step(0.0, 0.1) == OK
    relative = CONSTANTS["TIME_REL_TOLERANCE"]
    assert instance.step(0.1 * (1 + 0.9 * relative), 0.1) == OK
    late = 0.2 * (1 + 1.5 * relative)
    now = 0.1 + 0.1  # the FMU's own sum of its steps
    assert instance.step(late, 0.1) == ERROR
    assert errors(instance) == [step_refusal(late, 0.1, M["NOT_LAST_POINT"] % (
        repr(late), repr(now)))]
    assert instance.step(now, 0.1) == OK
    fresh = started(fmu)
    absolute = CONSTANTS["TIME_ABS_TOLERANCE_S"]
    assert fresh.step(0.9 * absolute, H) == OK
    assert fresh.step(H + 1.5 * absolute, H) == ERROR
    instance.free()
    fresh.free()


def test_a_step_too_short_for_the_road_history_at_a_crawl_is_refused_alike(fmu):
    """MAX_DELAY_STEPS: at the slowest rolling speed the road takes minutes to cross the
    zone; a step that would keep more than MAX_DELAY_STEPS steps of history is refused, one
    just long enough is taken."""
    from tire_fmu.core import validate
    from tire_fmu.core.contact_dynamics import build_contact_model

    speed = CONSTANTS["MIN_ROLLING_SPEED_M_S"]
    reach = build_contact_model(*validate({}, {"n_elements": N, "speed_m_s": speed})
                                ).windows.horizon_s
    instance = started(fmu, speed=speed)
    assert instance.step(0.0, 1e-4) == ERROR
    [said] = errors(instance)
    assert said == step_refusal(0.0, 1e-4, M["STEP_DELAY"] % (
        "0.0001", reach / CONSTANTS["MAX_DELAY_STEPS"], reach, CONSTANTS["MAX_DELAY_STEPS"]))
    h = 1.001 * reach / CONSTANTS["MAX_DELAY_STEPS"]
    assert instance.step(0.0, h) == OK and instance.step(h, h) == OK
    instance.free()


def test_a_step_too_short_for_a_truncated_rings_rate_term_is_refused_alike(fmu):
    """MIN_CORRECTED_STEP_S: a ring truncated with static correction refuses shorter steps
    (5e-324 s made both FMUs' outputs infinite), and goes on unchanged; the full ring steps
    them."""
    truncated = started(fmu, f_max=150.0)
    before = state_bytes(truncated)
    minimum = CONSTANTS["MIN_CORRECTED_STEP_S"]
    for h in (5e-324, 1e-6, minimum * (1 - 1e-15)):
        assert truncated.step(0.0, h) == ERROR
        assert errors(truncated) == [step_refusal(0.0, h, M["SHORT_STEP_CORRECTED"] % (
            repr(h), minimum))]
    assert state_bytes(truncated) == before
    assert truncated.step(0.0, minimum) == OK
    full = started(fmu)
    assert full.step(0.0, 1e-6) == OK and full.step(1e-6, 1e-5) == OK
    truncated.free()
    full.free()


def test_a_step_below_the_clocks_resolution_is_refused_alike_and_changes_nothing(both):
    """The clock resolution: h = 1e-4 s at t = 1e12 s is shorter than the spacing of doubles
    there (1.22e-4 s); both FMUs refuse it with the core's message, and take a resolved step
    after it."""
    for fmu in both:
        instance = started(fmu, start_time=1e12, speed=20.0)
        before = state_bytes(instance)
        assert instance.step(1e12, 1e-4) == ERROR
        assert errors(instance) == [step_refusal(1e12, 1e-4, clock.resolution_problem(
            1e12, 1e-4))]
        assert state_bytes(instance) == before
        assert instance.step(1e12, 2.5e-4) == OK
        assert instance.slave.getRealStatus(LAST_SUCCESSFUL_TIME) == 1e12 + 2.5e-4
        instance.free()


@pytest.mark.parametrize("start, stop, tolerance, why", [
    (math.nan, None, None, M["START_NOT_FINITE"] % "nan"),
    (math.inf, None, None, M["START_NOT_FINITE"] % "inf"),
    (-math.inf, None, None, M["START_NOT_FINITE"] % "-inf"),
    (1e16, None, None, M["START_UNRESOLVED"] % (
        "1e+16", clock.resolved_until(1.0) - 1.0, CONSTANTS["MAX_STEP_S"])),
    (0.0, -1.0, None, M["STOP_TIME"] % ("-1.0", "0.0")),
    (0.0, math.nan, None, M["STOP_TIME"] % ("nan", "0.0")),
    (0.0, math.inf, None, M["STOP_TIME"] % ("inf", "0.0")),
    (0.0, None, -1e-6, M["TOLERANCE"] % "-1e-06"),
    (0.0, None, math.nan, M["TOLERANCE"] % "nan"),
])
def test_setup_experiment_refuses_bad_times_alike(fmu, start, stop, tolerance, why):
    instance = Instance(fmu)
    before = state_bytes(instance)
    assert instance.call("fmi2SetupExperiment", tolerance is not None, tolerance or 0.0,
                         start, stop is not None, stop or 0.0) == ERROR
    assert errors(instance) == [refusal("fmi2SetupExperiment", why)]
    assert state_bytes(instance) == before
    # the clock's limit itself: the largest start time that resolves MAX_STEP_S is taken
    instance.slave.setupExperiment(startTime=-1.7e9)
    instance.slave.enterInitializationMode()
    instance.set(n_elements=N)
    assert instance.call("fmi2ExitInitializationMode") == OK
    assert instance.step(-1.7e9) == OK
    instance.free()


def test_simulate_fmu_stops_on_a_nan_input_at_its_set(fmu, tmp_path):
    """A NaN sample in fmpy.simulate_fmu's input ends the run at that fmi2SetReal with an
    error naming it (it never hangs, nor returns a cut result), logging off or on."""
    script = tmp_path / "nan_input.py"
    script.write_text(textwrap.dedent(f"""
        import numpy as np
        from fmpy import simulate_fmu
        from fmpy.fmi1 import FMICallException
        t = np.arange(0.0, 0.01, 1e-4)
        signals = np.zeros(t.size, dtype=[("time", float), ("road_z", float)])
        signals["time"] = t
        signals["road_z"][50] = np.nan
        logged = []
        try:
            simulate_fmu({str(fmu.path)!r}, start_values={{"n_elements": {N}}}, input=signals,
                         output=["rim_Fz"], output_interval=1e-4, stop_time=t[-1],
                         logger=lambda *a: logged.append((a[2], a[4].decode())))
        except FMICallException as error:
            print("stopped:", error)
        print([m for s, m in logged if s == 3])
    """))
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=TIMEOUT_S)
    assert "stopped: fmi2SetReal failed with status 3" in done.stdout, done.stderr[-2000:]
    assert refusal("fmi2SetReal", M["INPUT_RANGE"] % ("road_z", "nan", "m", 10, 10, "m")) \
        in done.stdout


# -- events and warnings ---------------------------------------------------------------------

def test_lift_off_is_ok_and_logged_as_an_event_alike(both):
    """The tread leaving the road and landing: status OK, one information line each in the
    category logEvents with the spec's text, the same steps in both FMUs; no warning."""
    logs = []
    for fmu in both:
        instance = started(fmu)
        lifted = []
        for k in range(1500):
            t = k * 1e-4
            instance.slave.setReal(instance.inputs, list(road_drop(t)))
            assert instance.step(t) == OK
            lifted.append(not instance.slave.getBoolean([instance.vr["in_contact"]])[0])
        assert any(lifted) and not lifted[-1]
        events = [(s, m) for s, c, m in instance.log if c == "logEvents"]
        assert events and {s for s, _ in events} == {OK}
        assert not [m for s, _, m in instance.log if s > OK]
        logs.append([m for _, m in events])
        instance.free()
    assert logs[0] == logs[1]  # it lands, and bounces once
    times = [float(m.split(" s:")[0][4:]) for m in logs[0]]
    assert len(times) % 2 == 0 and logs[0] == [
        M["TOUCH_DOWN" if i % 2 else "LIFT_OFF"] % t for i, t in enumerate(times)]


def test_the_footprint_at_the_zone_edge_warns_once_per_episode_alike(both):
    """Pressed down 3 cm twice (a slow cosine of the rim), the footprint reaches the end of a
    0.2 m zone each time: one warning per press with the spec's text, every step OK (a strict
    host must not stop on it), at the same steps in both FMUs."""
    warned = []
    for fmu in both:
        instance = started(fmu, n_elements=100, contact_zone_length=0.2, load=15000.0)
        w, steps = 2 * math.pi / 0.1, []
        for k in range(2000):
            t = k * 1e-4
            instance.slave.setReal(instance.inputs, [-0.015 * (1 - math.cos(w * t)),
                                                     -0.015 * w * math.sin(w * t), 0.0, 0.0])
            before = len(instance.log)
            assert instance.step(t) == OK
            steps += [(k, m) for s, _, m in instance.log[before:] if s == 1]
        warned.append(steps)
        instance.free()
    assert warned[0] == warned[1] and len(warned[0]) == 2
    (first, text), (second, _) = warned[0]
    assert first < 1000 <= second
    assert text == M["ZONE_EDGE"] % float(text.split(" s:")[0][4:])


# -- FMU states ------------------------------------------------------------------------------

def test_the_state_layout_is_the_specs_in_both_fmus(both):
    """One format: both FMUs' states parse with spec.state_unpack (magic, version, phase, own
    GUID, size, times, flags, values, a model part of two flags and the kernel's bytes, the
    CRC-32), and the same run gives the same bytes but the GUID and the checksum."""
    parsed = []
    for fmu in both:
        instance = started(fmu, speed=10.0)
        run_on(instance, 0.0, 100)
        data = state_bytes(instance)
        f = state_unpack(data, N_VALUES)
        assert (f["magic"], f["version"], f["phase"]) == (STATE_MAGIC.encode(), STATE_VERSION,
                                                          Phase.RUNNING)
        assert f["guid"] == fmu.model_description.guid and f["size"] == len(data)
        assert f["checksum"] == state_checksum(data[:-4]) and f["reason"] == b""
        assert list(f["values"][4:10]) == instance.outputs_now()
        flags = struct.unpack_from("<2i", f["model"])
        kernel = kernel_numpy.state_fields(f["model"][4 * STATE_MODEL_FLAGS:])
        assert flags == (1, 1) and kernel["start_time"] + kernel["elapsed_s"] == f["time"]
        parsed.append((data, f))
        instance.free()
    (a, fa), (b, fb) = parsed
    assert len(a) == len(b) and fa["time"] == fb["time"]
    assert relative_errors(np.array([fa["values"][4:10]]), np.array([fb["values"][4:10]])
                           ).max() < 1e-9


def test_state_rollback_reproduces_steps_exactly_also_serialized_and_in_a_fresh_instance(fmu):
    instance = started(fmu, speed=10.0)
    run_on(instance, 0.0, 300)
    state = instance.slave.getFMUstate()
    serialized = instance.slave.serializeFMUstate(state)
    reference = run_on(instance, 0.03, 300)
    instance.slave.setFMUstate(state)
    assert np.array_equal(run_on(instance, 0.03, 300), reference)
    restored = instance.slave.deSerializeFMUstate(serialized)
    instance.slave.setFMUstate(restored)
    assert np.array_equal(run_on(instance, 0.03, 300), reference)
    fresh = Instance(fmu)  # only instantiated: the state brings its parameters along
    fresh.slave.setFMUstate(fresh.slave.deSerializeFMUstate(serialized))
    assert relative_errors(reference, run_on(fresh, 0.03, 300)).max() < 1e-12
    other = started(fmu, load=15000.0)  # built for other parameters: rebuilt
    other.slave.setFMUstate(other.slave.deSerializeFMUstate(serialized))
    assert other.slave.getReal([other.vr["load"]]) == [pytest.approx(27654.753)]
    assert relative_errors(reference, run_on(other, 0.03, 300)).max() < 1e-12
    assert not (errors(instance) or errors(fresh) or errors(other))
    instance.slave.freeFMUstate(state)
    instance.slave.freeFMUstate(restored)
    for x in (instance, fresh, other):
        x.free()


def test_inputs_set_after_a_step_feed_through_after_a_rollback_too(fmu):
    instance = started(fmu)
    run_on(instance, 0.0, 3, signal=lambda t: (1e-3, 0.0, 0.0, 0.0))
    instance.slave.setReal(instance.inputs, [1e-3, 0.0, 0.0, 0.5])  # the damper acts at once
    state = instance.slave.getFMUstate()
    expected = instance.outputs_now()
    instance.slave.setFMUstate(state)
    assert instance.outputs_now() == expected
    instance.free()


def test_a_state_in_the_error_phase_carries_its_reason_into_every_refusal(fmu):
    broken = in_phase(fmu, "error")
    data = state_bytes(broken)
    f = state_unpack(data, N_VALUES)
    assert f["phase"] == Phase.ERROR and f["reason"].decode() == ERROR_REASON
    fresh = Instance(fmu)
    fresh.slave.setFMUstate(fresh.slave.deSerializeFMUstate(data))
    assert not errors(fresh)
    assert fresh.step(0.0) == ERROR
    assert errors(fresh) == [refusal("fmi2DoStep", ERROR_REASON)]
    broken.slave.freeInstance()
    fresh.slave.freeInstance()


def _forge(data: bytes, **fields) -> bytes:
    """State bytes with some header fields (or the kernel's, as kernel_<name>) changed and
    the checksum recomputed: a forger's state, to be refused for what it means."""
    f = state_unpack(data, N_VALUES)
    model = f["model"]
    kernel_changes = {k[7:]: v for k, v in fields.items() if k.startswith("kernel_")}
    if kernel_changes:
        flags, kernel = model[:4 * STATE_MODEL_FLAGS], model[4 * STATE_MODEL_FLAGS:]
        model = flags + kernel_numpy.state_data({**kernel_numpy.state_fields(kernel),
                                                 **kernel_changes})
    values = list(fields.get("values", f["values"]))
    reason = fields.get("reason", f["reason"].decode())
    return state_pack(fields.get("phase", f["phase"]), fields.get("guid", f["guid"]),
                      fields.get("time", f["time"]), fields.get("start_time", f["start_time"]),
                      fields.get("stale", f["stale"]), values, fields.get("model", model),
                      reason)


def _bad_states(fmu, data: bytes) -> dict[str, tuple[bytes, str]]:
    """State bytes that must be refused, with the reason both FMUs give."""
    f = state_unpack(data, N_VALUES)
    values = list(f["values"])
    vr = {v.name: i for i, v in enumerate(fmu_variables())}
    kernel = kernel_numpy.state_fields(f["model"][4 * STATE_MODEL_FLAGS:])
    flipped = bytearray(data)
    flipped[-20] ^= 1
    nan_q = kernel["q"].copy()
    nan_q[0] = complex(math.nan, 0)
    huge_q = kernel["q"].copy()
    huge_q[0] = 1e300
    future = kernel["history_t"].copy()
    future[-1] = 1.0
    nan_road = kernel["history_z"].copy()
    nan_road[0] = math.nan
    count = MAX_HISTORY_SAMPLES + 1

    def changed(name, x):
        out = list(values)
        out[vr[name]] = x
        return out

    not_ours = M["STATE_NOT_OURS"]
    return {
        "empty": (b"", not_ours % M["STATE_TOO_SHORT"]),
        "garbage": (b"garbage", not_ours % M["STATE_TOO_SHORT"]),
        "printf formats": (b"%s%n" * 300, not_ours % M["STATE_NO_HEADER"]),
        "trailing bytes": (data + b"\0extra", M["STATE_SIZE"] % (len(data), len(data) + 6)),
        "cut short": (data[:-100], M["STATE_SIZE"] % (len(data), len(data) - 100)),
        "one bit flipped": (bytes(flipped), M["STATE_DAMAGED"]),
        "another version": (state_reseal(data[:8] + struct.pack("<I", 2) + data[12:]),
                            M["STATE_VERSION"] % (2, STATE_VERSION)),
        "another FMU": (_forge(data, guid="{another}"), M["STATE_GUID"] % ("{another}",
                                                                           "<guid>")),
        # a model part and a reason whose sizes add up, modulo 2**64, to what follows
        "sizes that wrap around": (state_reseal(
            data[:92] + struct.pack("<I", f["model_size"] + 8) + data[96:f["model_at"] - 8]
            + struct.pack("<Q", 2**64 - 8) + data[f["model_at"]:]), M["STATE_MODEL_SIZE"]),
        "unknown phase": (state_reseal(data[:12] + struct.pack("<I", 7) + data[16:]),
                          M["STATE_PHASE"] % 7),
        "nan time": (_forge(data, time=math.nan), M["STATE_CLOCK"] % ("nan", "0.0")),
        "time 1e300 throughout": (
            _forge(data, time=1e300, start_time=1e300, kernel_start_time=1e300),
            M["STATE_START"] % (M["START_UNRESOLVED"] % (
                "1e+300", clock.resolved_until(1.0) - 1.0, 1.0))),
        "an input beyond its limit": (_forge(data, values=changed("road_z", 1e300)),
                                      M["STATE_INPUT"] % (M["INPUT_RANGE"] % (
                                          "road_z", "1e+300", "m", 10, 10, "m"))),
        "an integer C cannot hold": (_forge(data, values=changed("n_elements", 1e30)),
                                     M["STATE_VALUE"] % ("n_elements", "Integer")),
        "nan output": (_forge(data, values=changed("rim_Fz", math.nan)),
                       M["STATE_VALUE"] % ("rim_Fz", "Real")),
        "no model part": (_forge(data, model=b""), M["STATE_MODEL_PHASE"]),
        "a model part before initialisation": (
            _forge(data, phase=Phase.INITIALISATION, time=0.0), M["STATE_MODEL_PHASE"]),
        "error phase without its reason": (_forge(data, phase=Phase.ERROR, model=b""),
                                           M["STATE_NO_REASON"]),
        "a reason while running": (_forge(data, reason="why"),
                                   M["STATE_REASON_PHASE"] % "running"),
        "a NUL in the reason": (_forge(data, phase=Phase.ERROR, model=b"", reason="a\0b"),
                                M["STATE_REASON_NUL"]),
        "parameters that do not build": (_forge(data, values=changed("m_s", 1e-20)),
                                         M["STATE_PARAMETERS"] % core_problem(
                                             lambda: TireParameters(m_s=1e-20))),
        "a model flag not 0 or 1": (_forge(data, model=struct.pack("<2i", 1, 2)
                                           + f["model"][8:]), M["STATE_MODEL_FLAG"] % (1, 2)),
        "a short model part": (_forge(data, model=b"\1\0\0\0"), M["STATE_MODEL_SHORT"] % 4),
        "a header time not the model's": (
            _forge(data, time=1e300), M["STATE_MODEL_CLOCK"] % (
                "1e+300", "0.0", repr(f["time"]), "0.0")),
        "outputs not the model's": (_forge(data, values=changed("rim_Fz", 3e307)),
                                    M["STATE_MODEL_OUTPUTS"]),
        "nan modal state": (_forge(data, kernel_q=nan_q), "of its model part is not finite"),
        "modal state 1e300": (_forge(data, kernel_q=huge_q),
                              "the tread's excursion at the zone nodes from a mode reach"),
        "nan road sample": (_forge(data, kernel_history_z=nan_road),
                            "of its model part is not finite"),
        "road sample in the future": (_forge(data, kernel_history_t=future),
                                      "its newest road sample is at 1.0 s, but the state is"),
        "road history too long": (
            _forge(data, kernel_history_t=np.linspace(-1.0, 0.0, count),
                   kernel_history_z=np.zeros(count), kernel_history_v=np.zeros(count)),
            f"its road history holds {count} samples; the FMU keeps at most "
            f"{MAX_HISTORY_SAMPLES}"),
    }


def test_bad_states_are_refused_alike_and_leave_the_instance_unchanged(both):
    """Each case of _bad_states, set into each FMU (after fmi2DeSerializeFMUstate, which the
    native FMU's checks refuse already, the Python FMU's at the set): fmi2Error with the same
    reason from both, nothing changed, and the run goes on as one that never saw it. The
    kernel's own reasons come from the one C kernel (kernel_state_check)."""
    reasons = {}
    for fmu in both:
        undisturbed, disturbed = started(fmu, speed=20.0), started(fmu, speed=20.0)
        rows = [run_on(x, 0.0, 300) for x in (undisturbed, disturbed)]
        assert np.array_equal(*rows)
        data = state_bytes(disturbed)
        state_bytes(undisturbed)  # taking a state settles the force ramp alike in both
        before = state_bytes(disturbed)
        for case, (bad, why) in _bad_states(fmu, data).items():
            status = disturbed.call("fmi2DeSerializeFMUstate", bad, len(bad),
                                    byref(made := fmi2FMUstate()))
            if status == OK:
                status = disturbed.call("fmi2SetFMUstate", made)
                disturbed.slave.freeFMUstate(made)
            said = errors(disturbed)
            assert status == ERROR and len(said) == 1, (case, said)
            call, reason = said[0].split(" refused: ", 1)
            assert call in ("fmi2DeSerializeFMUstate", "fmi2SetFMUstate"), said
            assert reason.endswith("; nothing changed") and why in reason, (case, said)
            reasons.setdefault(case, []).append(reason)
            assert state_bytes(disturbed) == before, case
        assert np.array_equal(run_on(undisturbed, 0.03, 100), run_on(disturbed, 0.03, 100))
        undisturbed.free()
        disturbed.free()
    for case, (python, native) in reasons.items():
        assert python == native, case


def test_a_flipped_byte_anywhere_in_a_state_is_refused(fmu):
    """Every byte of a state (header, GUID, values, model part, road history, checksum) is
    covered by the CRC-32: flipping any one of them gives fmi2Error, and the FMU runs on."""
    instance = started(fmu, speed=10.0)
    run_on(instance, 0.0, 200)
    data = state_bytes(instance)
    accepted = []
    for position in range(len(data)):
        damaged = bytearray(data)
        damaged[position] ^= 0x5A
        made = fmi2FMUstate()
        if instance.call("fmi2DeSerializeFMUstate", bytes(damaged), len(data),
                         byref(made)) == OK:
            if instance.call("fmi2SetFMUstate", made) == OK:
                accepted.append(position)
            instance.slave.freeFMUstate(made)
    assert accepted == []
    assert len(errors(instance)) == len(data)
    assert np.isfinite(run_on(instance, 0.02, 5)).all()
    instance.free()


def test_a_state_of_the_other_fmu_is_refused_for_its_guid(both):
    """Each FMU puts its own GUID into its states and refuses those of another FMU, the other
    tire FMU of the project included."""
    python, native = both
    states = {}
    for fmu in both:
        instance = started(fmu)
        states[fmu.path] = state_bytes(instance)
        instance.free()
    for fmu, other in ((python, native), (native, python)):
        instance = started(fmu)
        data = states[other.path]
        made = fmi2FMUstate()
        status = instance.call("fmi2DeSerializeFMUstate", data, len(data), byref(made))
        call = "fmi2DeSerializeFMUstate"
        if status == OK:
            status, call = instance.call("fmi2SetFMUstate", made), "fmi2SetFMUstate"
            instance.slave.freeFMUstate(made)
        why = M["STATE_GUID"] % (other.model_description.guid, fmu.model_description.guid)
        assert status == ERROR
        assert [m for s, _, m in instance.log if s >= ERROR] == [refusal(call, why)]
        instance.free()


def test_printf_directives_in_what_a_state_holds_reach_the_host_as_text(fmu, tmp_path):
    """A state's GUID and error reason are quoted in refusals: printf directives in them
    reach the host as text (a Python FMU state whose header held "%s%s..." crashed the host
    once), in a fresh process."""
    source = started(fmu)
    data = state_bytes(source)
    source.free()
    hostile = "%s%s%s%s%s%s%s%s%n #r1#"
    forged = {"guid": _forge(data, guid=hostile),
              "reason": _forge(data, phase=Phase.ERROR, model=b"", reason=hostile)}
    for case, state in forged.items():
        (tmp_path / case).write_bytes(state)
    script = textwrap.dedent("""
        import json, sys
        from native_support import Instance, Opened
        fmu = Opened.of(sys.argv[1])
        out = {}
        for case in ("guid", "reason"):
            instance = Instance(fmu)
            data = open(sys.argv[2] + "/" + case, "rb").read()
            try:
                instance.slave.setFMUstate(instance.slave.deSerializeFMUstate(data))
                instance.step(0.0)
            except Exception:
                pass
            out[case] = [m for s, _, m in instance.log if s >= 3]
        print(json.dumps(out))
    """)
    done = subprocess.run([sys.executable, "-c", script, fmu.path, str(tmp_path)],
                          capture_output=True, text=True, timeout=TIMEOUT_S,
                          cwd=str(__import__("pathlib").Path(__file__).parent))
    assert done.returncode == 0, done.stderr[-3000:]
    import json

    said = json.loads(done.stdout.strip().splitlines()[-1])
    # the Python FMU doubles "#", FMI's escape of variable references, in the format it
    # hands the host (fmpy's proxy shows it as it is); the native FMU's format is "%s"
    shown = hostile.replace("#", "##") if identifier(fmu) == "TireModal" else hostile
    assert any(M["STATE_GUID"] % (shown, fmu.model_description.guid) in m
               for m in said["guid"]), said
    assert said["reason"] == [refusal("fmi2DoStep", shown)], said


# -- every limit of the spec, enforced alike ---------------------------------------------------

SPAN = re.compile(r"eigenvalues span [0-9.e+]+ \(")


def _lines(fmu, **parameters) -> tuple[int, list[str]]:
    instance = Instance(fmu)
    status = instance.initialise(**{"n_elements": N, **parameters})
    # the span of eigenvalues double precision does not resolve is rounding noise, each
    # FMU's own (test_native_fmu.py): compared without it
    lines = [SPAN.sub("(", same_text(fmu, m)) for s, _, m in instance.log
             if s >= ERROR and m.startswith("parameter problem")]
    instance.slave.freeInstance()
    return status, lines


#: A limit of the spec: parameters just beyond it (refused, with the FMUs' same problem
#: naming the limit), and at it where building there is cheap (taken).
LIMITS = {
    "MIN_ELEMENTS": ({"n_elements": CONSTANTS["MIN_ELEMENTS"] - 1},
                     {"n_elements": CONSTANTS["MIN_ELEMENTS"], "contact_zone_length": 1.5}),
    "MAX_ELEMENTS": ({"n_elements": CONSTANTS["MAX_ELEMENTS"] + 1}, None),
    "F_MAX_LIMIT_HZ": ({"f_max": CONSTANTS["F_MAX_LIMIT_HZ"] * 1.5},
                       {"f_max": CONSTANTS["F_MAX_LIMIT_HZ"]}),
    "N_MODES_LIMIT": ({"n_modes": CONSTANTS["N_MODES_LIMIT"] + 1},
                      {"n_modes": CONSTANTS["N_MODES_LIMIT"]}),
    "MIN_ROLLING_SPEED_M_S": ({"speed": CONSTANTS["MIN_ROLLING_SPEED_M_S"] / 2},
                              {"speed": CONSTANTS["MIN_ROLLING_SPEED_M_S"]}),
    "MIN_LAW_PRESSURE_PA": ({"sidewall_pressure_exponent": 1.0,
                             "inflation_pressure": CONSTANTS["MIN_LAW_PRESSURE_PA"] / 2},
                            None),
    "MAX_ZONE_HALF_ANGLE": ({"contact_zone_length": 5.0}, None),
    "MAX_PATCH_FRACTION": ({"load": 1e7}, None),
    "MAX_STIFFNESS_RATIO": ({"k_r1": 1e-3}, None),
    "MAX_EIGENVALUE_SPREAD": ({"m_s": 1e-3, "k_r2": 1e11, "beta": 0.1}, None),
}


@pytest.mark.parametrize("limit", list(LIMITS))
def test_every_parameter_limit_of_the_spec_is_enforced_alike(both, limit):
    beyond, at = LIMITS[limit]
    results = [_lines(fmu, **beyond) for fmu in both]
    (status, python), (_, native) = results
    assert status == ERROR and python and python == native
    if at is not None:
        assert [_lines(fmu, **at) for fmu in both] == [(OK, [])] * 2


@pytest.mark.parametrize("order, allowed", [(2.5, False), (8.0, True), (1e6, False)])
def test_the_sidewall_order_is_an_integer_in_range_alike(both, order, allowed):
    """sidewall_max_order is an integer (the tie acts on whole orders): both FMUs refuse a
    fraction or a value out of range with the same message naming it, and run 8."""
    results = [_lines(fmu, sidewall_max_order=order) for fmu in both]
    if allowed:
        assert results == [(OK, [])] * 2
    else:
        (status, python), (_, native) = results
        assert status == ERROR and python == native
        assert any("sidewall_max_order" in line and "[0, 100000]" in line for line in python)


def test_a_spacing_that_makes_too_many_contact_points_is_refused_alike(both):
    """MAX_CONTACT_POINTS: the smallest spacing in range makes more contact points on this mesh
    and zone than the contact solve takes; both FMUs refuse it at fmi2ExitInitializationMode
    with fmi2Error and the same problem line, naming contact_point_spacing, its value and the
    smallest spacing this mesh and zone take, which makes as many points as the limit allows."""
    from tire_fmu.core.contact import point_count_problems, points_per_node
    from tire_fmu.core.discretisation import Grid

    limit, spacing = CONSTANTS["MAX_CONTACT_POINTS"], CONSTANTS["MIN_POINT_SPACING_M"]
    zone_length = CONSTANTS["DEFAULT_ZONE_LENGTH_M"]
    grid = Grid(N, TireParameters().R)
    # the carrying nodes, counted here: those whose angle is within the zone's half angle
    half_angle = math.atan(0.5 * zone_length / grid.radius_m)
    carrying = sum(1 for j in range(-N // 2, N // 2 + 1) if abs(j) * grid.dtheta <= half_angle)
    m = 1
    while grid.node_arc_m / m > spacing:
        m += 2
    assert carrying * m > limit
    problem = fmu_message(ParameterError(point_count_problems(grid, zone_length,
                                                              spacing)).problems[0])
    assert problem.startswith(f"contact_point_spacing = {spacing:g} m: must be at least ")
    assert f"{m} points on each of its {carrying} carrying nodes make {carrying * m}" in problem
    results = [_lines(fmu, contact_point_spacing=spacing) for fmu in both]
    assert results == [(ERROR, [M["PROBLEM_LINE"] % (1, 1, problem)])] * 2
    # the smallest spacing named is taken, and makes the most points the limit allows
    smallest = float(re.search(r"must be at least ([0-9.e-]+) m", problem).group(1))
    assert point_count_problems(grid, zone_length, smallest) == []
    most = points_per_node(grid.node_arc_m, smallest)
    assert carrying * most <= limit < carrying * (most + 2)


def test_the_critical_speed_warning_fraction_is_enforced_alike(both):
    """CRITICAL_SPEED_WARNING_FRACTION: above it both FMUs warn with the same text, below it
    neither does."""
    from tire_fmu.core import OperatingPoint, build_model

    critical = build_model(TireParameters(), OperatingPoint(n_elements=N)).critical_speed_m_s
    fraction = CONSTANTS["CRITICAL_SPEED_WARNING_FRACTION"]
    for speed, warned in ((1.01 * fraction * critical, True), (0.99 * fraction * critical,
                                                               False)):
        said = []
        for fmu in both:
            instance = Instance(fmu)
            assert instance.initialise(n_elements=N, speed=speed) == OK
            said.append([m for s, _, m in instance.log if s == 1])
            instance.free()
        assert said[0] == said[1] and bool(said[0]) == warned


def test_every_limit_of_the_spec_that_limits_a_call_has_a_test_here():
    """The constants of spec.CONSTANTS that limit what a host may give, and where each is
    tested in this suite against both FMUs."""
    tested = {**dict.fromkeys(LIMITS, "test_every_parameter_limit_of_the_spec_..."),
              "TIME_ABS_TOLERANCE_S": "test_a_communication_point_within_the_time_tolerance",
              "TIME_REL_TOLERANCE": "test_a_communication_point_within_the_time_tolerance",
              "MAX_STEP_S": "test_bad_steps_are_refused_alike...",
              "MAX_DELAY_STEPS": "test_a_step_too_short_for_the_road_history_at_a_crawl",
              "MIN_CORRECTED_STEP_S": "test_a_step_too_short_for_a_truncated_rings_rate_term",
              "MAX_DISPLACEMENT_M": "test_inputs_at_their_limits / an_input_that_is_not_finite",
              "MAX_VELOCITY_M_S": "test_inputs_at_their_limits / an_input_that_is_not_finite",
              "MAX_HISTORY_SAMPLES": "test_bad_states_are_refused_alike (road history)",
              "MAX_STATE_DISPLACEMENT_M": "test_bad_states_are_refused_alike (modal state)",
              "MAX_STATE_VELOCITY_M_S": "test_bad_states_are_refused_alike (modal state)",
              "CRITICAL_SPEED_WARNING_FRACTION": "test_the_critical_speed_warning_fraction",
              "MAX_SCANNED_SPEED_M_S": "test_a_speed_at_the_critical_speed_is_refused_alike",
              # in test_native_fmu.py, against both FMUs
              "MAX_STEP_WORK": "test_a_step_of_more_work_than_a_step_may_take_is_refused_alike",
              "WORK_INTERVAL_S": "test_a_contact_the_step_cannot_afford_is_refused_alike",
              "MIN_SUBSTEP_S": "test_a_contact_the_step_cannot_afford_is_refused_alike",
              # the spacing's range is the contact_point_spacing variable's, checked with
              # every parameter's range above
              "MIN_POINT_SPACING_M": "test_every_parameter_limit_of_the_spec_...",
              "MAX_POINT_SPACING_M": "test_every_parameter_limit_of_the_spec_...",
              "MAX_CONTACT_POINTS": "test_a_spacing_that_makes_too_many_contact_points_...",
              # in test_kernel_position_road.py, against both step kernels (the FMUs pass
              # the wheel's x to them once they read the road by position, issue 37)
              "MAX_ROAD_POSITION_M": "test_steps_of_the_other_road_are_refused_... / "
                                     "test_states_of_the_other_road_or_beyond_a_hosts_reach_...",
              # in test_inplane_native_fmu.py, against both in-plane FMUs
              "MAX_TORQUE_N_M": "test_an_input_beyond_its_limit_is_refused_alike",
              "INPLANE_CRITICAL_SPEED_FRACTION":
                  "test_a_speed_above_the_critical_fraction_is_refused",
              "INPLANE_MIN_STEP_S": "test_a_step_off_the_tire_grid_is_taken_alike_...",
              "INPLANE_STATE_BASIS_TOLERANCE":
                  "test_a_state_of_another_basis_continues_or_is_refused (both runtimes)",
              # in test_inplane_limits.py, against both in-plane FMUs
              "INPLANE_MAX_FORCE_LOADS": "test_a_rim_jump_the_tire_cannot_carry_is_refused",
              "INPLANE_MAX_ROAD_SAMPLES": "test_a_forged_state_is_refused_at_its_set_...",
              "INPLANE_STATE_DEFORMATION_FRACTION":
                  "test_a_forged_state_is_refused_at_its_set_..."}
    # the rest are numerical rules of the model, not limits of a call
    rules = {"SAME_POINT_EPS", "LAG_SLACK", "MAX_SUBSTEP_S", "SUBSTEP_SLACK", "SERIES_LIMIT",
             "KERNEL_CACHE_SIZE", "ACTIVE_SET_PER_NODE", "ACTIVE_SET_EXTRA", "PGS_SWEEPS",
             "PGS_TOLERANCE", "DEFAULT_ZONE_LENGTH_M", "ZONE_ANGLE_SLACK", "EVENT_TOLERANCE",
             "EVENTS_TOGETHER", "TOUCH_ATOL", "SEGMENTS_PER_NODE", "MAX_DEFLECTION_FRACTION",
             "LENGTH_BISECTIONS", "MODE_TIE_TOLERANCE", "SCAN_POINTS", "ROOT_TOLERANCE",
             "SUBSTEP_WORK_BASE", "SUBSTEP_WORK_PER_MODE", "SUBSTEP_WORK_PER_ORDER_NODE",
             "SUBSTEP_WORK_PER_SUPPORT", "SUBSTEP_WORK_PER_POINT", "SUBSTEP_WORK_PER_NODE_PAIR",
             "SUBSTEP_WORK_PER_RATE_ENTRY", "DEFAULT_POINT_SPACING_M", "POINT_SPACING_SLACK",
             "MOST_POINTS_PER_NODE", "SIDEWALL_TIE_FACTOR", "HYSTERESIS_FULL_SPEED_M_S",
             # the in-plane step's (held to the Python by both FMUs' agreement)
             "INPLANE_MAX_DEFLECTION_FRACTION", "INPLANE_HOST_ROAD_MARGIN_M",
             "INPLANE_SPIN_REBUILD_FRACTION", "INPLANE_RING_REBUILD_FRACTION",
             "INPLANE_MAX_SET_PASSES", "INPLANE_SETTLE_PASSES", "INPLANE_MIN_ENTERING_FRACTION",
             "INPLANE_STATE_SPIN_FACTOR",
             # the wheel centre's (core/wheel_centre.py, both tires): what slip reads at rest,
             # how the road's query points decide a tie, how many there are and how close
             "SLIP_SPEED_FLOOR_M_S", "ROAD_QUERY_SLACK_M", "ROAD_QUERIES",
             "ROAD_QUERY_FLOOR_SHARE"}
    assert set(CONSTANTS) == set(tested) | rules, set(CONSTANTS) ^ (set(tested) | rules)


# -- the model structure ---------------------------------------------------------------------

@pytest.mark.parametrize("speed", [0.0, 10.0])
def test_the_outputs_declare_the_inputs_that_feed_through_and_no_other(fmu, speed):
    """Both FMUs declare, per output, the inputs it depends on directly (interface.py's one
    declaration): every output on every input but the deflection, the rim's and the road's
    positions alone. Checked against what they do: an input set after a step changes, at
    the next read, only the outputs declared to depend on it (once declared nothing, which
    FMI reads as every input)."""
    from fmpy.validation import validate_fmu

    from tire_fmu.fmu.interface import output_dependencies

    expected = {name: list(inputs) for name, inputs in
                output_dependencies(fmu_variables()).items()}
    assert declared_dependencies(fmu.path) == expected
    assert expected["deflection"] == ["rim_z", "road_z"] and len(expected) == 7
    assert validate_fmu(fmu.path) == []
    instance = started(fmu, speed=speed, f_max=300.0)
    by_vr = {v.valueReference: v.name for v in fmu.model_description.modelVariables}
    names = [by_vr[vr] for vr in instance.outputs]
    run_on(instance, 0.0, 20, signal=lambda t: (5e-4, 0.0, 1e-3, 0.0))
    state = instance.slave.getFMUstate()
    instance.slave.setReal(instance.inputs, [5e-4, 0.0, 1e-3, 0.0])  # read as at a new point
    before = instance.outputs_now()
    moved = set()
    for i, name in enumerate(("rim_z", "rim_vz", "road_z", "road_vz")):
        inputs = [5e-4, 0.0, 1e-3, 0.0]
        inputs[i] += 1e-4 if name.endswith("_z") else 0.05
        instance.slave.setReal(instance.inputs, inputs)
        after = instance.outputs_now()
        changed = {out for out, a, b in zip(names, before, after) if a != b}
        assert all(name in expected[out] for out in changed), (name, changed)
        moved |= changed
        instance.slave.setFMUstate(state)
    assert {"rim_Fz", "contact_Fz", "deflection"} <= moved  # it does feed through
    instance.slave.freeFMUstate(state)
    instance.free()
