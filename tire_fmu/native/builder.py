"""Build the native FMUs: the C of ``tire_fmu/native/c`` (package data), the generated headers,
the model description, linux64 and win64 binaries, all in one ``.fmu``.

Two kinds share this path and the generic FMI layer (``fmi2_layer.c``); a :class:`NativeKind`
says what differs: the model's C files, its variable table and its description.
``TireModalNative`` (:data:`RADIAL`) is the radial ring of TireModal.fmu;
``TireInPlaneNative`` (:data:`INPLANE`) the in-plane ring of TireInPlane.fmu, with exactly its
variables.

The C builds the model itself at ``fmi2ExitInitializationMode`` from its parameters, so an
export only chooses the parameters' start values (an operating point, a tire); every parameter
stays settable before initialisation. What the C and the Python FMU must agree on comes from
:mod:`tire_fmu.fmu.spec`, written into ``spec.h`` here; the export's own values (identifier,
GUID, start values) go into ``export.h``. ``sources/`` holds everything a host needs to compile
the FMU elsewhere: the C files, the headers, and ``buildDescription.xml`` (also listed as
``SourceFiles`` in the model description), so ``fmpy.build.build_platform_binary`` or a plain
``cc -shared sources/*.c -lm`` makes a binary.
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import uuid
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from xml.etree import ElementTree

import tire_fmu

from ..fmu.interface import CAPABILITIES as SHARED_CAPABILITIES
from ..fmu.interface import (
    FmuVariable,
    fmu_variables,
    inplane_fmu_variables,
    model_structure,
    output_dependencies,
    unit_definitions,
)
from ..fmu.spec import LOG_CATEGORIES, c_header
from ..publish import published_file

FMI_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")
GENERATED = ("spec.h", "export.h")
C_STANDARD = "C99"
WARNING_FLAGS = ("-Wall", "-Wextra")

_GUID_NAMESPACE = uuid.UUID("6f1c3a52-5d1e-4f57-9a53-2b1e0c7d9e41")

#: What the C really does.
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


class NativeBuildError(RuntimeError):
    """The native FMU could not be built, or what was built does not validate."""


@dataclass(frozen=True)
class NativeKind:
    """What one native FMU is: its C (the generic layer and a model behind model.h), its
    variable table (start values by parameter name -> the table) and its description."""

    name: str
    model_identifier: str  # the default one
    c_sources: tuple[str, ...]  # in compile order
    c_headers: tuple[str, ...]  # the headers they include, but the generated ones
    variables: Callable[[dict | None], tuple[FmuVariable, ...]]
    description: str


RADIAL = NativeKind(
    "radial", "TireModalNative",
    ("fmi2_layer.c", "tire_model.c", "model_problems.c", "ring.c", "contact.c",
     "contract_pack.c", "road.c", "kernel.c", "memory.c", "numerics.c", "road_file.c",
     "road_samples.c"),
    ("model.h", "model_problems.h", "tire.h", "numerics.h", "contract.h", "contract_pack.h",
     "kernel.h", "road_file.h", "road_samples.h", *FMI_HEADERS),
    lambda start_values: fmu_variables(parameter_values=start_values),
    "Open in-plane ring tire (0-300 Hz), native C: builds its free-ring modal model and "
    "static footprint for the parameters at initialisation, then steps with the unilateral "
    "contact; inputs are deviations from static equilibrium, forces are totals. Needs no "
    "Python.")

def _inplane_table(start_values: dict | None) -> tuple[FmuVariable, ...]:
    """The in-plane table with these start values and wheel_z's at the tire's loaded radius
    for them (build_inplane_fmu's rule, at the baked operating point too); start values the
    tire cannot be built with (refused at initialisation) keep the default tire's."""
    from ..core.parameters import ParameterError
    from ..fmu.builder import inplane_loaded_radius

    starts = dict(start_values or {})
    try:
        starts["wheel_z"] = inplane_loaded_radius(starts)
    except (ParameterError, ValueError, TypeError):
        pass
    return inplane_fmu_variables(starts)


INPLANE = NativeKind(
    "inplane", "TireInPlaneNative",
    ("fmi2_layer.c", "inplane_tire_model.c", "model_problems.c", "inplane_model.c",
     "inplane_step.c", "inplane_ring.c", "inplane_ritz.c", "inplane_critical.c",
     "inplane_build.c", "inplane_static.c", "inplane_points.c", "inplane_terms.c", "contact.c",
     "numerics.c", "memory.c", "road_file.c", "road_samples.c", "position_road.c"),
    ("model.h", "model_problems.h", "tire.h", "numerics.h", "contract.h", "inplane_model.h",
     "inplane_step.h", "inplane_build.h", "inplane_critical.h", "inplane_points.h",
     "inplane_ring.h", "inplane_ritz.h", "inplane_static.h", "inplane_terms.h", "road_file.h",
     "road_samples.h", "position_road.h", *FMI_HEADERS),
    _inplane_table,
    "Open in-plane ring tire with tangential tread motion, the wheel's rotation and Coulomb "
    "friction in the footprint (0-300 Hz), native C: Fx, Fz and the axle moment My from the "
    "rim's motion, the wheel torque and the road; builds its reduced step for the parameters "
    "at initialisation, with TireInPlane.fmu's variables and numbers. Needs no Python.")

KINDS = {kind.name: kind for kind in (RADIAL, INPLANE)}
DEFAULT_MODEL_IDENTIFIER = RADIAL.model_identifier
INPLANE_MODEL_IDENTIFIER = INPLANE.model_identifier
#: The radial FMU's C files and headers (its compile order).
C_SOURCES = RADIAL.c_sources
C_HEADERS = RADIAL.c_headers


def native_kind(kind: str | NativeKind) -> NativeKind:
    if isinstance(kind, NativeKind):
        return kind
    if kind not in KINDS:
        raise NativeBuildError(f"kind = {kind!r}: known {sorted(KINDS)}")
    return KINDS[kind]


@dataclass(frozen=True)
class Toolchain:
    """How one platform's binary is compiled on this machine."""

    platform: str  # FMI 2.0 binaries/ folder
    compiler: str  # a command (the first word of $CC for linux64)
    suffix: str
    flags: tuple[str, ...]
    libraries: tuple[str, ...]

    def available(self) -> bool:
        return shutil.which(self.compiler) is not None


def toolchains() -> dict[str, Toolchain]:
    cc = os.environ.get("CC", "").split() or ["gcc"]
    return {
        "linux64": Toolchain("linux64", cc[0], ".so",
                             (*cc[1:], "-shared", "-fPIC", "-fvisibility=hidden", "-O2"),
                             ("-lm",)),
        # mingw's own printf (correctly rounded, "1e+07" not "1e+007") and no DLL needed
        # beyond the C runtime Windows ships
        "win64": Toolchain("win64", "x86_64-w64-mingw32-gcc", ".dll",
                           ("-shared", "-O2", "-D__USE_MINGW_ANSI_STDIO=1", "-static-libgcc"),
                           ()),
    }


def c_folder():
    """The C sources shipped with the package (importlib.resources, so zipped installs work)."""
    return resources.files("tire_fmu.native") / "c"


def parameter_start_values(tire=None, load_n=None, speed_m_s=None, **settings) -> dict:
    """Start values by FMU parameter name: a tire (TireParameters, or for the in-plane FMU an
    InPlaneTire: its radial and tangential data), the load and speed, and any other parameter
    by its FMU name (n_elements, f_max, ...)."""
    values = {}
    if tire is not None:
        values = (dict(tire.as_dict()) if not hasattr(tire, "tangential")
                  else {**tire.tire.as_dict(), **tire.tangential.as_dict()})
    if load_n is not None:
        values["load"] = float(load_n)
    if speed_m_s is not None:
        values["speed"] = float(speed_m_s)
    values.update(settings)
    return values


def _table(start_values: dict | None, kind: NativeKind = RADIAL) -> tuple[FmuVariable, ...]:
    table = kind.variables(start_values)
    known = {v.name: v for v in table if v.causality == "parameter"}
    unknown = sorted(set(start_values or {}) - set(known))
    if unknown:
        raise NativeBuildError(f"start values for unknown parameters {unknown}; known: "
                               f"{sorted(known)}")
    for name, value in (start_values or {}).items():
        kind = known[name].type
        if kind == "Integer" and (isinstance(value, bool) or int(value) != value):
            raise NativeBuildError(f"{name} = {value!r}: an Integer parameter needs an integer")
    return table


def _c_double(value) -> str:
    value = float(value)
    if value != value or value in (float("inf"), float("-inf")):
        raise NativeBuildError(f"start value {value!r}: start values must be finite")
    return repr(value)


def _c_text(text: str) -> str:
    """A C string literal of ``text`` (UTF-8, every byte outside printable ASCII escaped)."""
    out = []
    for byte in str(text).encode("utf-8"):
        char = chr(byte)
        out.append(f"\\{byte:03o}" if byte < 0x20 or byte > 0x7e or char in '"\\?'
                   else char)
    return '"' + "".join(out) + '"'


def export_header(table: tuple[FmuVariable, ...], guid: str, model_identifier: str) -> str:
    starts = ", ".join(_c_double(0.0 if v.start is None or v.type == "String" else v.start)
                       for v in table)
    texts = ", ".join(_c_text(v.start or "") if v.type == "String" else "0" for v in table)
    return "\n".join([
        "/* export.h: this export's identifier, GUID and start values. GENERATED by",
        " * tire_fmu.native.builder: do not edit. */",
        "#ifndef TIRE_EXPORT_H",
        "#define TIRE_EXPORT_H",
        "",
        "/* one value per variable, by value reference (fmi2_layer.c checks the count) */",
        f'#define EXPORT_MODEL_IDENTIFIER "{model_identifier}"',
        f'#define EXPORT_GUID "{guid}"',
        "static const double EXPORT_START_VALUES[] = {",
        f"    {starts}",
        "};",
        "/* the String variables' start values (0 for the others) */",
        "static const char* const EXPORT_START_STRINGS[] = {",
        f"    {texts}",
        "};",
        "",
        "#endif",
        "",
    ])


def write_sources(folder: Path, table, guid: str, model_identifier: str,
                  kind: NativeKind = RADIAL) -> list[Path]:
    """The kind's C, the FMI headers, spec.h (from tire_fmu.fmu.spec) and export.h into
    ``folder``: a folder that compiles on its own."""
    folder.mkdir(parents=True, exist_ok=True)
    source = c_folder()
    written = []
    for name in kind.c_sources + kind.c_headers:
        path = folder / name
        path.write_bytes((source / name).read_bytes())
        written.append(path)
    (folder / "spec.h").write_text(c_header(table), encoding="utf-8")
    (folder / "export.h").write_text(export_header(table, guid, model_identifier),
                                     encoding="utf-8")
    written += [folder / "spec.h", folder / "export.h"]
    return written


def build_description(model_identifier: str, kind: NativeKind = RADIAL) -> bytes:
    """sources/buildDescription.xml (FMI 3.0 / 2.0.4 layout, read by fmpy's build)."""
    root = ElementTree.Element("fmiBuildDescription", fmiVersion="3.0")
    config = ElementTree.SubElement(root, "BuildConfiguration",
                                    modelIdentifier=model_identifier)
    files = ElementTree.SubElement(config, "SourceFileSet", language=C_STANDARD)
    for name in kind.c_sources:
        ElementTree.SubElement(files, "SourceFile", name=name)
    ElementTree.SubElement(config, "Library", name="m", description="libm (not on Windows)")
    ElementTree.indent(root, space="  ")
    return ElementTree.tostring(root, encoding="UTF-8", xml_declaration=True)


def compile_binary(sources: Path, toolchain: Toolchain, model_identifier: str, target: Path,
                   extra_flags: tuple[str, ...] = (), kind: NativeKind = RADIAL) -> Path:
    """``sources/*.c`` into ``target/<model_identifier><suffix>`` (include path: that folder
    only, which proves it stands alone)."""
    if not toolchain.available():
        raise NativeBuildError(f"{toolchain.platform}: compiler {toolchain.compiler} not found"
                               + (" (Debian: apt-get install gcc-mingw-w64-x86-64)"
                                  if toolchain.platform == "win64" else " (set CC)"))
    target.mkdir(parents=True, exist_ok=True)
    library = target / f"{model_identifier}{toolchain.suffix}"
    command = [toolchain.compiler, f"-std={C_STANDARD.lower()}", *toolchain.flags,
               *WARNING_FLAGS, *extra_flags, "-I", str(sources), "-o", str(library),
               *(str(sources / name) for name in kind.c_sources), *toolchain.libraries]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0 or result.stderr.strip():
        raise NativeBuildError(f"compiling for {toolchain.platform} failed or warned "
                               f"({' '.join(command)}):\n{result.stderr.strip()}")
    return library


def default_platforms() -> tuple[str, ...]:
    """linux64 (on Linux x86-64) and win64 when the cross compiler is installed."""
    chains = toolchains()
    found = []
    if sys.platform.startswith("linux") and platform.machine() in ("x86_64", "AMD64"):
        found.append("linux64")
    if chains["win64"].available():
        found.append("win64")
    return tuple(found)


def _xml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    return repr(float(value))


def model_description(table, guid: str, model_identifier: str,
                      kind: NativeKind = RADIAL) -> bytes:
    """``modelDescription.xml`` from the same variable table as spec.h and export.h."""
    root = ElementTree.Element("fmiModelDescription", {
        "fmiVersion": "2.0",
        "modelName": model_identifier,
        "guid": guid,
        "description": kind.description,
        "author": "tire_fmu contributors",
        "version": tire_fmu.__version__,
        "license": "MIT",
        "generationTool": f"tire_fmu {tire_fmu.__version__} (tire_fmu.native)",
        "variableNamingConvention": "structured",
        "numberOfEventIndicators": "0",
    })
    co_simulation = ElementTree.SubElement(root, "CoSimulation", {
        "modelIdentifier": model_identifier,
        **{name: _xml_value(value) for name, value in CAPABILITIES.items()},
    })
    sources = ElementTree.SubElement(co_simulation, "SourceFiles")
    for name in kind.c_sources:
        ElementTree.SubElement(sources, "File", name=name)
    root.append(unit_definitions(v.unit for v in table if v.unit))
    categories = ElementTree.SubElement(root, "LogCategories")
    for name, description in LOG_CATEGORIES.items():
        ElementTree.SubElement(categories, "Category", name=name, description=description)
    ElementTree.SubElement(root, "DefaultExperiment", startTime="0.0", stopTime="1.0",
                           stepSize="0.0001")
    variables = ElementTree.SubElement(root, "ModelVariables")
    for vr, v in enumerate(table):
        attributes = {"name": v.name, "valueReference": str(vr), "description": v.description,
                      "causality": v.causality, "variability": v.variability}
        if v.causality == "parameter":
            attributes["initial"] = "exact"
        elif v.causality == "output":
            attributes["initial"] = "calculated"
        element = ElementTree.SubElement(variables, "ScalarVariable", attributes)
        typed = ElementTree.SubElement(element, v.type)
        if v.causality != "output":  # outputs are calculated: no start value
            value = v.start
            if v.type == "Integer":
                value = int(value)
            elif v.type == "Boolean":
                value = bool(value)
            typed.set("start", str(value or "") if v.type == "String" else _xml_value(value))
        if v.unit:
            typed.set("unit", v.unit)
    root.append(model_structure(((v.name, v.causality, "calculated") for v in table),
                                output_dependencies(table)))
    ElementTree.indent(root, space="  ")
    return ElementTree.tostring(root, encoding="UTF-8", xml_declaration=True)


def export_guid(table, model_identifier: str, kind: NativeKind = RADIAL) -> str:
    """A GUID from the content: the model description without its GUID and every source."""
    digest = hashlib.sha256(model_description(table, "", model_identifier, kind))
    digest.update(c_header(table).encode())
    source = c_folder()
    for name in kind.c_sources + kind.c_headers:
        digest.update((source / name).read_bytes())
    return "{" + str(uuid.uuid5(_GUID_NAMESPACE, digest.hexdigest())) + "}"


def build_native_fmu(out: str | Path, start_values: dict | None = None,
                     platforms: tuple[str, ...] | None = None,
                     model_identifier: str | None = None,
                     validate: bool = True, kind: str | NativeKind = "radial") -> Path:
    """Write the native FMU of ``kind`` ("radial": TireModalNative, "inplane":
    TireInPlaneNative; see :data:`KINDS`) to ``out`` (a ``.fmu`` path, or a folder, created
    if missing, for ``<model_identifier>.fmu``; the identifier defaults to the kind's) and
    return its path.

    ``start_values`` (FMU parameter name -> value, see :func:`parameter_start_values`) become
    the parameters' start values: an operating point frozen as defaults, still settable before
    initialisation. ``platforms`` chooses the binaries (default :func:`default_platforms`;
    ``()`` writes a sources-only FMU). ``validate`` runs fmpy's validation and raises
    :class:`NativeBuildError` listing any problem.
    """
    kind = native_kind(kind)
    model_identifier = model_identifier or kind.model_identifier
    table = _table(start_values, kind)
    platforms = default_platforms() if platforms is None else tuple(platforms)
    chains = toolchains()
    unknown = [p for p in platforms if p not in chains]
    if unknown:
        raise NativeBuildError(f"platforms {unknown}: known {sorted(chains)}")
    out = Path(out)
    if out.is_dir() or out.suffix.lower() != ".fmu":  # a folder, as build_inplane_fmu takes
        out.mkdir(parents=True, exist_ok=True)
        out = out / f"{model_identifier}.fmu"
    if not out.parent.is_dir():
        raise NativeBuildError(f"{out}: folder {out.parent} does not exist")
    guid = export_guid(table, model_identifier, kind)
    with tempfile.TemporaryDirectory(prefix="tire_fmu_native_") as staging:
        staging = Path(staging)
        write_sources(staging / "sources", table, guid, model_identifier, kind)
        (staging / "sources" / "buildDescription.xml").write_bytes(
            build_description(model_identifier, kind))
        for name in platforms:
            compile_binary(staging / "sources", chains[name], model_identifier,
                           staging / "binaries" / name, kind=kind)
        (staging / "modelDescription.xml").write_bytes(
            model_description(table, guid, model_identifier, kind))
        # published only once packed and validated: a failed or interrupted build leaves
        # ``out`` as it was, and concurrent builds of one path never share a file
        with published_file(out) as partial:
            pack(staging, partial)
            if validate:
                problems = validation_problems(partial)
                if problems:
                    raise NativeBuildError(f"{out} does not validate: " + "; ".join(problems))
    return out


def build_native_inplane_fmu(out: str | Path, start_values: dict | None = None,
                             platforms: tuple[str, ...] | None = None,
                             model_identifier: str = INPLANE_MODEL_IDENTIFIER,
                             validate: bool = True, tire=None) -> Path:
    """:func:`build_native_fmu` of the in-plane kind: TireInPlaneNative.fmu, TireInPlane.fmu's
    variables in C. ``tire`` (an :class:`~tire_fmu.core.inplane.InPlaneTire`) gives the tire
    data's start values, radial and tangential, as ``build_inplane_fmu(tire=)`` does;
    ``start_values`` any parameter's by name (they win over ``tire``'s)."""
    starts = {**parameter_start_values(tire), **(start_values or {})}
    return build_native_fmu(out, starts or None, platforms=platforms,
                            model_identifier=model_identifier, validate=validate,
                            kind=INPLANE)


def pack(folder: Path, fmu: Path) -> None:
    """Zip the FMU's folder into ``fmu``, the model description first."""
    files = sorted(p for p in folder.rglob("*") if p.is_file())
    files.sort(key=lambda p: p.name != "modelDescription.xml")
    with zipfile.ZipFile(fmu, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in files:
            archive.write(path, path.relative_to(folder).as_posix())


def validation_problems(fmu: str | Path) -> list[str]:
    """fmpy's validation of the FMU."""
    try:
        from fmpy.validation import validate_fmu
    except ImportError as error:
        raise NativeBuildError("validating the FMU needs fmpy: pip install fmpy") from error
    return list(validate_fmu(str(fmu)))
