"""Short road obstacles: cleats and potholes, as height profiles along the road.

One definition, used by the cleat study (:func:`.studies.cleat_convergence`), by the vehicle
demo's road signals (``vehicle_demo/road.py``) and by the tests. An obstacle of height H
(negative: a pothole of depth -H) and length L across the road is a function of s, the
distance along the road behind its first edge (the edge a rolling tire meets first):

- rectangular: H for 0 <= s < L, else 0 (its edges are steps; the tire's contact points
  average them over their own windows of road);
- rounded: a (1 - cos) bump, H/2 (1 - cos 2πs/L) on 0 <= s < L, with its slope.

A longer road (a random ISO 8608 profile, a measured one) is a :class:`SampledRoad`: heights
every ``spacing_m`` from s = 0, linear between them. A road read from a file is a
:class:`ProfileRoad`: heights at any strictly increasing distances, linear between them and
level at its end heights beyond them. All answer what the in-plane simulator asks of a road,
the mean height over each contact point's window, from their exact integral.

The cleats of the SAE tire tests that have no length of their own are here too:
:class:`TriangularCleat` (SAE J2705's triangular cleats, given by their apex half-angle, with
a rounded crown) and :class:`StepCleat` (J2705's step, its top edge rounded).
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


def sampled_reads(s, z, at, x) -> tuple[np.ndarray, np.ndarray]:
    """(height, integral) at each ``x`` of the road through the samples (s, z) with running
    integral ``at`` (trapezoids from the first sample): linear between samples, level at the
    end heights beyond them (native/c/inplane_step.c's road_read, the same arithmetic)."""
    x = np.asarray(x, dtype=float)
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
    height = z_k + slope * past
    return height, at[k] + (z_k + 0.5 * slope * past) * past + (x - inside) * height


def sampled_window_reads(s, z, at, s_lo, s_hi, speed_m_s: float
                         ) -> tuple[np.ndarray, np.ndarray]:
    """(mean height, its rate) over each window [s_lo, s_hi] of the sampled road as it passes at
    ``speed_m_s``: the rate of a window mean is the speed times the difference of the heights
    at its ends over its width (the profile is continuous, so this is exact)."""
    n = len(s_lo)
    height, integral = sampled_reads(s, z, at, np.concatenate([s_lo, s_hi]))
    width = np.asarray(s_hi) - np.asarray(s_lo)
    safe = np.where(width > 0, width, 1.0)
    mean = np.where(width > 0, (integral[n:] - integral[:n]) / safe, height[:n])
    return mean, speed_m_s * (height[n:] - height[:n]) / safe


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


#: The most knots a :class:`ProfileRoad` holds (a road file's cross sections: 10 million, 10 km
#: at 1 mm, 80 MB for each array).
MAX_PROFILE_KNOTS = 10_000_000


@dataclass(frozen=True, eq=False)
class ProfileRoad(_WindowMeans):
    """A road profile through knots: ``heights_m`` at ``distances_m`` (strictly increasing, any
    spacing), linear between knots, and beyond them level at the first height before the first
    knot and at the last height after the last (OpenCRG's default border mode, "keep the last
    value"). :attr:`extent_m` is the stretch the knots cover, so that a user can say when a
    wheel has left it."""

    distances_m: np.ndarray
    heights_m: np.ndarray
    description: str = "road profile"

    def __post_init__(self) -> None:
        distances = np.asarray(self.distances_m, dtype=float)
        heights = np.asarray(self.heights_m, dtype=float)
        problems = []
        if distances.ndim != 1 or not 2 <= distances.size <= MAX_PROFILE_KNOTS:
            problems.append(Problem("distances_m", f"shape {distances.shape}", "",
                                    f"a 1-D array of 2 to {MAX_PROFILE_KNOTS} distances"))
        elif not np.all(np.isfinite(distances)):
            problems.append(Problem("distances_m", "a non-finite distance", "m", "finite"))
        elif not np.all(np.diff(distances) > 0):
            k = int(np.argmin(np.diff(distances) > 0))
            problems.append(Problem("distances_m", f"{distances[k + 1]!r} after "
                                    f"{distances[k]!r}", "m", "strictly increasing"))
        if heights.shape != distances.shape:
            problems.append(Problem("heights_m", f"shape {heights.shape}", "",
                                    f"one height per distance (shape {distances.shape})"))
        elif not np.all(np.isfinite(heights)):
            problems.append(Problem("heights_m", "a non-finite height", "m", "finite"))
        if problems:
            raise ParameterError(problems)
        for name, values in (("distances_m", distances), ("heights_m", heights)):
            values = values.copy()
            values.flags.writeable = False
            object.__setattr__(self, name, values)
        # the integral at each knot from the first (trapezoids: exact for the linear profile)
        steps = 0.5 * np.diff(distances) * (heights[1:] + heights[:-1])
        object.__setattr__(self, "_at_knots", np.r_[0.0, np.cumsum(steps)])

    @property
    def extent_m(self) -> tuple[float, float]:
        """(first, last) distance the knots cover (m); the road is level beyond them."""
        return float(self.distances_m[0]), float(self.distances_m[-1])

    def window_reads(self, s_lo, s_hi, speed_m_s: float) -> tuple[np.ndarray, np.ndarray]:
        """(mean height, its rate) over each window [s_lo, s_hi] as the road passes at
        ``speed_m_s`` (:func:`sampled_window_reads`: the C reads a road file so too)."""
        return sampled_window_reads(self.distances_m, self.heights_m, self._at_knots, s_lo,
                                    s_hi, speed_m_s)

    @property
    def length_m(self) -> float:
        return float(self.distances_m[-1] - self.distances_m[0])

    @property
    def label(self) -> str:
        return self.description

    def _segment(self, s) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(s, the knot each s follows, s clipped to the extent, the segment's slope)."""
        s = np.asarray(s, dtype=float)
        d, h = self.distances_m, self.heights_m
        k = np.clip(np.searchsorted(d, s, side="right") - 1, 0, d.size - 2)
        inside = np.clip(s, d[0], d[-1])
        slope = (h[k + 1] - h[k]) / (d[k + 1] - d[k])
        return s, k, inside, slope

    def profile(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(height, slope dz/ds) at ``s`` (m): level, slope 0, beyond the extent."""
        s, k, inside, slope = self._segment(s)
        height = self.heights_m[k] + slope * (inside - self.distances_m[k])
        on = (s >= self.distances_m[0]) & (s <= self.distances_m[-1])
        return height, np.where(on, slope, 0.0)

    def integral(self, s) -> np.ndarray:
        """∫ of the height from the first knot to ``s`` (m²; negative before it, the level
        road's beyond either end)."""
        s, k, inside, slope = self._segment(s)
        past = inside - self.distances_m[k]
        height = self.heights_m[k] + slope * past
        return (self._at_knots[k] + (self.heights_m[k] + 0.5 * slope * past) * past
                + (s - inside) * height)


#: The largest crown radius of a cleat here (m): SAE J2705 asks for 1.5 to 3.0 mm.
MAX_CROWN_RADIUS_M = 0.05


def _cleat_problems(height_m: float, crown_radius_m: float) -> list[Problem]:
    problems = []
    if not (isinstance(height_m, (int, float)) and math.isfinite(height_m)
            and 0 < height_m <= MAX_OBSTACLE_SIZE_M):
        problems.append(Problem("height_m", height_m, "m",
                                f"in (0, {MAX_OBSTACLE_SIZE_M:g}] m"))
    if not (isinstance(crown_radius_m, (int, float)) and math.isfinite(crown_radius_m)
            and 0 <= crown_radius_m <= MAX_CROWN_RADIUS_M):
        problems.append(Problem("crown_radius_m", crown_radius_m, "m",
                                f"in [0, {MAX_CROWN_RADIUS_M:g}] m"))
    elif problems == [] and crown_radius_m >= height_m:
        problems.append(Problem("crown_radius_m", crown_radius_m, "m",
                                f"below the height ({height_m:g} m)"))
    return problems


def _arc_area(x, r: float) -> np.ndarray:
    """∫_0^x sqrt(r² - t²) dt for |x| <= r."""
    x = np.clip(x, -r, r)
    if r == 0:
        return np.zeros_like(x)
    return 0.5 * (x * np.sqrt(np.maximum(r * r - x * x, 0.0)) + r * r * np.arcsin(x / r))


@dataclass(frozen=True)
class TriangularCleat(_WindowMeans):
    """A triangular cleat across the road (SAE J2705): flanks at ``half_angle_deg`` from the
    vertical, its apex rounded with ``crown_radius_m``, ``height_m`` to the top of the crown,
    its base from s = 0 to :attr:`length_m`."""

    height_m: float
    half_angle_deg: float = 45.0
    crown_radius_m: float = 0.002

    def __post_init__(self) -> None:
        problems = _cleat_problems(self.height_m, self.crown_radius_m)
        if not (isinstance(self.half_angle_deg, (int, float))
                and 10.0 <= self.half_angle_deg <= 89.0):
            problems.append(Problem("half_angle_deg", self.half_angle_deg, "deg",
                                    "in [10, 89] deg", "SAE J2705 uses 45, 60, 75, 80, 85"))
        if problems:
            raise ParameterError(problems)

    @property
    def _apex_m(self) -> float:
        """The sharp apex's height, above the crown's top."""
        alpha = math.radians(self.half_angle_deg)
        return self.height_m + self.crown_radius_m * (1.0 / math.sin(alpha) - 1.0)

    @property
    def length_m(self) -> float:
        """The base's length (m)."""
        return 2.0 * self._apex_m * math.tan(math.radians(self.half_angle_deg))

    @property
    def label(self) -> str:
        return (f"{self.height_m * 1e3:g} mm triangular cleat, half-angle "
                f"{self.half_angle_deg:g} deg, crown radius {self.crown_radius_m * 1e3:g} mm")

    def _parts(self):
        alpha = math.radians(self.half_angle_deg)
        r = self.crown_radius_m
        return 0.5 * self.length_m, r * math.cos(alpha), 1.0 / math.tan(alpha), r

    def profile(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(height, slope) at ``s`` (m) from the base's first edge."""
        s = np.asarray(s, dtype=float)
        half, crown, cot, r = self._parts()
        x = s - half
        flank = self._apex_m - np.abs(x) * cot
        on_crown = np.abs(x) < crown
        arc = np.sqrt(np.maximum(r * r - x * x, 0.0))
        height = np.where(on_crown, self.height_m - r + arc, np.maximum(flank, 0.0))
        slope = np.where(on_crown, -x / np.where(arc > 0, arc, 1.0), -np.sign(x) * cot)
        off = (s < 0) | (s > self.length_m)
        return np.where(off, 0.0, height), np.where(off, 0.0, slope)

    def integral(self, s) -> np.ndarray:
        """∫ of the height from s = 0 to ``s`` (m²)."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length_m)
        half, crown, cot, r = self._parts()
        x = s - half  # from the axis
        rising = 0.5 * cot * np.minimum(s, half - crown) ** 2
        on = np.clip(x, -crown, crown)
        crest = (self.height_m - r) * (on + crown) + _arc_area(on, r) - _arc_area(-crown, r)
        past = np.maximum(x, crown)
        falling = self._apex_m * (past - crown) - 0.5 * cot * (past * past - crown * crown)
        return rising + np.where(x > -crown, crest, 0.0) + falling


@dataclass(frozen=True)
class StepCleat(_WindowMeans):
    """A step up of ``height_m`` at s = 0, level beyond (SAE J2705's step cleat): a vertical
    face, its top edge rounded with ``crown_radius_m``."""

    height_m: float
    crown_radius_m: float = 0.002

    def __post_init__(self) -> None:
        problems = _cleat_problems(self.height_m, self.crown_radius_m)
        if problems:
            raise ParameterError(problems)

    @property
    def label(self) -> str:
        return (f"{self.height_m * 1e3:g} mm step, top edge radius "
                f"{self.crown_radius_m * 1e3:g} mm")

    def profile(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(height, slope) at ``s`` (m); the face at s = 0 is a jump (slope 0 there)."""
        s = np.asarray(s, dtype=float)
        r = self.crown_radius_m
        x = np.clip(s - r, -r, 0.0)
        arc = np.sqrt(np.maximum(r * r - x * x, 0.0))
        on_edge = (s >= 0) & (s < r)
        height = np.where(s < 0, 0.0, np.where(on_edge, self.height_m - r + arc,
                                                 self.height_m))
        slope = np.where(on_edge, -x / np.where(arc > 0, arc, 1.0), 0.0)
        return height, slope

    def integral(self, s) -> np.ndarray:
        """∫ of the height from s = 0 to ``s`` (m²; 0 before the face)."""
        s = np.maximum(np.asarray(s, dtype=float), 0.0)
        r = self.crown_radius_m
        edge = np.minimum(s, r)
        over_edge = (self.height_m - r) * edge + _arc_area(edge - r, r) - _arc_area(-r, r)
        return over_edge + self.height_m * np.maximum(s - r, 0.0)


def cell_means(shape: _WindowMeans, s, spacing_m: float) -> np.ndarray:
    """The heights a road sampled every ``spacing_m`` at ``s`` holds for ``shape``: its mean
    over each sample's stretch [s - spacing/2, s + spacing/2], from its exact integral. The
    linear interpolant of such samples has the shape's exact integral at every sample (its
    trapezoid sum telescopes), whatever the phase of an edge between samples, so the window
    means the contact points read keep the obstacle's area; an edge becomes a ramp one
    spacing long."""
    s = np.asarray(s, dtype=float)
    half = 0.5 * spacing_m
    return shape.mean_height(s - half, s + half)


def sampled_obstacle(shape: _WindowMeans, spacing_m: float, lead_in_m: float = 1.0,
                     lead_out_m: float = 1.0, description: str | None = None) -> ProfileRoad:
    """``shape`` (an :class:`Obstacle`, a :class:`TriangularCleat`, a :class:`StepCleat`)
    after ``lead_in_m`` of level road, ``lead_out_m`` of road after it (level at 0, or at the
    step's top), sampled every ``spacing_m`` from distance 0 by :func:`cell_means`."""
    problems = []
    if not (math.isfinite(spacing_m) and 1e-5 <= spacing_m <= 1.0):
        problems.append(Problem("spacing_m", spacing_m, "m", "in [1e-05, 1] m"))
    for name, value in (("lead_in_m", lead_in_m), ("lead_out_m", lead_out_m)):
        if not (math.isfinite(value) and 0 <= value <= 1e4):
            problems.append(Problem(name, value, "m", "in [0, 10000] m"))
    if problems:
        raise ParameterError(problems)
    length = lead_in_m + getattr(shape, "length_m", 0.0) + lead_out_m
    count = int(math.ceil(length / spacing_m - 1e-9)) + 1
    if count > MAX_PROFILE_KNOTS:
        raise ParameterError([Problem("spacing_m", spacing_m, "m",
                                      f"at least {length / (MAX_PROFILE_KNOTS - 1):.3g} m",
                                      f"{MAX_PROFILE_KNOTS} points at most")])
    s = spacing_m * np.arange(max(count, 2))
    return ProfileRoad(s, cell_means(shape, s - lead_in_m, spacing_m),
                       description or shape.label)


def cleat(height_m: float, length_m: float, shape: str = "rectangular") -> Obstacle:
    return Obstacle(float(height_m), float(length_m), shape)


def pothole(depth_m: float, length_m: float, shape: str = "rectangular") -> Obstacle:
    return Obstacle(-float(depth_m), float(length_m), shape)


class _SampledRoad(_WindowMeans):
    """A road held as samples (positions, heights and the running integral of the height, the
    trapezoids from the first sample kept), linear between them and level beyond them; the
    samples live in columns [lo, hi) of a buffer that grows by doubling (samples a step: no
    copy of the history per sample). Subclasses add and forget samples."""

    def __init__(self):
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

    def state(self) -> np.ndarray:
        """(samples, 3): positions, heights and the running integral, what :meth:`restore`
        takes back (the integral too, so that a restored road reads the same bits)."""
        return self._buffer[:, self._lo:self._hi].T.copy()

    def restore(self, samples: np.ndarray) -> None:
        samples = np.asarray(samples, dtype=float).reshape(-1, 3)
        n = samples.shape[0]
        self._buffer = np.zeros((3, max(64, 2 * n + 2)))
        self._buffer[:, :n] = samples.T
        self._lo, self._hi = 0, n

    def window_reads(self, s_lo, s_hi, speed_m_s: float) -> tuple[np.ndarray, np.ndarray]:
        """(mean height, its rate) over each window [s_lo, s_hi] as the road passes at
        ``speed_m_s`` (:func:`sampled_window_reads`)."""
        return sampled_window_reads(self.s, self.z, self._at, s_lo, s_hi, speed_m_s)

    def profile(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(height, slope dz/ds) at ``s`` (m)."""
        x = np.asarray(s, dtype=float)
        height, _ = sampled_reads(self.s, self.z, self._at, x)
        if self.s.size < 2:
            return height, np.zeros(x.shape)
        gap = np.diff(self.s)
        k = np.clip(np.searchsorted(self.s, x, side="right") - 1, 0, self.s.size - 2)
        inside = (x >= self.s[0]) & (x <= self.s[-1])
        return height, np.where(inside, np.diff(self.z)[k] / gap[k], 0.0)

    def integral(self, s) -> np.ndarray:
        """∫ of the height from the first sample kept to ``s`` (m²; level outside)."""
        return sampled_reads(self.s, self.z, self._at, np.asarray(s, dtype=float))[1]


class PositionRoad(_SampledRoad):
    """A road a host gives by samples at positions along it (m), linear between them, level at
    the first sample before it and at the newest beyond it: the FMUs' host road, sampled where
    they ask (their ``road_x_i`` outputs) at the contact points' resolution. A sample at a
    position already held replaces its height (at rest the host's road moves under a still tire
    so: a shaker plate); one between held positions is inserted. Samples further behind the
    newest than ``keep_m`` are forgotten (the one just before that reach is kept)."""

    label = "the host's road"
    #: Positions closer than this (relative to their magnitude, or 1e-12 m) are one position.
    SAME_POSITION = 1e-12

    def __init__(self, keep_m: float):
        super().__init__()
        self.keep_m = float(keep_m)

    def set_samples(self, positions, heights) -> None:
        """The host's heights at these positions (m, any order): appended beyond the newest,
        replacing a height held at the same position, inserted between others."""
        b = self._buffer
        first_changed = None
        for x, z in sorted(zip(np.asarray(positions, float).ravel(),
                               np.asarray(heights, float).ravel())):
            lo, hi = self._lo, self._hi
            k = lo + int(np.searchsorted(b[0, lo:hi], x))
            same = abs(x) * self.SAME_POSITION + 1e-12
            if k < hi and abs(b[0, k] - x) <= same:
                b[1, k] = z
            elif k > lo and abs(b[0, k - 1] - x) <= same:
                k -= 1
                b[1, k] = z
            else:
                if hi == b.shape[1]:
                    live = hi - lo
                    grown = np.zeros((3, max(64, 2 * live + 2)))
                    grown[:, :live] = b[:, lo:hi]
                    k -= lo
                    if first_changed is not None:  # its index moves with the samples
                        first_changed -= lo
                    self._buffer, b, self._lo, self._hi, lo, hi = grown, grown, 0, live, 0, live
                b[:, k + 1:hi + 1] = b[:, k:hi].copy()
                b[0, k], b[1, k] = x, z
                self._hi = hi = hi + 1
            first_changed = k if first_changed is None else min(first_changed, k)
        if first_changed is None:
            return
        self._integrate_from(first_changed)
        self._forget()

    def _integrate_from(self, k: int) -> None:
        """The running integral again from sample k on (trapezoids from the first kept)."""
        b, lo, hi = self._buffer, self._lo, self._hi
        if k <= lo:
            b[2, lo] = 0.0
            k = lo + 1
        for i in range(k, hi):
            b[2, i] = b[2, i - 1] + 0.5 * (b[0, i] - b[0, i - 1]) * (b[1, i] + b[1, i - 1])

    def _forget(self) -> None:
        b, lo, hi = self._buffer, self._lo, self._hi
        if hi - lo < 2:
            return
        reach = b[0, hi - 1] - self.keep_m
        self._lo = max(int(np.searchsorted(b[0, lo:hi], reach, side="right")) - 1, 0) + lo



class HostRoad(_SampledRoad):
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
        super().__init__()
        self.front_m, self.keep_m = float(front_m), float(keep_m)

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


