"""``tire-fmu cleat``: the rim load over a cleat or a pothole against the mesh, rim held at its
static height (the study of issue 21, :func:`tire_fmu.core.studies.cleat_convergence`)."""

from __future__ import annotations

import argparse

from ..core.parameters import DEFAULT_LOAD_N
from .commands import command_help
from .common import (
    LOAD_ZERO,
    Output,
    add_output_options,
    add_tire_options,
    checked_tire,
    element_list,
    load_default_text,
    plot_with,
    positive_problem,
    progress_bar,
    range_problem,
    table,
    write_plot,
)

DEFAULT_ELEMENT_LIST = "100,200,400,800"
# core.studies.CLEAT_STEP_S and CLEAT_POINT_SPACING_M (no numpy before parsing;
# tests/test_cli.py holds them equal)
DEFAULT_STEP_S = 2.5e-5
DEFAULT_POINT_SPACING_M = 2.5e-3


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "cleat",
        help=command_help("cleat"),
        description="A tire rolling over a cleat (or, with --pothole, into a pothole) with its "
        "rim held at the static height for --load, on each mesh of --elements-list: the rim "
        "load's peak rise, its history against the finest mesh's, a Richardson extrapolation "
        "of the peak over the meshes, the smallest contact force while the obstacle is under "
        "the tire, and the contact force's lines at the rates at which the nodes and the "
        "contact points pass over the road.",
    )
    p.add_argument("--height", metavar="M", type=float, default=0.02,
                   help="cleat height in m, or the pothole's depth (default 0.02)")
    p.add_argument("--length", metavar="M", type=float, default=0.02,
                   help="obstacle length along the road in m (default 0.02)")
    p.add_argument("--shape", choices=("rectangular", "rounded"), default="rectangular",
                   help="rectangular (steps) or rounded (a 1 - cos bump); default rectangular")
    p.add_argument("--pothole", action="store_true",
                   help="a pothole --height deep instead of a cleat")
    p.add_argument("--speed", metavar="M_PER_S", type=float, default=10.0,
                   help="rolling speed in m/s (default 10)")
    p.add_argument("--elements-list", metavar="N1,N2,...", default=DEFAULT_ELEMENT_LIST,
                   help=f"meshes, comma separated, coarse to fine (default "
                   f"{DEFAULT_ELEMENT_LIST}; the finest is the reference)")
    p.add_argument("--point-spacing", metavar="M", type=float, default=DEFAULT_POINT_SPACING_M,
                   help="largest distance in m between the contact points on the tread "
                   f"(default {DEFAULT_POINT_SPACING_M:g}; 1 gives one point per node, the "
                   "node contact)")
    p.add_argument("--load", metavar="N", type=float, default=DEFAULT_LOAD_N,
                   help="static load in N that sets the height the rim is held at "
                   f"({load_default_text(DEFAULT_LOAD_N)}; {LOAD_ZERO})")
    p.add_argument("--step", metavar="S", type=float, default=DEFAULT_STEP_S,
                   help=f"communication step in s (default {DEFAULT_STEP_S:g}: the peak rise "
                   "moves by under 0.2 %% when it is halved)")
    p.add_argument("--zone-length", metavar="M", type=float, default=None,
                   help="contact zone length in m (default 0.6, widened to meet the obstacle "
                   "where the undeformed tread first reaches it)")
    p.add_argument("--histories", action="store_true",
                   help="include the time, rim_Fz and contact_Fz histories (s, N) in --json")
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_cleat)


def run_cleat(args: argparse.Namespace) -> Output:
    from ..core.obstacles import MAX_OBSTACLE_LENGTH_M, MAX_OBSTACLE_SIZE_M, Obstacle
    from ..core.parameters import MAX_POINT_SPACING_M, MIN_POINT_SPACING_M
    from ..core.standing_waves import MAX_SCANNED_SPEED_M_S
    from ..core.studies import CLEAT_TABLE_HEADER, cleat_convergence, cleat_table

    counts, problem = element_list(args.elements_list, DEFAULT_ELEMENT_LIST)
    problems = [
        problem,
        range_problem("--height", args.height, 1e-4, MAX_OBSTACLE_SIZE_M, "m"),
        range_problem("--length", args.length, 1e-4, MAX_OBSTACLE_LENGTH_M, "m"),
        positive_problem("--speed", args.speed, "m/s", MAX_SCANNED_SPEED_M_S),
        range_problem("--step", args.step, 1e-7, 1e-3, "s"),
        range_problem("--point-spacing", args.point_spacing, MIN_POINT_SPACING_M,
                      MAX_POINT_SPACING_M, "m"),
        range_problem("--load", args.load, 0.0, 1e7, "N"),
    ]  # --zone-length: the core's zone check, as the FMU's contact_zone_length
    tire = checked_tire(args, problems)
    obstacle = Obstacle(-args.height if args.pothole else args.height, args.length, args.shape)
    with progress_bar("meshes") as progress:
        result = cleat_convergence(
            tire, obstacle, args.speed, counts, point_spacing_m=args.point_spacing,
            load_n=args.load, step_s=args.step, contact_zone_length_m=args.zone_length,
            progress=progress)
    data = result.to_dict(histories=args.histories)
    rows, note = cleat_table(data)
    lines = [f"{obstacle.label} at {args.speed:g} m/s, rim held at its static height for "
             f"{result.load_n:.6g} N, step {args.step:g} s.",
             "rim_Fz peak rise: largest rim_Fz less the static; vs converged: against the "
             "extrapolated rise; rms vs finest: the history against the finest mesh's, over "
             "the finest's rms deviation; min contact_Fz and the lines (Hann-windowed "
             "amplitude, within 5 % of the passing rate of the rays over the road) while the "
             f"obstacle is under the tire ({1e3 * result.under_tire_s[-1, 0]:.3g} to "
             f"{1e3 * result.under_tire_s[-1, 1]:.3g} ms from its first edge at the contact "
             "centre).",
             "", table(rows, list(CLEAT_TABLE_HEADER)), "", note + "."]
    output = Output(text="\n".join(lines), data=data)
    write_plot(args, output, plot_with("plot_cleat_convergence", result))
    return output
