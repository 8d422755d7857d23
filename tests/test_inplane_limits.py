"""Never OK with nonsense: the in-plane tire's limits enforced while it runs, the work of every
call bounded, states checked for what they mean, the hysteretic loss stable where it is taken.

Both runtimes (TireInPlane and TireInPlaneNative) are driven alike and must refuse alike, in
the same words; the core's stepper shows the physics (the loss's stability)."""

import struct

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from inplane_support import Instance

from tire_fmu.core.inplane_contact import (
    MAX_FORCE_LOADS,
    STEPPER_SCALARS,
    STEPPER_STATE_HEAD,
)
from tire_fmu.core.inplane_host import HostSettings, build_host_stepper
from tire_fmu.core.parameters import DEFAULT_LOAD_N
from tire_fmu.core.step_limits import MAX_STEP_WORK
from tire_fmu.fmu.slave import state_strings
from tire_fmu.fmu.spec import STATE_MODEL_FLAGS, state_pack, state_unpack

# -- the hysteretic loss (core) ------------------------------------------------------------------

@pytest.mark.parametrize("speed", [2.0, 30.0])
def test_the_largest_loss_taken_settles_rolling(speed):
    """At the largest loss factor the tire takes (0.1) free rolling settles: the rim's load
    rings down from the static start instead of growing (0.2 grew to 1e6 N and more)."""
    stepper = build_host_stepper(HostSettings(speed_m_s=speed,
                                              tangential={"loss_factor": 0.1})).stepper
    fz = np.array([stepper.advance(1e-3).rim_fz_n for _ in range(400)])
    early, late = np.ptp(fz[100:200]), np.ptp(fz[300:])
    assert late < 0.7 * early and np.abs(fz - DEFAULT_LOAD_N).max() < 0.1 * DEFAULT_LOAD_N


def test_a_loss_beyond_the_stable_range_is_refused():
    from tire_fmu.core.parameters import ParameterError

    with pytest.raises(ParameterError, match=r"loss_factor = 0.2.*\[0, 0.1\]"):
        build_host_stepper(HostSettings(tangential={"loss_factor": 0.2}))


def test_the_hysteretic_tire_holds_a_braked_wheel_at_rest():
    """GL073A_inplane_hysteretic's loss (0.05) and a brake at rest: the wheel's twist rings down
    and the tread holds the brake as the loss-free tire does (the loss's share follows the
    road's speed, zero here; one that followed the spin made a limit cycle of +-20 kN whose
    spin grew over 10 s)."""
    def braked(loss):
        stepper = build_host_stepper(HostSettings(speed_m_s=0.0,
                                                  tangential={"loss_factor": loss})).stepper
        return np.array([(o.rim_fx_n, o.spin_rad_s) for o in
                         (stepper.advance(1e-3, torque_n_m=-3000.0) for _ in range(2000))])

    lossy, plain = braked(0.05), braked(0.0)
    fx, spin = lossy[:, 0], lossy[:, 1]
    assert np.ptp(spin[-400:]) < 0.3 * np.ptp(spin[:400])
    assert np.ptp(fx[-400:]) < 0.3 * np.ptp(fx[:400])
    assert fx[-400:].mean() == pytest.approx(plain[-400:, 0].mean(), rel=0.05)


# -- both FMUs: the running limits, the work bound, the states ------------------------------------

class _Built(dict):
    """The two FMUs, each built when first asked for (a test of one runtime does not wait for,
    or fail with, the other's build)."""

    RUNTIMES = ("python", "native")

    def __init__(self, folder):
        super().__init__()
        self.folder = folder

    def __missing__(self, runtime):
        from tire_fmu.fmu.builder import build_inplane_fmu
        from tire_fmu.native.builder import build_native_inplane_fmu

        build = {"python": build_inplane_fmu, "native": build_native_inplane_fmu}[runtime]
        self[runtime] = path = build(self.folder / runtime)
        return path

    def __iter__(self):
        return iter(self.RUNTIMES)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    return _Built(tmp_path_factory.mktemp("inplane_limits"))


def instance(fmus, runtime, **parameters) -> Instance:
    return Instance(str(fmus[runtime]), format_log=runtime == "native", **parameters)


def refused(fmu, h, **inputs) -> str:
    """A step refused with fmi2Error, changing nothing: the FMU's message."""
    before = fmu.outputs()
    with pytest.raises(FMICallException) as error:
        fmu.step(h, **inputs)
    assert error.value.status == 3
    assert np.array_equal(fmu.outputs(), before)
    return fmu.log[-1][1]


def run_until_refused(fmu, h, steps, **inputs) -> tuple[str, np.ndarray]:
    last = fmu.outputs()
    for _ in range(steps):
        try:
            last = fmu.step(h, **inputs)
        except FMICallException:
            return fmu.log[-1][1], last
    raise AssertionError("never refused")


@pytest.mark.fmu
def test_a_spin_past_the_critical_speed_is_refused_alike(fmus):
    """A free wheel at rest under 3e5 N m reached 639 rad/s and returned 1e6-1e20 N with OK:
    now the step that would take it past 0.95 of the critical speed is refused, naming it,
    with every force returned before within the running limit, in both runtimes alike."""
    said = {}
    for runtime in fmus:
        fmu = instance(fmus, runtime)
        fmu.start()
        message, last = run_until_refused(fmu, 1e-3, 2000, wheel_torque=3e5)
        assert "the wheel's spin reached" in message and "critical speed" in message
        assert np.abs(last[:2]).max() <= MAX_FORCE_LOADS * DEFAULT_LOAD_N
        said[runtime] = message
        # it stays refused, and a smaller torque then steps on
        assert "spin reached" in refused(fmu, 1e-3, wheel_torque=3e5)
        fmu.step(1e-3, wheel_torque=-3e5)
        fmu.close()
    assert said["python"] == said["native"]


@pytest.mark.fmu
@pytest.mark.parametrize("runtime", ["python", "native"])
def test_a_road_speed_past_the_critical_speed_is_refused(fmus, runtime):
    """The wheel centre at 910 m/s over the road (the tire built at 10 m/s): refused."""
    fmu = instance(fmus, runtime, speed=10.0)
    fmu.start()
    fmu.step(1e-3)
    message = refused(fmu, 1e-3, wheel_vx=910.0)
    assert "the road's speed under the axle reached" in message
    fmu.close()


@pytest.mark.fmu
@pytest.mark.parametrize("runtime", ["python", "native"])
def test_a_rim_jump_the_tire_cannot_carry_is_refused(fmus, runtime):
    """The wheel centre jumping 10 m down in one step (within the input's limit): the force it
    would give is beyond MAX_FORCE_LOADS loads: refused, nothing changed."""
    fmu = instance(fmus, runtime)
    fmu.start()
    fmu.step(1e-3)
    message = refused(fmu, 1e-3, wheel_z=fmu.z0 - 10.0)
    assert f"beyond {MAX_FORCE_LOADS:g} times the load" in message
    fmu.step(1e-3)
    fmu.close()


@pytest.mark.fmu
def test_a_step_of_more_work_than_a_step_may_take_is_refused_alike(fmus):
    """step_size = 1e-6 s at N = 100 and a 0.1 s step: 1e5 of the tire's steps, 9.4 s of CPU
    natively before; refused before any work, naming the longest step that fits."""
    said = {}
    for runtime in fmus:
        fmu = instance(fmus, runtime, step_size=1e-6)
        fmu.start()
        message = refused(fmu, 0.1)
        assert f"more than the {MAX_STEP_WORK}" in message and "take steps of at most" in message
        said[runtime] = message
        fmu.step(1e-4)  # a step that fits is taken
        fmu.close()
    assert said["python"] == said["native"]


@pytest.mark.fmu
@pytest.mark.parametrize("runtime", ["python", "native"])
def test_a_mesh_too_costly_to_build_is_refused(fmus, runtime):
    fmu = instance(fmus, runtime, n_elements=1000)
    with pytest.raises(FMICallException):
        fmu.start()
    assert any("n_elements = 1000" in m and "[8, 800]" in m for _, m in fmu.log)
    fmu.fmu.freeInstance()


def _forged(data: bytes, n_values: int, scale_coordinates=1.0, samples=None) -> bytes:
    """The state with its coordinates scaled (its DOFs with them: it is its own basis) or its
    road history's count changed, resealed (a valid checksum)."""
    f = state_unpack(data, n_values)
    model = bytearray(f["model"])
    at = 4 * STATE_MODEL_FLAGS
    _, ny, p, count, _, n_dof, _ = struct.unpack_from(STEPPER_STATE_HEAD, model, at)
    doubles = at + struct.calcsize(STEPPER_STATE_HEAD)
    if scale_coordinates != 1.0:
        for start, size in ((STEPPER_SCALARS, 3 * ny),
                            (STEPPER_SCALARS + 3 * ny + 2 * p + 3 * count, 3 * n_dof)):
            values = np.frombuffer(model, "<f8", size, doubles + 8 * start) * scale_coordinates
            model[doubles + 8 * start:doubles + 8 * (start + size)] = values.tobytes()
    if samples is not None:
        struct.pack_into("<I", model, at + 16, samples)
    strings = state_strings(f["strings"])  # road_file's value, kept
    return state_pack(f["phase"], f["guid"], f["time"], f["start_time"], bool(f["stale"]),
                      f["values"], bytes(model), f["reason"].decode(), strings)


@pytest.mark.fmu
def test_a_forged_state_is_refused_at_its_set_saying_why_alike(fmus):
    """Coordinates of 1000 times a run's (its checksum valid) gave 5e16 N with OK: refused when
    set, for what they mean (the tire's deformation, its forces); a road history of two
    million samples likewise; the instance runs on as it was."""
    said = {}
    for runtime in fmus:
        fmu = instance(fmus, runtime, speed=10.0)
        fmu.start()
        for _ in range(20):
            fmu.step(1e-3, wheel_torque=-2000.0, wheel_z=fmu.z0 + 1e-3)
        data = fmu.fmu.serializeFMUstate(fmu.fmu.getFMUstate())
        n_values = len(read_model_description(str(fmus[runtime])).modelVariables)
        before = fmu.outputs()
        messages = []
        for forged in (_forged(data, n_values, scale_coordinates=1e3),
                       _forged(data, n_values, scale_coordinates=30.0),
                       _forged(data, n_values, samples=2_000_000)):
            with pytest.raises(FMICallException):
                fmu.fmu.setFMUstate(fmu.fmu.deSerializeFMUstate(forged))
            messages.append(fmu.log[-1][1])
        assert "its tire deforms by" in messages[0]
        assert "its forces reach" in messages[1] or "its tire deforms by" in messages[1]
        assert "its road history holds" in messages[2] or "wrong size" in messages[2]
        assert np.array_equal(fmu.outputs(), before)
        fmu.step(1e-3)
        said[runtime] = messages[:2]
        fmu.close()
    assert said["python"] == said["native"]
