"""The end-to-end job behind ``python -m vehicle_demo``.

1. build ``TireModal.fmu`` and ``QuarterCar.fmu`` into ``OUT/fmus`` (again only when a source
   is newer than the FMU);
2. co-simulate the quarter car on a broadband multisine road (speed 0: a shaker plate) and
   estimate the four ride transfer functions (H1, coherence);
3. compare them with the car on the full ring model and on a spring-damper tire, and
   identify body bounce, wheel hop and the tire modes;
4. run an ISO 8608 road at speed and a cleat, and plot rim load and contact force;
5. write the figures and ``summary.csv``, ``resonances.csv``, ``agreement.csv`` and
   ``summary.json``, and print the summary.

Everything is written into a private folder beside OUT, which replaces OUT once the run is
complete: OUT holds one run's outputs, never a mix of two (see :func:`run_demo`).
"""

from __future__ import annotations

import csv
import json
import math
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from .cosim import FmuPaths, QuarterCarCoSimulation
from .outputs import check_output_folder, run_folder
from .progress import step_bar
from .quarter_car import QuarterCarParameters
from .road import cleat, iso8608_road, pothole
from .transfer import Multisine


class DemoError(RuntimeError):
    """Something the user can fix (a missing package, an unwritable folder, a bad setting)."""


#: What the demo imports beyond numpy and scipy, and the extra of tire_fmu that brings it.
DEMO_PACKAGES = ("pythonfmu", "fmpy", "matplotlib", "tqdm")
DEMO_EXTRA = "demo"


@dataclass(frozen=True)
class DemoSettings:
    out_dir: Path = Path("demo_output")
    n_elements: int = 100
    step_s: float = 1e-4
    excitation: Multisine = field(default_factory=lambda: Multisine(
        period_s=4.0, settle_periods=1, average_periods=3, rms_velocity_m_s=0.005))
    tf_speed_m_s: float = 0.0
    road_class: str = "C"
    road_speed_m_s: float = 20.0
    road_duration_s: float = 4.0
    road_fade_in_s: float = 0.5  # the ISO road starts level: no step at t = 0
    cleat_height_m: float = 0.03
    cleat_length_m: float = 0.10
    cleat_shape: str = "rounded"
    cleat_speed_m_s: float = 10.0
    #: the contact events (two cleats and a pothole), unilateral against linear contact
    events_speed_m_s: float = 10.0
    events_duration_s: float = 0.35
    car: QuarterCarParameters = field(default_factory=QuarterCarParameters)
    rebuild: bool = False
    progress: bool = True

    @classmethod
    def quick(cls, **overrides) -> DemoSettings:
        """A shorter run for a first look and the benchmark: coarser mesh, 0.5 Hz lines."""
        values = dict(n_elements=60, road_duration_s=2.0, excitation=Multisine(
            period_s=2.0, settle_periods=1, average_periods=2, rms_velocity_m_s=0.005))
        values.update(overrides)
        return cls(**values)

    def problems(self, names: dict[str, str] | None = None) -> list[str]:
        """Every setting the demo cannot run with, found before anything is built: a mesh
        outside the core's range and speeds at or above the mesh's critical speed (the tire
        FMU would refuse them only after the runs before them). ``names`` renames settings in
        the messages (the command line's options)."""
        from tire_fmu.core import TireParameters, critical_speed
        from tire_fmu.core.parameters import MAX_ELEMENTS, MIN_ELEMENTS

        names = names or {}
        found = []
        n = self.n_elements
        if not (isinstance(n, int) and MIN_ELEMENTS <= n <= MAX_ELEMENTS):
            found.append(f"{names.get('n_elements', 'n_elements')} = {n!r}: must be an "
                         f"integer in [{MIN_ELEMENTS}, {MAX_ELEMENTS}]")
            critical = math.inf  # the speeds are checked against a valid mesh only
        else:
            critical = critical_speed(TireParameters(), n).speed_m_s
        for name in ("tf_speed_m_s", "road_speed_m_s", "cleat_speed_m_s", "events_speed_m_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value < critical):
                limit = (f"below the critical speed {critical:.4g} m/s of the mesh "
                         f"(N = {n})" if math.isfinite(critical) else "finite")
                found.append(f"{names.get(name, name)} = {value!r} m/s: must be >= 0 and "
                             f"{limit}")
        if not (math.isfinite(self.step_s) and self.step_s > 0):
            found.append(f"{names.get('step_s', 'step_s')} = {self.step_s!r} s: must be > 0")
        return found


def check_settings(settings: DemoSettings, names: dict[str, str] | None = None) -> None:
    """Raise DemoError naming every bad setting and every missing package, before any
    folder is made or FMU built."""
    import importlib.util

    found = settings.problems(names)
    missing = [name for name in DEMO_PACKAGES if _missing(name, importlib.util)]
    if missing:
        found.append(f"the demo needs {', '.join(missing)}: pip install "
                     f"'tire_fmu[{DEMO_EXTRA}]' (or '.[{DEMO_EXTRA}]' in a clone)")
    if found:
        raise DemoError("; ".join(found))


def _missing(name: str, util) -> bool:
    try:
        return util.find_spec(name) is None
    except (ImportError, ValueError):  # a module set to None in sys.modules, a broken one
        return True


def _sources() -> list[Path]:
    import tire_fmu

    package = Path(tire_fmu.__file__).parent
    here = Path(__file__).parent
    return [*package.glob("core/*.py"), *package.glob("fmu/*.py"), package / "__init__.py",
            here / "quarter_car_fmu.py", here / "vehicle_demo_quarter_car_dynamics.py"]


def ensure_fmus(folder: Path, rebuild: bool = False, log=print) -> FmuPaths:
    """The two FMUs in ``folder``, built when missing, older than their sources, not a whole
    FMU that the builder finished (no build record: cut short, or pythonfmu's output alone,
    as a build killed before its guard and model description leaves it), or asked."""
    try:
        from tire_fmu.fmu.builder import build_fmu, build_record

        from .quarter_car_fmu import build_quarter_car_fmu
    except ImportError as error:
        raise DemoError(f"building the FMUs needs pythonfmu and fmpy ({error}): "
                        f"pip install 'tire_fmu[{DEMO_EXTRA}]'") from error
    folder = Path(folder)
    paths = FmuPaths(folder / "TireModal.fmu", folder / "QuarterCar.fmu")
    newest = max(p.stat().st_mtime for p in _sources() if p.exists())
    for path, build in ((paths.tire, build_fmu), (paths.quarter_car, build_quarter_car_fmu)):
        if (rebuild or not path.exists() or path.stat().st_mtime < newest
                or build_record(path) is None):
            started = time.perf_counter()
            build(folder)
            log(f"built {path} ({time.perf_counter() - started:.1f} s)")
    return paths


@dataclass(frozen=True)
class DemoSummary:
    """What the demo measured (also written as CSV)."""

    rows: list  # (quantity, value, unit)
    resonances: list  # transfer.Resonance
    agreements: dict  # name -> transfer.Agreement
    figures: list
    tables: list
    wall_s: float


#: What a run writes into OUT: its figures, its tables and the FMUs it ran.
FIGURES = ("ride_transfer_functions.png", "road_run_iso8608.png", "road_psd.png",
           "road_run_cleat.png", "contact_events.png")
TABLES = ("summary.csv", "resonances.csv", "agreement.csv", "summary.json")
FMU_FOLDER = "fmus"
OUTPUTS = (*FIGURES, *TABLES, FMU_FOLDER)


def run_demo(settings: DemoSettings | None = None, log=print,
             names: dict[str, str] | None = None) -> DemoSummary:
    """The whole demo; ``names`` names the settings in error messages (see
    :meth:`DemoSettings.problems`).

    One run's outputs belong together: the run writes into a private folder beside OUT
    (the FMUs of the previous run linked in, rebuilt there when stale) and that folder
    replaces OUT only once complete (:func:`tire_fmu.publish.publish_folder`). A run that
    fails or is interrupted leaves OUT as the previous run left it. OUT must be new, or hold
    only what a run writes (:data:`OUTPUTS`): it is replaced whole.
    """
    settings = settings or DemoSettings()
    started = time.perf_counter()
    check_settings(settings, names)
    out = Path(settings.out_dir)
    option = (names or {}).get("out_dir", "out_dir")
    check_output_folder(out, option, OUTPUTS, DemoError)
    with run_folder(out, option, DemoError, carry=(FMU_FOLDER,)) as work:
        summary = _run(settings, work, started,
                       lambda text: log(str(text).replace(str(work), str(out))))

    def moved(paths):
        return [out / Path(p).relative_to(work) for p in paths]

    return replace(summary, figures=moved(summary.figures), tables=moved(summary.tables))


def _run(settings: DemoSettings, out: Path, started: float, log) -> DemoSummary:
    """The demo's work, every file written into ``out``."""
    fmus = ensure_fmus(out / FMU_FOLDER, settings.rebuild, log)
    rows: list[tuple[str, float | str, str]] = []
    figures, tables = [], []

    # -- references and coupling analysis ---------------------------------------------------
    from tire_fmu.core import OperatingPoint, TireParameters, build_model
    from tire_fmu.core.reduction import reduce

    from . import plots
    from .coupling import stability_limit
    from .quarter_car import (
        full_tire_two_port,
        quarter_car_modes,
        ride_response,
        spring_damper_two_port,
        tire_low_frequency,
    )
    from .transfer import (
        agreement,
        estimate_frf,
        identify_body_and_wheel,
        resonance_table,
        ride_outputs,
    )

    car, h, ex = settings.car, settings.step_s, settings.excitation
    log(f"tire model: N = {settings.n_elements}, load {car.static_tire_load_n:.0f} N, "
        f"speed {settings.tf_speed_m_s:g} m/s")
    model = build_model(TireParameters(), OperatingPoint(
        n_elements=settings.n_elements, load_n=car.static_tire_load_n,
        speed_m_s=settings.tf_speed_m_s))
    low = tire_low_frequency(model)
    modes = quarter_car_modes(car, model)
    reduced = reduce(model, report=False)
    limit = stability_limit(car, reduced)
    limit_jacobi = stability_limit(car, reduced, "jacobi")
    # how far Im K_dyn/ω strays from its low-frequency limit (the spring-damper's c) up to
    # wheel hop
    below_hop = np.linspace(ex.f_min_hz, modes.wheel_hop.frequency_hz, 40)
    k_dyn = -full_tire_two_port(model, below_hop).rim[0]
    damping_change = float(np.max(np.abs(k_dyn.imag / (2 * np.pi * below_hop)
                                         / low.damping_n_s_per_m - 1.0)))

    # -- transfer functions by co-simulation ------------------------------------------------
    tire_parameters = {"n_elements": settings.n_elements, "speed": settings.tf_speed_m_s}
    _, height, velocity = ex.road(h)
    with step_bar(height.size - 1, settings.progress, "transfer functions") as bar, \
            QuarterCarCoSimulation(fmus, car, tire_parameters, h) as sim:
        tf_run = sim.run(height, velocity, progress=bar.update)
    estimate = estimate_frf(height, ride_outputs(tf_run), ex, h)
    # the spring-damper reference feels the road where the footprint's centre does
    centre = model.patch.zone.centre
    delay = 0.5 * float(model.patch.road.early_s[centre] + model.patch.road.late_s[centre])

    def references(freqs):
        full = ride_response(car, full_tire_two_port(model, freqs))
        spring = ride_response(car, spring_damper_two_port(
            low.stiffness_n_per_m, low.damping_n_s_per_m, freqs, model.patch.load_n, delay))
        return full, spring

    full_at_lines, _ = references(estimate.freqs_hz)
    agreements = agreement(estimate, full_at_lines)
    fine = np.geomspace(ex.f_min_hz, ex.f_max_hz, 1500)
    full_fine, spring_fine = references(fine)
    identified = identify_body_and_wheel(estimate.freqs_hz, estimate.h1["body_acc"],
                                         estimate.h1["wheel_acc"],
                                         estimate.coherence["wheel_acc"])
    resonances = resonance_table(modes, full_fine, estimate, identified)
    figures.append(plots.plot_bode(
        estimate, full_fine, spring_fine, agreements, out / "ride_transfer_functions.png",
        title=f"Quarter car on TireModal.fmu, co-simulated through fmpy (h = {h * 1e3:g} ms, "
              f"N = {settings.n_elements}, speed {settings.tf_speed_m_s:g} m/s): "
              f"road -> ride, H1 from a {ex.f_min_hz:g}-{ex.f_max_hz:g} Hz multisine"))

    # -- road runs --------------------------------------------------------------------------
    road, spectrum = iso8608_road(settings.road_class, settings.road_speed_m_s,
                                  settings.road_duration_s, h, seed=1,
                                  fade_in_s=settings.road_fade_in_s)
    def road_run(profile, speed_m_s, what, figure):
        """Co-simulate one road profile at its speed and plot rim load and contact force."""
        parameters = {"n_elements": settings.n_elements, "speed": speed_m_s}
        with step_bar(profile.time_s.size - 1, settings.progress, what) as bar, \
                QuarterCarCoSimulation(fmus, car, parameters, h) as sim:
            run = sim.run(profile.height_m, profile.velocity_m_s, progress=bar.update)
        figures.append(plots.plot_road_run(
            run, out / figure, title=f"{profile.description}, N = {settings.n_elements}"))
        return run

    road_run_iso = road_run(road, settings.road_speed_m_s, "ISO 8608 road",
                            "road_run_iso8608.png")
    figures.append(_road_psd_figure(road, spectrum, out / "road_psd.png"))
    bump = cleat(settings.cleat_height_m, settings.cleat_length_m, settings.cleat_speed_m_s,
                 1.0, h, settings.cleat_shape, distance_m=1.0)
    cleat_run = road_run(bump, settings.cleat_speed_m_s, "cleat", "road_run_cleat.png")

    # -- contact events: the unilateral contact against the linear one ------------------
    v, duration = settings.events_speed_m_s, settings.events_duration_s
    distance = 0.5  # the obstacle reaches the zone front after 0.5 m
    events = {
        "cleat 20 x 20 mm": cleat(0.02, 0.02, v, duration, h, "rectangular", distance),
        "cleat 40 x 20 mm": cleat(0.04, 0.02, v, duration, h, "rectangular", distance),
        "pothole 50 mm deep, 0.3 m": pothole(0.05, 0.3, v, duration, h, "rectangular",
                                              distance),
    }
    event_runs = {}
    for name, profile in events.items():
        for law, linear in (("unilateral", False), ("linear", True)):
            parameters = {"n_elements": settings.n_elements, "speed": v,
                          "linear_contact": linear}
            with step_bar(profile.time_s.size - 1, settings.progress,
                           f"{name}, {law}") as bar, \
                    QuarterCarCoSimulation(fmus, car, parameters, h) as sim:
                event_runs[(name, law)] = sim.run(profile.height_m, profile.velocity_m_s,
                                                  progress=bar.update)
    figures.append(plots.plot_contact_events(
        events, event_runs, out / "contact_events.png",
        title=f"Contact events at {v:g} m/s, quarter car on TireModal.fmu (N = "
              f"{settings.n_elements}): the unilateral contact lets go, the linear one pulls"))

    # -- summary ----------------------------------------------------------------------------
    rows += [
        ("tire static stiffness K_v", low.stiffness_n_per_m, "N/m"),
        ("tire equivalent damping (low-frequency Im K_dyn / w)", low.damping_n_s_per_m,
         "N.s/m"),
        ("tire mass moving with the rim (road held)", low.rim_side_mass_kg, "kg"),
        ("coupling: spectral radius at h (Gauss-Seidel)", limit.radius_at_default, "-"),
        ("coupling: largest stable step (Gauss-Seidel)", limit.max_stable_step_s, "s"),
        ("coupling: largest stable step (Jacobi)", limit_jacobi.max_stable_step_s, "s"),
        ("tire equivalent damping: largest change of Im K_dyn / w up to wheel hop",
         100 * damping_change, "%"),
        ("road -> body acceleration (full model): fall from its peak to f_max",
         float(20 * np.log10(np.abs(full_fine["body_acc"]).max()
                             / abs(full_fine["body_acc"][-1]))), "dB"),
        ("transfer-function run: real-time factor (wall / simulated)",
         tf_run.real_time_factor, "-"),
        ("transfer-function run: contact lost", 100 * tf_run.contact_lost_fraction, "%"),
    ]
    for name, a in agreements.items():
        rows.append((f"max |dB| co-sim vs full model, {name} (coherence > 0.95)",
                     a.max_deviation_db, "dB"))
    for label, run in (("ISO road", road_run_iso), ("cleat", cleat_run)):
        rows += [
            (f"{label}: body acceleration RMS", float(np.std(run.body_az_m_s2)), "m/s2"),
            (f"{label}: rim load min", float(run.rim_Fz_n.min()), "N"),
            (f"{label}: rim load max", float(run.rim_Fz_n.max()), "N"),
            (f"{label}: contact force min", float(run.contact_Fz_n.min()), "N"),
            (f"{label}: contact force max", float(run.contact_Fz_n.max()), "N"),
            (f"{label}: contact lost", 100 * run.contact_lost_fraction, "%"),
            (f"{label}: real-time factor", run.real_time_factor, "-"),
        ]
    for (name, law), run in event_runs.items():
        rows += [
            (f"{name}, {law}: contact force min", float(run.contact_Fz_n.min()), "N"),
            (f"{name}, {law}: contact force max", float(run.contact_Fz_n.max()), "N"),
            (f"{name}, {law}: rim load max", float(run.rim_Fz_n.max()), "N"),
            (f"{name}, {law}: airborne", 100 * run.contact_lost_fraction, "%"),
        ]
    wall = time.perf_counter() - started
    rows.append(("demo wall time", wall, "s"))
    tables.append(_write_csv(out / "summary.csv", ("quantity", "value", "unit"), rows))
    tables.append(_write_csv(
        out / "resonances.csv",
        [*asdict(resonances[0]).keys(), "cosim_vs_analytic_pct"],
        [[*asdict(r).values(), r.cosim_vs_analytic_pct] for r in resonances]))
    tables.append(_write_csv(out / "agreement.csv", list(asdict(next(iter(
        agreements.values()))).keys()), [list(asdict(a).values()) for a in agreements.values()]))
    summary = DemoSummary(rows, resonances, agreements, figures, tables, wall)
    tables.append(_write_json(out / "summary.json", summary, settings))
    return summary


def _write_json(path: Path, summary: DemoSummary, settings: DemoSettings) -> Path:
    """Everything the summary tables hold, machine-readable (the docs quote it)."""
    def plain(value):
        return None if isinstance(value, float) and not math.isfinite(value) else value

    data = {
        "settings": {"n_elements": settings.n_elements, "step_s": settings.step_s,
                     "tf_speed_m_s": settings.tf_speed_m_s,
                     "road_speed_m_s": settings.road_speed_m_s,
                     "excitation": {k: plain(v) for k, v in asdict(settings.excitation).items()}},
        "rows": [{"quantity": q, "value": plain(v), "unit": u} for q, v, u in summary.rows],
        "agreements": {name: {k: plain(v) for k, v in asdict(a).items()}
                       for name, a in summary.agreements.items()},
        "resonances": [{k: plain(v) for k, v in asdict(r).items()}
                       for r in summary.resonances],
        "wall_s": summary.wall_s,
    }
    path.write_text(json.dumps(data, indent=1) + "\n")
    return path


def _road_psd_figure(road, spectrum, path):
    """The generator against its target, on a 2 km realisation of the same class and speed
    (the run itself is too short for a PSD estimate at long wavelengths)."""
    from scipy import signal, stats

    from . import plots

    length_m, spacing_m, segments = 2000.0, 0.02, 32
    long_road, _ = iso8608_road(spectrum.road_class, road.speed_m_s,
                                length_m / road.speed_m_s, spacing_m / road.speed_m_s, seed=1,
                                n_max_cycles_per_m=spectrum.n_max_cycles_per_m)
    z = long_road.height_m[:-1]
    n, psd = signal.welch(z, fs=1.0 / spacing_m, window="hann", nperseg=z.size // segments,
                          noverlap=0, detrend=False)
    dof = 2 * segments
    band = (dof / stats.chi2.ppf(0.975, dof), dof / stats.chi2.ppf(0.025, dof))
    return plots.plot_road_psd(n[1:], psd[1:], spectrum, band, path,
                               title=f"ISO 8608 class {spectrum.road_class} generator: a "
                                     f"{length_m / 1e3:g} km realisation vs the target PSD")


def _write_csv(path: Path, header, rows) -> Path:
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for row in rows:
            writer.writerow([_fmt(v) for v in row])
    return path


def _fmt(value):
    if isinstance(value, float):
        return "" if math.isnan(value) else f"{value:.6g}"
    return value


def format_summary(summary: DemoSummary) -> str:
    """The summary as text: key numbers, agreement, resonance table, files."""
    lines = ["", "Summary"]
    width = max(len(q) for q, _, _ in summary.rows)
    for quantity, value, unit in summary.rows:
        text = f"{value:.4g}" if isinstance(value, float) else str(value)
        lines.append(f"  {quantity:<{width}}  {text:>14} {unit}")
    lines += ["", "Resonances (f in Hz; analytic = two-mass car, tire spring K_v, with and "
              "without the tire's rim-side mass; - = not applicable)"]
    columns = [  # (header, width, format, value)
        ("resonance", -12, "", lambda r: r.resonance),
        ("response", -13, "", lambda r: r.response),
        ("analytic", 9, ".3f", lambda r: r.f_analytic_hz),
        ("massless", 9, ".3f", lambda r: r.f_analytic_massless_hz),
        ("reference", 10, ".3f", lambda r: r.f_reference_hz),
        ("co-sim", 9, ".3f", lambda r: r.f_cosim_hz),
        ("vs an. %", 9, "+.2f", lambda r: r.cosim_vs_analytic_pct),
        ("zeta ref", 9, ".3f", lambda r: r.zeta_reference),
        ("zeta co-sim", 11, ".3f", lambda r: r.zeta_cosim),
        ("gain ref", 11, ".4g", lambda r: r.gain_reference),
        ("gain co-sim", 11, ".4g", lambda r: r.gain_cosim),
        ("unit", -9, "", lambda r: r.gain_unit),
    ]

    def cell(value, width, spec):
        if isinstance(value, float) and math.isnan(value):
            value, spec = "-", ""
        text = format(value, spec)
        return text.ljust(-width) if width < 0 else text.rjust(width)

    lines.append("  " + " ".join(cell(h, w, "") for h, w, _, _ in columns).rstrip())
    for r in summary.resonances:
        lines.append("  " + " ".join(cell(get(r), w, spec)
                                     for _, w, spec, get in columns).rstrip())
    lines += ["", "Files"] + [f"  {p}" for p in [*summary.figures, *summary.tables]]
    return "\n".join(lines)
