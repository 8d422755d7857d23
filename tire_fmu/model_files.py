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
"""

from __future__ import annotations

import hashlib
import json
import math
import zipfile
from dataclasses import asdict, fields
from pathlib import Path

import numpy as np

from .core.contact import RoadWindows
from .core.io_model import OUTPUT_UNITS
from .core.io_model import OUTPUTS as OUTPUT_NAMES
from .core.parameters import ParameterError
from .core.reduction import ErrorReport, ReducedModel, ReductionRecord, ReductionSettings

FORMAT = "tire_fmu.reduced-model/2"
ARRAYS = ("eigenvalues", "b", "c", "d", "e", "road_window_early_s", "road_window_late_s")
#: dtype kind of each array ("c" complex, "f" real) and its shape in terms of k modes,
#: m inputs (the rim and g road groups), g road groups and p outputs
_ARRAY_SHAPES = {"eigenvalues": ("c", "k"), "b": ("c", "km"), "c": ("c", "pk"),
                 "d": ("f", "pm"), "e": ("f", "pm"), "road_window_early_s": ("f", "g"),
                 "road_window_late_s": ("f", "g")}


class ModelFileError(ValueError):
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


def _read_checked(path: Path, arrays: tuple[str, ...], fmt: str) -> tuple[dict, dict]:
    """(metadata, arrays) of a model .npz of format ``fmt`` whose checksums hold."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            contents = {name: archive[name] for name in archive.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        raise ModelFileError(f"{path}: not a readable .npz model file ({error})") from error
    missing = [name for name in ("metadata",) + arrays if name not in contents]
    if missing:
        raise ModelFileError(f"{path}: incomplete model file, missing {missing}")
    try:
        meta = json.loads(str(contents["metadata"]))
    except json.JSONDecodeError as error:
        raise ModelFileError(f"{path}: metadata is not valid JSON ({error})") from error
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
    with path.open("wb") as handle:
        np.savez(handle, metadata=np.array(text), **arrays)
    return path


def load_npz(path) -> ReducedModel:
    """The reduced model saved by :func:`save_npz`; ModelFileError names everything wrong."""
    path = Path(path)
    meta, contents = _read_checked(path, ARRAYS, FORMAT)
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
    except (ParameterError, TypeError, KeyError, ValueError, AttributeError) as error:
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
        if array.dtype.kind != kind or array.ndim != len(axes):
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


def save_mat(reduced: ReducedModel, path) -> Path:
    import scipy.io

    path = Path(path)
    names_in = input_names(reduced)
    mats = state_space_matrices(reduced)
    meta = metadata(reduced)
    scipy.io.savemat(
        path,
        {
            **mats,
            "input_names": np.array(names_in, dtype=object),
            "output_names": np.array(list(OUTPUT_NAMES), dtype=object),
            "static_outputs": np.array([reduced.static_outputs[n] for n in OUTPUT_NAMES]),
            "road_window_early_s": reduced.road_windows.early_s,
            "road_window_late_s": reduced.road_windows.late_s,
            "metadata_json": json.dumps(meta, allow_nan=True),
        },
        do_compression=True,
        oned_as="column",
    )
    return path


def load_mat(path) -> dict:
    """The matrices and metadata of a .mat export (for round-trip checks and scripts)."""
    import scipy.io

    path = Path(path)
    try:
        data = scipy.io.loadmat(path, squeeze_me=False)
    except (OSError, ValueError) as error:
        raise ModelFileError(f"{path}: not a readable .mat file ({error})") from error
    missing = [k for k in ("A", "B", "C", "D", "metadata_json") if k not in data]
    if missing:
        raise ModelFileError(f"{path}: incomplete model file, missing {missing}")
    meta = json.loads(str(np.squeeze(data["metadata_json"])))
    return {"A": data["A"], "B": data["B"], "C": data["C"], "D": data["D"], "metadata": meta}


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


def load_inplane_npz(path):
    """The model saved by :func:`save_inplane_npz`; ModelFileError names everything wrong."""
    from .core.inplane_io import InPlaneStateSpace

    path = Path(path)
    meta, contents = _read_checked(path, INPLANE_ARRAYS, INPLANE_FORMAT)
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
    if problems:
        return problems
    n_in, n_out = len(meta["inputs"]), len(meta["outputs"])
    n = contents["a"].shape[0] if contents["a"].ndim == 2 else -1
    roads = sum(str(name).startswith("road_") for name in meta["inputs"])
    shapes = {"a": (n, n), "b": (n, n_in), "c": (n_out, n), "d0": (n_out, n_in),
              "d1": (n_out, n_in), "d2": (n_out, n_in), "road_delays_s": (roads, 2)}
    for name, shape in shapes.items():
        array = contents[name]
        if array.dtype.kind != "f" or array.shape != shape:
            problems.append(f"array {name!r} is {array.dtype} of shape {array.shape}, must be "
                            f"real of shape {shape}")
        elif not np.all(np.isfinite(array)):
            problems.append(f"array {name!r} holds values that are not finite")
    return problems


def save_inplane_mat(model, path) -> Path:
    """Real (A, B, C, D) for MATLAB's ss(A, B, C, D) with inputs [u; u'; u''] (B = [b, 0,
    0], D = [d0, d1, d2]), the names, the road's delays and the metadata as JSON."""
    import scipy.io

    path = Path(path)
    zeros = np.zeros_like(model.b)
    scipy.io.savemat(
        path,
        {"A": model.a, "B": np.hstack([model.b, zeros, zeros]), "C": model.c,
         "D": np.hstack([model.d0, model.d1, model.d2]),
         "input_names": np.array([f"{name}{suffix}" for suffix in ("", "_rate", "_accel")
                                  for name in model.input_names], dtype=object),
         "output_names": np.array(list(model.output_names), dtype=object),
         "static_outputs": np.array([model.operating_point["static_outputs"][name]
                                     for name in model.output_names]),
         "road_delays_s": model.road_delays_s,
         "metadata_json": json.dumps(inplane_metadata(model), allow_nan=True)},
        do_compression=True, oned_as="column")
    return path
