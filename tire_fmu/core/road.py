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

Times here are the simulator's time since its start (:mod:`.clock`), so the road under the
tread does not depend on when the run started. Only the tolerances that decide whether two
steps are the same step, which a host's clock jitters, are relative to the absolute time
origin + now: that is where the host's rounding lives.
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

    def __init__(self, windows: RoadWindows, delay_line: bool = True, origin_s: float = 0.0):
        self.windows = windows
        self.delayed = bool(np.any(windows.late_s > 0))
        self.horizon_s = windows.horizon_s
        self.delay_line = delay_line  # False: always read the history (a reference path)
        self.reset(origin_s)

    def reset(self, origin_s: float = 0.0) -> None:
        """Forget the history; times are read from now on as time since ``origin_s``."""
        self.origin_s = float(origin_s)
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

    def state_problems(self, state: dict[str, np.ndarray], now: float, last_step_s: float,
                       max_height_m: float, max_rate_m_s: float) -> list[str]:
        """What makes ``state`` (from :meth:`get_state`) no history this reader could hold at
        time ``now`` after a last step of ``last_step_s`` (nan: none), with samples of at
        most the inputs' limits: empty when it could.

        The rules follow from how the history is kept: one sample per communication point, at
        the step's start; none before the start and none in the future; the newest at the
        last step's start or at ``now``; every sample but the oldest within the horizon of
        the newest (older ones are dropped); and while a delay line runs, the history is its
        buffer, written twice, of exactly the samples it needs at the last step's size.
        """
        t, z, v = (np.asarray(state[k], dtype=float) for k in ("history_t", "history_z",
                                                               "history_v"))
        raw = np.asarray(state["road_line"], dtype=float)
        run = int(state["road_run"][0]) if np.size(state["road_run"]) == 1 else None
        if not self.delayed:
            if t.size or raw.size:
                return [f"its road history holds {t.size} samples, but at rest the whole zone "
                        "reads the road at the instant and keeps none"]
            return []
        problems = []
        slack = SAME_POINT_EPS * (abs(now) + self.horizon_s + 1.0)
        if not np.all(np.diff(t) > 0.0):
            problems.append("its road history times do not increase")
        if t.size:
            newest = float(t[-1])
            earliest = now - (last_step_s if math.isfinite(last_step_s) else 0.0)
            if not earliest - slack <= newest <= now + slack:
                problems.append(
                    f"its newest road sample is at {newest!r} s, but the state is at {now!r} s "
                    f"after a step of {last_step_s!r} s: the road is sampled at each step's "
                    "start")
            if t[0] < -slack:
                problems.append(f"its road history starts at {float(t[0])!r} s, before the "
                                "start")
            if t.size > 1 and t[1] < newest - self.horizon_s - slack:
                problems.append(
                    f"its road history reaches back {newest - float(t[1]):.6g} s from its newest "
                    f"sample, beyond the {self.horizon_s:.6g} s the contact zone reads (older "
                    "samples are dropped)")
        elif math.isfinite(last_step_s):
            problems.append("its road history is empty, but a step was taken (each step "
                            "samples the road at its start)")
        if not (np.all(np.abs(z) <= max_height_m) and np.all(np.abs(v) <= max_rate_m_s)):
            problems.append(f"its road samples go beyond the inputs' limits ({max_height_m:g} m, "
                            f"{max_rate_m_s:g} m/s)")
        if run is None or not -1 <= run <= t.size:
            problems.append(f"its count of uniform road samples is {state['road_run']!r}, not "
                            f"-1 or at most the {t.size} samples it holds")
        if raw.size:
            problems += self._line_problems(raw, t, z, v, now, last_step_s, max_height_m,
                                            max_rate_m_s)
        return problems

    def _line_problems(self, raw, t, z, v, now, last_step_s, max_height_m, max_rate_m_s):
        h = float(raw[0]) if raw.size >= 4 else math.nan
        resolution = SAME_POINT_EPS * (abs(self.origin_s + now) + h)
        if not (h > 0.0 and math.isfinite(last_step_s) and abs(h - last_step_s) <= resolution):
            return [f"its road delay line runs at steps of {h!r} s, but its last step was "
                    f"{last_step_s!r} s (a delay line runs only while the steps keep its size)"]
        reach = self.horizon_s / h
        size = _DelayLine.samples_needed(self.windows, h) if reach < raw.size else raw.size
        if raw.size != 4 + 6 * size:
            return [f"its road delay line holds {raw.size - 4} values; steps of {h!r} s need "
                    f"{6 * size}"]
        start, count, newest = raw[1], raw[2], float(raw[3])
        buffer = raw[4:]
        problems = []
        if not (start == int(start) and 0 <= start < size and count == int(count)
                and count >= size):
            problems.append(f"its road delay line's position {start!r} or count {count!r} is "
                            f"not one of a line of {size} samples")
            return problems
        if not np.array_equal(buffer[:3 * size], buffer[3 * size:]):
            problems.append("its road delay line's two copies differ")
        rows = (int(start) + np.arange(size)) % size  # newest first
        line_t = (newest - np.arange(size) * h)[::-1]
        if not (np.array_equal(t, line_t) and np.array_equal(z, buffer[3 * rows][::-1])
                and np.array_equal(v, (buffer[3 * rows + 1] / h)[::-1])):
            problems.append("its road history is not its delay line's")
        bound = 2 * size * (max_height_m + max_rate_m_s * h / 6.0)
        if not np.all(np.abs(buffer[2::3]) <= bound):
            problems.append(f"its road delay line's integrals go beyond {bound:.3g} m·steps, "
                            "more than samples within the inputs' limits sum to")
        return problems

    def set_state(self, state: dict[str, np.ndarray]) -> None:
        """Restore a state that :meth:`state_problems` found none in (keeps the origin)."""
        self.reset(self.origin_s)
        self.history_t, self.history_z, self.history_v = (
            np.array(state[k], dtype=float) for k in ("history_t", "history_z", "history_v"))
        run = int(state["road_run"][0])
        self._uniform_run = None if run < 0 else run
        raw = np.asarray(state["road_line"], dtype=float)
        if raw.size:
            h = float(raw[0])
            line = _DelayLine(self.windows, h, [], [], [])
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
        # what a host's clock resolves at the absolute time: the step sizes it passes jitter
        # by that much, and a jittered step is the same step
        resolution = SAME_POINT_EPS * (abs(self.origin_s + now) + h)
        if line is not None and abs(h - self._line_h) <= resolution:
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
