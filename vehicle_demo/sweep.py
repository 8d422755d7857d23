"""Design-of-experiments sweeps of the co-simulated quarter car, run with dask.

A point is a dict of factor values. Factors are any TireModal.fmu parameter (``speed``,
``inflation_pressure``, ``n_elements``, tire data ...), any quarter-car field
(``body_mass_kg`` ...), or ``load``: the static tire load, which sets the body mass to
load/g - m_w so the car starts in equilibrium (the tire FMU's ``load`` always equals the car's
weight). Each point runs one co-simulated multisine, identifies body bounce and wheel hop
(poles) and the lowest tire mode (the first prominent peak of road -> rim load above 25 Hz),
and beside them the reference values of the car on the full tire model.

Execution follows fmpy's ``parameter_variation`` example (one task per point, the FMUs
extracted once per worker process): ``scheduler="synchronous"`` runs in this process,
``"processes"`` on dask's local multiprocessing scheduler, ``"auto"`` (default) picks between
the two (:func:`pick_scheduler`), and an ``address`` sends the points to a
``dask.distributed`` scheduler. Workers of a cluster need not see the client's files: the
FMUs travel as bytes (:class:`FmuBundle`), sent once to every worker and written once into
each worker's own folder. A point that fails is a row with ``status = "failed"`` and its
error, never dropped.
"""

from __future__ import annotations

import hashlib
import io
import itertools
import math
import os
import tempfile
import time
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from xml.etree import ElementTree

from .cosim import CoSimError, FmuPaths, QuarterCarCoSimulation
from .quarter_car import QuarterCarParameters
from .transfer import Multisine

RESULT_COLUMNS = (
    "status", "error", "body_bounce_hz", "body_bounce_zeta", "wheel_hop_hz", "wheel_hop_zeta",
    "tire_mode_hz", "tire_mode_gain_n_per_m", "body_acc_peak_gain", "contact_lost_fraction",
    "ref_body_bounce_hz", "ref_wheel_hop_hz", "ref_tire_mode_hz", "static_stiffness_n_per_m",
    "seconds",
)
#: Parameters of TireModal.fmu a sweep may set besides ``load`` (read from the FMU too).
_OPERATING = ("speed", "n_elements", "allow_supercritical")
_REDUCTION = ("f_max", "n_modes", "static_correction")


SCHEDULERS = ("auto", "synchronous", "processes")


class SweepError(ValueError):
    """A sweep that cannot run as given (the message says what to change)."""


@dataclass(frozen=True)
class SweepSettings:
    """What each point runs: a short multisine co-simulation."""

    excitation: Multisine = field(default_factory=lambda: Multisine(
        period_s=2.0, settle_periods=1, average_periods=2, rms_velocity_m_s=0.005))
    step_s: float = 1e-4
    n_elements: int = 60  # unless a factor sets it
    car: QuarterCarParameters = field(default_factory=QuarterCarParameters)
    reference: bool = True  # also the car on the full tire model


@dataclass(frozen=True, eq=False)
class FmuBundle:
    """The two FMUs as bytes, to run where the files are not (a cluster's workers).

    ``digest`` names the content: a worker writes a bundle to disk once, into its own folder,
    and reuses the files for every later point (:meth:`paths`)."""

    tire_name: str
    tire: bytes
    quarter_car_name: str
    quarter_car: bytes
    digest: str

    @classmethod
    def from_paths(cls, fmus: FmuPaths) -> FmuBundle:
        tire, car = Path(fmus.tire).read_bytes(), Path(fmus.quarter_car).read_bytes()
        digest = hashlib.sha256(tire + b"\0" + car).hexdigest()[:16]
        return cls(Path(fmus.tire).name, tire, Path(fmus.quarter_car).name, car, digest)

    def parameter_names(self) -> list[str]:
        """The tire FMU's parameters, read from its model description in the bytes."""
        with zipfile.ZipFile(io.BytesIO(self.tire)) as archive:
            root = ElementTree.fromstring(archive.read("modelDescription.xml"))
        return [v.get("name") for v in root.iter("ScalarVariable")
                if v.get("causality") == "parameter"]

    def paths(self, folder: str | Path | None = None) -> FmuPaths:
        """The FMUs as files under ``folder`` (default: this process's worker folder, or the
        temporary folder), written the first time this process asks for this bundle."""
        known = _MATERIALISED.get(self.digest)
        if known is not None and known.tire.is_file() and known.quarter_car.is_file():
            return known
        target = Path(folder or _worker_folder()) / f"tire_fmu_sweep_{self.digest}"
        target.mkdir(parents=True, exist_ok=True)
        paths = FmuPaths(target / self.tire_name, target / self.quarter_car_name)
        for path, data in ((paths.tire, self.tire), (paths.quarter_car, self.quarter_car)):
            if not path.is_file() or path.stat().st_size != len(data):
                staging = path.with_suffix(f".{os.getpid()}.part")
                staging.write_bytes(data)
                staging.replace(path)  # atomic: a concurrent reader never sees half a file
        _MATERIALISED[self.digest] = paths
        return paths


_MATERIALISED: dict[str, FmuPaths] = {}  # per process: bundle digest -> its files


def _worker_folder() -> str:
    try:
        from distributed import get_worker

        return get_worker().local_directory
    except (ImportError, ValueError):  # not inside a dask.distributed worker
        return tempfile.gettempdir()


def run_bundled_point(point: Mapping, bundle: FmuBundle, settings: SweepSettings) -> dict:
    """:func:`run_point` on a worker that has the FMUs as bytes (never raises)."""
    try:
        fmus = bundle.paths()
    except Exception as error:  # noqa: BLE001 -- a worker that cannot write is a failed row
        row = {**dict(point), **{name: math.nan for name in RESULT_COLUMNS}}
        row.update(status="failed", error=f"writing the FMUs on the worker failed: {error}",
                   seconds=0.0)
        return row
    return run_point(point, fmus, settings)


def full_factorial(factors: Mapping[str, Sequence]) -> list[dict]:
    """Every combination of the factor levels, the last factor varying fastest."""
    names = list(factors)
    return [dict(zip(names, values)) for values in itertools.product(*factors.values())]


def check_factors(points: Sequence[Mapping], tire_parameter_names: Sequence[str]) -> None:
    """Raise SweepError naming every unknown factor."""
    car_fields = {f.name for f in fields(QuarterCarParameters)}
    known = {"load"} | set(tire_parameter_names) | car_fields
    unknown = sorted({name for point in points for name in point} - known)
    if unknown:
        raise SweepError(f"unknown sweep factor(s) {unknown}; known: load, "
                         f"{', '.join(sorted(set(tire_parameter_names) - {'load'}))}, "
                         f"{', '.join(sorted(car_fields))}")


def _split(point: Mapping, settings: SweepSettings) -> tuple[QuarterCarParameters, dict]:
    car_fields = {f.name for f in fields(QuarterCarParameters)}
    car = replace(settings.car, **{k: v for k, v in point.items() if k in car_fields})
    if "load" in point:
        car = car.with_static_load(float(point["load"]))
    tire = {"n_elements": settings.n_elements}
    tire.update({k: v for k, v in point.items() if k not in car_fields and k != "load"})
    return car, tire


def run_point(point: Mapping, fmus: FmuPaths, settings: SweepSettings) -> dict:
    """One point: its factors, then :data:`RESULT_COLUMNS`. Never raises."""
    started = time.perf_counter()
    row = dict(point)
    row.update({name: math.nan for name in RESULT_COLUMNS})
    try:
        row.update(_measure(point, fmus, settings))
        row["status"], row["error"] = "ok", ""
    except Exception as error:  # noqa: BLE001 -- every failure becomes a recorded row
        row["status"], row["error"] = "failed", f"{type(error).__name__}: {error}"
    row["seconds"] = time.perf_counter() - started
    return row


def _measure(point: Mapping, fmus: FmuPaths, settings: SweepSettings) -> dict:
    from .transfer import estimate_frf, identify_body_and_wheel, ride_outputs, tire_mode_peaks

    car, tire = _split(point, settings)
    excitation = settings.excitation
    _, height, velocity = excitation.road(settings.step_s)
    with QuarterCarCoSimulation(fmus, car, tire, settings.step_s) as sim:
        result = sim.run(height, velocity)
    estimate = estimate_frf(height, ride_outputs(result), excitation, settings.step_s)
    body, wheel = identify_body_and_wheel(estimate.freqs_hz, estimate.h1["body_acc"],
                                          estimate.h1["wheel_acc"],
                                          estimate.coherence["wheel_acc"])
    peaks = _lowest(tire_mode_peaks(estimate.freqs_hz, estimate.h1["rim_load"]))
    out = {
        "body_bounce_hz": body.frequency_hz, "body_bounce_zeta": body.damping_ratio,
        "wheel_hop_hz": wheel.frequency_hz, "wheel_hop_zeta": wheel.damping_ratio,
        "tire_mode_hz": peaks[0][0] if peaks else math.nan,
        "tire_mode_gain_n_per_m": peaks[0][1] if peaks else math.nan,
        "body_acc_peak_gain": float(abs(estimate.h1["body_acc"]).max()),
        "contact_lost_fraction": result.contact_lost_fraction,
    }
    if settings.reference:
        out.update(_reference(car, tire, estimate.freqs_hz))
    return out


def _lowest(peaks: list) -> list:
    """The lowest of the prominent rim-load peaks (a list of one, or empty): the ring's
    n = 0/1 family, which follows load and pressure steadily, where the strongest peak jumps
    between it and the sidewall band near 168 Hz."""
    return [min(peaks, key=lambda p: p[0])] if peaks else []


def _reference(car: QuarterCarParameters, tire: Mapping, freqs_hz) -> dict:
    from tire_fmu.core import OperatingPoint, TireParameters, build_model

    from .quarter_car import full_tire_two_port, quarter_car_modes, ride_response
    from .transfer import tire_mode_peaks

    tire_data = {f.name: tire[f.name] for f in fields(TireParameters) if f.name in tire}
    op = OperatingPoint(n_elements=int(tire.get("n_elements", 100)),
                        load_n=car.static_tire_load_n,
                        speed_m_s=float(tire.get("speed", 0.0)),
                        allow_supercritical=bool(tire.get("allow_supercritical", False)))
    model = build_model(TireParameters(**tire_data), op)
    modes = quarter_car_modes(car, model)
    ride = ride_response(car, full_tire_two_port(model, freqs_hz))
    peaks = _lowest(tire_mode_peaks(freqs_hz, ride["rim_load"]))
    return {"ref_body_bounce_hz": modes.body_bounce.frequency_hz,
            "ref_wheel_hop_hz": modes.wheel_hop.frequency_hz,
            "ref_tire_mode_hz": peaks[0][0] if peaks else math.nan,
            "static_stiffness_n_per_m": model.static_vertical_stiffness_n_per_m}


@dataclass(frozen=True, eq=False)
class SweepResult:
    table: object  # pandas.DataFrame: factors, then RESULT_COLUMNS, in point order
    factors: tuple[str, ...]
    scheduler: str
    wall_s: float

    @property
    def points_per_minute(self) -> float:
        return 60.0 * len(self.table) / self.wall_s if self.wall_s > 0 else math.nan

    @property
    def failed(self):
        return self.table[self.table["status"] != "ok"]


class _SingleThreadBlas:
    """Worker processes inherit this environment: one BLAS thread each, so that two workers
    on two cores do not oversubscribe them (OpenBLAS's threads then spin against each other
    and small dense eigenproblems get ten times slower)."""

    names = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")

    def __enter__(self):
        self.saved = {n: os.environ.get(n) for n in self.names}
        for n in self.names:
            os.environ[n] = "1"

    def __exit__(self, *exc):
        for n, value in self.saved.items():
            if value is None:
                os.environ.pop(n, None)
            else:
                os.environ[n] = value


def run_sweep(points: Sequence[Mapping], fmus: FmuPaths | FmuBundle,
              settings: SweepSettings | None = None, scheduler: str = "auto",
              address: str | None = None, n_workers: int = 2,
              progress: bool = True) -> SweepResult:
    """Run every point; rows come back in point order whatever order they finished in.

    ``fmus``: the FMU files, or their bytes (:class:`FmuBundle`). ``scheduler``:
    ``"synchronous"`` (this process, one point after another), ``"processes"`` (dask's local
    scheduler with ``n_workers`` processes) or ``"auto"`` (:func:`pick_scheduler`);
    ``address`` (``"tcp://host:port"`` or a ``LocalCluster``'s ``scheduler_address``)
    overrides it with a distributed cluster, whose workers get the FMUs as bytes.
    """
    import pandas as pd

    settings = settings or SweepSettings()
    points = [dict(p) for p in points]
    if not points:
        raise SweepError("the sweep has no points")
    if scheduler not in SCHEDULERS:
        raise SweepError(f"scheduler = {scheduler!r}: must be one of {SCHEDULERS} (or give an "
                         "address)")
    bundle = fmus if isinstance(fmus, FmuBundle) else None
    if address is not None and bundle is None:
        bundle = FmuBundle.from_paths(fmus)  # read before anything runs
    if bundle is not None:
        tire_names = bundle.parameter_names()
    else:
        from fmpy import read_model_description

        tire_names = [v.name for v in read_model_description(str(fmus.tire)).modelVariables
                      if v.causality == "parameter"]
    check_factors(points, tire_names)
    started = time.perf_counter()
    if address is None and bundle is not None:
        fmus = bundle.paths()  # local runs read files
    if scheduler == "auto":
        scheduler = pick_scheduler(len(points), n_workers)
    if address is not None:
        rows = _distributed(points, bundle, settings, address, progress)
        used = f"dask.distributed at {address}"
    elif scheduler == "synchronous":
        rows, used = _serial(points, fmus, settings, progress), "synchronous"
    elif scheduler == "processes":
        rows, used = _local(points, fmus, settings, n_workers, progress), \
            f"dask local processes ({n_workers} workers)"
    wall = time.perf_counter() - started
    factors = tuple(dict.fromkeys(name for p in points for name in p))
    table = pd.DataFrame(rows, columns=list(factors) + list(RESULT_COLUMNS))
    return SweepResult(table, factors, used, wall)


def _bar(total: int, enabled: bool, what: str):
    from tqdm.auto import tqdm

    return tqdm(total=total, disable=not enabled, desc=what, unit="point")


def _serial(points, fmus, settings, progress) -> list:
    rows = []
    with _bar(len(points), progress, "sweep (serial)") as bar:
        for point in points:
            rows.append(run_point(point, fmus, settings))
            bar.update(1)
    return rows


def _local(points, fmus, settings, n_workers, progress) -> list:
    import dask
    from dask.callbacks import Callback

    tasks = [dask.delayed(run_point, pure=False)(p, fmus, settings) for p in points]
    keys = {t.key for t in tasks}

    class TqdmCallback(Callback):
        def __init__(self, bar):
            super().__init__()
            self.bar = bar

        def _posttask(self, key, result, dsk, state, worker_id):
            if key in keys:
                self.bar.update(1)

    with _bar(len(points), progress, f"sweep ({n_workers} processes)") as bar, \
            TqdmCallback(bar), _SingleThreadBlas():
        return list(dask.compute(*tasks, scheduler="processes", num_workers=n_workers))


def _distributed(points, bundle: FmuBundle, settings, address, progress) -> list:
    from distributed import Client, as_completed

    with Client(address) as client:
        # the bytes go to every worker once; each task then refers to the worker's copy
        [shipped] = client.scatter([bundle], broadcast=True, hash=False)
        futures = [client.submit(run_bundled_point, p, shipped, settings, pure=False)
                   for p in points]
        with _bar(len(points), progress, "sweep (distributed)") as bar:
            for _ in as_completed(futures):
                bar.update(1)
        return client.gather(futures)


def pick_scheduler(n_points: int, n_workers: int) -> str:
    """``"processes"`` when worker processes can pay for their start-up, else
    ``"synchronous"``: each worker imports numpy, scipy and fmpy and extracts the FMUs (a few
    seconds) before its first point, so parallel runs win only with at least two points per
    worker and a core free for each worker (the load average says how many are busy)."""
    cores = os.cpu_count() or 1
    try:
        busy = os.getloadavg()[0]
    except OSError:  # not available on this platform
        busy = 0.0
    free = cores - busy
    if n_workers < 2 or n_points < 2 * n_workers or free < n_workers - 0.5:
        return "synchronous"
    return "processes"


def local_cluster(n_workers: int = 2, local_directory: str | Path | None = None):
    """A ``dask.distributed.LocalCluster`` of single-threaded worker processes, each with one
    BLAS thread (close it when done); ``local_directory`` is where the workers keep their
    files (the FMUs of a sweep among them)."""
    from distributed import LocalCluster

    extra = {} if local_directory is None else {"local_directory": str(local_directory)}
    with _SingleThreadBlas():
        return LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                            dashboard_address=None, **extra)


def save_table(result: SweepResult, path: str | Path) -> Path:
    """Write the table as CSV or, for a ``.parquet`` path, Parquet (needs pyarrow)."""
    from tire_fmu.publish import published_file

    path = Path(path)
    if path.suffix not in (".csv", ".parquet"):
        raise SweepError(f"{path.name}: the table is written as .csv or .parquet")
    path.parent.mkdir(parents=True, exist_ok=True)
    with published_file(path) as partial:
        if path.suffix == ".parquet":
            try:
                result.table.to_parquet(partial, index=False)
            except ImportError as error:
                raise SweepError(f"writing {path.name} needs a Parquet engine (pip install "
                                 "pyarrow); or write .csv") from error
        else:
            result.table.to_csv(partial, index=False)
    return path


__all__ = ["CoSimError", "FmuBundle", "SweepError", "SweepResult", "SweepSettings",
           "check_factors", "full_factorial", "local_cluster", "pick_scheduler", "run_point",
           "run_sweep", "save_table"]
