"""Ring-model commands at rest: modes, analytic, patch, and the studies convergence and
patch-sweep (the paper's Figs. 14 and 17)."""

from __future__ import annotations

import argparse

import numpy as np

from ..core import analytic_modes, modal_analysis
from ..core.studies import ROUNDING_LEVEL, convergence_study, patch_sweep
from .commands import command_help
from .common import (
    LOAD_ZERO,
    Output,
    add_contact_options,
    add_mesh_option,
    add_output_options,
    add_speed_options,
    add_tire_options,
    checked_tire,
    checked_together,
    element_list,
    elements_problem,
    frequency_problem,
    model_from_args,
    order_problem,
    patch_length_problem,
    plot_with,
    progress_bar,
    raise_problems,
    range_problem,
    table,
    validated_args,
    write_plot,
)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "modes",
        help=command_help("modes"),
        description="Modal analysis of the ring tire, by default undeformed (no load) as the "
        "paper tabulates it; --load gives the loaded tire's split pairs. At rest: real modes "
        "labelled by order, "
        "in/out-of-phase and (with a patch) symmetric/antisymmetric about the patch centre. "
        "Rolling (--speed > 0): complex ground-frame modes with signed order and direction.",
    )
    add_mesh_option(p)
    add_contact_options(p, 0.0)  # the paper's modes start from the undeformed tire
    add_speed_options(p)
    p.add_argument("--max-frequency", metavar="HZ", type=float, default=300.0,
                   help="highest frequency listed in Hz (default 300)")
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_modes)

    p = subparsers.add_parser(
        "analytic",
        help=command_help("analytic"),
        description="Exact roots of eq. 12 per order n: in-phase and out-of-phase frequencies.",
    )
    p.add_argument("--nmax", metavar="N", type=int, default=12,
                   help="highest circumferential order n (default 12)")
    add_tire_options(p)
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_analytic)

    p = subparsers.add_parser(
        "patch",
        help=command_help("patch"),
        description="Static contact of the tire pressed on a flat road, computed by the model "
        "itself (unilateral road springs on the contact zone, active-set continuation in the "
        "rim deflection): deflection, footprint length (road length between the edges where "
        "the interpolated penetration crosses zero), line pressure per node, secant and "
        "tangent vertical stiffness. --deflection gives the load for a rim deflection instead; "
        "--patch-length shows the paper's prescribed patch (Figs. 17-19).",
    )
    group = p.add_mutually_exclusive_group(required=True)
    group.add_argument("--load", metavar="N", type=float,
                       help=f"static vertical load in N (no default: give --load, --deflection "
                       f"or --patch-length; {LOAD_ZERO})")
    group.add_argument("--deflection", metavar="M", type=float,
                       help="rim deflection in m: the load that makes it")
    group.add_argument("--patch-length", metavar="M", type=float,
                       help="the paper's prescribed patch of this length in m")
    p.add_argument("--zone-length", metavar="M", type=float,
                   help="length of road under the contact zone in m (default 0.6)")
    add_mesh_option(p)
    add_speed_options(p)
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_patch)

    p = subparsers.add_parser(
        "convergence",
        help=command_help("convergence"),
        description="Undeformed tire at rest: in-phase and out-of-phase frequency of each order "
        "from the assembled FDM model on each mesh, against the exact roots of eq. 12, with "
        "the observed convergence order (log-log slope of the error against δθ = 2π/N, "
        "fitted over meshes with N >= 8n; 2 expected).",
    )
    p.add_argument("--elements-list", metavar="N1,N2,...", default=DEFAULT_ELEMENT_LIST,
                   help=f"meshes to solve, comma separated (default {DEFAULT_ELEMENT_LIST})")
    p.add_argument("--nmax", metavar="N", type=int, default=10,
                   help="highest circumferential order n (default 10)")
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_convergence)

    p = subparsers.add_parser(
        "patch-sweep",
        help=command_help("patch-sweep"),
        description="Tire at rest: frequency of the symmetric member (antinode at the patch "
        "centre, Kindt's 'extr', the one the patch stiffens) and the antisymmetric member "
        "(node there, '0', barely moves) of each order, against patch length, as a shift over "
        "the undeformed tire of the same mesh.",
    )
    add_mesh_option(p)
    p.add_argument("--max-length", metavar="M", type=float, default=0.40,
                   help="longest patch in m (default 0.40)")
    p.add_argument("--steps", metavar="K", type=int, default=41,
                   help="number of patch lengths from 0 to --max-length (default 41: 1 cm steps)")
    p.add_argument("--nmax", metavar="N", type=int, default=6,
                   help="orders 1..N (default 6)")
    p.add_argument("--out-of-phase", action="store_true",
                   help="sweep the out-of-phase members too")
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_patch_sweep)


DEFAULT_ELEMENT_LIST = "20,40,60,80,100,150,200,300,400"


def run_modes(args: argparse.Namespace) -> Output:
    _, checked = checked_together(
        lambda: raise_problems([frequency_problem("--max-frequency", args.max_frequency)]),
        lambda: validated_args(args, undeformed_default=True))
    model = model_from_args(args, checked=checked)
    result = modal_analysis(model, f_max_hz=args.max_frequency)
    rolling = model.speed_m_s > 0
    header = ["#", "f [Hz]", "order", "phase", "symmetry" if not rolling else "direction",
              "zeta"]
    rows = []
    for i, m in enumerate(result.modes):
        label = m.direction if rolling else m.symmetry
        rows.append([i + 1, m.frequency_hz, m.order, m.phase, label, m.damping_ratio])
    summary = model.summary()
    head = (
        f"{len(result.modes)} modes up to {args.max_frequency:g} Hz; N = {model.n_elements}, "
        f"patch {summary['patch_length_m'] * 100:.3g} cm, load {summary['load_n']:.4g} N, "
        f"speed {model.speed_m_s:g} m/s"
    )
    output = Output(text=head + "\n" + table(rows, header), data=result.to_dict())

    write_plot(args, output, plot_with("plot_mode_shapes", result))
    return output


def run_analytic(args: argparse.Namespace) -> Output:
    tire = checked_tire(args, [order_problem("--nmax", args.nmax, None, low=0)])
    result = analytic_modes(tire, np.arange(args.nmax + 1))
    rows = [[n, f_in, f_out] for n, f_in, f_out in
            zip(result.orders, result.in_phase_hz, result.out_of_phase_hz)]
    text = table(rows, ["n", "in-phase [Hz]", "out-of-phase [Hz]"])
    return Output(text=text, data=result.to_dict())


def run_patch(args: argparse.Namespace) -> Output:
    from ..core.model import footprint_for_deflection

    if args.deflection is not None:
        args.load = 0.0  # the zone and its compliance, then the path at that deflection
    _, checked = checked_together(
        lambda: raise_problems([None if args.deflection is None else range_problem(
            "--deflection", args.deflection, 0.0, 0.5, unit="m")]),
        lambda: validated_args(args, undeformed_default=False))
    model = model_from_args(args, checked=checked)
    patch = model.patch
    if args.deflection is not None:
        patch = footprint_for_deflection(model, args.deflection)
    data = patch.to_dict()
    data.update(n_elements=model.n_elements, speed_m_s=model.speed_m_s)
    lines = [f"load                {patch.load_n:.6g} N",
             f"deflection          {patch.deflection_m * 1000:.4g} mm (rim lowered from "
             "touching)"]
    if patch.prescribed:
        lines += [f"patch length        {patch.length_m * 100:.4g} cm (prescribed: the "
                  "paper's patch, load K_v·δ)",
                  f"vertical stiffness  {patch.vertical_stiffness_n_per_m / 1e6:.4g} MN/m"]
    else:
        fp = patch.footprint
        data["footprint"] = fp.to_dict()
        lines += [f"footprint length    {fp.length_m * 100:.4g} cm on the road "
                  f"({fp.n_active} of {fp.zone.n_points} contact points push, N = "
                  f"{model.n_elements})",
                  f"contact points      {fp.zone.points_per_node} per node, "
                  f"{fp.zone.point_arc_m * 1e3:.3g} mm apart (--point-spacing "
                  f"{fp.zone.point_spacing_m * 1e3:g} mm)",
                  f"stiffness           secant {fp.secant_stiffness_n_per_m / 1e6:.4g} MN/m, "
                  f"tangent {fp.tangent_stiffness_n_per_m / 1e6:.4g} MN/m",
                  f"longitudinal force  {fp.longitudinal_force_n:.4g} N (road on tire, x "
                  "forward)"]
        rows = [[np.degrees(t), 1e3 * x, q / 1e3, 1e3 * pen] for t, x, q, pen in zip(
            fp.zone.point_theta, fp.zone.road_positions_m(fp.deflection_m),
            fp.line_pressure_n_per_m, fp.penetration_m) if q > 0]
        lines += ["", table(rows, ["theta [deg]", "x [mm]", "line pressure [kN/m]",
                                   "penetration [mm]"])]
    output = Output(text="\n".join(lines), data=data)
    write_plot(args, output, plot_with("plot_footprint", model, patch))
    return output


def run_convergence(args: argparse.Namespace) -> Output:
    counts, problem = element_list(args.elements_list, DEFAULT_ELEMENT_LIST)
    tire = checked_tire(args, [problem, range_problem("--nmax", args.nmax, 1, 200, integer=True)])
    with progress_bar("meshes") as progress:
        result = convergence_study(tire, counts, range(0, args.nmax + 1), progress=progress)
    lines = [
        f"FDM vs exact (eq. 12), undeformed tire at rest; N = {', '.join(map(str, counts))}.",
        "Error = FDM / exact - 1 in %; p = observed order of |error| ~ δθ^p "
        f"(fit over N >= 8n; assembled model vs FDM symbols within "
        f"{result.model_symbol_difference:.1e}).",
    ]
    for phase, name in (("in", "in-phase"), ("out", "out-of-phase")):
        error = 100.0 * result.relative_error(phase)
        slopes = result.convergence_order(phase)
        rows = [[n, result.exact_hz(phase)[j], *error[:, j],
                 _order_cell(slopes[j], error[:, j] / 100.0)]
                for j, n in enumerate(result.orders)]
        header = ["n", "exact [Hz]", *(f"N={c}" for c in counts), "p"]
        lines += ["", f"{name} error [%]", table(rows, header)]
    lines += ["", "p = exact: the FDM reproduces that order to rounding on every mesh (n = 0: "
              "uniform breathing, no stencil error); p = -: fewer than two meshes with "
              "N >= 8n."]
    output = Output(text="\n".join(lines), data=result.to_dict())
    write_plot(args, output, plot_with("plot_convergence", result))
    return output


def _order_cell(slope: float, relative_error: np.ndarray) -> float | str:
    """The observed order, or why there is none (instead of nan)."""
    if np.isfinite(slope):
        return float(slope)
    if np.all(np.abs(relative_error) <= ROUNDING_LEVEL):
        return "exact"
    return "-"


def run_patch_sweep(args: argparse.Namespace) -> Output:
    problems = [
        elements_problem(args.elements),
        range_problem("--steps", args.steps, 2, 1000, integer=True),
        range_problem("--nmax", args.nmax, 1, 50, integer=True),
    ]
    tire = checked_tire(args, problems, lambda t: [
        patch_length_problem("--max-length", args.max_length, t, positive=True)])
    phases = ("in", "out") if args.out_of_phase else ("in",)
    lengths = np.linspace(0.0, args.max_length, args.steps)
    with progress_bar("patch lengths") as progress:
        result = patch_sweep(tire, args.elements, lengths, range(1, args.nmax + 1), phases,
                             progress=progress)
    # A compact view: the shifts at a quarter, half and all of the longest patch.
    picks = sorted({result.at_length(f * args.max_length) for f in (0.25, 0.5, 1.0)})
    lines = [f"Frequency shift over the undeformed tire in % (N = {result.n_elements}, at rest); "
             "sym = symmetric member (antinode at the patch centre), anti = antisymmetric."]
    for phase in phases:
        sym = result.shift_percent("symmetric", phase)
        anti = result.shift_percent("antisymmetric", phase)
        header = ["n", "f0 [Hz]"]
        for i in picks:
            label = f"{result.lengths_m[i] * 100:.3g}cm"
            header += [f"sym {label}", f"anti {label}"]
        rows = []
        for j, n in enumerate(result.orders):
            row = [n, result.undeformed_hz[phase][j]]
            for i in picks:
                row += [sym[i, j], anti[i, j]]
            rows.append(row)
        loads = ", ".join(f"{result.lengths_m[i] * 100:.3g} cm: {result.loads_n[i] / 1e3:.3g} kN"
                          for i in picks)
        branch = "in-phase" if phase == "in" else "out-of-phase"
        lines += ["", f"{branch} (static loads {loads})", table(rows, header)]
    output = Output(text="\n".join(lines), data=result.to_dict())
    write_plot(args, output, plot_with("plot_patch_sweep", result))
    return output
