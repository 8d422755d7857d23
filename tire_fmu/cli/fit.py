"""``tire-fmu fit MEASURED``: identify tire data from measured natural frequencies."""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from pathlib import Path

from ..core.fit import CRITERIA, FitError, StaticMeasurement, fit_tire
from ..core.fit_inplane import FITTABLE
from ..core.inplane_host import HOST_FIELDS
from ..core.parameters import DEFAULT_LOAD_N, MAX_PATCH_FRACTION, TIRE_FIELDS, FieldSpec
from .common import (
    MAX_FREQUENCY_HZ,
    CliError,
    Output,
    add_output_options,
    add_tire_options,
    checked_tire,
    elements_problem,
    field_problem,
    order_problem,
    output_file,
    output_path,
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
    p.add_argument("measured", metavar="MEASURED", type=Path, nargs="?",
                   help="CSV table of measured modes (optional when only in-plane data are "
                   "given below)")
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
    g = p.add_argument_group(
        "in-plane data (the tangential ring of tire-fmu inplane-modes)",
        "fitted after the radial data, with the radial tire fixed at its fit (or its "
        "given values); the other tangential data are the tire file's [tangential] table")
    g.add_argument("--tangential-mode", metavar="N=HZ", action="append", default=[],
                   help="measured frequency in Hz of order N's tangential branch, rim held "
                   "(N = 0: the rotational mode, rim held); repeat for more orders")
    g.add_argument("--rotational-free", metavar="HZ", type=float,
                   help="measured rotational mode in Hz with the rim free (the wheel's "
                   "inertia of the tire file)")
    g.add_argument("--slip-stiffness", metavar="N", type=float,
                   help="measured longitudinal slip stiffness dFx/dκ at small slip, N per "
                   "unit slip")
    g.add_argument("--slip-load", metavar="N", type=float, default=DEFAULT_LOAD_N,
                   help=f"load of the slip stiffness in N (default {DEFAULT_LOAD_N:g})")
    g.add_argument("--slip-speed", metavar="M_PER_S", type=float, default=10.0,
                   help="speed of the slip stiffness in m/s (default 10)")
    g.add_argument("--free-tangential", metavar="NAME,...",
                   help=f"tangential parameters to fit, of {','.join(FITTABLE)} (default: "
                   "k_t1,k_t2 with modes, EA with a mode of order >= 1, k_tx with a slip "
                   "stiffness)")
    g.add_argument("--inplane-elements", metavar="N", type=int, default=100,
                   help="mesh of the in-plane model the data are fitted on (default 100)")
    p.add_argument("--confidence", metavar="P", type=float, default=0.95,
                   help="confidence level of the intervals (default 0.95)")
    p.add_argument("--determined-within", metavar="X", type=float, default=0.05,
                   help="flag a parameter whose interval reaches further than this relative "
                   "distance from its value (default 0.05)")
    p.add_argument("--out", metavar="FILE.toml", type=output_path,
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


def _measured_problems(args: argparse.Namespace) -> list[str | None]:
    """The measured values given as numbers: each a finite number in its range (the loads and
    speed as the in-plane FMU's, the rest up to what the tire data allow)."""
    given = [
        ("--load", args.load, HOST_FIELDS["load_n"]),
        ("--slip-load", args.slip_load, HOST_FIELDS["load_n"]),
        ("--slip-speed", args.slip_speed, replace(HOST_FIELDS["speed_m_s"], low_inclusive=False)),
        ("--vertical-stiffness", args.vertical_stiffness,
         FieldSpec("", "N/m", "", 0.0, TIRE_FIELDS["k_r1"].high)),
        ("--footprint-length", args.footprint_length,
         FieldSpec("", "m", "", 0.0, MAX_PATCH_FRACTION * 2 * math.pi * TIRE_FIELDS["R"].high)),
        ("--rotational-free", args.rotational_free,
         FieldSpec("", "Hz", "", 0.0, MAX_FREQUENCY_HZ)),
        ("--slip-stiffness", args.slip_stiffness,
         FieldSpec("", "N", "", 0.0, TIRE_FIELDS["k_r1"].high)),
    ]
    return [field_problem(option, value, spec, "") for option, value, spec in given
            if value is not None]


def run_fit(args: argparse.Namespace) -> Output:
    from ..measurements import MeasurementError, read_modes

    problems = [
        elements_problem(args.elements) if args.elements is not None else None,
        elements_problem(args.static_elements, "--static-elements"),
        elements_problem(args.inplane_elements, "--inplane-elements"),
        range_problem("--confidence", args.confidence, 0.5, 0.9999),
        positive_problem("--determined-within", args.determined_within, "", 1.0),
        positive_problem("--static-weight", args.static_weight, "", 1e6),
        *_measured_problems(args),
    ]
    if args.out is not None:
        try:
            args.out = output_file("--out", args.out, ".toml")
        except CliError as error:  # reported with the others
            problems.append(str(error))
    targets = _inplane_targets(args, problems)
    for name in (args.free_tangential or "").split(","):
        if name.strip() and name.strip() not in FITTABLE:
            problems.append(f"--free-tangential {name.strip()!r}: must be one of "
                            f"{', '.join(FITTABLE)}")
    if args.measured is None and not targets:
        problems.append("give MEASURED (a CSV table of modes) or in-plane data "
                        "(--tangential-mode, --rotational-free, --slip-stiffness)")
    start = checked_tire(args, problems)
    static = _static(args)
    result = None
    if args.measured is not None:
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
    inplane = _fit_inplane(args, targets, result.tire if result is not None else start)
    texts = ([report_text(result)] if result is not None else []) + (
        [inplane_report_text(inplane)] if inplane is not None else [])
    data = result.to_dict() if result is not None else {}
    if inplane is not None:
        data["inplane"] = inplane.to_dict()
    output = Output(text="\n\n".join(texts), data=data)
    if args.out is not None:
        from ..tire_files import TireFileError, write_tire_file

        # with in-plane data, the tire the in-plane ring was fitted with (its radial data
        # with the lumped sidewall the ring has): the file then reads back to that ring
        tire = (inplane.model.tire if inplane is not None
                else result.tire if result is not None else start)
        metadata = {"fit": fit_metadata(result)} if result is not None else None
        source = "tire-fmu fit" + (f" {args.measured.name}" if args.measured else "")
        try:
            write_tire_file(args.out, tire, name=args.name,
                            description=args.description or _description(result, inplane,
                                                                          args),
                            source=source, metadata=metadata,
                            tangential=None if inplane is None else inplane.model.tangential)
        except TireFileError as error:
            raise CliError(f"--out: {error}") from error
        output.written.append(args.out)
    if result is not None:
        write_plot(args, output, plot_with("plot_fit", result))
    return output


def _inplane_targets(args, problems: list) -> list:
    from ..core.fit_inplane import InPlaneTarget

    targets = []
    for item in args.tangential_mode:
        order, sep, hz = item.partition("=")
        try:
            order_n, hz_value = int(order), float(hz)
        except ValueError:
            problems.append(f"--tangential-mode {item!r}: expected N=HZ, N an integer order "
                            "and HZ a frequency in Hz")
            continue
        found = [order_problem(f"--tangential-mode {item!r}: N", order_n, None, low=0),
                 field_problem(f"--tangential-mode {item!r}: HZ", hz_value,
                               FieldSpec("", "Hz", "", 0.0, MAX_FREQUENCY_HZ), "")]
        problems += [problem for problem in found if problem]
        if not any(found):
            targets.append(InPlaneTarget("tangential", hz_value, order=order_n))
    if args.rotational_free is not None:
        targets.append(InPlaneTarget("rotational_free", args.rotational_free))
    if args.slip_stiffness is not None:
        targets.append(InPlaneTarget("slip_stiffness", args.slip_stiffness,
                                     load_n=args.slip_load, speed_m_s=args.slip_speed))
    return targets


def _fit_inplane(args, targets, radial_tire):
    """The tangential fit on the radial tire (fitted or given), or None without data."""
    if not targets:
        return None
    from dataclasses import replace

    from ..core.fit_inplane import fit_inplane
    from ..core.inplane import InPlaneTire
    from .inplane import DEFAULT_TIRE_FILE, _tangential

    if args.free_tangential is not None:
        free = [n.strip() for n in args.free_tangential.split(",") if n.strip()]
    else:
        kinds = {t.kind for t in targets}
        free = (["k_t1", "k_t2"] if kinds & {"tangential", "rotational_free"} else [])
        if any(t.kind == "tangential" and t.order >= 1 for t in targets):
            free.append("EA")
        if "slip_stiffness" in kinds:
            free.append("k_tx")
    tangential = _tangential([], args.tire_file or DEFAULT_TIRE_FILE)
    # fitted on the paper's lumped radial sidewall (sidewall_max_order = 0), as the in-plane
    # tire files give it: the measured modes are low orders, where the tie does not act
    model = InPlaneTire(replace(radial_tire, sidewall_max_order=0.0), tangential)
    try:
        return fit_inplane(targets, free, model, n_elements=args.inplane_elements,
                           confidence=args.confidence,
                           determined_within=args.determined_within)
    except FitError as error:
        raise CliError(str(error)) from error


def inplane_report_text(result) -> str:
    conf = f"{100 * result.confidence:g} %"
    lines = [f"in-plane fit of {len(result.free)} tangential parameters to "
             f"{len(result.targets)} measurements on the FDM ring, N = {result.n_elements} "
             f"({'converged' if result.success else 'NOT converged: ' + result.message})", ""]
    rows = [[r["name"], r["unit"], r["start"], r["value"], r["interval_low"],
             r["interval_high"], r["status"]] for r in result.parameter_rows()]
    lines.append(table(rows, ["parameter", "unit", "start", "fitted", f"{conf} low",
                              f"{conf} high", "status"]))
    rows = [[t["label"], t["unit"], t["measured"], t["fitted"], t["residual_percent"]]
            for t in result.target_rows()]
    lines += ["", table(rows, ["measurement", "unit", "measured", "fitted", "residual [%]"]),
              "", f"rank of the Jacobian: {result.rank} of {len(result.free)}; residual rms "
              f"{result.residual_rms:.3g} with {result.degrees_of_freedom} degrees of freedom"]
    for direction in result.null_directions:
        combo = " ".join(f"{v:+.2f}*ln({k})" for k, v in direction.items())
        lines.append(f"the data cannot see the direction {combo}: fix one of "
                     f"{', '.join(direction)} at a measured value")
    return "\n".join(lines)


def _description(result, inplane, args) -> str:
    parts = []
    if result is not None:
        model = ("analytic ring" if result.n_elements is None
                 else f"FDM N = {result.n_elements}")
        parts.append(f"fitted by tire-fmu fit to {args.measured.name}: "
                     f"{', '.join(result.free)} free ({model}, {result.criterion})")
    if inplane is not None:
        parts.append(f"tangential {', '.join(inplane.free)} fitted to "
                     f"{', '.join(t.name for t in inplane.targets)} (in-plane ring, "
                     f"N = {inplane.n_elements})")
    return "; ".join(parts)


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
