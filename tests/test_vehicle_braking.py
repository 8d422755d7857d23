"""vehicle_demo braking: the quarter car hosting the in-plane tire step by step, and the
sampled road profile it runs on.

The run is checked against the laws it is built from, written here apart from the code: the
vehicle's momentum (m ΔV = ∫ Fx dt) and the wheel's angular momentum (I_w dω/dt = T + My,
the tire's moment on the rim); the road profile's window means against quadrature.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.integrate import quad

from tire_fmu.core.inplane import InPlaneTire
from tire_fmu.core.obstacles import SampledRoad
from tire_fmu.core.parameters import ParameterError
from vehicle_demo.__main__ import main
from vehicle_demo.braking import BrakingError, BrakingSettings, run_braking


def test_sampled_road_window_means_are_the_integral_of_its_profile():
    rng = np.random.default_rng(3)
    road = SampledRoad(0.01, 0.01 * rng.standard_normal(201))
    grid = np.arange(201) * 0.01

    def reference(lo, hi):
        if hi == lo:
            return float(road.profile(lo)[0])
        inside = grid[(grid > lo) & (grid < hi)]
        value = quad(lambda s: float(road.profile(s)[0]), lo, hi, points=inside, limit=400)[0]
        return value / (hi - lo)

    # windows inside, across both ends and off the profile, and a point
    for lo, hi in [(0.0131, 0.4467), (-0.3, 0.052), (1.95, 2.4), (2.1, 2.3), (0.777, 0.777)]:
        assert road.mean_height(lo, hi) == pytest.approx(reference(lo, hi), abs=1e-14)
    # a level stretch between samples has the samples' value
    assert road.profile(0.005)[0] == pytest.approx(0.5 * (road.heights_m[0]
                                                          + road.heights_m[1]))


def test_sampled_road_names_every_bad_argument_at_once():
    with pytest.raises(ParameterError) as caught:
        SampledRoad(0.0, [0.0, np.nan, 0.5])
    text = str(caught.value)
    assert "spacing_m = 0 m" in text and "heights_m = nan" in text


@pytest.fixture(scope="module")
def braking(tmp_path_factory):
    out = tmp_path_factory.mktemp("braking")
    # a coarse tire: the laws checked hold on any mesh
    settings = BrakingSettings.quick(out_dir=out, duration_s=0.35, brake_at_s=0.05,
                                     cleat_at_s=0.25, n_elements=48, step_s=2e-4,
                                     point_spacing_m=0.02, f_max_hz=200.0, progress=False)
    return settings, run_braking(settings, log=lambda text: None)


def test_the_vehicle_and_the_wheel_obey_their_momentum_laws(braking):
    settings, summary = braking
    radius = InPlaneTire().tire.R
    inertia = InPlaneTire().tangential.wheel_inertia_kg_m2
    for run in summary.runs:
        t = run.time_s
        # m dV/dt = Fx: the speed lost is the impulse of the force at the axle
        impulse = np.sum(0.5 * (run.fx_n[1:] + run.fx_n[:-1]) * np.diff(t))
        lost = settings.mass_kg * (run.vehicle_speed_m_s[-1] - run.vehicle_speed_m_s[0])
        assert lost == pytest.approx(impulse, rel=5e-3), run.name
        assert run.vehicle_speed_m_s[-1] < settings.speed_m_s - 0.1
        # the wheel: I_w dω/dt = T + My, once the brake is in (central differences)
        spin = run.wheel_speed_m_s / radius
        rate = (spin[2:] - spin[:-2]) / (t[2:] - t[:-2])
        drive = run.torque_n_m[1:-1] + run.my_n_m[1:-1]
        on = t[1:-1] > settings.brake_at_s + settings.brake_ramp_s + 0.02
        assert np.sqrt(np.mean((inertia * rate[on] - drive[on]) ** 2)) < 0.02 * abs(
            settings.brake_torque_n_m), run.name


def test_braking_on_a_level_road_slips_where_the_steady_solve_says(braking):
    settings, summary = braking
    level = summary.runs[0].summary(summary.settled_after_s)
    # the steady solve rolls at a constant speed; decelerating, the turning tread and wheel
    # take a share of the torque and the rim's Fx leaves out the force that slows the tire's
    # own mass, so the run's drag and slip are a few % to about 10 % smaller
    assert level["mean_slip_ratio"] < 0 and summary.steady_slip_ratio < 0
    assert level["mean_slip_ratio"] == pytest.approx(summary.steady_slip_ratio, rel=0.2)
    assert abs(level["mean_fx_n"]) < abs(summary.steady_fx_n)
    assert level["mean_fx_n"] == pytest.approx(summary.steady_fx_n, rel=0.12)
    # the cleat shakes Fz far beyond the level road's, the rough road in between
    spans = [s["fz_max_n"] - s["fz_min_n"] for s in
             (run.summary(summary.settled_after_s) for run in summary.runs)]
    assert spans[0] < 0.01 * spans[2] and spans[0] < spans[1]


def test_braking_demo_writes_its_figures_and_summary(braking):
    settings, summary = braking
    out = settings.out_dir
    for name in ("braking.png", "cleat_test.png"):
        assert (out / name).stat().st_size > 10_000
    data = json.loads((out / "summary.json").read_text())
    assert [r["name"] for r in data["runs"]] == [r.name for r in summary.runs]
    assert data["settings"]["brake_torque_n_m"] == settings.brake_torque_n_m
    test = data["cleat_test"]
    assert test["fz_max_n"] > settings.load_n and test["fx_max_n"] > 0 > test["fx_min_n"]


def test_braking_settings_are_all_reported_at_once(tmp_path, capsys):
    with pytest.raises(BrakingError) as caught:
        run_braking(BrakingSettings(out_dir=tmp_path, speed_m_s=-1.0, n_elements=3,
                                    road_class="Z"))
    text = str(caught.value)
    assert "speed_m_s = -1.0 m/s" in text and "n_elements = 3" in text
    assert "road_class = 'Z'" in text
    assert main(["braking", "--out", str(tmp_path), "--speed", "-1", "--n-elements", "3"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--speed = -1.0" in err and "--n-elements = 3" in err


@pytest.mark.fmu
def test_the_braking_car_runs_the_in_plane_fmu_through_fmpy_as_it_runs_the_core(braking,
                                                                                  tmp_path):
    """--fmu: the same quarter car stepping TireInPlane.fmu through fmpy. On the level road
    it is the core's tire (its C step against the core's numpy one: 1e-8 of the load); over
    the rough road and the cleat the FMU reads the road a host gives it, heights at the
    positions it asks for (the contact points' spacing apart), where the core reads window
    means of the exact profile, so the forces follow the core's closely, not exactly."""
    from dataclasses import replace

    settings, core = braking
    fmu = run_braking(replace(settings, out_dir=tmp_path, fmu=True), log=lambda text: None)
    assert (tmp_path / "fmus" / "TireInPlane.fmu").is_file()
    load = settings.load_n
    level_core, level_fmu = core.runs[0], fmu.runs[0]
    assert level_fmu.time_s.size == level_core.time_s.size
    for a, b in [(level_core.fx_n, level_fmu.fx_n), (level_core.fz_n, level_fmu.fz_n),
                 (level_core.my_n_m, level_fmu.my_n_m)]:
        assert np.max(np.abs(a - b)) < 1e-8 * load
    assert np.max(np.abs(level_core.wheel_speed_m_s - level_fmu.wheel_speed_m_s)) < 1e-9
    def rms(x):
        return float(np.sqrt(np.mean(x**2)))

    rough_core, rough_fmu = core.runs[1], fmu.runs[1]
    assert rms(rough_core.fz_n - rough_fmu.fz_n) < 0.01 * rms(rough_core.fz_n - load)
    # the 20 mm cleat given as heights 20 mm apart (this coarse tire's point spacing): the
    # lines between them round its edges
    cleat_core, cleat_fmu = core.runs[2], fmu.runs[2]
    assert cleat_fmu.fz_n.max() == pytest.approx(cleat_core.fz_n.max(), rel=0.1)
    assert cleat_fmu.fz_n.max() - load > 0.5 * (cleat_core.fz_n.max() - load)
    # the cleat test steps the FMU at the tire's own step: the road sampled finely
    for key in ("fz_max_n", "fx_max_n", "fx_min_n"):
        assert fmu.cleat_test[key] == pytest.approx(core.cleat_test[key], rel=0.03)
    assert fmu.cleat_test["fx_dominant_hz"] == pytest.approx(core.cleat_test["fx_dominant_hz"],
                                                             rel=0.02)
