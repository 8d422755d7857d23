"""``python -m vehicle_demo [--out DIR] [--quick]``, ``python -m vehicle_demo sweep ...`` and
``python -m vehicle_demo braking ...``, ``python -m vehicle_demo truck ...``.

Only parses arguments and delegates to :mod:`vehicle_demo.demo`, :mod:`vehicle_demo.sweep` and
:mod:`vehicle_demo.braking`.
"""

from __future__ import annotations

import os

# Before numpy loads: one BLAS thread. On two shared cores OpenBLAS's worker threads spin
# against each other and the small dense eigenproblems here get about ten times slower.
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

from tire_fmu.cli.parsing import (  # noqa: E402
    Parser,
    interrupted,
    one_line_warnings,
    stdout_failure,
    write_stdout,
)

PROG = "vehicle_demo"
#: The sweep's figure, beside its table in --out.
SWEEP_FIGURE = "sweep_resonances.png"


def _demo_parser() -> argparse.ArgumentParser:
    p = Parser(
        prog="python -m vehicle_demo",
        description="Quarter car co-simulated with TireModal.fmu through fmpy: ride transfer "
                    "functions (0.5-300 Hz) against the full-model and spring-damper "
                    "references, an ISO 8608 road run and a cleat. Writes figures and "
                    "summary tables to --out. (For a parameter sweep: python -m vehicle_demo "
                    "sweep --help; for the braking quarter car: python -m vehicle_demo braking "
                    "--help.)")
    p.add_argument("--out", type=Path, default=Path("demo_output"),
                   help="output folder (default: demo_output)")
    p.add_argument("--quick", action="store_true",
                   help="shorter run: N = 60, 0.5 Hz lines, 2 s road")
    p.add_argument("--n-elements", type=int, help="tire mesh (default 100, quick 60)")
    p.add_argument("--road-class", default="C", choices=list("ABCDEFGH"),
                   help="ISO 8608 class of the road run (default C)")
    p.add_argument("--road-speed", type=float, default=20.0, help="road-run speed, m/s")
    p.add_argument("--rebuild", action="store_true", help="rebuild the FMUs")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    return p


#: The demo's settings under the names of their options, for error messages.
OPTION_NAMES = {"n_elements": "--n-elements", "road_speed_m_s": "--road-speed",
                "out_dir": "--out"}


class _StdoutFailed(Exception):
    """stdout could not take the output (kept apart from the OSErrors of files)."""

    def __init__(self, error: OSError):
        super().__init__(str(error))
        self.error = error


def say(text="") -> None:
    """One line of output on stdout, flushed."""
    try:
        write_stdout(str(text))
    except OSError as error:
        raise _StdoutFailed(error) from error


def _sweep_parser() -> argparse.ArgumentParser:
    p = Parser(
        prog="python -m vehicle_demo sweep",
        description="Full-factorial sweep of the co-simulated quarter car on dask; writes the "
                    "table (CSV or Parquet) and a plot of how the resonances move.")
    p.add_argument("--factor", action="append", default=[], metavar="NAME=V1,V2,...",
                   help="a factor and its levels, e.g. load=20000,27655 or speed=0,10 or "
                        "inflation_pressure=6e5,7.9e5 (repeat for more factors)")
    p.add_argument("--out", type=Path, default=Path("sweep_output"), help="output folder")
    p.add_argument("--table", default="sweep.csv", help="file name: .csv or .parquet")
    p.add_argument("--address", help="dask.distributed scheduler address (default: dask's "
                                     "local process scheduler)")
    p.add_argument("--scheduler", choices=("auto", "synchronous", "processes"), default="auto",
                   help="synchronous: in this process; processes: dask's local processes; "
                        "auto (default): processes when there are at least two points per "
                        "worker and a free core for each, else synchronous")
    p.add_argument("--workers", type=int, default=2, help="local worker processes")
    p.add_argument("--n-elements", type=int, default=60, help="tire mesh unless a factor")
    p.add_argument("--rebuild", action="store_true", help="rebuild the FMUs")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def _parse_factors(items: list[str]) -> dict:
    from .sweep import SweepError

    factors = {}
    for item in items:
        name, sep, levels = item.partition("=")
        if not sep or not name or not levels:
            raise SweepError(f"--factor {item!r}: write NAME=V1,V2,...")
        try:
            factors[name.strip()] = [float(v) if any(c in v for c in ".eE") else int(v)
                                     for v in levels.split(",")]
        except ValueError:
            raise SweepError(f"--factor {item!r}: levels must be numbers") from None
    if not factors:
        raise SweepError("give at least one --factor NAME=V1,V2,...")
    return factors


def _braking_parser() -> argparse.ArgumentParser:
    p = Parser(
        prog="python -m vehicle_demo braking",
        description="Braking quarter car with the in-plane tire (the core in process, or "
                    "with --fmu TireInPlane.fmu through fmpy): the wheel "
                    "a turning body under a brake torque, the vehicle's fore-aft speed driven "
                    "by Fx, the axle's height held; on a level road, an ISO 8608 road and over "
                    "a cleat, then the classic cleat test (axle held, constant speed). Writes "
                    "braking.png, cleat_test.png and summary.json to --out.")
    p.add_argument("--out", type=Path, default=Path("braking_output"),
                   help="output folder (default: braking_output)")
    p.add_argument("--quick", action="store_true", help="shorter run: N = 60, 0.6 s")
    p.add_argument("--speed", type=float, help="start speed in m/s (default 20)")
    p.add_argument("--torque", type=float,
                   help="brake torque in N m, negative brakes (default -6000)")
    p.add_argument("--duration", type=float, help="run length in s (default 1.2, quick 0.6)")
    p.add_argument("--road-class", choices=list("ABCDEFGH"), help="ISO 8608 class (default C)")
    p.add_argument("--n-elements", type=int, help="tire mesh (default 100, quick 60)")
    p.add_argument("--fmu", action="store_true",
                   help="step TireInPlane.fmu through fmpy (built into OUT/fmus) instead of "
                   "the core's tire in process")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    return p


def _truck_parser() -> argparse.ArgumentParser:
    from .truck import TIRE_FMUS

    p = Parser(
        prog="python -m vehicle_demo truck",
        description="A two-axle truck (heave, pitch, roll, four wheels) on four tire FMUs over "
                    "an OpenCRG road (written to OUT/truck_road.crg unless --road is given: "
                    "independent ISO 8608 left and right tracks), stepped by fmpy and, with "
                    "--host both, by libcosim too, whose outputs are compared. Prints the ride "
                    "figures and the real-time factor; writes truck.png and summary.json.")
    p.add_argument("--out", type=Path, default=Path("truck_output"),
                   help="output folder (default: truck_output)")
    p.add_argument("--tire", choices=TIRE_FMUS, default=TIRE_FMUS[0],
                   help=f"the tire FMU, built into OUT/fmus (default {TIRE_FMUS[0]})")
    p.add_argument("--host", choices=("fmpy", "libcosim", "both"), default="fmpy",
                   help="the master (default fmpy; both: fmpy, then libcosim, compared)")
    p.add_argument("--speed", type=float, default=15.0, help="truck speed in m/s (default 15)")
    p.add_argument("--duration", type=float, default=3.0, help="run length in s (default 3)")
    p.add_argument("--step", type=float, default=1e-3,
                   help="host communication step in s (default 0.001)")
    p.add_argument("--road", type=Path,
                   help="an OpenCRG road (at least the track wide: the wheels run at v = "
                        "±track/2), instead of the generated one")
    p.add_argument("--road-class", choices=list("ABCDEFGH"), default="C",
                   help="ISO 8608 class of the generated road (default C)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    return p


def _truck(argv) -> int:
    from .truck import format_truck, run_truck_demo

    args = _truck_parser().parse_args(argv)
    summary = run_truck_demo(args.out, tire=args.tire, host=args.host, speed_m_s=args.speed,
                             duration_s=args.duration, step_s=args.step, road=args.road,
                             road_class=args.road_class, progress=not args.no_progress,
                             log=say)
    say(format_truck(summary))
    return 0


#: The braking demo's settings under the names of their options, for error messages.
BRAKING_OPTION_NAMES = {"speed_m_s": "--speed", "brake_torque_n_m": "--torque",
                        "duration_s": "--duration", "road_class": "--road-class",
                        "n_elements": "--n-elements"}


def _braking(argv) -> int:
    from .braking import BrakingSettings, format_braking, run_braking

    args = _braking_parser().parse_args(argv)
    given = {"out_dir": args.out, "speed_m_s": args.speed, "brake_torque_n_m": args.torque,
             "duration_s": args.duration, "road_class": args.road_class,
             "n_elements": args.n_elements, "progress": not args.no_progress,
             "fmu": args.fmu or None}
    overrides = {k: v for k, v in given.items() if v is not None}
    settings = (BrakingSettings.quick(**overrides) if args.quick
                else BrakingSettings(**overrides))
    summary = run_braking(settings, log=say, names=BRAKING_OPTION_NAMES)
    say(format_braking(summary))
    return 0


def _demo(argv) -> int:
    from .demo import DemoSettings, format_summary, run_demo

    args = _demo_parser().parse_args(argv)
    overrides = dict(out_dir=args.out, road_class=args.road_class,
                     road_speed_m_s=args.road_speed, rebuild=args.rebuild,
                     progress=not args.no_progress)
    if args.n_elements is not None:
        overrides["n_elements"] = args.n_elements
    settings = DemoSettings.quick(**overrides) if args.quick else DemoSettings(**overrides)
    summary = run_demo(settings, log=say, names=OPTION_NAMES)
    say(format_summary(summary))
    return 0


def _sweep(argv) -> int:
    from .demo import ensure_fmus
    from .outputs import check_output_folder, run_folder
    from .plots import plot_sweep
    from .sweep import SweepError, SweepSettings, full_factorial, run_sweep, save_table

    args = _sweep_parser().parse_args(argv)
    factors = _parse_factors(args.factor)
    out = args.out
    # one run's FMUs, table and figure, replacing the previous run's whole (any table name)
    earlier_tables = [p.name for p in out.glob("*") if p.suffix in (".csv", ".parquet")]
    check_output_folder(out, "--out", ("fmus", SWEEP_FIGURE, Path(args.table).parts[0],
                                       *earlier_tables), SweepError)
    with run_folder(out, "--out", SweepError, carry=("fmus",)) as work:
        fmus = ensure_fmus(work / "fmus", args.rebuild,
                           log=lambda text: say(str(text).replace(str(work), str(out))))
        result = run_sweep(full_factorial(factors), fmus,
                           SweepSettings(n_elements=args.n_elements), scheduler=args.scheduler,
                           address=args.address, n_workers=args.workers,
                           progress=not args.no_progress)
        table = out / save_table(result, work / args.table).relative_to(work)
        figure = out / plot_sweep(result.table, next(iter(factors)), work / SWEEP_FIGURE,
                                  title=f"Resonances over the sweep ({result.scheduler})"
                                  ).relative_to(work)
    shown = [*result.factors, "status", "body_bounce_hz", "wheel_hop_hz", "tire_mode_hz",
             "ref_body_bounce_hz", "ref_wheel_hop_hz", "contact_lost_fraction"]
    say(result.table[shown].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    for _, row in result.failed.iterrows():
        point = ", ".join(f"{f}={row[f]:g}" for f in result.factors)
        say(f"failed: {point}: {row['error']}")
    say(f"\n{len(result.table)} points in {result.wall_s:.1f} s "
          f"({result.points_per_minute:.1f} points/min, {result.scheduler}); "
          f"{len(result.failed)} failed")
    say(f"wrote {table}\nwrote {figure}")
    return 0


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        with one_line_warnings(PROG):  # e.g. a build without a win64 compiler: what to install
            return _main(argv)
    except KeyboardInterrupt:
        return interrupted(PROG)


def _main(argv: list[str]) -> int:
    from tire_fmu.core.inplane_contact import ContactSetError
    from tire_fmu.core.parameters import ParameterError
    from tire_fmu.file_checks import FileContentError

    from .braking import BrakingError
    from .cosim import CoSimError
    from .demo import DemoError
    from .quarter_car import QuarterCarError
    from .road import RoadError
    from .sweep import SweepError
    from .truck import TruckError

    user_errors = (DemoError, SweepError, RoadError, QuarterCarError, CoSimError,
                   BrakingError, TruckError, ContactSetError, ParameterError, FileContentError,
                   FileNotFoundError, PermissionError)
    warnings.filterwarnings("ignore", category=DeprecationWarning)
    try:
        if argv[:1] == ["sweep"]:
            return _sweep(argv[1:])
        if argv[:1] == ["braking"]:
            return _braking(argv[1:])
        if argv[:1] == ["truck"]:
            return _truck(argv[1:])
        return _demo(argv)
    except user_errors as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 2
    except _StdoutFailed as failed:
        return stdout_failure(PROG, failed.error)


if __name__ == "__main__":
    sys.exit(main())
