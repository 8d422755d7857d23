"""``tire-fmu fit MEASURED``: identify tire data from measured natural frequencies."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..core.fit import CRITERIA, FitError, StaticMeasurement, fit_tire
from .common import (
    CliError,
    Output,
    add_output_options,
    add_tire_options,
    checked_tire,
    elements_problem,
    plot_with,
    positive_problem,
    range_problem,
    table,
    write_plot,
)

DEFAULT_FREE = "m_s,k_r1,k_r2,EI"


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "fit",
        help="identify tire data from measured natural frequencies (and static contact data)",
        description="Fit tire parameters to a CSV table of measured natural frequencies "
        "(columns order, branch in/out, frequency_hz, optional weight and damping_ratio) of "
        "the undeformed tire at rest, optionally with a vertical stiffness and footprint "
        "length measured at a load. Parameters not named by --free stay at the values of "
        "--tire-file / --tire (default GL073A), which are also the start values. Reports the "
        "fitted values with confidence intervals from the Jacobian, the residual of every "
        "mode, and the parameters the data cannot determine.",
    )
    p.add_argument("measured", metavar="MEASURED", type=Path,
                   help="CSV table of measured modes")
    p.add_argument("--free", metavar="NAME,...", default=DEFAULT_FREE,
                   help=f"parameters to fit, comma separated (default {DEFAULT_FREE}: tread "
                   "mass, geometry and pressure are taken as measured)")
    p.add_argument("--elements", metavar="N", type=int, default=None,
                   help="fit the FDM model of this mesh (exact per-order frequencies of the "
                   "assembled model) instead of the analytic ring, so the tire is right for "
                   "the mesh it runs on")
    p.add_argument("--criterion", choices=CRITERIA, default="least_squares",
                   help="least_squares (default) or max: smallest largest relative residual, "
                   "for a re-identification that must stay within a tolerance of every mode")
    g = p.add_argument_group("static contact measured at a load")
    g.add_argument("--load", metavar="N", type=float,
                   help="load of the static measurement in N, > 0 (no default: without it no "
                   "static data are fitted)")
    g.add_argument("--vertical-stiffness", metavar="N_PER_M", type=float,
                   help="measured vertical stiffness at --load, N/m")
    g.add_argument("--footprint-length", metavar="M", type=float,
                   help="measured footprint (contact patch) length at --load, m")
    g.add_argument("--static-weight", metavar="W", type=float, default=1.0,
                   help="weight of the static residuals (default 1, as one mode)")
    g.add_argument("--static-elements", metavar="N", type=int, default=100,
                   help="mesh of the static contact model (default 100)")
    p.add_argument("--confidence", metavar="P", type=float, default=0.95,
                   help="confidence level of the intervals (default 0.95)")
    p.add_argument("--determined-within", metavar="X", type=float, default=0.05,
                   help="flag a parameter whose interval reaches further than this relative "
                   "distance from its value (default 0.05)")
    p.add_argument("--out", metavar="FILE.toml", type=Path,
                   help="write the fitted tire as a tire file (read it with --tire-file)")
    p.add_argument("--name", default="", help="name written into the tire file")
    p.add_argument("--description", default=None,
                   help="description written into the tire file (default: what was fitted)")
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_fit)


def _static(args) -> StaticMeasurement | None:
    given = args.vertical_stiffness is not None or args.footprint_length is not None
    if args.load is None and not given:
        return None
    if args.load is None:
        raise CliError("--vertical-stiffness / --footprint-length need the --load they were "
                       "measured at")
    return StaticMeasurement(load_n=args.load, weight=args.static_weight,
                             vertical_stiffness_n_per_m=args.vertical_stiffness,
                             footprint_length_m=args.footprint_length,
                             n_elements=args.static_elements)


def run_fit(args: argparse.Namespace) -> Output:
    from ..measurements import MeasurementError, read_modes

    problems = [
        elements_problem(args.elements) if args.elements is not None else None,
        elements_problem(args.static_elements),
        range_problem("--confidence", args.confidence, 0.5, 0.9999),
        positive_problem("--determined-within", args.determined_within, ""),
        positive_problem("--static-weight", args.static_weight, ""),
    ]
    if args.out is not None and not args.out.parent.exists():
        problems.append(f"--out {args.out}: folder {args.out.parent} does not exist")
    start = checked_tire(args, problems)
    static = _static(args)
    try:
        modes = read_modes(args.measured)
    except MeasurementError as error:
        raise CliError(f"MEASURED {error}") from error
    free = [name.strip() for name in args.free.split(",") if name.strip()]
    try:
        result = fit_tire(modes, free, start, n_elements=args.elements, static=static,
                          criterion=args.criterion, confidence=args.confidence,
                          determined_within=args.determined_within)
    except FitError as error:
        raise CliError(str(error)) from error
    output = Output(text=report_text(result), data=result.to_dict())
    if args.out is not None:
        from ..tire_files import TireFileError, write_tire_file

        try:
            write_tire_file(args.out, result.tire, name=args.name,
                            description=args.description or _description(result, args),
                            source=f"tire-fmu fit {args.measured.name}",
                            metadata={"fit": fit_metadata(result)})
        except TireFileError as error:
            raise CliError(f"--out: {error}") from error
        output.written.append(args.out)
    write_plot(args, output, plot_with("plot_fit", result))
    return output


def _description(result, args) -> str:
    model = "analytic ring" if result.n_elements is None else f"FDM N = {result.n_elements}"
    return (f"fitted by tire-fmu fit to {args.measured.name}: {', '.join(result.free)} free "
            f"({model}, {result.criterion})")


def fit_metadata(result) -> dict:
    """What the [fit] table of a written tire file records."""
    data = {
        "model": "analytic" if result.n_elements is None else "fdm",
        "criterion": result.criterion,
        "free": list(result.free),
        "modes": len(result.modes),
        "residual_rms": result.residual_rms,
        "max_abs_residual_percent": float(max(abs(r) for r in result.residual_percent)),
        "confidence": result.confidence,
        "rank": result.rank,
        "undetermined": list(result.undetermined),
        "weakly_determined": list(result.weakly_determined),
    }
    if result.n_elements is not None:
        data["n_elements"] = result.n_elements
    intervals = {}
    for row in result.parameter_rows():
        if math.isfinite(row["interval_low"]) and math.isfinite(row["interval_high"]):
            intervals[row["name"]] = [row["interval_low"], row["interval_high"]]
    if intervals:
        data["intervals"] = intervals
    return data


def report_text(result) -> str:
    model = ("analytic ring" if result.n_elements is None
             else f"FDM model, N = {result.n_elements}")
    conf = f"{100 * result.confidence:g} %"
    lines = [
        f"fit of {len(result.free)} parameters to {len(result.modes)} modes on the {model} "
        f"({result.criterion}; {result.evaluations} evaluations, "
        f"{'converged' if result.success else 'NOT converged: ' + result.message})",
    ]
    rows = [[r["name"], r["unit"], r["start"], r["value"], r["interval_low"],
             r["interval_high"], r["status"]] for r in result.parameter_rows()]
    lines += ["", table(rows, ["parameter", "unit", "start", "fitted", f"{conf} low",
                               f"{conf} high", "status"])]
    mode_rows = [[m["label"], m["order"], m["branch"], m["measured_hz"], m["fitted_hz"],
                  m["residual_percent"], m["fitted_damping_ratio"]]
                 for m in result.mode_rows()]
    lines += ["", table(mode_rows, ["mode", "n", "branch", "measured [Hz]", "fitted [Hz]",
                                    "residual [%]", "fitted zeta"])]
    if result.static is not None:
        s = result.fitted_static
        lines.append(
            f"static at {result.static.load_n:g} N: vertical stiffness "
            f"{s['fitted_vertical_stiffness_n_per_m'] / 1e6:.4g} MN/m"
            + (f" (measured {result.static.vertical_stiffness_n_per_m / 1e6:.4g})"
               if result.static.vertical_stiffness_n_per_m else "")
            + f", footprint {s['fitted_footprint_length_m'] * 100:.4g} cm"
            + (f" (measured {result.static.footprint_length_m * 100:.4g})"
               if result.static.footprint_length_m else ""))
    lines.append("")
    lines.append(f"rank of the Jacobian: {result.rank} of {len(result.free)}; residual rms "
                 f"{result.residual_rms:.3g} with {result.degrees_of_freedom} degrees of freedom")
    if result.degrees_of_freedom <= 0:
        lines.append("no residual degrees of freedom: no confidence intervals (measure more "
                     "modes than free parameters)")
    for direction in result.null_directions:
        combo = " ".join(f"{v:+.2f}*ln({k})" for k, v in direction.items())
        lines.append(f"the data cannot see the direction {combo}: fix one of "
                     f"{', '.join(direction)} at a measured value")
    if result.weakly_determined:
        lines.append(f"weakly determined (interval beyond ±{100 * result.determined_within:g} "
                     f"%): {', '.join(result.weakly_determined)}")
    for a, b, r in result.correlated_pairs:
        lines.append(f"correlated: {a} and {b} (r = {r:+.3f}); the data pin a combination")
    return "\n".join(lines)
