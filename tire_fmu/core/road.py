"""The road under each contact node, from the road height a host gives at the front of the
contact zone.

The host gives ``road_z`` and ``road_vz`` at each communication point. Between points the road
is the cubic Hermite interpolant of those samples (exact for the ramps a step assumes), and
before the first point it is level at its first value. Node j sees the average of that history
over its window [t - late_j, t - early_j] (:class:`~.contact.RoadWindows`: the stretch of road
under its arc passed the zone front then), and its slope is the difference of the window's
end values over the window's duration. At V = 0 every window is the present instant.

Windows are read through the running integral of the interpolant, so a window costs the same
however many samples it spans. This module reads the recorded history (the numpy kernel's
reference path); the compiled kernel's road.c reads the same history, and once the steps have
had one size h for the whole reach of the windows it switches to a delay line that reads each
window end with fixed weights from a ring buffer of samples (the same values to rounding, a
test compares them).

Times here are the simulator's time since its start (:mod:`.clock`), so the road under the
tread does not depend on when the run started. Only the tolerances that decide whether two
steps are the same step, which a host's clock jitters, are relative to the absolute time
origin + now: that is where the host's rounding lives.
"""

from __future__ import annotations

import numpy as np

from .contact import RoadWindows

#: Communication points closer than this times the time are one point (a few ulps).
SAME_POINT_EPS = 8 * np.finfo(float).eps
#: Slack when a delay is cut into whole steps, so a delay of exactly k steps is k steps (the
#: delay line of road.c).
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
    """Keeps the road history a set of windows needs and reads the road under each point."""

    def __init__(self, windows: RoadWindows, origin_s: float = 0.0):
        self.windows = windows
        self.delayed = bool(np.any(windows.late_s > 0))
        self.horizon_s = windows.horizon_s
        self.reset(origin_s)

    def reset(self, origin_s: float = 0.0) -> None:
        """Forget the history; times are read from now on as time since ``origin_s``."""
        self.origin_s = float(origin_s)
        self.history_t = np.zeros(0)
        self.history_z = np.zeros(0)
        self.history_v = np.zeros(0)

    def history(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.history_t.copy(), self.history_z.copy(), self.history_v.copy()

    def read(self, now: float, z: float, vz: float, h: float, out: np.ndarray) -> None:
        """Record the sample of communication point ``now`` (replacing one already there) and
        write the road under each point at ``now`` into ``out`` = [heights, slopes]. (``h``,
        the step about to be taken, is what road.c's delay line keys on; reading the history
        does not need it.)"""
        n = self.windows.early_s.size
        if not self.delayed:
            out[:n] = z
            out[n:] = vz
            return
        self._record(now, z, vz)
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
