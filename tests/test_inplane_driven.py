"""A driven wheel (``wheel="driven"``): the host gives the wheel's spin, as a host that models
the wheel's body itself does, and reads the tire's moment on the rim.

Held to the two wheels the tire already has, each stepped apart: driven at the nominal spin it
is the held wheel; driven at the spin a free wheel takes under a brake torque, it gives that
free wheel's forces and moment (the free wheel's step solves its turn's equation jointly with
the ring's, the driven one takes the turn and solves the ring's alone)."""

import numpy as np
import pytest

from tire_fmu.core.inplane import InPlaneTire
from tire_fmu.core.inplane_contact import (
    InPlaneSimulator,
    InPlaneStepper,
    deflection_for_load,
    steady_rolling,
)

MODEL = InPlaneTire()
N, SPEED, H, LOAD = 50, 10.0, 1e-4, 27000.0


@pytest.fixture(scope="module")
def deflection():
    return deflection_for_load(MODEL, LOAD, N, f_max_hz=300.0)


def stepper(deflection, wheel, backend):
    return InPlaneStepper(InPlaneSimulator(MODEL, N, SPEED, deflection, wheel=wheel,
                                           f_max_hz=300.0, backend=backend), host_road=True)


def forces(out):
    return np.array([out.rim_fx_n, out.rim_fz_n, out.rim_my_n_m])


@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_driven_at_the_nominal_spin_is_the_held_wheel(deflection, backend):
    held, driven = stepper(deflection, "held", backend), stepper(deflection, "driven", backend)
    worst = 0.0
    for k in range(1, 801):
        t = k * H
        road = dict(road_z_m=0.01 * np.sin(40 * t) ** 2, road_vz_m_s=0.4 * np.sin(80 * t))
        a, b = held.advance(H, **road), driven.advance(H, wheel_rate_rad_s=0.0, **road)
        worst = max(worst, float(np.abs(forces(a) - forces(b)).max()))
        assert b.spin_rad_s == a.spin_rad_s
    assert worst < 1e-9 * LOAD


@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_driven_at_a_braked_free_wheels_spin_gives_its_forces(deflection, backend):
    """Driven at the spin a braked free wheel takes, given at each step's start as a host
    reads it (the free wheel's spin at the end of its last step), the tire gives the free
    wheel's forces and moment to the extension's error (the spin's last change carried over
    the step): once the brake's step has passed, within 1 % of the load and 5 % of the
    brake's torque (the slip builds a step late); the spin within what it changes in a
    step."""
    free, driven = stepper(deflection, "free", backend), stepper(deflection, "driven", backend)
    differences, fx, spin = [], [], SPEED / MODEL.tire.R
    for k in range(1, 2001):
        f = free.advance(H, torque_n_m=-3000.0 if k > 100 else 0.0)
        d = driven.advance(H, wheel_rate_rad_s=spin - SPEED / MODEL.tire.R,
                           torque_n_m=1e6)  # a driven wheel's torque is the host's: unread
        differences.append([*(forces(f) - forces(d)), f.spin_rad_s - d.spin_rad_s])
        fx.append(f.rim_fx_n)
        spin = f.spin_rad_s
    assert min(fx) < -5e3  # the brake was felt
    after = np.abs(np.array(differences)[150:]).max(axis=0)
    assert after[:2].max() < 1e-2 * LOAD, after
    assert after[2] < 0.05 * 3000.0, after
    assert after[3] < 0.02, after


def test_a_driven_wheel_spun_up_drives_the_tire_forward(deflection):
    """Spun 2 % above free rolling, the wheel pushes the road back: Fx forward, the moment on
    the rim against the spin, and both settle where the steady solve of the free wheel under
    the torque that spins it so puts them (the same slip, the same drive)."""
    driven = stepper(deflection, "driven", "compiled")
    rate = 0.02 * SPEED / MODEL.tire.R
    for k in range(1, 3001):
        out = driven.advance(H, wheel_rate_rad_s=rate * min(k / 500, 1.0))
    steady = steady_rolling(InPlaneSimulator(MODEL, N, SPEED, deflection, wheel="free",
                                             f_max_hz=300.0), -out.rim_my_n_m)
    assert out.rim_fx_n > 1e3 and out.rim_my_n_m < 0
    assert steady.spin_rad_s == pytest.approx(out.spin_rad_s, rel=1e-3)
    assert steady.rim_fx_n == pytest.approx(out.rim_fx_n, rel=0.02)


def test_a_driven_wheel_is_not_the_tires_to_run_or_linearise(deflection):
    sim = InPlaneSimulator(MODEL, N, SPEED, deflection, wheel="driven", f_max_hz=300.0)
    with pytest.raises(ValueError, match="InPlaneStepper"):
        sim.run(0.01)
    with pytest.raises(ValueError, match="wheel = 'free'"):
        steady_rolling(sim)
