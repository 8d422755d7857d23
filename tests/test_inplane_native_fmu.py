"""TireInPlaneNative.fmu (the in-plane tire in C, tire_fmu.native) against TireInPlane.fmu (the
Python FMU) through fmpy, both driven as a host drives them: the wheel centre's state in (the
values at t, set before fmi2DoStep(t, h)), the road by position (a road file, or the host's
heights where the FMU asks for them). The same variables; the same outputs to 1e-9 of their
scale over a cleat in the host's road and in a road file (profile and OpenCRG), a brake, the
wheel centre's motion, a held wheel, the shaker at rest and a driven wheel; the same parameter
refusals, a bad road file's too; the extent warning once; a refused step that changes
nothing; FMU states bit for bit and across the runtimes; other hosts."""

import re
import shutil
import struct
import subprocess
import zipfile

import numpy as np
import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmpy import read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from inplane_support import Instance  # noqa: E402
from native_support import (  # noqa: E402
    compile_host,
    declared_dependencies,
    host_outputs,
    in_host,
    needs_windows_tools,
    run_host,
)

from tire_fmu.core.inplane import InPlaneTire, TangentialParameters  # noqa: E402
from tire_fmu.core.inplane_contact import STEPPER_SCALARS, STEPPER_STATE_HEAD  # noqa: E402
from tire_fmu.core.inplane_host import CRITICAL_SPEED_FRACTION  # noqa: E402
from tire_fmu.core.inplane_modes import critical_speed  # noqa: E402
from tire_fmu.core.obstacles import PositionRoad, cleat, sampled_obstacle  # noqa: E402
from tire_fmu.core.parameters import TireParameters  # noqa: E402
from tire_fmu.core.step_limits import MAX_TORQUE_N_M, MAX_VELOCITY_M_S  # noqa: E402
from tire_fmu.fmu.builder import inplane_loaded_radius  # noqa: E402
from tire_fmu.fmu.interface import (  # noqa: E402
    MAX_ROAD_HEIGHT_M,
    MAX_ROAD_POSITION_M,
    ROAD_QUERIES,
    inplane_fmu_variables,
)
from tire_fmu.fmu.spec import (  # noqa: E402
    MESSAGES,
    STATE_MODEL_FLAGS,
    state_pack,
    state_unpack,
)
from tire_fmu.road_files import write_road  # noqa: E402

pytestmark = pytest.mark.fmu

TABLE = {v.name: v for v in inplane_fmu_variables()}
LOAD = TABLE["load"].start
RADIUS = TireParameters().R
TOLERANCE = 1e-9  # of each output's scale (forces: the load; the moment: load * R; ...)
#: The Real outputs a host reads of the tire (road_x_i apart), and the scale each is compared
#: in: the load, load * R, the spin at the speed (set per run), a count, R, 1
OUTPUTS = ("rim_Fz", "rim_Fx", "rim_My", "contact_Fz", "contact_Fx", "wheel_spin",
           "sliding_points", "loaded_radius", "effective_rolling_radius", "longitudinal_slip",
           "contact_length")
WHEEL = ("wheel_x", "wheel_vx", "wheel_z", "wheel_vz", "wheel_torque", "wheel_rate")
ROAD_X = tuple(f"road_x_{i}" for i in range(1, ROAD_QUERIES + 1))
ROAD_Z = tuple(f"road_z_{i}" for i in range(1, ROAD_QUERIES + 1))
#: wheel_z's start value: the default tire's loaded radius at the default load (both FMUs)
AT_LOAD = TABLE["wheel_z"].start


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


def wheel_inputs(speed: float, t: float, **given) -> list[float]:
    """The inputs at t (WHEEL's order): by default rolling steadily at ``speed`` at the loaded
    radius above a level road."""
    values = {"wheel_x": speed * t, "wheel_vx": speed, "wheel_z": AT_LOAD, "wheel_vz": 0.0,
              "wheel_torque": 0.0, "wheel_rate": 0.0, **given}
    return [float(values[name]) for name in WHEEL]


class Wheel(Instance):
    """An in-plane FMU driven as a host drives its wheel centre: before each fmi2DoStep(t, h)
    the inputs at t (by default rolling steadily at ``speed`` at the loaded radius above a
    level road) and, with a host road, its heights at the road_x_i the FMU gave."""

    def __init__(self, path, road_file: str | None = None, **parameters):
        super().__init__(str(path), format_log="Native" in str(path), **parameters)
        self.speed = float(parameters.get("speed", 0.0))
        if road_file is not None:
            self.fmu.setString([self.vr["road_file"]], [road_file])

    def step(self, h, road=None, **given):
        """One step from self.t; ``road``: the host's road, heights at positions (m)."""
        if road is not None:
            asked = np.array(self.fmu.getReal([self.vr[n] for n in ROAD_X]))
            self.fmu.setReal([self.vr[n] for n in ROAD_Z],
                             [float(z) for z in road(asked, self.t)])
        self.fmu.setReal([self.vr[n] for n in WHEEL], wheel_inputs(self.speed, self.t, **given))
        self.fmu.doStep(self.t, h)
        self.t += h
        return self.outputs()

    def outputs(self):
        return np.array(self.fmu.getReal([self.vr[n] for n in OUTPUTS]))

    def asked(self):
        return np.array(self.fmu.getReal([self.vr[n] for n in ROAD_X]))


# -- the runs --------------------------------------------------------------------------------

#: a 20 mm x 20 mm cleat 1 m along the road, sampled every millimetre (a road file's knots)
CLEAT = sampled_obstacle(cleat(0.02, 0.02), 1e-3, lead_in_m=1.0, lead_out_m=1.0)
#: where the wheel starts on it: the contact zone (0.55 m) on the file's road
CLEAT_START_M = 0.3


def on_the_cleat(t):
    """Rolling over the cleat at 10 m/s from CLEAT_START_M (the contact zone's front reaches
    it after 43 ms, its rear leaves it after 100 ms)."""
    return dict(wheel_x=CLEAT_START_M + 10.0 * t, wheel_vx=10.0)


def host_cleat(x, t):
    """The host's road: the cleat's profile where the tire asks."""
    return CLEAT.profile(x)[0]


def braking(t):
    return dict(wheel_torque=-3000.0 if t > 0.01 else 0.0)


def wheel_moving(t):
    """The axle slowing at 3 m/s² from 10 m/s and bouncing 2 mm at 60 rad/s, a light drive
    torque."""
    return dict(wheel_x=10.0 * t - 1.5 * t**2, wheel_vx=10.0 - 3.0 * t,
                wheel_z=AT_LOAD + 2e-3 * np.sin(60.0 * t), wheel_vz=0.12 * np.cos(60.0 * t),
                wheel_torque=500.0)


def rise(x, t):
    """A 4 mm (1 - cos) rise of the road over 0.3 m from 0.35 m on."""
    u = np.clip((np.asarray(x) - 0.35) / 0.3, 0.0, 1.0)
    return 2e-3 * (1 - np.cos(np.pi * u))


def shaker(x, t):
    """At rest on a shaker plate: the whole road 1 mm at 20 Hz."""
    return np.full(np.shape(x), 1e-3 * np.sin(2 * np.pi * 20.0 * t))


def wave(x, t):
    return 5e-3 * np.sin(5.0 * np.asarray(x))


def driven_to_a_lock(t):
    """The host's wheel braked from rolling to a lock in 40 ms (wheel_driven: its spin)."""
    return dict(wheel_rate=10.0 / RADIUS * max(1.0 - t / 0.04, 0.0))


RUNS = {  # parameters, inputs at t, the host's road (or a road file), step, steps
    "cleat in the host's road": ({"speed": 10.0}, on_the_cleat, host_cleat, 1e-3, 110),
    "cleat in a profile file": ({"speed": 10.0}, on_the_cleat, "cleat.txt", 1e-3, 110),
    "cleat in an OpenCRG file": ({"speed": 10.0}, on_the_cleat, "cleat.crg", 1e-3, 110),
    # at a tenth of the host step: the road read alike whatever the step cuts it into
    "cleat in the host's road, 0.1 ms": ({"speed": 10.0}, on_the_cleat, host_cleat, 1e-4, 1100),
    "cleat in an OpenCRG file, 0.1 ms": ({"speed": 10.0}, on_the_cleat, "cleat.crg", 1e-4,
                                         1100),
    "brake": ({"speed": 10.0}, braking, None, 5e-4, 200),
    "wheel motion": ({"speed": 10.0}, wheel_moving, None, 1e-3, 100),
    "held wheel": ({"speed": 10.0, "wheel_free": False},
                   lambda t: dict(wheel_torque=-5000.0), rise, 5e-4, 160),
    "at rest": ({"speed": 0.0}, lambda t: {}, shaker, 1e-3, 100),
    "driven": ({"speed": 10.0, "wheel_driven": True}, driven_to_a_lock, wave, 5e-4, 120),
}


@pytest.fixture(scope="module")
def road_files(tmp_path_factory):
    """The cleat as a profile file and as an OpenCRG file (KDBI, three long sections)."""
    folder = tmp_path_factory.mktemp("roads")
    return {name: str(write_road(folder / name, CLEAT)) for name in ("cleat.txt", "cleat.crg")}


def outputs_of(path, parameters, signal, road, h, steps, road_files=None):
    """(steps + 1, 11) outputs, (steps + 1,) in_contact and (steps + 1, 16) road_x, from
    before the first step on, and the instance's log."""
    road_file = road_files[road] if isinstance(road, str) else None
    fmu = Wheel(path, road_file=road_file, **parameters).start()
    host_road = None if isinstance(road, str) else road
    rows, contact, asked = [fmu.outputs()], [fmu.fmu.getBoolean([fmu.vr["in_contact"]])[0]], [
        fmu.asked()]
    for _ in range(steps):
        rows.append(fmu.step(h, host_road, **signal(fmu.t)))
        contact.append(fmu.fmu.getBoolean([fmu.vr["in_contact"]])[0])
        asked.append(fmu.asked())
    fmu.close()
    return np.array(rows), np.array(contact), np.array(asked), fmu.log


def scales(speed):
    spin = max(speed / RADIUS, 1.0)
    return np.array([LOAD, LOAD, LOAD * RADIUS, LOAD, LOAD, spin, 1.0, RADIUS, RADIUS, 1.0,
                     RADIUS])


def scaled_difference(a, b, speed):
    """Per output, the largest difference over the run in the scale of its kind."""
    return np.abs(a - b).max(axis=0) / scales(speed)[:a.shape[1]]


@pytest.mark.parametrize("name", RUNS)
def test_the_native_fmu_gives_the_python_fmus_outputs(native_path, python_path, road_files,
                                                       name):
    parameters, signal, road, h, steps = RUNS[name]
    native, native_contact, native_asked, _ = outputs_of(native_path, parameters, signal, road,
                                                         h, steps, road_files)
    python, python_contact, python_asked, _ = outputs_of(python_path, parameters, signal, road,
                                                         h, steps, road_files)
    difference = scaled_difference(native, python, parameters["speed"])
    assert difference.max() < TOLERANCE, dict(zip(OUTPUTS, difference))
    assert np.array_equal(native[:, 6], python[:, 6])  # sliding points: a count
    assert np.array_equal(native_contact, python_contact)
    assert np.abs(native_asked - python_asked).max() < 1e-9  # where the road is wanted
    # the run moved the forces (a test of equal constants would pass too otherwise)
    assert np.ptp(python[:, 0]) > 1e-3 * LOAD
    # the loaded radius at the start: the tire's at this operating point (where a host places
    # its wheel to carry the load)
    assert python[0, 7] == pytest.approx(inplane_loaded_radius(parameters), abs=1e-12)
    if "cleat" in name:  # the cleat is felt: almost twice the load
        assert python[:, 0].max() > 1.5 * LOAD
    if isinstance(road, str):  # a road file: no queries
        assert not native_asked.any() and not python_asked.any()
    if name == "brake":
        assert python[-1, 1] < -1e3 and python[-1, 5] < python[0, 5]
        assert python[-1, 9] < -1e-3  # braking slip
    if name == "held wheel":
        assert np.all(native[:, 5] == native[0, 5])
    if name == "at rest":  # the shaker's heights replace the samples under the still tire:
        # the zone asked for again at every step once the one look ahead after the first holds
        # the road beyond the zone's front
        assert np.all(native_asked[2:] == native_asked[0])
        assert np.all(native_asked[1] > native_asked[0][-1])
    if name == "driven":  # the host's spin, and a locked wheel's drag
        assert native[-1, 5] == pytest.approx(0.0, abs=1e-9)
        assert python[-1, 1] < -0.5 * 0.8 * LOAD
        assert native[-1, 8] == RADIUS  # no spin: the effective radius is R


def test_the_host_road_is_asked_for_at_the_contact_points_resolution(native_path):
    """Before the first step the zone is asked for; rolling, the road ahead of what the tire
    holds, at most the contact point spacing apart, covering the zone's front over the step;
    the samples it keeps are the host's heights there (the native PositionRoad holds what the
    core's holds, checked through the state's road)."""
    fmu = Wheel(native_path, speed=10.0, x0=CLEAT_START_M).start()  # where it starts
    zone = fmu.asked()
    assert zone[0] < CLEAT_START_M < zone[-1] and np.allclose(np.diff(zone), np.diff(zone)[0])
    road = PositionRoad(TABLE["contact_zone_length"].start + 1.0)
    for _ in range(40):
        asked = fmu.asked()
        road.set_samples(asked, host_cleat(asked, fmu.t))
        fmu.step(1e-3, host_cleat, **on_the_cleat(fmu.t))
        ahead = fmu.asked()
        gaps = np.diff(ahead)
        assert np.all(gaps > 0) and gaps.max() <= TABLE["contact_point_spacing"].start + 1e-12 \
            or np.allclose(gaps, np.diff(zone))  # ahead, or the zone again
    state = state_unpack(fmu.fmu.serializeFMUstate(fmu.fmu.getFMUstate()), len(TABLE))
    fmu.close()
    model = state["model"][4 * STATE_MODEL_FLAGS:]
    _, ny, p, samples, _, n_dof, _ = struct.unpack_from(STEPPER_STATE_HEAD, model)
    at = struct.calcsize(STEPPER_STATE_HEAD) + 8 * (STEPPER_SCALARS + 3 * ny + 2 * p)
    held = np.frombuffer(model, "<f8", 3 * samples, at).reshape(-1, 3)
    assert samples == road.s.size > 3 * ROAD_QUERIES
    assert np.array_equal(held[:, 0], road.s) and np.array_equal(held[:, 1], road.z)
    # the running integral from the first sample kept, the core's to the bit
    assert np.array_equal(held[:, 2] - held[0, 2], road._at - road._at[0])


# -- refusals --------------------------------------------------------------------------------

def _refused(path, road_file=None, **parameters):
    """The status of fmi2ExitInitializationMode and the parameter problems logged, by name:
    {name: (the value it says, the message)}."""
    fmu = Wheel(path, road_file=road_file, **parameters)
    try:
        fmu.start()
        status = 0
    except FMICallException as error:
        status = error.status
    named = {}
    for _, message in fmu.log:
        found = re.match(r"parameter problem \d+/\d+: (\w+) = ('[^']*'|[^ :]+)", message)
        if found:
            value = found.group(2)
            named[found.group(1)] = (value.strip("'") if value.startswith("'")
                                     else float(value), message)
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


@pytest.mark.parametrize("case", ["missing", "folder", "malformed", "offset on a profile"])
def test_a_road_file_that_cannot_be_used_is_refused_at_initialisation(
        native_path, python_path, tmp_path, case):
    """A missing, a folder, a malformed road file (or an offset a profile cannot take) is
    refused by fmi2ExitInitializationMode with fmi2Error and a message naming road_file, the
    path and what is wrong, in both runtimes alike, with every other problem at once."""
    path = tmp_path / {"missing": "nowhere.crg", "folder": "roads",
                       "malformed": "bad.txt", "offset on a profile": "good.txt"}[case]
    if case == "folder":
        path.mkdir()
    elif case == "malformed":
        path.write_text("distance_m,height_m\n0,0\n1,abc\n")
    elif case == "offset on a profile":
        path.write_text("distance_m,height_m\n0,0\n1,0.01\n")
    what = {"missing": "cannot be read", "folder": "is a folder", "malformed": "line 3",
            "offset on a profile": "a profile file has no width"}[case]
    said = []
    for runtime in (native_path, python_path):
        extra = {"road_lateral_offset": 0.5} if case == "offset on a profile" else {}
        status, named, fmu = _refused(runtime, road_file=str(path), load=-1.0, **extra)
        assert status == 3
        assert set(named) == {"road_file", "load"}  # every problem at once, the road's first
        value, message = named["road_file"]
        assert value == str(path) and what in message, message
        assert message.startswith("parameter problem 1/2: road_file = ")
        said.append(message)
        fmu.fmu.freeInstance()
    assert said[0] == said[1]
    # alone, the road's problem is the only one
    status, named, fmu = _refused(native_path, road_file=str(path), **extra)
    assert status == 3 and set(named) == {"road_file"}
    fmu.fmu.freeInstance()


def test_a_wheel_leaving_the_road_files_extent_is_warned_once(native_path, python_path,
                                                              road_files):
    """Beyond a road file's extent the road is level at its end heights: a warning once when
    the contact zone leaves the file's road (and never while it stays on it), the same in both
    runtimes, naming the file and its extent."""
    warnings = []
    for path in (native_path, python_path):
        fmu = Wheel(path, road_file=road_files["cleat.txt"], speed=10.0).start()
        for _ in range(100):  # from x = 1.3 m: the zone's front leaves the road at 1.75 m
            fmu.step(1e-3, **dict(wheel_x=1.3 + 10.0 * fmu.t, wheel_vx=10.0))
        said = [(s, m) for s, m in fmu.log if "reaches beyond the road file" in m]
        fmu.close()
        assert len(said) == 1 and said[0][0] == 1, said  # fmi2Warning
        warnings.append(re.sub(r"at t = \S+ s", "", said[0][1]))
    assert warnings[0] == warnings[1]
    assert road_files["cleat.txt"] in warnings[0] and "(0 to 2.02 m along it)" in warnings[0]
    # starting on the file's road and staying on it: no warning
    fmu = Wheel(native_path, road_file=road_files["cleat.txt"], speed=10.0).start()
    for _ in range(20):
        fmu.step(1e-3, **on_the_cleat(fmu.t))
    assert not [m for _, m in fmu.log if "reaches beyond" in m]
    fmu.close()


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
                                         ("wheel_vx", MAX_VELOCITY_M_S),
                                         ("wheel_x", MAX_ROAD_POSITION_M),
                                         ("wheel_z", MAX_ROAD_HEIGHT_M),
                                         ("road_z_7", MAX_ROAD_HEIGHT_M)])
def test_an_input_beyond_its_limit_is_refused_alike(native_path, python_path, name, limit):
    """At its limit an input is taken; just beyond it (or not finite) both FMUs refuse it
    with fmi2Error and the same words, and step on as before."""
    messages = []
    for path in (native_path, python_path):
        fmu = Wheel(path, speed=10.0).start()
        fmu.fmu.setReal([fmu.vr[name]], [limit])  # taken
        for bad in (1.000001 * limit, -1.000001 * limit, float("nan")):
            with pytest.raises(FMICallException) as error:
                fmu.fmu.setReal([fmu.vr[name]], [bad])
            assert error.value.status == 3
        messages.append(fmu.log[-2][1])
        fmu.fmu.setReal([fmu.vr[name]], [TABLE[name].start])
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
        fmu = Wheel(path, speed=10.0).start()
        rows = []
        for h in sizes:
            rows.append(fmu.step(h, wave, **braking(fmu.t)))
        with pytest.raises(FMICallException) as error:
            fmu.fmu.doStep(fmu.t, 5e-8)
        assert error.value.status == 3
        assert "shortest step" in fmu.log[-1][1]
        rows.append(fmu.step(1e-3, wave, **braking(fmu.t)))
        end = fmu.t
        fmu.close()
        return np.array(rows), end

    native, end = run(native_path)
    python, _ = run(python_path)
    assert end == pytest.approx(sum(sizes) + 1e-3, abs=1e-15)
    assert np.all(np.isfinite(native))
    assert scaled_difference(native, python, 10.0).max() < TOLERANCE


def test_a_refused_step_changes_nothing(native_path, python_path):
    """A step the tire refuses (the force beyond its limit: the wheel centre put far into the
    road) leaves the host's road, the origin and the tire as they were: the next steps are
    those of a run that never tried it, in both runtimes."""
    for path in (native_path, python_path):
        runs = []
        for tried in (False, True):
            fmu = Wheel(path, speed=10.0).start()
            rows = []
            for k in range(30):
                if tried and k == 12:
                    with pytest.raises(FMICallException):
                        fmu.step(1e-3, wave, wheel_z=AT_LOAD - 0.2)
                rows.append(fmu.step(1e-3, wave, **wheel_moving(fmu.t)))
            runs.append(np.array(rows))
            fmu.close()
        assert np.array_equal(runs[0], runs[1]), path


# -- FMU states ------------------------------------------------------------------------------

def _run_on(fmu, t, h, k_range):
    fmu.t = t
    return np.array([fmu.step(h, host_cleat, **on_the_cleat(fmu.t) | braking(fmu.t))
                     for _ in k_range])


def test_fmu_states_round_trip_bit_for_bit(native_path):
    """The host road's samples, the origin and the tire go into a state and come back: the
    run from it is the same to the bit, in this instance and in a fresh one given the
    bytes."""
    h = 1e-3
    fmu = Wheel(native_path, speed=10.0).start()
    _run_on(fmu, 0.0, h, range(20))
    state, t = fmu.fmu.getFMUstate(), fmu.t
    data = fmu.fmu.serializeFMUstate(state)
    first = _run_on(fmu, t, h, range(20))
    fmu.fmu.setFMUstate(state)
    assert np.array_equal(_run_on(fmu, t, h, range(20)), first)
    fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(data))
    assert np.array_equal(_run_on(fmu, t, h, range(20)), first)
    fmu.fmu.freeFMUstate(state)
    fmu.close()
    # a fresh instance, never initialised, given the bytes: the same tire and the same bits
    fresh = Wheel(native_path, speed=10.0)
    fresh.fmu.setFMUstate(fresh.fmu.deSerializeFMUstate(data))
    assert np.array_equal(_run_on(fresh, t, h, range(20)), first)
    fresh.close()


@pytest.mark.parametrize("road", ["host", "file"])
def test_a_state_of_one_runtime_continues_in_the_other(native_path, python_path, road_files,
                                                       road):
    """The model part of a state is the same bytes in both runtimes (the stepper's layout,
    the host's samples and the origin with it), so a state written by either, under the
    other's GUID, continues in the other as in its own runtime, to 1e-9 of the load; the
    road_file goes with the state (a fresh instance restores it with its road)."""
    h = 1e-3
    road_file = road_files["cleat.crg"] if road == "file" else None
    ends = {}
    for writer, reader in ((native_path, python_path), (python_path, native_path)):
        fmu = Wheel(writer, road_file=road_file, speed=10.0).start()
        _run_on(fmu, 0.0, h, range(25))
        t, data = fmu.t, fmu.fmu.serializeFMUstate(fmu.fmu.getFMUstate())
        own = _run_on(fmu, t, h, range(15))
        fmu.close()
        guid = read_model_description(str(reader)).guid
        f = state_unpack(data, len(TABLE))
        moved = state_pack(f["phase"], guid, f["time"], f["start_time"], bool(f["stale"]),
                           f["values"], f["model"], f["reason"].decode(),
                           [road_file or ""])
        other = Wheel(reader, speed=10.0)  # fresh: the state's parameters and road_file
        other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(moved))
        assert other.fmu.getString([other.vr["road_file"]]) == [(road_file or "").encode()]
        continued = _run_on(other, t, h, range(15))
        other.close()
        assert scaled_difference(own, continued, 10.0).max() < TOLERANCE
        ends[writer] = f["model"]
    native, python = ends[native_path], ends[python_path]
    assert len(native) == len(python)  # the same layout: the same number of road samples
    head = 4 * STATE_MODEL_FLAGS + struct.calcsize(STEPPER_STATE_HEAD)
    scalars = [np.frombuffer(m, "<f8", STEPPER_SCALARS, head) for m in (native, python)]
    assert np.array_equal(np.isnan(scalars[0]), np.isnan(scalars[1]))
    assert np.allclose(scalars[0][24:26], scalars[1][24:26], rtol=0, atol=1e-12)  # the origin


def _foreign_basis(data: bytes, n_values: int, shift_dofs: float = 0.0) -> bytes:
    """The state as another build of the same tire would have written it: another basis
    fingerprint, its coordinates scrambled (they refer to that basis), its DOFs kept; with
    ``shift_dofs`` the DOFs also moved off this basis (a shape no build of it reaches)."""
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
                      f["values"], bytes(model), f["reason"].decode(),
                      [s.decode() for s in f["strings"].split(b"\0")[:-1]])


@pytest.mark.parametrize("runtime", ["native", "python"])
def test_a_state_of_another_basis_continues_or_is_refused(native_path, python_path, runtime):
    """A state written by a build whose reduced basis came out otherwise (another BLAS, thread
    count or CPU: other signs and rotations of the modes) is taken into this build's basis
    through the tire's own DOFs it carries, and continues as the original within 1e-9 of the
    load; one whose shape lies outside this basis is refused, saying why, never stepped."""
    path = native_path if runtime == "native" else python_path
    h = 5e-4
    fmu = Wheel(path, speed=10.0).start()
    for _ in range(20):
        fmu.step(h, wave, **wheel_moving(fmu.t) | braking(fmu.t))
    t, data = fmu.t, fmu.fmu.serializeFMUstate(fmu.fmu.getFMUstate())
    n_values = len(read_model_description(str(path)).modelVariables)

    def run_on():
        fmu.t = t
        return np.array([fmu.step(h, wave, **wheel_moving(fmu.t) | braking(fmu.t))
                         for _ in range(20)])

    first = run_on()
    fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(_foreign_basis(data, n_values)))
    assert np.abs(run_on() - first)[:, :3].max() < 1e-9 * LOAD
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
        if v.type == "String":
            return v.start
        return v.start.lower() in ("true", "1") if v.type == "Boolean" else float(v.start)

    def variables(md):
        return [(v.name, v.type, v.causality, v.variability, v.unit, start(v))
                for v in md.modelVariables]

    assert variables(native) == variables(python)
    # wheel_z starts where the tire carries its load (the loaded radius both builds bake)
    assert start(next(v for v in native.modelVariables if v.name == "wheel_z")) == \
        inplane_loaded_radius({}) == pytest.approx(AT_LOAD, abs=1e-12)
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


def test_a_native_fmu_built_for_another_load_starts_its_wheel_at_that_loaded_radius(
        tmp_path):
    """The builder bakes wheel_z at the loaded radius of the tire and operating point it is
    built for: a host that leaves wheel_z unset has the tire carry the load it was built at."""
    from tire_fmu.native.builder import build_native_inplane_fmu

    path = build_native_inplane_fmu(tmp_path, start_values={"load": 0.6 * LOAD},
                                    platforms=("linux64",))
    start = float(next(v.start for v in read_model_description(str(path)).modelVariables
                       if v.name == "wheel_z"))
    assert start > AT_LOAD  # a lighter load deflects less
    fmu = Instance(str(path), format_log=True).start()
    assert fmu.fmu.getReal([fmu.vr["loaded_radius"]])[0] == pytest.approx(start, abs=1e-9)
    fmu.fmu.setReal([fmu.vr["wheel_z"]], [start])  # its start value, set as a host sets it
    fmu.fmu.doStep(0.0, 1e-3)
    assert fmu.fmu.getReal([fmu.vr["rim_Fz"]])[0] == pytest.approx(0.6 * LOAD, rel=1e-3)
    fmu.close()


def test_no_output_declares_a_dependency_and_none_feeds_through(native_path, python_path):
    """The outputs declared no dependencies, which FMI reads as every input, and a host
    looking for algebraic loops found false ones: each output is the last step's."""
    from fmpy.validation import validate_fmu

    from tire_fmu.fmu.interface import output_dependencies

    names = [v.name for v in inplane_fmu_variables() if v.causality == "output"]
    assert output_dependencies(inplane_fmu_variables()) == {name: () for name in names}
    inputs = [v.name for v in inplane_fmu_variables() if v.causality == "input"]
    for path in (python_path, native_path):
        assert declared_dependencies(path) == {name: [] for name in names}, path
        assert validate_fmu(str(path)) == []
        run = Wheel(path, speed=10.0).start()
        run.step(1e-3, host_cleat, **wheel_moving(0.0))
        before = run.outputs(), run.asked()
        for name in inputs:
            run.fmu.setReal([run.vr[name]], [1e-3])
            after = run.outputs(), run.asked()
            assert all(np.array_equal(a, b) for a, b in zip(after, before)), (path, name)
        run.close()


def test_a_bad_reference_is_refused_and_road_file_is_a_string(native_path, python_path):
    """TireInPlane's message named TireModal ("TireModal has 49 variables"); road_file is
    the FMU's String: got and set as one, a Real's reference refused for it."""
    count = len(inplane_fmu_variables())
    for path, name in ((python_path, "TireInPlane"), (native_path, "TireInPlaneNative")):
        run = Wheel(path)
        assert run.fmu.getString([run.vr["road_file"]]) == [b""]
        run.fmu.setString([run.vr["road_file"]], ["some road.crg"])
        assert run.fmu.getString([run.vr["road_file"]]) == [b"some road.crg"]
        run.fmu.setString([run.vr["road_file"]], [""])
        run.start()
        with pytest.raises(FMICallException):  # fixed after initialisation
            run.fmu.setString([run.vr["road_file"]], ["other.crg"])
        assert run.fmu.getString([run.vr["road_file"]]) == [b""]
        for call, arguments in ((run.fmu.getReal, ([999],)),
                                (run.fmu.setReal, ([999], [0.0])),
                                (run.fmu.getString, ([run.vr["wheel_x"]],))):
            with pytest.raises(FMICallException):
                call(*arguments)
        said = [m for status, m in run.log if status >= 3][1:]
        missing = MESSAGES["REFERENCE_MISSING"] % (999, name, count)
        wrong = MESSAGES["REFERENCE_TYPE"] % (run.vr["wheel_x"], "wheel_x", "Real", "Real",
                                              "Real")
        assert said == [MESSAGES["REFUSED"] % (call, why) for call, why in (
            ("fmi2GetReal", missing), ("fmi2SetReal", missing),
            ("fmi2GetString", wrong))], said
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
    reference = in_host(native_path, "fmpy", LOAD, 10.0, tmp_path, inplane=True)
    other = in_host(native_path, host, LOAD, 10.0, tmp_path, inplane=True)
    assert reference.shape == other.shape == (400, 7)
    assert np.ptp(reference[:, 1]) > 1e3  # the brake and the wheel's lift were felt
    assert scaled_difference(reference, other, 10.0).max() < TOLERANCE


def test_in_a_fresh_process_the_python_fmu_gives_the_native_fmus_outputs(native_path,
                                                                          python_path, tmp_path):
    """Each FMU alone in a new process (no tire_fmu imported before it: the Python FMU runs
    the package its resources carry), rolling at 10 m/s, lifted off the road and braked."""
    native = in_host(native_path, "fmpy", LOAD, 10.0, tmp_path, inplane=True)
    python = in_host(python_path, "fmpy", LOAD, 10.0, tmp_path, inplane=True)
    assert np.ptp(native[:, 0]) > 0.5 * LOAD  # off the road and back
    assert scaled_difference(native, python, 10.0).max() < TOLERANCE


@needs_windows_tools
def test_win64_under_wine_gives_the_linux64_and_fmpys_outputs(native_path, tmp_path):
    """A plain C host (native_host/host.c) runs the win64 binary under wine and the linux64
    one over a brake and the wheel's motion: the outputs of both, and fmpy's, agree; the
    statuses and the log lines are the same (but the build's CPU time)."""
    zipfile.ZipFile(native_path).extractall(tmp_path)
    guid = read_model_description(str(native_path)).guid
    vr = {v.name: i for i, v in enumerate(inplane_fmu_variables())}
    h, steps = 1e-4, 600

    def given(t):
        return dict(zip(WHEEL, wheel_inputs(10.0, t, **wheel_moving(t) | braking(t))))

    lines = [f"real {vr['speed']} 10.0", "init"]
    for k in range(steps):
        lines += [f"real {vr[name]} {value!r}" for name, value in given(k * h).items()]
        lines.append(f"step {k * h!r} {h!r}")
    commands = tmp_path / "commands.txt"
    commands.write_text("\n".join(lines) + "\n")
    binaries = tmp_path / "binaries"
    linux = run_host(compile_host(tmp_path, windows=False),
                     binaries / "linux64" / "TireInPlaneNative.so", guid, commands)
    windows = run_host(compile_host(tmp_path, windows=True),
                       binaries / "win64" / "TireInPlaneNative.dll", guid, commands)
    fmpy_run, _, _, _ = outputs_of(native_path, {"speed": 10.0},
                                   lambda t: wheel_moving(t) | braking(t), None, h, steps)
    n = len(OUTPUTS)
    assert scaled_difference(host_outputs(linux)[:, :n], fmpy_run[1:], 10.0).max() < TOLERANCE
    assert scaled_difference(host_outputs(windows)[:, :n], host_outputs(linux)[:, :n],
                             10.0).max() < TOLERANCE
    assert np.ptp(fmpy_run[:, 1]) > 1e3

    def said(run):
        return [line.strip() for line in run if not line.startswith("out ")
                and "ready in" not in line]

    assert said(linux) == said(windows)
    assert said(linux).count("status step 0") == steps


def test_a_plain_c_host_gives_road_file_and_saves_and_restores_the_state(native_path,
                                                                         road_files, tmp_path):
    """native_host/host.c sets road_file with fmi2SetString (and reads it back), rolls over
    the cleat in the file, serialises a state, steps on, restores the state from its bytes
    and steps again: the same outputs to the bit, fmpy's outputs, and (under valgrind where
    it is installed) no invalid access and no leak in the String and state code."""
    zipfile.ZipFile(native_path).extractall(tmp_path)
    guid = read_model_description(str(native_path)).guid
    vr = {v.name: i for i, v in enumerate(inplane_fmu_variables())}
    h, road_file = 1e-3, road_files["cleat.crg"]

    def steps(first, last):
        lines = []
        for k in range(first, last):
            given = wheel_inputs(10.0, k * h, **on_the_cleat(k * h))
            lines += [f"real {vr[name]} {value!r}" for name, value in zip(WHEEL, given)]
            lines.append(f"step {k * h!r} {h!r}")
        return lines

    commands = tmp_path / "commands.txt"
    commands.write_text("\n".join([f"real {vr['speed']} 10.0",
                                   f"string {vr['road_file']} {road_file}", "init"] +
                                  steps(0, 60) + ["save"] + steps(60, 110) + ["restore"] +
                                  steps(60, 110) + [f"string {vr['road_file']} other.crg",
                                                    f"getstring {vr['road_file']}"])
                        + "\n")
    host = compile_host(tmp_path, windows=False)
    binary = tmp_path / "binaries" / "linux64" / "TireInPlaneNative.so"
    if shutil.which("valgrind"):
        done = subprocess.run(["valgrind", "--error-exitcode=9", "--leak-check=full",
                               "--errors-for-leak-kinds=definite,indirect", "-q", str(host),
                               str(binary), guid, str(commands)],
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-3000:]
        lines = done.stdout.splitlines()
    else:
        lines = run_host(host, binary, guid, commands)
    assert f"string {road_file}" in lines  # got back as set
    assert any(f"road {road_file} (KDBI" in line for line in lines)  # the file it stepped on
    statuses = [line for line in lines if line.startswith("status ")]
    assert statuses[:3] == ["status real 0", "status string 0", "status init 0"]
    assert "status save 0" in statuses and "status restore 0" in statuses
    # fixed after initialisation: refused, the value kept
    assert statuses[-2:] == ["status string 3", "status getstring 0"]
    out = host_outputs(lines)[:, :len(OUTPUTS)]
    assert out.shape[0] == 160
    assert np.array_equal(out[60:110], out[110:])  # the restored state: the same bits
    fmpy_run, _, _, _ = outputs_of(native_path, {"speed": 10.0}, on_the_cleat, "cleat.crg", h,
                                   110, road_files)
    # (valgrind runs the arithmetic on its own CPU: the same to rounding, not to the bit)
    assert scaled_difference(out[:110], fmpy_run[1:], 10.0).max() < TOLERANCE
    assert out[:, 0].max() > 1.5 * LOAD  # the cleat in the file was felt
