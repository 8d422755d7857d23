"""FMU command: build-fmu (TireModal.fmu, or with --inplane TireInPlane.fmu, with the core
inside, or with --inplane --native TireInPlaneNative.fmu, in C; validated by fmpy)."""

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
    output_path,
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
    p.add_argument("out", metavar="OUT", type=output_path,
                   help="file to write (ending in .fmu), or a folder for TireModal.fmu (a name "
                   "without an extension: created if missing)")
    add_tire_options(p)  # the tire the FMU's parameters start from
    p.add_argument("--inplane", action="store_true",
                   help="build TireInPlane.fmu instead: the in-plane tire (tangential tread "
                   "motion, the wheel's rotation, friction in the footprint) with inputs "
                   "rim_x, rim_vx and wheel_torque besides the radial FMU's and outputs "
                   "rim_Fx, rim_My and wheel_spin; its tire data default to the tire file "
                   "GL073A_inplane")
    p.add_argument("--tangential", metavar="NAME=VALUE", action="append", default=[],
                   help="with --inplane: override a tangential parameter of the tire file "
                   "(repeatable), as tire-fmu inplane-modes takes them")
    p.add_argument("--native", action="store_true",
                   help="with --inplane: build TireInPlaneNative.fmu, the same variables and "
                   "numbers in C (compiled here; its sources inside), which needs no Python "
                   "on the host (the radial native FMU: tire-fmu export --format fmu)")
    p.add_argument("--platform", action="append", choices=("linux64", "win64"), default=None,
                   help="with --native: binaries to include (repeatable; default: linux64 and "
                   "win64 when x86_64-w64-mingw32-gcc is installed)")
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_build_fmu)


def run_build_fmu(args: argparse.Namespace) -> Output:
    from ..fmu.builder import (
        INPLANE_MODEL_IDENTIFIER,
        MODEL_IDENTIFIER,
        FmuBuildError,
        build_fmu,
        build_inplane_fmu,
    )

    if args.tangential and not args.inplane:
        raise CliError("--tangential: only with --inplane (the radial FMU has no tangential "
                       "data)")
    if args.native and not args.inplane:
        raise CliError("--native: only with --inplane (the radial native FMU is built by "
                       "tire-fmu export OUT.fmu --format fmu)")
    if args.platform and not args.native:
        raise CliError("--platform: only with --native (the Python FMUs' binaries are "
                       "pythonfmu's)")
    identifier = INPLANE_MODEL_IDENTIFIER if args.inplane else MODEL_IDENTIFIER
    if args.native:
        from ..native.builder import INPLANE_MODEL_IDENTIFIER as identifier
        from .reduce import _check_native_tools

        _check_native_tools()
    out = output_file("OUT", args.out, ".fmu", f"{identifier}.fmu")
    if args.inplane:
        from ..core.inplane import InPlaneTire
        from .inplane import DEFAULT_TIRE_FILE, _tangential

        if args.tire_file is None:
            args.tire_file = DEFAULT_TIRE_FILE
        model = InPlaneTire(checked_tire(args), _tangential(args.tangential, args.tire_file))
        tire_data = {**model.tire.as_dict(), **model.tangential.as_dict()}
    else:
        tire = checked_tire(args)
        tire_data = tire.as_dict()
    make_folder("OUT", out)
    if args.native:
        return _build_native_inplane(args, out, model, tire_data)
    try:
        with writing("OUT", out):
            path = (build_inplane_fmu(out, tire=model) if args.inplane
                    else build_fmu(out, tire=tire))
    except FmuBuildError as error:
        raise CliError(str(error)) from error
    validated = _fmpy_installed()  # the build validated, and raised on any problem
    data = {"path": path, "size_bytes": path.stat().st_size, "validated_with_fmpy": validated,
            "tire": tire_data}
    check = "fmpy validate: no problems" if validated else "not validated (fmpy not installed)"
    output = Output(text=f"{path} ({data['size_bytes'] / 1e3:.0f} kB; {check})", data=data)
    output.written.append(path)
    return output


def _build_native_inplane(args: argparse.Namespace, out: Path, model, tire_data: dict
                          ) -> Output:
    import zipfile

    from ..native.builder import NativeBuildError, build_native_inplane_fmu

    platforms = tuple(args.platform) if args.platform else None
    try:
        with writing("OUT", out):
            path = build_native_inplane_fmu(out, platforms=platforms, tire=model)
    except NativeBuildError as error:
        raise CliError(f"OUT = {str(out)!r}: {_first_line(error)}") from error
    binaries = sorted(n.split("/")[1] for n in zipfile.ZipFile(path).namelist()
                      if n.startswith("binaries/") and n.count("/") == 2)
    data = {"path": path, "size_bytes": path.stat().st_size, "validated_with_fmpy": True,
            "binaries": binaries, "tire": tire_data}
    output = Output(text=f"{path} ({data['size_bytes'] / 1e3:.0f} kB; native, binaries: "
                    f"{', '.join(binaries) or 'none, sources only'}; fmpy validate: no "
                    "problems)", data=data)
    output.written.append(path)
    return output


def _first_line(error: Exception) -> str:
    # a compiler's output follows the first line: an error stays one line
    return str(error).splitlines()[0] if str(error) else type(error).__name__


def _fmpy_installed() -> bool:
    try:
        import fmpy.validation  # noqa: F401
    except ImportError:
        return False
    return True
