"""Build a native FMU: C sources from :mod:`.codegen`, the model description, a linux64 binary
compiled with the local C compiler, all packed into one ``.fmu``.

The FMU holds ``sources/`` (the generated C and the FMI 2.0 headers, copied from fmpy, a
maintained package, rather than typed by hand) listed in the model description's
``SourceFiles``, so a host on another platform can compile it: the folder builds on its own,
and the binary here is built from exactly that folder. The build fails unless
``fmpy.validation.validate_fmu`` reports no problem.
"""

from __future__ import annotations

import os
import platform
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import tire_fmu

from ..core.parameters import OperatingPoint
from ..core.reduction import ReducedModel
from ..fmu.interface import CAPABILITIES as SHARED_CAPABILITIES
from ..fmu.interface import unit_definitions
from .codegen import DEFAULT_MODEL_IDENTIFIER, NativeModel, generate_sources, native_model
from .runtime import RUNTIME_FILE

#: The FMI 2.0 headers the sources include.
FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
COMPILE_FLAGS = ("-shared", "-fPIC", "-O2", "-Wall", "-Wextra")
PLATFORM = "linux64"

#: What the C runtime really does (see tire_fmu/native/runtime.py).
CAPABILITIES = {
    "needsExecutionTool": False,
    "canInterpolateInputs": False,  # the velocity inputs carry the ramp instead
    "maxOutputDerivativeOrder": 0,
    "canRunAsynchronuously": False,  # FMI 2.0's own spelling
    "canBeInstantiatedOnlyOncePerProcess": False,  # no global mutable state
    "canNotUseMemoryManagementFunctions": False,  # allocates through the host's callbacks
    "providesDirectionalDerivative": False,
    **SHARED_CAPABILITIES,  # variable steps, state get/set and serialisation: as the Python FMU
}

LOG_CATEGORIES = {
    "logStatusWarning": "Messages with status fmi2Warning (loss of contact); always on unless "
                        "categories are chosen",
    "logStatusDiscard": "Messages with status fmi2Discard (a refused doStep)",
    "logStatusError": "Messages with status fmi2Error (a refused call)",
    "logAll": "All messages, including information when the FMU starts",
}


class NativeBuildError(RuntimeError):
    """The native FMU could not be built, or what was built does not validate."""


def build_native_fmu(reduced: ReducedModel, out: str | Path,
                     operating_point: OperatingPoint | None = None,
                     model_identifier: str = DEFAULT_MODEL_IDENTIFIER,
                     binary: bool = True, validate: bool = True) -> Path:
    """Write the native FMU of ``reduced`` to ``out`` (a ``.fmu`` path, or a folder to hold
    ``<model_identifier>.fmu``) and return its path.

    ``operating_point`` supplies the requested load for the ``load`` parameter (see
    :func:`~tire_fmu.native.codegen.export_parameters`). ``binary=False`` leaves out the
    linux64 binary: a sources-only FMU for a host that compiles it. ``validate`` runs fmpy's
    validation and raises :class:`NativeBuildError` listing any problem.
    """
    try:
        native = native_model(reduced, operating_point, model_identifier)
    except ValueError as error:
        raise NativeBuildError(str(error)) from error
    out = Path(out)
    if out.is_dir():
        out = out / f"{native.model_identifier}.fmu"
    if not out.parent.is_dir():
        raise NativeBuildError(f"{out}: folder {out.parent} does not exist")
    with tempfile.TemporaryDirectory(prefix="tire_fmu_native_") as staging:
        staging = Path(staging)
        write_sources(native, staging / "sources")
        if binary:
            compile_sources(staging / "sources", native.model_identifier,
                            staging / "binaries" / PLATFORM)
        (staging / "modelDescription.xml").write_bytes(model_description(native))
        pack(staging, out)
    if validate:
        problems = validation_problems(out)
        if problems:
            raise NativeBuildError(f"{out} does not validate: " + "; ".join(problems))
    return out


def write_sources(native: NativeModel, folder: Path) -> list[Path]:
    """The generated C and the FMI headers, a folder that compiles on its own."""
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, text in generate_sources(native).items():
        path = folder / name
        path.write_text(text, encoding="utf-8")
        written.append(path)
    headers = fmi_header_folder()
    for name in FMI_HEADERS:
        written.append(Path(shutil.copyfile(headers / name, folder / name)))
    return written


def fmi_header_folder() -> Path:
    """fmpy's copy of the FMI 2.0 headers."""
    try:
        import fmpy
    except ImportError as error:
        raise NativeBuildError("the FMI 2.0 headers come from fmpy: pip install fmpy") from error
    folder = Path(fmpy.__file__).parent / "c-code"
    missing = [name for name in FMI_HEADERS if not (folder / name).is_file()]
    if missing:
        raise NativeBuildError(f"fmpy {fmpy.__version__} at {folder} lacks {missing}")
    return folder


def find_compiler() -> list[str]:
    """$CC (a command, perhaps with flags) when set, else gcc, else cc."""
    chosen = os.environ.get("CC", "").split()
    if chosen:
        if shutil.which(chosen[0]) is None:
            raise NativeBuildError(f"CC = {os.environ['CC']!r}: {chosen[0]} not found")
        return chosen
    for candidate in ("gcc", "cc"):
        if shutil.which(candidate):
            return [candidate]
    raise NativeBuildError("no C compiler found (set CC, or install gcc); or build a "
                           "sources-only FMU with binary=False")


def compile_sources(sources: Path, model_identifier: str, target_folder: Path,
                    extra_flags: tuple[str, ...] = ()) -> Path:
    """Compile ``sources`` (include path: that folder only, which proves it stands alone)
    into ``target_folder/<model_identifier>.so``."""
    if not (sys.platform.startswith("linux") and platform.machine() in ("x86_64", "AMD64")):
        raise NativeBuildError(f"binaries are built for {PLATFORM} only, and this is "
                               f"{sys.platform}/{platform.machine()}; build a sources-only FMU "
                               "with binary=False and let the host compile it")
    target_folder.mkdir(parents=True, exist_ok=True)
    library = target_folder / f"{model_identifier}.so"
    command = [*find_compiler(), *COMPILE_FLAGS, *extra_flags, "-I", str(sources),
               "-o", str(library), str(sources / RUNTIME_FILE), "-lm"]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise NativeBuildError(f"compiling the FMU failed ({' '.join(command)}):\n"
                               + result.stderr.strip())
    return library


def pack(folder: Path, fmu: Path) -> None:
    """Zip the FMU's folder, the model description first; written beside and moved into
    place, so a failed build never leaves a half-written FMU."""
    partial = fmu.with_name(fmu.name + ".partial")
    files = sorted(p for p in folder.rglob("*") if p.is_file())
    files.sort(key=lambda p: p.name != "modelDescription.xml")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in files:
            archive.write(path, path.relative_to(folder).as_posix())
    partial.replace(fmu)


# -- the model description ----------------------------------------------------------------

def _xml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    return repr(float(value))


def model_description(native: NativeModel) -> bytes:
    """``modelDescription.xml`` from the same variable table as the C code."""
    root = ElementTree.Element("fmiModelDescription", {
        "fmiVersion": "2.0",
        "modelName": native.model_identifier,
        "guid": native.guid,
        "description": native.description,
        "author": "tire_fmu contributors",
        "version": tire_fmu.__version__,
        "license": "MIT",
        "generationTool": f"tire_fmu {tire_fmu.__version__} (tire_fmu.native)",
        "variableNamingConvention": "structured",
        "numberOfEventIndicators": "0",
    })
    co_simulation = ElementTree.SubElement(root, "CoSimulation", {
        "modelIdentifier": native.model_identifier,
        **{name: _xml_value(value) for name, value in CAPABILITIES.items()},
    })
    sources = ElementTree.SubElement(co_simulation, "SourceFiles")
    ElementTree.SubElement(sources, "File", name=RUNTIME_FILE)

    root.append(unit_definitions(v.unit for v in native.variables if v.unit))
    categories = ElementTree.SubElement(root, "LogCategories")
    for name, description in LOG_CATEGORIES.items():
        ElementTree.SubElement(categories, "Category", name=name, description=description)
    ElementTree.SubElement(root, "DefaultExperiment", startTime="0.0", stopTime="1.0",
                           stepSize="0.0001")
    annotations = ElementTree.SubElement(root, "VendorAnnotations")
    tool = ElementTree.SubElement(annotations, "Tool", name="tire_fmu")
    ElementTree.SubElement(tool, "ReducedModel", _export_record(native))

    variables = ElementTree.SubElement(root, "ModelVariables")
    for vr, v in enumerate(native.variables):
        attributes = {"name": v.name, "valueReference": str(vr), "description": v.description,
                      "causality": v.causality, "variability": v.variability}
        if v.causality == "parameter":
            attributes["initial"] = "exact"
        elif v.causality == "output":
            attributes["initial"] = "calculated"
        element = ElementTree.SubElement(variables, "ScalarVariable", attributes)
        typed = ElementTree.SubElement(element, v.type)
        if v.causality != "output":  # outputs are calculated: no start value
            typed.set("start", _xml_value(v.start))
        if v.unit:
            typed.set("unit", v.unit)

    structure = ElementTree.SubElement(root, "ModelStructure")
    outputs = [i for i, v in enumerate(native.variables, 1) if v.causality == "output"]
    for tag in ("Outputs", "InitialUnknowns"):  # every output is calculated
        group = ElementTree.SubElement(structure, tag)
        for index in outputs:
            ElementTree.SubElement(group, "Unknown", index=str(index))
    ElementTree.indent(root, space="  ")
    return ElementTree.tostring(root, encoding="UTF-8", xml_declaration=True)


def _export_record(native: NativeModel) -> dict[str, str]:
    """The reduction settings and the model's size, machine-readable, for the annotations."""
    r = native.reduced
    s = r.settings
    op = r.metadata.operating_point
    record = {
        "method": s.method,
        "contribution_threshold": repr(s.contribution_threshold),
        "f_max_hz": "none" if s.f_max_hz is None else repr(float(s.f_max_hz)),
        "n_modes_limit": "none" if s.n_modes is None else str(s.n_modes),
        "static_correction": _xml_value(s.static_correction),
        "n_states_requested": "none" if s.n_states is None else str(s.n_states),
        "target_error": repr(s.target_error),
        "error_band_hz": f"{s.error_band_hz[0]!r} {s.error_band_hz[1]!r}",
        "modes": str(r.n_modes),
        "states": str(r.n_states),
        "road_delay_groups": str(r.n_inputs - 1),
        "road_delays_s": " ".join(repr(float(t)) for t in r.input_delays_s[1:]),
        "patch_length_m": repr(float(op.patch_length_m)),
        "patch_load_n": repr(float(op.load_n)),
        "critical_speed_m_s": repr(float(op.critical_speed_m_s)),
    }
    if r.report is not None:
        record["max_relative_frf_error"] = repr(float(r.report.max_relative_error))
    return record


def validation_problems(fmu: str | Path) -> list[str]:
    """fmpy's validation of the FMU."""
    try:
        from fmpy.validation import validate_fmu
    except ImportError as error:
        raise NativeBuildError("validating the FMU needs fmpy: pip install fmpy") from error
    return list(validate_fmu(str(fmu)))
