"""Identify tire data from measured natural frequencies (and optionally static contact data).

The model of a measurement is the undeformed, non-rotating tire per circumferential order n:
both roots of the 2x2 problem of :mod:`.dispersion` (in-phase = low root, out-of-phase = high
root), with the continuum symbols (the analytic ring, eq. 12) or the FDM symbols of a mesh of N
nodes, which give exactly the frequencies of the assembled model on that mesh without building
it. A measured damping ratio is modelled by the proportional damping of the ring,
ζ = α/(2ω) + βω/2, exact for these modes. A measured vertical stiffness and footprint length at
a load come from :func:`static_contact`.

Free parameters are fitted in log space (x = ln(p/p_start)), which keeps them positive, makes
the Jacobian's columns relative sensitivities, and lets the ranges of
:data:`~tire_fmu.core.parameters.TIRE_FIELDS` act as bounds. Residuals are relative errors
times the measurement's weight. The report takes its uncertainty from the Jacobian at the
solution: covariance s²(JᵀJ)⁺ with s² the residual variance, Student-t intervals, the numerical
rank of J (a direction the data cannot see at all, e.g. scaling every line quantity together)
and the correlations between parameters.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import scipy.optimize as so
import scipy.stats as st

from .dispersion import body_frequencies
from .parameters import (
    MAX_ELEMENTS,
    MIN_ELEMENTS,
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    TireParameters,
)

BRANCHES = ("in", "out")
#: Singular values below this fraction of the largest mark directions the data cannot see.
RANK_TOLERANCE = 1e-6
#: A parameter takes part in an unseen direction when its share of that singular vector
#: exceeds this.
NULL_SHARE = 0.1
#: Pairs correlated beyond this are reported.
CORRELATION_LIMIT = 0.95
#: Step of the central differences of the reported Jacobian, in ln(parameter).
JACOBIAN_STEP = 1e-6
#: Iteration limit of the minimax (SLSQP) refinement.
MINIMAX_ITERATIONS = 300
CRITERIA = ("least_squares", "max")


class FitError(ValueError):
    """The fit cannot be set up or run; ``problems`` lists every reason found."""

    def __init__(self, problems: Sequence[str]):
        self.problems = list(problems)
        message = (self.problems[0] if len(self.problems) == 1 else
                   f"{len(self.problems)} fit problems: " + "; ".join(self.problems))
        super().__init__(message)


@dataclass(frozen=True)
class MeasuredMode:
    """One measured natural frequency: order n, branch "in" or "out", frequency in Hz.

    ``weight`` multiplies the mode's relative residual; ``damping_ratio`` (optional) is the
    measured modal damping ratio; ``label`` names the mode in messages (e.g. its table row).
    """

    order: int
    branch: str
    frequency_hz: float
    weight: float = 1.0
    damping_ratio: float | None = None
    label: str = ""

    @property
    def name(self) -> str:
        return self.label or f"mode n={self.order} {self.branch}"


@dataclass(frozen=True)
class StaticMeasurement:
    """Measured static contact at ``load_n``: vertical stiffness and/or footprint length."""

    load_n: float
    vertical_stiffness_n_per_m: float | None = None
    footprint_length_m: float | None = None
    weight: float = 1.0
    #: mesh of the FDM model the static contact is computed on
    n_elements: int = 100


def static_contact(tire: TireParameters, load_n: float, n_elements: int) -> tuple[float, float]:
    """(vertical stiffness N/m, footprint length m) of ``tire`` at ``load_n``.

    The one place the fit asks the model for its static contact: the footprint the model
    computes for the load. The stiffness is the secant, load over rim deflection, what a
    press test at that load reports; unlike the tangent it is smooth in the tire data (the
    tangent steps where a node enters the footprint), which a least-squares fit needs.
    """
    from .model import build_model  # the fit of frequencies alone never assembles a model

    patch = build_model(tire, OperatingPoint(n_elements=n_elements, load_n=load_n)).patch
    return patch.footprint.secant_stiffness_n_per_m, patch.length_m


def model_frequencies_hz(tire: TireParameters, orders, n_elements: int | None = None):
    """(in-phase, out-of-phase) natural frequencies in Hz of the undeformed tire at rest,
    per order: the analytic ring for ``n_elements=None``, else the FDM mesh's exact ones."""
    low, high = body_frequencies(tire, np.asarray(orders), 0.0, n_elements)
    return low / (2.0 * np.pi), high / (2.0 * np.pi)


def modal_damping_ratio(tire: TireParameters, omega_rad_s) -> np.ndarray:
    """ζ = α/(2ω) + βω/2 of a mode of the undeformed tire at rest (C = αM + βK)."""
    omega = np.asarray(omega_rad_s, dtype=float)
    return tire.alpha / (2.0 * omega) + tire.beta * omega / 2.0


@dataclass(frozen=True, eq=False)
class FitResult:
    """Fitted tire data and what the data say about them."""

    tire: TireParameters
    start: TireParameters
    free: tuple[str, ...]
    n_elements: int | None
    criterion: str
    modes: tuple[MeasuredMode, ...]
    fitted_hz: np.ndarray
    fitted_damping_ratio: np.ndarray  # nan where no damping was measured
    static: StaticMeasurement | None
    fitted_static: dict
    confidence: float
    determined_within: float
    interval_low: np.ndarray  # per free parameter, nan without residual degrees of freedom
    interval_high: np.ndarray
    log_std: np.ndarray  # standard deviation of ln(parameter); inf where undetermined
    singular_values: np.ndarray
    rank: int
    correlation: np.ndarray
    undetermined: tuple[str, ...]
    #: each direction the data do not see, as {parameter: share} of ln(parameter) (unit norm)
    null_directions: tuple[dict, ...]
    weakly_determined: tuple[str, ...]
    correlated_pairs: tuple[tuple[str, str, float], ...]
    degrees_of_freedom: int
    residual_rms: float
    success: bool
    message: str
    evaluations: int

    @property
    def values(self) -> np.ndarray:
        return np.array([getattr(self.tire, name) for name in self.free])

    @property
    def measured_hz(self) -> np.ndarray:
        return np.array([m.frequency_hz for m in self.modes])

    @property
    def residual_percent(self) -> np.ndarray:
        """Fitted / measured - 1 per mode, in %."""
        return 100.0 * (self.fitted_hz / self.measured_hz - 1.0)

    @property
    def relative_half_width(self) -> np.ndarray:
        """Larger side of each confidence interval relative to the value."""
        return np.maximum(self.interval_high / self.values - 1.0,
                          1.0 - self.interval_low / self.values)

    def parameter_rows(self) -> list[dict]:
        rows = []
        for j, name in enumerate(self.free):
            status = ("undetermined" if name in self.undetermined else
                      "weak" if name in self.weakly_determined else "determined")
            rows.append({
                "name": name,
                "unit": TIRE_FIELDS[name].unit,
                "start": getattr(self.start, name),
                "value": getattr(self.tire, name),
                "interval_low": self.interval_low[j],
                "interval_high": self.interval_high[j],
                "relative_std": math.expm1(self.log_std[j]) if np.isfinite(self.log_std[j])
                else math.inf,
                "status": status,
            })
        return rows

    def mode_rows(self) -> list[dict]:
        rows = []
        for i, m in enumerate(self.modes):
            rows.append({
                "label": m.name, "order": m.order, "branch": m.branch,
                "measured_hz": m.frequency_hz, "fitted_hz": self.fitted_hz[i],
                "residual_percent": self.residual_percent[i], "weight": m.weight,
                "measured_damping_ratio": m.damping_ratio,
                "fitted_damping_ratio": (self.fitted_damping_ratio[i]
                                         if m.damping_ratio is not None else None),
            })
        return rows

    def to_dict(self) -> dict:
        return {
            "free": list(self.free),
            "model": "analytic" if self.n_elements is None else f"fdm N={self.n_elements}",
            "criterion": self.criterion,
            "tire": self.tire.as_dict(),
            "parameters": self.parameter_rows(),
            "modes": self.mode_rows(),
            "static": None if self.static is None else {
                "load_n": self.static.load_n,
                "measured_vertical_stiffness_n_per_m": self.static.vertical_stiffness_n_per_m,
                "measured_footprint_length_m": self.static.footprint_length_m,
                **self.fitted_static,
            },
            "confidence": self.confidence,
            "determined_within": self.determined_within,
            "rank": self.rank,
            "singular_values": self.singular_values.tolist(),
            "correlation": self.correlation.tolist(),
            "undetermined": list(self.undetermined),
            "null_directions": list(self.null_directions),
            "weakly_determined": list(self.weakly_determined),
            "correlated_pairs": [list(p) for p in self.correlated_pairs],
            "degrees_of_freedom": self.degrees_of_freedom,
            "residual_rms": self.residual_rms,
            "max_abs_residual_percent": float(np.max(np.abs(self.residual_percent))),
            "success": self.success,
            "message": self.message,
            "evaluations": self.evaluations,
        }


def fit_problems(modes: Sequence[MeasuredMode], free: Sequence[str], start: TireParameters,
                 n_elements: int | None, static: StaticMeasurement | None,
                 criterion: str = "least_squares", confidence: float = 0.95) -> list[str]:
    """Every problem with a fit's set-up, each naming the mode, parameter or option."""
    problems = []
    if criterion not in CRITERIA:
        problems.append(f"criterion = {criterion!r}: must be one of {list(CRITERIA)}")
    if not 0.0 < confidence < 1.0:
        problems.append(f"confidence = {confidence!r}: must be in (0, 1)")
    if not free:
        problems.append("no free parameters: name at least one")
    for name in free:
        if name not in TIRE_FIELDS:
            problems.append(f"free parameter {name!r}: not a tire parameter; known: "
                            f"{sorted(TIRE_FIELDS)}")
        elif not getattr(start, name) > 0.0:
            problems.append(f"free parameter {name} = {getattr(start, name):g} "
                            f"{TIRE_FIELDS[name].unit}: the fit works in ln({name}), so it "
                            "needs a start value > 0")
    if len(set(free)) != len(free):
        problems.append(f"free parameters {list(free)}: each may be named once")
    if n_elements is not None and not MIN_ELEMENTS <= n_elements <= MAX_ELEMENTS:
        problems.append(f"n_elements = {n_elements}: must be in [{MIN_ELEMENTS}, "
                        f"{MAX_ELEMENTS}] (or None: analytic)")
    seen: dict[tuple[int, str], str] = {}
    for m in modes:
        if m.branch not in BRANCHES:
            problems.append(f"{m.name}: branch {m.branch!r} must be 'in' or 'out'")
        if not (isinstance(m.order, (int, np.integer)) and m.order >= 0):
            problems.append(f"{m.name}: order {m.order!r} must be an integer >= 0")
        elif m.branch == "out" and 0 < start.sidewall_max_order < m.order:
            problems.append(f"{m.name}: the tire's sidewall is tied to the tread above "
                            f"sidewall_max_order = {start.sidewall_max_order:g}, so it has no "
                            f"out-of-phase (sidewall) mode of order {m.order}; fit with "
                            f"sidewall_max_order = 0 or >= {m.order} (--tire "
                            "sidewall_max_order=0, or --tire-file GL073A)")
        elif n_elements is not None and 2 * m.order > n_elements:
            problems.append(f"{m.name}: order {m.order} is not resolved by a mesh of "
                            f"{n_elements} nodes (n <= N/2 = {n_elements // 2})")
        if not (math.isfinite(m.frequency_hz) and m.frequency_hz > 0.0):
            problems.append(f"{m.name}: frequency {m.frequency_hz!r} Hz must be finite and > 0")
        if not (math.isfinite(m.weight) and m.weight > 0.0):
            problems.append(f"{m.name}: weight {m.weight!r} must be finite and > 0")
        if m.damping_ratio is not None and not 0.0 < m.damping_ratio < 1.0:
            problems.append(f"{m.name}: damping ratio {m.damping_ratio!r} must be in (0, 1)")
        key = (m.order, m.branch)
        if key in seen:
            problems.append(f"{m.name}: order {m.order} {m.branch}-phase already given by "
                            f"{seen[key]}")
        seen.setdefault(key, m.name)
    if static is not None:
        given = [v for v in (static.vertical_stiffness_n_per_m, static.footprint_length_m)
                 if v is not None]
        if not given:
            problems.append(f"static measurement at load {static.load_n:g} N: give a vertical "
                            "stiffness, a footprint length or both")
        for name, value, unit in (("load", static.load_n, "N"),
                                  ("vertical stiffness", static.vertical_stiffness_n_per_m,
                                   "N/m"),
                                  ("footprint length", static.footprint_length_m, "m")):
            if value is not None and not (math.isfinite(value) and value > 0.0):
                problems.append(f"static {name} = {value!r} {unit}: must be finite and > 0")
    n_data = len(modes) + sum(m.damping_ratio is not None for m in modes)
    if static is not None:
        n_data += (static.vertical_stiffness_n_per_m is not None) + \
            (static.footprint_length_m is not None)
    if n_data == 0:
        problems.append("no measurements: give at least one mode")
    return problems


class _Problem:
    """Residuals of the measurements as a function of x = ln(p / p_start) of the free set."""

    def __init__(self, modes, free, start, n_elements, static):
        self.modes, self.free, self.start = modes, tuple(free), start
        self.n_elements, self.static = n_elements, static
        self.orders = np.array([m.order for m in modes], dtype=int)
        self.high = np.array([m.branch == "out" for m in modes])
        self.measured = np.array([m.frequency_hz for m in modes])
        self.weights = np.array([m.weight for m in modes])
        damped = [i for i, m in enumerate(modes) if m.damping_ratio is not None]
        self.damped = np.array(damped, dtype=int)
        self.measured_damping = np.array([modes[i].damping_ratio for i in damped])
        self.start_values = np.array([getattr(start, name) for name in free])
        self.evaluations = 0

    def bounds(self):
        low, high = [], []
        for name, value in zip(self.free, self.start_values):
            spec = TIRE_FIELDS[name]
            # an open lower bound stays open: keep a hair inside it
            floor = spec.low * (1.0 + 1e-9) if spec.low > 0.0 else 0.0
            low.append(math.log(floor / value) if floor > 0.0 else -np.inf)
            high.append(math.log(spec.high / value))
        return np.array(low), np.array(high)

    def tire(self, x) -> TireParameters:
        values = self.start_values * np.exp(x)
        return replace(self.start, **{n: float(v) for n, v in zip(self.free, values)})

    def predictions(self, tire: TireParameters):
        low, high = model_frequencies_hz(tire, self.orders, self.n_elements)
        frequencies = np.where(self.high, high, low)
        damping = modal_damping_ratio(tire, 2.0 * np.pi * frequencies[self.damped])
        statics = {}
        if self.static is not None:
            stiffness, length = static_contact(tire, self.static.load_n, self.static.n_elements)
            statics = {"fitted_vertical_stiffness_n_per_m": stiffness,
                       "fitted_footprint_length_m": length}
        return frequencies, damping, statics

    def residuals(self, x) -> np.ndarray:
        self.evaluations += 1
        frequencies, damping, statics = self.predictions(self.tire(x))
        parts = [self.weights * (frequencies / self.measured - 1.0),
                 self.weights[self.damped] * (damping / self.measured_damping - 1.0)]
        s = self.static
        if s is not None:
            if s.vertical_stiffness_n_per_m is not None:
                parts.append([s.weight * (statics["fitted_vertical_stiffness_n_per_m"]
                                          / s.vertical_stiffness_n_per_m - 1.0)])
            if s.footprint_length_m is not None:
                parts.append([s.weight * (statics["fitted_footprint_length_m"]
                                          / s.footprint_length_m - 1.0)])
        return np.concatenate([np.asarray(p, dtype=float) for p in parts])

    def jacobian(self, x, low, high) -> np.ndarray:
        """Central differences in ln(p), one-sided where a bound is within a step."""
        columns = []
        for j in range(x.size):
            up, down = x.copy(), x.copy()
            up[j] = min(x[j] + JACOBIAN_STEP, high[j])
            down[j] = max(x[j] - JACOBIAN_STEP, low[j])
            columns.append((self.residuals(up) - self.residuals(down)) / (up[j] - down[j]))
        return np.column_stack(columns)


def fit_tire(modes: Sequence[MeasuredMode], free: Sequence[str],
             start: TireParameters | None = None, n_elements: int | None = None,
             static: StaticMeasurement | None = None, criterion: str = "least_squares",
             confidence: float = 0.95, determined_within: float = 0.05) -> FitResult:
    """Fit the ``free`` tire parameters to measured modes (and static contact data).

    The other parameters stay at their ``start`` values (default: GL073A). ``n_elements``
    None fits the analytic ring; an integer fits the FDM model of that mesh (per-order
    symbols, as fast). ``criterion`` "least_squares" minimises the sum of squared weighted
    relative residuals; "max" then minimises the largest one (SLSQP on min t subject to
    |r_i| <= t), for a re-identification that must stay within a tolerance of every mode.
    A parameter is reported weakly determined when its ``confidence`` interval reaches further than
    ``determined_within`` (relative) from the value, undetermined when it lies in a direction
    the data do not see at all (numerical rank of the Jacobian).

    Raises :class:`FitError` listing every problem with the set-up.
    """
    start = start or TireParameters()
    modes = tuple(modes)
    free = tuple(free)
    problems = fit_problems(modes, free, start, n_elements, static, criterion, confidence)
    if problems:
        raise FitError(problems)
    problem = _Problem(modes, free, start, n_elements, static)
    low, high = problem.bounds()
    x0 = np.clip(np.zeros(len(free)), low, high)
    try:
        solution = so.least_squares(problem.residuals, x0, bounds=(low, high), jac="3-point",
                                    x_scale=1.0, xtol=1e-12, ftol=1e-12, gtol=1e-12,
                                    method="trf")
        x = solution.x
        if criterion == "max":
            x = _minimax(problem, x, low, high)
    except ParameterError as error:  # e.g. a load the trial tire cannot carry
        raise FitError([f"the model refused a trial tire during the fit: {error}"]) from error
    return _report(problem, x, low, high, criterion, confidence, determined_within,
                   bool(solution.success), str(solution.message))


def _minimax(problem: _Problem, x, low, high) -> np.ndarray:
    """Smallest largest |residual|: min t subject to -t <= r_i(x) <= t (SLSQP), started from
    the least-squares solution."""
    cache: dict = {}

    def evaluate(z):
        key = z[:-1].tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = (problem.residuals(z[:-1]), problem.jacobian(z[:-1], low, high))
        return cache[key]

    def constraints(z):
        r, _ = evaluate(z)
        return np.concatenate([z[-1] - r, z[-1] + r])

    def constraints_jacobian(z):
        _, jac = evaluate(z)
        ones = np.ones((jac.shape[0], 1))
        return np.vstack([np.hstack([-jac, ones]), np.hstack([jac, ones])])

    start_max = float(np.max(np.abs(problem.residuals(x))))
    z0 = np.r_[x, start_max]
    bounds = [(lo if np.isfinite(lo) else None, hi if np.isfinite(hi) else None)
              for lo, hi in zip(low, high)] + [(0.0, None)]
    gradient = np.r_[np.zeros(x.size), 1.0]
    solution = so.minimize(lambda z: z[-1], z0, jac=lambda z: gradient, method="SLSQP",
                           bounds=bounds, options={"maxiter": MINIMAX_ITERATIONS,
                                                   "ftol": 1e-14},
                           constraints=[{"type": "ineq", "fun": constraints,
                                         "jac": constraints_jacobian}])
    candidate = np.clip(solution.x[:-1], low, high)
    if np.max(np.abs(problem.residuals(candidate))) < start_max:
        return candidate
    return x


def jacobian_statistics(jac: np.ndarray, residuals: np.ndarray, names: Sequence[str],
                        values: np.ndarray, confidence: float,
                        determined_within: float) -> dict:
    """What the Jacobian in ln(parameter) at a solution says about the parameters: the
    covariance s²(JᵀJ)⁺ on the directions the data see, Student-t intervals, the numerical
    rank, the unseen directions, weak parameters and correlated pairs (FitResult's fields of
    those names). Shared by every fit."""
    m, p = jac.shape
    # the full V: with fewer data than free parameters the null space is the rows of Vᵀ
    # past the data's count, which the economy SVD leaves out
    _, s, vt = np.linalg.svd(jac, full_matrices=True)
    rank = int(np.sum(s > RANK_TOLERANCE * s[0])) if s.size and s[0] > 0 else 0
    null = vt[rank:]
    unseen = np.any(np.abs(null) > NULL_SHARE, axis=0) if null.size else np.zeros(p, bool)
    # Covariance on the directions the data see; unseen parameters get an infinite spread.
    inverse = (vt[:rank].T / s[:rank] ** 2) @ vt[:rank]
    dof = m - p
    variance = float(residuals @ residuals) / dof if dof > 0 else math.nan
    log_var = np.diag(inverse) * variance
    log_std = np.where(unseen, np.inf, np.sqrt(np.abs(log_var)))
    t = st.t.ppf(0.5 * (1.0 + confidence), dof) if dof > 0 else math.nan
    with np.errstate(over="ignore", invalid="ignore"):
        interval_low = values * np.exp(-t * log_std)
        interval_high = values * np.exp(t * log_std)
    scale = np.sqrt(np.abs(np.diag(inverse)))
    with np.errstate(divide="ignore", invalid="ignore"):
        correlation = inverse / np.outer(scale, scale)
    correlation = np.where(np.outer(~unseen, ~unseen), correlation, np.nan)
    names = tuple(names)
    undetermined = tuple(n for n, u in zip(names, unseen) if u)
    directions = tuple({n: float(v) for n, v in zip(names, row) if abs(v) > NULL_SHARE}
                       for row in null)
    half_width = np.maximum(interval_high / values - 1.0, 1.0 - interval_low / values)
    weak = () if dof <= 0 else tuple(  # without residual freedom there is no spread to judge
        n for n, u, w in zip(names, unseen, half_width) if not u and not w <= determined_within)
    pairs = tuple((names[i], names[j], float(correlation[i, j]))
                  for i in range(p) for j in range(i + 1, p)
                  if abs(correlation[i, j]) > CORRELATION_LIMIT)
    return dict(interval_low=interval_low, interval_high=interval_high, log_std=log_std,
                singular_values=s, rank=rank, correlation=correlation,
                undetermined=undetermined, null_directions=directions,
                weakly_determined=weak, correlated_pairs=pairs, degrees_of_freedom=dof,
                residual_rms=float(np.sqrt(np.mean(residuals**2))))


def _report(problem: _Problem, x, low, high, criterion, confidence, determined_within,
            success, message) -> FitResult:
    tire = problem.tire(x)
    residuals = problem.residuals(x)
    jac = problem.jacobian(x, low, high)
    values = np.array([getattr(tire, name) for name in problem.free])
    stats = jacobian_statistics(jac, residuals, problem.free, values, confidence,
                                determined_within)
    frequencies, damping, statics = problem.predictions(tire)
    fitted_damping = np.full(len(problem.modes), np.nan)
    fitted_damping[problem.damped] = damping
    return FitResult(
        tire=tire, start=problem.start, free=problem.free, n_elements=problem.n_elements,
        criterion=criterion, modes=problem.modes, fitted_hz=frequencies,
        fitted_damping_ratio=fitted_damping, static=problem.static, fitted_static=statics,
        confidence=confidence, determined_within=determined_within, success=success,
        message=message, evaluations=problem.evaluations, **stats)


def modes_of(tire: TireParameters, orders, branches=BRANCHES, n_elements: int | None = None,
             damping: bool = False) -> list[MeasuredMode]:
    """The modes a tire has, as measurements (synthetic data for checks and re-fits)."""
    orders = np.asarray(orders, dtype=int)
    low, high = model_frequencies_hz(tire, orders, n_elements)
    modes = []
    for branch in branches:
        values = low if branch == "in" else high
        for n, f in zip(orders, values):
            zeta = float(modal_damping_ratio(tire, 2.0 * np.pi * f)) if damping else None
            modes.append(MeasuredMode(int(n), branch, float(f), damping_ratio=zeta))
    return modes
