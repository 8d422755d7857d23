"""Reduced-order model commands: frf (Bode, full and reduced), reduce (the report), export."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..core.frequency_response import full_frequency_response, reduced_frequency_response
from ..core.io_model import OUTPUTS as OUTPUT_NAMES
from ..core.parameters import DEFAULT_LOAD_N, ParameterError
from ..core.reduction import ReductionSettings, reduce
from .commands import command_help
from .common import (
    CLI_NAMES,
    CLI_UNSET,
    CliError,
    Output,
    add_contact_options,
    add_mesh_option,
    add_output_options,
    add_speed_options,
    add_tire_options,
    checked_together,
    frequency_grid,
    make_folder,
    model_from_args,
    operating_point_values,
    output_file,
    output_path,
    parse_tire_overrides,
    plot_with,
    raise_problems,
    response_table,
    table,
    validated_args,
    write_plot,
    writing,
)


def output_name(text: str) -> str:
    """An output by its FMU name (rim_Fz, ...), whatever the letter case."""
    by_lower = {name.lower(): name for name in OUTPUT_NAMES}
    return by_lower.get(text.lower(), text)  # argparse's choices then reject the rest

_DEFAULTS = ReductionSettings()
#: npz and mat: the reduced model as data; fmu: compiled into a native FMU (tire_fmu.native)
EXPORT_FORMATS = ("npz", "mat", "fmu")


def add_reduction_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("reduction settings")
    g.add_argument("--method", choices=("modal", "balanced"), default=_DEFAULTS.method,
                   help="modal truncation (default) or balanced truncation")
    g.add_argument("--f-max", metavar="HZ", type=float, default=None,
                   help="keep only modes with natural frequency up to this, Hz; the rest "
                   "enter statically (default: no cut, the error target decides)")
    g.add_argument("--target-error", metavar="X", type=float, default=_DEFAULTS.target_error,
                   help="largest relative FRF error allowed over the band: modal keeps the "
                   "fewest modes it finds that meet it, balanced the fewest states "
                   f"(default {_DEFAULTS.target_error:g})")
    g.add_argument("--n-modes", metavar="K", type=int, default=None,
                   help="modal: keep at most K modes (complex pairs), the most dominant first")
    g.add_argument("--no-static-correction", action="store_true",
                   help="do not add the dropped modes' static response (DC gain then inexact)")
    g.add_argument("--n-states", metavar="K", type=int, default=None,
                   help="balanced: states to keep (default: fewest meeting --target-error)")
    # the former modal budget, refused with what to give instead
    g.add_argument("--threshold", metavar="X", type=float, default=None,
                   help=argparse.SUPPRESS)
    g.add_argument("--band", metavar="LOW,HIGH", default="1,300",
                   help="band of the error report in Hz (default 1,300)")


def _band(text: str) -> tuple[float, float]:
    try:
        low, high = (float(v) for v in text.split(","))
    except ValueError as error:
        raise CliError(f"--band = {text!r}: expected LOW,HIGH in Hz, e.g. 1,300") from error
    return low, high


def settings_from_args(args: argparse.Namespace) -> ReductionSettings:
    """Reduction settings from the options; every problem is reported at once."""
    problems = []
    if args.threshold is not None:
        problems.append(f"--threshold = {args.threshold:g}: replaced by --target-error, the "
                        "largest relative FRF error allowed over the band, which modal "
                        "truncation now meets exactly as balanced truncation does: give "
                        f"--target-error {args.threshold:g}")
    settings = None
    try:
        band = _band(args.band)
    except CliError as error:
        problems.append(str(error))
        band = _DEFAULTS.error_band_hz
    try:
        settings = ReductionSettings(
            method=args.method,
            f_max_hz=args.f_max,
            n_modes=args.n_modes,
            static_correction=not args.no_static_correction,
            n_states=args.n_states,
            target_error=args.target_error,
            error_band_hz=band,
        )
    except ParameterError as error:
        problems += error.render(CLI_NAMES, CLI_UNSET)
    raise_problems(problems)
    return settings


def _add_model_options(p: argparse.ArgumentParser) -> None:
    add_mesh_option(p)
    add_contact_options(p, DEFAULT_LOAD_N)  # the road reaches the tire through its footprint
    add_speed_options(p)
    add_tire_options(p)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "frf",
        help=command_help("frf"),
        description="Frequency response from rim displacement or road height (at the front "
        "of the contact zone, the fixed stretch of road centred on the contact centre that "
        "the tread may meet, as the FMU's road_z) to a force or the deflection. With --reduced "
        "the reduced model built with the reduction settings is overlaid, with its relative "
        "error.",
    )
    p.add_argument("--input", choices=("road", "rim"), default="road",
                   help="excitation: road height or rim displacement (default road)")
    p.add_argument("--output", type=output_name, choices=OUTPUT_NAMES, default="rim_Fz",
                   help="response, named as the FMU's outputs (any letter case; default rim_Fz, "
                   "the force on the rim)")
    p.add_argument("--reduced", action="store_true", help="overlay the reduced model")
    p.add_argument("--min-frequency", metavar="HZ", type=float, default=0.5,
                   help="lowest frequency of the response in Hz (default 0.5)")
    p.add_argument("--max-frequency", metavar="HZ", type=float, default=300.0,
                   help="highest frequency of the response in Hz (default 300; the reduction's "
                   "mode cut is --f-max)")
    p.add_argument("--points", metavar="K", type=int, default=600,
                   help="frequencies, log-spaced (default 600)")
    _add_model_options(p)
    add_reduction_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_frf)

    p = subparsers.add_parser(
        "reduce",
        help=command_help("reduce"),
        description="Reduce the tire at its operating point and report the states kept, the "
        "settings and the maximum relative FRF error against the full model over the band.",
    )
    _add_model_options(p)
    add_reduction_options(p)
    p.add_argument("--exact-report", action="store_true",
                   help="check the reduced model against the assembled full model solved at "
                   "every frequency (slower) instead of the full model's modal decomposition")
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_reduce)

    p = subparsers.add_parser(
        "export",
        help=command_help("export"),
        description="Export the reduced model. npz: diagonal modal form, JSON metadata, "
        "checksums (load with tire_fmu.model_files.load_npz). mat: real A, B, C, D for "
        "ss(A, B, C, D), inputs [r; dr/dt]. fmu: the native FMI 2.0 co-simulation FMU in C "
        "(linux64 and win64 binaries and its sources), which needs no Python on the host and "
        "builds its model at initialisation; the options become its parameters' start values "
        "(docs/native.md).",
    )
    p.add_argument("out", metavar="OUT", type=output_path,
                   help="file to write (.npz, .mat or .fmu; with --format fmu also a folder "
                   "to hold TireModalNative.fmu, created if missing)")
    p.add_argument("--format", choices=EXPORT_FORMATS, default=None,
                   help="file format (default: from the extension of OUT)")
    _add_model_options(p)
    add_reduction_options(p)
    g = p.add_argument_group("native FMU (--format fmu)",
                             "The FMU builds its model at initialisation from its parameters: "
                             "the options above only become their start values (--f-max, "
                             "--n-modes and --no-static-correction as the FMU's truncation; the "
                             "other reduction settings do not apply).")
    g.add_argument("--zone-length", metavar="M", type=float, default=None,
                   help="contact_zone_length: road length under the tread nodes that may meet "
                   "it (default 0.6)")
    g.add_argument("--linear-contact", action="store_true",
                   help="linear_contact: two-sided springs on the static footprint")
    g.add_argument("--platform", action="append", choices=("linux64", "win64"), default=None,
                   help="binaries to include (repeatable; default: linux64 and win64 when "
                   "x86_64-w64-mingw32-gcc is installed)")
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_export)


def run_frf(args: argparse.Namespace) -> Output:
    freqs, settings, checked = checked_together(
        lambda: frequency_grid(args), lambda: settings_from_args(args),
        lambda: validated_args(args, undeformed_default=False))
    low, high = freqs[0], freqs[-1]
    model = model_from_args(args, checked=checked)
    output_name = args.output
    responses = [full_frequency_response(model, args.input, output_name, freqs)]
    reduced = None
    if args.reduced:
        reduced = reduce(model, settings)
        responses.append(reduced_frequency_response(reduced, args.input, output_name, freqs))
    data = {**model.summary(), "responses": [r.to_dict() for r in responses]}
    text = response_table(responses)
    if reduced is not None:
        error = float(responses[1].relative_error_to(responses[0]).max())
        data["max_relative_error"] = error
        data["reduction"] = reduced.summary()
        text += f"\nmax relative error {error:.3g} over {low:g}-{high:g} Hz"
    output = Output(text=text, data=data)
    title = (f"{args.input} -> {output_name}: N = {model.n_elements}, patch "
             f"{model.patch.length_m * 100:.3g} cm, load {model.patch.load_n / 1e3:.3g} kN, "
             f"speed {model.speed_m_s:g} m/s")
    write_plot(args, output, plot_with("plot_bode", responses, title=title))
    return output


def _report_text(reduced, model) -> str:
    report = reduced.report
    lines = [
        f"method {reduced.settings.method}: {reduced.n_states} states "
        f"({reduced.n_modes} modes) of {4 * model.n_elements}, "
        f"{reduced.n_inputs} inputs (rim + {reduced.n_inputs - 1} road delay groups)",
        f"built in {reduced.metadata.build_seconds:.2f} s",
        f"max relative FRF error over {report.band_hz[0]:g}-{report.band_hz[1]:g} Hz: "
        f"{report.max_relative_error:.3g} (full model from its {report.reference} "
        f"{'solves' if report.reference == 'exact' else 'decomposition'})",
    ]
    rows = [[pair, err] for pair, err in report.per_pair.items()]
    return "\n".join(lines) + "\n" + table(rows, ["input->output", "max rel. error"])


def run_reduce(args: argparse.Namespace) -> Output:
    settings, checked = checked_together(
        lambda: settings_from_args(args), lambda: validated_args(args, undeformed_default=False))
    model = model_from_args(args, checked=checked)
    reduced = reduce(model, settings, report="exact" if args.exact_report else True)
    return Output(text=_report_text(reduced, model), data=reduced.summary())


def run_export(args: argparse.Namespace) -> Output:
    from ..model_files import save_mat, save_npz

    fmt = args.format or args.out.suffix.lstrip(".").lower()
    if fmt not in EXPORT_FORMATS:
        raise CliError(f"--format = {fmt!r}: must be npz, mat or fmu (or give OUT a .npz, .mat "
                       "or .fmu extension)")
    if fmt == "fmu":
        from ..native import DEFAULT_MODEL_IDENTIFIER

        out = output_file("OUT", args.out, ".fmu", f"{DEFAULT_MODEL_IDENTIFIER}.fmu")
        _check_native_tools()
        return _export_native_fmu(args, out)
    out = output_file("OUT", args.out, f".{fmt}")
    if args.zone_length is not None or args.linear_contact or args.platform:
        raise CliError("--zone-length, --linear-contact and --platform apply to --format fmu")
    settings, checked = checked_together(
        lambda: settings_from_args(args), lambda: validated_args(args, undeformed_default=False))
    model = model_from_args(args, checked=checked)
    reduced = reduce(model, settings)
    with writing("OUT", out):
        path = (save_npz if fmt == "npz" else save_mat)(reduced, out)
    output = Output(text=_report_text(reduced, model), data={**reduced.summary(),
                                                             "file": str(path)})
    output.written.append(path)
    return output


def _check_native_tools() -> None:
    """The native export takes the FMI headers and the validator from fmpy: say so before the
    model is built, naming the extra that brings it."""
    try:
        import fmpy  # noqa: F401
    except ImportError as error:
        raise CliError("exporting a native FMU needs fmpy (the FMI 2.0 headers and the "
                       "validator): pip install 'tire_fmu[fmu]'") from error


def _export_native_fmu(args: argparse.Namespace, out: Path) -> Output:
    """The native FMU with the options as its parameters' start values. The core builds the
    model once here, so that values it cannot run fail now, with its messages."""
    from ..core.contact_dynamics import ContactSettings, build_contact_model
    from ..core.free_ring import RingTruncation
    from ..core.parameters import validate
    from ..native import NativeBuildError, build_native_fmu

    if args.patch_length is not None:
        raise CliError("--patch-length: the native FMU computes its footprint from the load; "
                       "give --load")
    op_values = operating_point_values(args, undeformed_default=False)
    if args.zone_length is not None:
        op_values["contact_zone_length_m"] = args.zone_length
    tire, op = validate(parse_tire_overrides(args), op_values)
    truncation = RingTruncation(f_max_hz=args.f_max, n_modes=args.n_modes,
                                static_correction=not args.no_static_correction)
    law = "linear" if args.linear_contact else "unilateral"
    contact = build_contact_model(tire, op, truncation, ContactSettings(law=law))
    start_values = {**tire.as_dict(), "load": op.requested_load_n, "speed": op.speed_m_s,
                    "n_elements": op.n_elements, "f_max": args.f_max or 0.0,
                    "n_modes": args.n_modes or 0,
                    "static_correction": not args.no_static_correction,
                    "allow_supercritical": op.allow_supercritical,
                    "contact_zone_length": op.contact_zone_length_m,
                    "linear_contact": args.linear_contact}
    platforms = tuple(args.platform) if args.platform else None
    make_folder("OUT", out)
    try:
        with writing("OUT", out):
            path = build_native_fmu(out, start_values, platforms=platforms)
    except NativeBuildError as error:
        raise CliError(f"OUT = {str(out)!r}: {error}") from error
    import zipfile

    binaries = sorted(n.split("/")[1] for n in zipfile.ZipFile(path).namelist()
                      if n.startswith("binaries/") and n.count("/") == 2)
    summary = contact.summary()
    data = {"file": str(path), "binaries": binaries,
            "start_values": start_values, "model_at_start_values": summary}
    # the path itself is reported once, on stderr, with the other commands' files
    text = (f"native FMU, binaries: {', '.join(binaries) or 'none, sources only'}; at its "
            f"start values it builds {summary['ring_modes']} of "
            f"{summary['ring_modes_total']} ring modes, a {summary['patch_length_m'] * 100:.3g} "
            f"cm footprint at {summary['load_n']:.6g} N")
    output = Output(text=text, data=data)
    output.written.append(path)
    return output
