"""Saving and loading reduced models: .npz (no pickles), MATLAB .mat, python-control.

File formats are an adapter over the physics core (which knows no files), like the CLI and
the FMUs: this module turns a :class:`~tire_fmu.core.reduction.ReducedModel` into files and
back.

``.npz`` holds the diagonal modal form as plain arrays plus a JSON metadata string (tire data,
operating point, settings, error report, names, units) with a SHA-256 checksum of every array
and of the metadata itself, so a tampered or truncated file is refused with a message saying
what is wrong; so is one whose parts are missing, of the wrong type or shape, or not finite
(every problem at once, as :class:`ModelFileError`). Loading gives back a
:class:`ReducedModel` equal bit for bit.

``.mat`` holds the real block form ready for MATLAB's ``ss(A, B, C, D)``: the inputs are
[r; ṙ] (displacements, then velocities), so B = [B_r, 0] and D = [D_r, E].

Reading either checks the file before it allocates what the file asks for
(at most ``max_bytes``, :data:`MAX_MODEL_FILE_BYTES` unless a caller asks for less; .npz
members stored uncompressed and no larger than the file, each array's kind and shape from its
.npy header, no object arrays; a .mat's variables from their headers: savemat compresses them,
and the full linear model's sparse A 80 to 150 times, so only the limit bounds what a small
.mat may ask for), and every failure is a :class:`ModelFileError`.
Writing goes through :func:`tire_fmu.publish.published_file`: a file in place is a whole
export, the previous one until the new one is complete.
"""

from __future__ import annotations

import hashlib
import json
import math
import zipfile
import zlib
from dataclasses import asdict, fields
from pathlib import Path

import numpy as np

from .core.contact import RoadWindows
from .core.io_model import OUTPUT_UNITS
from .core.io_model import OUTPUTS as OUTPUT_NAMES
from .core.parameters import ParameterError
from .core.reduction import ErrorReport, ReducedModel, ReductionRecord, ReductionSettings
from .file_checks import FileContentError, load_json
from .publish import published_file

FORMAT = "tire_fmu.reduced-model/2"
ARRAYS = ("eigenvalues", "b", "c", "d", "e", "road_window_early_s", "road_window_late_s")
#: dtype kind of each array ("c" complex, "f" real) and its shape in terms of k modes,
#: m inputs (the rim and g road groups), g road groups and p outputs
_ARRAY_SHAPES = {"eigenvalues": ("c", "k"), "b": ("c", "km"), "c": ("c", "pk"),
                 "d": ("f", "pm"), "e": ("f", "pm"), "road_window_early_s": ("f", "g"),
                 "road_window_late_s": ("f", "g")}


#: The most a model file may expand to in memory (bytes), its arrays and metadata together.
#: The full in-plane linear model has about 6 states per element (627 at N = 100, 1230 at
#: N = 200: ``tire-fmu inplane-reduce --elements N``), so at the finest mesh (1600) its A
#: alone takes about 0.8 GB; no file this package writes comes near the limit.
MAX_MODEL_FILE_BYTES = 2**31
#: The metadata's JSON (characters); a model's, its report's pairs included, is a few tens of
#: kilobytes.
MAX_METADATA_CHARS = 10**7


#: The dtypes a model file's arrays are written with, by kind (exactly: no float16, no
#: big-endian, whose checksums a forger could recompute as well).
_DTYPES = {"c": np.dtype(np.complex128), "f": np.dtype(np.float64)}


class ModelFileError(FileContentError):
    """A model file that cannot be trusted: wrong format, missing parts, failed checksum."""


def _checksum(array: np.ndarray) -> str:
    digest = hashlib.sha256()
    digest.update(f"{array.dtype.str}{array.shape}".encode())
    digest.update(np.ascontiguousarray(array).tobytes())
    return digest.hexdigest()


def input_names(reduced: ReducedModel) -> list[str]:
    """rim_z, road_z_0, road_z_1, ...: road group k sees the road at the zone front averaged
    over [road_window_late_s[k], road_window_early_s[k]] ago, then the same names with _vz."""
    names = ["rim_z"] + [f"road_z_{k}" for k in range(reduced.road_windows.early_s.size)]
    return names + [name.replace("_z", "_vz", 1) for name in names]


def metadata(reduced: ReducedModel) -> dict:
    return {
        "format": FORMAT,
        "description": "Reduced in-plane ring tire (tire_fmu): q' = diag(eigenvalues) q + b r, "
        "y = Re(c q) + d r + e r', r = [rim_z, road_z_k = road height at the front of the "
        "contact zone averaged over the window [t - road_window_late_s[k], t - "
        "road_window_early_s[k]]] in m; outputs are deviations from static_outputs",
        "outputs": list(reduced.output_names),
        "output_units": [OUTPUT_UNITS[name] for name in reduced.output_names],
        "inputs": input_names(reduced),
        "road_window_early_s": reduced.road_windows.early_s.tolist(),
        "road_window_late_s": reduced.road_windows.late_s.tolist(),
        "road_front_m": reduced.road_windows.front_m,
        "static_outputs": reduced.static_outputs,
        "settings": asdict(reduced.settings),
        "report": reduced.report.to_dict() if reduced.report else None,
        "model": reduced.metadata.to_dict() if reduced.metadata else None,
    }


def _metadata_checksum(meta: dict) -> str:
    """SHA-256 of the metadata as JSON with sorted keys (which JSON reads back exactly)."""
    text = json.dumps(meta, allow_nan=True, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def save_npz(reduced: ReducedModel, path) -> Path:
    arrays = {name: np.asarray(getattr(reduced, name)) for name in ARRAYS[:5]}
    arrays["road_window_early_s"] = np.asarray(reduced.road_windows.early_s)
    arrays["road_window_late_s"] = np.asarray(reduced.road_windows.late_s)
    return _write_checked(Path(path), metadata(reduced), arrays)


def _npz_arrays(path: Path, names: tuple[str, ...], max_bytes: int) -> dict[str, np.ndarray]:
    """The arrays ``names`` of the .npz at ``path``, each checked in the zip directory and its
    .npy header before a byte of it is allocated (stored, not compressed: a model file is
    written by np.savez; no larger than the file; of a plain dtype; of the size its header
    says), every other member refused; ModelFileError names what is wrong."""
    try:
        file_bytes = path.stat().st_size
        with zipfile.ZipFile(path) as archive:
            members = archive.infolist()
            problems = _member_problems(members, names, file_bytes, max_bytes)
            if problems:
                raise ModelFileError(f"{path}: not a model file as np.savez writes it: "
                                     + "; ".join(problems))
            return {member.filename[:-4]: _npy_array(path, archive, member)
                    for member in members}
    except ModelFileError:
        raise
    except (OSError, ValueError, EOFError, RuntimeError, NotImplementedError, zlib.error,
            zipfile.BadZipFile) as error:  # a damaged zip (RuntimeError: an encrypted one)
        raise ModelFileError(f"{path}: not a readable .npz model file ({error})") from error


def _member_problems(members: list, names: tuple[str, ...], file_bytes: int,
                     max_bytes: int) -> list[str]:
    """What the zip directory says that makes the archive no model file (before reading)."""
    problems = []
    listed = [member.filename for member in members]
    wanted = {f"{name}.npy" for name in names}
    missing = [name for name in names if f"{name}.npy" not in listed]
    if missing:
        problems.append(f"incomplete model file, missing {missing}")
    extra = sorted(set(listed) - wanted)
    if extra:
        problems.append(f"it holds {extra[:5]}, which a model file does not")
    if len(set(listed)) != len(listed):
        problems.append("a member is listed twice")
    for member in members:
        if member.compress_type != zipfile.ZIP_STORED:
            problems.append(f"member {member.filename!r} is compressed: a model file's are "
                            "stored (np.savez), so that none expands beyond the file's size")
        elif not (member.file_size == member.compress_size
                  and member.header_offset + member.compress_size <= file_bytes):
            problems.append(f"member {member.filename!r} says it holds {member.file_size} "
                            f"bytes, more than the file's {file_bytes}")
    total = sum(member.file_size for member in members)
    if total > max_bytes:
        problems.append(f"its members hold {total} bytes, more than the {max_bytes} a model "
                        "file may take")
    return problems


def _npy_array(path: Path, archive: zipfile.ZipFile, member: zipfile.ZipInfo) -> np.ndarray:
    """One member's array, read into memory of the size its header states once that size is
    checked against the member's own."""
    where = f"{path}: member {member.filename!r}"
    with archive.open(member) as stream:
        version = np.lib.format.read_magic(stream)
        if version not in ((1, 0), (2, 0)):
            raise ModelFileError(f"{where}: .npy format version {version}, expected 1.0 "
                                 "or 2.0")
        read_header = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                       else np.lib.format.read_array_header_2_0)
        shape, fortran, dtype = read_header(stream)
        if dtype.hasobject or dtype.fields is not None or dtype.kind not in "fcU":
            raise ModelFileError(f"{where} is an array of {dtype}: a model file holds real, "
                                 "complex or text arrays only (no objects, no pickles)")
        size = dtype.itemsize * math.prod(shape)
        if size != member.file_size - stream.tell():
            raise ModelFileError(f"{where}: its header says {shape} of {dtype} ({size} "
                                 f"bytes), it holds {member.file_size - stream.tell()}")
        data = bytearray(size)
        view, done = memoryview(data), 0
        while done < size:  # in pieces: never a second copy of the whole member
            got = stream.readinto(view[done:done + _READ_CHUNK])
            if not got:
                raise ModelFileError(f"{where} is cut short")
            done += got
    return np.frombuffer(data, dtype).reshape(shape, order="F" if fortran else "C")


_READ_CHUNK = 1 << 24


def _read_checked(path: Path, arrays: tuple[str, ...], fmt: str,
                  max_bytes: int) -> tuple[dict, dict]:
    """(metadata, arrays) of a model .npz of format ``fmt`` whose checksums hold."""
    contents = _npz_arrays(path, ("metadata",) + arrays, max_bytes)
    text = contents["metadata"]
    if text.dtype.kind != "U" or text.shape != ():
        raise ModelFileError(f"{path}: its metadata is {text.dtype} of shape {text.shape}, "
                             "must be one string of JSON")
    meta = load_json(str(text), str(path), "its metadata", MAX_METADATA_CHARS, ModelFileError)
    if not isinstance(meta, dict):
        raise ModelFileError(f"{path}: metadata is {type(meta).__name__}, not a JSON object")
    if meta.get("format") != fmt:
        family = fmt.rsplit("/", 1)[0] + "/"
        raise ModelFileError(f"{path}: format {meta.get('format')!r}, expected {fmt!r}"
                             + ("; export it again" if str(meta.get("format", "")).startswith(
                                 family) else ""))
    checksums = meta.pop("checksums", None)
    if not isinstance(checksums, dict):
        raise ModelFileError(f"{path}: the metadata has no checksums")
    changed = [f"array {name!r}" for name in arrays
               if checksums.get(name) != _checksum(contents[name])]
    if checksums.get("metadata") != _metadata_checksum(meta):
        changed.append("the metadata")
    if changed:
        verb = "does not match its checksum" if len(changed) == 1 else \
            "do not match their checksums"
        raise ModelFileError(f"{path}: {' and '.join(changed)} {verb}; the file was changed "
                             "after export")
    return meta, contents


def _write_checked(path: Path, meta: dict, arrays: dict[str, np.ndarray]) -> Path:
    """A model .npz: the arrays and the metadata with every part's checksum."""
    meta = json.loads(json.dumps(meta, allow_nan=True))  # as it will read back
    checksums = {name: _checksum(array) for name, array in arrays.items()}
    checksums["metadata"] = _metadata_checksum(meta)
    text = json.dumps({**meta, "checksums": checksums}, allow_nan=True, sort_keys=True)
    with published_file(path) as partial, partial.open("wb") as handle:
        np.savez(handle, metadata=np.array(text), **arrays)
    return path


def load_npz(path, max_bytes: int = MAX_MODEL_FILE_BYTES) -> ReducedModel:
    """The reduced model saved by :func:`save_npz`, refused before loading when it would take
    more than ``max_bytes``; ModelFileError names everything wrong."""
    path = Path(path)
    meta, contents = _read_checked(path, ARRAYS, FORMAT, max_bytes)
    problems = _contents_problems(meta, contents)
    if problems:
        raise ModelFileError(f"{path}: not a consistent model file: " + "; ".join(problems))
    try:
        known = {f.name for f in fields(ReductionSettings)}
        settings_values = {k: v for k, v in meta["settings"].items() if k in known}
        former = meta["settings"].get("contribution_threshold")
        if former is not None and settings_values.get("method") == "modal":
            # written before target_error applied to modal truncation: this was its budget
            settings_values["target_error"] = former
        settings_values["error_band_hz"] = tuple(settings_values["error_band_hz"])
        settings = ReductionSettings(**settings_values)
        report = meta["report"]
        if report is not None:
            report = ErrorReport(**{**report, "band_hz": tuple(report["band_hz"])})
        metadata_record = ReductionRecord.from_dict(meta["model"]) if meta.get("model") else None
        front_m = float(meta["road_front_m"])
    except (ParameterError, TypeError, KeyError, ValueError, AttributeError, IndexError,
            OverflowError) as error:
        raise ModelFileError(f"{path}: its settings or report cannot be read ({error})") from error
    return ReducedModel(
        eigenvalues=contents["eigenvalues"],
        b=contents["b"],
        c=contents["c"],
        d=contents["d"],
        e=contents["e"],
        road_windows=RoadWindows(contents["road_window_early_s"],
                                 contents["road_window_late_s"], front_m),
        static_outputs={k: float(v) for k, v in meta["static_outputs"].items()},
        settings=settings,
        metadata=metadata_record,
        report=report,
        output_names=tuple(meta["outputs"]),
    )


def _contents_problems(meta: dict, contents: dict) -> list[str]:
    """Every part that is missing, of the wrong type or shape, or not finite."""
    problems = []
    kinds = {"outputs": list, "static_outputs": dict, "settings": dict,
             "road_window_early_s": list, "road_window_late_s": list}
    for key, kind in kinds.items():
        if not isinstance(meta.get(key), kind):
            problems.append(f"metadata {key!r} is {type(meta.get(key)).__name__}, must be "
                            f"{kind.__name__}")
    for key in ("report", "model"):
        if not (meta.get(key) is None or isinstance(meta[key], dict)):
            problems.append(f"metadata {key!r} is {type(meta[key]).__name__}, must be "
                            "an object or null")
    front = meta.get("road_front_m")
    if not (isinstance(front, (int, float)) and not isinstance(front, bool)
            and math.isfinite(front)):
        problems.append(f"metadata 'road_front_m' is {front!r}, must be a finite number")
    if problems:
        return problems
    outputs = meta["outputs"]
    if outputs != list(OUTPUT_NAMES):
        problems.append(f"outputs {outputs!r}: must be {list(OUTPUT_NAMES)}")
    statics = meta["static_outputs"]
    if sorted(statics) != sorted(OUTPUT_NAMES) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in statics.values()):
        problems.append(f"static_outputs {statics!r}: must give a finite number for each of "
                        f"{list(OUTPUT_NAMES)}")
    sizes = {}
    for name, (kind, axes) in _ARRAY_SHAPES.items():
        array = contents[name]
        if array.dtype != _DTYPES[kind] or array.ndim != len(axes):
            problems.append(f"array {name!r} is {array.dtype} with {array.ndim} dimension(s), "
                            f"must be {'complex' if kind == 'c' else 'real'} with {len(axes)}")
            continue
        if not np.all(np.isfinite(array)):
            problems.append(f"array {name!r} holds values that are not finite")
        for axis, size in zip(axes, array.shape):
            if sizes.setdefault(axis, (size, name))[0] != size:
                problems.append(f"array {name!r} has {size} along {axis!r} where "
                                f"{sizes[axis][1]!r} has {sizes[axis][0]}")
    if "p" in sizes and sizes["p"][0] != len(OUTPUT_NAMES):
        problems.append(f"{sizes['p'][0]} outputs in the arrays, {len(OUTPUT_NAMES)} named")
    if "g" in sizes and "m" in sizes and sizes["m"][0] != sizes["g"][0] + 1:
        problems.append(f"{sizes['m'][0]} inputs in the arrays for {sizes['g'][0]} road "
                        "windows: must be one more (the rim)")
    for name in ("road_window_early_s", "road_window_late_s"):
        if meta[name] != contents[name].tolist():
            problems.append(f"metadata {name!r} differs from the array")
    return problems


def state_space_matrices(reduced: ReducedModel) -> dict[str, np.ndarray]:
    """Real (A, B, C, D) with inputs [r; ṙ], ready for ``ss()``."""
    a, b, c, d, e = reduced.real_form()
    return {
        "A": a,
        "B": np.hstack([b, np.zeros_like(b)]),
        "C": c,
        "D": np.hstack([d, e]),
    }


def _write_mat(path: Path, variables: dict) -> None:
    """A .mat file (compressed, vectors as columns), published whole (to an open handle:
    savemat would add .mat to a name without it)."""
    import scipy.io

    with published_file(path) as partial, partial.open("wb") as handle:
        scipy.io.savemat(handle, variables, do_compression=True, oned_as="column")


def save_mat(reduced: ReducedModel, path) -> Path:
    path = Path(path)
    names_in = input_names(reduced)
    mats = state_space_matrices(reduced)
    meta = metadata(reduced)
    variables = {
        **mats,
        "input_names": np.array(names_in, dtype=object),
        "output_names": np.array(list(OUTPUT_NAMES), dtype=object),
        "static_outputs": np.array([reduced.static_outputs[n] for n in OUTPUT_NAMES]),
        "road_window_early_s": reduced.road_windows.early_s,
        "road_window_late_s": reduced.road_windows.late_s,
        "metadata_json": json.dumps(meta, allow_nan=True),
    }
    _write_mat(path, variables)
    return path


def load_mat(path, max_bytes: int = MAX_MODEL_FILE_BYTES) -> dict:
    """The matrices and metadata of a .mat export (for round-trip checks and scripts): real
    finite A, B, C, D of fitting shapes and the metadata of either format, refused before
    loading when they would take more than ``max_bytes``; ModelFileError names everything
    wrong."""
    import scipy.io

    path = Path(path)
    wanted = {"A": "double", "B": "double", "C": "double", "D": "double",
              "metadata_json": "char"}
    try:
        file_bytes = path.stat().st_size
        listed = {name: (shape, kind)  # chars_as_strings=False: the text's length too
                  for name, shape, kind in scipy.io.whosmat(path, chars_as_strings=False)}
    except OSError as error:
        raise ModelFileError(f"{path}: cannot be read: {error.strerror or error}") from error
    except Exception as error:  # scipy's reader raises a dozen types on a damaged file
        raise ModelFileError(f"{path}: not a readable .mat file ({type(error).__name__}: "
                             f"{error})") from error
    missing = [name for name in wanted if name not in listed]
    if missing:
        raise ModelFileError(f"{path}: incomplete model file, missing {missing}")
    problems = [f"{name} is {listed[name][1]}, must be {kind}" for name, kind in wanted.items()
                if listed[name][1] != kind or len(listed[name][0]) != 2]
    # what loading them takes (8 bytes a double, 4 a character)
    needed = sum(math.prod(listed[name][0]) * (4 if kind == "char" else 8)
                 for name, kind in wanted.items())
    if needed > max_bytes:
        problems.append(f"its {file_bytes} bytes expand to {needed}, more than the {max_bytes} "
                        "a model file may take")
    if problems:
        raise ModelFileError(f"{path}: not a model file as save_mat writes it: "
                             + "; ".join(problems))
    try:
        data = scipy.io.loadmat(path, squeeze_me=False, variable_names=list(wanted))
    except Exception as error:  # as whosmat's
        raise ModelFileError(f"{path}: not a readable .mat file ({type(error).__name__}: "
                             f"{error})") from error
    text = data["metadata_json"]
    meta = load_json(str(np.squeeze(text)) if text.size == 1 else "".join(
        np.ravel(text).astype(str)), str(path), "its metadata_json", MAX_METADATA_CHARS,
        ModelFileError)
    matrices = {name: data[name] for name in "ABCD"}
    problems = _mat_problems(meta, matrices)
    if problems:
        raise ModelFileError(f"{path}: not a consistent model file: " + "; ".join(problems))
    return {**matrices, "metadata": meta}


def _mat_problems(meta, matrices: dict[str, np.ndarray]) -> list[str]:
    """Every matrix not real, finite or of a shape that fits the others, and metadata that is
    no export's."""
    problems = []
    if not isinstance(meta, dict) or meta.get("format") not in (FORMAT, INPLANE_FORMAT):
        shown = meta.get("format") if isinstance(meta, dict) else type(meta).__name__
        problems.append(f"metadata format {shown!r}, expected {FORMAT!r} or "
                        f"{INPLANE_FORMAT!r}")
    for name, matrix in matrices.items():
        if matrix.dtype != np.float64 or matrix.ndim != 2:
            problems.append(f"{name} is {matrix.dtype} with {matrix.ndim} dimension(s), must "
                            "be a real matrix")
        elif not np.all(np.isfinite(matrix)):
            problems.append(f"{name} holds values that are not finite")
    if problems:
        return problems
    (n, n_a), (n_b, m), (p, n_c), (p_d, m_d) = (matrices[k].shape for k in "ABCD")
    if not (n == n_a == n_b == n_c and p == p_d and m == m_d):
        problems.append(f"A {n}x{n_a}, B {n_b}x{m}, C {p}x{n_c} and D {p_d}x{m_d} do not fit "
                        "one state space (A square, B and C its rows and columns, D C's rows "
                        "and B's columns)")
    return problems


def to_control(reduced: ReducedModel):
    """A python-control ``StateSpace`` with named inputs [r; ṙ] and outputs."""
    try:
        import control
    except ImportError as error:
        raise ImportError(
            "python-control is not installed: pip install 'tire_fmu[control]'"
        ) from error
    mats = state_space_matrices(reduced)
    return control.ss(
        mats["A"], mats["B"], mats["C"], mats["D"],
        inputs=input_names(reduced),
        outputs=list(OUTPUT_NAMES),
        name="tire_fmu_reduced",
    )


# ----- the in-plane tire's linear model (core.inplane_io) -----

INPLANE_FORMAT = "tire_fmu.inplane-linear/1"
INPLANE_ARRAYS = ("a", "b", "c", "d0", "d1", "d2", "road_delays_s")


def inplane_metadata(model) -> dict:
    from .core.inplane_io import INPUT_UNITS, OUTPUT_UNITS

    return {
        "format": INPLANE_FORMAT,
        "description": "The in-plane ring tire linearised at an operating point (tire_fmu): "
        "z' = a z + b u, y = c z + d0 u + d1 u' + d2 u''; u = [torque (a free wheel's), "
        "rim_x, rim_z, road_0, road_1, ...]: the road under each contact point, the mean of "
        "the road at the contact zone's front over [t - road_delays_s[j, 1], t - "
        "road_delays_s[j, 0]]; deviations from the operating point, SI units; outputs are "
        "deviations from operating_point.static_outputs",
        "inputs": list(model.input_names),
        "input_units": [INPUT_UNITS["road" if name.startswith("road_") else name]
                        for name in model.input_names],
        "outputs": list(model.output_names),
        "output_units": [OUTPUT_UNITS[name] for name in model.output_names],
        "operating_point": model.operating_point,
        "report": model.report,
    }


def save_inplane_npz(model, path) -> Path:
    """An :class:`~tire_fmu.core.inplane_io.InPlaneStateSpace` as plain arrays and JSON
    metadata with checksums (:func:`load_inplane_npz` gives it back bit for bit)."""
    arrays = {name: np.asarray(getattr(model, name), dtype=float) for name in INPLANE_ARRAYS}
    return _write_checked(Path(path), inplane_metadata(model), arrays)


def load_inplane_npz(path, max_bytes: int = MAX_MODEL_FILE_BYTES):
    """The model saved by :func:`save_inplane_npz`, refused before loading when it would take
    more than ``max_bytes``; ModelFileError names everything wrong."""
    from .core.inplane_io import InPlaneStateSpace

    path = Path(path)
    meta, contents = _read_checked(path, INPLANE_ARRAYS, INPLANE_FORMAT, max_bytes)
    problems = _inplane_problems(meta, contents)
    if problems:
        raise ModelFileError(f"{path}: not a consistent model file: " + "; ".join(problems))
    return InPlaneStateSpace(*(contents[name] for name in INPLANE_ARRAYS[:6]),
                             input_names=tuple(meta["inputs"]),
                             output_names=tuple(meta["outputs"]),
                             road_delays_s=contents["road_delays_s"],
                             operating_point=meta["operating_point"], report=meta["report"])


def _inplane_problems(meta: dict, contents: dict) -> list[str]:
    """Every array of the wrong kind, shape or not finite, and names that do not fit them."""
    problems = []
    for key, kind in (("inputs", list), ("outputs", list), ("operating_point", dict),
                      ("report", dict)):
        if not isinstance(meta.get(key), kind):
            problems.append(f"metadata {key!r} is {type(meta.get(key)).__name__}, must be "
                            f"{kind.__name__}")
    for key in ("inputs", "outputs"):
        if not all(isinstance(name, str) for name in meta[key]):
            problems.append(f"metadata {key!r} must be a list of names (strings)")
    if problems:
        return problems
    n_in, n_out = len(meta["inputs"]), len(meta["outputs"])
    n = contents["a"].shape[0] if contents["a"].ndim == 2 else -1
    roads = sum(str(name).startswith("road_") for name in meta["inputs"])
    shapes = {"a": (n, n), "b": (n, n_in), "c": (n_out, n), "d0": (n_out, n_in),
              "d1": (n_out, n_in), "d2": (n_out, n_in), "road_delays_s": (roads, 2)}
    for name, shape in shapes.items():
        array = contents[name]
        if array.dtype != np.float64 or array.shape != shape:
            problems.append(f"array {name!r} is {array.dtype} of shape {array.shape}, must be "
                            f"real of shape {shape}")
        elif not np.all(np.isfinite(array)):
            problems.append(f"array {name!r} holds values that are not finite")
    return problems


def save_inplane_mat(model, path) -> Path:
    """Real (A, B, C, D) for MATLAB's ss(A, B, C, D) with inputs [u; u'; u''] (B = [b, 0,
    0], D = [d0, d1, d2]), the names, the road's delays and the metadata as JSON."""
    path = Path(path)
    zeros = np.zeros_like(model.b)
    _write_mat(path, {
        "A": model.a, "B": np.hstack([model.b, zeros, zeros]), "C": model.c,
        "D": np.hstack([model.d0, model.d1, model.d2]),
        "input_names": np.array([f"{name}{suffix}" for suffix in ("", "_rate", "_accel")
                                 for name in model.input_names], dtype=object),
        "output_names": np.array(list(model.output_names), dtype=object),
        "static_outputs": np.array([model.operating_point["static_outputs"][name]
                                    for name in model.output_names]),
        "road_delays_s": model.road_delays_s,
        "metadata_json": json.dumps(inplane_metadata(model), allow_nan=True)})
    return path
