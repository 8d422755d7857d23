"""FMU command: build-fmu (TireModal.fmu with the core inside, validated by fmpy)."""

from __future__ import annotations

import argparse
from pathlib import Path

from .commands import command_help
from .common import (
    CliError,
    Output,
    add_output_options,
    add_tire_options,
    checked_tire,
    make_folder,
    output_file,
    writing,
)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "build-fmu",
        help=command_help("build-fmu"),
        description="Build TireModal.fmu (pythonfmu) as OUT (a .fmu file, or a folder, "
        "created if missing, to hold TireModal.fmu): the tire_fmu core ships inside, "
        "the model description is completed (units, initial unknowns, capability flags) and "
        "checked with fmpy's validator when fmpy is installed. The tire parameters start from "
        "--tire-file / --tire (default GL073A). A host needs Python with numpy and scipy "
        "(pythonfmu embeds the host's Python).",
    )
    p.add_argument("out", metavar="OUT", type=Path,
                   help="file to write (ending in .fmu), or a folder for TireModal.fmu (a name "
                   "without an extension: created if missing)")
    add_tire_options(p)  # the tire the FMU's parameters start from
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_build_fmu)


def run_build_fmu(args: argparse.Namespace) -> Output:
    from ..fmu.builder import MODEL_IDENTIFIER, FmuBuildError, build_fmu

    out = output_file("OUT", args.out, ".fmu", f"{MODEL_IDENTIFIER}.fmu")
    tire = checked_tire(args)
    make_folder("OUT", out)
    try:
        with writing("OUT", out):
            path = build_fmu(out, tire=tire)
    except FmuBuildError as error:
        raise CliError(str(error)) from error
    validated = _fmpy_installed()  # build_fmu validated, and raised on any problem
    data = {"path": path, "size_bytes": path.stat().st_size, "validated_with_fmpy": validated,
            "tire": tire.as_dict()}
    check = "fmpy validate: no problems" if validated else "not validated (fmpy not installed)"
    output = Output(text=f"{path} ({data['size_bytes'] / 1e3:.0f} kB; {check})", data=data)
    output.written.append(path)
    return output


def _fmpy_installed() -> bool:
    try:
        import fmpy.validation  # noqa: F401
    except ImportError:
        return False
    return True
