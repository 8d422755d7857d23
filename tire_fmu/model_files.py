"""Saving and loading reduced models: .npz (no pickles), MATLAB .mat, python-control.

File formats are an adapter over the physics core (which knows no files), like the CLI and
the FMUs: this module turns a :class:`~tire_fmu.core.reduction.ReducedModel` into files and
back.

``.npz`` holds the diagonal modal form as plain arrays plus a JSON metadata string (tire data,
operating point, settings, error report, names, units) with a SHA-256 checksum of every array,
so a tampered or truncated file is refused with a message saying what is wrong. Loading gives
back a :class:`ReducedModel` equal bit for bit.

``.mat`` holds the real block form ready for MATLAB's ``ss(A, B, C, D)``: the inputs are
[r; ṙ] (displacements, then velocities), so B = [B_r, 0] and D = [D_r, E].
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from dataclasses import asdict, fields
from pathlib import Path

import numpy as np

from .core.contact import RoadWindows
from .core.io_model import OUTPUT_UNITS
from .core.io_model import OUTPUTS as OUTPUT_NAMES
from .core.reduction import ErrorReport, ReducedModel, ReductionRecord, ReductionSettings

FORMAT = "tire_fmu.reduced-model/2"
ARRAYS = ("eigenvalues", "b", "c", "d", "e", "road_window_early_s", "road_window_late_s")


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


def save_npz(reduced: ReducedModel, path) -> Path:
    path = Path(path)
    arrays = {name: np.asarray(getattr(reduced, name)) for name in ARRAYS[:5]}
    arrays["road_window_early_s"] = np.asarray(reduced.road_windows.early_s)
    arrays["road_window_late_s"] = np.asarray(reduced.road_windows.late_s)
    meta = metadata(reduced)
    meta["checksums"] = {name: _checksum(array) for name, array in arrays.items()}
    text = json.dumps(meta, allow_nan=True, sort_keys=True)
    with path.open("wb") as handle:
        np.savez(handle, metadata=np.array(text), **arrays)
    return path


def load_npz(path) -> ReducedModel:
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as archive:
            contents = {name: archive[name] for name in archive.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        raise ModelFileError(f"{path}: not a readable .npz model file ({error})") from error
    missing = [name for name in ("metadata",) + ARRAYS if name not in contents]
    if missing:
        raise ModelFileError(f"{path}: incomplete model file, missing {missing}")
    try:
        meta = json.loads(str(contents["metadata"]))
    except json.JSONDecodeError as error:
        raise ModelFileError(f"{path}: metadata is not valid JSON ({error})") from error
    if meta.get("format") != FORMAT:
        raise ModelFileError(f"{path}: format {meta.get('format')!r}, expected {FORMAT!r}")
    checksums = meta.get("checksums", {})
    for name in ARRAYS:
        if checksums.get(name) != _checksum(contents[name]):
            raise ModelFileError(
                f"{path}: array {name!r} does not match its checksum; the file was changed "
                "after export"
            )
    known = {f.name for f in fields(ReductionSettings)}
    settings_values = {k: v for k, v in meta["settings"].items() if k in known}
    settings_values["error_band_hz"] = tuple(settings_values["error_band_hz"])
    report = meta.get("report")
    if report is not None:
        report = ErrorReport(**{**report, "band_hz": tuple(report["band_hz"])})
    return ReducedModel(
        eigenvalues=contents["eigenvalues"],
        b=contents["b"],
        c=contents["c"],
        d=contents["d"],
        e=contents["e"],
        road_windows=RoadWindows(contents["road_window_early_s"],
                                 contents["road_window_late_s"], float(meta["road_front_m"])),
        static_outputs={k: float(v) for k, v in meta["static_outputs"].items()},
        settings=ReductionSettings(**settings_values),
        metadata=ReductionRecord.from_dict(meta["model"]) if meta.get("model") else None,
        report=report,
        output_names=tuple(meta["outputs"]),
    )


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
