"""The road under each contact node, from the road height a host gives at the front of the
contact zone.

The host gives ``road_z`` and ``road_vz`` at each communication point. Between points the road
is the cubic Hermite interpolant of those samples (exact for the ramps a step assumes), and
before the first point it is level at its first value. Node j sees the average of that history
over its window [t - late_j, t - early_j] (:class:`~.contact.RoadWindows`: the stretch of road
under its arc passed the zone front then), and its slope is the difference of the window's
end values over the window's duration. At V = 0 every window is the present instant.

Windows are read through the running integral of the interpolant, so a window costs the same
however many samples it spans. Once the steps have had one size h for the whole reach of the
windows, each window end sits at the same fraction of the same lagged interval at every step,
and a delay line reads them with fixed weights from a ring buffer of samples: a gather and one
matrix-vector product a step.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg.blas import dgemv

from .contact import RoadWindows

#: Communication points closer than this times the time are one point (a few ulps).
SAME_POINT_EPS = 8 * np.finfo(float).eps
#: Slack when a delay is cut into whole steps, so a delay of exactly k steps is k steps.
LAG_SLACK = 1e-12


def hermite_value(t, z, v, x):
    """Road height and slope at times ``x`` from samples (t, z, v); level before t[0]."""
    x = np.asarray(x, dtype=float)
    if t.size == 1:
        return np.full(x.shape, z[0]), np.where(x < t[0], 0.0, v[0])
    i = np.clip(np.searchsorted(t, x, side="right") - 1, 0, t.size - 2)
    dt = t[i + 1] - t[i]
    s = (x - t[i]) / dt
    z0, z1, v0, v1 = z[i], z[i + 1], v[i] * dt, v[i + 1] * dt
    s2, s3 = s * s, s * s * s
    height = (2 * s3 - 3 * s2 + 1) * z0 + (s3 - 2 * s2 + s) * v0 \
        + (-2 * s3 + 3 * s2) * z1 + (s3 - s2) * v1
    slope = ((6 * s2 - 6 * s) * z0 + (3 * s2 - 4 * s + 1) * v0
             + (-6 * s2 + 6 * s) * z1 + (3 * s2 - 2 * s) * v1) / dt
    before = x < t[0]
    return np.where(before, z[0], height), np.where(before, 0.0, slope)


def _partial_integral(s, z0, v0, z1, v1):
    """∫_0^s of the Hermite cubic on the unit interval (v already scaled by the interval)."""
    s2, s3, s4 = s * s, s * s * s, s * s * s * s
    return ((0.5 * s4 - s3 + s) * z0 + (0.25 * s4 - 2 * s3 / 3 + 0.5 * s2) * v0
            + (-0.5 * s4 + s3) * z1 + (0.25 * s4 - s3 / 3) * v1)


def hermite_integral(t, z, v, x):
    """∫ of the interpolant from t[0] to each ``x`` (negative before t[0]: level at z[0])."""
    x = np.asarray(x, dtype=float)
    if t.size == 1:
        return (x - t[0]) * z[0]
    dt = np.diff(t)
    segments = dt * (0.5 * (z[:-1] + z[1:]) + dt * (v[:-1] - v[1:]) / 12.0)
    cumulative = np.concatenate([[0.0], np.cumsum(segments)])
    i = np.clip(np.searchsorted(t, x, side="right") - 1, 0, t.size - 2)
    width = t[i + 1] - t[i]
    s = np.clip((x - t[i]) / width, 0.0, None)
    inside = cumulative[i] + width * _partial_integral(
        s, z[i], v[i] * width, z[i + 1], v[i + 1] * width)
    after = x > t[-1]  # reads never reach past the newest sample; keep the formula finite
    inside = np.where(after, cumulative[-1] + (x - t[-1]) * z[-1], inside)
    return np.where(x < t[0], (x - t[0]) * z[0], inside)


def window_reads(t, z, v, now: float, windows: RoadWindows):
    """(heights, slopes) under each node at ``now`` from the samples (general path)."""
    early, late = now - windows.early_s, now - windows.late_s
    width = windows.late_s - windows.early_s
    point = width <= 0.0
    safe = np.where(point, 1.0, width)
    mean = (hermite_integral(t, z, v, early) - hermite_integral(t, z, v, late)) / safe
    end_value, end_slope = hermite_value(t, z, v, early)
    start_value, _ = hermite_value(t, z, v, late)
    slope = (end_value - start_value) / safe
    return np.where(point, end_value, mean), np.where(point, end_slope, slope)


class RoadReader:
    """Keeps the road history a set of windows needs and reads the road under each node."""

    def __init__(self, windows: RoadWindows, delay_line: bool = True):
        self.windows = windows
        self.delayed = bool(np.any(windows.late_s > 0))
        self.horizon_s = windows.horizon_s
        self.delay_line = delay_line  # False: always read the history (a reference path)
        self.reset()

    def reset(self) -> None:
        self.history_t = np.zeros(0)
        self.history_z = np.zeros(0)
        self.history_v = np.zeros(0)
        self._line: _DelayLine | None = None
        self._line_h = math.nan
        self._uniform_run: int | None = None
        self._last_read: tuple | None = None  # (now, z, vz, h) of the last read

    # -- the history as a state ----------------------------------------------------------
    def history(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self._line is not None:
            return self._line.history()
        return self.history_t.copy(), self.history_z.copy(), self.history_v.copy()

    def get_state(self) -> dict[str, np.ndarray]:
        """The history, and the delay line's own buffer while it runs, so that a restored
        reader continues with the same arithmetic, bit for bit."""
        t, z, v = self.history()
        line = self._line
        raw = (np.zeros(0) if line is None else np.concatenate(
            [[line.h, line._start, line._count, line.newest_time], line._buffer]))
        run = -1 if self._uniform_run is None else self._uniform_run
        return {"history_t": t, "history_z": z, "history_v": v, "road_line": raw,
                "road_run": np.array([run], dtype=np.int64)}

    def set_state(self, state: dict[str, np.ndarray]) -> None:
        self.reset()
        self.history_t, self.history_z, self.history_v = (
            np.array(state[k], dtype=float) for k in ("history_t", "history_z", "history_v"))
        run = int(state["road_run"][0])
        self._uniform_run = None if run < 0 else run
        raw = np.asarray(state["road_line"], dtype=float)
        if raw.size:
            h = float(raw[0])
            line = _DelayLine(self.windows, h, [], [], [])
            if raw.size != 4 + line._buffer.size:
                raise ValueError(f"road delay line of {raw.size - 4} values, expected "
                                 f"{line._buffer.size}")
            line._start, line._count = int(raw[1]), int(raw[2])
            line.newest_time = float(raw[3])
            line._buffer[:] = raw[4:]
            self._line, self._line_h = line, h

    # -- reading ---------------------------------------------------------------------------
    def read(self, now: float, z: float, vz: float, h: float, out: np.ndarray) -> None:
        """Record the sample of communication point ``now`` (replacing one already there) and
        write the road under each node at ``now`` into ``out`` = [heights, slopes], the
        caller's one buffer (the same read again leaves it as the last read wrote it).

        ``h`` is the step about to be taken: once the samples are h apart over the whole
        reach of the windows, a delay line with fixed weights takes over (the rule depends on
        the history and h alone, so a restored state takes the same path, bit for bit).
        """
        n = self.windows.early_s.size
        if not self.delayed:
            out[:n] = z
            out[n:] = vz
            return
        read = (now, z, vz, h)
        if read == self._last_read:  # the same point again (outputs read, then the step)
            return
        self._last_read = read
        line = self._line
        if line is not None and abs(h - self._line_h) <= SAME_POINT_EPS * (abs(now) + h):
            line.push(now, z, vz)
            line.read_into(out)
            return
        if line is not None:  # the step size changed: back to the recorded history
            self.history_t, self.history_z, self.history_v = line.history()
            self._line, self._uniform_run = None, None
        appended = self._record(now, z, vz)
        if not (h > 0 and math.isfinite(h)):  # no step size yet: read the history
            out[:n], out[n:] = window_reads(self.history_t, self.history_z,
                                            self.history_v, now, self.windows)
            return
        needed = _DelayLine.samples_needed(self.windows, h)
        resolution = SAME_POINT_EPS * (abs(now) + h)
        t = self.history_t
        if self._uniform_run is None:
            self._uniform_run = _uniform_run(t, h, resolution)
        elif appended:
            uniform = t.size > 1 and abs(t[-1] - t[-2] - h) <= resolution
            self._uniform_run = self._uniform_run + 1 if uniform else 1
        if self._uniform_run >= needed and self.delay_line:
            self._line = _DelayLine(self.windows, h, self.history_t[-needed:],
                                    self.history_z[-needed:], self.history_v[-needed:])
            self._line_h = h
            self._line.read_into(out)
            return
        out[:n], out[n:] = window_reads(self.history_t, self.history_z, self.history_v, now,
                                        self.windows)

    def _record(self, now: float, z: float, vz: float) -> bool:
        """Add the sample of ``now``, or replace the newest if it is that point again."""
        t = self.history_t
        if t.size and t[-1] >= now - SAME_POINT_EPS * (abs(now) + 1.0):
            # the same communication point again (a retried step): replace, never duplicate
            self.history_z[-1], self.history_v[-1] = z, vz
            return False
        # keep what the longest window can still reach, plus the sample just before it
        keep = max(int(np.searchsorted(t, now - self.horizon_s, side="right")) - 1, 0)
        self.history_t = np.append(t[keep:], now)
        self.history_z = np.append(self.history_z[keep:], z)
        self.history_v = np.append(self.history_v[keep:], vz)
        return True


def _uniform_run(times: np.ndarray, h: float, resolution: float) -> int:
    """How many samples at the end of ``times`` are spaced h apart (0 for none)."""
    if not times.size:
        return 0
    regular = np.abs(np.diff(times) - h) <= resolution
    irregular = np.flatnonzero(~regular)
    return times.size - (irregular[-1] + 1 if irregular.size else 0)


class _DelayLine:
    """Window reads for steps of one size h from a ring buffer of samples.

    Each sample k holds (z, v·h, C) with C the running integral of the road up to it (over h,
    re-based when the buffer wraps so it never grows large). A window end at lag ℓ + s (s in
    [0, 1) of the interval from sample ℓ+1 to sample ℓ, newest = lag 0) reads
    I = h·(C_{ℓ+1} + ∫_0^{1-s} H) and z = H(1-s): five fixed weights on two samples. Every
    sample is written twice, one buffer length apart, so the window is contiguous.
    """

    def __init__(self, windows: RoadWindows, h: float, times, heights, slopes):
        self.h = h
        self.size = self.samples_needed(windows, h)
        n = windows.early_s.size
        width = windows.late_s - windows.early_s
        ends = np.concatenate([windows.early_s, windows.late_s]) / h  # lag of each end
        older = np.floor(ends + LAG_SLACK).astype(int) + 1  # the older sample of its interval
        s = np.clip(older - ends, 0.0, 1.0)  # fraction from the older sample to the newer
        s2, s3 = s * s, s * s * s
        weights_z = np.stack([2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2,
                              s3 - s2], -1)  # on z_o, v_o h, z_n, v_n h
        ints = np.stack([0.5 * s2 * s2 - s3 + s, 0.25 * s2 * s2 - 2 * s3 / 3 + 0.5 * s2,
                         -0.5 * s2 * s2 + s3, 0.25 * s2 * s2 - s3 / 3], -1)
        # gather layout per end: [z_o, v_o, C_o, z_n, v_n] at columns of the buffer rows
        lag_o, lag_n = older, older - 1
        self._index = np.stack([3 * lag_o, 3 * lag_o + 1, 3 * lag_o + 2, 3 * lag_n,
                                3 * lag_n + 1], -1).reshape(-1)
        combine = np.zeros((2 * n, 2 * n * 5))
        for end in range(2 * n):
            node, sign = end % n, (1.0 if end < n else -1.0)
            cols = slice(5 * end, 5 * end + 5)
            # window mean: (I(early) - I(late)) / width, I = h (C_o + ∫_0^s H)
            combine[node, cols] = sign * h / width[node] * np.array(
                [ints[end, 0], ints[end, 1], 1.0, ints[end, 2], ints[end, 3]])
            # slope: (z(early) - z(late)) / width
            combine[n + node, cols] = sign / width[node] * np.array(
                [weights_z[end, 0], weights_z[end, 1], 0.0, weights_z[end, 2],
                 weights_z[end, 3]])
        self._combine = np.asfortranarray(combine)
        self._gathered = np.zeros(self._index.size)
        self._buffer = np.zeros(6 * self.size)  # each sample twice: [z, v h, C] x 2 windows
        self._start = 0  # buffer row of the newest sample
        self.newest_time = math.nan
        self._count = 0
        for t, z, v in zip(times, heights, slopes):  # oldest first
            self.push(float(t), float(z), float(v))

    @classmethod
    def samples_needed(cls, windows: RoadWindows, h: float) -> int:
        """Samples a read reaches: the older sample of the latest window end, and lag 0."""
        return int(np.floor(windows.horizon_s / h + LAG_SLACK)) + 2

    def push(self, time: float, z: float, v: float) -> None:
        """Add the sample of communication point ``time``; the same point again replaces it."""
        vh = v * self.h
        size, buffer = self.size, self._buffer
        if abs(time - self.newest_time) < 0.5 * self.h:
            row = self._start  # replace: its integral follows from the sample before it
        else:
            row = (self._start - 1) % size
            self._start, self.newest_time = row, time
            self._count += 1
        if self._count == 1:
            c = 0.0
        else:
            older = 3 * ((row + 1) % size)
            z0, v0 = buffer[older], buffer[older + 1]
            c = buffer[older + 2] + (0.5 * (z0 + z) + (v0 - vh) / 12.0)
        for offset in (0, size):
            base = 3 * (row + offset)
            buffer[base], buffer[base + 1], buffer[base + 2] = z, vh, c
        if row == 0 and c != 0.0:
            # re-base the integral on the newest sample (a read uses differences only), so it
            # never accumulates rounding over a long run
            buffer[2::3] -= c

    def read_into(self, out: np.ndarray) -> None:
        """[heights, slopes] into ``out`` (contiguous), in place."""
        self._buffer.take(self._index + 3 * self._start, out=self._gathered)
        dgemv(1.0, self._combine, self._gathered, 0.0, out, 0, 1, 0, 1, 0, 1)

    def history(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rows = (self._start + np.arange(self.size)) % self.size  # newest first
        z = self._buffer[3 * rows]
        v = self._buffer[3 * rows + 1] / self.h
        t = self.newest_time - np.arange(self.size) * self.h
        return t[::-1].copy(), z[::-1].copy(), v[::-1].copy()
