"""vehicle_demo: the quarter car co-simulated with TireModal.fmu through fmpy.

Layers: the quarter car and its references against closed forms; the quarter-car FMU against
its exact solution; the co-simulation against the full-model reference (the acceptance: 1 dB
where coherence > 0.95 and the gain is above 1 % of its peak, up to 300 Hz; body bounce and
wheel hop within 2 % of the analytic values; equilibrium at rest); the road generator against
its target PSD; sweeps on dask against the serial run; the demo and its command line.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from scipy import signal, stats

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from tire_fmu.core import OperatingPoint, TireParameters, build_model  # noqa: E402
from tire_fmu.core.parameters import MAX_ELEMENTS  # noqa: E402
from vehicle_demo.quarter_car import (  # noqa: E402
    QuarterCarError,
    QuarterCarParameters,
    analytic_frequencies,
    full_tire_two_port,
    quarter_car_modes,
    ride_response,
    spring_damper_two_port,
    state_space,
    tire_low_frequency,
)
from vehicle_demo.road import (  # noqa: E402
    ISO_8608_GD_N0_M3,
    RoadError,
    cleat,
    iso8608_road,
)
from vehicle_demo.transfer import (  # noqa: E402
    Multisine,
    agreement,
    estimate_frf,
    identify_body_and_wheel,
    ride_outputs,
)

N_ELEMENTS = 50  # coarse mesh: the acceptance compares co-simulation with the same mesh
CAR = QuarterCarParameters()
EXCITATION = Multisine(period_s=2.0, settle_periods=1, average_periods=2,
                       rms_velocity_m_s=0.005)
STEP_S = 1e-4


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    from vehicle_demo.demo import ensure_fmus

    return ensure_fmus(tmp_path_factory.mktemp("fmus"), log=lambda *_: None)


@pytest.fixture(scope="module")
def model():
    return build_model(TireParameters(), OperatingPoint(n_elements=N_ELEMENTS,
                                                        load_n=CAR.static_tire_load_n))


@pytest.fixture(scope="module")
def transfer_run(fmus, model):
    """One co-simulated multisine at speed 0, its H1 and the full-model reference."""
    from vehicle_demo.cosim import cosimulate

    _, height, velocity = EXCITATION.road(STEP_S)
    result = cosimulate(fmus, height, velocity, CAR, {"n_elements": N_ELEMENTS}, STEP_S)
    estimate = estimate_frf(height, ride_outputs(result), EXCITATION, STEP_S)
    reference = ride_response(CAR, full_tire_two_port(model, estimate.freqs_hz))
    return result, estimate, reference


# -- quarter car and references --------------------------------------------------------------

def test_quarter_car_parameters_list_every_problem_and_carry_a_load():
    with pytest.raises(QuarterCarError) as caught:
        QuarterCarParameters(body_mass_kg=-1.0, suspension_damping_n_s_per_m=math.nan)
    assert len(caught.value.problems) == 2
    assert CAR.static_tire_load_n == pytest.approx(2820 * 9.80665)
    heavier = CAR.with_static_load(35_000.0)
    assert heavier.static_tire_load_n == pytest.approx(35_000.0)
    assert heavier.wheel_mass_kg == CAR.wheel_mass_kg
    with pytest.raises(QuarterCarError):
        CAR.with_static_load(100.0)


def test_analytic_frequencies_are_the_two_mass_eigenvalues():
    k_t = 2.0e6
    found = analytic_frequencies(CAR, k_t, tire_mass_kg=40.0)
    mass = np.diag([CAR.body_mass_kg, CAR.wheel_mass_kg + 40.0])
    k_s = CAR.suspension_stiffness_n_per_m
    stiffness = np.array([[k_s, -k_s], [-k_s, k_s + k_t]])
    expected = np.sort(np.sqrt(np.linalg.eigvals(np.linalg.solve(mass, stiffness)).real))
    assert [found.body_bounce_hz, found.wheel_hop_hz] == pytest.approx(expected / (2 * np.pi),
                                                                        rel=1e-12)
    # the textbook approximations of a soft suspension on a stiff tire
    massless = analytic_frequencies(CAR, k_t)
    assert massless.body_bounce_hz == pytest.approx(
        math.sqrt(k_s * k_t / (k_s + k_t) / CAR.body_mass_kg) / (2 * math.pi), rel=0.01)
    assert massless.wheel_hop_hz == pytest.approx(
        math.sqrt((k_s + k_t) / CAR.wheel_mass_kg) / (2 * math.pi), rel=0.02)


def test_tire_low_frequency_terms_match_the_full_model(model):
    low = tire_low_frequency(model)
    assert low.stiffness_n_per_m == pytest.approx(model.static_vertical_stiffness_n_per_m,
                                                  rel=1e-9)
    f = np.array([0.2, 1.0])
    omega = 2 * np.pi * f
    k_dyn = -full_tire_two_port(model, f).rim[0]
    # K_dyn = k + iωc - ω²m up to O(ω⁴)
    assert (low.stiffness_n_per_m - k_dyn.real) / omega**2 == pytest.approx(
        [low.rim_side_mass_kg] * 2, rel=2e-3)
    assert k_dyn.imag / omega == pytest.approx([low.damping_n_s_per_m] * 2, rel=1e-3)
    # part of the 121 kg tire moves with the rim; a radial-only ring carries at most half
    assert 20.0 < low.rim_side_mass_kg < 61.0


def test_spring_damper_reference_is_the_classic_quarter_car():
    k_t, c_t = 2.0e6, 300.0
    f = np.geomspace(0.5, 300, 50)
    ride = ride_response(CAR, spring_damper_two_port(k_t, c_t, f, CAR.static_tire_load_n))
    # the same car as one state space with the tire spring inside it
    a, b = state_space(CAR)
    a = a.copy()
    a[3, 2] -= k_t / CAR.wheel_mass_kg
    a[3, 3] -= c_t / CAR.wheel_mass_kg
    for i, w in enumerate(2 * np.pi * f):
        x = np.linalg.solve(1j * w * np.eye(4) - a, b * (k_t + 1j * w * c_t))
        assert ride["body_acc"][i] == pytest.approx(-w * w * x[0], rel=1e-9)
        assert ride["wheel_acc"][i] == pytest.approx(-w * w * x[2], rel=1e-9)
        tire_force = (k_t + 1j * w * c_t) * (1 - x[2])
        assert ride["rim_load"][i] == pytest.approx(tire_force, rel=1e-9)
        assert ride["contact_force"][i] == pytest.approx(tire_force, rel=1e-9)


# -- the quarter-car FMU ---------------------------------------------------------------------

@pytest.mark.fmu
def test_quarter_car_fmu_validates_and_steps_exactly(fmus):
    from fmpy.validation import validate_fmu

    from vehicle_demo.cosim import FmuInstance

    assert validate_fmu(str(fmus.quarter_car)) == []
    unit = FmuInstance(fmus.quarter_car, "qc")
    try:
        unit.start(CAR.fmu_values())
        force_step, h = 1000.0, 1e-3
        vrs = [unit.vr("rim_Fz"), unit.vr("rim_Fz_rate")]
        unit.fmu.setReal(vrs, [CAR.static_tire_load_n + force_step, 0.0])
        states = []
        for k in range(200):
            unit.fmu.doStep(k * h, h)
            states.append(unit.get(["body_z", "body_vz", "wheel_z", "wheel_vz"]))
    finally:
        unit.close()
    a, b = state_space(CAR)
    t = h * np.arange(1, 201)
    _, _, expected = signal.lsim((a, b[:, None] * force_step, np.eye(4), np.zeros((4, 1))),
                                 np.ones(t.size + 1), np.r_[0.0, t])
    assert np.allclose(states, expected[1:], rtol=1e-6, atol=1e-12)


# -- the co-simulation: the acceptance -------------------------------------------------------

@pytest.mark.fmu
def test_cosimulated_transfer_functions_agree_with_the_full_model(transfer_run):
    result, estimate, reference = transfer_run
    assert result.contact_lost_fraction == 0.0  # the small-signal excitation keeps contact
    found = agreement(estimate, reference, f_max_hz=300.0)
    lines = estimate.freqs_hz.size
    assert estimate.freqs_hz.max() == pytest.approx(300.0)
    for name, a in found.items():
        assert a.max_deviation_db < 1.0, (name, a)
        # most lines count: the criterion is not met by comparing nothing
        # (the body's response falls below the comparison floor first, a little above 200 Hz)
        assert a.points_compared > (0.6 if name == "body_acc" else 0.7) * lines, (name, a)
        assert a.f_max_compared_hz > 200.0, (name, a)


@pytest.mark.fmu
def test_cosimulated_transfer_functions_agree_at_speed_with_a_finer_step(fmus):
    """At 20 m/s the road crosses the patch with delays; the contact force's road feedthrough
    needs the finer step for 1 dB there (its error is second order in h: about 1.4 dB at
    1e-4 s, 0.3 dB at 5e-5 s), the other responses are far inside already."""
    from vehicle_demo.cosim import cosimulate

    speed, h = 20.0, 5e-5
    model = build_model(TireParameters(), OperatingPoint(
        n_elements=N_ELEMENTS, load_n=CAR.static_tire_load_n, speed_m_s=speed))
    _, height, velocity = EXCITATION.road(h)
    result = cosimulate(fmus, height, velocity, CAR,
                        {"n_elements": N_ELEMENTS, "speed": speed}, h)
    estimate = estimate_frf(height, ride_outputs(result), EXCITATION, h)
    reference = ride_response(CAR, full_tire_two_port(model, estimate.freqs_hz))
    for name, a in agreement(estimate, reference, f_max_hz=300.0).items():
        assert a.max_deviation_db < 1.0, (name, a)
        # the body's response falls below the comparison floor first: at 20 m/s the
        # footprint averages the road over its length
        assert a.f_max_compared_hz > (140.0 if name == "body_acc" else 190.0), (name, a)


@pytest.mark.fmu
def test_body_bounce_and_wheel_hop_match_the_analytic_quarter_car(transfer_run, model):
    _, estimate, reference = transfer_run
    modes = quarter_car_modes(CAR, model)
    analytic = modes.with_tire_mass
    body, wheel = identify_body_and_wheel(estimate.freqs_hz, estimate.h1["body_acc"],
                                          estimate.h1["wheel_acc"],
                                          estimate.coherence["wheel_acc"])
    assert body.frequency_hz == pytest.approx(analytic.body_bounce_hz, rel=0.02)
    assert wheel.frequency_hz == pytest.approx(analytic.wheel_hop_hz, rel=0.02)
    # the reference's own poles agree too, and the fit finds them in the reference response
    assert modes.body_bounce.frequency_hz == pytest.approx(analytic.body_bounce_hz, rel=0.02)
    assert modes.wheel_hop.frequency_hz == pytest.approx(analytic.wheel_hop_hz, rel=0.02)
    ref_body, ref_wheel = identify_body_and_wheel(reference.freqs_hz, reference["body_acc"],
                                                  reference["wheel_acc"])
    assert ref_body.frequency_hz == pytest.approx(modes.body_bounce.frequency_hz, rel=5e-3)
    assert ref_wheel.frequency_hz == pytest.approx(modes.wheel_hop.frequency_hz, rel=5e-3)
    assert wheel.damping_ratio == pytest.approx(modes.wheel_hop.damping_ratio, rel=0.05)
    # a massless tire of the same stiffness puts wheel hop several percent too high
    assert modes.massless.wheel_hop_hz > 1.04 * modes.wheel_hop.frequency_hz


@pytest.mark.fmu
@pytest.mark.parametrize("speed", [0.0, 10.0])
def test_a_road_at_rest_leaves_the_car_in_equilibrium(fmus, speed):
    from vehicle_demo.cosim import cosimulate
    from vehicle_demo.road import road_at_rest

    road = road_at_rest(0.5, STEP_S)
    result = cosimulate(fmus, road.height_m, road.velocity_m_s, CAR,
                        {"n_elements": N_ELEMENTS, "speed": speed}, STEP_S)
    load = CAR.static_tire_load_n
    assert result.static_load_n == pytest.approx(load, rel=1e-15)
    # the tire's static load matches the car's weight to its patch solver's tolerance
    # (~1e-12 relative): forces stay within 1 ppb of it, motions below 0.1 nm
    for states in (result.body_z_m, result.wheel_z_m, result.wheel_vz_m_s):
        assert np.abs(states).max() < 1e-10
    for acc in (result.body_az_m_s2, result.wheel_az_m_s2):
        assert np.abs(acc).max() < 1e-8
    assert np.abs(result.rim_Fz_n - load).max() < 1e-9 * load
    assert np.abs(result.contact_Fz_n - load).max() < 1e-9 * load
    assert result.in_contact.all()


@pytest.mark.fmu
def test_a_native_tire_exported_at_a_typed_load_runs_the_cars_computed_load(fmus, tmp_path,
                                                                           capsys):
    """`tire-fmu export --load 27654.753` and the car's weight (2500 + 320)·9.80665 =
    27654.752999999997 are one load within FIXED_PARAMETER_REL_TOLERANCE: the master sends
    the declared value, the native FMU accepts it, and the car stays in equilibrium."""
    from tire_fmu.cli import main as tire_fmu
    from vehicle_demo.cosim import FmuPaths, QuarterCarCoSimulation
    from vehicle_demo.road import road_at_rest

    native = tmp_path / "native.fmu"
    assert tire_fmu(["export", str(native), "--load", "27654.753", "--elements",
                     str(N_ELEMENTS)]) == 0
    capsys.readouterr()
    assert CAR.static_tire_load_n != 27654.753
    road = road_at_rest(0.2, STEP_S)
    with QuarterCarCoSimulation(FmuPaths(native, fmus.quarter_car), CAR, {}, STEP_S) as sim:
        result = sim.run(road.height_m, road.velocity_m_s)
    assert np.abs(result.rim_Fz_n - 27654.753).max() < 1e-9 * 27654.753
    assert np.abs(result.wheel_z_m).max() < 1e-10 and result.in_contact.all()


def test_coupling_is_stable_far_beyond_the_default_step(model):
    from tire_fmu.core.reduction import reduce
    from vehicle_demo.coupling import spectral_radius

    reduced = reduce(model, report=False)
    body = quarter_car_modes(CAR, model).body_bounce
    decay = body.damping_ratio * 2 * np.pi * body.frequency_hz
    for scheme in ("gauss-seidel", "jacobi"):
        # at 1e-4 s the slowest mode decays per step as the exact solution does
        assert spectral_radius(CAR, reduced, 1e-4, scheme) == pytest.approx(
            math.exp(-decay * 1e-4), abs=1e-7)
        assert spectral_radius(CAR, reduced, 1e-3, scheme) < 1.0
    # Gauss-Seidel with the force interpolated stays stable where Jacobi does not
    assert spectral_radius(CAR, reduced, 5e-3, "gauss-seidel") < 1.0
    assert spectral_radius(CAR, reduced, 5e-3, "jacobi") > 1.0


# -- roads -----------------------------------------------------------------------------------

@pytest.mark.parametrize("road_class", ["A", "C", "E"])
def test_iso8608_road_reproduces_its_psd_within_welchs_band(road_class):
    speed, spacing, segments = 20.0, 0.05, 30
    road, spectrum = iso8608_road(road_class, speed, 3000.0 / speed, spacing / speed, seed=3)
    z = road.height_m[:-1]
    n, psd = signal.welch(z, fs=1 / spacing, window="hann", nperseg=z.size // segments,
                          noverlap=0, detrend=False)
    dn = n[1] - n[0]
    # away from the band edges, where the window's leakage biases the estimate
    inside = (n > spectrum.n_min_cycles_per_m + 3 * dn) & (n < 0.9 * spectrum.n_max_cycles_per_m)
    ratio = psd[inside] / spectrum.psd_m3(n[inside])
    dof = 2 * segments
    for level, allowed in ((0.95, 0.05), (0.99, 0.01)):
        low = dof / stats.chi2.ppf(0.5 + level / 2, dof)
        high = dof / stats.chi2.ppf(0.5 - level / 2, dof)
        outside = np.mean((ratio < low) | (ratio > high))
        assert outside <= allowed, (level, outside)
    assert np.mean(ratio) == pytest.approx(1.0, abs=0.03)
    assert spectrum.gd_n0_m3 == ISO_8608_GD_N0_M3[road_class]
    assert ISO_8608_GD_N0_M3["B"] == pytest.approx(4 * ISO_8608_GD_N0_M3["A"])


def test_road_velocity_is_the_derivative_of_the_height():
    road, _ = iso8608_road("D", 15.0, 2.0, 1e-4, seed=1, fade_in_s=0.5)
    slope = np.gradient(road.height_m, road.time_s)
    assert np.allclose(road.velocity_m_s[1:-1], slope[1:-1],
                       atol=1e-3 * np.abs(road.velocity_m_s).max())
    assert road.height_m[0] == 0.0 and road.velocity_m_s[0] == 0.0  # faded in from rest
    with pytest.raises(RoadError):
        iso8608_road("Z", 15.0, 2.0, 1e-4)
    with pytest.raises(RoadError):
        iso8608_road("C", 0.0, 2.0, 1e-4)


@pytest.mark.parametrize("shape", ["rectangular", "rounded"])
def test_cleat_has_its_height_and_length(shape):
    bump = cleat(0.02, 0.1, 10.0, 0.5, 1e-4, shape, distance_m=1.0)
    on = bump.height_m > 1e-9
    assert bump.height_m.max() == pytest.approx(0.02, rel=1e-6)
    duration_on = on.sum() * 1e-4
    assert duration_on == pytest.approx(0.1 / 10.0, abs=2e-4)
    assert bump.time_s[on][0] == pytest.approx(0.1, abs=2e-4)
    with pytest.raises(RoadError):
        cleat(0.02, 0.1, 10.0, 0.5, 1e-4, "triangular")


# -- sweeps ----------------------------------------------------------------------------------

@pytest.mark.fmu
@pytest.mark.slow
def test_sweep_on_a_cluster_whose_workers_cannot_see_the_fmu_files(fmus, tmp_path):
    import shutil

    from vehicle_demo.cosim import FmuPaths
    from vehicle_demo.sweep import (
        RESULT_COLUMNS,
        FmuBundle,
        SweepSettings,
        local_cluster,
        run_sweep,
    )

    client = tmp_path / "client"
    client.mkdir()
    copies = FmuPaths(*(Path(shutil.copy2(p, client / p.name)) for p in (fmus.tire,
                                                                           fmus.quarter_car)))
    settings = SweepSettings(n_elements=40, reference=False)
    points = [{"load": 22_000.0, "speed": 0.0}, {"load": CAR.static_tire_load_n, "speed": 5.0},
              {"load": CAR.static_tire_load_n, "speed": 500.0}]  # above the critical speed
    serial = run_sweep(points, copies, settings, scheduler="synchronous", progress=False)
    bundle = FmuBundle.from_paths(copies)
    shutil.rmtree(client)  # from here on only the bytes exist
    workers = tmp_path / "workers"
    cluster = local_cluster(n_workers=2, local_directory=workers)
    try:
        parallel = run_sweep(points, bundle, settings, address=cluster.scheduler_address,
                             progress=False)
        # each worker that ran a point wrote the FMUs once, into its own folder (which the
        # worker removes when it closes)
        written = sorted(workers.rglob("tire_fmu_sweep_*/TireModal.fmu"))
        assert 1 <= len(written) <= 2 and all(p.read_bytes() == bundle.tire for p in written)
    finally:
        cluster.close()
    for result in (serial, parallel):
        table = result.table
        assert list(table["status"]) == ["ok", "ok", "failed"], list(table["error"])
        assert "critical" in table["error"][2] and "500" in table["error"][2]
        assert table.loc[:1, "body_bounce_hz"].notna().all()
    numeric = [c for c in RESULT_COLUMNS if c not in ("status", "error", "seconds")]
    a = serial.table[numeric].to_numpy(float)
    b = parallel.table[numeric].to_numpy(float)
    assert np.allclose(a, b, rtol=1e-9, equal_nan=True)
    # a heavier body lowers body bounce
    assert serial.table["body_bounce_hz"][1] < serial.table["body_bounce_hz"][0]


def test_auto_scheduler_runs_in_process_unless_workers_pay_off(monkeypatch):
    from vehicle_demo.sweep import pick_scheduler

    monkeypatch.setattr("os.cpu_count", lambda: 2)
    monkeypatch.setattr("os.getloadavg", lambda: (0.1, 0.1, 0.1))
    assert pick_scheduler(8, 2) == "processes"
    assert pick_scheduler(3, 2) == "synchronous"  # fewer than two points per worker
    monkeypatch.setattr("os.getloadavg", lambda: (1.8, 1.8, 1.8))  # the cores are taken
    assert pick_scheduler(8, 2) == "synchronous"


@pytest.mark.fmu
def test_sweep_rejects_unknown_factors_with_the_known_ones(fmus):
    from vehicle_demo.sweep import SweepError, run_sweep

    with pytest.raises(SweepError, match="inflation_pressure"):
        run_sweep([{"tyre_pressure": 1.0}], fmus, progress=False)


# -- the demo and its command line -----------------------------------------------------------

@pytest.mark.fmu
@pytest.mark.slow
def test_quick_demo_writes_figures_and_tables(tmp_path, fmus, monkeypatch):
    import shutil

    import vehicle_demo.plots as plots
    from vehicle_demo.demo import DemoSettings, format_summary, run_demo

    figures, save = {}, plots._save

    def keep(fig, path):
        figures[path.name] = fig
        return save(fig, path)

    monkeypatch.setattr(plots, "_save", keep)

    out = tmp_path / "demo"
    (out / "fmus").mkdir(parents=True)
    for path in (fmus.tire, fmus.quarter_car):  # reuse the built FMUs (they are up to date)
        shutil.copy2(path, out / "fmus" / path.name)
    (out / "summary.json").write_text("an earlier run's")
    summary = run_demo(DemoSettings.quick(out_dir=out, n_elements=40, road_duration_s=0.5,
                                          progress=False), log=lambda *_: None)
    for name in ("ride_transfer_functions.png", "road_run_iso8608.png", "road_run_cleat.png",
                 "contact_events.png",
                 "road_psd.png", "summary.csv", "resonances.csv", "agreement.csv",
                 "summary.json"):
        assert (out / name).stat().st_size > 0, name
    # published whole: the run's own files where it says, nothing left beside them
    from vehicle_demo.demo import OUTPUTS

    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUTS)
    assert sorted(p.name for p in (out / "fmus").iterdir()) == ["QuarterCar.fmu",
                                                                "TireModal.fmu"]
    assert [p.name for p in tmp_path.iterdir()] == ["demo"]
    assert [*summary.figures, *summary.tables] == [*(out / n for n in (
        "ride_transfer_functions.png", "road_run_iso8608.png", "road_psd.png",
        "road_run_cleat.png", "contact_events.png")), *(out / n for n in (
        "summary.csv", "resonances.csv", "agreement.csv", "summary.json"))]
    assert json.loads((out / "summary.json").read_text())["settings"]["n_elements"] == 40
    assert all(a.max_deviation_db < 1.0 for a in summary.agreements.values())
    # the contact events: the 40 mm cleat throws the tire off the road, the unilateral
    # contact never pulls, the linear one does over the pothole
    values = {quantity: value for quantity, value, _ in summary.rows}
    assert values["cleat 40 x 20 mm, unilateral: airborne"] > 0
    assert values["cleat 40 x 20 mm, unilateral: contact force min"] == 0.0
    assert values["pothole 50 mm deep, 0.3 m, unilateral: contact force min"] >= 0.0
    assert values["pothole 50 mm deep, 0.3 m, linear: contact force min"] < 0.0
    # the ride grid: one legend for all panels, readable, in several columns; a coherence
    # row only when some line is less than fully coherent (the unilateral contact makes the
    # tire slightly nonlinear; a noise-free multisine on a linear tire gives coherence 1)
    ride = figures["ride_transfer_functions.png"]
    (legend,) = ride.legends
    assert legend._ncols >= 4 and min(t.get_fontsize() for t in legend.get_texts()) >= 10
    assert not any(ax.get_legend() for ax in ride.axes)
    from vehicle_demo.plots import COHERENCE_SHOWN_BELOW

    coherence = [ax for ax in ride.axes if "coherence" in ax.get_ylabel()]
    assert len(ride.axes) == 12 + len(coherence) and len(coherence) in (0, 4)
    if coherence:  # drawn because some line is below the threshold
        lowest = min(np.min(line.get_ydata()) for ax in coherence for line in ax.get_lines())
        assert lowest < COHERENCE_SHOWN_BELOW
    text = format_summary(summary)
    assert "wheel hop" in text and "body bounce" in text
    # one number per cell of summary.csv, so a spreadsheet reads it
    import csv

    with open(out / "summary.csv", newline="") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["quantity", "value", "unit"]
    for quantity, value, _ in rows[1:]:
        assert math.isfinite(float(value)), (quantity, value)
    # the resonance table's columns line up, whatever is missing ("-") in a row
    lines = text.split("Resonances")[1].split("\n\n")[0].splitlines()[1:]
    assert len(lines) == 1 + len(summary.resonances)
    assert len({len(line.rstrip().rsplit(" ", 1)[0]) for line in lines}) == 1, lines


@pytest.mark.parametrize("argv, message", [
    (["--road-speed", "1000"], "--road-speed = 1000.0 m/s: must be >= 0 and below the critical "
                               "speed 83.36 m/s of the mesh (N = 100)"),
    (["--n-elements", "3"], f"--n-elements = 3: must be an integer in [8, {MAX_ELEMENTS}]"),
    (["--quick", "--n-elements", "400", "--road-speed", "-1"],
     "--road-speed = -1.0 m/s: must be >= 0 and below the critical speed 80.07"),
])
def test_demo_settings_are_refused_before_anything_is_built(tmp_path, capsys, monkeypatch,
                                                             argv, message):
    import vehicle_demo.demo as demo
    from vehicle_demo.__main__ import main

    monkeypatch.setattr(demo, "ensure_fmus", lambda *_, **__: pytest.fail("built the FMUs"))
    out = tmp_path / "out"
    assert main(["--out", str(out), *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("vehicle_demo: error: ") and message in err and err.count("\n") == 1
    assert not out.exists()


def test_demo_without_its_packages_names_the_extra_and_leaves_no_folder(tmp_path, capsys,
                                                                        monkeypatch):
    import sys

    from vehicle_demo.__main__ import main

    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if it were not installed
    out = tmp_path / "out"
    assert main(["--out", str(out), "--quick"]) == 2
    err = capsys.readouterr().err
    assert "the demo needs matplotlib: pip install 'tire_fmu[demo]'" in err
    assert not out.exists()


def _snapshot(folder: Path) -> dict:
    return {str(p.relative_to(folder)): (p.read_bytes(), p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.fmu
def test_an_interrupted_rerun_leaves_the_previous_run_as_it_was(tmp_path, fmus, monkeypatch):
    # the previous run's outputs and FMUs, the FMUs older than their sources: the rerun
    # rebuilds them, then is interrupted before its first figure
    import shutil

    import tire_fmu.core
    from vehicle_demo.demo import DemoSettings, run_demo

    out = tmp_path / "demo"
    (out / "fmus").mkdir(parents=True)
    for path in (fmus.tire, fmus.quarter_car):
        shutil.copy2(path, out / "fmus" / path.name)
        os.utime(out / "fmus" / path.name, (0, 0))
    for name in ("ride_transfer_functions.png", "summary.csv", "summary.json"):
        (out / name).write_text(f"previous run: {name}")
    before = _snapshot(out)
    built = []

    def interrupted(*_, **__):
        built.extend(p.name for p in tmp_path.rglob("*.fmu"))
        raise KeyboardInterrupt

    monkeypatch.setattr(tire_fmu.core, "build_model", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_demo(DemoSettings.quick(out_dir=out, n_elements=40, progress=False),
                 log=lambda *_: None)
    assert built.count("TireModal.fmu") == 2  # rebuilt (beside the old ones), then stopped
    assert _snapshot(out) == before
    assert [p.name for p in tmp_path.iterdir()] == ["demo"]  # and no partial run beside it


def test_an_output_folder_with_other_files_is_refused_untouched(tmp_path, monkeypatch):
    import vehicle_demo.demo as demo
    from vehicle_demo.__main__ import main

    monkeypatch.setattr(demo, "ensure_fmus", lambda *_, **__: pytest.fail("built the FMUs"))
    (tmp_path / "notes.txt").write_text("mine")
    (tmp_path / "summary.csv").write_text("a run's")
    assert main(["--out", str(tmp_path), "--quick"]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt", "summary.csv"]


@pytest.mark.fmu
def test_the_up_to_date_check_rebuilds_an_fmu_a_killed_build_left(tmp_path, fmus,
                                                                    monkeypatch):
    # pythonfmu's zip without the builder's completion (a build killed before the guard and
    # the model description), and a zip cut short: both newer than every source
    import shutil
    import zipfile

    import tire_fmu.fmu.builder as builder
    import vehicle_demo.quarter_car_fmu as quarter_car_fmu
    from vehicle_demo.demo import ensure_fmus

    built = []

    def build(folder, *_, **__):
        built.append(Path(folder))

    monkeypatch.setattr(builder, "build_fmu", build)
    monkeypatch.setattr(quarter_car_fmu, "build_quarter_car_fmu", build)
    for path in (fmus.tire, fmus.quarter_car):
        shutil.copy2(path, tmp_path / path.name)
    assert ensure_fmus(tmp_path, log=lambda *_: None) and built == []  # whole: reused
    with zipfile.ZipFile(fmus.tire) as source, \
            zipfile.ZipFile(tmp_path / "TireModal.fmu", "w") as target:
        for item in source.infolist():
            if item.filename != builder.BUILD_RECORD:
                target.writestr(item, source.read(item.filename))
    data = fmus.quarter_car.read_bytes()
    (tmp_path / "QuarterCar.fmu").write_bytes(data[: len(data) // 2])
    ensure_fmus(tmp_path, log=lambda *_: None)
    assert built == [tmp_path, tmp_path]  # both rebuilt


def test_the_quarter_car_is_defined_once():
    from dataclasses import fields

    from tire_fmu.core.parameters import DEFAULT_LOAD_N
    from tire_fmu.fmu.interface import same_fixed_value
    from vehicle_demo import quarter_car_fmu

    # the FMU's parameters and the master's names come from QuarterCarParameters' fields
    assert [p[:3] for p in quarter_car_fmu.PARAMETERS] == [
        (f.metadata["fmu_name"], f.default, f.metadata["unit"]) for f in fields(CAR)]
    assert QuarterCarParameters.from_fmu_values(CAR.fmu_values()) == CAR
    assert quarter_car_fmu.INPUTS[0][:2] == ("rim_Fz", CAR.static_tire_load_n)
    # the core's default load is its own number, which the demo car happens to carry
    assert DEFAULT_LOAD_N != CAR.static_tire_load_n
    assert same_fixed_value(CAR.static_tire_load_n, DEFAULT_LOAD_N)


def test_fixed_parameters_match_within_the_stated_tolerance():
    from tire_fmu.fmu.interface import FIXED_PARAMETER_REL_TOLERANCE, same_fixed_value

    load = 27654.753
    assert same_fixed_value(27654.752999999997, load)
    assert same_fixed_value(load * (1 + 0.5 * FIXED_PARAMETER_REL_TOLERANCE), load)
    assert not same_fixed_value(load * (1 + 2 * FIXED_PARAMETER_REL_TOLERANCE), load)
    assert same_fixed_value(0.0, 0.0) and not same_fixed_value(1e-300, 0.0)
    assert not same_fixed_value(math.nan, math.nan)


def test_command_line_reports_user_errors_in_one_line(tmp_path, capsys):
    from vehicle_demo.__main__ import main

    blocker = tmp_path / "a_file"
    blocker.write_text("")
    assert main(["--out", str(blocker / "out"), "--quick"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("vehicle_demo: error:") and "\n" not in err
    assert main(["sweep", "--factor", "load=oops", "--out", str(tmp_path)]) == 2
    assert "levels must be numbers" in capsys.readouterr().err


@pytest.mark.fmu
@pytest.mark.parametrize("height_m", [0.02, 0.04])
def test_cleats_at_10_m_s_the_python_and_native_tires_agree(fmus, native_fmu_path, height_m):
    """Issue 10's cleat runs: the quarter car at 10 m/s over a 20 mm and a 40 mm high, 20 mm
    long cleat, on the Python tire and on the native one; the 40 mm cleat throws the tire off
    the road, the 20 mm one does not, and the two tires agree to 1e-9 over the whole run."""
    from vehicle_demo.cosim import FmuPaths, cosimulate
    from vehicle_demo.road import cleat

    profile = cleat(height_m, 0.02, 10.0, 0.25, STEP_S, "rectangular", distance_m=0.5)
    runs = []
    for tire in (fmus.tire, native_fmu_path):
        runs.append(cosimulate(FmuPaths(tire, fmus.quarter_car), profile.height_m,
                               profile.velocity_m_s, CAR, {"speed": 10.0}, STEP_S))
    python_run, native_run = runs
    lifted = ~python_run.in_contact
    assert lifted.any() == (height_m > 0.03)
    assert np.array_equal(lifted, ~native_run.in_contact)
    assert python_run.contact_Fz_n.min() == 0.0 if lifted.any() else True
    scale = np.abs(python_run.rim_Fz_n).max()
    for name in ("rim_Fz_n", "contact_Fz_n", "wheel_z_m", "body_az_m_s2"):
        a, b = getattr(python_run, name), getattr(native_run, name)
        assert np.abs(a - b).max() <= 1e-9 * (scale if name.endswith("_n")
                                              else np.abs(a).max()), name
    np.testing.assert_allclose(native_run.contact_length_m, python_run.contact_length_m,
                               rtol=0, atol=1e-9 * python_run.contact_length_m.max())
