"""Issue 19 through fmpy on both FMUs (the Python FMU and the native C FMU): outputs that do
not depend on the start time, steps and start times the clock cannot resolve refused, long
runs that keep time, forged states refused for what they mean, and one meaning of
"deflection"."""

from __future__ import annotations

import dataclasses
import math
import struct

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from native_support import OUTPUTS, Instance, Opened, relative_errors

from tire_fmu.core import OperatingPoint, TireParameters, build_model
from tire_fmu.fmu.interface import MAX_HISTORY_SAMPLES
from tire_fmu.fmu.slave import TireModal

pytestmark = pytest.mark.fmu

LAST_SUCCESSFUL_TIME = 2  # fmi2LastSuccessfulTime


@pytest.fixture(scope="module", params=["python", "native"])
def fmu(request, python_fmu_path, native_fmu_path):
    return Opened.of(python_fmu_path if request.param == "python" else native_fmu_path)


@pytest.fixture(scope="module")
def both(python_fmu_path, native_fmu_path):
    return Opened.of(python_fmu_path), Opened.of(native_fmu_path)


def _road(t):
    """A 15 Hz road of 5 mm and a 1 cm step up at 20 ms."""
    w = 2 * math.pi * 15
    return (0.0, 0.0, 0.005 * math.sin(w * t) + (0.01 if t >= 0.02 else 0.0),
            0.005 * w * math.cos(w * t))


def _run(fmu, start, steps, h, accumulate=False, speed=20.0):
    """Outputs after each step of a host that passes start + k·h (or adds h to its t)."""
    instance = Instance(fmu, logging_on=False)
    assert instance.initialise(start_time=start, speed=speed) == 0, instance.errors()
    rows, t = [], start
    for k in range(steps):
        if not accumulate:
            t = start + k * h
        instance.slave.setReal(instance.inputs, list(_road(k * h)))
        assert instance.step(t, h) == 0, instance.errors()
        rows.append(instance.outputs_now())
        t += h
    last = instance.slave.getRealStatus(LAST_SUCCESSFUL_TIME)
    instance.free()
    return np.array(rows), last


# -- the start time ------------------------------------------------------------------------------

def test_outputs_at_any_start_time_are_those_from_zero_on_both_fmus(both):
    """Issue 19: at 20 m/s the outputs depended on the start time (0.76 N apart at 1e6 s,
    1.3-4 kN at 1.7e9 s, 13 kN at 1e12 s), in both FMUs. They now agree to the tolerance the
    two FMUs agree to at t = 0 (in fact bit for bit)."""
    h = 2.5e-4  # resolved up to 2.2e12 s; 1e-4 s is not at 1e12 s (refused: below)
    python, native = both
    runs = {(fmu.path, start): _run(fmu, start, 300, h)[0]
            for fmu in (python, native) for start in (0.0, 1e6, 1.7e9, 1e12)}
    across = relative_errors(runs[python.path, 0.0], runs[native.path, 0.0]).max()
    assert across < 1e-9
    for (path, start), rows in runs.items():
        errors = relative_errors(runs[path, 0.0], rows)
        assert errors.max() <= max(across, 1e-12), (path, start, dict(zip(OUTPUTS, errors)))


def test_a_step_below_the_clocks_resolution_is_refused_alike_and_changes_nothing(both):
    """h = 1e-4 s at t = 1e12 s is shorter than the spacing of doubles there (1.22e-4 s); from
    1e15 s the clock stood still and every step returned OK. Both FMUs refuse it with the same
    message naming the shortest step and the latest time, and take a resolved step after."""
    reasons = []
    for fmu in both:
        instance = Instance(fmu)
        assert instance.initialise(start_time=1e12, speed=20.0) == 0
        before = instance.outputs_now()
        assert instance.step(1e12, 1e-4) == 3
        reasons.append(instance.errors()[-1])
        assert instance.outputs_now() == before
        assert instance.step(1e12, 2.5e-4) == 0
        assert instance.slave.getRealStatus(LAST_SUCCESSFUL_TIME) == 1e12 + 2.5e-4
        instance.free()
    assert reasons[0] == reasons[1]
    assert reasons[0] == (
        "fmi2DoStep(t = 1000000000000.0 s, h = 0.0001 s) refused: step size h = 0.0001 s at "
        "t = 1000000000000.0 s: shorter than the resolution of the clock there (0.000122 s "
        "between one double and the next), so the communication points would not advance by "
        "h; take steps of at least 0.000122 s, or run at times below 5.498e+11 s (a start "
        "time nearer 0); nothing changed")


def test_a_start_time_where_no_step_is_resolved_is_refused_alike(both):
    reasons = []
    for fmu in both:
        instance = Instance(fmu)
        with pytest.raises(FMICallException):
            instance.slave.setupExperiment(startTime=1e16)
        reasons.append(instance.errors()[-1])
        instance.slave.setupExperiment(startTime=-1.7e9)  # nothing changed: set it now
        instance.slave.enterInitializationMode()
        assert instance.call("fmi2ExitInitializationMode") == 0
        assert instance.step(-1.7e9, 1e-4) == 0
        instance.free()
    assert reasons[0] == reasons[1] == (
        "fmi2SetupExperiment refused: startTime = 1e+16 s: must be at most 9.007e+15 s in "
        "magnitude: beyond it a clock of doubles resolves no step the FMU takes (at most 1 s); "
        "nothing changed")


@pytest.mark.parametrize("steps", [20_000])
def test_a_long_run_from_an_epoch_start_keeps_time_and_gives_the_outputs_from_zero(fmu,
                                                                                  steps):
    """A host that adds h to its t at an epoch clock drifts (each sum rounds to 2.4e-7 s);
    the FMU sums its steps itself, so it stays at start + k·h and its outputs after 2 s are
    those of the same run from 0 (the FMU took the host's t as its clock before)."""
    h, start = 1e-4, 1.7e9
    late, late_time = _run(fmu, start, steps, h, accumulate=True)
    early, _ = _run(fmu, 0.0, steps, h)
    assert relative_errors(early, late).max() <= 1e-12
    if "Native" in fmu.path:  # pythonfmu's wrapper reports the host's t + h itself
        assert abs(late_time - (start + steps * h)) <= math.ulp(start)


# -- forged states -----------------------------------------------------------------------------

def _native_state(data: bytes, n_values: int):
    """Where things are in a native FMU state (fmi2_layer.c, tire_model.c's two flags, then
    kernel.c's state)."""
    head = 8 + 4 + 4 + 48 + 8
    model = head + 8 + 8 + 4 + 4 + 8 * n_values + 8
    k, z, history = struct.unpack_from("<3i", data, model + 8)
    doubles = model + 6 * 4
    at = {"time": head, "start": head + 8, "values": head + 24, "model_start": doubles,
          "q": doubles + 8 * 15, "t": doubles + 8 * (15 + 2 * k + 5 * z)}
    return at, history, z


def _fnv1a(data: bytes) -> int:
    value = 14695981039346656037
    for byte in data:
        value = ((value ^ byte) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return value


def _native_forged(data: bytes, n_values: int, vr: dict, case: str) -> bytes:
    at, history, _ = _native_state(data, n_values)
    data = bytearray(data)

    def put(offset, value):
        data[offset:offset + 8] = struct.pack("<d", value)

    if case == "header time 1e300":
        put(at["time"], 1e300)
    elif case == "time 1e300 throughout":
        put(at["time"], 1e300)
        put(at["start"], 1e300)
        put(at["model_start"], 1e300)
    elif case == "road sample in the future":
        put(at["t"] + 8 * (history - 1), 1.0)
    elif case == "road history too long":
        count = MAX_HISTORY_SAMPLES + 1
        arrays = np.concatenate([np.linspace(-1.0, 0.0, count), np.zeros(2 * count)])
        data[at["t"]:at["t"] + 24 * history] = arrays.astype("<f8").tobytes()
        model = at["model_start"] - 6 * 4  # its ints: two flags, then K, P, history length
        data[model + 16:model + 20] = struct.pack("<i", count)
        size_at = at["values"] + 8 * n_values  # the model part's size, then the total
        model_size = struct.unpack_from("<Q", data, size_at)[0]
        data[size_at:size_at + 8] = struct.pack("<Q", model_size + 24 * (count - history))
        data[64:72] = struct.pack("<Q", len(data))
    elif case == "modal state 1e300":
        put(at["q"], 1e300)
    elif case == "outputs 3e307":
        put(at["values"] + 8 * vr["rim_Fz"], 3e307)
    data[-8:] = struct.pack("<Q", _fnv1a(bytes(data[:-8])))
    return bytes(data)


def _python_forged(data: bytes, case: str) -> bytes:
    state = TireModal._fmu_state_from_bytes(data)
    sim = state.simulator
    if case == "header time 1e300":
        state = dataclasses.replace(state, start_time=1e300)
    elif case == "time 1e300 throughout":
        state = dataclasses.replace(state, start_time=1e300,
                                    simulator=sim.replaced(start_time=1e300))
    elif case == "road sample in the future":
        t = sim.history_t.copy()
        t[-1] = 1.0
        state = dataclasses.replace(state, simulator=sim.replaced(history_t=t))
    elif case == "road history too long":
        count = MAX_HISTORY_SAMPLES + 1
        state = dataclasses.replace(state, simulator=sim.replaced(
            history_t=np.linspace(-1.0, 0.0, count), history_z=np.zeros(count),
            history_v=np.zeros(count)))
    elif case == "modal state 1e300":
        q = sim.q.copy()
        q[0] = 1e300
        state = dataclasses.replace(state, simulator=sim.replaced(q=q))
    elif case == "outputs 3e307":
        values = list(state.values)
        values[4] = 3e307  # rim_Fz
        state = dataclasses.replace(state, values=tuple(values))
    return TireModal._fmu_state_to_bytes(state)


FORGED = {  # case: what each FMU's refusal names
    "header time 1e300": ("start time is 1e+300 s, but its simulator started at 0.0 s",
                          "its time is 1e+300 s from a start at 0.0 s, but its model is at"),
    "time 1e300 throughout": ("startTime = 1e+300 s: must be at most 9.007e+15 s",) * 2,
    "road sample in the future": ("its newest road sample is at 1.0 s, but the state is at",)
    * 2,
    "road history too long": (f"its road history holds {MAX_HISTORY_SAMPLES + 1} samples; "
                              f"the FMU keeps at most {MAX_HISTORY_SAMPLES}",) * 2,
    "modal state 1e300": ("the tread's excursion at the zone nodes from a mode reach",) * 2,
    "outputs 3e307": ("the outputs it shows",) * 2,
}


@pytest.mark.parametrize("case", list(FORGED))
def test_a_forged_state_with_a_recomputed_checksum_is_refused_for_what_it_means(fmu, case):
    """Issue 19: states whose checksum was recomputed were accepted with times of 1e300 (the
    clock then stalled), road histories with wrong times or 2e6 samples, modal states of
    1e300 (outputs of 3e307 with status OK). Each is now fmi2Error with the reason logged,
    and the instance runs on exactly as one that never saw it."""
    native = "Native" in fmu.path
    undisturbed, disturbed = Instance(fmu), Instance(fmu)
    rows = {}
    for instance in (undisturbed, disturbed):
        assert instance.initialise(speed=20.0) == 0
        for k in range(300):
            instance.slave.setReal(instance.inputs, list(_road(k * 1e-4)))
            assert instance.step(k * 1e-4) == 0
    # taking a state settles the native FMU's pending force ramp into its modes (a rounding
    # of its own): both take one here
    undisturbed.slave.serializeFMUstate(undisturbed.slave.getFMUstate())
    data = bytes(disturbed.slave.serializeFMUstate(disturbed.slave.getFMUstate()))
    forged = (_native_forged(data, len(fmu.model_description.modelVariables), disturbed.vr,
                             case) if native else _python_forged(data, case))
    before = disturbed.outputs_now()
    with pytest.raises(FMICallException):
        disturbed.slave.setFMUstate(disturbed.slave.deSerializeFMUstate(forged))
    reason = disturbed.errors()[-1]
    # refused where it is found: at fmi2DeSerializeFMUstate, or at fmi2SetFMUstate
    assert "FMUstate refused: " in reason and FORGED[case][native] in reason, reason
    assert disturbed.outputs_now() == before
    for k in range(300, 400):
        for instance, out in ((undisturbed, "a"), (disturbed, "b")):
            instance.slave.setReal(instance.inputs, list(_road(k * 1e-4)))
            assert instance.step(k * 1e-4) == 0
            rows.setdefault(out, []).append(instance.outputs_now())
    assert rows["a"] == rows["b"]
    undisturbed.free()
    disturbed.free()


# -- deflection ----------------------------------------------------------------------------------

def test_deflection_is_the_rims_lowering_and_tread_deflection_the_treads_in_both_fmus(fmu):
    """Issue 19: "deflection" was the rim's lowering in `patch` (18.66 mm) and the tread's
    compression in the FMU (18.17 mm). The FMU's deflection is now the rim's lowering at the
    contact centre (the footprint's, plus the road's rise there, less rim_z); the tread's
    compression relative to the rim is tread_deflection."""
    patch = build_model(TireParameters(), OperatingPoint()).patch
    instance = Instance(fmu)
    assert instance.initialise() == 0
    vr = instance.vr
    deflection, tread = instance.slave.getReal([vr["deflection"], vr["tread_deflection"]])
    assert deflection == patch.deflection_m and 0.0186 < deflection < 0.0187
    assert tread == pytest.approx(patch.centre_compression_m, rel=1e-12) and \
        0.0181 < tread < 0.0182
    rim_z, road_z, road_vz, h = -1e-3, 2e-3, 0.05, 1e-4
    instance.slave.setReal(instance.inputs, [rim_z, 0.0, road_z, road_vz])
    assert instance.step(0.0, h) == 0  # at rest the whole zone reads the road at once
    deflection, tread = instance.slave.getReal([vr["deflection"], vr["tread_deflection"]])
    assert deflection == pytest.approx(patch.deflection_m + road_z + h * road_vz - rim_z,
                                       abs=1e-15)
    assert tread > patch.centre_compression_m + 1e-4  # pressed further: the tread gives too
    instance.slave.setReal(instance.inputs, [0.1, 0.0, 0.0, 0.0])  # lifted clear
    assert instance.step(h, h) == 0
    deflection, contact = instance.slave.getReal([vr["deflection"], vr["contact_Fz"]])
    assert deflection == pytest.approx(patch.deflection_m - 0.1, abs=1e-15) and contact == 0.0
    instance.free()
