"""Road inputs for the tire FMU: height and velocity at the front of its contact zone (the
``road_z`` it takes), sampled at the communication points.

ISO 8608 random road: one-sided displacement PSD over spatial frequency n (cycles/m),

    G_d(n) = G_d(n0) · (n / n0)^(-w),    n0 = 0.1 cycles/m, waviness w = 2,

with the geometric-mean G_d(n0) of each class A-H (each class is 4x the previous one). It is
synthesised as a sum of cosines on the grid n_k = k / (V·T) with deterministic amplitudes
sqrt(2 G_d(n_k) Δn) and uniformly random phases (ISO 8608 annex, Cebon's method), through one
inverse FFT; the velocity is the exact derivative of the same sum. At speed V the time-
frequency PSD is G(f) = G_d(f/V)/V. The default band is ISO's, 0.011-2.83 cycles/m (up to
57 Hz at 20 m/s); a higher n_max extrapolates the slope. Each tread node of the tire sees the
road averaged over its own arc, so wavelengths shorter than a node's arc (4 cm at N = 100)
are averaged out node by node, and the unilateral footprint lets go of a dip it cannot
follow.

Cleat: a short obstacle of height H and length L across the road, rectangular (its edges are
steps of the road history; each tread node averages them over its arc) or rounded, a
(1 - cos) bump. Pothole: the same shapes downwards. Their profiles are
:class:`tire_fmu.core.obstacles.Obstacle`'s, the ones the cleat study reads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tire_fmu.core.obstacles import OBSTACLE_SHAPES, Obstacle
from tire_fmu.core.parameters import ParameterError

#: Geometric-mean G_d(n0) per ISO 8608 class, m³ (= m²/(cycles/m)).
ISO_8608_GD_N0_M3 = {c: 16e-6 * 4**i for i, c in enumerate("ABCDEFGH")}
N0_CYCLES_PER_M = 0.1
WAVINESS = 2.0
ISO_N_MIN_CYCLES_PER_M = 0.011
ISO_N_MAX_CYCLES_PER_M = 2.83


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


@dataclass(frozen=True)
class Iso8608Spectrum:
    """The target displacement PSD of an ISO 8608 class over a spatial band."""

    road_class: str = "C"
    waviness: float = WAVINESS
    n_min_cycles_per_m: float = ISO_N_MIN_CYCLES_PER_M
    n_max_cycles_per_m: float = ISO_N_MAX_CYCLES_PER_M

    def __post_init__(self) -> None:
        if self.road_class not in ISO_8608_GD_N0_M3:
            raise RoadError(f"road class {self.road_class!r}: must be one of "
                            f"{''.join(ISO_8608_GD_N0_M3)}")
        if not 0 < self.n_min_cycles_per_m < self.n_max_cycles_per_m:
            raise RoadError(f"spatial band ({self.n_min_cycles_per_m:g}, "
                            f"{self.n_max_cycles_per_m:g}) cycles/m: must have 0 < n_min < n_max")

    @property
    def gd_n0_m3(self) -> float:
        return ISO_8608_GD_N0_M3[self.road_class]

    def psd_m3(self, n_cycles_per_m) -> np.ndarray:
        """One-sided G_d(n), m³; zero outside the band."""
        n = np.asarray(n_cycles_per_m, dtype=float)
        inside = (n >= self.n_min_cycles_per_m) & (n <= self.n_max_cycles_per_m)
        safe = np.where(inside, n, N0_CYCLES_PER_M)
        return np.where(inside, self.gd_n0_m3 * (safe / N0_CYCLES_PER_M) ** -self.waviness, 0.0)

    def time_psd_m2_per_hz(self, f_hz, speed_m_s: float) -> np.ndarray:
        """One-sided PSD of the height seen at speed V over time frequency: G_d(f/V)/V."""
        return self.psd_m3(np.asarray(f_hz, dtype=float) / speed_m_s) / speed_m_s


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
    spectrum = Iso8608Spectrum(road_class, WAVINESS, n_min_cycles_per_m, n_max_cycles_per_m)
    samples = int(round(duration_s / step_s))
    period = samples * step_s
    k = np.arange(samples // 2 + 1)
    f = k / period
    n = f / speed_m_s
    dn = 1.0 / (speed_m_s * period)
    amplitude = np.sqrt(2.0 * spectrum.psd_m3(n) * dn)
    amplitude[f >= 0.5 / step_s] = 0.0  # nothing at or above Nyquist
    phase = np.random.default_rng(seed).uniform(0.0, 2 * np.pi, k.size)
    coefficients = 0.5 * samples * amplitude * np.exp(1j * phase)
    height = np.fft.irfft(coefficients, samples)
    velocity = np.fft.irfft(1j * 2 * np.pi * f * coefficients, samples)
    time = step_s * np.arange(samples + 1)
    height, velocity = np.r_[height, height[0]], np.r_[velocity, velocity[0]]
    if fade_in_s > 0:
        ramp = np.clip(time / fade_in_s, 0.0, 1.0)
        window = 0.5 * (1 - np.cos(np.pi * ramp))
        slope = np.where(ramp < 1, 0.5 * np.pi / fade_in_s * np.sin(np.pi * ramp), 0.0)
        height, velocity = window * height, window * velocity + slope * height
    signal = RoadSignal(time, height, velocity, float(speed_m_s),
                        f"ISO 8608 class {road_class} at {speed_m_s:g} m/s (seed {seed})")
    return signal, spectrum


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
