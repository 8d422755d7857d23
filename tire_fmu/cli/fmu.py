"""FMU command: build-fmu (TireModal.fmu with the core inside, validated by fmpy)."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import CliError, Output, add_output_options, output_file


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "build-fmu",
        help="build TireModal.fmu, the FMI 2.0 co-simulation FMU",
        description="Build TireModal.fmu (pythonfmu) as OUT (a .fmu file, or an existing "
        "folder to hold TireModal.fmu): the tire_fmu core ships inside, "
        "the model description is completed (units, initial unknowns, capability flags) and "
        "checked with fmpy's validator when fmpy is installed. A host needs Python with numpy "
        "and scipy (pythonfmu embeds the host's Python).",
    )
    p.add_argument("out", metavar="OUT", type=Path,
                   help="file to write (ending in .fmu), or an existing folder for TireModal.fmu")
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_build_fmu)


def run_build_fmu(args: argparse.Namespace) -> Output:
    from ..fmu.builder import MODEL_IDENTIFIER, FmuBuildError, build_fmu

    out = output_file("OUT", args.out, ".fmu", f"{MODEL_IDENTIFIER}.fmu")
    try:
        path = build_fmu(out)
    except FmuBuildError as error:
        raise CliError(str(error)) from error
    validated = _fmpy_installed()  # build_fmu validated, and raised on any problem
    data = {"path": path, "size_bytes": path.stat().st_size, "validated_with_fmpy": validated}
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
