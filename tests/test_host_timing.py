"""The four FMUs as a co-simulation master drives them: the inputs set before
fmi2DoStep(t, h) are the values at t (fmpy's simulate_fmu, libcosim, ecos and fmusim all set
them so), and the tire extends them over the step in one way (core/host_inputs.py).

The master here is written apart from the project's own helpers: fmpy's FMU2Slave and a plain
loop, as a user would write it. Checked for TireModal, TireModalNative, TireInPlane and
TireInPlaneNative alike:

- a smooth rim motion and a smooth road at a 1 ms host step give the outputs of a 0.1 ms one
  within 1 % of their range;
- a quarter car integrated semi-implicitly (the position from the new velocity), the usual
  host integrator, stays stable at 1 ms on a cleat;
- an inconsistent input (a 1 mm step of the rim's height with its rate zero) gives bounded
  forces, the same at either step;
- simulate_fmu from a start time of 1e9 s gives the outputs of a start at 0 (any step the FMU
  declares it takes is taken, exactly in time).

The in-plane FMUs take the wheel centre (wheel_x, wheel_vx along the road, wheel_z, wheel_vz
above its datum, from the loaded_radius they report after initialisation) and, with no road
file, the host's road by position: heights road_z_i at the road_x_i they ask for. The same
motions are given to them so (:class:`Master`); the road's bumps then lie at positions along
the road where the radial FMUs get them at the zone's front in time.
"""

import math

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave

pytestmark = pytest.mark.fmu

SPEED_M_S = 10.0
KINDS = ("TireModal", "TireModalNative", "TireInPlane", "TireInPlaneNative")


class _Built(dict):
    """The four FMUs, each built when a test first asks for it."""

    def __init__(self, folder):
        super().__init__()
        self.folder = folder

    def __missing__(self, kind):
        from tire_fmu.fmu.builder import build_fmu, build_inplane_fmu
        from tire_fmu.native import build_native_fmu
        from tire_fmu.native.builder import build_native_inplane_fmu

        build = {"TireModal": lambda: build_fmu(self.folder / "modal"),
                 "TireModalNative": lambda: build_native_fmu(
                     self.folder / "TireModalNative.fmu"),
                 "TireInPlane": lambda: build_inplane_fmu(self.folder / "inplane"),
                 "TireInPlaneNative": lambda: build_native_inplane_fmu(
                     self.folder / "inplane_native")}[kind]
        self[kind] = path = build()
        return path


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    return _Built(tmp_path_factory.mktemp("host_timing"))


def level(x):
    return np.zeros_like(x)


class Master:
    """A minimal master: one instance, inputs set at t, then fmi2DoStep(t, h).

    :meth:`step` takes the rim's motion as the deviation from rolling steadily at
    ``SPEED_M_S`` at the static load (``rim_z``, ``rim_vz``, ``rim_x``, ``rim_vx``) and the
    road as heights by position (``road``, m along the road from the wheel centre's start);
    it gives an in-plane FMU the wheel centre's state at t and the road where it asks, a
    radial one its own inputs (the road at its zone's front, ``road_z``, ``road_vz``)."""

    def __init__(self, path, start_time=0.0, **parameters):
        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName="master")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=start_time)
        self.fmu.enterInitializationMode()
        for name, value in parameters.items():
            self.fmu.setReal([self.vr[name]], [value])
        self.speed = parameters.get("speed", 0.0)
        self.wheel_centre = "wheel_z" in self.vr
        if self.wheel_centre:
            self.fmu.setReal([self.vr["wheel_vx"]], [self.speed])
        self.fmu.exitInitializationMode()
        self.start_time = self.t = start_time
        if self.wheel_centre:
            self.loaded_radius = self.read("loaded_radius")[0]
            self.asked = [self.vr[n] for n in self.vr if n.startswith("road_x_")]
            self.heights = [self.vr[n.replace("road_x_", "road_z_")]
                            for n in self.vr if n.startswith("road_x_")]

    def read(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def step(self, h, road=None, **inputs):
        if self.wheel_centre:
            t = self.t - self.start_time
            inputs = {"wheel_x": self.speed * t + inputs.get("rim_x", 0.0),
                      "wheel_vx": self.speed + inputs.get("rim_vx", 0.0),
                      "wheel_z": self.loaded_radius + inputs.get("rim_z", 0.0),
                      "wheel_vz": inputs.get("rim_vz", 0.0)}
            heights = (road or level)(np.array(self.fmu.getReal(self.asked)))
            self.fmu.setReal(self.heights, list(heights))
        else:  # the radial FMUs: no fore-aft input; the road at the zone's front (at 0.15 m)
            inputs = {n: v for n, v in inputs.items() if n not in ("rim_x", "rim_vx")}
            if road is not None:
                inputs |= road_at_front(road, self.speed * (self.t - self.start_time))
        names = [n for n in inputs if n in self.vr]
        assert len(names) == len(inputs), set(inputs) - set(names)
        self.fmu.setReal([self.vr[n] for n in names], [inputs[n] for n in names])
        self.fmu.doStep(self.t, h)
        self.t += h

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


#: Where the radial FMUs read the road: ahead of the wheel centre (their zone's front, m).
FRONT_M = 0.15


def rounded_bump(start_m, length_m, height_m):
    """A (1 - cos) bump on a level road (m along it): heights and slopes at x."""
    def road(x, slope=False):
        u = np.clip((np.asarray(x, dtype=float) - start_m) / length_m, 0.0, 1.0)
        if slope:
            on = (u > 0) & (u < 1)
            return np.where(on, 0.5 * height_m * 2 * np.pi * np.sin(2 * np.pi * u) / length_m,
                            0.0)
        return 0.5 * height_m * (1 - np.cos(2 * np.pi * u))
    return road


def road_at_front(road, travelled_m):
    """The radial FMUs' road inputs: the height and its rate at their zone's front."""
    at = np.array([travelled_m + FRONT_M])
    return {"road_z": float(road(at)[0]), "road_vz": float(road(at, slope=True)[0]) * SPEED_M_S}


#: A 10 mm, 0.5 m long rounded bump whose start the zone's front meets at 0.1 s.
BUMP = rounded_bump(1.0 + FRONT_M, 0.5, 1e-2)


def rim(t):
    """The wheel hopping 1 mm at 12 Hz (vertically, and half of it fore and aft), from rest
    (sin³: its rate and acceleration start at zero): values and rates at t."""
    w = 2 * math.pi * 12.0
    s, c = math.sin(w * t), math.cos(w * t)
    z, vz = 1e-3 * s**3, 3e-3 * w * s * s * c
    return {"rim_z": z, "rim_vz": vz, "rim_x": 0.5 * z, "rim_vx": 0.5 * vz}


def history(path, h, duration_s, outputs, inputs=rim, road=BUMP):
    master = Master(path, speed=SPEED_M_S)
    rows = []
    for k in range(int(round(duration_s / h))):
        master.step(h, road=road, **inputs(k * h))
        rows.append(master.read(*outputs))
    master.close()
    return np.array(rows)


def outputs_of(kind):
    return ("rim_Fz", "rim_Fx", "rim_My") if "InPlane" in kind else ("rim_Fz", "rim_Fx")


@pytest.mark.parametrize("kind", KINDS)
def test_a_1_ms_host_step_gives_the_outputs_of_a_tenth_of_it(fmus, kind):
    names = outputs_of(kind)
    coarse = history(fmus[kind], 1e-3, 0.25, names)
    fine = history(fmus[kind], 1e-4, 0.25, names)[9::10]
    for i, name in enumerate(names):
        error = np.abs(coarse[:, i] - fine[:, i]).max() / np.ptp(fine[:, i])
        assert error < 0.01, (kind, name, error)
    assert np.ptp(fine[:, 0]) > 1e3  # the motion and the bump are felt


def quarter_car(path, h, duration_s=0.5, wheel_kg=200.0):
    """A quarter car on the tire, integrated semi-implicitly, over a 20 mm cleat: the wheel
    (its mass without the tire's) on the tire, the body on the suspension; rim_Fz per step."""
    body_kg, k_s, c_s = 2500.0, 80e3, 8.5e3
    master = Master(path, speed=SPEED_M_S)
    load = master.read("rim_Fz")[0]
    zw = vw = zb = vb = 0.0
    forces = []
    cleat = rounded_bump(1.0 + FRONT_M, 0.3, 0.02)
    for _ in range(int(round(duration_s / h))):
        master.step(h, road=cleat, rim_z=zw, rim_vz=vw)
        fz = master.read("rim_Fz")[0]
        spring = k_s * (zb - zw) + c_s * (vb - vw)
        vw += h * ((fz - load) + spring) / wheel_kg
        zw += h * vw  # semi-implicit: the position from the new velocity
        vb += h * (-spring) / body_kg
        zb += h * vb
        forces.append(fz)
    master.close()
    return np.array(forces)


@pytest.mark.parametrize("kind", KINDS)
def test_a_semi_implicit_quarter_car_stays_stable_at_1_ms(fmus, kind):
    coarse = quarter_car(fmus[kind], 1e-3)
    fine = quarter_car(fmus[kind], 1e-4)[9::10]
    load = fine[0]
    assert np.all(np.isfinite(coarse))
    assert np.abs(coarse - load).max() < 2.0 * np.abs(fine - load).max()
    # the last 0.1 s: settled as the fine run is, no growing oscillation
    assert np.ptp(coarse[-100:]) < 0.05 * np.ptp(fine)


@pytest.mark.parametrize("kind", KINDS)
def test_a_rim_step_with_no_rate_gives_bounded_forces(fmus, kind):
    """rim_z jumping 1 mm with rim_vz zero: the rim goes there, the tire's mass does not (its
    momentum carries on): the force moves by about what the tire's stiffness gives for 1 mm,
    at either host step, and rings down."""
    def lifted(t):
        return {"rim_z": -1e-3 if t >= 0.05 else 0.0}

    runs = [history(fmus[kind], h, 0.6, ("rim_Fz",), lifted, road=None)[:, 0]
            for h in (1e-3, 1e-4)]
    load = runs[1][0]
    for forces in runs:
        assert np.abs(forces - load).max() < 20e3  # about ten times the static 1.5 MN/m * 1 mm
        late = forces[-len(forces) // 6:]
        assert np.abs(late - load).mean() == pytest.approx(1.5e3, rel=0.35)
    assert np.abs(runs[0] - runs[1][9::10]).max() < 0.2 * np.abs(runs[1] - load).max()


@pytest.mark.parametrize("kind", KINDS)
def test_simulate_fmu_from_a_start_time_of_1e9_s_gives_the_run_from_0(fmus, kind):
    """There a double resolves 1.2e-7 s, so simulate_fmu passes each 1 ms step as the
    difference of two time points, a few 1e-7 s off: the FMU takes it as the step it is and
    gives the outputs of a run from 0 (the rim lowered 1 mm from the start and rolling at
    10 m/s: the tire rings). simulate_fmu itself ends a run within 1e-9 of the stop time
    relative, a second at 1e9 s, and takes every sample of an input table as an event there,
    so the inputs are start values and the rows it gives are compared. The in-plane FMUs take
    the wheel centre's position, which constant inputs cannot move along: their wheel stands
    (speed 0) 1 mm below its loaded radius with a 2 kN m torque on it (Fz and Fx ring)."""
    names = list(outputs_of(kind))
    h, duration = 1e-3, 1.3
    starts = {"speed": SPEED_M_S, "rim_z": -1e-3}
    if "InPlane" in kind:
        md = read_model_description(str(fmus[kind]))
        loaded = next(float(v.start) for v in md.modelVariables if v.name == "wheel_z")
        starts = {"speed": 0.0, "wheel_z": loaded - 1e-3, "wheel_torque": 2e3}

    def run(start):
        result = simulate_fmu(str(fmus[kind]), start_time=start, stop_time=start + duration,
                              output_interval=h, output=names, start_values=starts)
        return np.column_stack([result[n] for n in names])

    from_zero, late = run(0.0), run(1e9)
    rows = len(late)
    assert rows > 250
    for i in range(len(names)):
        scale = np.ptp(from_zero[:rows, i])
        assert scale > 10.0  # the tire rings: there is something to compare
        assert np.abs(late[:, i] - from_zero[:rows, i]).max() <= 1e-6 * scale, names[i]
