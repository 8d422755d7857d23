"""Parameter studies behind the paper's figures: mesh convergence (Fig. 14), contact-patch length
(Fig. 17) and speed (Figs. 18-19).

Each study is a plain function over the assembled model that returns a frozen result object with
``to_dict()``; the CLI prints and the plots draw from these, nothing here reads files or plots.
Long loops take an optional ``progress(done, total)`` callback so a front end can show a bar.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace

import numpy as np

from .analytic import analytic_modes
from .complex_modal import complex_modes
from .contact import DEFAULT_CONTACT_POINT_SPACING_M
from .dispersion import Dispersion, body_frequencies, dispersion_relation
from .modal import ANTISYMMETRIC, SYMMETRIC, ModalResult, real_modes
from .model import SupercriticalSpeedWarning, build_model
from .parameters import OperatingPoint, ParameterError, Problem, TireParameters
from .standing_waves import critical_speed

Progress = Callable[[int, int], None]

#: The fit of the convergence order uses only meshes with at least this many nodes per
#: wavelength (N >= 8n): coarser meshes are outside the asymptotic δθ² regime for that order.
ASYMPTOTIC_NODES_PER_WAVELENGTH = 8

#: Relative errors below this are rounding, not discretisation (n = 0 is exact on any mesh).
ROUNDING_LEVEL = 1e-11

#: The paper's spin for Figs. 18-19.
PAPER_SPIN_RAD_S = 20.0 * np.pi

PHASES = ("in", "out")


def _rolling_setup(tire: TireParameters, damped: bool, nmax: int, problems: list[Problem]):
    """Check nmax, raise every problem found so far, and return the tire the rolling studies
    solve (undamped unless ``damped``) and the signed orders -nmax..nmax."""
    if nmax < 1:
        problems.append(Problem("nmax", nmax, "", "an integer >= 1"))
    if problems:
        raise ParameterError(problems)
    swept_tire = tire if damped else replace(tire, alpha=0.0, beta=0.0)
    return swept_tire, np.arange(-nmax, nmax + 1)


def _report(progress: Progress | None, done: int, total: int) -> None:
    if progress is not None:
        progress(done, total)


def _orders(values: Iterable[int], name: str, low: int) -> np.ndarray:
    orders = np.atleast_1d(np.asarray(list(values), dtype=int))
    if orders.size == 0 or orders.min() < low:
        raise ParameterError([Problem(name, orders.tolist(), "",
                                      f"a non-empty list of integers >= {low}")])
    return orders


# --------------------------------------------------------------------------------------------
# Mesh convergence (Fig. 14)


@dataclass(frozen=True, eq=False)
class ConvergenceStudy:
    """FDM frequencies of the undeformed tire at rest against the exact roots of eq. 12.

    Arrays indexed [mesh, order]; nan where the mesh does not resolve the order (n > N/2).
    """

    element_counts: np.ndarray
    orders: np.ndarray
    in_phase_hz: np.ndarray
    out_of_phase_hz: np.ndarray
    exact_in_phase_hz: np.ndarray
    exact_out_of_phase_hz: np.ndarray
    #: largest relative difference between the assembled model's modes and the per-order FDM
    #: symbols: the two must agree to rounding, or assembly and dispersion disagree
    model_symbol_difference: float

    @property
    def dtheta(self) -> np.ndarray:
        return 2.0 * np.pi / self.element_counts

    def frequencies_hz(self, phase: str) -> np.ndarray:
        return {"in": self.in_phase_hz, "out": self.out_of_phase_hz}[phase]

    def exact_hz(self, phase: str) -> np.ndarray:
        return {"in": self.exact_in_phase_hz, "out": self.exact_out_of_phase_hz}[phase]

    def relative_error(self, phase: str) -> np.ndarray:
        """(FDM - exact) / exact per [mesh, order]; the FDM frequencies lie below the exact."""
        return self.frequencies_hz(phase) / self.exact_hz(phase)[None, :] - 1.0

    def convergence_order(self, phase: str) -> np.ndarray:
        """Log-log slope of |error| against δθ per order, fitted over N >= 8n (nan if < 2 meshes
        qualify, or if the error is rounding only, as for n = 0)."""
        error = np.abs(self.relative_error(phase))
        slopes = np.full(self.orders.size, np.nan)
        for j, n in enumerate(self.orders):
            usable = (
                (self.element_counts >= ASYMPTOTIC_NODES_PER_WAVELENGTH * max(n, 1))
                & np.isfinite(error[:, j])
                & (error[:, j] > ROUNDING_LEVEL)
            )
            if np.count_nonzero(usable) >= 2:
                x = np.log(self.dtheta[usable])
                slopes[j] = np.polyfit(x, np.log(error[usable, j]), 1)[0]
        return slopes

    def to_dict(self) -> dict:
        branches = {}
        for phase in PHASES:
            branches[phase] = {
                "exact_hz": self.exact_hz(phase).tolist(),
                "fdm_hz": self.frequencies_hz(phase).tolist(),
                "relative_error": self.relative_error(phase).tolist(),
                "convergence_order": self.convergence_order(phase).tolist(),
            }
        return {
            "element_counts": self.element_counts.tolist(),
            "orders": self.orders.tolist(),
            "fit_nodes_per_wavelength": ASYMPTOTIC_NODES_PER_WAVELENGTH,
            "model_symbol_difference": self.model_symbol_difference,
            "in_phase": branches["in"],
            "out_of_phase": branches["out"],
        }


def _order_frequency(result: ModalResult, order: int, phase: str) -> float:
    # Undeformed: the cos and sin members are degenerate, either one will do.
    found = result.select(order=order, phase=phase)
    return result.modes[found[0]].frequency_hz if found else np.nan


def convergence_study(
    tire: TireParameters | None = None,
    element_counts: Iterable[int] = (20, 40, 60, 80, 100, 150, 200, 300, 400),
    orders: Iterable[int] = range(0, 11),
    progress: Progress | None = None,
) -> ConvergenceStudy:
    """Both branches of each order from the assembled FDM model on each mesh (paper's Fig. 14).

    Every mesh is solved in full with :func:`real_modes`, and its frequencies are checked
    against the discrete per-order symbols of :func:`body_frequencies`.
    """
    tire = tire or TireParameters()
    counts = _orders(element_counts, "element_counts", 8)
    n = _orders(orders, "orders", 0)
    exact = analytic_modes(tire, n)
    fdm = {phase: np.full((counts.size, n.size), np.nan) for phase in PHASES}
    mismatch = 0.0
    for i, count in enumerate(counts):
        op = OperatingPoint(n_elements=int(count), patch_length_m=0.0)
        result = real_modes(build_model(tire, op))
        resolved = n <= count // 2
        symbols = body_frequencies(tire, n[resolved], 0.0, n_elements=int(count))
        for phase, symbol_rad_s in zip(PHASES, symbols):
            values = np.array([_order_frequency(result, int(k), phase) for k in n[resolved]])
            fdm[phase][i, resolved] = values
            symbol_hz = symbol_rad_s / (2.0 * np.pi)
            mismatch = max(mismatch, float(np.max(np.abs(values / symbol_hz - 1.0))))
        _report(progress, i + 1, counts.size)
    return ConvergenceStudy(
        element_counts=counts,
        orders=n,
        in_phase_hz=fdm["in"],
        out_of_phase_hz=fdm["out"],
        exact_in_phase_hz=exact.in_phase_hz,
        exact_out_of_phase_hz=exact.out_of_phase_hz,
        model_symbol_difference=mismatch,
    )


# --------------------------------------------------------------------------------------------
# Contact-patch length (Fig. 17)


@dataclass(frozen=True, eq=False)
class PatchSweep:
    """Both members of each split pair against patch length, at rest.

    ``symmetric_hz[phase]`` and ``antisymmetric_hz[phase]`` are indexed [length, order]. The
    symmetric member has an antinode at the patch centre (Kindt's *extr*) and is the one the
    patch stiffens; the antisymmetric one has a node there (*0*) and barely moves.
    """

    n_elements: int
    lengths_m: np.ndarray
    loads_n: np.ndarray  # the model's secant load that makes each patch
    orders: np.ndarray
    phases: tuple[str, ...]
    undeformed_hz: dict[str, np.ndarray]  # [order], same mesh, no contact
    symmetric_hz: dict[str, np.ndarray]
    antisymmetric_hz: dict[str, np.ndarray]

    def shift_percent(self, symmetry: str, phase: str = "in") -> np.ndarray:
        """Rise over the undeformed tire of the same mesh in %, per [length, order]."""
        member = {SYMMETRIC: self.symmetric_hz, ANTISYMMETRIC: self.antisymmetric_hz}[symmetry]
        return 100.0 * (member[phase] / self.undeformed_hz[phase][None, :] - 1.0)

    def at_length(self, length_m: float) -> int:
        """Index of the swept length closest to ``length_m``."""
        return int(np.argmin(np.abs(self.lengths_m - length_m)))

    def to_dict(self) -> dict:
        branches = {
            phase: {
                "undeformed_hz": self.undeformed_hz[phase].tolist(),
                "symmetric_hz": self.symmetric_hz[phase].tolist(),
                "antisymmetric_hz": self.antisymmetric_hz[phase].tolist(),
                "symmetric_shift_percent": self.shift_percent(SYMMETRIC, phase).tolist(),
                "antisymmetric_shift_percent": self.shift_percent(ANTISYMMETRIC, phase).tolist(),
            }
            for phase in self.phases
        }
        return {
            "n_elements": self.n_elements,
            "lengths_m": self.lengths_m.tolist(),
            "loads_n": self.loads_n.tolist(),
            "orders": self.orders.tolist(),
            "branches": branches,
        }


def patch_sweep(
    tire: TireParameters | None = None,
    n_elements: int = 100,
    lengths_m: Iterable[float] = np.linspace(0.0, 0.40, 41),
    orders: Iterable[int] = (1, 2, 3, 4, 5, 6),
    phases: tuple[str, ...] = ("in",),
    progress: Progress | None = None,
) -> PatchSweep:
    """Frequencies of the symmetric and antisymmetric member of each order vs patch length.

    Labels come from :func:`real_modes`, which follows each mode continuously from the
    undeformed tire, so a member keeps its order and branch as the patch grows.
    """
    tire = tire or TireParameters()
    lengths = np.atleast_1d(np.asarray(list(lengths_m), dtype=float))
    n = _orders(orders, "orders", 0)
    bad_phases = [p for p in phases if p not in PHASES]
    problems = []
    if lengths.size == 0 or not np.all(np.isfinite(lengths)):
        problems.append(Problem("lengths_m", lengths.tolist(), "m", "finite numbers"))
    elif lengths.min() < 0.0 or lengths.max() > tire.max_patch_length_m:
        problems.append(Problem("lengths_m", lengths.tolist(), "m",
                                f"in [0, {tire.max_patch_length_m:.4g}] m", "for this tire"))
    if bad_phases or not phases:
        problems.append(Problem("phases", phases, "", f"a non-empty subset of {PHASES}"))
    if problems:
        raise ParameterError(problems)

    reference = real_modes(build_model(tire, OperatingPoint(n_elements, patch_length_m=0.0)))
    undeformed_hz = {
        phase: np.array([_order_frequency(reference, int(k), phase) for k in n]) for phase in phases
    }
    # Contact only raises frequencies, and by far less than this for credible patches; the
    # bound keeps large meshes on the cheap partial solve.
    f_max_hz = 2.0 * max(float(np.nanmax(f)) for f in undeformed_hz.values())
    members = {name: {p: np.full((lengths.size, n.size), np.nan) for p in phases}
               for name in (SYMMETRIC, ANTISYMMETRIC)}
    loads = np.zeros(lengths.size)
    for i, length in enumerate(lengths):
        model = build_model(tire, OperatingPoint(n_elements, patch_length_m=float(length)))
        loads[i] = model.patch.load_n
        if length == 0.0:
            for name in members:
                for phase in phases:
                    members[name][phase][i] = undeformed_hz[phase]
        else:
            result = real_modes(model, f_max_hz=f_max_hz)
            for name in members:
                for phase in phases:
                    for j, k in enumerate(n):
                        found = result.select(order=int(k), phase=phase, symmetry=name)
                        if found:
                            members[name][phase][i, j] = result.modes[found[0]].frequency_hz
        _report(progress, i + 1, lengths.size)
    return PatchSweep(
        n_elements=int(n_elements),
        lengths_m=lengths,
        loads_n=loads,
        orders=n,
        phases=tuple(phases),
        undeformed_hz=undeformed_hz,
        symmetric_hz=members[SYMMETRIC],
        antisymmetric_hz=members[ANTISYMMETRIC],
    )


# --------------------------------------------------------------------------------------------
# Speed (Figs. 18-19)


def paper_speed_m_s(tire: TireParameters) -> float:
    """The speed of the paper's rolling results, Ω = 20π rad/s, for this tire's radius."""
    return PAPER_SPIN_RAD_S * tire.R


@dataclass(frozen=True, eq=False)
class SpeedSweep:
    """Ground-frame frequencies of the rolling tire against speed.

    The undeformed curves come per signed order from the dispersion relation of the same mesh
    (indexed [speed, order]; n > 0 travels backward, its frequency falls with speed). With a
    patch, ``loaded`` holds the complex modes of the loaded model at each speed, labelled by
    their dominant signed harmonic.
    """

    n_elements: int
    radius_m: float
    patch_length_m: float
    speeds_m_s: np.ndarray
    orders: np.ndarray  # signed
    undeformed_in_phase_hz: np.ndarray
    undeformed_out_of_phase_hz: np.ndarray
    critical_speed_m_s: float
    damped: bool
    f_max_hz: float
    loaded: tuple[ModalResult, ...] | None

    @property
    def spins_rad_s(self) -> np.ndarray:
        return self.speeds_m_s / self.radius_m

    def to_dict(self) -> dict:
        data = {
            "n_elements": self.n_elements,
            "patch_length_m": self.patch_length_m,
            "radius_m": self.radius_m,
            "speeds_m_s": self.speeds_m_s.tolist(),
            "critical_speed_m_s": self.critical_speed_m_s,
            "damped": self.damped,
            "f_max_hz": self.f_max_hz,
            "orders": self.orders.tolist(),
            "undeformed_in_phase_hz": self.undeformed_in_phase_hz.tolist(),
            "undeformed_out_of_phase_hz": self.undeformed_out_of_phase_hz.tolist(),
            "loaded": None,
        }
        if self.loaded is not None:
            data["loaded"] = [
                {"speed_m_s": float(v), "modes": [m.to_dict() for m in result.modes]}
                for v, result in zip(self.speeds_m_s, self.loaded)
            ]
        return data


def speed_sweep(
    tire: TireParameters | None = None,
    n_elements: int = 100,
    speeds_m_s: Iterable[float] | None = None,
    patch_length_m: float = 0.0,
    f_max_hz: float = 250.0,
    nmax: int = 10,
    damped: bool = False,
    allow_supercritical: bool = False,
    progress: Progress | None = None,
) -> SpeedSweep:
    """Ground-frame frequencies vs speed, undeformed and (``patch_length_m > 0``) loaded.

    Default speeds: 0 to the paper's Ω = 20π rad/s in 21 steps. By default the tire is swept
    undamped (α = β = 0) so that the loaded modes, the undamped dispersion curves and the rest
    analysis compare exactly; damping moves the frequencies by O(ζ²), under 0.1 %.
    """
    tire = tire or TireParameters()
    if speeds_m_s is None:
        speeds_m_s = np.linspace(0.0, paper_speed_m_s(tire), 21)
    speeds = np.atleast_1d(np.asarray(list(speeds_m_s), dtype=float))
    critical = critical_speed(tire, n_elements).speed_m_s
    problems = []
    if speeds.size == 0 or not np.all(np.isfinite(speeds)) or speeds.min() < 0.0:
        problems.append(Problem("speeds_m_s", speeds.tolist(), "m/s",
                                "finite numbers >= 0 m/s"))
    elif patch_length_m > 0.0 and speeds.max() >= critical and not allow_supercritical:
        problems.append(Problem(
            "speeds_m_s", speeds.max(), "m/s", f"below the critical speed {critical:.4g} m/s "
            "of this mesh", f"n_elements = {n_elements}; allow_supercritical runs anyway"))
    if not 0.0 <= patch_length_m <= tire.max_patch_length_m:
        problems.append(Problem("patch_length_m", patch_length_m, "m",
                                f"in [0, {tire.max_patch_length_m:.4g}] m"))
    if not f_max_hz > 0.0:
        problems.append(Problem("f_max_hz", f_max_hz, "Hz", "> 0 Hz"))
    swept_tire, orders = _rolling_setup(tire, damped, nmax, problems)
    curves = [dispersion_relation(swept_tire, orders, v / tire.R, n_elements) for v in speeds]
    loaded = None
    if patch_length_m > 0.0:
        results = []
        with warnings.catch_warnings():
            # The sweep reports the critical speed itself; one warning per speed is noise.
            warnings.simplefilter("ignore", SupercriticalSpeedWarning)
            for i, v in enumerate(speeds):
                op = OperatingPoint(n_elements, patch_length_m=patch_length_m, speed_m_s=float(v),
                                    allow_supercritical=allow_supercritical)
                results.append(complex_modes(build_model(swept_tire, op), f_max_hz=f_max_hz))
                _report(progress, i + 1, speeds.size)
        loaded = tuple(results)
    return SpeedSweep(
        n_elements=int(n_elements),
        radius_m=tire.R,
        patch_length_m=float(patch_length_m),
        speeds_m_s=speeds,
        orders=orders,
        undeformed_in_phase_hz=np.array([c.in_phase_hz for c in curves]),
        undeformed_out_of_phase_hz=np.array([c.out_of_phase_hz for c in curves]),
        critical_speed_m_s=critical,
        damped=damped,
        f_max_hz=float(f_max_hz),
        loaded=loaded,
    )


@dataclass(frozen=True, eq=False)
class DispersionAtSpeed:
    """The paper's Fig. 18: ground-frame dispersion of the undeformed tire at one speed (and at
    rest, for the asymmetry), with the loaded tire's complex modes when there is a patch."""

    speed_m_s: float
    patch_length_m: float
    damped: bool
    undeformed: Dispersion
    at_rest: Dispersion
    loaded: ModalResult | None

    def to_dict(self) -> dict:
        return {
            "speed_m_s": self.speed_m_s,
            "spin_rad_s": self.undeformed.spin_rad_s,
            "patch_length_m": self.patch_length_m,
            "damped": self.damped,
            "undeformed": self.undeformed.to_dict(),
            "at_rest": self.at_rest.to_dict(),
            "loaded": None if self.loaded is None else self.loaded.to_dict(),
        }


def dispersion_at_speed(
    tire: TireParameters | None = None,
    n_elements: int = 100,
    speed_m_s: float | None = None,
    patch_length_m: float = 0.0,
    nmax: int = 12,
    f_max_hz: float = 300.0,
    damped: bool = False,
    allow_supercritical: bool = False,
) -> DispersionAtSpeed:
    """Undeformed dispersion for |n| <= nmax at ``speed_m_s`` (default: the paper's
    Ω = 20π rad/s) and, with a patch, the loaded model's complex modes up to ``f_max_hz``.

    Undamped by default for the same reason as :func:`speed_sweep`.
    """
    tire = tire or TireParameters()
    speed = paper_speed_m_s(tire) if speed_m_s is None else float(speed_m_s)
    problems = []
    if not np.isfinite(speed) or speed < 0.0:
        problems.append(Problem("speed_m_s", speed, "m/s", "a finite number >= 0 m/s"))
    swept_tire, orders = _rolling_setup(tire, damped, nmax, problems)
    loaded = None
    if patch_length_m > 0.0:
        op = OperatingPoint(n_elements, patch_length_m=patch_length_m, speed_m_s=speed,
                            allow_supercritical=allow_supercritical)
        loaded = complex_modes(build_model(swept_tire, op), f_max_hz=f_max_hz)
    return DispersionAtSpeed(
        speed_m_s=speed,
        patch_length_m=float(patch_length_m),
        damped=damped,
        undeformed=dispersion_relation(swept_tire, orders, speed / tire.R, n_elements),
        at_rest=dispersion_relation(swept_tire, orders, 0.0, n_elements),
        loaded=loaded,
    )


# --------------------------------------------------------------------------------------------
# Mesh convergence over a cleat (issue 21): the rim held at its static height


#: The default point spacing of the study (m): the contact points' default, which resolves a
#: 10 mm feature with four points.
CLEAT_POINT_SPACING_M = DEFAULT_CONTACT_POINT_SPACING_M
#: Meshes of the study: doubling, so the Richardson ratio is 2.
CLEAT_ELEMENT_COUNTS = (100, 200, 400, 800)
#: Default communication step (s). The rim load's peak over a 20 mm cleat at 10 m/s moves by
#: under 0.2 % when it is halved (tests/test_cleat_convergence.py halves it once); at the
#: FMU's 1e-4 s it is up to 1 % low, and the contact force sampled at the step ends is biased
#: high by O(h) (docs/theory.md, "Contact points: convergence over cleats").
CLEAT_STEP_S = 2.5e-5
#: Time the run goes on after the obstacle has left the contact zone (s): the rim load rings
#: down at the tire's low modes.
CLEAT_SETTLE_S = 0.02
#: The observed order of the Richardson extrapolation is searched in (0, this].
MAX_OBSERVED_ORDER = 10.0


#: A line is looked for within this fraction of its frequency either side: the rays of the
#: nodes (points) meet the road (R - δ)·δθ·sec²θ apart, closest at the contact centre.
LINE_BAND = 0.05


def line_amplitude(time_s: np.ndarray, values: np.ndarray, frequency_hz: float,
                   band: float = LINE_BAND) -> float:
    """Amplitude of the line near ``frequency_hz`` in a record: the largest Hann-windowed
    discrete Fourier sum 2|Σ w x e^{-2πift}| / Σ w of the record less its mean (a sine of
    amplitude A reads A) for f within ``band`` of it (on a grid of an eighth of the window's
    resolution); nan if that reaches the record's Nyquist frequency."""
    t = np.asarray(time_s, dtype=float)
    x = np.asarray(values, dtype=float)
    if t.size < 4 or not frequency_hz * (1 + band) < 0.5 / float(np.mean(np.diff(t))):
        return math.nan
    window = np.hanning(t.size)
    x = x - np.sum(window * x) / np.sum(window)
    resolution = 1.0 / (t[-1] - t[0])
    count = max(int(math.ceil(16 * band * frequency_hz / resolution)), 1) + 1
    f = np.linspace(frequency_hz * (1 - band), frequency_hz * (1 + band), count)
    sums = np.exp(-2j * np.pi * f[:, None] * (t - t[0])[None, :]) @ (window * x)
    return float(2 * np.max(np.abs(sums)) / np.sum(window))


def richardson(sizes, values) -> tuple[float, float]:
    """(extrapolated value, observed order) from the three finest of ``values`` on meshes of
    spacing ``sizes`` (any ratios): the order p solves (f1 - f2)/(f2 - f3) =
    (h1^p - h2^p)/(h2^p - h3^p), and f = f3 - (f2 - f3) h3^p/(h2^p - h3^p). When the three do
    not converge monotonically (the differences change sign or grow) there is no order to
    observe: (the finest value, nan)."""
    h = np.asarray(sizes, dtype=float)[-3:]
    f = np.asarray(values, dtype=float)[-3:]
    if h.size < 3 or not np.all(np.isfinite(f)):
        return (float(f[-1]) if f.size else math.nan), math.nan
    e1, e2 = f[1] - f[0], f[2] - f[1]
    if e2 == 0.0:
        return float(f[2]), math.nan
    target = e1 / e2

    def ratio(p: float) -> float:
        return (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p)

    low, high = 1e-6, MAX_OBSERVED_ORDER
    if not ratio(low) < target <= ratio(high):
        return float(f[2]), math.nan
    for _ in range(200):
        middle = 0.5 * (low + high)
        if ratio(middle) < target:
            low = middle
        else:
            high = middle
    p = 0.5 * (low + high)
    return float(f[2] + e2 * h[2] ** p / (h[1] ** p - h[2] ** p)), p


@dataclass(frozen=True, eq=False)
class CleatConvergence:
    """The rim load over an obstacle against the mesh, the rim held at its static height.

    Arrays are indexed [mesh] or [mesh, time]; ``time_s`` is common to every mesh and counts
    from the moment the obstacle's first edge passes the contact centre. The obstacle is
    "under the tire" (``under_tire_s``, per mesh) while it overlaps the stretch of road
    |x| <= ``reach_m`` where the undeformed tread, the rim at its static height, would reach
    down to the obstacle's top (to the road, for a pothole): from the first touch to the last.
    The minimum of contact_Fz and the spectrum lines (of contact_Fz, sampled at ``step_s``)
    are read over that time.
    """

    obstacle: object  # obstacles.Obstacle
    speed_m_s: float
    load_n: float
    step_s: float
    point_spacing_m: float  # asked for
    element_counts: np.ndarray
    points_per_node: np.ndarray
    n_points: np.ndarray
    time_s: np.ndarray
    rim_fz_n: np.ndarray  # [mesh, time]
    contact_fz_n: np.ndarray  # [mesh, time]
    static_rim_fz_n: np.ndarray
    under_tire_s: np.ndarray  # [mesh, (start, end)]
    reach_m: np.ndarray  # [mesh]
    contact_zone_length_m: np.ndarray  # [mesh]
    node_line_n: np.ndarray  # contact_Fz line at the node-passing frequency
    point_line_n: np.ndarray  # and at the point-passing frequency
    run_s: np.ndarray  # wall time of each mesh's run (s)
    deflection_m: np.ndarray  # the rim's static lowering on each mesh
    radius_m: float

    @property
    def node_arc_m(self) -> np.ndarray:
        return 2 * np.pi * self.radius_m / self.element_counts

    @property
    def point_arc_m(self) -> np.ndarray:
        """Spacing of the contact points on the tread (m)."""
        return self.node_arc_m / self.points_per_node

    @property
    def node_passing_hz(self) -> np.ndarray:
        """V/((R - δ)·2π/N): the rate at which the nodes' rays pass over a point of the road
        at the contact centre (on the tread they are R·2π/N apart, on the road (R - δ)/R of
        that)."""
        return self.speed_m_s / ((self.radius_m - self.deflection_m) * 2 * np.pi
                                 / self.element_counts)

    @property
    def point_passing_hz(self) -> np.ndarray:
        return self.node_passing_hz * self.points_per_node

    @property
    def peak_rise_n(self) -> np.ndarray:
        """Largest rim_Fz over the run less the static rim load."""
        return self.rim_fz_n.max(axis=1) - self.static_rim_fz_n

    @property
    def peak_dip_n(self) -> np.ndarray:
        """Smallest rim_Fz over the run less the static rim load (negative: the load falls;
        what a pothole shows first)."""
        return self.rim_fz_n.min(axis=1) - self.static_rim_fz_n

    @property
    def min_contact_fz_n(self) -> np.ndarray:
        """Smallest contact_Fz while the obstacle is under the tire."""
        out = np.empty(self.element_counts.size)
        for i, (start, end) in enumerate(self.under_tire_s):
            inside = (self.time_s >= start) & (self.time_s <= end)
            out[i] = self.contact_fz_n[i, inside].min() if inside.any() else math.nan
        return out

    def extrapolated_rise(self) -> tuple[float, float]:
        """(mesh-converged peak rise, observed order): :func:`richardson` over the meshes."""
        return richardson(1.0 / self.element_counts, self.peak_rise_n)

    def rise_error(self) -> np.ndarray:
        """Peak rise of each mesh over the extrapolated one, less 1."""
        return self.peak_rise_n / self.extrapolated_rise()[0] - 1.0

    def history_difference(self) -> np.ndarray:
        """rms of each rim_Fz history less the finest mesh's, over the rms of the finest's
        deviation from its static value (0 for the finest)."""
        finest = self.rim_fz_n[-1]
        scale = np.sqrt(np.mean((finest - self.static_rim_fz_n[-1]) ** 2))
        return np.sqrt(np.mean((self.rim_fz_n - finest[None, :]) ** 2, axis=1)) / scale

    def table_rows(self) -> list[dict]:
        """One row per mesh: what the convergence table shows."""
        error, difference = self.rise_error(), self.history_difference()
        return [{"n_elements": int(n), "points_per_node": int(m), "point_arc_mm": 1e3 * s,
                 "peak_rise_kn": rise / 1e3, "peak_dip_kn": dip / 1e3,
                 "rise_error": float(e),
                 "history_rms_difference": float(d), "min_contact_fz_kn": fmin / 1e3,
                 "node_passing_hz": float(fn), "node_line_kn": ln / 1e3,
                 "point_passing_hz": float(fp), "point_line_kn": lp / 1e3}
                for n, m, s, rise, dip, e, d, fmin, fn, ln, fp, lp in zip(
                    self.element_counts, self.points_per_node, self.point_arc_m,
                    self.peak_rise_n, self.peak_dip_n, error, difference, self.min_contact_fz_n,
                    self.node_passing_hz, self.node_line_n, self.point_passing_hz,
                    self.point_line_n)]

    def to_dict(self, histories: bool = True) -> dict:
        rise, order = self.extrapolated_rise()
        data = {
            "obstacle": self.obstacle.to_dict(),
            "speed_m_s": self.speed_m_s,
            "load_n": self.load_n,
            "step_s": self.step_s,
            "point_spacing_m": self.point_spacing_m,
            "element_counts": self.element_counts.tolist(),
            "static_rim_fz_n": self.static_rim_fz_n.tolist(),
            "deflection_m": self.deflection_m.tolist(),
            "extrapolated_rise_kn": rise / 1e3,
            "observed_order": order,
            "meshes": self.table_rows(),
            "under_tire_s": self.under_tire_s.tolist(),
            "reach_m": self.reach_m.tolist(),
            "contact_zone_length_m": self.contact_zone_length_m.tolist(),
            "run_s": self.run_s.tolist(),
        }
        if histories:
            data["time_s"] = self.time_s.tolist()
            data["rim_fz_n"] = self.rim_fz_n.tolist()
            data["contact_fz_n"] = self.contact_fz_n.tolist()
        return data


def obstacle_reach_m(radius_m: float, deflection_m: float, obstacle) -> float:
    """Half-length of the road |x| <= reach over which the undeformed tread, its rim lowered
    by ``deflection_m``, is below the obstacle's top (for a pothole: below the road)."""
    top = max(obstacle.height_m, 0.0)
    return math.sqrt(max(radius_m**2 - (radius_m - deflection_m - top) ** 2, 0.0))


def zone_length_for_reach(radius_m: float, reach_m: float) -> float:
    """The contact zone whose rays reach the road beyond the undeformed tread's first touch
    at ``reach_m``, with :data:`CLEAT_ZONE_MARGIN_M` to spare."""
    return 2 * radius_m * math.tan(math.asin(min(reach_m / radius_m, 1.0))) \
        + CLEAT_ZONE_MARGIN_M


#: Road the contact zone reaches beyond the obstacle's first touch of the undeformed tread.
CLEAT_ZONE_MARGIN_M = 0.05


def cleat_convergence(
    tire: TireParameters | None = None,
    obstacle=None,
    speed_m_s: float = 10.0,
    n_elements: Iterable[int] = CLEAT_ELEMENT_COUNTS,
    point_spacing_m: float = CLEAT_POINT_SPACING_M,
    load_n: float | None = None,
    step_s: float = CLEAT_STEP_S,
    settle_s: float = CLEAT_SETTLE_S,
    contact_zone_length_m: float | None = None,
    backend: str = "auto",
    progress: Progress | None = None,
) -> CleatConvergence:
    """The rim held at the static height for ``load_n`` (default the FMU's 27.7 kN) while the
    tire rolls over ``obstacle`` (default a 20 mm x 20 mm cleat) at ``speed_m_s``, on each
    mesh, with :class:`~.simulator.ContactSimulator`.

    The road input is the obstacle's profile at the front of each mesh's contact zone
    (road_z, and road_vz = V dz/ds), sampled at ``step_s`` as
    :meth:`~.obstacles.Obstacle.road_samples` says; the obstacle lies on the ground,
    so every mesh meets it at the same time. ``point_spacing_m`` sets the contact points
    (above the node arc, every node is its own point). The contact zone is by default the
    FMU's, widened where the obstacle would meet the tread before the zone
    (:func:`zone_length_for_reach`); a zone given that is too short is refused.
    """
    import time

    from .contact import DEFAULT_ZONE_LENGTH_M
    from .contact_dynamics import build_contact_model
    from .obstacles import Obstacle
    from .parameters import DEFAULT_LOAD_N
    from .simulator import ContactSimulator

    tire = tire or TireParameters()
    obstacle = obstacle if obstacle is not None else Obstacle(0.02, 0.02)
    load = DEFAULT_LOAD_N if load_n is None else load_n
    counts = _orders(n_elements, "n_elements", 8)
    problems = []
    if not isinstance(obstacle, Obstacle):
        problems.append(Problem("obstacle", obstacle, "", "an Obstacle (core.obstacles)"))
    if not (math.isfinite(speed_m_s) and speed_m_s > 0):
        problems.append(Problem("speed_m_s", speed_m_s, "m/s", "> 0 m/s",
                                "the tire must roll over the obstacle"))
    if not (math.isfinite(load) and load >= 0):
        problems.append(Problem("load_n", load, "N", ">= 0 N"))
    if not (math.isfinite(step_s) and 0 < step_s <= 1e-3):
        problems.append(Problem("step_s", step_s, "s", "in (0, 1e-3] s"))
    if not (math.isfinite(settle_s) and 0 <= settle_s <= 1.0):
        problems.append(Problem("settle_s", settle_s, "s", "in [0, 1] s"))
    if np.any(np.diff(counts) <= 0):
        problems.append(Problem("n_elements", counts.tolist(), "", "ascending and distinct"))
    if problems:
        raise ParameterError(problems)

    def build(n: int, zone_length: float):
        op = OperatingPoint(n_elements=int(n), load_n=float(load), speed_m_s=float(speed_m_s),
                            contact_zone_length_m=float(zone_length),
                            contact_point_spacing_m=float(point_spacing_m))
        return build_contact_model(tire, op)

    contacts, found = [], []
    for n in counts:  # every mesh's problems at once
        try:
            zone = DEFAULT_ZONE_LENGTH_M if contact_zone_length_m is None \
                else contact_zone_length_m
            contact = build(n, zone)
            reach = obstacle_reach_m(tire.R, contact.patch.deflection_m, obstacle)
            needed = zone_length_for_reach(tire.R, reach)
            if zone < needed:
                if contact_zone_length_m is not None:
                    raise ParameterError([Problem(
                        "contact_zone_length_m", zone, "m", f"at least {needed:.4g} m",
                        f"the {obstacle.label} meets the undeformed tread {reach:.4g} m ahead "
                        "of the contact centre")])
                contact = build(n, needed)
            contacts.append(contact)
        except ParameterError as error:
            found += error.details
    if found:
        raise ParameterError(found)
    # the obstacle's first edge starts just ahead of the farthest zone front, and the run
    # ends once its last edge has left the farthest zone rear, then settles
    fronts = np.array([c.windows.front_m for c in contacts])
    rears = np.array([c.windows.front_m - speed_m_s * c.windows.horizon_s for c in contacts])
    # ... a whole number of steps ahead, so the samples fall on t = k·h from its passing the
    # contact centre, whatever the meshes
    lead = (math.ceil(float(fronts.max()) / (speed_m_s * step_s)) + 2) * speed_m_s * step_s
    steps = int(math.ceil(((lead + obstacle.length_m - rears.min()) / speed_m_s + settle_s)
                          / step_s))
    absolute = step_s * np.arange(steps + 1)
    time_s = step_s * (np.arange(steps + 1) - round(lead / (speed_m_s * step_s)))

    size = counts.size
    rim, contact_fz = np.empty((size, steps + 1)), np.empty((size, steps + 1))
    statics, per_node, n_points = np.empty(size), np.empty(size, int), np.empty(size, int)
    under, reaches, zones = np.empty((size, 2)), np.empty(size), np.empty(size)
    node_line, point_line, run_s = np.empty(size), np.empty(size), np.empty(size)
    deflections = np.empty(size)
    for i, contact in enumerate(contacts):
        started = time.perf_counter()
        simulator = ContactSimulator(contact, backend=backend)
        front = contact.windows.front_m
        height, slope = obstacle.road_samples(front - lead + speed_m_s * absolute,
                                              speed_m_s * step_s)
        road_v = slope * speed_m_s
        out = np.empty((steps + 1, 2))
        first = simulator.outputs
        out[0] = first[0], first[2]
        step = simulator.step_values
        for k in range(steps):
            values = step(step_s, 0.0, 0.0, float(height[k]), float(road_v[k]))
            out[k + 1] = values[0], values[2]
        run_s[i] = time.perf_counter() - started
        rim[i], contact_fz[i] = out[:, 0], out[:, 1]
        statics[i] = contact.static_outputs["rim_Fz"]
        zone = contact.patch.zone
        per_node[i], n_points[i], zones[i] = zone.points_per_node, zone.n_points, zone.length_m
        reaches[i] = obstacle_reach_m(tire.R, contact.patch.deflection_m, obstacle)
        # the obstacle [X, X + L], X = -V t, overlaps [-reach, reach] for these t
        under[i] = -reaches[i] / speed_m_s, (obstacle.length_m + reaches[i]) / speed_m_s
        deflections[i] = contact.patch.deflection_m
        passing = speed_m_s / ((tire.R - deflections[i]) * 2 * np.pi / counts[i])
        inside = (time_s >= under[i, 0]) & (time_s <= under[i, 1])
        node_line[i] = line_amplitude(time_s[inside], contact_fz[i, inside], passing)
        point_line[i] = line_amplitude(time_s[inside], contact_fz[i, inside],
                                       passing * per_node[i])
        _report(progress, i + 1, size)
    return CleatConvergence(
        obstacle=obstacle, speed_m_s=float(speed_m_s), load_n=float(load), step_s=float(step_s),
        point_spacing_m=float(point_spacing_m), element_counts=counts,
        points_per_node=per_node, n_points=n_points, time_s=time_s, rim_fz_n=rim,
        contact_fz_n=contact_fz, static_rim_fz_n=statics, under_tire_s=under,
        reach_m=reaches, contact_zone_length_m=zones, node_line_n=node_line,
        point_line_n=point_line, run_s=run_s, deflection_m=deflections, radius_m=float(tire.R))


#: Columns of the cleat convergence table (the CLI, its figure and docs/theory.md show it).
CLEAT_TABLE_HEADER = ("N", "points per node (arc)", "rim_Fz peak rise", "vs converged",
                      "rim_Fz dip", "rim_Fz rms vs finest", "min contact_Fz",
                      "line at node passing", "line at point passing")


def cleat_table(data: dict) -> tuple[list[list[str]], str]:
    """Rows of :data:`CLEAT_TABLE_HEADER` and the sentence on the converged value, from
    :meth:`CleatConvergence.to_dict` (or its record): the one formatting of the table."""

    def line(amplitude_kn, hz) -> str:
        if amplitude_kn is None or not math.isfinite(amplitude_kn):
            return f"- ({hz:.0f} Hz above Nyquist)"
        return f"{amplitude_kn:.3g} kN at {hz:.0f} Hz"

    rows = [[str(row["n_elements"]),
             f"{row['points_per_node']} ({row['point_arc_mm']:.3g} mm)",
             f"{row['peak_rise_kn']:.2f} kN",
             f"{100 * row['rise_error']:+.1f} %",
             f"{row['peak_dip_kn']:.2f} kN",
             f"{100 * row['history_rms_difference']:.1f} %",
             f"{row['min_contact_fz_kn']:.1f} kN",
             line(row["node_line_kn"], row["node_passing_hz"]),
             line(row["point_line_kn"], row["point_passing_hz"])]
            for row in data["meshes"]]
    counts = ", ".join(str(row["n_elements"]) for row in data["meshes"][-3:])
    order = data["observed_order"]
    if order is not None and math.isfinite(order):
        note = (f"converged peak rise {data['extrapolated_rise_kn']:.2f} kN: Richardson "
                f"extrapolation over N = {counts}, observed order {order:.2f}")
    elif len(data["meshes"]) < 3:
        note = (f"converged peak rise taken as the finest mesh's, "
                f"{data['extrapolated_rise_kn']:.2f} kN: an order needs three meshes")
    else:
        note = (f"converged peak rise {data['extrapolated_rise_kn']:.2f} kN, the finest "
                f"mesh's: the differences between N = {counts} change sign or do not shrink, "
                "so no order is observed to extrapolate with")
    return rows, note
