"""Build ``TireModal.fmu`` and ``TireInPlane.fmu``: pythonfmu's builder, then the model
description it leaves short.

Every pythonfmu FMU in a process shares ``sys.modules``, and Python imports a name once per
process. So each FMU carries the package it runs (``__init__.py``, ``core/``, the variable
table, its slave, the compiled kernels' ctypes) under a name of its own, in ``resources/``
(which pythonfmu puts first on ``sys.path``): ``tire_fmu_<model>_<version>_<hash>``, the hash
of the files it carries, their absolute ``tire_fmu`` imports rewritten to that name
(:func:`bundle_name`, :func:`rename_imports`). Two FMUs, of one version or two, and a host
that imports ``tire_fmu`` itself, then never run each other's code, in whichever order they
are loaded; the slave module pythonfmu loads is a two-line module of the same name that
imports the slave class from the package. ``requirements.txt`` lists what the host's Python
needs (pythonfmu embeds the host's interpreter and installs nothing).

pythonfmu 0.7 writes no units, no ``UnitDefinitions``, no ``ModelStructure/InitialUnknowns``
and no output dependencies; :func:`complete_model_description` adds them, and the build fails
unless ``fmpy.validation.validate_fmu`` then reports no problem. :func:`build_pythonfmu` does
all of this for any pythonfmu slave (the quarter car of ``vehicle_demo`` uses it too).

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

import ast
import hashlib
import json
import os
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
from .interface import (
    BAKED_PARAMETERS_FILE,
    CAPABILITIES,
    fmu_variables,
    model_structure,
    output_dependencies,
    unit_definitions,
)

MODEL_IDENTIFIER = "TireModal"
INPLANE_MODEL_IDENTIFIER = "TireInPlane"
#: What the slave imports besides the shipped package (pyproject's runtime dependencies,
#: used when the package metadata is not installed): threadpoolctl limits BLAS's threads
#: while the model is built (without it the FMU runs, on BLAS's default threads, and says so).
FALLBACK_REQUIREMENTS = ("numpy>=1.24", "scipy>=1.10", "threadpoolctl>=3.1")

_PACKAGE_ROOT = Path(tire_fmu.__file__).parent
#: Each FMU's slave: (its module in tire_fmu.fmu, its class, the fmu/ modules it needs).
SLAVES = {
    MODEL_IDENTIFIER: ("slave", "TireModal", ("slave.py",)),
    # its FMI layer is TireModal's
    INPLANE_MODEL_IDENTIFIER: ("inplane_slave", "TireInPlane", ("slave.py", "inplane_slave.py")),
}
#: The compiled kernels' ctypes (the radial step's and the in-plane step's), which every FMU
#: carries, and the fmu/ modules besides the slaves: the table and wording both FMUs share.
_NATIVE_MODULES = ("__init__.py", "kernel.py", "contract.py", "inplane_kernel.py",
                   "inplane_ring.py", "inplane_critical.py")
_FMU_MODULES = ("__init__.py", "interface.py", "spec.py")
#: The slave module pythonfmu loads: the class from the FMU's own package. pythonfmu 0.7's
#: wrapper runs the module's code again at every fmi2Instantiate, in the module's namespace,
#: and then releases a reference to that namespace which it never took (findClass's
#: Py_DECREF of PyModule_GetDict's borrowed dict). A slave module full of functions hides it
#: (each run leaks their copies, each holding the namespace); this one makes one function per
#: run, kept, or the second instance would free the namespace under the module.
_SLAVE_SHIM = '''"""{model}'s slave module: {cls} from the package this FMU carries
({package}/), under a name of its own, so that no other FMU's copy and not the host's
tire_fmu runs in its place. The last line holds the reference to this namespace that
pythonfmu's wrapper releases after running this code at each fmi2Instantiate."""
from {package}.fmu.{module} import {cls}  # noqa: F401

globals().setdefault("_held_by_each_instantiation", []).append(lambda: None)
'''

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
    return _build_tire_fmu(MODEL_IDENTIFIER, fmu_variables(), out, validate,
                           None if tire is None else tire.as_dict())


def build_inplane_fmu(out: str | Path = ".", validate: bool = True, tire=None) -> Path:
    """Write ``TireInPlane.fmu`` (the in-plane tire: Fx, Fz and My, the wheel's rotation,
    friction) to ``out``, as :func:`build_fmu` writes TireModal.fmu. Its slave is
    :class:`~tire_fmu.fmu.inplane_slave.TireInPlane`, whose FMI layer is TireModal's, so the
    package it carries holds ``fmu/slave.py`` too. ``tire`` (an
    :class:`~tire_fmu.core.inplane.InPlaneTire`) gives the parameters' start values, radial
    and tangential (default: GL073A with the shipped tangential estimates)."""
    from .interface import inplane_fmu_variables

    # the FMUs' default tire is the parameters' start values (GL073A, its sidewall tied)
    starts = {} if tire is None else {**tire.tire.as_dict(), **tire.tangential.as_dict()}
    starts["wheel_z"] = inplane_loaded_radius(starts)
    return _build_tire_fmu(INPLANE_MODEL_IDENTIFIER, inplane_fmu_variables(starts), out,
                           validate, starts)


def inplane_loaded_radius(values: dict) -> float:
    """The in-plane tire's loaded radius (m) with these values by FMU parameter name: the
    tire data, and the operating point (load, speed, n_elements, ...) where given (the rest
    the FMUs' defaults): wheel_z's start value, so that a host that leaves it unset has the
    tire carry its load."""
    from ..core.inplane import TANGENTIAL_RANGES
    from ..core.inplane_host import FMU_NAMES, HostSettings, build_host_stepper
    from ..core.parameters import TIRE_FIELDS

    operating = {core: values[name] for core, name in FMU_NAMES.items() if name in values}
    if "n_elements" in operating:
        operating["n_elements"] = int(operating["n_elements"])
    settings = HostSettings(tire={k: v for k, v in values.items() if k in TIRE_FIELDS},
                            tangential={k: v for k, v in values.items()
                                        if k in TANGENTIAL_RANGES}, **operating)
    return build_host_stepper(settings, "numpy").stepper.loaded_radius_m


def _build_tire_fmu(model_identifier: str, table, out, validate: bool,
                    starts: dict[str, float] | None) -> Path:
    """One of the tire's pythonfmu FMUs: its package under its own name, the slave module
    that loads its slave from there, the start values ``starts`` baked in."""
    module, cls, _ = SLAVES[model_identifier]
    with tempfile.TemporaryDirectory(prefix="tire_fmu_build_") as staging:
        staging = Path(staging)
        package, project = stage_package(staging / "project", model_identifier)
        if starts is not None:
            baked = staging / "project" / BAKED_PARAMETERS_FILE
            baked.write_text(json.dumps(starts, indent=1) + "\n")
            project.append(baked)
        shim = staging / "slave.py"
        shim.write_text(_SLAVE_SHIM.format(model=model_identifier, cls=cls, package=package,
                                           module=module))
        return build_pythonfmu(
            shim, fmu_destination(out, model_identifier), f"{package}_slave",
            project_files=project, capabilities=CAPABILITIES,
            units={v.name: v.unit for v in table if v.unit}, validate=validate,
            real_starts=starts, kernel=True, dependencies=output_dependencies(table))


def fmu_destination(out: str | Path, model_identifier: str) -> Path:
    """``out`` itself when it names a ``.fmu`` file, else ``out/<model_identifier>.fmu``."""
    out = Path(out)
    if out.suffix.lower() == ".fmu" and not out.is_dir():
        return out
    return out / f"{model_identifier}.fmu"


def build_pythonfmu(slave_source: Path, dest: Path, module_name: str, *,
                    project_files=(), capabilities: dict, units: dict[str, str],
                    validate: bool = True, real_starts: dict[str, float] | None = None,
                    kernel: bool = False,
                    dependencies: dict[str, tuple[str, ...]] | None = None) -> Path:
    """Build a pythonfmu FMU from ``slave_source`` and complete its model description.

    The slave is built under ``module_name``: every pythonfmu FMU in a process shares
    ``sys.modules``, and two slave modules with one name would run the first one's code.
    ``project_files`` go into ``resources/`` beside it, and the build imports the slave from
    beside them, as the FMU will. ``units`` maps variable names to the units written into the
    model description (pythonfmu 0.7 writes none); ``capabilities`` are the flags the slave
    really supports; ``real_starts`` are Real start values to write exactly (pythonfmu rounds
    to 16 digits); ``kernel`` ships the compiled step kernel for every platform a compiler is
    found for; ``dependencies`` gives, for an output, the inputs it depends on directly (an
    output not in it depends on every input, FMI's default).
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
        # the slave and what it imports side by side, as in the FMU's resources/
        resources_folder = staging / "resources"
        resources_folder.mkdir()
        script = resources_folder / f"{module_name}.py"
        shutil.copyfile(slave_source, script)
        staged = []
        for item in map(Path, project_files):
            staged.append(resources_folder / item.name)
            (shutil.copytree if item.is_dir() else shutil.copyfile)(item, staged[-1])
        try:
            # pythonfmu's own FMU stays private: it lacks the completed model description and
            # the guard, and only the finished, validated FMU may appear at ``dest``
            built = Path(FmuBuilder.build_FMU(script, dest=staging / "pythonfmu" / dest.name,
                                              project_files=staged, **capabilities))
        finally:
            _forget_build_imports(resources_folder)
        try:
            guard = compile_guard(staging / "guard")
        except FmuBuildError as error:
            # still a working FMU, with pythonfmu's own wrapper and its failure modes
            # (docs/fmu.md, "The win64 binary"): better than none
            warnings.warn(f"{error}; the FMU's linux64 binary is pythonfmu's wrapper without "
                          f"the guard (fmi2Error statuses, the exit fix), see docs/fmu.md",
                          GuardMissingWarning, stacklevel=2)
            guard = None
        kernels = compile_kernels(staging / "kernel", dest.name) if kernel else {}
        with published_file(dest) as partial:
            complete_fmu(built, capabilities, units, real_starts, guard, target=partial,
                         kernels=kernels, dependencies=dependencies)
            if validate:
                problems = validation_problems(partial)
                if problems:
                    raise FmuBuildError(f"{dest} does not validate: " + "; ".join(problems))
    return dest


def stage_package(folder: Path, model_identifier: str,
                  package_root: Path = _PACKAGE_ROOT) -> tuple[str, list[Path]]:
    """The package ``model_identifier``'s slave imports, from ``package_root``, in
    ``folder`` under :func:`bundle_name` (no CLI, plots or caches; its imports of
    ``tire_fmu`` renamed), and the host's requirements: (its name, [its folder, the
    requirements file])."""
    _, _, slaves = SLAVES[model_identifier]
    # how the slave checks a file it reads (resources/tire_parameters.json): file_checks;
    # the road files its road_file parameter names: road_files (numpy and the core only)
    files = [Path("__init__.py"), Path("file_checks.py"), Path("road_files.py"),
             *(Path("core", source.name) for source in
               sorted((package_root / "core").glob("*.py")))]
    files += [Path("fmu", name) for name in sorted(_FMU_MODULES + slaves)]
    files += [Path("native", name) for name in _NATIVE_MODULES]
    sources = {path: (package_root / path).read_bytes() for path in files}
    name = bundle_name(model_identifier, sources)
    for path, source in sources.items():
        target = folder / name / path
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(rename_imports(source.decode("utf-8"), name, path), encoding="utf-8")
    requirements = folder / "requirements.txt"
    requirements.write_text(f"# Python packages the host's interpreter needs for "
                            f"{model_identifier}.fmu\n" + "\n".join(runtime_requirements()) + "\n")
    return name, [folder / name, requirements]


def bundle_name(model_identifier: str, sources: dict[Path, bytes]) -> str:
    """The name an FMU's package goes by: ``tire_fmu_<model>_<version>_<hash>``, the hash of
    the model and the files (their paths and bytes), so that FMUs built from different code
    never share a module, and an FMU built again from the same code keeps its name."""
    digest = hashlib.sha256(model_identifier.encode() + b"\0")
    for path, source in sorted(sources.items()):
        digest.update(path.as_posix().encode() + b"\0" + source + b"\0")
    version = re.sub(r"\W", "_", tire_fmu.__version__)
    return f"tire_fmu_{model_identifier.lower()}_{version}_{digest.hexdigest()[:12]}"


#: ``import tire_fmu`` and ``from tire_fmu[.x] import``, at the start of a line
_IMPORT = re.compile(r"^(?P<indent>[ \t]*)(?:from[ \t]+tire_fmu(?P<sub>(?:\.\w+)*)[ \t]+import\b"
                     r"|import[ \t]+tire_fmu(?=[ \t]*(?:#.*)?$))", re.MULTILINE)


def rename_imports(source: str, package: str, path: Path | str = "<source>") -> str:
    """``source`` with its absolute imports of ``tire_fmu`` made imports of ``package``
    (``import tire_fmu`` keeps the name: ``import <package> as tire_fmu``). FmuBuildError if
    anything else would still name the package absolutely (another form of import, or a
    dotted name in a string, as importlib and importlib.resources take it): that code would
    run the host's tire_fmu, or none."""
    def renamed(match: re.Match) -> str:
        if match.group("sub") is not None:
            return f"{match['indent']}from {package}{match['sub']} import"
        return f"{match['indent']}import {package} as tire_fmu"

    text = _IMPORT.sub(renamed, source)
    left = []
    for node in ast.walk(ast.parse(text, filename=str(path))):
        if isinstance(node, ast.ImportFrom) and node.level == 0:
            names = [node.module or ""]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            names = [node.value] if re.fullmatch(r"tire_fmu(\.\w+)+", node.value) else []
        else:
            continue
        left += [f"line {node.lineno}" for n in names if n.split(".")[0] == "tire_fmu"]
    if left:
        raise FmuBuildError(f"{path}: names the package tire_fmu absolutely where the build "
                            f"cannot rename it ({', '.join(left)}): import it relatively")
    return text


def runtime_requirements() -> list[str]:
    """The package's unconditional dependencies (those without an extra or a marker)."""
    try:
        declared = metadata.requires("tire_fmu") or []
    except metadata.PackageNotFoundError:
        return list(FALLBACK_REQUIREMENTS)
    plain = [item.replace(" ", "") for item in declared if ";" not in item]
    return plain or list(FALLBACK_REQUIREMENTS)


def _forget_build_imports(folder: Path) -> None:
    # pythonfmu's builder imports the slave (and what it imports from beside it) from the
    # staging folder and leaves that folder on sys.path; the folder is about to disappear,
    # and an FMU of the same package loaded later must import its own: take them back out.
    inside = str(folder) + os.sep
    for name, module in list(sys.modules.items()):
        if (getattr(module, "__file__", None) or "").startswith(inside):
            del sys.modules[name]
    while str(folder) in sys.path:
        sys.path.remove(str(folder))


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


def compile_kernels(folder: Path, fmu_name: str = "TireModal.fmu") -> dict[str, Path]:
    """The step kernel (native/c/kernel.c and what it needs) compiled for every platform
    this machine has a compiler for: {platform: library}. A platform without one is named in
    a KernelMissingWarning (the FMU ``fmu_name`` runs there with the numpy reference kernel),
    which says what to install."""
    from ..native.kernel import PLATFORMS, KernelUnavailable, compile_kernel

    built = {}
    for platform, (_, _, _, name) in PLATFORMS.items():
        try:
            built[platform] = compile_kernel(folder / platform / name, platform)
        except KernelUnavailable as error:
            warnings.warn(f"{error}, then build again: without it {fmu_name} steps on "
                          f"{platform} with the numpy reference kernel (the same outputs, "
                          "slower)", KernelMissingWarning, stacklevel=3)
    return built


def complete_fmu(fmu: str | Path, capabilities: dict, units: dict[str, str],
                 real_starts: dict[str, float] | None = None, guard: Path | None = None,
                 target: str | Path | None = None,
                 kernels: dict[str, Path] | None = None,
                 dependencies: dict[str, tuple[str, ...]] | None = None) -> None:
    """Rewrite the FMU's ``modelDescription.xml`` with :func:`complete_model_description`;
    with ``guard``, that library becomes the linux64 binary and pythonfmu's wrapper moves to
    ``binaries/linux64/pythonfmu-export.so``; ``kernels`` ({platform: library}) go into
    ``binaries/<platform>/`` under their names. The last entry written is the build record
    (:func:`build_record`). Written to ``target``, or in place of ``fmu`` without one."""
    fmu = Path(fmu)
    kernels = kernels or {}
    if target is None:
        with published_file(fmu) as partial:
            complete_fmu(fmu, capabilities, units, real_starts, guard, partial, kernels,
                         dependencies)
        return
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(target, "w",
                                                          zipfile.ZIP_DEFLATED) as archive:
        for item in source.infolist():
            data = source.read(item.filename)
            if item.filename == BUILD_RECORD or "/__pycache__/" in item.filename:
                continue  # of an earlier completion: written anew
            if item.filename == "modelDescription.xml":
                data = complete_model_description(data, capabilities, units, real_starts,
                                                  dependencies)
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
                               real_starts: dict[str, float] | None = None,
                               dependencies: dict[str, tuple[str, ...]] | None = None) -> bytes:
    """Write the units and their definitions, the outputs (with the inputs each depends on
    directly, for those in ``dependencies``) and initial unknowns, exact Real start values
    (``repr``, which reads back to the same double), and pin the capability flags."""
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
    variables = [(v.get("name"), v.get("causality", "local"), v.get("initial", "calculated"))
                 for v in root.find("ModelVariables").findall("ScalarVariable")]
    old = root.find("ModelStructure")
    position = list(root).index(old)
    root.remove(old)
    root.insert(position, model_structure(variables, dependencies))
    ElementTree.indent(root, space="  ")
    return ElementTree.tostring(root, encoding="UTF-8", xml_declaration=True)


def validation_problems(fmu: str | Path) -> list[str]:
    """fmpy's validation of the FMU, or [] when fmpy is not installed."""
    try:
        from fmpy.validation import validate_fmu
    except ImportError:
        return []
    return list(validate_fmu(str(fmu)))
