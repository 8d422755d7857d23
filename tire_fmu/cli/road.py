"""``tire-fmu road``: road files for the tire's ``road_file``: cleats, potholes and ISO 8608
random roads written as OpenCRG (``.crg``) or two-column profile files, and a road file read
back (its extent, heights and a plot of the profile the tire reads).

The shapes are the core's (:mod:`tire_fmu.core.obstacles`, :mod:`tire_fmu.core.iso8608`),
the files :mod:`tire_fmu.road_files`'s; this module only parses and delegates.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .commands import command_help
from .common import (
    CliError,
    Output,
    add_output_options,
    check_parent_folder,
    plot_with,
    positive_problem,
    raise_problems,
    range_problem,
    write_plot,
    writing,
)

# core.obstacles' and road_files' limits (no numpy before parsing; tests/test_road_files.py
# holds them equal)
MAX_OBSTACLE_SIZE_M = 0.3
MAX_OBSTACLE_LENGTH_M = 10.0
MAX_CROWN_RADIUS_M = 0.05
FORMATS = ("KRBI", "KDBI", "LRFI", "LDFI")
OBSTACLE_SPACING_M = 5e-4
ISO_SPACING_M = 5e-3

J2730 = ("SAE J2730 (Dynamic Cleat Test with Perpendicular and Inclined Cleats): a rolling "
         "tire with its spindle held at a fixed loaded radius meets a rectangular cleat across "
         "its path. The standard's cleat dimensions are in its paid text, not reproduced here: "
         "give yours (the default, 20 mm x 20 mm, is this project's cleat study's).")
J2705 = ("SAE J2705 (Tire Quasi-Static Envelopment of Triangular/Step Cleats Test) presses a "
         "non-rolling tire onto triangular cleats of apex half-angle 45, 60, 75, 80 or 85 deg "
         "(75 and 85 optional) or onto a single step cleat, each with a crown radius of 1.5 to "
         "3.0 mm (from the public summary of the standard, tnlab.org's guide to J2705-2018); "
         "its heights are not public: give yours.")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "road", help=command_help("road"),
        description="Road files for the FMUs' road_file: cleats (SAE J2730's rectangular, SAE "
        "J2705's triangular and step cleats), potholes and ISO 8608 random roads, written as "
        "OpenCRG (.crg) or profile files (distance m, height m), and a road file read back. "
        "An obstacle starts after --lead-in of level road; each sample holds the shape's mean "
        "over its stretch of road (an edge is a ramp one --spacing long, and the road's "
        "integral is the shape's at every sample).")
    kinds = p.add_subparsers(dest="road_kind", required=True, metavar="KIND")

    cleat = kinds.add_parser("cleat", help="a rectangular (SAE J2730) or rounded cleat",
                             description=J2730)
    cleat.add_argument("--height", metavar="M", type=float, default=0.02,
                       help="cleat height in m (default 0.02)")
    cleat.add_argument("--length", metavar="M", type=float, default=0.02,
                       help="cleat length along the road in m (default 0.02)")
    cleat.add_argument("--shape", choices=("rectangular", "rounded"), default="rectangular",
                       help="rectangular (J2730's) or rounded, a 1 - cos bump (default "
                       "rectangular)")
    _writer_options(cleat, OBSTACLE_SPACING_M)
    cleat.set_defaults(handler=run_cleat)

    pothole = kinds.add_parser("pothole", help="a rectangular or rounded pothole",
                               description="A pothole across the road.")
    pothole.add_argument("--depth", metavar="M", type=float, default=0.05,
                         help="pothole depth in m (default 0.05)")
    pothole.add_argument("--length", metavar="M", type=float, default=0.3,
                         help="pothole length along the road in m (default 0.3)")
    pothole.add_argument("--shape", choices=("rectangular", "rounded"),
                         default="rectangular", help="rectangular or rounded (default "
                         "rectangular)")
    _writer_options(pothole, OBSTACLE_SPACING_M)
    pothole.set_defaults(handler=run_pothole)

    triangle = kinds.add_parser("triangle", help="an SAE J2705 triangular cleat",
                                description=J2705)
    triangle.add_argument("--height", metavar="M", type=float, default=0.05,
                          help="height to the top of the crown in m (default 0.05)")
    triangle.add_argument("--half-angle", metavar="DEG", type=float, default=45.0,
                          help="apex half-angle in deg (J2705: 45, 60, 75, 80, 85; default "
                          "45)")
    triangle.add_argument("--crown-radius", metavar="M", type=float, default=0.002,
                          help="crown radius in m (J2705: 0.0015 to 0.003; default 0.002)")
    _writer_options(triangle, OBSTACLE_SPACING_M)
    triangle.set_defaults(handler=run_triangle)

    step = kinds.add_parser("step", help="an SAE J2705 step cleat", description=J2705)
    step.add_argument("--height", metavar="M", type=float, default=0.05,
                      help="step height in m (default 0.05)")
    step.add_argument("--crown-radius", metavar="M", type=float, default=0.002,
                      help="radius of the step's top edge in m (J2705: 0.0015 to 0.003; "
                      "default 0.002)")
    _writer_options(step, OBSTACLE_SPACING_M)
    step.set_defaults(handler=run_step)

    iso = kinds.add_parser(
        "iso8608", help="an ISO 8608 random road of a class A-H",
        description="A random road of an ISO 8608 class: displacement PSD Gd(n) = Gd(n0) "
        "(n / n0)^-2 with n0 = 0.1 cycles/m and the class's geometric-mean Gd(n0) (16e-6 m^3 "
        "for A, 4 times more per class), a sum of cosines with random phases (the vehicle "
        "demo's generator), the same heights across the road's width.")
    iso.add_argument("--class", dest="road_class", choices=tuple("ABCDEFGH"), default="C",
                     help="ISO 8608 road class (default C)")
    iso.add_argument("--length", metavar="M", type=float, default=100.0,
                     help="road length in m (default 100)")
    iso.add_argument("--seed", metavar="N", type=int, default=0,
                     help="random seed of the phases (default 0)")
    iso.add_argument("--fade-in", metavar="M", type=float, default=5.0,
                     help="the first metres rise from height 0 by a half-cosine (default 5)")
    iso.add_argument("--n-min", metavar="CYCLES_PER_M", type=float, default=0.011,
                     help="lowest spatial frequency in cycles/m (default ISO's 0.011)")
    iso.add_argument("--n-max", metavar="CYCLES_PER_M", type=float, default=2.83,
                     help="highest spatial frequency in cycles/m (default ISO's 2.83; higher "
                     "extrapolates the spectrum's slope)")
    _writer_options(iso, ISO_SPACING_M, lead=False)
    iso.set_defaults(handler=run_iso8608)

    show = kinds.add_parser(
        "show", help="read a road file: its extent and heights, the profile the tire reads",
        description="Read a road file (OpenCRG or profile) as the FMUs read it: the road "
        "along u at --lateral-offset, level at its end heights beyond its extent.")
    show.add_argument("file", metavar="FILE", type=Path, help="the road file")
    show.add_argument("--lateral-offset", metavar="M", type=float, default=0.0,
                      help="v of the track on an OpenCRG road in m, left positive (default 0)")
    add_output_options(show)
    show.set_defaults(handler=run_show)


def _writer_options(parser: argparse.ArgumentParser, spacing_m: float, lead: bool = True
                    ) -> None:
    parser.add_argument("--out", metavar="FILE", type=Path, required=True,
                        help="the file to write: FILE.crg an OpenCRG file, any other name a "
                        "profile (distance m, height m; .csv)")
    parser.add_argument("--format", choices=FORMATS, default="KDBI",
                        help="OpenCRG data format (default KDBI: binary, double precision)")
    parser.add_argument("--spacing", metavar="M", type=float, default=spacing_m,
                        help=f"distance between samples in m (default {spacing_m:g})")
    if lead:
        parser.add_argument("--lead-in", metavar="M", type=float, default=1.0,
                            help="level road before the obstacle in m (default 1)")
        parser.add_argument("--lead-out", metavar="M", type=float, default=1.0,
                            help="road after the obstacle in m (default 1)")
    parser.add_argument("--width", metavar="M", type=float, default=1.0,
                        help="an OpenCRG road's width in m: long sections at -W/2, 0 and W/2 "
                        "(default 1)")
    add_output_options(parser)


def _writer_problems(args) -> list[str | None]:
    problems = [range_problem("--spacing", args.spacing, 1e-5, 1.0, "m"),
                positive_problem("--width", args.width, "m", 100.0)]
    if hasattr(args, "lead_in"):
        problems += [range_problem("--lead-in", args.lead_in, 0.0, 1e4, "m"),
                     range_problem("--lead-out", args.lead_out, 0.0, 1e4, "m")]
    out = args.out
    if out.is_dir():
        problems.append(f"--out = {str(out)!r} is a folder: give a file name")
    else:
        try:
            check_parent_folder("--out", out)
        except CliError as error:
            problems.append(str(error))
    return problems


def _write(args, road, description: str, extra: dict) -> Output:
    from ..road_files import write_road

    comments = [f"{description}", "written by tire-fmu road (tire_fmu)"]
    with writing("--out", args.out):
        path = write_road(args.out, road, args.format, args.width, comments)
    return _report(road, path, description,
                   args.format if path.suffix.lower() == ".crg" else "profile", extra,
                   written=True)


def _report(road, path, description: str, data_format: str, extra: dict,
            written: bool = False) -> Output:
    import numpy as np

    first, last = road.extent_m
    heights = road.heights_m
    spacing = np.diff(road.distances_m)
    data = {"file": str(path), "format": data_format, "description": description,
            "points": int(heights.size), "extent_m": [first, last],
            "spacing_m": float(np.median(spacing)), "uniform": bool(np.ptp(spacing)
                                                                     <= 1e-9 * last),
            "height_min_m": float(heights.min()), "height_max_m": float(heights.max()),
            "beyond_extent": "level at the end heights", **extra}
    text = (f"{description}: {heights.size} points every {data['spacing_m']:g} m from "
            f"{first:g} to {last:g} m, heights {heights.min() * 1e3:.4g} to "
            f"{heights.max() * 1e3:.4g} mm ({data_format}); level at the end heights beyond.")
    output = Output(text=text, data=data)
    if written:
        output.written.append(Path(path))
    return output


def _finish(args, output: Output, road, title: str) -> Output:
    write_plot(args, output, plot_with("plot_road_profile", road, title))
    return output


def _obstacle(args, make, extra: dict) -> Output:
    from ..core.obstacles import sampled_obstacle

    shape = make()
    road = sampled_obstacle(shape, args.spacing, args.lead_in, args.lead_out)
    description = f"{shape.label}, after {args.lead_in:g} m of level road"
    output = _write(args, road, description, {"shape": extra})
    return _finish(args, output, road, description)


def run_cleat(args: argparse.Namespace) -> Output:
    from ..core.obstacles import Obstacle

    raise_problems([range_problem("--height", args.height, 1e-4, MAX_OBSTACLE_SIZE_M, "m"),
                    range_problem("--length", args.length, 1e-4, MAX_OBSTACLE_LENGTH_M, "m"),
                    *_writer_problems(args)])
    return _obstacle(args, lambda: Obstacle(args.height, args.length, args.shape),
                     {"kind": "cleat", "standard": "SAE J2730", "height_m": args.height,
                      "length_m": args.length, "form": args.shape})


def run_pothole(args: argparse.Namespace) -> Output:
    from ..core.obstacles import Obstacle

    raise_problems([range_problem("--depth", args.depth, 1e-4, MAX_OBSTACLE_SIZE_M, "m"),
                    range_problem("--length", args.length, 1e-4, MAX_OBSTACLE_LENGTH_M, "m"),
                    *_writer_problems(args)])
    return _obstacle(args, lambda: Obstacle(-args.depth, args.length, args.shape),
                     {"kind": "pothole", "depth_m": args.depth, "length_m": args.length,
                      "form": args.shape})


def run_triangle(args: argparse.Namespace) -> Output:
    from ..core.obstacles import TriangularCleat

    raise_problems([range_problem("--height", args.height, 1e-4, MAX_OBSTACLE_SIZE_M, "m"),
                    range_problem("--half-angle", args.half_angle, 10.0, 89.0, "deg",
                                  reason="SAE J2705: 45, 60, 75, 80, 85"),
                    range_problem("--crown-radius", args.crown_radius, 0.0,
                                  min(MAX_CROWN_RADIUS_M, 0.999 * args.height)
                                  if args.height == args.height and args.height > 0
                                  else MAX_CROWN_RADIUS_M, "m"),
                    *_writer_problems(args)])
    return _obstacle(args, lambda: TriangularCleat(args.height, args.half_angle,
                                                   args.crown_radius),
                     {"kind": "triangular cleat", "standard": "SAE J2705",
                      "height_m": args.height, "half_angle_deg": args.half_angle,
                      "crown_radius_m": args.crown_radius})


def run_step(args: argparse.Namespace) -> Output:
    from ..core.obstacles import StepCleat

    raise_problems([range_problem("--height", args.height, 1e-4, MAX_OBSTACLE_SIZE_M, "m"),
                    range_problem("--crown-radius", args.crown_radius, 0.0,
                                  min(MAX_CROWN_RADIUS_M, 0.999 * args.height)
                                  if args.height == args.height and args.height > 0
                                  else MAX_CROWN_RADIUS_M, "m"),
                    *_writer_problems(args)])
    return _obstacle(args, lambda: StepCleat(args.height, args.crown_radius),
                     {"kind": "step cleat", "standard": "SAE J2705", "height_m": args.height,
                      "crown_radius_m": args.crown_radius})


def run_iso8608(args: argparse.Namespace) -> Output:
    import numpy as np

    from ..core.iso8608 import iso8608_profile
    from ..core.obstacles import ProfileRoad

    raise_problems([range_problem("--length", args.length, 1.0, 1e5, "m"),
                    range_problem("--seed", args.seed, 0, 2**32 - 1, integer=True),
                    range_problem("--fade-in", args.fade_in, 0.0, args.length
                                  if args.length == args.length else 1e5, "m"),
                    range_problem("--n-min", args.n_min, 1e-4, 10.0, "cycles/m"),
                    range_problem("--n-max", args.n_max, 1e-3, 1e3, "cycles/m"),
                    None if args.n_max > args.n_min else
                    f"--n-max = {args.n_max:g} cycles/m: must be above --n-min = "
                    f"{args.n_min:g} cycles/m",
                    *_writer_problems(args)])
    samples = int(round(args.length / args.spacing))
    if samples + 1 > 10_000_000:
        raise CliError(f"--length = {args.length:g} m at --spacing = {args.spacing:g} m: "
                       f"{samples + 1} points, more than the 10000000 a road file holds")
    profile = iso8608_profile(args.road_class, samples, args.spacing, args.seed,
                              args.n_min, args.n_max, args.fade_in)
    road = ProfileRoad(args.spacing * np.arange(samples + 1), profile.heights_m,
                       f"ISO 8608 class {args.road_class}")
    description = (f"ISO 8608 class {args.road_class} road, {args.length:g} m (seed "
                   f"{args.seed}, {args.n_min:g}-{args.n_max:g} cycles/m, rising from 0 over "
                   f"{args.fade_in:g} m)")
    output = _write(args, road, description, {
        "road_class": args.road_class, "gd_n0_m3": profile.spectrum.gd_n0_m3,
        "n0_cycles_per_m": 0.1, "waviness": profile.spectrum.waviness, "seed": args.seed,
        "n_min_cycles_per_m": args.n_min, "n_max_cycles_per_m": args.n_max,
        "fade_in_m": args.fade_in, "rms_height_m": float(np.std(profile.heights_m))})
    return _finish(args, output, road, description)


def run_show(args: argparse.Namespace) -> Output:
    from ..road_files import read_road_file

    raise_problems([range_problem("--lateral-offset", args.lateral_offset, -1e4, 1e4, "m")])
    road_file = read_road_file(args.file, args.lateral_offset)
    extra = {"lateral_offset_m": road_file.lateral_offset_m,
             "height_shift_m": road_file.height_shift_m,
             "width_m": list(road_file.width_m) if road_file.width_m else None}
    description = (f"{args.file.name}" + (f" at v = {road_file.lateral_offset_m:g} m"
                                          if road_file.width_m else ""))
    output = _report(road_file.road, args.file, description, road_file.data_format, extra)
    return _finish(args, output, road_file.road, description)
