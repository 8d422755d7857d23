"""Ride transfer functions from a co-simulation: broadband road, H1 estimate, resonances.

Excitation: a periodic multisine road (:class:`Multisine`), every line k/T from f_min to f_max
(default 0.5-300 Hz every 0.25 Hz) excited with the same road *velocity* amplitude (the
height falls as 1/f, like a road's) and Schroeder phases for a low crest factor. The first
``settle_periods`` let the transient die out; Welch's averages then use one period per
segment with a rectangular window, so every excited line falls on an FFT bin without leakage.

Estimator: H1 = S_xy / S_xx with x the road height at the front of the tire's contact zone
and y each ride output, and the coherence |S_xy|² / (S_xx S_yy), from ``scipy.signal.csd``
and ``welch``.

Resonances: body bounce and wheel hop are heavily damped (docs/vehicle_demo.md gives ζ), so
their peaks sit away from the natural frequencies; they are identified as poles instead, by a
common-denominator rational fit (Sanathanan-Koerner iterations) of the body and wheel
displacement transmissibilities over IDENTIFICATION_BAND_HZ. Tire modes are light (ζ ~ 2 %)
and are read as peaks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

from .quarter_car import RIDE_OUTPUTS, QuarterCarModes, RideResponse

#: Where the acceptance compares co-simulation with the reference.
COHERENCE_MIN = 0.95
GAIN_FLOOR = 0.01  # of the reference's peak over the band
#: Where body bounce and wheel hop are looked for (identify_body_and_wheel): the band of the
#: fit, and the frequency and damping ranges of each mode's pole.
IDENTIFICATION_BAND_HZ = (0.5, 20.0)
BODY_BOUNCE_MAX_HZ = 3.0
BODY_BOUNCE_MAX_ZETA = 0.7
WHEEL_HOP_BAND_HZ = (3.0, 30.0)
WHEEL_HOP_MAX_ZETA = 0.5
#: Tire modes are the most prominent rim-load peaks above this (tire_mode_peaks).
TIRE_MODE_MIN_HZ = 25.0


@dataclass(frozen=True)
class Multisine:
    """A periodic broadband road: lines k/T for f_min <= k/T <= f_max (Hz)."""

    f_min_hz: float = 0.5
    f_max_hz: float = 300.0
    period_s: float = 4.0
    rms_velocity_m_s: float = 0.05
    settle_periods: int = 1
    average_periods: int = 3

    def __post_init__(self) -> None:
        if not 0 < self.f_min_hz < self.f_max_hz:
            raise ValueError(f"band ({self.f_min_hz}, {self.f_max_hz}) Hz: need 0 < min < max")
        if self.f_min_hz * self.period_s < 1 - 1e-9:
            raise ValueError(f"period {self.period_s} s: must be >= 1/f_min = "
                             f"{1 / self.f_min_hz:g} s to reach f_min")
        if self.average_periods < 2 or self.settle_periods < 0:
            raise ValueError("need average_periods >= 2 (coherence) and settle_periods >= 0")

    @property
    def line_indices(self) -> np.ndarray:
        first = math.ceil(self.f_min_hz * self.period_s - 1e-9)
        last = math.floor(self.f_max_hz * self.period_s + 1e-9)
        return np.arange(first, last + 1)

    @property
    def lines_hz(self) -> np.ndarray:
        return self.line_indices / self.period_s

    @property
    def duration_s(self) -> float:
        return self.period_s * (self.settle_periods + self.average_periods)

    def samples_per_period(self, step_s: float) -> int:
        samples = int(round(self.period_s / step_s))
        if abs(samples * step_s - self.period_s) > 1e-9 * self.period_s:
            raise ValueError(f"period {self.period_s} s is not a whole number of steps "
                             f"{step_s} s")
        if self.f_max_hz >= 0.5 / step_s:
            raise ValueError(f"f_max {self.f_max_hz} Hz: must be below Nyquist {0.5 / step_s} Hz")
        return samples

    def road(self, step_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(t, height, velocity) at t_k = k·step over the whole run (last sample included)."""
        m = self.samples_per_period(step_s)
        k = self.line_indices
        # Schroeder phases: low crest factor for a flat (velocity) spectrum
        phase = -np.pi * (k - k[0]) * (k - k[0] + 1) / k.size
        velocity_amplitude = self.rms_velocity_m_s * math.sqrt(2.0 / k.size)
        omega = 2 * np.pi * k / self.period_s
        spectrum = np.zeros(m // 2 + 1, dtype=complex)
        spectrum[k] = 0.5 * m * (velocity_amplitude / omega) * np.exp(1j * phase)
        one_height = np.fft.irfft(spectrum, m)
        spectrum[k] *= 1j * omega
        one_velocity = np.fft.irfft(spectrum, m)
        periods = self.settle_periods + self.average_periods
        n = m * periods + 1
        index = np.arange(n) % m
        return step_s * np.arange(n), one_height[index], one_velocity[index]


@dataclass(frozen=True, eq=False)
class FrfEstimate:
    """H1 estimates and coherences at the excited lines."""

    freqs_hz: np.ndarray
    h1: dict  # name -> complex
    coherence: dict  # name -> real
    n_averages: int


def estimate_frf(road_height_m: np.ndarray, outputs: dict, excitation: Multisine,
                 step_s: float) -> FrfEstimate:
    """H1 and coherence of each output against the road height, steady state only."""
    m = excitation.samples_per_period(step_s)
    start = m * excitation.settle_periods
    stop = start + m * excitation.average_periods
    x = np.asarray(road_height_m)[start:stop]
    fs = 1.0 / step_s
    settings = dict(fs=fs, window="boxcar", nperseg=m, noverlap=0, detrend=False)
    freqs, sxx = signal.welch(x, **settings)
    lines = excitation.line_indices  # only these bins carry excitation
    sxx = sxx[lines]
    h1, coherence = {}, {}
    for name, y in outputs.items():
        y = np.asarray(y)[start:stop]
        sxy = signal.csd(x, y, **settings)[1][lines]
        syy = signal.welch(y, **settings)[1][lines]
        h1[name] = sxy / sxx
        # an output that is exactly zero (a perfectly still body) has no coherence to show
        with np.errstate(invalid="ignore", divide="ignore"):
            coherence[name] = np.where(syy > 0, np.abs(sxy) ** 2 / (sxx * syy), 0.0)
    return FrfEstimate(freqs[lines], h1, coherence, excitation.average_periods)


def ride_outputs(result) -> dict:
    """The ride outputs of a :class:`~vehicle_demo.cosim.CoSimResult`, by RIDE_OUTPUTS name."""
    return {"body_acc": result.body_az_m_s2, "wheel_acc": result.wheel_az_m_s2,
            "rim_load": result.rim_load_n, "contact_force": result.contact_force_n}


# -- agreement with the reference ------------------------------------------------------------

@dataclass(frozen=True)
class Agreement:
    """|20 log10 |H1 / H_ref|| where coherence > 0.95 and |H_ref| > 1 % of its peak."""

    name: str
    max_deviation_db: float
    rms_deviation_db: float
    worst_frequency_hz: float
    points_compared: int
    points_total: int
    f_max_compared_hz: float


def agreement(estimate: FrfEstimate, reference: RideResponse, f_max_hz: float = 300.0,
              coherence_min: float = COHERENCE_MIN, gain_floor: float = GAIN_FLOOR
              ) -> dict[str, Agreement]:
    """Compare H1 with a reference evaluated at the same lines."""
    if not np.allclose(reference.freqs_hz, estimate.freqs_hz):
        raise ValueError("evaluate the reference at the estimate's lines")
    out = {}
    band = estimate.freqs_hz <= f_max_hz
    for name in RIDE_OUTPUTS:
        ref = reference[name]
        peak = np.abs(ref[band]).max()
        use = band & (estimate.coherence[name] > coherence_min) & (np.abs(ref) > gain_floor * peak)
        db = 20 * np.log10(np.abs(estimate.h1[name][use]) / np.abs(ref[use]))
        worst = int(np.argmax(np.abs(db))) if db.size else 0
        out[name] = Agreement(
            name, float(np.abs(db).max()) if db.size else math.nan,
            float(np.sqrt(np.mean(db**2))) if db.size else math.nan,
            float(estimate.freqs_hz[use][worst]) if db.size else math.nan,
            int(use.sum()), int(band.sum()),
            float(estimate.freqs_hz[use].max()) if db.size else math.nan)
    return out


# -- resonances ------------------------------------------------------------------------------

@dataclass(frozen=True)
class IdentifiedMode:
    frequency_hz: float  # |λ| / 2π
    damping_ratio: float


@dataclass(frozen=True, eq=False)
class RationalFit:
    """H_j(s) ≈ N_j(s)/D(s) over a band, s in rad/s."""

    poles: np.ndarray
    numerators: list  # per response, increasing powers of s/scale
    denominator: np.ndarray  # monic, increasing powers of s/scale
    scale: float

    def residue(self, j: int, pole: complex) -> complex:
        """Residue of response j at a simple pole."""
        x = pole / self.scale
        derivative = np.polynomial.polynomial.polyder(self.denominator)
        return complex(np.polynomial.polynomial.polyval(x, self.numerators[j])
                       / np.polynomial.polynomial.polyval(x, derivative) * self.scale)


def fit_rational(freqs_hz: np.ndarray, responses: list[np.ndarray], n_poles: int = 6,
                 numerator_degree: int = 8, iterations: int = 15) -> RationalFit:
    """Common-denominator rational fit H_j(s) = N_j(s)/D(s), D monic of degree ``n_poles``,
    by Sanathanan-Koerner iterations with each H_j weighted by 1/|H_j| (relative error, so
    every decade of gain counts alike). s is scaled by the band's geometric mean.

    Two poles more than the car has and a generous numerator absorb what is not a car mode:
    the tire's mass and, at speed, the contact patch's averaging of the road (the road
    reaches the patch nodes over L/V, a filter with its first null near V/L).
    """
    freqs_hz = np.asarray(freqs_hz, dtype=float)
    scale = 2 * np.pi * math.sqrt(freqs_hz.min() * freqs_hz.max())
    s = 1j * 2 * np.pi * freqs_hz / scale
    weight = np.ones_like(freqs_hz)
    n_num = numerator_degree + 1
    powers_d = np.vander(s, n_poles, increasing=True)  # s^0 .. s^(n-1)
    powers_n = np.vander(s, n_num, increasing=True)
    solution = None
    for _ in range(iterations):
        rows, rhs = [], []
        for j, h in enumerate(responses):
            w = (weight / np.abs(h))[:, None]
            block = np.zeros((s.size, n_poles + n_num * len(responses)), dtype=complex)
            block[:, :n_poles] = -h[:, None] * powers_d
            block[:, n_poles + j * n_num:n_poles + (j + 1) * n_num] = powers_n
            rows.append(w * block)
            rhs.append(w[:, 0] * h * s**n_poles)
        a = np.vstack(rows)
        b = np.concatenate(rhs)
        solution, *_ = np.linalg.lstsq(np.vstack([a.real, a.imag]),
                                       np.concatenate([b.real, b.imag]), rcond=None)
        denominator = np.r_[solution[:n_poles], 1.0]  # increasing powers
        weight = 1.0 / np.abs(np.polynomial.polynomial.polyval(s, denominator))
    numerators = [solution[n_poles + j * n_num:n_poles + (j + 1) * n_num]
                  for j in range(len(responses))]
    poles = np.polynomial.polynomial.polyroots(denominator) * scale
    return RationalFit(poles, numerators, denominator, scale)


def identify_body_and_wheel(freqs_hz, body_acc, wheel_acc, coherence=None,
                            band_hz=IDENTIFICATION_BAND_HZ
                            ) -> tuple[IdentifiedMode, IdentifiedMode]:
    """Body bounce and wheel hop as poles of the displacement transmissibilities Z_b/Z_r =
    A_b/(-ω²) and Z_w/Z_r over ``band_hz`` (points with coherence > 0.95 only).

    A road vehicle's modes sit in known ranges, and the fit's extra poles (which absorb the
    patch filter) are heavily damped, so: body bounce is the pole below BODY_BOUNCE_MAX_HZ
    with ζ < BODY_BOUNCE_MAX_ZETA, wheel hop the pole in WHEEL_HOP_BAND_HZ with ζ <
    WHEEL_HOP_MAX_ZETA; where several qualify, the one contributing most to the body's or the
    wheel's response (|residue| / decay rate, its peak height). Near and below V = L·f_hop
    (the patch's averaging then puts a null of the road input at wheel hop) the road does not
    excite the modes cleanly and this may find none: it then raises ValueError rather than
    return a wrong number.
    """
    freqs_hz = np.asarray(freqs_hz)
    use = (freqs_hz >= band_hz[0]) & (freqs_hz <= band_hz[1])
    if coherence is not None:
        use &= coherence > COHERENCE_MIN
    w2 = (2 * np.pi * freqs_hz[use]) ** 2
    fit = fit_rational(freqs_hz[use], [-np.asarray(body_acc)[use] / w2,
                                       -np.asarray(wheel_acc)[use] / w2])
    poles = fit.poles[(fit.poles.imag > 0) & (fit.poles.real < 0)]
    f_hz, zeta = np.abs(poles) / (2 * np.pi), -poles.real / np.abs(poles)
    found = []
    hop_low, hop_high = WHEEL_HOP_BAND_HZ
    for label, j, inside in (
            ("body bounce", 0, (f_hz < BODY_BOUNCE_MAX_HZ) & (zeta < BODY_BOUNCE_MAX_ZETA)),
            ("wheel hop", 1, (f_hz >= hop_low) & (f_hz < hop_high)
             & (zeta < WHEEL_HOP_MAX_ZETA))):
        if not inside.any():
            raise ValueError(
                f"no {label} pole in the fit (poles at {np.round(f_hz, 3)} Hz, ζ "
                f"{np.round(zeta, 3)}): at low speed the contact patch filters the road "
                "input near wheel hop")
        candidates = poles[inside]
        peak = [abs(fit.residue(j, p)) / -p.real for p in candidates]
        best = candidates[int(np.argmax(peak))]
        found.append(IdentifiedMode(float(abs(best) / (2 * np.pi)),
                                    float(-best.real / abs(best))))
    return found[0], found[1]


@dataclass(frozen=True)
class Resonance:
    """One row of the resonance table."""

    resonance: str
    response: str
    method: str  # how the frequencies were read
    f_analytic_massless_hz: float
    f_analytic_hz: float
    f_reference_hz: float
    f_cosim_hz: float
    zeta_reference: float
    zeta_cosim: float
    gain_reference: float
    gain_cosim: float
    gain_unit: str

    @property
    def cosim_vs_analytic_pct(self) -> float:
        return 100 * (self.f_cosim_hz / self.f_analytic_hz - 1)


def _peak_near(freqs, h, f_centre, rel=0.3) -> tuple[float, float]:
    window = (freqs >= f_centre * (1 - rel)) & (freqs <= f_centre * (1 + rel))
    if not window.any():
        return math.nan, math.nan
    i = np.flatnonzero(window)[np.argmax(np.abs(h[window]))]
    return float(freqs[i]), float(np.abs(h[i]))


def tire_mode_peaks(freqs_hz, h, f_min_hz=TIRE_MODE_MIN_HZ, min_prominence_db=1.0,
                    max_peaks=4) -> list[tuple[float, float]]:
    """(frequency, gain) of the most prominent local maxima of |h| above ``f_min_hz``."""
    freqs_hz = np.asarray(freqs_hz)
    above = freqs_hz >= f_min_hz
    db = 20 * np.log10(np.abs(h[above]))
    peaks, props = signal.find_peaks(db, prominence=min_prominence_db)
    order = np.argsort(props["prominences"])[::-1][:max_peaks]
    chosen = sorted(peaks[order])
    return [(float(freqs_hz[above][i]), float(np.abs(h[above][i]))) for i in chosen]


def resonance_table(modes: QuarterCarModes, reference: RideResponse,
                    estimate: FrfEstimate | None, identified=None,
                    tire_response: str = "rim_load") -> list[Resonance]:
    """Body bounce, wheel hop and the tire modes seen in ``tire_response``.

    ``reference`` is the quarter car on the full tire on a fine grid; ``identified`` the
    (body, wheel) modes fitted to ``estimate``.
    """
    from .quarter_car import RIDE_UNITS

    nan = math.nan
    rows = []
    f_ref = reference.freqs_hz
    for label, response, analytic_massless, analytic, pole, index in (
        ("body bounce", "body_acc", modes.massless.body_bounce_hz,
         modes.with_tire_mass.body_bounce_hz, modes.body_bounce, 0),
        ("wheel hop", "wheel_acc", modes.massless.wheel_hop_hz,
         modes.with_tire_mass.wheel_hop_hz, modes.wheel_hop, 1),
    ):
        _, gain_ref = _peak_near(f_ref, reference[response], pole.frequency_hz)
        fit = identified[index] if identified is not None else None
        gain_cosim = nan
        if estimate is not None:
            _, gain_cosim = _peak_near(estimate.freqs_hz, estimate.h1[response],
                                       pole.frequency_hz)
        rows.append(Resonance(label, response, "pole |λ|/2π", analytic_massless, analytic,
                              pole.frequency_hz, fit.frequency_hz if fit else nan,
                              pole.damping_ratio, fit.damping_ratio if fit else nan,
                              gain_ref, gain_cosim, RIDE_UNITS[response]))
    for i, (f_peak, gain) in enumerate(tire_mode_peaks(f_ref, reference[tire_response]), 1):
        f_cosim = gain_cosim = nan
        if estimate is not None:
            f_cosim, gain_cosim = _peak_near(estimate.freqs_hz, estimate.h1[tire_response],
                                             f_peak, rel=0.03)
        rows.append(Resonance(f"tire mode {i}", tire_response, "peak of |H|", nan, nan,
                              f_peak, f_cosim, nan, nan, gain, gain_cosim,
                              RIDE_UNITS[tire_response]))
    return rows
