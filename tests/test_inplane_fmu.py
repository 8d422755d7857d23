"""TireInPlane.fmu (the in-plane tire as a pythonfmu FMU) run through fmpy against the core's
stepper in process: the same numbers, the FMI refusals, parameter problems, FMU states."""

import numpy as np
import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmpy.fmi1 import FMICallException  # noqa: E402
from inplane_support import ROAD_QUERIES, ROAD_X, WHEEL_OUTPUTS, Instance, core_stepper  # noqa: E402

from tire_fmu.core.parameters import TireParameters  # noqa: E402

pytestmark = pytest.mark.fmu


@pytest.fixture(scope="module")
def fmu_path(tmp_path_factory):
    from tire_fmu.fmu.builder import build_inplane_fmu

    return build_inplane_fmu(tmp_path_factory.mktemp("inplane_fmu"))


def bumpy(x):
    """The host's road: 8 mm humps every 0.39 m (at 10 m/s the 40 rad/s of sin^2)."""
    return 8e-3 * np.sin(4.0 * np.asarray(x)) ** 2


def _drive(fmu):
    """At the instance's t: a brake torque, the wheel centre bouncing and slowing."""
    t = fmu.t
    return dict(wheel_torque=-2500.0 if t > 0.01 else 0.0,
                wheel_z=fmu.z0 + 2e-3 * np.sin(60.0 * t), wheel_vz=0.12 * np.cos(60.0 * t),
                wheel_x=fmu.speed * t - 0.5 * 0.4 * t**2, wheel_vx=fmu.speed - 0.4 * t)


def test_the_fmu_gives_the_cores_numbers(fmu_path):
    """Through fmpy and in process, the same stepper over the same wheel centre and the same
    host road (the heights given where the FMU asked, which is where the core asks): the same
    outputs (one code, so to rounding of the values' round trip: 1e-12 relative)."""
    h, steps = 1e-3, 40
    fmu = Instance(fmu_path, speed=10.0).start()
    core = core_stepper(speed_m_s=10.0)
    assert fmu.outputs()[0] == pytest.approx(core.outputs().rim_fz_n, rel=1e-12)
    assert fmu.z0 == pytest.approx(core.loaded_radius_m, rel=1e-12)
    worst, spread = 0.0, []
    for _ in range(steps):
        inputs = _drive(fmu)
        t = fmu.t
        asked = fmu.read(*(f"road_x_{i}" for i in range(1, ROAD_QUERIES + 1)))
        if t > 0:  # where the core would ask after the same steps
            x, vx, _ = core.wheel_centre()
            assert np.allclose(core.road_queries(ROAD_QUERIES, x, vx, h), asked,
                               rtol=0, atol=1e-12)
        got = fmu.step(h, road=bumpy, **inputs)
        positions, heights = fmu.last_road
        o = core.advance_wheel(h, inputs["wheel_x"], inputs["wheel_vx"], inputs["wheel_z"],
                               inputs["wheel_vz"], inputs["wheel_torque"], at_time_s=t,
                               road_positions=positions, road_heights=heights)
        x, vx, z = core.wheel_centre()
        wheel = core.wheel_outputs(x, vx, z)
        want = np.array([o.rim_fz_n, o.rim_fx_n, o.rim_my_n_m, o.contact_fz_n, o.contact_fx_n,
                         o.spin_rad_s, o.sliding_points, *(wheel[n] for n in WHEEL_OUTPUTS)])
        got = np.concatenate([got, fmu.read(*WHEEL_OUTPUTS)])
        worst = max(worst, float(np.max(np.abs(got - want) / np.maximum(np.abs(want), 1.0))))
        spread.append(got[1])
    fmu.close()
    assert worst < 1e-12
    assert np.ptp(spread) > 1e3  # Fx moved: the brake and the bumps were felt
    # both ran the C step: the FMU its own library, the core the package's
    assert core.sim.stepping_with == "compiled"
    assert any("stepping with the compiled in-plane step" in m for _, m in fmu.log)


def test_states_round_trip_and_refused_steps_change_nothing(fmu_path):
    fmu = Instance(fmu_path, speed=10.0).start()
    for _ in range(5):
        fmu.step(1e-3, road=bumpy, **_drive(fmu))
    state = fmu.fmu.getFMUstate()
    serialized = fmu.fmu.serializeFMUstate(state)
    t = fmu.t
    first = fmu.step(1e-3, road=bumpy, **_drive(fmu))
    first_wheel = fmu.read(*WHEEL_OUTPUTS, "road_x_1", ROAD_X[-1])
    # a step shorter than the tire's shortest is refused, naming it
    with pytest.raises(FMICallException):
        fmu.fmu.doStep(fmu.t, 5e-8)
    assert "must be at least 1e-07 s, the in-plane tire's shortest step" in fmu.log[-1][1]
    fmu.step(1.5e-4, road=bumpy, **_drive(fmu))  # off the tire's grid: taken
    fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(serialized))
    fmu.t = t
    assert np.array_equal(fmu.step(1e-3, road=bumpy, **_drive(fmu)), first)
    # the host's road held and where the FMU asks next came back with the state
    assert fmu.read(*WHEEL_OUTPUTS, "road_x_1", ROAD_X[-1]) == first_wheel
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
    for _ in range(7):
        first.step(1e-3, road=bumpy, **_drive(first))
    data = first.fmu.serializeFMUstate(first.fmu.getFMUstate())
    inputs = _drive(first)
    expected = first.step(1e-3, road=bumpy, **inputs)
    second = Instance(fmu_path)  # in initialisation mode, default parameters
    second.fmu.setFMUstate(second.fmu.deSerializeFMUstate(data))
    second.t = first.t - 1e-3
    assert np.array_equal(second.step(1e-3, road=bumpy, **inputs), expected)
    first.close()
    second.close()


def test_a_held_wheel_keeps_its_spin_and_a_finer_tire_step_divides_the_hosts(fmu_path):
    """wheel_free = false holds the spin at speed / R whatever the torque; a tire step that
    divides the host's runs that many steps per communication step, and the forces converge
    as it is refined."""
    radius = TireParameters().R
    held = Instance(fmu_path, speed=10.0, wheel_free=False).start()
    def ramp(x):  # the road rising 2 mm over 0.2 m ahead of the tire
        return 2e-3 * np.clip((np.asarray(x) - 0.15) / 0.2, 0.0, 1.0)

    outputs = [held.step(1e-3, road=ramp, wheel_torque=-5000.0) for k in range(30)]
    held.close()
    assert all(o[5] == pytest.approx(10.0 / radius, rel=1e-12) for o in outputs)
    def rise(x):  # a 4 mm (1 - cos) rise of the road over 0.3 m, met from the start
        u = np.clip((np.asarray(x) - 0.15) / 0.3, 0.0, 1.0)
        return 2e-3 * (1 - np.cos(np.pi * u))

    runs = []
    for step in (2e-4, 1e-4, 5e-5):  # the brake ramped in over 30 ms
        fmu = Instance(fmu_path, speed=10.0, step_size=step).start()
        runs.append(np.array([fmu.step(2e-4, road=rise,
                                       wheel_torque=-3000.0 * min(k * 2e-4 / 0.03, 1.0))
                              for k in range(1, 301)]))
        fmu.close()
    errors = [np.max(np.abs(runs[i][:, :2] - runs[2][:, :2])) for i in (0, 1)]
    assert np.ptp(runs[2][:, 0]) > 2e3 and np.ptp(runs[2][:, 1]) > 1e3
    # the difference falls as the tire's step is refined (not at second order: the step's
    # rebuild when the wheel's spin has drifted, and the road's samples, are per step)
    assert errors[1] < 0.01 * np.ptp(runs[2][:, 0])
    assert errors[1] < 0.75 * errors[0]
