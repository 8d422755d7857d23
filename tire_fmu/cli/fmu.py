"""FMU command: build-fmu (TireModal.fmu with the core inside, validated by fmpy)."""

from __future__ import annotations

import argparse
from pathlib import Path

from .commands import command_help
from .common import CliError, Output, add_output_options


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "build-fmu",
        help=command_help("build-fmu"),
        description="Build TireModal.fmu (pythonfmu) into OUT: the tire_fmu core ships inside, "
        "the model description is completed (units, initial unknowns, capability flags) and "
        "checked with fmpy's validator when fmpy is installed. A host needs Python with numpy "
        "and scipy (pythonfmu embeds the host's Python).",
    )
    p.add_argument("out", metavar="OUT", type=Path, help="folder to write TireModal.fmu into")
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_build_fmu)


def run_build_fmu(args: argparse.Namespace) -> Output:
    from ..fmu.builder import FmuBuildError, build_fmu

    try:
        path = build_fmu(args.out)
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
