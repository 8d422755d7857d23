"""TireInPlaneNative.fmu (the in-plane tire in C, tire_fmu.native) against TireInPlane.fmu (the
Python FMU) through fmpy: the same variables, the same outputs to 1e-9 of the load over a
cleat, a brake, the rim's motion, a held wheel and the shaker at rest; the same parameter
refusals; a refused step that changes nothing; FMU states bit for bit; other hosts."""

import re
import shutil
import subprocess
import zipfile

import numpy as np
import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmpy import read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from inplane_support import OUTPUTS, Instance  # noqa: E402
from native_support import (  # noqa: E402
    compile_host,
    declared_dependencies,
    host_outputs,
    in_host,
    needs_windows_tools,
    run_host,
)

from tire_fmu.core.inplane import InPlaneTire, TangentialParameters  # noqa: E402
from tire_fmu.core.inplane_host import CRITICAL_SPEED_FRACTION  # noqa: E402
from tire_fmu.core.inplane_modes import critical_speed  # noqa: E402
from tire_fmu.core.obstacles import cleat  # noqa: E402
from tire_fmu.core.parameters import TireParameters  # noqa: E402
from tire_fmu.core.step_limits import (  # noqa: E402
    MAX_DISPLACEMENT_M,
    MAX_TORQUE_N_M,
    MAX_VELOCITY_M_S,
)
from tire_fmu.fmu.interface import inplane_fmu_variables  # noqa: E402
from tire_fmu.fmu.spec import MESSAGES  # noqa: E402

pytestmark = pytest.mark.fmu

LOAD = inplane_fmu_variables()[[v.name for v in inplane_fmu_variables()].index("load")].start
RADIUS = TireParameters().R
TOLERANCE = 1e-9  # of the load (forces), of load * R (the moment), of V / R (the spin)


@pytest.fixture(scope="module")
def native_path(tmp_path_factory):
    from tire_fmu.native.builder import build_native_inplane_fmu

    # win64 too where it can be run (under wine): a few seconds more
    windows = all(shutil.which(tool) for tool in ("x86_64-w64-mingw32-gcc", "wine"))
    return build_native_inplane_fmu(tmp_path_factory.mktemp("inplane_native"),
                                    platforms=("linux64", "win64") if windows else ("linux64",))


@pytest.fixture(scope="module")
def python_path(tmp_path_factory):
    from tire_fmu.fmu.builder import build_inplane_fmu

    return build_inplane_fmu(tmp_path_factory.mktemp("inplane_python"))


def instance(path, **parameters) -> Instance:
    """An instance of either FMU, the native one's log formatted (its messages are formats)."""
    return Instance(str(path), format_log="Native" in str(path), **parameters)


# -- the runs --------------------------------------------------------------------------------

CLEAT = cleat(0.02, 0.02)


def over_a_cleat(t):
    """A 20 mm x 20 mm cleat read at the zone front from 10 ms on, at 10 m/s, the rim held."""
    z, slope = CLEAT.profile([10.0 * t - 0.1])
    return dict(road_z=float(z[0]), road_vz=float(10.0 * slope[0]))


def braking(t):
    return dict(wheel_torque=-3000.0 if t > 0.01 else 0.0)


def rim_moving(t):
    """The axle slowing at 3 m/s² and bouncing 2 mm at 60 rad/s, a light drive torque."""
    return dict(rim_x=-1.5 * t**2, rim_vx=-3.0 * t, rim_z=2e-3 * np.sin(60.0 * t),
                rim_vz=0.12 * np.cos(60.0 * t), wheel_torque=500.0)


def held_wheel(t):
    """A 4 mm (1 - cos) rise of the road over 30 ms, a torque the held wheel ignores."""
    u = min(t / 0.03, 1.0)
    return dict(road_z=2e-3 * (1 - np.cos(np.pi * u)),
                road_vz=2e-3 * np.pi / 0.03 * np.sin(np.pi * u) if u < 1 else 0.0,
                wheel_torque=-5000.0)


def shaker(t):
    """At rest on a shaker plate: 1 mm at 20 Hz."""
    w = 2 * np.pi * 20.0
    return dict(road_z=1e-3 * np.sin(w * t), road_vz=1e-3 * w * np.cos(w * t))


def driven_to_a_lock(t):
    """The host's wheel braked to a lock in 40 ms over a 5 mm road wave (wheel_driven)."""
    return dict(wheel_rate=-10.0 / RADIUS * min(t / 0.04, 1.0),
                road_z=5e-3 * np.sin(50.0 * t), road_vz=0.25 * np.cos(50.0 * t))


RUNS = {  # parameters, inputs at the end of each step, communication step, steps
    "cleat": ({"speed": 10.0}, over_a_cleat, 2e-4, 400),
    "brake": ({"speed": 10.0}, braking, 5e-4, 200),
    "rim motion": ({"speed": 10.0}, rim_moving, 1e-3, 100),
    "held wheel": ({"speed": 10.0, "wheel_free": False}, held_wheel, 5e-4, 160),
    "at rest": ({"speed": 0.0}, shaker, 1e-3, 100),
    "driven": ({"speed": 10.0, "wheel_driven": True}, driven_to_a_lock, 5e-4, 120),
}


def outputs_of(path, parameters, signal, h, steps):
    """(steps + 1, 7) outputs and (steps + 1,) in_contact, from before the first step on."""
    fmu = instance(path, **parameters).start()
    rows, contact = [fmu.outputs()], [fmu.fmu.getBoolean([fmu.vr["in_contact"]])[0]]
    for k in range(1, steps + 1):
        rows.append(fmu.step(h, **signal(k * h)))
        contact.append(fmu.fmu.getBoolean([fmu.vr["in_contact"]])[0])
    fmu.close()
    return np.array(rows), np.array(contact)


def scaled_difference(a, b, speed):
    """Per output, the largest difference over the run in the scale of its kind."""
    spin = max(speed / RADIUS, 1.0)
    scales = np.array([LOAD, LOAD, LOAD * RADIUS, LOAD, LOAD, spin, 1.0])
    return np.abs(a - b).max(axis=0) / scales


@pytest.mark.parametrize("name", RUNS)
def test_the_native_fmu_gives_the_python_fmus_outputs(native_path, python_path, name):
    parameters, signal, h, steps = RUNS[name]
    native, native_contact = outputs_of(native_path, parameters, signal, h, steps)
    python, python_contact = outputs_of(python_path, parameters, signal, h, steps)
    difference = scaled_difference(native, python, parameters["speed"])
    assert difference.max() < TOLERANCE, dict(zip(OUTPUTS, difference))
    assert np.array_equal(native[:, 6], python[:, 6])  # sliding points: a count
    assert np.array_equal(native_contact, python_contact)
    # the run moved the forces (a test of equal constants would pass too otherwise)
    assert np.ptp(python[:, 0]) > 1e-3 * LOAD
    if name == "brake":
        assert python[-1, 1] < -1e3 and python[-1, 5] < python[0, 5]
    if name == "held wheel":
        assert np.all(native[:, 5] == native[0, 5])
    if name == "driven":  # the host's spin, and a locked wheel's drag
        assert native[-1, 5] == pytest.approx(0.0, abs=1e-9)
        assert python[-1, 1] < -0.5 * 0.8 * LOAD


# -- refusals --------------------------------------------------------------------------------

def _refused(path, **parameters):
    """The status of fmi2ExitInitializationMode and the parameter problems logged, by name:
    {name: (the value it says, the message)}."""
    fmu = instance(path, **parameters)
    try:
        fmu.start()
        status = 0
    except FMICallException as error:
        status = error.status
    named = {}
    for _, message in fmu.log:
        found = re.match(r"parameter problem \d+/\d+: (\w+) = ([^ :]+)", message)
        if found:
            named[found.group(1)] = (float(found.group(2)), message)
    return status, named, fmu


def test_bad_parameters_are_all_named_with_their_values(native_path, python_path):
    bad = dict(n_elements=3, friction_coefficient=-1.0, load=-1.0, step_size=0.5, EA=-5.0,
               contact_point_spacing=0.5)
    status, native, fmu = _refused(native_path, **bad)
    assert status == 3
    _, python, other = _refused(python_path, **bad)
    assert set(native) == set(python) == set(bad)
    for name, value in bad.items():
        assert native[name][0] == value, native[name][1]
    # the instance stays in its error state and says why a step is refused
    with pytest.raises(FMICallException):
        fmu.fmu.doStep(0.0, 1e-3)
    fmu.fmu.freeInstance()
    other.fmu.freeInstance()


def test_a_speed_above_the_critical_fraction_is_refused(native_path, python_path):
    """The critical speed from the Python core's own search (not the C's): above
    CRITICAL_SPEED_FRACTION of it both FMUs refuse, naming speed; below, the native one runs."""
    critical = critical_speed(InPlaneTire(TireParameters(), TangentialParameters()),
                              100).speed_m_s
    too_fast = 1.01 * CRITICAL_SPEED_FRACTION * critical
    status, native, fmu = _refused(native_path, speed=too_fast)
    fmu.fmu.freeInstance()
    assert status == 3 and set(native) == {"speed"}
    assert native["speed"][0] == too_fast
    assert f"{critical:.4g} m/s" in native["speed"][1]  # the critical speed it found
    status, python, fmu = _refused(python_path, speed=too_fast)
    fmu.fmu.freeInstance()
    assert status == 3 and set(python) == {"speed"}
    status, native, fmu = _refused(native_path, speed=0.99 * CRITICAL_SPEED_FRACTION * critical)
    assert status == 0 and not native
    fmu.close()


@pytest.mark.parametrize("name, limit", [("wheel_torque", MAX_TORQUE_N_M),
                                         ("wheel_rate", MAX_VELOCITY_M_S),
                                         ("rim_vx", MAX_VELOCITY_M_S),
                                         ("rim_x", MAX_DISPLACEMENT_M)])
def test_an_input_beyond_its_limit_is_refused_alike(native_path, python_path, name, limit):
    """At its limit an input is taken; just beyond it (or not finite) both FMUs refuse it
    with fmi2Error and the same words, and step on as before."""
    messages = []
    for path in (native_path, python_path):
        fmu = instance(path, speed=10.0).start()
        fmu.fmu.setReal([fmu.vr[name]], [limit])  # taken
        for bad in (1.000001 * limit, -1.000001 * limit, float("nan")):
            with pytest.raises(FMICallException) as error:
                fmu.fmu.setReal([fmu.vr[name]], [bad])
            assert error.value.status == 3
        messages.append(fmu.log[-2][1])
        fmu.fmu.setReal([fmu.vr[name]], [0.0])
        assert np.isfinite(fmu.step(1e-3)).all()
        fmu.close()
    assert messages[0] == messages[1]
    assert name in messages[0] and f"{limit:g}" in messages[0]


def test_a_step_off_the_tire_grid_is_taken_alike_in_both_runtimes(native_path, python_path):
    """A host step that is no whole number of step_size (an input event between the tire's
    steps) is cut into equal shorter steps that end exactly at t + h, in both runtimes alike;
    a step shorter than the tire's shortest is refused and changes nothing."""
    sizes = [1e-3] * 5 + [1.5e-4, 8.5e-4] + [1e-3] * 5 + [3.7e-4] * 3

    def run(path):
        fmu = instance(path, speed=10.0).start()
        rows = []
        for h in sizes:
            rows.append(fmu.step(h, **braking(fmu.t)))
        with pytest.raises(FMICallException) as error:
            fmu.fmu.doStep(fmu.t, 5e-8)
        assert error.value.status == 3
        assert "shortest step" in fmu.log[-1][1]
        rows.append(fmu.step(1e-3, **braking(fmu.t)))
        end = fmu.t
        fmu.close()
        return np.array(rows), end

    native, end = run(native_path)
    python, _ = run(python_path)
    assert end == pytest.approx(sum(sizes) + 1e-3, abs=1e-15)
    assert np.all(np.isfinite(native))
    assert scaled_difference(native, python, 10.0).max() < TOLERANCE


# -- FMU states ------------------------------------------------------------------------------

def test_fmu_states_round_trip_bit_for_bit(native_path):
    h = 5e-4
    fmu = instance(native_path, speed=10.0).start()
    for k in range(1, 21):
        fmu.step(h, **rim_moving(k * h) | braking(k * h))
    state, t = fmu.fmu.getFMUstate(), fmu.t
    data = fmu.fmu.serializeFMUstate(state)

    def run_on(instance):
        instance.t = t
        return np.array([instance.step(h, **rim_moving(k * h) | braking(k * h))
                         for k in range(21, 41)])

    first = run_on(fmu)
    fmu.fmu.setFMUstate(state)
    assert np.array_equal(run_on(fmu), first)
    fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(data))
    assert np.array_equal(run_on(fmu), first)
    fmu.fmu.freeFMUstate(state)
    fmu.close()
    # a fresh instance, never initialised, given the bytes: the same tire and the same bits
    fresh = instance(native_path)
    fresh.fmu.setFMUstate(fresh.fmu.deSerializeFMUstate(data))
    assert np.array_equal(run_on(fresh), first)
    fresh.close()


def _foreign_basis(data: bytes, n_values: int, shift_dofs: float = 0.0) -> bytes:
    """The state as another build of the same tire would have written it: another basis
    fingerprint, its coordinates scrambled (they refer to that basis), its DOFs kept; with
    ``shift_dofs`` the DOFs also moved off this basis (a shape no build of it reaches)."""
    import struct

    from tire_fmu.core.inplane_contact import STEPPER_SCALARS, STEPPER_STATE_HEAD
    from tire_fmu.fmu.spec import STATE_MODEL_FLAGS, state_pack, state_unpack

    f = state_unpack(data, n_values)
    model = bytearray(f["model"])
    at = 4 * STATE_MODEL_FLAGS
    _, ny, p, samples, _, n_dof, fingerprint = struct.unpack_from(STEPPER_STATE_HEAD, model, at)
    struct.pack_into("<I", model, at + 32, fingerprint ^ 0x5A5A5A5A)
    doubles = at + struct.calcsize(STEPPER_STATE_HEAD)
    y = np.frombuffer(model, "<f8", 3 * ny, doubles + 8 * STEPPER_SCALARS).copy()
    model[doubles + 8 * STEPPER_SCALARS:doubles + 8 * (STEPPER_SCALARS + 3 * ny)] = (
        y[::-1] * 7.0).astype("<f8").tobytes()
    if shift_dofs:
        dofs_at = doubles + 8 * (STEPPER_SCALARS + 3 * ny + 2 * p + 3 * samples)
        u = np.frombuffer(model, "<f8", n_dof, dofs_at).copy()
        u[:-1] += shift_dofs * np.cos(np.arange(n_dof - 1)) * np.abs(u[:-1]).max()
        model[dofs_at:dofs_at + 8 * n_dof] = u.astype("<f8").tobytes()
    return state_pack(f["phase"], f["guid"], f["time"], f["start_time"], bool(f["stale"]),
                      f["values"], bytes(model), f["reason"].decode())


@pytest.mark.parametrize("runtime", ["native", "python"])
def test_a_state_of_another_basis_continues_or_is_refused(native_path, python_path, runtime):
    """A state written by a build whose reduced basis came out otherwise (another BLAS, thread
    count or CPU: other signs and rotations of the modes) is taken into this build's basis
    through the tire's own DOFs it carries, and continues as the original within 1e-9 of the
    load; one whose shape lies outside this basis is refused, saying why, never stepped."""
    path = native_path if runtime == "native" else python_path
    h = 5e-4
    fmu = instance(path, speed=10.0).start()
    for k in range(1, 21):
        fmu.step(h, **rim_moving(k * h) | braking(k * h))
    t, data = fmu.t, fmu.fmu.serializeFMUstate(fmu.fmu.getFMUstate())
    n_values = len(read_model_description(str(path)).modelVariables)

    def run_on():
        fmu.t = t
        return np.array([fmu.step(h, **rim_moving(k * h) | braking(k * h))
                         for k in range(21, 41)])

    first = run_on()
    fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(_foreign_basis(data, n_values)))
    assert np.abs(run_on() - first)[:, :3].max() < 1e-9 * 27654.8
    with pytest.raises(FMICallException):
        fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(
            _foreign_basis(data, n_values, shift_dofs=1e-3)))
    assert "lies outside this FMU's reduced basis" in fmu.log[-1][1]
    assert "restore it in the process that saved it" in fmu.log[-1][1]
    fmu.close()


# -- the FMU itself --------------------------------------------------------------------------

def test_it_declares_tireinplanes_variables_and_ships_its_sources(native_path, python_path,
                                                                  tmp_path):
    native, python = (read_model_description(str(p)) for p in (native_path, python_path))
    assert native.coSimulation.modelIdentifier == "TireInPlaneNative"

    def start(v):
        if v.causality == "output":
            return None
        return v.start.lower() in ("true", "1") if v.type == "Boolean" else float(v.start)

    def variables(md):
        return [(v.name, v.type, v.causality, v.variability, v.unit, start(v))
                for v in md.modelVariables]

    assert variables(native) == variables(python)
    assert "Needs no Python" in native.description
    for flag in ("canHandleVariableCommunicationStepSize", "canGetAndSetFMUstate",
                 "canSerializeFMUstate"):
        assert getattr(native.coSimulation, flag)
    # sources/ compiles and links on its own: no symbol left for the host to supply
    zipfile.ZipFile(native_path).extractall(tmp_path)
    sources = sorted((tmp_path / "sources").glob("*.c"))
    listed = re.findall(r'SourceFile name="([^"]+)"',
                        (tmp_path / "sources" / "buildDescription.xml").read_text())
    assert sorted(listed) == sorted(p.name for p in sources)
    done = subprocess.run(["gcc", "-std=c99", "-shared", "-fPIC", "-Wl,--no-undefined",
                           "-I", str(tmp_path / "sources"), "-o", str(tmp_path / "t.so"),
                           *map(str, sources), "-lm"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_no_output_declares_a_dependency_and_none_feeds_through(native_path, python_path):
    """The outputs declared no dependencies, which FMI reads as every input, and a host
    looking for algebraic loops found false ones: each output is the last step's."""
    from fmpy.validation import validate_fmu

    from tire_fmu.fmu.interface import output_dependencies

    names = [v.name for v in inplane_fmu_variables() if v.causality == "output"]
    assert output_dependencies(inplane_fmu_variables()) == {name: () for name in names}
    for path in (python_path, native_path):
        assert declared_dependencies(path) == {name: [] for name in names}, path
        assert validate_fmu(str(path)) == []
        run = instance(path, speed=10.0).start()
        run.step(1e-3, **rim_moving(1e-3), **over_a_cleat(0.02))
        before = run.outputs()
        for name in ("rim_z", "rim_vz", "road_z", "road_vz", "rim_x", "rim_vx",
                     "wheel_torque"):
            run.fmu.setReal([run.vr[name]], [1e-3])
            assert np.array_equal(run.outputs(), before), (path, name)
        run.close()


def test_a_bad_reference_or_a_string_is_refused_in_the_fmus_own_name(native_path,
                                                                     python_path):
    """TireInPlane's message named TireModal ("TireModal has 49 variables")."""
    count = len(inplane_fmu_variables())
    for path, name in ((python_path, "TireInPlane"), (native_path, "TireInPlaneNative")):
        run = instance(path).start()
        for call, arguments in ((run.fmu.getReal, ([999],)),
                                (run.fmu.setReal, ([999], [0.0])),
                                (run.fmu.getString, ([0],))):
            with pytest.raises(FMICallException):
                call(*arguments)
        said = [m for status, m in run.log if status >= 3]
        missing = MESSAGES["REFERENCE_MISSING"] % (999, name, count)
        assert said == [MESSAGES["REFUSED"] % (call, why) for call, why in (
            ("fmi2GetReal", missing), ("fmi2SetReal", missing),
            ("fmi2GetString", MESSAGES["NO_STRINGS"] % name))], said
        run.close()


def test_the_cli_builds_it(tmp_path, capsys):
    from tire_fmu.cli import main

    code = main(["build-fmu", str(tmp_path), "--inplane", "--native", "--platform", "linux64",
                 "--tangential", "friction_coefficient=0.6"])
    err = capsys.readouterr().err
    assert code == 0, err
    assert err.count("\n") == 1 and "TireInPlaneNative.fmu" in err  # "wrote PATH"
    md = read_model_description(str(tmp_path / "TireInPlaneNative.fmu"))
    starts = {v.name: v.start for v in md.modelVariables}
    assert md.coSimulation.modelIdentifier == "TireInPlaneNative"
    assert float(starts["friction_coefficient"]) == 0.6
    assert main(["build-fmu", str(tmp_path), "--native"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--native: only with --inplane" in err


# -- other hosts -----------------------------------------------------------------------------

@pytest.mark.parametrize("host", ["libcosimpy", "ecospy"])
def test_other_hosts_give_fmpys_outputs(native_path, host, tmp_path):
    reference = in_host(native_path, "fmpy", 30000.0, 10.0, tmp_path, inplane=True)
    other = in_host(native_path, host, 30000.0, 10.0, tmp_path, inplane=True)
    assert reference.shape == other.shape == (400, len(OUTPUTS))
    assert np.ptp(reference[:, 1]) > 1e3  # the brake and the road's drop were felt
    assert scaled_difference(reference, other, 10.0).max() < TOLERANCE


def test_in_a_fresh_process_the_python_fmu_gives_the_native_fmus_outputs(native_path,
                                                                          python_path, tmp_path):
    """Each FMU alone in a new process (no tire_fmu imported before it: the Python FMU runs
    the package its resources carry), rolling at 10 m/s through the road's drop and a brake."""
    native = in_host(native_path, "fmpy", 30000.0, 10.0, tmp_path, inplane=True)
    python = in_host(python_path, "fmpy", 30000.0, 10.0, tmp_path, inplane=True)
    assert scaled_difference(native, python, 10.0).max() < TOLERANCE


@needs_windows_tools
def test_win64_under_wine_gives_the_linux64_and_fmpys_outputs(native_path, tmp_path):
    """A plain C host (native_host/host.c) runs the win64 binary under wine and the linux64
    one over a brake and a cleat: the outputs of both, and fmpy's, agree; the statuses and
    the log lines are the same (but the build's CPU time)."""
    zipfile.ZipFile(native_path).extractall(tmp_path)
    guid = read_model_description(str(native_path)).guid
    vr = {v.name: i for i, v in enumerate(inplane_fmu_variables())}
    h, steps = 1e-4, 600
    lines = [f"real {vr['speed']} 10.0", "init"]
    for k in range(1, steps + 1):
        given = braking(k * h) | over_a_cleat(k * h)
        lines += [f"real {vr[name]} {value!r}" for name, value in given.items()]
        lines.append(f"step {(k - 1) * h!r} {h!r}")
    commands = tmp_path / "commands.txt"
    commands.write_text("\n".join(lines) + "\n")
    binaries = tmp_path / "binaries"
    linux = run_host(compile_host(tmp_path, windows=False),
                     binaries / "linux64" / "TireInPlaneNative.so", guid, commands)
    windows = run_host(compile_host(tmp_path, windows=True),
                       binaries / "win64" / "TireInPlaneNative.dll", guid, commands)
    fmpy_run, _ = outputs_of(native_path, {"speed": 10.0},
                             lambda t: braking(t) | over_a_cleat(t), h, steps)
    assert scaled_difference(host_outputs(linux), fmpy_run[1:], 10.0).max() < TOLERANCE
    assert scaled_difference(host_outputs(windows), host_outputs(linux), 10.0).max() < TOLERANCE
    assert np.ptp(fmpy_run[:, 1]) > 1e3

    def said(run):
        return [line.strip() for line in run if not line.startswith("out ")
                and "ready in" not in line]

    assert said(linux) == said(windows)
    assert said(linux).count("status step 0") == steps
