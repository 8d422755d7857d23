"""TireInPlane.fmu (the in-plane tire as a pythonfmu FMU) run through fmpy against the core's
stepper in process: the same numbers, the FMI refusals, parameter problems, FMU states."""

import numpy as np
import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmpy.fmi1 import FMICallException  # noqa: E402
from inplane_support import Instance  # noqa: E402

from tire_fmu.core.inplane_host import HostSettings, build_host_stepper  # noqa: E402
from tire_fmu.core.parameters import TireParameters  # noqa: E402

pytestmark = pytest.mark.fmu


@pytest.fixture(scope="module")
def fmu_path(tmp_path_factory):
    from tire_fmu.fmu.builder import build_inplane_fmu

    return build_inplane_fmu(tmp_path_factory.mktemp("inplane_fmu"))


def _drive(k, h):
    """A brake torque, a wheel bouncing, the axle slowing and a bump in the road."""
    t = k * h
    return dict(wheel_torque=-2500.0 if t > 0.01 else 0.0,
                rim_z=2e-3 * np.sin(60.0 * t), rim_vz=0.12 * np.cos(60.0 * t),
                rim_x=-0.5 * 0.4 * t**2, rim_vx=-0.4 * t,
                road_z=8e-3 * np.sin(40.0 * t) ** 2, road_vz=8e-3 * 40.0 * np.sin(80.0 * t))


def test_the_fmu_gives_the_cores_numbers(fmu_path):
    """Through fmpy and in process, the same stepper over the same inputs: the same outputs
    (one code, so to rounding of the values' round trip: 1e-12 relative)."""
    h, steps = 1e-3, 40
    fmu = Instance(fmu_path, speed=10.0).start()
    core = build_host_stepper(HostSettings(speed_m_s=10.0)).stepper
    assert fmu.outputs()[0] == pytest.approx(core.outputs().rim_fz_n, rel=1e-12)
    worst, spread = 0.0, []
    for k in range(1, steps + 1):
        inputs = _drive(k, h)
        got = fmu.step(h, **inputs)
        o = core.advance(h, inputs["rim_x"], inputs["rim_vx"], inputs["rim_z"],
                         inputs["rim_vz"], inputs["wheel_torque"], inputs["road_z"],
                         inputs["road_vz"])
        want = np.array([o.rim_fz_n, o.rim_fx_n, o.rim_my_n_m, o.contact_fz_n, o.contact_fx_n,
                         o.spin_rad_s, o.sliding_points])
        worst = max(worst, float(np.max(np.abs(got - want) / np.maximum(np.abs(want), 1.0))))
        spread.append(got[1])
    fmu.close()
    assert worst < 1e-12
    assert np.ptp(spread) > 1e3  # Fx moved: the brake and the bump were felt
    # both ran the C step: the FMU its own library, the core the package's
    assert core.sim.stepping_with == "compiled"
    assert any("stepping with the compiled in-plane step" in m for _, m in fmu.log)


def test_states_round_trip_and_refused_steps_change_nothing(fmu_path):
    fmu = Instance(fmu_path, speed=10.0).start()
    for k in range(1, 6):
        fmu.step(1e-3, **_drive(k, 1e-3))
    state = fmu.fmu.getFMUstate()
    serialized = fmu.fmu.serializeFMUstate(state)
    t = fmu.t
    first = fmu.step(1e-3, **_drive(6, 1e-3))
    # a step shorter than the tire's shortest is refused, naming it
    with pytest.raises(FMICallException):
        fmu.fmu.doStep(fmu.t, 5e-8)
    assert "must be at least 1e-07 s, the in-plane tire's shortest step" in fmu.log[-1][1]
    fmu.step(1.5e-4, **_drive(7, 1e-3))  # off the tire's grid: taken
    fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(serialized))
    fmu.t = t
    assert np.array_equal(fmu.step(1e-3, **_drive(6, 1e-3)), first)
    fmu.close()


def test_parameter_problems_are_logged_all_at_once(fmu_path):
    fmu = Instance(fmu_path, n_elements=3, friction_coefficient=-1.0, load=-1.0,
                   step_size=0.5)
    with pytest.raises(FMICallException):
        fmu.start()
    lines = [message for status, message in fmu.log if "parameter problem" in message]
    assert len(lines) == 4 and all(m.startswith(f"parameter problem {i}/4: ")
                                   for i, m in enumerate(lines, 1))
    text = " ".join(lines)
    # in the FMU's names, with the value and what is allowed
    for said in ("load = -1 N", "n_elements = 3", "step_size = 0.5 s",
                 "friction_coefficient = -1"):
        assert said in text
    # and the FMU is in the error state, saying why
    with pytest.raises(FMICallException):
        fmu.fmu.doStep(0.0, 1e-3)
    assert "the parameters were refused" in fmu.log[-1][1]
    fmu.fmu.freeInstance()


def test_the_wheels_spin_and_the_brake_force_build_up(fmu_path):
    """Free rolling at 10 m/s spins the wheel at about V/R; a brake torque slows it below
    that and the tire pulls the rim backwards while the axle moment opposes the brake."""
    fmu = Instance(fmu_path, speed=10.0).start()
    free = [fmu.step(1e-3) for _ in range(20)][-1]
    braked = [fmu.step(1e-3, wheel_torque=-3000.0) for _ in range(60)][-1]
    fmu.close()
    radius = TireParameters().R
    assert free[5] == pytest.approx(10.0 / radius, rel=0.02)
    assert braked[5] < free[5]
    assert braked[1] < -1000.0 and braked[2] > 1000.0


def test_a_state_set_into_a_fresh_instance_builds_its_model_and_steps_on(fmu_path):
    """An FMU state carries the parameters: a new instance given it (no initialisation)
    builds the same tire and steps on with the first one's bits."""
    first = Instance(fmu_path, speed=10.0, friction_coefficient=0.6).start()
    for k in range(1, 8):
        first.step(1e-3, **_drive(k, 1e-3))
    data = first.fmu.serializeFMUstate(first.fmu.getFMUstate())
    expected = first.step(1e-3, **_drive(8, 1e-3))
    second = Instance(fmu_path)  # in initialisation mode, default parameters
    second.fmu.setFMUstate(second.fmu.deSerializeFMUstate(data))
    second.t = first.t - 1e-3
    assert np.array_equal(second.step(1e-3, **_drive(8, 1e-3)), expected)
    first.close()
    second.close()


def test_a_held_wheel_keeps_its_spin_and_a_finer_tire_step_divides_the_hosts(fmu_path):
    """wheel_free = false holds the spin at speed / R whatever the torque; a tire step that
    divides the host's runs that many steps per communication step, and the forces converge
    as it is refined."""
    radius = TireParameters().R
    held = Instance(fmu_path, speed=10.0, wheel_free=False).start()
    outputs = [held.step(1e-3, wheel_torque=-5000.0, road_z=2e-3 * min(k / 20, 1.0))
               for k in range(30)]
    held.close()
    assert all(o[5] == pytest.approx(10.0 / radius, rel=1e-12) for o in outputs)
    def smooth(t):  # from rest: a 4 mm (1 - cos) rise of the road and the brake ramped in
        u = min(t / 0.03, 1.0)
        w = np.pi / 0.03
        return dict(road_z=2e-3 * (1 - np.cos(np.pi * u)),
                    road_vz=2e-3 * w * np.sin(np.pi * u) if u < 1 else 0.0,
                    wheel_torque=-3000.0 * u)

    runs = []
    for step in (2e-4, 1e-4, 5e-5):
        fmu = Instance(fmu_path, speed=10.0, step_size=step).start()
        runs.append(np.array([fmu.step(2e-4, **smooth(k * 2e-4)) for k in range(1, 301)]))
        fmu.close()
    errors = [np.max(np.abs(runs[i][:, :2] - runs[2][:, :2])) for i in (0, 1)]
    assert np.ptp(runs[2][:, 0]) > 2e3 and np.ptp(runs[2][:, 1]) > 1e3
    # the difference falls as the tire's step is refined (not at second order: the step's
    # rebuild when the wheel's spin has drifted, and the road's samples, are per step)
    assert errors[1] < 0.01 * np.ptp(runs[2][:, 0])
    assert errors[1] < 0.75 * errors[0]
