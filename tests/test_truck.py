"""The truck example (vehicle_demo/truck.py): its body equations against an independent
integration, and the whole example through its FMUs in fmpy and libcosim: a level road keeps
it at rest, a road the same under both tracks does not roll it, both hosts give the same
outputs."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tire_fmu.road_files import write_crg
from vehicle_demo.truck import (
    TruckError,
    TruckParameters,
    build_tire_fmu,
    first_order_hold,
    run_truck,
    run_truck_demo,
    truck_matrices,
)

#: The FMU these runs use: the native in-plane tire, the faster of the two on the wheel-centre
#: interface to build and step.
FMU = "TireInPlaneNative"
#: N = 50 points and a coarse zone: the truck's loop and hosts are what is tested here.
TIRE = {"n_elements": 50}
SPEED_M_S = 10.0
SPACING_M = 0.01


def test_the_first_order_hold_is_the_integral_of_the_truck_under_a_ramp_of_forces():
    truck = TruckParameters()
    a, b = truck_matrices(truck)
    h = 2e-3
    phi, gamma0, gamma1 = first_order_hold(a, b, h)
    rng = np.random.default_rng(3)
    s0 = rng.normal(scale=1e-3, size=a.shape[0])
    u0, u1 = rng.normal(scale=1e3, size=4), rng.normal(scale=1e3, size=4)
    reference = solve_ivp(lambda t, s: a @ s + b @ (u0 + (u1 - u0) * t / h), (0.0, h), s0,
                          method="DOP853", rtol=1e-12, atol=1e-15).y[:, -1]
    held = phi @ s0 + gamma0 @ u0 + gamma1 @ ((u1 - u0) / h)
    assert np.abs(held - reference).max() <= 1e-9 * np.abs(reference).max()


def test_the_truck_stands_on_its_springs_and_its_corners_carry_its_weight():
    truck = TruckParameters()
    a, b = truck_matrices(truck)
    # forces beyond the static loads that push every wheel up by the same amount lift the
    # body as one: no pitch, no roll, the springs unchanged (an equal acceleration of all)
    lift = np.array(truck.unsprung_kg) * 1.0
    rates = a @ np.zeros(a.shape[0]) + b @ lift
    assert np.allclose(rates[7 + 3:], 1.0)
    total = sum(truck.tire_loads_n)
    weight = (truck.sprung_mass_kg + sum(truck.unsprung_kg)) * 9.81
    assert total == pytest.approx(weight, rel=1e-12)


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    return build_tire_fmu(FMU, tmp_path_factory.mktemp("truck_fmu"))


def _road(path, left, right, spacing_m=SPACING_M, track_m=2.0):
    return write_crg(path, np.column_stack([right, 0.5 * (left + right), left]), spacing_m,
                     [-0.5 * track_m, 0.0, 0.5 * track_m])


def _bumps(samples: int) -> np.ndarray:
    x = np.arange(samples) * SPACING_M
    # two smooth 15 mm bumps, 0.5 m long, that the front axle (from 5 m) meets 0.15 s and
    # 0.25 s in, the rear (4 m behind it) 0.55 s and 0.65 s in
    centre = np.array([6.5, 7.5])
    return sum(0.015 * np.where(np.abs(x - c) < 0.25,
                                0.5 * (1 + np.cos(2 * np.pi * (x - c) / 0.5)), 0.0)
               for c in centre)


@pytest.mark.fmu
@pytest.mark.parametrize("speed_m_s, rest_share", [(0.0, 1e-9), (SPEED_M_S, 3e-3)])
def test_a_level_road_keeps_the_truck_at_rest(fmu, tmp_path, speed_m_s, rest_share):
    level = np.zeros(4000)
    road = _road(tmp_path / "level.crg", level, level)
    run = run_truck(fmu, road, speed_m_s=speed_m_s, duration_s=0.3, step_s=1e-3,
                    tire_parameters=TIRE)
    # the tires carry the corners' static loads where the truck's wheels put them; rolling,
    # the tire starts from its footprint at the speed, but its tread's own start (sheared
    # from rest) rings for a few tenths of a second (0.13 % of the load at N = 50)
    loads = run.tire_loads_n
    assert np.abs(run.rim_fz_n - loads).max() < rest_share * loads.min()
    assert np.abs(run.body_z_m).max() < 1e-3 * rest_share
    assert np.abs(run.pitch_rad).max() < 1e-3 * rest_share
    assert np.abs(run.roll_rad).max() < 1e-12


@pytest.mark.fmu
def test_the_same_road_under_both_tracks_does_not_roll_the_truck_and_libcosim_agrees(fmu,
                                                                                     tmp_path):
    bumps = _bumps(4000)
    road = _road(tmp_path / "bumps.crg", bumps, bumps)
    runs = [run_truck(fmu, road, speed_m_s=SPEED_M_S, duration_s=0.7, step_s=1e-3,
                      tire_parameters=TIRE, start_x_m=5.0)]
    pytest.importorskip("libcosimpy")
    runs.append(run_truck(fmu, road, speed_m_s=SPEED_M_S, duration_s=0.7, step_s=1e-3,
                          host="libcosim", tire_parameters=TIRE, start_x_m=5.0,
                          loaded_radii_m=runs[0].wheel_z_m[0]))
    fmpy_run, cosim_run = runs
    dynamic = fmpy_run.rim_fz_n - fmpy_run.tire_loads_n
    # the bumps reach both axles and load the tires: the run has something to compare
    assert np.abs(dynamic[:, 0]).max() > 2e3 and np.abs(dynamic[:, 2]).max() > 2e3
    assert np.abs(fmpy_run.pitch_rad).max() > 1e-4
    # left and right wheels see the same road: no roll, the two sides' loads equal
    assert np.abs(fmpy_run.roll_rad).max() < 1e-9
    assert np.abs(dynamic[:, 0] - dynamic[:, 1]).max() < 1e-6 * np.abs(dynamic).max()
    # one loop, two masters: the same FMU gives the same outputs
    assert np.abs(fmpy_run.rim_fz_n - cosim_run.rim_fz_n).max() < 1e-6
    assert np.abs(fmpy_run.pitch_rad - cosim_run.pitch_rad).max() < 1e-12


@pytest.mark.fmu
def test_the_demo_writes_its_figure_and_summary(tmp_path):
    summary = run_truck_demo(tmp_path / "out", tire=FMU, duration_s=0.1, progress=False,
                             log=lambda *_: None)
    written = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert written["runs"][0]["real_time_factor"] == pytest.approx(
        summary["runs"][0]["real_time_factor"])
    assert (tmp_path / "out" / "truck.png").stat().st_size > 10_000
    assert (tmp_path / "out" / "truck_road.crg").is_file()


def test_the_demo_refuses_every_bad_argument_at_once(tmp_path):
    with pytest.raises(TruckError) as caught:
        run_truck_demo(tmp_path / "out", tire="Pacejka", speed_m_s=-1.0, step_s=1.0,
                       progress=False, log=lambda *_: None)
    text = str(caught.value)
    assert "--tire 'Pacejka'" in text and "--speed -1.0" in text and "--step 1.0" in text
    assert not (tmp_path / "out").exists()
