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
- an inconsistent input (a 1 mm step of rim_z with rim_vz zero) gives bounded forces, the same
  at either step;
- simulate_fmu from a start time of 1e9 s gives the outputs of a start at 0 (any step the FMU
  declares it takes is taken, exactly in time).
"""

import math

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave

pytestmark = pytest.mark.fmu

SPEED_M_S = 10.0
KINDS = ("TireModal", "TireModalNative", "TireInPlane", "TireInPlaneNative")


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    from tire_fmu.fmu.builder import build_fmu, build_inplane_fmu
    from tire_fmu.native import build_native_fmu
    from tire_fmu.native.builder import build_native_inplane_fmu

    folder = tmp_path_factory.mktemp("host_timing")
    return {"TireModal": build_fmu(folder / "modal"),
            "TireModalNative": build_native_fmu(folder / "TireModalNative.fmu"),
            "TireInPlane": build_inplane_fmu(folder / "inplane"),
            "TireInPlaneNative": build_native_inplane_fmu(folder / "inplane_native")}


class Master:
    """A minimal master: one instance, inputs set at t, then fmi2DoStep(t, h)."""

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
        self.fmu.exitInitializationMode()
        self.t = start_time

    def read(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def step(self, h, **inputs):
        names = [n for n in inputs if n in self.vr]
        self.fmu.setReal([self.vr[n] for n in names], [inputs[n] for n in names])
        self.fmu.doStep(self.t, h)
        self.t += h

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def rim_and_road(t):
    """The wheel hopping 1 mm at 12 Hz (vertically, and half of it fore and aft), from rest
    (sin³: its rate and acceleration start at zero), and a 10 mm, 0.5 m long rounded bump at
    the zone front from 0.1 s on: values and rates at t."""
    w = 2 * math.pi * 12.0
    s, c = math.sin(w * t), math.cos(w * t)
    z, vz = 1e-3 * s**3, 3e-3 * w * s * s * c
    u = (SPEED_M_S * t - 1.0) / 0.5
    bump, bump_rate = 0.0, 0.0
    if 0.0 <= u <= 1.0:
        bump = 5e-3 * (1 - math.cos(2 * math.pi * u))
        bump_rate = 5e-3 * 2 * math.pi * math.sin(2 * math.pi * u) * SPEED_M_S / 0.5
    return {"rim_z": z, "rim_vz": vz, "rim_x": 0.5 * z, "rim_vx": 0.5 * vz,
            "road_z": bump, "road_vz": bump_rate}


def history(path, h, duration_s, outputs, inputs=rim_and_road):
    master = Master(path, speed=SPEED_M_S)
    rows = []
    for k in range(int(round(duration_s / h))):
        master.step(h, **inputs(k * h))
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
    for i in range(int(round(duration_s / h))):
        u = (SPEED_M_S * i * h - 1.0) / 0.3
        cleat = 0.01 * (1 - math.cos(2 * math.pi * u)) if 0 <= u <= 1 else 0.0
        cleat_rate = (0.01 * 2 * math.pi * math.sin(2 * math.pi * u) * SPEED_M_S / 0.3
                      if 0 <= u <= 1 else 0.0)
        master.step(h, rim_z=zw, rim_vz=vw, road_z=cleat, road_vz=cleat_rate)
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

    runs = [history(fmus[kind], h, 0.6, ("rim_Fz",), lifted)[:, 0] for h in (1e-3, 1e-4)]
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
    so the inputs are start values and the rows it gives are compared."""
    names = list(outputs_of(kind))
    h, duration = 1e-3, 1.3

    def run(start):
        result = simulate_fmu(str(fmus[kind]), start_time=start, stop_time=start + duration,
                              output_interval=h, output=names,
                              start_values={"speed": SPEED_M_S, "rim_z": -1e-3})
        return np.column_stack([result[n] for n in names])

    from_zero, late = run(0.0), run(1e9)
    rows = len(late)
    assert rows > 250
    for i in range(len(names)):
        scale = np.ptp(from_zero[:rows, i])
        assert scale > 10.0  # the tire rings: there is something to compare
        assert np.abs(late[:, i] - from_zero[:rows, i]).max() <= 1e-6 * scale, names[i]
