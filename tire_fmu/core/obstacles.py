"""Short road obstacles: cleats and potholes, as height profiles along the road.

One definition, used by the cleat study (:func:`.studies.cleat_convergence`), by the vehicle
demo's road signals (``vehicle_demo/road.py``) and by the tests. An obstacle of height H
(negative: a pothole of depth -H) and length L across the road is a function of s, the
distance along the road behind its first edge (the edge a rolling tire meets first):

- rectangular: H for 0 <= s < L, else 0 (its edges are steps; the tire's contact points
  average them over their own windows of road);
- rounded: a (1 - cos) bump, H/2 (1 - cos 2πs/L) on 0 <= s < L, with its slope.

A longer road (a random ISO 8608 profile, a measured one) is a :class:`SampledRoad`: heights
every ``spacing_m`` from s = 0, linear between them. Both answer what the in-plane simulator
asks of a road, the mean height over each contact point's window, from their exact integral.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .parameters import ParameterError, Problem

OBSTACLE_SHAPES = ("rectangular", "rounded")
#: Obstacles higher (or deeper) than this are outside what a tire model is asked to meet.
MAX_OBSTACLE_SIZE_M = 0.3
#: Obstacles longer than this are roads, not obstacles.
MAX_OBSTACLE_LENGTH_M = 10.0


class _WindowMeans:
    """The mean of a height profile over windows of road, from its exact integral."""

    def mean_height(self, s_lo, s_hi) -> np.ndarray:
        """Mean height over the road [s_lo, s_hi] (the height itself where s_lo = s_hi)."""
        s_lo, s_hi = np.asarray(s_lo, dtype=float), np.asarray(s_hi, dtype=float)
        width = s_hi - s_lo
        point = width <= 0
        mean = (self.integral(s_hi) - self.integral(s_lo)) / np.where(point, 1.0, width)
        return np.where(point, self.profile(s_lo)[0], mean)


@dataclass(frozen=True)
class Obstacle(_WindowMeans):
    """A cleat (``height_m > 0``) or a pothole (``height_m < 0``) of ``length_m``."""

    height_m: float
    length_m: float
    shape: str = "rectangular"

    def __post_init__(self) -> None:
        problems = []
        if not (isinstance(self.height_m, (int, float)) and math.isfinite(self.height_m)
                and 0 < abs(self.height_m) <= MAX_OBSTACLE_SIZE_M):
            problems.append(Problem("height_m", self.height_m, "m",
                                    f"in [-{MAX_OBSTACLE_SIZE_M:g}, {MAX_OBSTACLE_SIZE_M:g}] m "
                                    "and not 0", "negative: a pothole"))
        if not (isinstance(self.length_m, (int, float)) and math.isfinite(self.length_m)
                and 0 < self.length_m <= MAX_OBSTACLE_LENGTH_M):
            problems.append(Problem("length_m", self.length_m, "m",
                                    f"in (0, {MAX_OBSTACLE_LENGTH_M:g}] m"))
        if self.shape not in OBSTACLE_SHAPES:
            problems.append(Problem("shape", self.shape, "",
                                    f"one of {', '.join(OBSTACLE_SHAPES)}"))
        if problems:
            raise ParameterError(problems)

    @property
    def kind(self) -> str:
        return "cleat" if self.height_m > 0 else "pothole"

    @property
    def label(self) -> str:
        """``20 x 20 mm cleat``, ``50 mm deep pothole, 0.3 m long`` (rounded ones say so)."""
        size, length = abs(self.height_m) * 1e3, self.length_m * 1e3
        rounded = "rounded " if self.shape == "rounded" else ""
        if self.kind == "cleat":
            return f"{size:g} x {length:g} mm {rounded}cleat"
        return f"{size:g} mm deep {rounded}pothole, {length / 1e3:g} m long"

    def profile(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(height, slope dz/ds) at distances ``s`` (m) behind the first edge; a rectangular
        obstacle's slope is 0 (its edges are steps)."""
        s = np.asarray(s, dtype=float)
        on = (s >= 0) & (s < self.length_m)
        if self.shape == "rectangular":
            return np.where(on, self.height_m, 0.0), np.zeros_like(s)
        wave = 2 * np.pi * s / self.length_m
        height = np.where(on, 0.5 * self.height_m * (1 - np.cos(wave)), 0.0)
        slope = np.where(on, 0.5 * self.height_m * np.sin(wave) * 2 * np.pi / self.length_m,
                         0.0)
        return height, slope

    def integral(self, s) -> np.ndarray:
        """∫ of the height from the first edge to ``s`` (m²; 0 before it, constant after)."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length_m)
        if self.shape == "rectangular":
            return self.height_m * s
        wave = 2 * np.pi * s / self.length_m
        return 0.5 * self.height_m * (s - self.length_m / (2 * np.pi) * np.sin(wave))

    def road_samples(self, s, spacing_m: float) -> tuple[np.ndarray, np.ndarray]:
        """(height, slope) of a road signal sampled every ``spacing_m`` of road at ``s``.

        A rectangular obstacle is sampled by its mean over each sample's stretch of road
        [s - spacing/2, s + spacing/2], slope 0: the trapezoid sum of such samples, which is
        what a cubic Hermite interpolant with zero slopes integrates to, is then the exact
        integral of the steps at every sample, whatever the phase of the edges between
        samples (a point sample would shift each edge by up to half a sample). A rounded one
        is smooth: its height and slope at the sample."""
        if self.shape == "rectangular":
            s = np.asarray(s, dtype=float)
            half = 0.5 * spacing_m
            return self.mean_height(s - half, s + half), np.zeros_like(s)
        return self.profile(s)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "height_m": self.height_m, "length_m": self.length_m,
                "shape": self.shape, "label": self.label}


@dataclass(frozen=True, eq=False)
class SampledRoad(_WindowMeans):
    """A road profile: ``heights_m`` every ``spacing_m`` from s = 0, linear between samples,
    level (0) before the first and after the last."""

    spacing_m: float
    heights_m: np.ndarray
    description: str = "sampled road"

    def __post_init__(self) -> None:
        heights = np.asarray(self.heights_m, dtype=float)
        problems = []
        if not (isinstance(self.spacing_m, (int, float)) and math.isfinite(self.spacing_m)
                and 1e-5 <= self.spacing_m <= 1.0):
            problems.append(Problem("spacing_m", self.spacing_m, "m", "in [1e-05, 1] m"))
        if heights.ndim != 1 or heights.size < 2:
            problems.append(Problem("heights_m", f"shape {heights.shape}", "",
                                    "a 1-D array of at least 2 samples"))
        elif not (np.all(np.isfinite(heights))
                  and np.max(np.abs(heights)) <= MAX_OBSTACLE_SIZE_M):
            worst = heights[np.argmax(np.where(np.isfinite(heights), np.abs(heights), np.inf))]
            problems.append(Problem("heights_m", float(worst), "m",
                                    f"finite and in [-{MAX_OBSTACLE_SIZE_M:g}, "
                                    f"{MAX_OBSTACLE_SIZE_M:g}] m"))
        if problems:
            raise ParameterError(problems)
        heights = heights.copy()
        heights.flags.writeable = False
        object.__setattr__(self, "heights_m", heights)
        # the integral at each sample (trapezoids, exact for the linear profile)
        steps = 0.5 * self.spacing_m * (heights[1:] + heights[:-1])
        object.__setattr__(self, "_at_samples", np.r_[0.0, np.cumsum(steps)])

    @property
    def length_m(self) -> float:
        return self.spacing_m * (self.heights_m.size - 1)

    @property
    def label(self) -> str:
        return self.description

    def _segment(self, s) -> tuple[np.ndarray, np.ndarray]:
        """The sample each s follows and its distance past it, s clipped to the profile."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length_m)
        k = np.minimum((s / self.spacing_m).astype(int), self.heights_m.size - 2)
        return k, s - k * self.spacing_m

    def profile(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(height, slope dz/ds) at ``s`` (m); 0 off the profile."""
        s = np.asarray(s, dtype=float)
        k, past = self._segment(s)
        h = self.heights_m
        slope = (h[k + 1] - h[k]) / self.spacing_m
        on = (s >= 0) & (s <= self.length_m)
        return np.where(on, h[k] + slope * past, 0.0), np.where(on, slope, 0.0)

    def integral(self, s) -> np.ndarray:
        """∫ of the height from s = 0 to ``s`` (m²; 0 before, constant after the profile)."""
        k, past = self._segment(s)
        h = self.heights_m
        slope = (h[k + 1] - h[k]) / self.spacing_m
        return self._at_samples[k] + h[k] * past + 0.5 * slope * past**2


def cleat(height_m: float, length_m: float, shape: str = "rectangular") -> Obstacle:
    return Obstacle(float(height_m), float(length_m), shape)


def pothole(depth_m: float, length_m: float, shape: str = "rectangular") -> Obstacle:
    return Obstacle(-float(depth_m), float(length_m), shape)


class HostRoad(_WindowMeans):
    """The road a host gives at one place ahead of the tire, kept along the road as it passes.

    The host gives the height at ``front_m`` ahead of the contact centre (the contact zone's
    front, where an FMU's ``road_z`` is measured) each time the tire has travelled to
    ``distance_m`` along the road; the profile is linear between those samples (at a step of
    1e-4 s and 20 m/s, 2 mm apart), level at the first sample before it and at the newest one
    ahead of it (nothing the points read lies ahead of the front). Samples further behind the
    front than ``keep_m`` are forgotten. A sample at a distance not beyond the newest (the
    tire at rest, or the host giving one point again) replaces it: the road under a tire that
    does not roll is not rewritten behind it, so this is a rolling road (at rest, a shaker
    plate moves every point at once, which the stepper does itself)."""

    label = "the host's road"

    def __init__(self, front_m: float, keep_m: float):
        self.front_m, self.keep_m = float(front_m), float(keep_m)
        # distances, heights and the running integral, live in rows [lo, hi) of a buffer
        # that grows by doubling (a sample a step: no copy of the history per sample)
        self._buffer = np.zeros((3, 64))
        self._lo = self._hi = 0

    @property
    def s(self) -> np.ndarray:
        return self._buffer[0, self._lo:self._hi]

    @property
    def z(self) -> np.ndarray:
        return self._buffer[1, self._lo:self._hi]

    @property
    def _at(self) -> np.ndarray:
        return self._buffer[2, self._lo:self._hi]

    def record(self, distance_m: float, height_m: float) -> None:
        """The host's height at the front when the tire has travelled ``distance_m``."""
        s = distance_m + self.front_m
        b, lo, hi = self._buffer, self._lo, self._hi
        if hi > lo and s <= b[0, hi - 1] + 1e-12 * max(1.0, abs(s)):
            b[1, hi - 1] = height_m
            if hi - lo > 1:
                b[2, hi - 1] = b[2, hi - 2] + 0.5 * (b[0, hi - 1] - b[0, hi - 2]) * (
                    b[1, hi - 1] + b[1, hi - 2])
            return
        # forget what lies behind the reach, keeping the sample just before it
        lo = max(int(np.searchsorted(b[0, lo:hi], s - self.keep_m, side="right")) - 1, 0) + lo
        if hi == b.shape[1]:
            live = hi - lo
            grown = np.zeros((3, max(64, 2 * live + 2)))
            grown[:, :live] = b[:, lo:hi]
            self._buffer, b, lo, hi = grown, grown, 0, live
        b[0, hi], b[1, hi] = s, height_m
        b[2, hi] = b[2, hi - 1] + 0.5 * (s - b[0, hi - 1]) * (height_m + b[1, hi - 1]) \
            if hi > lo else 0.0
        self._lo, self._hi = lo, hi + 1

    def state(self) -> np.ndarray:
        """(samples, 3): distances, heights and the running integral, what :meth:`restore`
        takes back (the integral too, so that a restored road reads the same bits)."""
        return self._buffer[:, self._lo:self._hi].T.copy()

    def restore(self, samples: np.ndarray) -> None:
        samples = np.asarray(samples, dtype=float).reshape(-1, 3)
        n = samples.shape[0]
        self._buffer = np.zeros((3, max(64, 2 * n + 2)))
        self._buffer[:, :n] = samples.T
        self._lo, self._hi = 0, n

    def _reads(self, x):
        """(height, integral) at each x: one search for both."""
        s, z, at = self.s, self.z, self._at
        n = s.size
        if n < 2:
            level = z[0] if n else 0.0
            return np.full(x.shape, level), level * (x - (s[0] if n else 0.0))
        k = np.searchsorted(s, x, side="right") - 1
        np.clip(k, 0, n - 2, out=k)
        s_k, z_k = s[k], z[k]
        slope = (z[k + 1] - z_k) / (s[k + 1] - s_k)
        inside = np.clip(x, s[0], s[-1])
        past = inside - s_k
        height = z_k + slope * past  # level at the end values outside the samples
        return height, at[k] + (z_k + 0.5 * slope * past) * past + (x - inside) * height

    def window_reads(self, s_lo, s_hi, speed_m_s: float) -> tuple[np.ndarray, np.ndarray]:
        """(mean height, its rate) over each window [s_lo, s_hi] as the road passes at
        ``speed_m_s``: the rate of a window mean is the speed times the difference of the
        heights at its ends over its width (the profile is continuous, so this is exact)."""
        n = len(s_lo)
        height, at = self._reads(np.concatenate([s_lo, s_hi]))
        width = np.asarray(s_hi) - np.asarray(s_lo)
        safe = np.where(width > 0, width, 1.0)
        mean = np.where(width > 0, (at[n:] - at[:n]) / safe, height[:n])
        return mean, speed_m_s * (height[n:] - height[:n]) / safe

    def profile(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(height, slope dz/ds) at ``s`` (m)."""
        x = np.asarray(s, dtype=float)
        height, _ = self._reads(x)
        if self.s.size < 2:
            return height, np.zeros(x.shape)
        gap = np.diff(self.s)
        k = np.clip(np.searchsorted(self.s, x, side="right") - 1, 0, self.s.size - 2)
        inside = (x >= self.s[0]) & (x <= self.s[-1])
        return height, np.where(inside, np.diff(self.z)[k] / gap[k], 0.0)

    def integral(self, s) -> np.ndarray:
        """∫ of the height from the first sample kept to ``s`` (m²; level outside)."""
        return self._reads(np.asarray(s, dtype=float))[1]
