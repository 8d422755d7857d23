"""TireModal.fmu built once per session and run through fmpy: validation, equality with the
core's stepping kernel, physics seen through the FMU, refusals with status and message (in
this process and in a subprocess), state rollback, several instances, reset."""

import gc
import json
import math
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmpy import extract, read_model_description, simulate_fmu  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import (  # noqa: E402
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.validation import validate_fmu  # noqa: E402

from tire_fmu.core import (  # noqa: E402
    DEFAULT_LOAD_N,
    OperatingPoint,
    TireParameters,
    validate,
)
from tire_fmu.core.contact_dynamics import (  # noqa: E402
    INPUT_NAMES,
    OUTPUT_NAMES,
    ContactSimulator,
    build_contact_model,
)
from tire_fmu.core.frequency_response import ringing_modes, sine_response  # noqa: E402
from tire_fmu.core.io_model import build_io_model  # noqa: E402
from tire_fmu.fmu.builder import SLAVE_MODULE, build_fmu  # noqa: E402

pytestmark = pytest.mark.fmu

N = 40  # elements: accuracy does not matter here, build time does
DISCARD = 2


@pytest.fixture(scope="session")
def fmu_path(tmp_path_factory):
    return build_fmu(tmp_path_factory.mktemp("fmu"))


@pytest.fixture(scope="session")
def unpacked(fmu_path):
    return read_model_description(str(fmu_path)), extract(str(fmu_path))


class Host:
    """An fmpy FMU2Slave with a logger that keeps (status, message), initialised with the
    given parameters (set with the function of their FMI type)."""

    def __init__(self, unpacked, name="tire", initialise=True, **parameters):
        description, folder = unpacked
        self.variables = {v.name: v for v in description.modelVariables}
        self.messages = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        self.fmu = FMU2Slave(guid=description.guid, unzipDirectory=folder,
                             modelIdentifier=description.coSimulation.modelIdentifier,
                             instanceName=name)
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=True)
        self.time = 0.0
        if initialise:
            self.initialise(**parameters)

    def _log(self, environment, instance, status, category, message):
        self.messages.append((status, message.decode()))

    def initialise(self, start_time=0.0, **parameters):
        parameters.setdefault("n_elements", N)
        self.fmu.setupExperiment(startTime=start_time)
        self.fmu.enterInitializationMode()
        self.set(**parameters)
        self.fmu.exitInitializationMode()
        self.time = start_time

    def set(self, **values):
        for name, value in values.items():
            kind = self.variables[name].type
            setter = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
                      "Boolean": self.fmu.setBoolean}[kind]
            setter([self.variables[name].valueReference], [value])

    def get(self, *names):
        return self.fmu.getReal([self.variables[n].valueReference for n in names])

    def step(self, h, rim_z=0.0, rim_vz=0.0, road_z=0.0, road_vz=0.0):
        self.set(rim_z=rim_z, rim_vz=rim_vz, road_z=road_z, road_vz=road_vz)
        self.fmu.doStep(self.time, h)
        self.time += h
        return self.get(*OUTPUT_NAMES)

    def taken(self, status=None):
        found = [m for s, m in self.messages if status is None or s == status]
        self.messages.clear()
        return found

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


@pytest.fixture
def host(unpacked):
    made = []

    def make(**parameters):
        made.append(Host(unpacked, name=f"tire{len(made)}", **parameters))
        return made[-1]

    yield make
    for h in made:
        h.close()


def core_simulator(load=DEFAULT_LOAD_N, speed=0.0):
    tire, op = validate({}, {"n_elements": N, "load_n": load, "speed_m_s": speed})
    contact = build_contact_model(tire, op)
    return ContactSimulator(contact), contact.model


def signals(t):
    """Rim and road motion with their exact velocities: a few mm, 5-80 Hz."""
    rim = 2e-3 * np.sin(2 * np.pi * 7 * t) + 5e-4 * np.sin(2 * np.pi * 80 * t)
    rim_v = 2e-3 * 2 * np.pi * 7 * np.cos(2 * np.pi * 7 * t) \
        + 5e-4 * 2 * np.pi * 80 * np.cos(2 * np.pi * 80 * t)
    road = 3e-3 * np.sin(2 * np.pi * 23 * t) ** 2
    road_v = 3e-3 * 2 * np.pi * 23 * np.sin(2 * np.pi * 46 * t)
    return np.column_stack([rim, rim_v, road, road_v])


def assert_equal_to_core(fmu_outputs, core_outputs):
    np.testing.assert_allclose(fmu_outputs, core_outputs, rtol=1e-12,
                               atol=1e-12 * DEFAULT_LOAD_N)


# -- the package ----------------------------------------------------------------------------

def test_fmpy_validation_finds_no_problem(fmu_path):
    assert validate_fmu(str(fmu_path)) == []


def test_capabilities_units_and_the_shipped_core(fmu_path, unpacked):
    description, _ = unpacked
    cs = description.coSimulation
    assert cs.modelIdentifier == "TireModal"
    assert cs.canHandleVariableCommunicationStepSize and cs.canGetAndSetFMUstate
    assert cs.canSerializeFMUstate and not cs.providesDirectionalDerivative
    units = {v.name: v.unit for v in description.modelVariables}
    assert units["rim_Fz"] == "N" and units["load"] == "N" and units["speed"] == "m/s"
    assert {u.name for u in description.unitDefinitions} >= {"N", "m", "m/s", "Hz", "Pa"}
    outputs = {u.variable.name for u in description.initialUnknowns}
    assert outputs == {*OUTPUT_NAMES, "in_contact"}
    with zipfile.ZipFile(fmu_path) as archive:
        names = set(archive.namelist())
        requirements = archive.read("resources/requirements.txt").decode()
        module = archive.read("resources/slavemodule.txt").decode().strip()
    assert {"resources/tire_fmu/__init__.py", "resources/tire_fmu/core/contact_dynamics.py",
            "resources/tire_fmu/fmu/interface.py", f"resources/{SLAVE_MODULE}.py"} <= names
    # the core and the variable table only: no CLI, no builder, no slave twice, no caches
    shipped_fmu = {n for n in names if "/tire_fmu/fmu/" in n}
    assert shipped_fmu == {"resources/tire_fmu/fmu/__init__.py",
                           "resources/tire_fmu/fmu/interface.py",
                           "resources/tire_fmu/fmu/spec.py"}  # the wording both FMUs share
    assert not any("/cli/" in n or "__pycache__" in n for n in names)
    assert module == SLAVE_MODULE and module.startswith("tire_fmu_modal_slave_")
    assert "numpy" in requirements and "scipy" in requirements


def test_the_command_line_and_build_fmu_py_build_it_too(tmp_path, capsys):
    from tire_fmu.cli import main

    # OUT is the file (as for export), or an existing folder to hold TireModal.fmu
    target = tmp_path / "my_tire.fmu"
    assert main(["build-fmu", str(target), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert Path(data["path"]) == target and target.is_file()
    assert data["validated_with_fmpy"] and validate_fmu(data["path"]) == []
    repo = Path(__file__).resolve().parents[1]
    done = subprocess.run([sys.executable, "build_fmu.py", "-o", str(tmp_path / "script")],
                          cwd=repo, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert Path(done.stdout.strip()) == tmp_path / "script" / "TireModal.fmu"
    assert validate_fmu(done.stdout.strip()) == []


# -- equal to the core ----------------------------------------------------------------------

@pytest.mark.parametrize("speed", [0.0, 12.0])
def test_a_hand_written_loop_equals_the_core_kernel(host, speed):
    tire = host(speed=speed)
    core, _ = core_simulator(speed=speed)
    h = 1e-4
    inputs = signals(np.arange(400) * h)
    assert_equal_to_core([tire.step(h, *u) for u in inputs],
                         [core.step(h, *u) for u in inputs])
    assert not tire.taken(status=3)


def test_simulate_fmu_equals_the_core_kernel(fmu_path):
    h, steps = 1e-3, 300
    t = np.arange(steps + 1) * h
    inputs = signals(t)
    table = np.zeros(t.size, dtype=[("time", float)] + [(n, float) for n in INPUT_NAMES])
    table["time"] = t
    for i, name in enumerate(INPUT_NAMES):
        table[name] = inputs[:, i]
    logged = []
    result = simulate_fmu(str(fmu_path), start_values={"n_elements": N}, input=table,
                          output=list(OUTPUT_NAMES), output_interval=h, stop_time=t[-1],
                          debug_logging=True,
                          logger=lambda *args: logged.append((args[2], args[4].decode())))
    core, _ = core_simulator()
    # fmpy sets the inputs of t = 0 during initialisation and samples before the first step:
    # the statics plus the direct feedthrough of those inputs (rim velocity on the dampers)
    first = core.outputs_with(*inputs[0])
    assert abs(first[0] - core.static_ring[0]) > 100.0
    expected = [core.step(h, *u) for u in inputs[:-1]]
    fmu_outputs = np.column_stack([result[n] for n in OUTPUT_NAMES])
    assert fmu_outputs.shape[0] == steps + 1
    assert_equal_to_core(fmu_outputs[0], first)
    assert_equal_to_core(fmu_outputs[1:], expected)
    assert any("TireModal ready" in m for _, m in logged)


# -- physics through the FMU ----------------------------------------------------------------

def _smooth_lift(t, height, duration):
    """0 -> height over ``duration`` with zero velocity and acceleration at both ends."""
    s = np.clip(t / duration, 0.0, 1.0)
    ds = np.where((t > 0) & (t < duration), 1.0 / duration, 0.0)
    return height * (10 * s**3 - 15 * s**4 + 6 * s**5), height * 30 * (s**2 - 2 * s**3 + s**4) * ds


def test_rim_and_road_moving_together_leave_the_rim_force_static(host):
    together, rim_only = host(), host()
    static = together.get("rim_Fz")[0]
    h, height = 1e-3, 5e-3
    t = np.arange(0.0, 1.5, h)
    z, v = _smooth_lift(t, height, 0.5)
    both = np.array([together.step(h, zi, vi, zi, vi)[0] for zi, vi in zip(z, v)])
    alone = np.array([rim_only.step(h, zi, vi)[0] for zi, vi in zip(z, v)])
    # moving the rim alone by 5 mm changes the rim force by about K·5 mm ~ 7 kN ...
    assert abs(alone[-1] - static) > 0.2 * static
    # ... together with the road only the tire's own inertia shows, at most its mass times
    # the peak acceleration (about 14 N here), and at rest at the new height the force is
    # the static load again
    tire = TireParameters()
    mass_kg = (tire.rhoA + tire.m_s) * tire.circumference_m
    peak_acceleration = 10 / math.sqrt(3) * height / 0.5**2
    assert np.abs(both - static).max() < mass_kg * peak_acceleration
    assert abs(both[-1] - static) < 1e-6 * static


def test_static_stiffness_through_the_fmu_is_the_models(host):
    tire = host()
    _, model = core_simulator()
    static = tire.get("rim_Fz")[0]
    dz, h = 1e-4, 1e-2  # rim 0.1 mm down, held, road fixed; long steps are substepped
    for _ in range(300):  # 3 s: the slowest mode (~50 Hz, 2 % damping) has long settled
        force = tire.step(h, rim_z=-dz)[0]
    previous = force
    force = tire.step(h, rim_z=-dz)[0]
    assert abs(force - previous) < 1e-9 * static  # steady
    stiffness = (force - static) / dz
    assert stiffness == pytest.approx(model.static_vertical_stiffness_n_per_m, rel=1e-7)


# -- refusals: status, message, and a host that carries on ----------------------------------

def _refused(tire, function, *args):
    with pytest.raises(FMICallException) as caught:
        function(*args)
    # pythonfmu releases a slave whose method raised but keeps using it: after a garbage
    # collection the next call would crash this process. The slave never raises.
    gc.collect()
    return caught.value.status


def test_rejected_parameters_log_every_problem_and_steps_are_discarded(host):
    tire = host(R=-1.0, n_elements=3, load=math.nan)  # exitInitializationMode: fmi2OK
    problems = [m for m in tire.taken(status=3) if "parameter problem" in m]
    assert len(problems) == 3
    assert any("R = -1" in p for p in problems) and any("n_elements = 3" in p for p in problems)
    assert any("load = nan" in p for p in problems)
    assert _refused(tire, tire.fmu.doStep, 0.0, 1e-3) == DISCARD
    (message,) = tire.taken(status=DISCARD)
    assert "rejected" in message and "n_elements = 3" in message


def test_a_speed_at_the_critical_speed_is_rejected(host):
    tire = host(speed=1000.0)
    assert any("critical (standing-wave) speed" in m for m in tire.taken(status=3))
    assert _refused(tire, tire.fmu.doStep, 0.0, 1e-3) == DISCARD


@pytest.mark.parametrize("case,message", [
    ("nan input", "rim_z = nan m: must be in"),
    ("inf input", "road_vz = inf m/s: must be in"),
    ("zero h", "step size h = 0.0 s: must be finite and > 0"),
    ("negative h", "step size h = -0.001 s: must be finite and > 0"),
    ("wrong time", "the last communication point is t = 0.001 s"),
])
def test_bad_steps_are_discarded_with_their_message_and_the_host_retries(host, case, message):
    tire = host()
    expected = tire.step(1e-3, rim_z=1e-3)
    t, h = 1e-3, 1e-3
    if case == "nan input":
        tire.set(rim_z=math.nan)
    elif case == "inf input":
        tire.set(road_vz=math.inf)
    elif case == "zero h":
        h = 0.0
    elif case == "negative h":
        h = -1e-3
    else:
        t = 0.5
    tire.taken()
    assert _refused(tire, tire.fmu.doStep, t, h) == DISCARD
    (logged,) = tire.taken(status=DISCARD)
    assert message in logged and "state unchanged" in logged
    assert tire.get(*OUTPUT_NAMES) == expected  # nothing moved
    tire.step(1e-3, rim_z=1e-3)  # fixed and retried: accepted


def test_parameters_cannot_change_after_initialisation(host):
    tire = host()
    tire.set(load=1.0)  # fmi2OK (pythonfmu cannot refuse a set) but ignored and logged
    assert tire.get("load") == [pytest.approx(DEFAULT_LOAD_N)]
    assert any("fixed after initialisation" in m for m in tire.taken(status=3))


def test_bad_cases_in_a_fresh_process_leave_it_alive(fmu_path):
    """Only fmpy is imported, so the slave also has to find its core in resources/."""
    script = textwrap.dedent('''
        import gc, json, math, sys
        from fmpy import extract, read_model_description
        from fmpy.fmi1 import FMICallException
        from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
        path = sys.argv[1]
        md = read_model_description(path)
        folder = extract(path)
        refs = {v.name: v.valueReference for v in md.modelVariables}
        log = []
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda env, name, status, category, msg: log.append((status, msg.decode())))
        statuses = {}

        def attempt(label, function, *args):
            try:
                function(*args)
                statuses[label] = 0
            except FMICallException as error:
                statuses[label] = error.status
            gc.collect()  # a released slave would crash the next call

        fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder, instanceName="bad",
                        modelIdentifier=md.coSimulation.modelIdentifier)
        fmu.instantiate(callbacks=callbacks, loggingOn=True)
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setReal([refs["R"], refs["speed"]], [-1.0, math.inf])
        attempt("exit", fmu.exitInitializationMode)
        attempt("step", fmu.doStep, 0.0, 1e-3)
        attempt("state", fmu.setFMUstate, fmu.deSerializeFMUstate(b"not a state"))
        attempt("reset", fmu.reset)
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setInteger([refs["n_elements"]], [40])
        attempt("exit again", fmu.exitInitializationMode)
        fmu.setReal([refs["rim_z"]], [math.nan])
        attempt("nan", fmu.doStep, 0.0, 1e-3)
        fmu.setReal([refs["rim_z"]], [1e-3])
        attempt("good", fmu.doStep, 0.0, 1e-3)
        fmu.terminate()
        fmu.freeInstance()
        print(json.dumps({"statuses": statuses, "log": log, "alive": True}))
    ''')
    done = subprocess.run([sys.executable, "-c", script, str(fmu_path)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["alive"]
    assert report["statuses"] == {"exit": 0, "step": DISCARD, "state": 0, "reset": 0,
                                  "exit again": 0, "nan": DISCARD, "good": 0}
    log = [message for _, message in report["log"]]
    assert any("R = -1" in m for m in log) and any("speed = inf" in m for m in log)
    assert any("fmi2SetFMUstate refused" in m for m in log)
    assert any("rim_z = nan m: must be in" in m for m in log)
    ready = [m for m in log if "TireModal ready" in m]
    assert ready and "/resources/tire_fmu/__init__.py" in ready[0]  # the shipped core


# -- state, instances, reset ----------------------------------------------------------------

def test_state_rollback_reproduces_a_step_exactly_also_when_serialized(host):
    tire = host()
    for u in signals(np.arange(30) * 1e-3):
        tire.step(1e-3, *u)
    state = tire.fmu.getFMUstate()
    saved = tire.fmu.serializeFMUstate(state)
    t_saved = tire.time
    future = signals(0.03 + np.arange(5) * 1e-3)
    first = [tire.step(1e-3, *u) for u in future]
    tire.fmu.setFMUstate(state)
    tire.time = t_saved
    assert [tire.step(1e-3, *u) for u in future] == first
    restored = tire.fmu.deSerializeFMUstate(saved)
    tire.fmu.setFMUstate(restored)
    tire.time = t_saved
    assert [tire.step(1e-3, *u) for u in future] == first
    tire.fmu.freeFMUstate(state)
    tire.fmu.freeFMUstate(restored)
    # and into another, never initialised instance
    other = host(initialise=False)
    other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(saved))
    other.time = t_saved
    assert [other.step(1e-3, *u) for u in future] == first


def test_two_instances_with_different_loads_give_their_own_answers(host):
    light, heavy = host(load=15_000.0), host(load=30_000.0)
    inputs = signals(np.arange(50) * 1e-3)
    for tire, load in ((light, 15_000.0), (heavy, 30_000.0)):
        core, _ = core_simulator(load=load)
        assert tire.get("rim_Fz")[0] == pytest.approx(load, rel=1e-6)
        assert_equal_to_core([tire.step(1e-3, *u) for u in inputs],
                             [core.step(1e-3, *u) for u in inputs])


def test_reset_returns_to_the_start_and_takes_new_parameters(host):
    tire = host()
    tire.step(1e-3, rim_z=1e-3)
    tire.fmu.reset()
    assert tire.get("load") == [pytest.approx(DEFAULT_LOAD_N)]
    tire.initialise(start_time=2.5, load=20_000.0)  # the first step starts at the start time
    core, _ = core_simulator(load=20_000.0)
    assert_equal_to_core(tire.step(1e-3, rim_z=1e-3), core.step(1e-3, 1e-3, 0, 0, 0))


# -- the unilateral contact at small amplitude: the linearised loaded model -----------------

def _sine_response(tire, source, f_hz, transients, amplitude=1e-4, h=1e-4):
    """rim_Fz and contact_Fz per metre of a 0.1 mm sine of the rim or the road, through the
    FMU: a host that sets the inputs of each new point before reading the outputs there.
    The sine starts at t = 0; the fit takes the tire's own slowly decaying modes
    (``transients``: their eigenvalues) alongside the sine, so no run waits for them."""
    w = 2 * np.pi * f_hz
    fit_s = max(0.25, 1.0 / f_hz)
    n = int(round((0.1 + fit_s) / h))

    def inputs(t):
        z, v = amplitude * np.sin(w * t), amplitude * w * np.cos(w * t)
        return (z, v, 0.0, 0.0) if source == "rim" else (0.0, 0.0, z, v)

    names = [tire.variables[k].valueReference for k in INPUT_NAMES]
    out_refs = [tire.variables[k].valueReference for k in ("rim_Fz", "contact_Fz")]
    fmu = tire.fmu
    ys = np.empty((n, 2))
    for i in range(n):
        t = i * h
        fmu.setReal(names, list(inputs(t)))
        fmu.doStep(t, h)
        fmu.setReal(names, list(inputs(t + h)))
        ys[i] = fmu.getReal(out_refs)
    t = (np.arange(n) + 1) * h
    keep = t > 0.1
    return sine_response(t[keep], ys[keep], w, transients) / amplitude


@pytest.mark.slow
@pytest.mark.parametrize("speed", [0.0, 10.0])
def test_small_amplitude_sines_follow_the_linearised_loaded_model(host, speed):
    """0.1 mm sines of the rim and of the road, 2-300 Hz, through the FMU: the unilateral
    contact then keeps its static footprint, and rim_Fz and contact_Fz follow the FRF of the
    model linearised about that footprint within 1 % in magnitude."""
    model = build_contact_model(TireParameters(), OperatingPoint(speed_m_s=speed)).model
    io = build_io_model(model)
    transients = ringing_modes(io.a.toarray())
    for source in ("rim", "road"):
        for f_hz in (2.0, 20.0, 57.0, 120.0, 185.0, 300.0):
            measured = _sine_response(host(n_elements=100, speed=speed), source, f_hz,
                                      transients)
            expected = io.frequency_response(source, [f_hz])[[0, 2], 0]
            error = np.abs(np.abs(measured) / np.abs(expected) - 1)
            assert error.max() < 0.01, (source, f_hz, error)
