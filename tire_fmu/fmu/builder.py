"""Build ``TireModal.fmu``: pythonfmu's builder, then the model description it leaves short.

The slave is copied under a versioned module name, because every pythonfmu FMU in a process
shares ``sys.modules``: two FMUs whose slave modules are both called ``slave`` would run the
first one's code. The ``tire_fmu`` package (``__init__.py`` and ``core/``) goes into
``resources/``, which pythonfmu puts first on ``sys.path``, with a ``requirements.txt`` for
the host's Python (pythonfmu embeds the host's interpreter and installs nothing).

pythonfmu 0.7 writes no units, no ``UnitDefinitions`` and no ``ModelStructure/
InitialUnknowns``; :func:`complete_model_description` adds them, and the build fails unless
``fmpy.validation.validate_fmu`` then reports no problem. :func:`build_pythonfmu` does all of
this for any pythonfmu slave (the quarter car of ``vehicle_demo`` uses it too).

The Linux binary pythonfmu ships is its generic C++ wrapper, which crashes on a folder path
with an escaped character, cannot return fmi2Error for a slave, reports every refused step as
"terminated" and corrupts the heap at process exit. The build compiles ``pythonfmu_guard.c``
(needs a C compiler) as the FMU's linux64 binary, in front of that wrapper, which it ships as
``binaries/linux64/pythonfmu-export.so``; see that file for what it changes and why. The win64
binary is pythonfmu's wrapper as it is (docs/fmu.md says what that host then gets).

The FMU appears at its destination only when pythonfmu's packaging, the guard and the model
description are done and fmpy's validation passed (:mod:`tire_fmu.publish`): a build that fails
or is interrupted leaves a previous FMU there as it was, and concurrent builds of one path
each publish a whole FMU. The last entry of a completed FMU is its build record
(:func:`build_record`), which tells a finished FMU from pythonfmu's output alone.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import tempfile
import warnings
import zipfile
from importlib import metadata, resources
from pathlib import Path
from xml.etree import ElementTree

import tire_fmu

from ..publish import published_file
from .interface import BAKED_PARAMETERS_FILE, CAPABILITIES, fmu_variables, unit_definitions

MODEL_IDENTIFIER = "TireModal"
SLAVE_MODULE = "tire_fmu_modal_slave_" + re.sub(r"\W", "_", tire_fmu.__version__)
#: What the slave imports besides the shipped package (pyproject's runtime dependencies,
#: used when the package metadata is not installed).
FALLBACK_REQUIREMENTS = ("numpy>=1.24", "scipy>=1.10")

_PACKAGE_ROOT = Path(tire_fmu.__file__).parent
_SLAVE_SOURCE = Path(__file__).with_name("slave.py")

#: The FMU's linux64 binary: pythonfmu_guard.c, in front of pythonfmu's wrapper, shipped as
GUARD_SOURCE = "pythonfmu_guard.c"
WRAPPER_FILE = "pythonfmu-export.so"  # the name the guard loads, beside itself
#: Written last into every FMU this module completes (see :func:`build_record`).
BUILD_RECORD = "resources/tire_fmu_build.json"
GUARD_FLAGS = ("-shared", "-fPIC", "-O2", "-std=c99", "-Wall", "-Wextra",
               # its exit handler must stay mapped, and its calls must stay its own
               "-Wl,-z,nodelete", "-Wl,-Bsymbolic")


class GuardMissingWarning(UserWarning):
    """The FMU was built without pythonfmu_guard.c (no C compiler, or not on Linux)."""


class KernelMissingWarning(UserWarning):
    """The FMU was built without the compiled step kernel for a platform (no C compiler for
    it): there the slave steps with the numpy reference kernel, slower, and says so."""


class FmuBuildError(RuntimeError):
    """The FMU could not be built, or what was built does not validate."""


def build_fmu(out: str | Path = ".", validate: bool = True, tire=None) -> Path:
    """Write the FMU to ``out`` and return its path: a path ending in ``.fmu``, or a folder
    (created if missing) to hold ``TireModal.fmu``.

    ``tire`` (a :class:`~tire_fmu.core.parameters.TireParameters`) becomes the start values
    of the tire parameters (default: GL073A); the slave reads them from
    ``resources/tire_parameters.json``, so the model description and the running FMU agree.
    ``validate`` runs ``fmpy.validation.validate_fmu`` when fmpy is installed and raises
    :class:`FmuBuildError` listing any problem.
    """
    with tempfile.TemporaryDirectory(prefix="tire_fmu_build_") as staging:
        project = _stage_project(Path(staging) / "project")
        if tire is not None:
            baked = Path(staging) / "project" / BAKED_PARAMETERS_FILE
            baked.write_text(json.dumps(tire.as_dict(), indent=1) + "\n")
            project.append(baked)
        return build_pythonfmu(
            _SLAVE_SOURCE, fmu_destination(out, MODEL_IDENTIFIER), SLAVE_MODULE,
            project_files=project, capabilities=CAPABILITIES,
            units={v.name: v.unit for v in fmu_variables() if v.unit}, validate=validate,
            real_starts=None if tire is None else tire.as_dict(), kernel=True)


INPLANE_MODEL_IDENTIFIER = "TireInPlane"
INPLANE_SLAVE_MODULE = "tire_fmu_inplane_slave_" + re.sub(r"\W", "_", tire_fmu.__version__)
_INPLANE_SLAVE_SOURCE = Path(__file__).with_name("inplane_slave.py")


def build_inplane_fmu(out: str | Path = ".", validate: bool = True, tire=None) -> Path:
    """Write ``TireInPlane.fmu`` (the in-plane tire: Fx, Fz and My, the wheel's rotation,
    friction) to ``out``, as :func:`build_fmu` writes TireModal.fmu. Its slave is
    :class:`~tire_fmu.fmu.inplane_slave.TireInPlane`, whose FMI layer is TireModal's, so the
    package staged into its resources carries ``fmu/slave.py`` too. ``tire`` (an
    :class:`~tire_fmu.core.inplane.InPlaneTire`) gives the parameters' start values, radial
    and tangential (default: GL073A with the shipped tangential estimates)."""
    from .interface import inplane_fmu_variables

    with tempfile.TemporaryDirectory(prefix="tire_fmu_build_") as staging:
        project = _stage_project(Path(staging) / "project", with_slave=True)
        starts = None
        if tire is not None:
            starts = {**tire.tire.as_dict(), **tire.tangential.as_dict()}
            baked = Path(staging) / "project" / BAKED_PARAMETERS_FILE
            baked.write_text(json.dumps(starts, indent=1) + "\n")
            project.append(baked)
        return build_pythonfmu(
            _INPLANE_SLAVE_SOURCE, fmu_destination(out, INPLANE_MODEL_IDENTIFIER),
            INPLANE_SLAVE_MODULE, project_files=project, capabilities=CAPABILITIES,
            units={v.name: v.unit for v in inplane_fmu_variables() if v.unit},
            validate=validate, real_starts=starts, kernel=True)


def fmu_destination(out: str | Path, model_identifier: str) -> Path:
    """``out`` itself when it names a ``.fmu`` file, else ``out/<model_identifier>.fmu``."""
    out = Path(out)
    if out.suffix.lower() == ".fmu" and not out.is_dir():
        return out
    return out / f"{model_identifier}.fmu"


def build_pythonfmu(slave_source: Path, dest: Path, module_name: str, *,
                    project_files=(), capabilities: dict, units: dict[str, str],
                    validate: bool = True, real_starts: dict[str, float] | None = None,
                    kernel: bool = False) -> Path:
    """Build a pythonfmu FMU from ``slave_source`` and complete its model description.

    The slave is built under ``module_name``: every pythonfmu FMU in a process shares
    ``sys.modules``, and two slave modules with one name would run the first one's code.
    ``units`` maps variable names to the units written into the model description (pythonfmu
    0.7 writes none); ``capabilities`` are the flags the slave really supports;
    ``real_starts`` are Real start values to write exactly (pythonfmu rounds to 16 digits);
    ``kernel`` ships the compiled step kernel for every platform a compiler is found for.
    """
    try:
        from pythonfmu.builder import FmuBuilder
    except ImportError as error:
        raise FmuBuildError("building the FMU needs pythonfmu: pip install "
                            "'tire_fmu[fmu]'") from error
    dest = Path(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="pythonfmu_build_") as staging:
        staging = Path(staging)
        script = staging / f"{module_name}.py"
        shutil.copyfile(slave_source, script)
        try:
            # pythonfmu's own FMU stays private: it lacks the completed model description and
            # the guard, and only the finished, validated FMU may appear at ``dest``
            built = Path(FmuBuilder.build_FMU(script, dest=staging / "pythonfmu" / dest.name,
                                              project_files=list(project_files),
                                              **capabilities))
        finally:
            _forget_build_imports(script)
        try:
            guard = compile_guard(staging / "guard")
        except FmuBuildError as error:
            # still a working FMU, with pythonfmu's own wrapper and its failure modes
            # (docs/fmu.md, "The win64 binary"): better than none
            warnings.warn(f"{error}; the FMU's linux64 binary is pythonfmu's wrapper without "
                          f"the guard (fmi2Error statuses, the exit fix), see docs/fmu.md",
                          GuardMissingWarning, stacklevel=2)
            guard = None
        kernels = compile_kernels(staging / "kernel") if kernel else {}
        with published_file(dest) as partial:
            complete_fmu(built, capabilities, units, real_starts, guard, target=partial,
                         kernels=kernels)
            if validate:
                problems = validation_problems(partial)
                if problems:
                    raise FmuBuildError(f"{dest} does not validate: " + "; ".join(problems))
    return dest


def _stage_project(folder: Path, with_slave: bool = False) -> list[Path]:
    """The package the slave imports (no CLI, plots or caches) and the host requirements;
    ``with_slave`` adds the radial slave, whose FMI layer the in-plane slave extends."""
    package = folder / "tire_fmu"
    (package / "core").mkdir(parents=True)
    (package / "fmu").mkdir()
    (package / "native").mkdir()
    shutil.copyfile(_PACKAGE_ROOT / "__init__.py", package / "__init__.py")
    # how the slave checks a file it reads (resources/tire_parameters.json)
    shutil.copyfile(_PACKAGE_ROOT / "file_checks.py", package / "file_checks.py")
    for source in sorted((_PACKAGE_ROOT / "core").glob("*.py")):
        shutil.copyfile(source, package / "core" / source.name)
    names = ("__init__.py", "interface.py", "spec.py") + (("slave.py",) if with_slave else ())
    for name in names:  # the table and wording it uses
        shutil.copyfile(_PACKAGE_ROOT / "fmu" / name, package / "fmu" / name)
    # the compiled kernels' ctypes (the radial step's and the in-plane step's)
    for name in ("__init__.py", "kernel.py", "contract.py", "inplane_kernel.py", "inplane_ring.py",
                 "inplane_critical.py"):
        shutil.copyfile(_PACKAGE_ROOT / "native" / name, package / "native" / name)
    requirements = folder / "requirements.txt"
    requirements.write_text("# Python packages the host's interpreter needs for TireModal.fmu\n"
                            + "\n".join(runtime_requirements()) + "\n")
    return [package, requirements]


def runtime_requirements() -> list[str]:
    """The package's unconditional dependencies (those without an extra or a marker)."""
    try:
        declared = metadata.requires("tire_fmu") or []
    except metadata.PackageNotFoundError:
        return list(FALLBACK_REQUIREMENTS)
    plain = [item.replace(" ", "") for item in declared if ";" not in item]
    return plain or list(FALLBACK_REQUIREMENTS)


def _forget_build_imports(script: Path) -> None:
    # pythonfmu's builder imports the slave from the staging folder and leaves that folder on
    # sys.path; the folder is about to disappear, so take both back out.
    sys.modules.pop(script.stem, None)
    while str(script.parent) in sys.path:
        sys.path.remove(str(script.parent))


# -- the model description -----------------------------------------------------------------

def compile_guard(folder: Path) -> Path:
    """``pythonfmu_guard.c`` compiled into ``folder`` (the FMI headers come from fmpy)."""
    from ..native.builder import c_folder, toolchains

    if not sys.platform.startswith("linux"):
        raise FmuBuildError(f"the FMU's linux64 binary is compiled on Linux, and this is "
                            f"{sys.platform}")
    folder.mkdir(parents=True, exist_ok=True)
    source = folder / GUARD_SOURCE
    source.write_bytes(resources.files(__package__).joinpath(GUARD_SOURCE).read_bytes())
    for header in ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"):
        (folder / header).write_bytes(c_folder().joinpath(header).read_bytes())
    library = folder / "guard.so"
    linux = toolchains()["linux64"]
    if not linux.available():
        raise FmuBuildError(f"building the FMU's linux64 binary needs a C compiler; "
                            f"{linux.compiler} was not found (install gcc, or set CC)")
    command = [linux.compiler, *linux.flags[:linux.flags.index("-shared")], *GUARD_FLAGS,
               "-I", str(folder), "-o", str(library), str(source), "-ldl", "-lpthread"]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise FmuBuildError(f"compiling {GUARD_SOURCE} failed ({' '.join(command)}):\n"
                            + done.stderr.strip())
    return library


def compile_kernels(folder: Path) -> dict[str, Path]:
    """The step kernel (native/c/kernel.c and what it needs) compiled for every platform
    this machine has a compiler for: {platform: library}. A platform without one is named in
    a KernelMissingWarning (the FMU runs there with the numpy reference kernel)."""
    from ..native.kernel import PLATFORMS, KernelUnavailable, compile_kernel

    built = {}
    for platform, (_, _, _, name) in PLATFORMS.items():
        try:
            built[platform] = compile_kernel(folder / platform / name, platform)
        except KernelUnavailable as error:
            warnings.warn(f"{error}: on {platform} TireModal.fmu steps with the numpy "
                          "reference kernel (the same outputs, slower)", KernelMissingWarning,
                          stacklevel=3)
    return built


def complete_fmu(fmu: str | Path, capabilities: dict, units: dict[str, str],
                 real_starts: dict[str, float] | None = None, guard: Path | None = None,
                 target: str | Path | None = None,
                 kernels: dict[str, Path] | None = None) -> None:
    """Rewrite the FMU's ``modelDescription.xml`` with :func:`complete_model_description`;
    with ``guard``, that library becomes the linux64 binary and pythonfmu's wrapper moves to
    ``binaries/linux64/pythonfmu-export.so``; ``kernels`` ({platform: library}) go into
    ``binaries/<platform>/`` under their names. The last entry written is the build record
    (:func:`build_record`). Written to ``target``, or in place of ``fmu`` without one."""
    fmu = Path(fmu)
    kernels = kernels or {}
    if target is None:
        with published_file(fmu) as partial:
            complete_fmu(fmu, capabilities, units, real_starts, guard, partial, kernels)
        return
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(target, "w",
                                                          zipfile.ZIP_DEFLATED) as archive:
        for item in source.infolist():
            data = source.read(item.filename)
            if item.filename == BUILD_RECORD or "/__pycache__/" in item.filename:
                continue  # of an earlier completion: written anew
            if item.filename == "modelDescription.xml":
                data = complete_model_description(data, capabilities, units, real_starts)
            elif guard is not None and re.fullmatch(r"binaries/linux64/[^/]+\.so",
                                                    item.filename):
                wrapper = zipfile.ZipInfo(f"binaries/linux64/{WRAPPER_FILE}", item.date_time)
                wrapper.external_attr = item.external_attr
                archive.writestr(wrapper, data, compress_type=zipfile.ZIP_DEFLATED)
                data = guard.read_bytes()
            archive.writestr(item, data, compress_type=zipfile.ZIP_DEFLATED)
            if re.fullmatch(r"resources/.+\.py", item.filename):
                _write_bytecode(archive, item, data)
        for platform, library in sorted(kernels.items()):
            archive.write(library, f"binaries/{platform}/{library.name}")
        record = {"built_by": f"tire_fmu {tire_fmu.__version__}", "guard": guard is not None,
                  "kernel": sorted(kernels)}
        archive.writestr(BUILD_RECORD, json.dumps(record) + "\n")


def _write_bytecode(archive: zipfile.ZipFile, item: zipfile.ZipInfo, source: bytes) -> None:
    """The bytecode of a Python file the FMU carries, beside it in ``__pycache__`` for this
    interpreter's version. A host extracts the FMU afresh (often with bytecode writing off), so
    without it every start compiles the package and pythonfmu's own modules again: about a
    third of a fresh start. The bytecode is checked by the source's hash, not its time stamp,
    which extraction does not keep; a host of another Python version compiles as before."""
    import importlib.util
    import py_compile

    cached = importlib.util.cache_from_source(item.filename)
    with tempfile.TemporaryDirectory(prefix="tire_fmu_pyc_") as folder:
        script, compiled = Path(folder) / "source.py", Path(folder) / "source.pyc"
        script.write_bytes(source)
        py_compile.compile(str(script), cfile=str(compiled), dfile=item.filename, doraise=True,
                           invalidation_mode=py_compile.PycInvalidationMode.CHECKED_HASH)
        entry = zipfile.ZipInfo(cached.replace("\\", "/"), item.date_time)
        entry.external_attr = item.external_attr
        archive.writestr(entry, compiled.read_bytes(), compress_type=zipfile.ZIP_DEFLATED)


def build_record(fmu: str | Path) -> dict | None:
    """What :func:`complete_fmu` recorded in ``fmu``, or None unless ``fmu`` is a whole zip
    (every entry's CRC checks) that this builder completed: pythonfmu's FMU on its own, an
    FMU cut short, or another tool's, have none."""
    try:
        with zipfile.ZipFile(fmu) as archive:
            if archive.testzip() is not None:
                return None
            record = json.loads(archive.read(BUILD_RECORD))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile):
        return None
    return record if isinstance(record, dict) else None


def complete_model_description(xml: bytes, capabilities: dict, units: dict[str, str],
                               real_starts: dict[str, float] | None = None) -> bytes:
    """Write the units and their definitions, the outputs and initial unknowns, exact Real
    start values (``repr``, which reads back to the same double), and pin the capability
    flags."""
    root = ElementTree.fromstring(xml)
    co_simulation = root.find("CoSimulation")
    for name, value in capabilities.items():
        co_simulation.set(name, str(value).lower())
    co_simulation.attrib.pop("providesDirectionalDerivative", None)
    for variable in root.find("ModelVariables").findall("ScalarVariable"):
        real = variable.find("Real")
        if real is not None and units.get(variable.get("name")):
            real.set("unit", units[variable.get("name")])
        if real is not None and variable.get("name") in (real_starts or {}):
            real.set("start", repr(float(real_starts[variable.get("name")])))
    used = {real.get("unit") for real in root.iter("Real") if real.get("unit")}
    if used:
        for old in root.findall("UnitDefinitions"):
            root.remove(old)
        root.insert(list(root).index(co_simulation) + 1, unit_definitions(used))
    variables = root.find("ModelVariables").findall("ScalarVariable")
    outputs = [i for i, v in enumerate(variables, 1) if v.get("causality") == "output"]
    calculated = [i for i in outputs
                  if variables[i - 1].get("initial", "calculated") in ("calculated", "approx")]
    structure = root.find("ModelStructure")
    for old in list(structure):
        structure.remove(old)
    for tag, indices in (("Outputs", outputs), ("InitialUnknowns", calculated)):
        if indices:
            group = ElementTree.SubElement(structure, tag)
            for index in indices:
                ElementTree.SubElement(group, "Unknown", index=str(index))
    ElementTree.indent(root, space="  ")
    return ElementTree.tostring(root, encoding="UTF-8", xml_declaration=True)


def validation_problems(fmu: str | Path) -> list[str]:
    """fmpy's validation of the FMU, or [] when fmpy is not installed."""
    try:
        from fmpy.validation import validate_fmu
    except ImportError:
        return []
    return list(validate_fmu(str(fmu)))
