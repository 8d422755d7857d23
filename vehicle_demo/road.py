"""Road inputs for the tire FMU: height and velocity at the front of its contact zone (the
``road_z`` it takes), sampled at the communication points.

ISO 8608 random road: the profile of :func:`tire_fmu.core.iso8608.iso8608_profile` (one
generator for the demo and the road files ``tire-fmu road iso8608`` writes) seen at speed V:
height(t) = profile(V t), velocity = V times its exact slope. At speed V the time-frequency PSD
is G(f) = G_d(f/V)/V. The default band is ISO's, 0.011-2.83 cycles/m (up to 57 Hz at 20 m/s).
Each tread node of the tire sees the road averaged over its own arc, so wavelengths shorter
than a node's arc (4 cm at N = 100) are averaged out node by node, and the unilateral
footprint lets go of a dip it cannot follow.

Cleat: a short obstacle of height H and length L across the road, rectangular (its edges are
steps of the road history; each tread node averages them over its arc) or rounded, a
(1 - cos) bump. Pothole: the same shapes downwards. Their profiles are
:class:`tire_fmu.core.obstacles.Obstacle`'s, the ones the cleat study reads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tire_fmu.core.iso8608 import (  # noqa: F401  (the demo's names for them)
    ISO_8608_GD_N0_M3,
    ISO_N_MAX_CYCLES_PER_M,
    ISO_N_MIN_CYCLES_PER_M,
    N0_CYCLES_PER_M,
    WAVINESS,
    Iso8608Spectrum,
    iso8608_profile,
)
from tire_fmu.core.obstacles import OBSTACLE_SHAPES, Obstacle
from tire_fmu.core.parameters import ParameterError


class RoadError(ValueError):
    """A road that cannot be made as asked (the message says how to fix it)."""


@dataclass(frozen=True, eq=False)
class RoadSignal:
    """Road height and velocity at the front of the tire's contact zone at t_k = k·step."""

    time_s: np.ndarray
    height_m: np.ndarray
    velocity_m_s: np.ndarray
    speed_m_s: float
    description: str

    @property
    def step_s(self) -> float:
        return float(self.time_s[1] - self.time_s[0])


def iso8608_road(road_class: str, speed_m_s: float, duration_s: float, step_s: float,
                 seed: int = 0, n_min_cycles_per_m: float = ISO_N_MIN_CYCLES_PER_M,
                 n_max_cycles_per_m: float = ISO_N_MAX_CYCLES_PER_M, fade_in_s: float = 0.0,
                 ) -> tuple[RoadSignal, Iso8608Spectrum]:
    """A random road of the class at speed V, sampled at step_s for duration_s.

    Without fade-in the signal is periodic with period duration_s (the FFT grid), so its
    spectrum is exact on the grid n_k = k/(V·duration_s); the first and last samples coincide.
    ``fade_in_s`` > 0 multiplies the first seconds by a half-cosine rising from 0 (velocity by
    the product rule), so a car that starts in equilibrium on a level road is not hit by a
    step of several millimetres at t = 0.
    """
    if not (speed_m_s > 0 and math.isfinite(speed_m_s)):
        raise RoadError(f"speed = {speed_m_s!r} m/s: a random road needs a speed > 0")
    if not (duration_s > 0 and step_s > 0 and duration_s >= 10 * step_s):
        raise RoadError(f"duration = {duration_s!r} s, step = {step_s!r} s: need "
                        "duration >= 10 steps > 0")
    if not 0 <= fade_in_s <= duration_s:
        raise RoadError(f"fade_in = {fade_in_s!r} s: must be in [0, duration]")
    samples = int(round(duration_s / step_s))
    try:
        profile = iso8608_profile(road_class, samples, speed_m_s * step_s, seed,
                                  n_min_cycles_per_m, n_max_cycles_per_m,
                                  fade_in_m=speed_m_s * fade_in_s)
    except ParameterError as error:
        raise RoadError(f"ISO 8608 road: {error}") from None
    time = step_s * np.arange(samples + 1)
    signal = RoadSignal(time, profile.heights_m, speed_m_s * profile.slopes, float(speed_m_s),
                        f"ISO 8608 class {road_class} at {speed_m_s:g} m/s (seed {seed})")
    return signal, profile.spectrum


CLEAT_SHAPES = OBSTACLE_SHAPES


def cleat(height_m: float, length_m: float, speed_m_s: float, duration_s: float,
          step_s: float, shape: str = "rounded", distance_m: float = 1.0) -> RoadSignal:
    """A cleat whose front reaches the front of the contact zone after ``distance_m``."""
    return _obstacle(height_m, length_m, speed_m_s, duration_s, step_s, shape, distance_m,
                     "cleat")


def pothole(depth_m: float, length_m: float, speed_m_s: float, duration_s: float,
            step_s: float, shape: str = "rectangular", distance_m: float = 1.0) -> RoadSignal:
    """A pothole ``depth_m`` deep whose front edge reaches the zone front after
    ``distance_m``."""
    return _obstacle(-depth_m, length_m, speed_m_s, duration_s, step_s, shape, distance_m,
                     "pothole")


def _obstacle(height_m, length_m, speed_m_s, duration_s, step_s, shape, distance_m, kind):
    if shape not in CLEAT_SHAPES:
        raise RoadError(f"{kind} shape {shape!r}: must be one of {CLEAT_SHAPES}")
    size = abs(height_m)
    if not (speed_m_s > 0 and length_m > 0 and size > 0 and distance_m >= 0):
        raise RoadError(f"a {kind} needs speed > 0, length > 0, "
                        f"{'height' if kind == 'cleat' else 'depth'} > 0 and distance >= 0")
    samples = int(round(duration_s / step_s))
    time = step_s * np.arange(samples + 1)
    x = speed_m_s * time - distance_m  # position of the zone front on the obstacle
    # the profile is the core's (tire_fmu.core.obstacles), the one the cleat study reads
    try:
        obstacle = Obstacle(float(height_m), float(length_m), shape)
    except ParameterError as error:
        raise RoadError(f"{kind}: {error}") from None
    height, slope = obstacle.profile(x)
    velocity = slope * speed_m_s
    return RoadSignal(time, height, velocity, float(speed_m_s),
                      f"{shape} {kind} {size * 1e3:g} mm x {length_m * 1e3:g} mm at "
                      f"{speed_m_s:g} m/s")


def road_at_rest(duration_s: float, step_s: float) -> RoadSignal:
    samples = int(round(duration_s / step_s))
    zeros = np.zeros(samples + 1)
    return RoadSignal(step_s * np.arange(samples + 1), zeros, zeros.copy(), 0.0, "road at rest")
