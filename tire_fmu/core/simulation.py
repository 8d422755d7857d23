"""Time-domain tire: a reduced model stepped under rim and road input, with road delays and
static values, the engine behind the FMU slave (which only adapts it to FMI).

Inputs at each communication point are deviations from static equilibrium: rim displacement
and velocity, road height and velocity at the leading edge of the patch. Each group of patch
nodes sees the road height a delay τ later; the road's history is kept at the communication
points and read back by cubic Hermite interpolation (exact for the ramps the step assumes).
Before the first communication point the road is taken as level at its first value. Once the
steps have had one size for the whole reach of the delays, that read-back is fixed weights on
the last samples, and a delay line applies them with one product a step.

Outputs are totals: static value plus deviation, so a host in equilibrium stays there. The
linear contact cannot lift off; when the total contact force drops below zero,
``in_contact`` turns false and the caller decides how to report it.
"""

from __future__ import annotations

import io
import json
import math
import struct
from dataclasses import dataclass

import numpy as np
from scipy.linalg.blas import dgemv

from .reduction import ReducedModel
from .stepping import DiagonalStepper, FusedStep

INPUT_NAMES = ("rim_z", "rim_vz", "road_z", "road_vz")
OUTPUT_NAMES = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection")
_STATE_FORMAT = "tire_fmu.simulator-state/1"
_KERNEL_CACHE_SIZE = 64
#: Steps closer than this times the current time are one step (a few ulps of the time axis).
SAME_STEP_EPS = 8 * np.finfo(float).eps
_PACK_INPUTS = struct.Struct(f"{len(INPUT_NAMES)}d").pack_into
_PACK_PAIR = struct.Struct("2d").pack_into
_UNPACK_OUTPUTS = struct.Struct(f"{len(OUTPUT_NAMES)}d").unpack_from


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

    The modal state lives in one buffer that :class:`FusedStep` advances in place, so a step
    allocates nothing but its list of outputs: it is the inner loop of the FMU.
    """

    def __init__(self, reduced: ReducedModel, start_time: float = 0.0):
        self.reduced = reduced
        self.stepper = DiagonalStepper.from_reduced(reduced)
        self.road_delays_s = np.asarray(reduced.input_delays_s[1:], dtype=float)
        self._delayed = bool(np.any(self.road_delays_s > 0))
        self._horizon = float(self.road_delays_s.max()) if self.road_delays_s.size else 0.0
        self.static = np.array([reduced.static_outputs[name] for name in OUTPUT_NAMES])
        m, k = reduced.n_inputs, reduced.n_modes
        # The step's inputs p start with rim_z, rim_vz. At rest road_z, road_vz follow and
        # feed every road input; at speed each road input has its own delayed height, then
        # its own slope: p = [rim_z, rim_vz, r_1 .. r_m-1, v_1 .. v_m-1].
        n_p = len(INPUT_NAMES) if not self._delayed else 2 * m
        self._input_map = np.zeros((2 * m, n_p))
        self._input_map[0, 0] = self._input_map[m, 1] = 1.0  # rim_z, rim_vz
        if self._delayed:
            self._input_map[1:m, 2:m + 1] = self._input_map[m + 1:, m + 1:] = np.eye(m - 1)
        else:
            self._input_map[1:m, 2] = self._input_map[m + 1:, 3] = 1.0  # road_z, road_vz
        # One real buffer [q as (re, im) pairs, inputs, 1] that FusedStep advances in place;
        # the 1 carries the static outputs through the readout.
        self._buffer = np.zeros(2 * k + n_p + 1)
        self._buffer[-1] = 1.0
        self._q = self._buffer[:2 * k].view(complex)
        self._p = self._buffer[2 * k:2 * k + n_p]
        self._road = self._buffer[2 * k + 2:2 * k + n_p]  # the delayed road inputs
        self._y = np.zeros(len(OUTPUT_NAMES))
        # inputs go in with one struct call and the outputs come out as floats with another:
        # cheaper than numpy item assignments and a tolist
        self._buffer_bytes = memoryview(self._buffer).cast("B")
        self._input_offset = 2 * k * self._buffer.itemsize
        # Outputs at the current time for inputs given now (direct feedthrough), on the same
        # buffer [q as (re, im) pairs, inputs, 1] the step reads: Re(C q), then D and E on the
        # internal inputs as the input map makes them, then the statics.
        c_pairs = np.empty((len(OUTPUT_NAMES), 2 * k))
        c_pairs[:, 0::2], c_pairs[:, 1::2] = reduced.c.real, -reduced.c.imag
        feedthrough = np.hstack([reduced.d, reduced.e]) @ self._input_map
        self._now_readout = np.asfortranarray(
            np.hstack([c_pairs, feedthrough, self.static[:, None]]))
        self._kernels: dict[float, FusedStep] = {}
        self._kernel: FusedStep | None = None
        self._kernel_h = math.nan
        self._advance = None
        self.reset(start_time)

    def reset(self, start_time: float = 0.0) -> None:
        self.time = float(start_time)
        self._q[:] = 0.0
        self.history_t = np.zeros(0)
        self.history_z = np.zeros(0)
        self.history_v = np.zeros(0)
        self._delay_line: _RoadDelayLine | None = None
        self._uniform_run: int | None = None  # see _road_inputs; None: count it again
        self._values = tuple(self.static.tolist())

    @property
    def q(self) -> np.ndarray:
        """Modal state (a copy: the simulator advances its own buffer in place)."""
        return self._q.copy()

    @q.setter
    def q(self, value) -> None:
        self._q[:] = value

    @property
    def in_contact(self) -> bool:
        """Whether the contact force is positive (the linear contact cannot lift off)."""
        return self._values[2] > 0.0

    @property
    def outputs(self) -> np.ndarray:
        """Total outputs (rim_Fz, rim_Fx, contact_Fz, deflection) at ``time``."""
        return np.array(self._values)

    @outputs.setter
    def outputs(self, value) -> None:
        self._values = tuple(float(v) for v in value)

    # -- stepping ----------------------------------------------------------------------------
    def step(self, h: float, rim_z: float, rim_vz: float, road_z: float, road_vz: float
             ) -> np.ndarray:
        """Advance from ``time`` to ``time + h`` with the inputs given at ``time``; returns the
        total outputs (rim_Fz, rim_Fx, contact_Fz, deflection) at the new time."""
        return np.array(self.step_values(h, rim_z, rim_vz, road_z, road_vz))

    def step_values(self, h: float, rim_z: float, rim_vz: float, road_z: float,
                    road_vz: float) -> tuple[float, ...]:
        """:meth:`step` returning the outputs as a tuple of floats (the FMU's hot path)."""
        # One test for all four inputs: x * 0 is 0 only for finite x, and a sum keeps any nan
        # or inf. h is checked when its coefficients are chosen: only a valid h gets them.
        if h != self._kernel_h or (rim_z + rim_vz + road_z + road_vz) * 0.0 != 0.0:
            self._check_step(h, (rim_z, rim_vz, road_z, road_vz))
            if h != self._kernel_h:
                self._use_kernel(h)
        if not self._delayed:
            _PACK_INPUTS(self._buffer_bytes, self._input_offset, rim_z, rim_vz, road_z, road_vz)
        else:
            _PACK_PAIR(self._buffer_bytes, self._input_offset, rim_z, rim_vz)
            if self._delay_line is None:
                self._road_inputs(road_z, road_vz)
            else:
                self._delay_line.push(self.time, road_z, road_vz)
                self._delay_line.read_into(self._road)
        self._advance()
        values = _UNPACK_OUTPUTS(self._y)
        self._values = values
        self.time += h
        return values

    def outputs_with(self, rim_z: float, rim_vz: float, road_z: float, road_vz: float
                     ) -> tuple[float, ...]:
        """Total outputs at ``time`` for inputs given at ``time``, leaving the state alone.

        A step reports its outputs at its end with the inputs ramped from its start; once the
        host sets the inputs of the new communication point, the direct feedthrough (the
        contact spring and damper on the road, the sidewall on the rim) should use those.
        The contact damper alone passes about 1.7e4 N·s/m of road velocity straight to the
        contact force, and the slope a step ramped with is a step old.
        """
        if (rim_z + rim_vz + road_z + road_vz) * 0.0 != 0.0:
            self._check_step(1.0, (rim_z, rim_vz, road_z, road_vz))
        if not self._delayed:
            _PACK_INPUTS(self._buffer_bytes, self._input_offset, rim_z, rim_vz, road_z, road_vz)
        else:
            _PACK_PAIR(self._buffer_bytes, self._input_offset, rim_z, rim_vz)
            if self._delay_line is not None:
                self._delay_line.push(self.time, road_z, road_vz)
                self._delay_line.read_into(self._road)
            else:
                height, slope = self._road_now(road_z, road_vz)
                n = height.size
                self._road[:n], self._road[n:] = height, slope
        dgemv(1.0, self._now_readout, self._buffer, 0.0, self._y, 0, 1, 0, 1, 0, 1)
        self._values = _UNPACK_OUTPUTS(self._y)
        return self._values

    def _road_now(self, road_z: float, road_vz: float) -> tuple[np.ndarray, np.ndarray]:
        """Delayed road inputs at ``time`` with the present sample taken as given."""
        if self._delay_line is not None:
            t, z, v = self._delay_line.history()
        else:
            t, z, v = self.history_t, self.history_z, self.history_v
        if t.size and t[-1] >= self.time - SAME_STEP_EPS * (abs(self.time) + 1.0):
            t, z, v = t[:-1], z[:-1], v[:-1]  # the present sample again: replace it
        t, z, v = np.append(t, self.time), np.append(z, road_z), np.append(v, road_vz)
        return _hermite(t, z, v, self.time - self.road_delays_s)

    def _check_step(self, h: float, values: tuple) -> None:
        """Raise StepError for a bad h or a non-finite input (a finite sum that overflowed
        passes)."""
        if not (h > 0.0 and math.isfinite(h)):
            raise StepError(f"step size h = {h!r} s: must be finite and > 0")
        bad = [f"{n} = {v!r}" for n, v in zip(INPUT_NAMES, values) if not math.isfinite(v)]
        if bad:
            raise StepError("non-finite input: " + ", ".join(bad))

    def _use_kernel(self, h: float) -> None:
        """Step with the fused step for h from now on. A step that differs from a cached one
        by less than the time axis resolves at this time is that step: hosts that compute h
        as a difference of communication points (fmpy does) jitter it in the last bits, and
        the jitter does not accumulate because the host's own time stays the reference."""
        resolution = SAME_STEP_EPS * (abs(self.time) + h)
        kernel = next((cached for cached_h, cached in self._kernels.items()
                       if abs(h - cached_h) <= resolution), None)
        if kernel is None:
            kernel = self.stepper.fused(h, self._input_map, self.static)
            if len(self._kernels) >= _KERNEL_CACHE_SIZE:
                self._kernels.pop(next(iter(self._kernels)))
            self._kernels[h] = kernel
        if kernel is not self._kernel:
            self._stop_delay_line()  # its weights belong to the old step size
            self._kernel = kernel
            self._advance = kernel.bind(self._buffer, self._y)
            if self._delayed:
                self._delay_line_samples = _RoadDelayLine.samples_needed(self.road_delays_s,
                                                                         kernel.h)
        self._kernel_h = h

    def _road_inputs(self, road_z: float, road_vz: float) -> None:
        """Delayed road inputs while no delay line runs.

        The rule, a function of the recorded history and h alone (so a restored state takes
        the same path as the run it was saved from, bit for bit): once the last samples,
        this step's included, are spaced h apart over the whole reach of the delays, a
        delay line with fixed weights takes over; until then the history is searched.
        """
        h, needed = self._kernel.h, self._delay_line_samples
        t = self.history_t
        resolution = SAME_STEP_EPS * (abs(self.time) + h)
        if self._uniform_run is None:
            self._uniform_run = _uniform_run(t, h, resolution)
        uniform = t.size > 0 and abs(self.time - t[-1] - h) <= resolution
        self._uniform_run = self._uniform_run + 1 if uniform else 1
        if self._uniform_run >= needed:
            self._delay_line = _RoadDelayLine(
                self.road_delays_s, h, t[1 - needed:], self.history_z[1 - needed:],
                self.history_v[1 - needed:])
            self._delay_line.push(self.time, road_z, road_vz)
            self._delay_line.read_into(self._road)
            return
        self._record_road(road_z, road_vz)
        height, slope = self._road_at(self.time - self.road_delays_s)
        n = height.size
        self._road[:n], self._road[n:] = height, slope

    def _stop_delay_line(self) -> None:
        """Back to the recorded history, which the delay line holds while it runs."""
        if self._delay_line is not None:
            self.history_t, self.history_z, self.history_v = self._delay_line.history()
            self._delay_line = None
        self._uniform_run = None

    def _record_road(self, z: float, vz: float) -> None:
        if self.history_t.size and self.history_t[-1] >= self.time - SAME_STEP_EPS * (
                abs(self.time) + 1.0):
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
        return _hermite(self.history_t, self.history_z, self.history_v, times)

    # -- state -------------------------------------------------------------------------------
    def get_state(self) -> SimulatorState:
        if self._delay_line is not None:
            history = self._delay_line.history()
        else:
            history = (self.history_t.copy(), self.history_z.copy(), self.history_v.copy())
        return SimulatorState(self.time, self.q, *history, self.outputs, self.in_contact)

    def set_state(self, state: SimulatorState) -> None:
        if state.q.shape != self.q.shape or state.outputs.shape != self.outputs.shape:
            raise ValueError(
                f"state of a model with {state.q.size} modes cannot be set on one with "
                f"{self.q.size}: build both with the same parameters"
            )
        self.time = state.time
        self.q = state.q
        self._delay_line, self._uniform_run = None, None
        self.history_t, self.history_z = state.history_t.copy(), state.history_z.copy()
        self.history_v = state.history_v.copy()
        self.outputs = state.outputs  # in_contact follows from them

    def output_dict(self) -> dict[str, float]:
        return dict(zip(OUTPUT_NAMES, self._values))


def _hermite(t: np.ndarray, z: np.ndarray, v: np.ndarray, times: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    """Road height and slope at past ``times`` from samples (t, z, v): cubic Hermite between
    communication points, level at the first value before the first one."""
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


def _uniform_run(times: np.ndarray, h: float, resolution: float) -> int:
    """How many samples at the end of ``times`` are spaced h apart (0 for none)."""
    if not times.size:
        return 0
    regular = np.abs(np.diff(times) - h) <= resolution
    irregular = np.flatnonzero(~regular)
    return times.size - (irregular[-1] + 1 if irregular.size else 0)


class _RoadDelayLine:
    """The road under each patch node group for steps of one size h.

    With uniform steps the time t - τ_j that group j reads sits at the same fraction s_j of
    the same interval between lagged samples at every step, so the cubic Hermite read-back of
    :meth:`TireSimulator._road_at` is fixed weights on the last samples: one matrix-vector
    product a step instead of a search and a polynomial. Each sample (z, v) is written twice,
    one window apart, so the window, newest first, is always contiguous and BLAS reads it in
    place from an offset.
    """

    def __init__(self, delays_s: np.ndarray, h: float, times, heights, slopes):
        lags, fractions = self._intervals(delays_s, h)
        n = int(lags.max()) + 1
        self.h, self.window = h, 2 * n
        # rows: heights of every group, then slopes; columns: (z, v) of lag 0, 1, ...
        weights = np.zeros((2 * delays_s.size, self.window), order="F")
        s = fractions
        s2, s3 = s * s, s * s * s
        rows = np.arange(delays_s.size)
        older, newer = 2 * lags, 2 * (lags - 1)  # columns of z; v follows each
        for row, column, value in (
            (rows, older, 2 * s3 - 3 * s2 + 1), (rows, older + 1, (s3 - 2 * s2 + s) * h),
            (rows, newer, -2 * s3 + 3 * s2), (rows, newer + 1, (s3 - s2) * h),
            (rows + s.size, older, (6 * s2 - 6 * s) / h), (rows + s.size, older + 1,
                                                           3 * s2 - 4 * s + 1),
            (rows + s.size, newer, (-6 * s2 + 6 * s) / h), (rows + s.size, newer + 1,
                                                            3 * s2 - 2 * s),
        ):
            weights[row, column] += value
        self.weights = weights
        self.samples = np.zeros(2 * self.window)
        self._bytes = memoryview(self.samples).cast("B")
        self.start = 0  # index of the newest sample's z in the window
        self.newest_time = math.nan
        for t, z, v in zip(times, heights, slopes):  # oldest first
            self.push(float(t), float(z), float(v))

    @staticmethod
    def _intervals(delays_s: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
        """Per group: the lag of the older sample of its interval and the fraction s in
        [0, 1] from it to the newer one (lag - 1); a zero delay reads the newest sample."""
        ratio = delays_s / h
        lags = np.maximum(1, np.ceil(ratio - 1e-9)).astype(int)
        return lags, np.clip(lags - ratio, 0.0, 1.0)

    @classmethod
    def samples_needed(cls, delays_s: np.ndarray, h: float) -> int:
        return int(cls._intervals(delays_s, h)[0].max()) + 1

    def push(self, time: float, z: float, v: float) -> None:
        """Add the sample of communication point ``time``; the same point again (outputs read
        there before its step, or a retried step) replaces it instead."""
        # Steps here are h apart, so anything within half a step of the newest sample is that
        # point again: hosts hand back their own clock, which may differ from ours by ulps.
        if abs(time - self.newest_time) < 0.5 * self.h:
            offset = self.start * self.samples.itemsize
            _PACK_PAIR(self._bytes, offset, z, v)
            _PACK_PAIR(self._bytes, offset + self.window * self.samples.itemsize, z, v)
            return
        start = (self.start - 2) % self.window
        offset = start * self.samples.itemsize
        _PACK_PAIR(self._bytes, offset, z, v)
        _PACK_PAIR(self._bytes, offset + self.window * self.samples.itemsize, z, v)
        self.start, self.newest_time = start, time

    def read_into(self, out: np.ndarray) -> None:
        """The groups' delayed heights then slopes, written into ``out`` in place."""
        # positional arguments, Fortran-ordered weights: no copy, no keyword parsing
        dgemv(1.0, self.weights, self.samples, 0.0, out, self.start, 1, 0, 1, 0, 1)

    def history(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The samples as the recorded history (times ascending)."""
        window = self.samples[self.start:self.start + self.window]
        lags = np.arange(self.window // 2)[::-1]
        return self.newest_time - lags * self.h, window[0::2][::-1].copy(), \
            window[1::2][::-1].copy()
