"""The native (C) FMU: built from a reduced model, run through fmpy and held against the Python
FMU, TireModal.fmu, which is the reference (same variables, same numbers to 1e-9 relative).

Everything is built once per session on small meshes (N = 48): a native FMU at rest and one at
10 m/s (whose patch has several road delay groups, so the delay line runs), and the Python FMU.
"""

from __future__ import annotations

import ctypes
import json
import re
import shutil
import zipfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
from fmpy import extract, read_model_description, simulate_fmu  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import (  # noqa: E402
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2Terminated,
    fmi2True,
)
from fmpy.validation import validate_fmu  # noqa: E402

from tire_fmu.cli import main  # noqa: E402
from tire_fmu.core.model import build_model  # noqa: E402
from tire_fmu.core.parameters import DEFAULT_LOAD_N, validate  # noqa: E402
from tire_fmu.core.reduction import ReductionSettings, reduce  # noqa: E402
from tire_fmu.fmu.interface import fmu_variables  # noqa: E402
from tire_fmu.native import build_native_fmu, codegen, native_model  # noqa: E402
from tire_fmu.native.builder import compile_sources  # noqa: E402

pytestmark = pytest.mark.fmu

N_ELEMENTS = 48
SPEEDS = (0.0, 10.0)
INPUTS = ("rim_z", "rim_vz", "road_z", "road_vz")
OUTPUTS = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection")
DISCARD, ERROR, WARNING = 2, 3, 1
#: Variable communication steps, cycled (fmpy-style accumulated time adds its own jitter).
STEPS = (1e-4, 2.5e-4, 1e-4, 5e-5, 3e-4, 1e-4)


@dataclass(frozen=True)
class Export:
    reduced: object
    native: codegen.NativeModel
    path: Path


@pytest.fixture(scope="session")
def exports(tmp_path_factory) -> dict[float, Export]:
    folder = tmp_path_factory.mktemp("native")
    built = {}
    for speed in SPEEDS:
        tire, op = validate({}, {"n_elements": N_ELEMENTS, "load_n": DEFAULT_LOAD_N,
                                 "speed_m_s": speed})
        reduced = reduce(build_model(tire, op), ReductionSettings(), report=False)
        path = build_native_fmu(reduced, folder / f"tire_{speed:g}.fmu", op)
        built[speed] = Export(reduced, native_model(reduced, op), path)
    return built


@pytest.fixture(scope="session")
def python_fmu(tmp_path_factory) -> Path:
    pytest.importorskip("pythonfmu")
    from tire_fmu.fmu.builder import build_fmu

    return build_fmu(tmp_path_factory.mktemp("python_fmu"))


_EXTRACTED: dict[Path, str] = {}
_HOSTS: dict[int, Host] = {}


def _route_message(environment, name, status, category, message):
    _HOSTS[environment].messages.append((status, message.decode()))


# fmpy's logger proxy (which formats the FMU's printf-style messages) keeps one logger for the
# whole process, so every host registers this one and the component environment says whose
# message it is.
_LOGGER = fmi2CallbackLoggerTYPE(_route_message)


class Host:
    """An fmpy co-simulation master for one instance, keeping every logged message."""

    def __init__(self, fmu: Path, name: str = "tire", logging_on: bool = False,
                 parameters: dict | None = None, initialise: bool = True):
        fmu = Path(fmu)
        if fmu not in _EXTRACTED:
            _EXTRACTED[fmu] = extract(str(fmu))
        self.md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.inputs = [self.vr[n] for n in INPUTS]
        self.outputs = [self.vr[n] for n in OUTPUTS]
        self.messages: list[tuple[int, str]] = []
        key = len(_HOSTS) + 1
        _HOSTS[key] = self
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = _LOGGER
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        self._callbacks.componentEnvironment = ctypes.c_void_p(key)
        from fmpy.logging import addLoggerProxy

        addLoggerProxy(ctypes.byref(self._callbacks))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=_EXTRACTED[fmu],
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=name)
        self.fmu.instantiate(callbacks=self._callbacks, loggingOn=logging_on)
        self.time = 0.0
        if initialise:
            self.initialise(parameters)

    def initialise(self, parameters: dict | None = None) -> None:
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in (parameters or {}).items():
            self.set(name, value)
        self.fmu.exitInitializationMode()
        self.time = 0.0

    def set(self, name: str, value) -> None:
        vr = [self.vr[name]]
        if isinstance(value, bool):
            self.fmu.setBoolean(vr, [value])
        elif isinstance(value, int):
            self.fmu.setInteger(vr, [value])
        else:
            self.fmu.setReal(vr, [value])

    def step(self, h: float, u) -> list[float]:
        self.fmu.setReal(self.inputs, list(u))
        self.fmu.doStep(self.time, h)
        self.time += h
        return self.fmu.getReal(self.outputs)

    def raw_step(self, t: float, h: float) -> int:
        """doStep's status, which fmpy's doStep neither returns nor raises below discard."""
        try:
            return self.fmu.fmi2DoStep(self.fmu.component, t, h, fmi2True)
        except FMICallException as failure:
            return failure.status

    def problems(self) -> list[str]:
        return [m for s, m in self.messages if s > 0]

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def excitation(kind: str, n: int):
    """(steps, inputs): a 37 Hz sine plus a 4 mm bump on the rim or the road, with the
    velocities that belong to them, over variable steps."""
    steps = np.array([STEPS[i % len(STEPS)] for i in range(n)])
    t = np.concatenate([[0.0], np.cumsum(steps)[:-1]])
    w = 2 * np.pi * 37.0
    bump = np.where((t > 0.01) & (t < 0.03), 0.5 * (1 - np.cos(2 * np.pi * (t - 0.01) / 0.02)), 0)
    bump_v = np.where((t > 0.01) & (t < 0.03),
                      0.5 * np.sin(2 * np.pi * (t - 0.01) / 0.02) * 2 * np.pi / 0.02, 0)
    z = 1e-3 * np.sin(w * t) + 4e-3 * bump
    v = 1e-3 * w * np.cos(w * t) + 4e-3 * bump_v
    zero = np.zeros(n)
    u = np.column_stack([z, v, zero, zero] if kind == "rim" else [zero, zero, z, v])
    return steps, u


def run(host: Host, steps, u) -> np.ndarray:
    return np.array([host.step(h, row) for h, row in zip(steps, u)])


def relative_difference(y: np.ndarray, reference: np.ndarray, static: np.ndarray) -> float:
    """Largest difference relative to the size of the dynamic response: forces against the
    largest force deviation (rim_Fx is zero by symmetry at rest), deflection against its own."""
    deviation = np.abs(reference - static)
    force_scale = deviation[:, :3].max()
    scale = np.array([force_scale] * 3 + [deviation[:, 3].max()])
    return float((np.abs(y - reference) / scale).max())


def static_outputs(export: Export) -> np.ndarray:
    return np.array([export.reduced.static_outputs[n] for n in OUTPUTS])


# -- the FMU as a file ----------------------------------------------------------------------

def test_exported_fmus_validate_with_zero_problems(exports):
    for export in exports.values():
        assert validate_fmu(str(export.path)) == []


def test_model_description_declares_the_export(exports):
    export = exports[10.0]
    md = read_model_description(str(export.path))
    cs = md.coSimulation
    assert cs.modelIdentifier == "TireModalNative"
    assert cs.canHandleVariableCommunicationStepSize and cs.canGetAndSetFMUstate
    assert cs.canSerializeFMUstate and not cs.needsExecutionTool
    assert not cs.providesDirectionalDerivative and not cs.canInterpolateInputs
    assert md.buildConfigurations[0].sourceFileSets[0].sourceFiles == ["tire_native.c"]
    variables = {v.name: v for v in md.modelVariables}
    for name in ("load", "speed", "n_elements", "f_max", "n_modes", "static_correction",
                 "inflation_pressure", "R", "k_cw"):
        assert variables[name].causality == "parameter"
        assert variables[name].variability == "fixed"
    assert float(variables["load"].start) == DEFAULT_LOAD_N  # asked for, not the bisected one
    assert float(variables["speed"].start) == 10.0
    assert int(variables["n_elements"].start) == N_ELEMENTS
    assert "speed 10 m/s" in md.description and f"N = {N_ELEMENTS}" in md.description
    with zipfile.ZipFile(export.path) as archive:
        names = set(archive.namelist())
    assert {"modelDescription.xml", "binaries/linux64/TireModalNative.so",
            "sources/tire_native.c", "sources/tire_model_data.h", "sources/fmi2Functions.h",
            "sources/fmi2FunctionTypes.h", "sources/fmi2TypesPlatform.h"} <= names


def test_variables_mirror_the_python_fmu(exports, python_fmu):
    mine = read_model_description(str(exports[0.0].path)).modelVariables
    theirs = read_model_description(str(python_fmu)).modelVariables

    def signature(v):
        return (v.name, v.valueReference, v.type, v.causality, v.variability, v.unit)

    assert [signature(v) for v in mine] == [signature(v) for v in theirs]


def test_tables_hold_the_model_bit_for_bit(exports):
    r = exports[10.0].reduced
    header = codegen.model_data_header(exports[10.0].native)

    def table(name):
        body = re.search(rf"static const double {name}\[[^=]*= \{{(.*?)\}};", header, re.S)
        return np.array([float(x) for x in re.findall(r"[-+0-9.eE]+", body.group(1))])

    k = r.n_modes
    assert np.array_equal(table("EIGEN_RE")[:k] + 1j * table("EIGEN_IM")[:k], r.eigenvalues)
    pad = codegen.padded_modes(k)
    b = table("B_RE").reshape(pad, -1)[:k] + 1j * table("B_IM").reshape(pad, -1)[:k]
    assert np.array_equal(b, r.b)
    c = table("C_RE").reshape(4, pad)[:, :k] + 1j * table("C_IM").reshape(4, pad)[:, :k]
    assert np.array_equal(c, r.c)
    assert np.array_equal(table("D").reshape(4, -1), r.d)
    assert np.array_equal(table("INPUT_DELAY"), r.input_delays_s)


def test_sources_compile_on_their_own_without_warnings(exports, tmp_path):
    folder = tmp_path / "unzipped"
    with zipfile.ZipFile(exports[10.0].path) as archive:
        archive.extractall(folder)
    shutil.rmtree(folder / "binaries")
    strict = ("-std=c99", "-Wpedantic", "-Wshadow", "-Wconversion", "-Wno-sign-conversion",
              "-Werror")
    compile_sources(folder / "sources", "strict", tmp_path / "strict", extra_flags=strict)
    if shutil.which("cmake") is None:
        pytest.skip("cmake not installed: fmpy's build of the sources/ folder needs it")
    from fmpy.build import build_platform_binary

    (tmp_path / "cmake").mkdir()
    build_platform_binary(folder, build_dir=tmp_path / "cmake")
    rebuilt = tmp_path / "rebuilt.fmu"
    with zipfile.ZipFile(rebuilt, "w") as archive:
        for path in sorted(folder.rglob("*")):
            if path.is_file():
                archive.write(path, path.relative_to(folder).as_posix())
    assert "binaries/linux64/TireModalNative.so" in zipfile.ZipFile(rebuilt).namelist()
    steps, u = excitation("road", 200)
    original, own = Host(exports[10.0].path), Host(rebuilt, "rebuilt")
    y_original, y_rebuilt = run(original, steps, u), run(own, steps, u)
    assert relative_difference(y_rebuilt, y_original, static_outputs(exports[10.0])) < 1e-12


# -- against the Python FMU -----------------------------------------------------------------

@pytest.mark.parametrize("speed", SPEEDS)
@pytest.mark.parametrize("kind", ["rim", "road"])
def test_matches_the_python_fmu(exports, python_fmu, speed, kind):
    export = exports[speed]
    if speed > 0:
        assert export.native.road_delayed and export.reduced.n_inputs > 2
    steps, u = excitation(kind, 600)
    native = Host(export.path, "native")
    python = Host(python_fmu, "python", parameters={"n_elements": N_ELEMENTS, "speed": speed})
    y_native, y_python = run(native, steps, u), run(python, steps, u)
    static = static_outputs(export)
    assert np.abs(y_python - static).max(axis=0)[0] > 100.0  # a real excitation, in newtons
    difference = relative_difference(y_native, y_python, static)
    print(f"\nV = {speed:g} m/s, {kind}: max relative difference C vs Python FMU "
          f"{difference:.2e}")
    assert difference < 1e-9
    # in_contact follows the total contact force in both
    assert native.fmu.getBoolean([native.vr["in_contact"]]) == \
        python.fmu.getBoolean([python.vr["in_contact"]])
    native.close()
    python.close()


@pytest.mark.parametrize("speed", SPEEDS)
def test_outputs_read_after_new_inputs_feed_through_as_in_the_python_fmu(exports, python_fmu,
                                                                       speed):
    """Read after the host sets the inputs of the new communication point, both FMUs recompute
    the direct feedthrough with them (the road delay line included at speed)."""
    export = exports[speed]
    steps, u = excitation("road", 400)
    native = Host(export.path, "native")
    python = Host(python_fmu, "python", parameters={"n_elements": N_ELEMENTS, "speed": speed})
    read = {"native": [], "python": []}
    for h, row, following in zip(steps, u, u[1:]):
        for name, host in (("native", native), ("python", python)):
            host.step(h, row)
            host.fmu.setReal(host.inputs, list(following))
            read[name].append(host.fmu.getReal(host.outputs))
    y_native, y_python = np.array(read["native"]), np.array(read["python"])
    static = static_outputs(export)
    assert relative_difference(y_native, y_python, static) < 1e-9
    # a real change at rest, where the contact damper passes the new road velocity straight
    # through; at speed the road at the leading edge reaches the patch nodes only later
    ramped = native.step(steps[0], u[-1])
    native.fmu.setReal(native.inputs, [0.0, 0.0, u[-1][2], u[-1][3] + 0.1])
    change = abs(native.fmu.getReal(native.outputs)[2] - ramped[2])
    assert change > 100.0 if speed == 0.0 else change < 10.0
    native.close()
    python.close()


@pytest.mark.parametrize("which", ["native", "python"])
def test_reading_outputs_between_steps_leaves_the_steps_alone(exports, python_fmu, which):
    """A master that sets the next point's inputs and reads the outputs before stepping must
    get the same steps as one that does not, also when its clock (k·h) differs from the
    FMU's running sum by rounding: the road sample recorded for the read is that point's."""
    export = exports[10.0]
    steps, u = excitation("road", 500)
    h = 1e-4
    path, params = ((export.path, None) if which == "native"
                    else (python_fmu, {"n_elements": N_ELEMENTS, "speed": 10.0}))
    plain, reading = Host(path, "plain", parameters=params), Host(path, "reading",
                                                                  parameters=params)
    for host, read in ((plain, False), (reading, True)):
        for k, row in enumerate(u[:-1]):
            host.fmu.setReal(host.inputs, list(row))
            if read:
                host.fmu.getReal(host.outputs)
            host.fmu.doStep(k * 0.1 * h * 10, h)  # the host's clock, not a running sum
        host.result = host.fmu.getReal(host.outputs)
    np.testing.assert_allclose(reading.result, plain.result, rtol=1e-12)
    plain.close()
    reading.close()


def test_simulate_fmu_runs_it_and_agrees_with_the_python_fmu(exports, python_fmu):
    t = np.linspace(0.0, 0.06, 301)
    signal = np.zeros(t.size, dtype=[(name, float) for name in ("time", *INPUTS)])
    signal["time"] = t
    signal["road_z"] = 3e-3 * np.sin(2 * np.pi * 25 * t)
    signal["road_vz"] = 3e-3 * 2 * np.pi * 25 * np.cos(2 * np.pi * 25 * t)
    common = dict(input=signal, output=list(OUTPUTS), output_interval=2e-4, stop_time=0.06)
    native = simulate_fmu(str(exports[10.0].path), **common)
    python = simulate_fmu(str(python_fmu), start_values={"n_elements": N_ELEMENTS,
                                                         "speed": 10.0}, **common)
    y_native = np.column_stack([native[n] for n in OUTPUTS])
    y_python = np.column_stack([python[n] for n in OUTPUTS])
    assert len(native) == len(python) > 250
    difference = relative_difference(y_native, y_python, static_outputs(exports[10.0]))
    print(f"\nsimulate_fmu, V = 10 m/s, uniform steps: max relative difference C vs Python "
          f"FMU {difference:.2e}")
    assert difference < 1e-9


# -- failure is a status, and the host survives ---------------------------------------------

def test_bad_steps_are_discarded_with_a_message_and_change_nothing(exports):
    steps, u = excitation("road", 40)
    reference = run(Host(exports[10.0].path, "reference"), steps, u)
    host = Host(exports[10.0].path)
    y = []
    for i, (h, row) in enumerate(zip(steps, u)):
        if i == 20:  # every refusal, then the real step
            host.fmu.setReal(host.inputs, [np.nan, 0.0, 0.0, np.inf])
            assert host.raw_step(host.time, h) == DISCARD
            host.fmu.setReal(host.inputs, list(row))
            for bad_h in (0.0, -1e-4, np.inf, np.nan):
                assert host.raw_step(host.time, bad_h) == DISCARD
            assert host.raw_step(host.time + 1e-3, h) == DISCARD
            with pytest.raises(FMICallException) as failure:
                host.fmu.doStep(host.time - 5e-4, h)
            assert failure.value.status == DISCARD
            # a refused step does not end the simulation: the host may retry
            assert host.fmu.getBooleanStatus(fmi2Terminated) == 0
        y.append(host.step(h, row))
    assert np.array_equal(np.array(y), reference)  # the refusals changed nothing
    problems = host.problems()
    assert any("non-finite input: rim_z = nan, road_vz = inf; state unchanged" in m
               for m in problems), problems
    assert any("step size h = 0.0 s: must be finite and > 0" in m for m in problems)
    assert any("step size h = -0.0001 s" in m for m in problems)
    assert sum("must start there" in m for m in problems) == 2
    assert all(m.startswith("doStep at t = ") for m in problems)


def test_stepping_before_initialisation_or_after_termination_is_discarded(exports):
    host = Host(exports[0.0].path, initialise=False)
    assert host.raw_step(0.0, 1e-4) == DISCARD
    assert "not initialised (call fmi2ExitInitializationMode)" in host.problems()[-1]
    host.initialise()
    assert all(status > 0 for status, _ in host.messages)  # information needs loggingOn
    chatty = Host(exports[0.0].path, "chatty", logging_on=True)
    assert any(status == 0 and "TireModalNative ready: exported reduced model, N = 48" in m
               for status, m in chatty.messages)
    chatty.close()
    host.step(1e-4, [0, 0, 0, 0])
    host.fmu.terminate()
    assert host.raw_step(host.time, 1e-4) == DISCARD
    assert "terminated (fmi2Terminate)" in host.problems()[-1]
    host.fmu.freeInstance()


def test_fixed_parameters_refuse_another_value_and_accept_their_own(exports):
    host = Host(exports[10.0].path, initialise=False)
    host.fmu.setupExperiment(startTime=0.0)
    host.fmu.enterInitializationMode()
    host.set("load", DEFAULT_LOAD_N)  # the export value: fine
    host.set("n_elements", N_ELEMENTS)
    host.set("static_correction", True)
    host.set("speed", 10.0)
    assert host.problems() == []
    for name, value in (("load", 30000.0), ("n_elements", 100), ("static_correction", False),
                        ("k_cw", 6e8)):
        with pytest.raises(FMICallException) as failure:
            host.set(name, value)
        assert failure.value.status == ERROR
    messages = host.problems()
    assert len(messages) == 4
    assert (f"load = 30000.0 N refused: this FMU was exported for load = {DEFAULT_LOAD_N!r} N"
            in messages[0])
    assert "re-export" in messages[0] and "option --load" in messages[0]
    assert "n_elements = 100 refused: this FMU was exported for n_elements = 48" in messages[1]
    assert "static_correction = false refused" in messages[2]
    assert "option --tire k_cw=VALUE" in messages[3]
    host.fmu.exitInitializationMode()
    assert host.fmu.getReal([host.vr["load"]]) == [DEFAULT_LOAD_N]
    with pytest.raises(FMICallException):  # after initialisation just the same
        host.set("speed", 20.0)
    host.step(1e-4, [0, 0, 0, 0])  # and the instance runs on
    host.close()


def test_variable_access_errors_are_errors_and_ignored(exports):
    host = Host(exports[0.0].path)
    for call in (lambda: host.fmu.setReal([host.vr["rim_Fz"]], [1.0]),
                 lambda: host.fmu.setReal([999], [1.0]),
                 lambda: host.fmu.getReal([999]),
                 lambda: host.fmu.setReal([host.vr["n_elements"]], [48.0]),
                 lambda: host.fmu.getInteger([host.vr["load"]]),
                 lambda: host.fmu.setString([host.vr["load"]], ["x"]),
                 lambda: host.fmu.setDebugLogging(True, ["noSuchCategory"])):
        with pytest.raises(FMICallException) as failure:
            call()
        assert failure.value.status == ERROR
    messages = host.problems()
    assert "rim_Fz is an output; ignored" in messages[0]
    count = len(fmu_variables())
    assert (f"value reference 999 does not exist (TireModalNative has {count} variables)"
            in messages[1])
    assert "n_elements is an Integer variable; use fmi2SetInteger" in messages[3]
    assert "unknown log category 'noSuchCategory'" in messages[6]
    static = static_outputs(exports[0.0])
    assert host.step(1e-4, [0, 0, 0, 0]) == pytest.approx(static, rel=1e-12)
    host.close()


def test_losing_contact_warns_once_per_episode(exports):
    host = Host(exports[0.0].path)
    in_contact = host.vr["in_contact"]
    # the rim rises 3 cm and comes back, slowly, twice: a 14 mm static deflection lets go
    h, period = 2e-4, 0.1
    t = np.arange(int(2 * period / h)) * h
    phase = 2 * np.pi * t / period
    lift, lift_v = 0.015 * (1 - np.cos(phase)), 0.015 * np.sin(phase) * 2 * np.pi / period
    statuses, contact = [], []
    for z, v in zip(lift, lift_v):
        host.fmu.setReal(host.inputs, [z, v, 0.0, 0.0])
        statuses.append(host.raw_step(host.time, h))
        host.time += h
        contact.append(host.fmu.getBoolean([in_contact])[0])
    warnings = [m for s, m in host.messages if s == WARNING]
    assert len(warnings) == 2 and statuses.count(WARNING) == 2  # one per episode
    assert statuses.count(ERROR) == statuses.count(DISCARD) == 0
    assert "the tire has lost contact (in_contact = false)" in warnings[0]
    episodes = np.flatnonzero(np.diff(np.array(contact, dtype=int)) == -1)
    assert len(episodes) == 2 and contact[-1]
    host.close()


# -- state, reset, instances ----------------------------------------------------------------

def test_state_rollback_and_serialization_reproduce_a_step_exactly(exports):
    export = exports[10.0]
    steps, u = excitation("road", 120)
    host = Host(export.path)
    for h, row in zip(steps[:100], u[:100]):
        host.step(h, row)
    t0 = host.time
    state = host.fmu.getFMUState()
    first = [host.step(h, row) for h, row in zip(steps[100:], u[100:])]
    host.fmu.setFMUState(state)
    host.time = t0
    again = [host.step(h, row) for h, row in zip(steps[100:], u[100:])]
    assert again == first  # bit for bit
    data = host.fmu.serializeFMUState(state)
    host.fmu.freeFMUState(state)

    fresh = Host(export.path, "fresh")
    fresh.fmu.setFMUState(fresh.fmu.deserializeFMUState(data))
    fresh.time = t0
    assert [fresh.step(h, row) for h, row in zip(steps[100:], u[100:])] == first

    other = Host(exports[0.0].path, "other")
    tampered = bytearray(data)
    tampered[-1] ^= 0xFF
    for bad, why in ((data[:-8], "road history does not match its size"),
                     (bytes(20), "not a tire_fmu native FMU state"),
                     (bytes(tampered[:30]) + bytes(len(data) - 30), "belongs to another FMU")):
        with pytest.raises(FMICallException) as failure:
            fresh.fmu.deserializeFMUState(bad)
        assert failure.value.status == ERROR
        assert why in fresh.problems()[-1], fresh.problems()
    with pytest.raises(FMICallException):  # a state of the other export
        other.fmu.deserializeFMUState(data)
    assert "belongs to another FMU" in other.problems()[-1]
    assert fresh.step(1e-4, [0, 0, 0, 0])  # still running
    for h in (host, fresh, other):
        h.close()


def test_reset_starts_over(exports):
    steps, u = excitation("rim", 150)
    host = Host(exports[10.0].path)
    first = run(host, steps, u)
    host.fmu.reset()
    host.initialise()
    assert np.array_equal(run(host, steps, u), first)
    host.close()


def test_instances_are_independent(exports):
    steps, u_road = excitation("road", 100)
    _, u_rim = excitation("rim", 100)
    solo = {key: run(Host(exports[speed].path, f"solo{key}"), steps, u)
            for key, (speed, u) in {"a": (10.0, u_road), "b": (10.0, u_rim),
                                     "c": (0.0, u_road)}.items()}
    hosts = {"a": Host(exports[10.0].path, "a"), "b": Host(exports[10.0].path, "b"),
             "c": Host(exports[0.0].path, "c")}
    inputs = {"a": u_road, "b": u_rim, "c": u_road}
    together = {key: [] for key in hosts}
    for i, h in enumerate(steps):  # interleaved, step by step
        for key, host in hosts.items():
            together[key].append(host.step(h, inputs[key][i]))
    for key in hosts:
        assert np.array_equal(np.array(together[key]), solo[key])


# -- export paths ---------------------------------------------------------------------------

def test_cli_exports_a_native_fmu(tmp_path, capsys):
    path = tmp_path / "tire.fmu"
    assert main(["export", str(path), "--elements", "40", "--speed", "5", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["file"] == str(path) and validate_fmu(str(path)) == []
    host = Host(path, "cli")
    assert host.fmu.getReal([host.vr["load"], host.vr["speed"]]) == [DEFAULT_LOAD_N, 5.0]
    assert np.isfinite(host.step(1e-4, [1e-3, 0, 0, 0])).all()
    host.close()
    assert main(["export", "--format", "fmu", str(tmp_path / "no" / "t.fmu"),
                 "--elements", "40"]) == 2
    assert "folder" in capsys.readouterr().err


def test_a_model_without_modes_builds_and_feeds_through(exports, tmp_path):
    # what the benchmark's overhead FMU is: the same machinery, nothing to integrate
    r = exports[0.0].reduced
    m = r.n_inputs
    empty = replace(r, eigenvalues=np.zeros(0, complex), b=np.zeros((0, m), complex),
                    c=np.zeros((4, 0), complex))
    path = build_native_fmu(empty, tmp_path / "empty.fmu", model_identifier="TireEmpty")
    host = Host(path, "empty")
    y = host.step(1e-4, [1e-3, 0.0, 0.0, 0.0])
    assert y == pytest.approx(static_outputs(exports[0.0]) + r.d[:, 0] * 1e-3, rel=1e-12)
    host.close()


def test_compiler_failure_is_a_clear_error(exports, tmp_path, monkeypatch):
    from tire_fmu.native import NativeBuildError

    monkeypatch.setenv("CC", "gcc -include no/such/header.h")
    with pytest.raises(NativeBuildError, match="compiling the FMU failed"):
        build_native_fmu(exports[0.0].reduced, tmp_path / "broken.fmu")
    assert not (tmp_path / "broken.fmu").exists()
