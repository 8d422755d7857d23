"""Issue 37's long run: the in-plane FMU rolls from rest to 25 m/s, brakes back to rest and
stands there for 10 s, in one run, on an ISO 8608 class C road file, driven by a plain master
through fmpy (the wheel centre and the torque at t, then fmi2DoStep(t, h)).

The road is level where the wheel rolls steadily at 10, 20 and 25 m/s under a drive torque:
there the FMU's forces and spin are held to the steady solve of the full tire built at that
speed (core steady_rolling), within 1 %. Everywhere the spin, the slip and the forces are
continuous (no step of the host's changes them by more than the road and the torque can), and
at rest the wheel does not creep. The native FMU runs it (the Python one gives its numbers:
tests/test_inplane_native_fmu.py)."""

from __future__ import annotations

import numpy as np
import pytest
from inplane_support import Instance, core_stepper

from tire_fmu.core.iso8608 import iso8608_profile
from tire_fmu.core.obstacles import ProfileRoad
from tire_fmu.road_files import write_road

pytestmark = pytest.mark.fmu

H = 1e-3
START_M = 2.0
#: (duration s, acceleration m/s^2, torque N m): rest, up to 10 m/s, steady, up to 20, steady,
#: up to 25, steady, braking to rest, at rest
PHASES = ((0.5, 0.0, 0.0), (2.5, 4.0, 600.0), (1.0, 0.0, 600.0), (2.5, 4.0, 600.0),
          (1.0, 0.0, 600.0), (1.25, 4.0, 600.0), (1.0, 0.0, 600.0), (5.0, -5.0, -1500.0),
          (10.0, 0.0, 0.0))
STEADY_PHASES = (2, 4, 6)
#: the corner's unsprung mass (kg) and suspension (N/m, N s/m)
UNSPRUNG_KG, SPRING_N_M, DAMPER_N_S_M = 400.0, 3.0e5, 1.5e4
#: the last part of a steady phase the steady state is read over (s)
SETTLED_S = 0.4
#: level road this far (m) either side of each steady stretch, the random road rising
#: from and falling to it by half-cosines
LEVEL_MARGIN_M = 2.0


def schedule():
    """Per host step: time, wheel_x, wheel_vx, torque at t, and the phase."""
    t, x, v, rows = 0.0, START_M, 0.0, []
    for phase, (duration, acceleration, torque) in enumerate(PHASES):
        for _ in range(int(round(duration / H))):
            rows.append((t, x, v, torque, phase))
            x += v * H + 0.5 * acceleration * H * H
            v = max(v + acceleration * H, 0.0)
            t += H
    return np.array(rows)


def road_file(path, plan):
    """ISO 8608 class C, level at the datum where the wheel starts (where it stands at its
    loaded radius above the datum), over each steady stretch and where it comes to rest."""
    spacing = 0.005
    end = plan[-1, 1] + 5.0
    s = np.arange(0.0, end, spacing)
    heights = iso8608_profile("C", s.size, spacing, seed=7, fade_in_m=5.0).heights_m[:s.size]
    weight = np.ones_like(s)
    for phase in (0, *STEADY_PHASES, len(PHASES) - 1):
        stretch = plan[plan[:, 4] == phase, 1]
        lo, hi = stretch[0] - 0.5 - LEVEL_MARGIN_M, stretch[-1] + 0.5 + LEVEL_MARGIN_M
        ramp = 2.0
        for a, b, up in ((lo - ramp, lo, False), (hi, hi + ramp, True)):
            inside = (s >= a) & (s <= b)
            u = (s[inside] - a) / ramp
            weight[inside] = np.minimum(weight[inside],
                                        0.5 * (1 + np.cos(np.pi * (u if not up else 1 - u))))
        weight[(s > lo) & (s < hi)] = 0.0
    return write_road(path, ProfileRoad(s, heights * weight))


@pytest.fixture(scope="module")
def native_path(tmp_path_factory):
    from tire_fmu.native.builder import build_native_inplane_fmu

    return build_native_inplane_fmu(tmp_path_factory.mktemp("rest_to_rest"))


@pytest.fixture(scope="module")
def run(native_path, tmp_path_factory):
    plan = schedule()
    path = road_file(tmp_path_factory.mktemp("road") / "iso_c.crg", plan)
    fmu = Instance(str(native_path), format_log=True, x0=START_M, speed=0.0,
                   road_file=str(path))
    fmu.speed = 0.0
    fmu.start()
    # the wheel centre on a truck's corner: an unsprung mass on the suspension of a body that
    # runs level, integrated by the host (semi-implicit Euler, as many hosts do)
    z0, z, vz, load = fmu.z0, fmu.z0, 0.0, None
    rows = []
    for _, x, v, torque, _phase in plan:
        forces = fmu.step(H, wheel_x=x, wheel_vx=v, wheel_z=z, wheel_vz=vz, wheel_torque=torque)
        load = forces[0] if load is None else load
        vz += H * ((forces[0] - load) - SPRING_N_M * (z - z0) - DAMPER_N_S_M * vz) / UNSPRUNG_KG
        z += H * vz
        rows.append([*forces, *fmu.read("longitudinal_slip")])
    fmu.close()
    return plan, np.array(rows), fmu.log


def test_it_rolls_from_rest_to_25_m_s_brakes_to_rest_and_stands(run):
    plan, out, log = run
    assert not [m for status, m in log if status > 1]  # no error on the way
    speeds = plan[:, 2]
    assert speeds.max() == pytest.approx(25.0, abs=1e-9) and abs(speeds[-1]) < 1e-9
    fz, fx, spin, slip = out[:, 0], out[:, 1], out[:, 5], out[:, 7]
    load = fz[0]
    # continuous: the spin moves by a hundredth of its range in a host step at most (0.16 rad/s
    # of 38 measured), the slip and the forces by a fifth (the brake's 2.1 kN m step turns
    # the wheel's spin at dT/I, 0.004 of slip in 1 ms of a 0.04 range; the road's slopes at
    # 23 m/s move Fz by 3.7 kN and Fx by 1.3 kN in 1 ms, of 40 and 10 kN ranges): a restart
    # of the rolling, a lost tread state or a wrong sign at the speed's zero would jump further
    # (the slip while rolling: below 0.1 m/s it is over 0.1 m/s, and near rest any creep of
    # the tread is a large share of that)
    rolling = speeds > 1.0
    for column, share in ((spin, 0.01), (slip[rolling], 0.2), (fz, 0.2), (fx, 0.2)):
        assert np.abs(np.diff(column)).max() < share * np.ptp(column)
    assert np.abs(slip[rolling]).max() < 0.2  # the torques stay well inside the friction
    # at rest, after braking: the wheel stands (no creep) and the tire carries its load
    rest = plan[:, 4] == len(PHASES) - 1
    last = rest & (plan[:, 0] > plan[rest, 0][0] + 5.0)
    # the wheel's slow ringing on the tread (1.8e-3 rad/s 5 s after stopping) dies away
    final = plan[:, 0] > plan[-1, 0] - 1.0
    assert np.abs(spin[final]).max() < 1e-4 < np.abs(spin[last]).max()
    turned = np.sum(spin[last]) * H
    assert abs(turned) < 1e-4  # rad over the last 5 s: a creep would turn it on and on
    assert np.ptp(fz[last]) < 1e-3 * load and np.abs(fx[final]).max() < 1e-3 * load
    assert np.abs(fz[last] - load).max() < 0.01 * load  # back on the datum, at its load


@pytest.mark.parametrize("phase", STEADY_PHASES)
def test_the_steady_rolling_on_the_way_is_the_full_tires(run, phase):
    from tire_fmu.core.inplane_contact import InPlaneSimulator, steady_rolling

    plan, out, _ = run
    rows = (plan[:, 4] == phase) & (plan[:, 0] >= plan[plan[:, 4] == phase, 0][-1] - SETTLED_S)
    speed, torque = plan[rows, 2][0], plan[rows, 3][0]
    fz, fx, spin = (out[rows, k].mean() for k in (0, 1, 5))
    sim = core_stepper().sim
    steady = steady_rolling(InPlaneSimulator(sim.model, sim.n_elements, speed,
                                             sim.deflection_m, f_max_hz=sim.f_max_hz),
                            torque)
    assert fz == pytest.approx(steady.rim_fz_n, rel=0.01)
    assert fx == pytest.approx(steady.rim_fx_n, rel=0.01)
    assert spin == pytest.approx(steady.spin_rad_s, rel=0.01)
