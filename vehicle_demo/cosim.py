"""The master algorithm: the quarter car and the tire as two FMUs stepped by fmpy.

Coupling (default ``"gauss-seidel"``), over each communication step t_k -> t_k + h:

1. the tire gets the wheel state at t_k (``rim_z`` = z_w, ``rim_vz`` = ż_w: it ramps the
   rim with that velocity over the step) and the road at t_k (height and velocity at the
   front of its contact zone), steps, and returns its total rim force F_{k+1};
2. the quarter car gets ``rim_Fz`` = F_k and ``rim_Fz_rate`` = (F_{k+1} - F_k)/h, i.e. the tire
   force linearly interpolated over the step (first-order hold), steps exactly, and returns
   the wheel and body state at t_{k+1}.

The tire goes first because its force has direct feedthrough from rim displacement and
velocity (its structural damping passes ż_rim straight to the rim), whereas the quarter car's
wheel state depends on the force only through an integration: so the ordering never needs the
unknown end-of-step value of a feedthrough output. What remains explicit is the rim motion
the tire assumes over the step (a ramp from the state at t_k): an O(h²) error per step.
``"jacobi"`` steps both from t_k values (force held over the step): first order, for
comparison. :mod:`vehicle_demo.coupling` gives the step-size limit and the error of both.

After each step the master sets the tire's inputs of the new communication point (wheel state
and road) and only then reads its outputs: the tire recomputes its direct feedthrough with
them. That matters for the contact force, whose feedthrough from the road (the contact springs
and dampers of the pushing nodes) nearly cancels its modal part: read with the velocity the
step ramped with, a step old (``read_after_inputs=False``, for comparison), it is off by an
O(h) error; read with the new inputs the error is O(h²) (docs/vehicle_demo.md quotes both from
benchmarks/bench_coupling.py).

Both FMUs start in static equilibrium: the tire's ``load`` is set to the car's weight
(m_b + m_w)·g, which the quarter car subtracts from the total rim force it receives.
"""

from __future__ import annotations

import atexit
import math
import shutil
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .quarter_car import QuarterCarParameters

SCHEMES = ("gauss-seidel", "jacobi")
DEFAULT_STEP_S = 1e-4


class CoSimError(RuntimeError):
    """An FMU refused a call; the message carries what the FMU logged."""


@dataclass(frozen=True)
class FmuPaths:
    tire: Path
    quarter_car: Path


_EXTRACTED: dict[tuple[str, float], str] = {}


def _extracted(path: Path) -> str:
    """Unzip an FMU once per process (and file version); removed when the process ends."""
    from fmpy import extract

    key = (str(Path(path).resolve()), Path(path).stat().st_mtime)
    folder = _EXTRACTED.get(key)
    if folder is None:
        folder = extract(str(path))
        _EXTRACTED[key] = folder
        atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


_STATUS = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING"]


def printed(message: bytes | None) -> str:
    """An FMI log message as printf shows it without arguments: FMI messages are formats
    ("%%" for "%"). fmpy's C proxy that formats them keeps one logger per process, so a
    master with two FMUs, each with its own logger, formats here instead."""
    text = message.decode("utf-8", "replace") if message else ""
    try:
        return text % ()
    except (TypeError, ValueError):  # a conversion without its argument: show it as it is
        return text


def _raw(fmu, name: str):
    """The bare ctypes function fmi2<name>, returning its status: fmpy's wrapper checks and
    logs every call, which costs about a microsecond a call in a loop of seven calls a step;
    the master checks the statuses itself. Falls back to the wrapper (which raises) if fmpy
    keeps its functions elsewhere."""
    functions = getattr(fmu, "_functions", None)
    raw = functions.get("fmi2" + name) if isinstance(functions, dict) else None
    if raw is None:
        wrapped = getattr(fmu, "fmi2" + name)

        def raw(*args):
            wrapped(*args)
            return 0

    return raw


class FmuInstance:
    """One fmpy ``FMU2Slave`` with variables by name, its log captured, and errors that say
    what the FMU logged. Instantiated once; :meth:`start` (re)initialises with parameters."""

    def __init__(self, path: str | Path, instance_name: str):
        from fmpy import read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.path = Path(path)
        if not self.path.is_file():
            raise CoSimError(f"{self.path}: no such FMU")
        self.description = read_model_description(str(self.path))
        self.variables = {v.name: v for v in self.description.modelVariables}
        self.log: list[tuple[str, str]] = []  # (status, message)
        self.fmu = FMU2Slave(guid=self.description.guid, unzipDirectory=_extracted(self.path),
                             modelIdentifier=self.description.coSimulation.modelIdentifier,
                             instanceName=instance_name)
        self._callbacks = self._make_callbacks()
        self.fmu.instantiate(callbacks=self._callbacks, loggingOn=True)
        self._fresh = True

    def _make_callbacks(self):
        from fmpy import calloc, free
        from fmpy.fmi2 import (
            fmi2CallbackAllocateMemoryTYPE,
            fmi2CallbackFreeMemoryTYPE,
            fmi2CallbackFunctions,
            fmi2CallbackLoggerTYPE,
        )

        def logger(component, instance, status, category, message):
            label = _STATUS[status] if 0 <= status < len(_STATUS) else str(status)
            self.log.append((label, printed(message)))

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        return callbacks

    def vr(self, name: str) -> int:
        try:
            return self.variables[name].valueReference
        except KeyError:
            raise CoSimError(f"{self.path.name} has no variable {name!r}; it has "
                             f"{sorted(self.variables)}") from None

    def problems(self) -> str:
        """What the FMU logged at warning or worse: the first error (the cause; later
        messages mostly repeat it) or else the last warning, and how many more there were."""
        bad = [(s, m) for s, m in self.log if s != "OK"]
        if not bad:
            return "(the FMU logged nothing)"
        errors = [(s, m) for s, m in bad if s in ("ERROR", "FATAL")]
        status, message = errors[0] if errors else bad[-1]
        more = f" (+{len(bad) - 1} more message(s))" if len(bad) > 1 else ""
        return f"[{status}] {message}{more}"

    def fail(self, what: str, error: Exception) -> CoSimError:
        return CoSimError(f"{self.path.name}: {what} failed ({error}): {self.problems()}")

    def start(self, parameters: Mapping[str, float | int | bool], start_time: float = 0.0
              ) -> None:
        """(Re)initialise with ``parameters`` (FMU names): reset, set, initialise.

        A Real parameter that is fixed at export (a native tire FMU's ``load``) gets its
        declared value when the given one matches it within
        :data:`tire_fmu.fmu.interface.FIXED_PARAMETER_REL_TOLERANCE`: the car's weight
        (2500 + 320)·g is 27654.752999999997 N, the export's load 27654.753 N."""
        try:
            if not self._fresh:
                self.fmu.reset()
            self._fresh = False
            self.log.clear()
            self.fmu.setupExperiment(startTime=start_time)
            self.fmu.enterInitializationMode()
            for name, value in parameters.items():
                vr, kind = self.vr(name), self.variables[name].type
                if kind == "Real":
                    self.fmu.setReal([vr], [self._declared_if_same(name, float(value))])
                elif kind == "Integer":
                    self.fmu.setInteger([vr], [int(value)])
                elif kind == "Boolean":
                    self.fmu.setBoolean([vr], [bool(value)])
                elif kind == "String":
                    self.fmu.setString([vr], [str(value)])
                else:
                    raise CoSimError(f"{name}: {kind} parameters are not supported")
            self.fmu.exitInitializationMode()
        except CoSimError:
            raise
        except Exception as error:
            raise self.fail("initialisation", error) from error

    def _declared_if_same(self, name: str, value: float) -> float:
        from tire_fmu.fmu.interface import same_fixed_value

        variable = self.variables[name]
        if variable.causality == "parameter" and variable.variability == "fixed" \
                and variable.start is not None and same_fixed_value(value, variable.start):
            return float(variable.start)
        return value

    def get(self, names) -> list[float]:
        return self.fmu.getReal([self.vr(n) for n in names])

    def close(self) -> None:
        try:
            self.fmu.terminate()
        except Exception:  # noqa: BLE001 -- a refused terminate must not hide the real error
            pass
        self.fmu.freeInstance()


@dataclass(frozen=True, eq=False)
class CoSimResult:
    """Signals at the communication points t_0 ... t_n (deviations unless 'total')."""

    time_s: np.ndarray
    road_z_m: np.ndarray
    road_vz_m_s: np.ndarray
    body_z_m: np.ndarray
    body_az_m_s2: np.ndarray
    wheel_z_m: np.ndarray
    wheel_vz_m_s: np.ndarray
    wheel_az_m_s2: np.ndarray
    rim_Fz_n: np.ndarray  # total
    contact_Fz_n: np.ndarray  # total
    contact_length_m: np.ndarray  # footprint length on the road
    in_contact: np.ndarray  # the tire FMU's flag
    static_load_n: float
    step_s: float
    scheme: str
    wall_s: float
    tire_log: tuple = field(default=())

    @property
    def rim_load_n(self) -> np.ndarray:
        """Dynamic rim load (total minus static)."""
        return self.rim_Fz_n - self.static_load_n

    @property
    def contact_force_n(self) -> np.ndarray:
        return self.contact_Fz_n - self.static_load_n

    @property
    def real_time_factor(self) -> float:
        """Wall time over simulated time (< 1: faster than real time)."""
        simulated = self.time_s[-1] - self.time_s[0]
        return self.wall_s / simulated if simulated > 0 else math.nan

    @property
    def contact_lost_fraction(self) -> float:
        return float(np.mean(~self.in_contact[1:])) if self.in_contact.size > 1 else 0.0


class QuarterCarCoSimulation:
    """The two FMUs, instantiated once; :meth:`run` (re)initialises them and co-simulates.

    ``tire_parameters`` are TireModal.fmu parameters (``speed``, ``n_elements``, tire data...);
    ``load`` is always the car's weight, so give the car a body mass instead
    (:meth:`QuarterCarParameters.with_static_load`).
    """

    def __init__(self, fmus: FmuPaths, car: QuarterCarParameters | None = None,
                 tire_parameters: Mapping | None = None, step_s: float = DEFAULT_STEP_S,
                 scheme: str = "gauss-seidel", read_after_inputs: bool = True):
        if scheme not in SCHEMES:
            raise ValueError(f"scheme = {scheme!r}: must be one of {SCHEMES}")
        if not (step_s > 0 and math.isfinite(step_s)):
            raise ValueError(f"step_s = {step_s!r}: must be finite and > 0")
        self.car = car or QuarterCarParameters()
        self.tire_parameters = dict(tire_parameters or {})
        if "load" in self.tire_parameters:
            raise ValueError("tire parameter 'load' is set from the car's weight; change the "
                             "body mass instead (QuarterCarParameters.with_static_load)")
        self.step_s = float(step_s)
        self.scheme = scheme
        self.read_after_inputs = bool(read_after_inputs)
        self.tire = FmuInstance(fmus.tire, "tire")
        try:
            self.car_fmu = FmuInstance(fmus.quarter_car, "quarter_car")
        except Exception:
            self.tire.close()
            raise

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        self.tire.close()
        self.car_fmu.close()

    @property
    def speed_m_s(self) -> float:
        return float(self.tire_parameters.get("speed", 0.0))

    def run(self, road_z_m, road_vz_m_s, start_time: float = 0.0,
            progress: Callable[[int], None] | None = None) -> CoSimResult:
        """Co-simulate with the road (at the tire's zone front) sampled at t_k = start + k·h.

        ``progress(n)`` is called with the steps done since its last call.
        """
        road_z = np.ascontiguousarray(road_z_m, dtype=float)
        road_vz = np.ascontiguousarray(road_vz_m_s, dtype=float)
        if road_z.shape != road_vz.shape or road_z.ndim != 1 or road_z.size < 2:
            raise ValueError("road height and velocity must be 1-D arrays of one length >= 2")
        car = self.car
        static_load = car.static_tire_load_n
        self.car_fmu.start(car.fmu_values(), start_time)
        self.tire.start({"load": static_load, **self.tire_parameters}, start_time)
        return self._loop(road_z, road_vz, static_load, start_time, progress)

    def _loop(self, road_z, road_vz, static_load, start_time, progress) -> CoSimResult:
        from ctypes import memmove, sizeof

        from fmpy.fmi2 import fmi2Boolean, fmi2Real, fmi2True, fmi2ValueReference

        tire, car = self.tire, self.car_fmu
        n = road_z.size - 1
        h = self.step_s
        gauss_seidel = self.scheme == "gauss-seidel"
        read_after_inputs = self.read_after_inputs

        def refs(fmu, names):
            return (fmi2ValueReference * len(names))(*[fmu.vr(x) for x in names])

        tire_in = refs(tire, ("rim_z", "rim_vz", "road_z", "road_vz"))
        tire_out = refs(tire, ("rim_Fz", "contact_Fz", "contact_length"))
        tire_flag = refs(tire, ("in_contact",))
        car_in = refs(car, ("rim_Fz", "rim_Fz_rate"))
        car_out = refs(car, ("wheel_z", "wheel_vz", "wheel_az", "body_z", "body_az"))
        u_t, y_t, y_flag = (fmi2Real * 4)(), (fmi2Real * 3)(), (fmi2Boolean * 1)()
        u_c, y_c = (fmi2Real * 2)(), (fmi2Real * 5)()
        ct, cc = tire.fmu.component, car.fmu.component
        t_set, t_step, t_get = (_raw(tire.fmu, f) for f in ("SetReal", "DoStep", "GetReal"))
        t_get_flag = _raw(tire.fmu, "GetBoolean")
        c_set, c_step, c_get = (_raw(car.fmu, f) for f in ("SetReal", "DoStep", "GetReal"))

        out = np.empty((n + 1, 8))  # wheel z, vz, az, body z, az, rim Fz, contact Fz, length
        flags = np.empty(n + 1, dtype=np.dtype(f"i{sizeof(fmi2Boolean)}"))
        # Each step's outputs are copied from the FMUs' buffers into these arrays with memmove
        # at computed addresses: a numpy slice assignment from a ctypes array goes through
        # the buffer protocol and costs about a microsecond each, on a ~15 µs step.
        out_address, row_bytes = out.ctypes.data, out.strides[0]
        car_bytes, tire_bytes = sizeof(fmi2Real) * 5, sizeof(fmi2Real) * 3
        flag_address, flag_bytes = flags.ctypes.data, flags.strides[0]
        road_z_list, road_vz_list = road_z.tolist(), road_vz.tolist()  # floats: cheap to index
        c_get(cc, car_out, 5, y_c)
        z_w, v_w = y_c[0], y_c[1]
        # the tire's inputs at t_0, then its outputs for them (direct feedthrough)
        u_t[0], u_t[1], u_t[2], u_t[3] = z_w, v_w, road_z[0], road_vz[0]
        t_set(ct, tire_in, 4, u_t)
        t_get(ct, tire_out, 3, y_t)
        t_get_flag(ct, tire_flag, 1, y_flag)
        out[0, :5] = y_c[:]
        out[0, 5:] = y_t[:]
        flags[0] = bool(y_flag[0])
        force = y_t[0]
        report_every = max(1, min(n // 100, 5000))
        started = time.perf_counter()
        k = 0
        try:
            for k in range(n):
                t = start_time + k * h  # multiples of h: no drift of the communication points
                if gauss_seidel:  # the tire's force at the step's end, ramped from t_k
                    status = t_step(ct, t, h, fmi2True) | t_get(ct, tire_out, 3, y_t)
                    u_c[0], u_c[1] = force, (y_t[0] - force) / h
                    status |= c_set(cc, car_in, 2, u_c) | c_step(cc, t, h, fmi2True)
                else:  # both from t_k values, the force held
                    u_c[0], u_c[1] = force, 0.0
                    status = c_set(cc, car_in, 2, u_c) | t_step(ct, t, h, fmi2True)
                    status |= c_step(cc, t, h, fmi2True)
                    if not read_after_inputs:
                        status |= t_get(ct, tire_out, 3, y_t)
                status |= c_get(cc, car_out, 5, y_c)
                if not read_after_inputs:  # the flag of the step's end, inputs not yet new
                    status |= t_get_flag(ct, tire_flag, 1, y_flag)
                # the inputs of t_{k+1}, then the tire's outputs for them: its feedthrough
                # (contact damper on the road velocity, sidewall on the rim's) is then current
                u_t[0], u_t[1] = y_c[0], y_c[1]
                u_t[2], u_t[3] = road_z_list[k + 1], road_vz_list[k + 1]
                status |= t_set(ct, tire_in, 4, u_t)
                if read_after_inputs:
                    status |= t_get(ct, tire_out, 3, y_t) | t_get_flag(ct, tire_flag, 1, y_flag)
                if status > 1:  # an OR of statuses exceeds 1 iff one was discard or worse
                    raise CoSimError(f"an FMI call returned {_STATUS[min(status, 4)]} or worse")
                row = out_address + (k + 1) * row_bytes
                memmove(row, y_c, car_bytes)
                memmove(row + car_bytes, y_t, tire_bytes)
                memmove(flag_address + (k + 1) * flag_bytes, y_flag, flag_bytes)
                force = y_t[0]
                if progress is not None and (k + 1) % report_every == 0:
                    progress(report_every)
        except Exception as error:  # fmpy raises on any status worse than warning
            t = start_time + k * h
            said = [f"{unit.path.name}: {unit.problems()}" for unit in (tire, car)
                    if any(status != "OK" for status, _ in unit.log)]
            raise CoSimError(f"step {k} at t = {t:.6g} s refused ({error}); "
                             + ("; ".join(said) or "no FMU logged why")) from error
        wall = time.perf_counter() - started
        if progress is not None and n % report_every:
            progress(n % report_every)
        times = start_time + h * np.arange(n + 1)
        return CoSimResult(
            time_s=times, road_z_m=road_z, road_vz_m_s=road_vz,
            body_z_m=out[:, 3].copy(), body_az_m_s2=out[:, 4].copy(),
            wheel_z_m=out[:, 0].copy(), wheel_vz_m_s=out[:, 1].copy(),
            wheel_az_m_s2=out[:, 2].copy(), rim_Fz_n=out[:, 5].copy(),
            contact_Fz_n=out[:, 6].copy(), contact_length_m=out[:, 7].copy(),
            in_contact=flags != 0, static_load_n=static_load,
            step_s=h, scheme=self.scheme, wall_s=wall, tire_log=tuple(tire.log),
        )


def cosimulate(fmus: FmuPaths, road_z_m, road_vz_m_s, car: QuarterCarParameters | None = None,
               tire_parameters: Mapping | None = None, step_s: float = DEFAULT_STEP_S,
               scheme: str = "gauss-seidel", progress=None,
               read_after_inputs: bool = True) -> CoSimResult:
    """One co-simulation with fresh FMU instances (see :class:`QuarterCarCoSimulation`)."""
    with QuarterCarCoSimulation(fmus, car, tire_parameters, step_s, scheme,
                                read_after_inputs) as sim:
        return sim.run(road_z_m, road_vz_m_s, progress=progress)

