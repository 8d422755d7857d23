"""Time-domain tire: a reduced model stepped under rim and road input, with road delays and
static values, the engine behind the FMU slave (which only adapts it to FMI).

Inputs at each communication point are deviations from static equilibrium: rim displacement
and velocity, road height and velocity at the leading edge of the patch. Each group of patch
nodes sees the road height a delay τ later; the road's history is kept at the communication
points and read back by cubic Hermite interpolation (exact for the ramps the step assumes).
Before the first communication point the road is taken as level at its first value.

Outputs are totals: static value plus deviation, so a host in equilibrium stays there. The
linear contact cannot lift off; when the total contact force drops below zero,
``in_contact`` turns false and the caller decides how to report it.
"""

from __future__ import annotations

import io
import json
import math
from dataclasses import dataclass

import numpy as np

from .reduction import ReducedModel
from .stepping import DiagonalStepper, FusedStep

INPUT_NAMES = ("rim_z", "rim_vz", "road_z", "road_vz")
OUTPUT_NAMES = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection")
_STATE_FORMAT = "tire_fmu.simulator-state/1"
_INF = math.inf
_KERNEL_CACHE_SIZE = 64
#: Steps closer than this times the current time are one step (a few ulps of the time axis).
_SAME_STEP_EPS = 8 * np.finfo(float).eps


class StepError(ValueError):
    """A step the simulator refuses (bad h, non-finite input); nothing was changed."""


@dataclass(frozen=True, eq=False)
class SimulatorState:
    """Everything a simulator needs to resume exactly (copies, safe to keep)."""

    time: float
    q: np.ndarray
    history_t: np.ndarray
    history_z: np.ndarray
    history_v: np.ndarray
    outputs: np.ndarray
    in_contact: bool

    def to_bytes(self) -> bytes:
        buffer = io.BytesIO()
        header = json.dumps({"format": _STATE_FORMAT, "time": self.time,
                             "in_contact": self.in_contact}).encode()
        np.savez(buffer, header=np.frombuffer(header, dtype=np.uint8), q=self.q,
                 history_t=self.history_t, history_z=self.history_z, history_v=self.history_v,
                 outputs=self.outputs)
        return buffer.getvalue()

    @classmethod
    def from_bytes(cls, data: bytes) -> SimulatorState:
        try:
            with np.load(io.BytesIO(data), allow_pickle=False) as arrays:
                header = json.loads(arrays["header"].tobytes().decode())
                if header.get("format") != _STATE_FORMAT:
                    raise ValueError(f"unknown format {header.get('format')!r}")
                return cls(float(header["time"]), arrays["q"].copy(), arrays["history_t"].copy(),
                           arrays["history_z"].copy(), arrays["history_v"].copy(),
                           arrays["outputs"].copy(), bool(header["in_contact"]))
        except (OSError, ValueError, KeyError) as error:
            raise ValueError(f"not a tire_fmu simulator state: {error}") from error


class TireSimulator:
    """Steps a :class:`ReducedModel` from communication point to communication point.

    The modal state lives in one buffer z = [q, inputs, 1] that :class:`FusedStep` advances in
    place, so a step allocates nothing: it is the inner loop of the FMU.
    """

    def __init__(self, reduced: ReducedModel, start_time: float = 0.0):
        self.reduced = reduced
        self.stepper = DiagonalStepper.from_reduced(reduced)
        self.road_delays_s = np.asarray(reduced.input_delays_s[1:], dtype=float)
        self._delayed = bool(np.any(self.road_delays_s > 0))
        self._horizon = float(self.road_delays_s.max()) if self.road_delays_s.size else 0.0
        self.static = np.array([reduced.static_outputs[name] for name in OUTPUT_NAMES])
        m, k = reduced.n_inputs, reduced.n_modes
        if self._delayed:  # the road history gives each internal input its own value
            self._input_map = np.eye(2 * m)
        else:  # the four physical inputs feed the internal ones directly
            self._input_map = np.zeros((2 * m, len(INPUT_NAMES)))
            self._input_map[0, 0] = self._input_map[m, 1] = 1.0  # rim_z, rim_vz
            self._input_map[1:m, 2] = self._input_map[m + 1:, 3] = 1.0  # road_z, road_vz
        n_p = self._input_map.shape[1]
        self._z = np.zeros(k + n_p + 1, dtype=complex)
        self._z[-1] = 1.0  # carries the static outputs through the readout
        self._q, self._p = self._z[:k], self._z[k:k + n_p]
        self._y = np.zeros(len(OUTPUT_NAMES), dtype=complex)
        self._g = np.zeros(k, dtype=complex)
        self._kernels: dict[float, FusedStep] = {}
        self._kernel: FusedStep | None = None
        self._kernel_h = math.nan
        self.reset(start_time)

    def reset(self, start_time: float = 0.0) -> None:
        self.time = float(start_time)
        self._q[:] = 0.0
        self.history_t = np.zeros(0)
        self.history_z = np.zeros(0)
        self.history_v = np.zeros(0)
        self._values = self.static.tolist()
        self.in_contact = bool(self.static[2] > 0.0)

    @property
    def q(self) -> np.ndarray:
        """Modal state (a copy: the simulator advances its own buffer in place)."""
        return self._q.copy()

    @q.setter
    def q(self, value) -> None:
        self._q[:] = value

    @property
    def outputs(self) -> np.ndarray:
        """Total outputs (rim_Fz, rim_Fx, contact_Fz, deflection) at ``time``."""
        return np.array(self._values)

    @outputs.setter
    def outputs(self, value) -> None:
        self._values = [float(v) for v in value]

    # -- stepping ----------------------------------------------------------------------------
    def step(self, h: float, rim_z: float, rim_vz: float, road_z: float, road_vz: float
             ) -> np.ndarray:
        """Advance from ``time`` to ``time + h`` with the inputs given at ``time``; returns the
        total outputs (rim_Fz, rim_Fx, contact_Fz, deflection) at the new time."""
        return np.array(self.step_values(h, rim_z, rim_vz, road_z, road_vz))

    def step_values(self, h: float, rim_z: float, rim_vz: float, road_z: float,
                    road_vz: float) -> list[float]:
        """:meth:`step` returning the outputs as a list of floats (the FMU's hot path)."""
        # One test for all four inputs: x * 0 is 0 only for finite x, and a sum keeps any nan
        # or inf; the exact check runs only when this one fails.
        if not 0.0 < h < _INF or (rim_z + rim_vz + road_z + road_vz) * 0.0 != 0.0:
            self._check_step(h, (rim_z, rim_vz, road_z, road_vz))
        kernel = self._kernel if h == self._kernel_h else self._kernel_for(h)
        if self._delayed:
            r, v = self._internal_inputs(rim_z, rim_vz, road_z, road_vz)
            m = r.size
            self._p[:m] = r
            self._p[m:] = v
        else:
            z, k = self._z, self._q.size
            z[k] = rim_z
            z[k + 1] = rim_vz
            z[k + 2] = road_z
            z[k + 3] = road_vz
        np.dot(kernel.readout, self._z, out=self._y)  # from the state at t, so before q moves
        np.multiply(self._q, kernel.decay, out=self._q)
        np.dot(kernel.gain, self._p, out=self._g)
        np.add(self._q, self._g, out=self._q)
        values = self._y.real.tolist()
        self._values = values
        self.time += h
        self.in_contact = values[2] > 0.0
        return values

    def _check_step(self, h: float, values: tuple) -> None:
        """Raise StepError for a bad h or a non-finite input (a finite sum that overflowed
        passes)."""
        if not (h > 0.0 and math.isfinite(h)):
            raise StepError(f"step size h = {h!r} s: must be finite and > 0")
        bad = [f"{n} = {v!r}" for n, v in zip(INPUT_NAMES, values) if not math.isfinite(v)]
        if bad:
            raise StepError("non-finite input: " + ", ".join(bad))

    def _kernel_for(self, h: float) -> FusedStep:
        """The fused step for h. A step that differs from a cached one by less than the time
        axis resolves at this time is that step: hosts that compute h as a difference of
        communication points (fmpy does) jitter it in the last bits, and the jitter does not
        accumulate because the host's own time stays the reference."""
        resolution = _SAME_STEP_EPS * (abs(self.time) + h)
        kernel = next((cached for cached_h, cached in self._kernels.items()
                       if abs(h - cached_h) <= resolution), None)
        if kernel is None:
            kernel = self.stepper.fused(h, self._input_map, self.static)
            if len(self._kernels) >= _KERNEL_CACHE_SIZE:
                self._kernels.pop(next(iter(self._kernels)))
            self._kernels[h] = kernel
        self._kernel, self._kernel_h = kernel, h
        return kernel

    def _internal_inputs(self, rim_z, rim_vz, road_z, road_vz):
        n_road = self.road_delays_s.size
        r = np.empty(1 + n_road)
        v = np.empty(1 + n_road)
        r[0], v[0] = rim_z, rim_vz
        if not n_road:
            return r, v
        if not self._delayed:
            r[1:], v[1:] = road_z, road_vz
            return r, v
        self._record_road(road_z, road_vz)
        r[1:], v[1:] = self._road_at(self.time - self.road_delays_s)
        return r, v

    def _record_road(self, z: float, vz: float) -> None:
        if self.history_t.size and self.history_t[-1] >= self.time:
            # the same communication point again (a retried step): replace, never duplicate
            self.history_z[-1], self.history_v[-1] = z, vz
            return
        # keep what the longest delay can still reach, plus the sample just before it
        keep = np.searchsorted(self.history_t, self.time - self._horizon, side="right") - 1
        keep = max(keep, 0)
        self.history_t = np.append(self.history_t[keep:], self.time)
        self.history_z = np.append(self.history_z[keep:], z)
        self.history_v = np.append(self.history_v[keep:], vz)

    def _road_at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Road height and slope at past times: cubic Hermite between communication points,
        level at the first value before the first one."""
        t, z, v = self.history_t, self.history_z, self.history_v
        if t.size == 1:  # only the present sample: level before it
            return np.full(times.shape, z[0]), np.where(times < t[0], 0.0, v[0])
        i = np.clip(np.searchsorted(t, times, side="right") - 1, 0, t.size - 2)
        t0, t1 = t[i], t[i + 1]
        dt = t1 - t0
        s = (times - t0) / dt
        z0, z1, v0, v1 = z[i], z[i + 1], v[i] * dt, v[i + 1] * dt
        s2, s3 = s * s, s * s * s
        height = (2 * s3 - 3 * s2 + 1) * z0 + (s3 - 2 * s2 + s) * v0 \
            + (-2 * s3 + 3 * s2) * z1 + (s3 - s2) * v1
        slope = ((6 * s2 - 6 * s) * z0 + (3 * s2 - 4 * s + 1) * v0
                 + (-6 * s2 + 6 * s) * z1 + (3 * s2 - 2 * s) * v1) / dt
        before = times < t[0]
        return np.where(before, z[0], height), np.where(before, 0.0, slope)

    # -- state -------------------------------------------------------------------------------
    def get_state(self) -> SimulatorState:
        return SimulatorState(self.time, self.q, self.history_t.copy(),
                              self.history_z.copy(), self.history_v.copy(),
                              self.outputs, self.in_contact)

    def set_state(self, state: SimulatorState) -> None:
        if state.q.shape != self.q.shape or state.outputs.shape != self.outputs.shape:
            raise ValueError(
                f"state of a model with {state.q.size} modes cannot be set on one with "
                f"{self.q.size}: build both with the same parameters"
            )
        self.time = state.time
        self.q = state.q
        self.history_t, self.history_z = state.history_t.copy(), state.history_z.copy()
        self.history_v = state.history_v.copy()
        self.outputs = state.outputs
        self.in_contact = state.in_contact

    def output_dict(self) -> dict[str, float]:
        return dict(zip(OUTPUT_NAMES, self._values))
