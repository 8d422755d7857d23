"""ISO 8608 random roads: a profile of heights over distance whose displacement PSD is a
class's.

One-sided displacement PSD over spatial frequency n (cycles/m),

    G_d(n) = G_d(n0) · (n / n0)^(-w),    n0 = 0.1 cycles/m, waviness w = 2,

with the geometric-mean G_d(n0) of each class A-H (each class is 4x the previous one). The
profile is a sum of cosines on the grid n_k = k / L (L the profile's length) with deterministic
amplitudes sqrt(2 G_d(n_k) Δn) and uniformly random phases (ISO 8608 annex, Cebon's method),
through one inverse FFT; the slope is the exact derivative of the same sum. Without a fade-in
the profile is periodic with period L, so its spectrum is exact on the grid. The default band
is ISO's, 0.011-2.83 cycles/m; a higher n_max extrapolates the slope of the spectrum.

One generator serves the vehicle demo's road signals (``vehicle_demo/road.py``: the profile
seen at a speed) and the road files ``tire-fmu road iso8608`` writes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .parameters import ParameterError, Problem

#: Geometric-mean G_d(n0) per ISO 8608 class, m³ (= m²/(cycles/m)).
ISO_8608_GD_N0_M3 = {c: 16e-6 * 4**i for i, c in enumerate("ABCDEFGH")}
N0_CYCLES_PER_M = 0.1
WAVINESS = 2.0
ISO_N_MIN_CYCLES_PER_M = 0.011
ISO_N_MAX_CYCLES_PER_M = 2.83


@dataclass(frozen=True)
class Iso8608Spectrum:
    """The target displacement PSD of an ISO 8608 class over a spatial band."""

    road_class: str = "C"
    waviness: float = WAVINESS
    n_min_cycles_per_m: float = ISO_N_MIN_CYCLES_PER_M
    n_max_cycles_per_m: float = ISO_N_MAX_CYCLES_PER_M

    def __post_init__(self) -> None:
        problems = []
        if self.road_class not in ISO_8608_GD_N0_M3:
            problems.append(Problem("road_class", self.road_class, "",
                                    f"one of {''.join(ISO_8608_GD_N0_M3)}"))
        low, high = self.n_min_cycles_per_m, self.n_max_cycles_per_m
        if not (math.isfinite(low) and math.isfinite(high) and 0 < low < high):
            problems.append(Problem("n_min_cycles_per_m", low, "cycles/m",
                                    f"in (0, n_max = {high:g} cycles/m)"))
        if problems:
            raise ParameterError(problems)

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


@dataclass(frozen=True, eq=False)
class Iso8608Profile:
    """Heights and slopes every ``spacing_m`` from distance 0 (``samples`` + 1 of them: without
    a fade-in the first and the last coincide, the profile's period)."""

    heights_m: np.ndarray
    slopes: np.ndarray
    spacing_m: float
    spectrum: Iso8608Spectrum
    seed: int

    @property
    def distances_m(self) -> np.ndarray:
        return self.spacing_m * np.arange(self.heights_m.size)


def iso8608_profile(road_class: str, samples: int, spacing_m: float, seed: int = 0,
                    n_min_cycles_per_m: float = ISO_N_MIN_CYCLES_PER_M,
                    n_max_cycles_per_m: float = ISO_N_MAX_CYCLES_PER_M,
                    fade_in_m: float = 0.0) -> Iso8608Profile:
    """A random profile of the class over ``samples`` spacings of ``spacing_m``.

    ``fade_in_m`` > 0 multiplies the first metres by a half-cosine rising from 0 (the slope by
    the product rule), so that the road starts level at height 0 (a vehicle starting there in
    equilibrium is not hit by a step)."""
    problems = []
    if not (isinstance(samples, int) and 10 <= samples):
        problems.append(Problem("samples", samples, "", "an integer >= 10"))
    if not (math.isfinite(spacing_m) and spacing_m > 0):
        problems.append(Problem("spacing_m", spacing_m, "m", "> 0"))
    elif not problems and not (math.isfinite(fade_in_m)
                               and 0 <= fade_in_m <= samples * spacing_m):
        problems.append(Problem("fade_in_m", fade_in_m, "m",
                                f"in [0, {samples * spacing_m:g}] m (the length)"))
    if problems:
        raise ParameterError(problems)
    spectrum = Iso8608Spectrum(road_class, WAVINESS, n_min_cycles_per_m, n_max_cycles_per_m)
    length = samples * spacing_m
    k = np.arange(samples // 2 + 1)
    n = k / length
    amplitude = np.sqrt(2.0 * spectrum.psd_m3(n) / length)
    amplitude[n >= 0.5 / spacing_m] = 0.0  # nothing at or above Nyquist
    phase = np.random.default_rng(seed).uniform(0.0, 2 * np.pi, k.size)
    coefficients = 0.5 * samples * amplitude * np.exp(1j * phase)
    height = np.fft.irfft(coefficients, samples)
    slope = np.fft.irfft(1j * 2 * np.pi * n * coefficients, samples)
    height, slope = np.r_[height, height[0]], np.r_[slope, slope[0]]
    if fade_in_m > 0:
        ramp = np.clip(spacing_m * np.arange(samples + 1) / fade_in_m, 0.0, 1.0)
        window = 0.5 * (1 - np.cos(np.pi * ramp))
        rise = np.where(ramp < 1, 0.5 * np.pi / fade_in_m * np.sin(np.pi * ramp), 0.0)
        height, slope = window * height, window * slope + rise * height
    return Iso8608Profile(height, slope, float(spacing_m), spectrum, seed)
