"""Identify the in-plane ring's tangential data from measured tangential and rotational modes
and a longitudinal slip stiffness.

GL073A's published data are radial only (§13.6 of docs/theory.md): ``EA``, the tangential
sidewall ``k_t1``, ``k_t2`` and the tread's shear stiffness ``k_tx`` are estimates until a
measurement pins them. What pins them:

- a **tangential mode** of order n: the branch of order n whose kinetic energy is mostly
  tangential, of the undeformed tire at rest with the rim held, on the FDM mesh (the order's
  exact frequencies, as the radial fit takes them); order 0 is the rotational mode with the
  rim held;
- the **rotational mode with the rim free** (the wheel's inertia against the tread's, through
  the sidewall): the assembled tire's mode labelled rotational;
- the **longitudinal slip stiffness** C_κ = dFx/dκ at κ → 0, at a load and speed: the slope
  of :func:`.inplane_contact.steady_rolling` between two small brake and drive torques, all
  points sticking, which the tread elements' ``k_tx`` sets.

The radial data stay as given (fit them first with :func:`.fit.fit_tire`): the tangential
frequencies depend on them through the pressure, EI and the sidewall. The fit is the radial
fit's method: relative residuals times weights, free parameters in ln(p / p_start) bounded
by :data:`.inplane.TANGENTIAL_RANGES`, and the report's statistics from
:func:`.fit.jacobian_statistics`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
import scipy.optimize as so

from .fit import FitError, jacobian_statistics
from .inplane import TANGENTIAL_RANGES, InPlaneRing, InPlaneTire
from .parameters import DEFAULT_LOAD_N, MAX_ELEMENTS, MIN_ELEMENTS, ParameterError

TARGET_KINDS = ("tangential", "rotational_free", "slip_stiffness")
#: What each kind is measured in.
TARGET_UNITS = {"tangential": "Hz", "rotational_free": "Hz", "slip_stiffness": "N"}
#: The probing torques of the slip stiffness: a drive and a brake that pull this fraction of
#: the load at the tread, small enough that every point sticks.
SLIP_PROBE_FRACTION = 0.01
#: Parameters the fit may free (the wheel's and the rim's are measured, not fitted).
FITTABLE = ("EA", "k_t1", "k_t2", "k_tx")


@dataclass(frozen=True)
class InPlaneTarget:
    """One measured in-plane quantity (``kind`` one of :data:`TARGET_KINDS`): a frequency in
    Hz (``order`` for a tangential mode), or a slip stiffness in N at ``load_n`` and
    ``speed_m_s``; ``weight`` multiplies its relative residual."""

    kind: str
    value: float
    order: int = 0
    load_n: float = DEFAULT_LOAD_N
    speed_m_s: float = 10.0
    weight: float = 1.0
    label: str = ""

    @property
    def name(self) -> str:
        if self.label:
            return self.label
        if self.kind == "tangential":
            return f"tangential n={self.order}" + (" (rotational, rim held)"
                                                   if self.order == 0 else "")
        if self.kind == "rotational_free":
            return "rotational, rim free"
        return f"slip stiffness at {self.load_n:g} N, {self.speed_m_s:g} m/s"


def tangential_frequency_hz(ring: InPlaneRing, order: int) -> float:
    """The undamped frequency of order ``order``'s most tangential branch (rim held, at rest)."""
    from .inplane_modes import order_matrices

    mass, _, stiffness = order_matrices(ring, order)
    lam, vectors = scipy.linalg.eigh(0.5 * (stiffness + stiffness.conj().T),
                                     0.5 * (mass + mass.conj().T))
    tangential = [i for i, name in enumerate(ring.fields) if name.startswith("v")]
    energy = np.real(np.conj(vectors) * (mass @ vectors))  # per field, per branch
    share = energy[tangential].sum(axis=0) / energy.sum(axis=0)
    return float(np.sqrt(max(lam[int(np.argmax(share))], 0.0)) / (2 * np.pi))


def rotational_free_hz(model: InPlaneTire, n_elements: int) -> float:
    """The rotational mode of the undeformed tire at rest with the rim free (Hz)."""
    from .inplane_modes import tire_modes

    modes = tire_modes(InPlaneRing(model, n_elements, rim_free=True))
    rotational = modes.select(kind="rotational")
    if not rotational:
        raise FitError(["the trial tire has no rotational mode with the rim free"])
    return min(m.frequency_hz for m in rotational)


def slip_stiffness_n(model: InPlaneTire, load_n: float, speed_m_s: float,
                     n_elements: int) -> float:
    """C_κ = dFx/dκ at κ → 0 (N per unit slip) of the steady rolling tire at the load."""
    from .inplane_contact import InPlaneSimulator, deflection_for_load, steady_rolling

    deflection = deflection_for_load(model, load_n, n_elements)
    sim = InPlaneSimulator(model, n_elements, speed_m_s, deflection, wheel="free")
    torque = SLIP_PROBE_FRACTION * load_n * model.tire.R
    drive, brake = steady_rolling(sim, torque), steady_rolling(sim, -torque)
    if drive.sliding_points or brake.sliding_points:
        raise FitError([f"the slip-stiffness probe slides at {load_n:g} N (points sliding: "
                        f"{drive.sliding_points}, {brake.sliding_points}); the trial tire's "
                        "friction limit is below 1 % of the load"])
    return (drive.rim_fx_n - brake.rim_fx_n) / (drive.slip_ratio - brake.slip_ratio)


def predictions(model: InPlaneTire, targets: Sequence[InPlaneTarget],
                n_elements: int) -> np.ndarray:
    """Each target's value for ``model`` (frequencies on the mesh of ``n_elements``)."""
    ring = None
    out = []
    for target in targets:
        if target.kind == "tangential":
            ring = ring or InPlaneRing(model, n_elements)
            out.append(tangential_frequency_hz(ring, target.order))
        elif target.kind == "rotational_free":
            out.append(rotational_free_hz(model, n_elements))
        else:
            out.append(slip_stiffness_n(model, target.load_n, target.speed_m_s, n_elements))
    return np.array(out)


def target_problems(targets: Sequence[InPlaneTarget], free: Sequence[str],
                    n_elements: int) -> list[str]:
    """Every problem with a tangential fit's set-up, at once."""
    problems = []
    if not targets:
        problems.append("no in-plane measurements: give a tangential or rotational mode or a "
                        "slip stiffness")
    if not free:
        problems.append(f"no free tangential parameter: name some of {', '.join(FITTABLE)}")
    for name in free:
        if name not in FITTABLE:
            problems.append(f"free tangential parameter {name!r}: must be one of "
                            f"{', '.join(FITTABLE)}")
    if len(set(free)) != len(free):
        problems.append(f"free tangential parameters {', '.join(free)}: each once")
    if not (isinstance(n_elements, int) and MIN_ELEMENTS <= n_elements <= MAX_ELEMENTS):
        problems.append(f"n_elements = {n_elements!r}: must be an integer in "
                        f"[{MIN_ELEMENTS}, {MAX_ELEMENTS}]")
    for t in targets:
        unit = TARGET_UNITS.get(t.kind, "")
        if t.kind not in TARGET_KINDS:
            problems.append(f"{t.name}: kind {t.kind!r} must be one of {', '.join(TARGET_KINDS)}")
            continue
        if not (math.isfinite(t.value) and t.value > 0):
            problems.append(f"{t.name} = {t.value!r} {unit}: must be finite and > 0")
        if not (math.isfinite(t.weight) and t.weight > 0):
            problems.append(f"{t.name}: weight = {t.weight!r}: must be finite and > 0")
        if t.kind == "tangential" and not (isinstance(t.order, int)
                                           and 0 <= t.order <= n_elements // 2):
            problems.append(f"{t.name}: order = {t.order!r}: must be an integer in "
                            f"[0, {n_elements // 2}] (N/2 of the mesh)")
        if t.kind == "slip_stiffness":
            if not (math.isfinite(t.load_n) and 0 < t.load_n <= 1e6):
                problems.append(f"{t.name}: load_n = {t.load_n!r} N: must be in (0, 1e+06] N")
            if not (math.isfinite(t.speed_m_s) and 0.5 <= t.speed_m_s <= 60):
                problems.append(f"{t.name}: speed_m_s = {t.speed_m_s!r} m/s: must be in "
                                "[0.5, 60] m/s")
    return problems


@dataclass(frozen=True, eq=False)
class InPlaneFitResult:
    """Fitted tangential data and what the measurements say about them (the statistics are
    :class:`.fit.FitResult`'s)."""

    model: InPlaneTire
    start: InPlaneTire
    free: tuple[str, ...]
    n_elements: int
    targets: tuple[InPlaneTarget, ...]
    fitted: np.ndarray
    confidence: float
    determined_within: float
    interval_low: np.ndarray
    interval_high: np.ndarray
    log_std: np.ndarray
    singular_values: np.ndarray
    rank: int
    correlation: np.ndarray
    undetermined: tuple[str, ...]
    null_directions: tuple[dict, ...]
    weakly_determined: tuple[str, ...]
    correlated_pairs: tuple[tuple[str, str, float], ...]
    degrees_of_freedom: int
    residual_rms: float
    success: bool
    message: str

    @property
    def residual_percent(self) -> np.ndarray:
        return 100.0 * (self.fitted / np.array([t.value for t in self.targets]) - 1.0)

    def parameter_rows(self) -> list[dict]:
        rows = []
        for j, name in enumerate(self.free):
            status = ("undetermined" if name in self.undetermined else
                      "weak" if name in self.weakly_determined else "determined")
            rows.append({"name": name, "unit": TANGENTIAL_RANGES[name][2],
                         "start": getattr(self.start.tangential, name),
                         "value": getattr(self.model.tangential, name),
                         "interval_low": float(self.interval_low[j]),
                         "interval_high": float(self.interval_high[j]), "status": status})
        return rows

    def target_rows(self) -> list[dict]:
        return [{"label": t.name, "kind": t.kind, "unit": TARGET_UNITS[t.kind],
                 "measured": t.value, "fitted": float(f), "residual_percent": float(r),
                 "weight": t.weight}
                for t, f, r in zip(self.targets, self.fitted, self.residual_percent)]

    def to_dict(self) -> dict:
        return {"free": list(self.free), "model": f"fdm N={self.n_elements}",
                "tangential": {k: getattr(self.model.tangential, k) for k in TANGENTIAL_RANGES},
                "parameters": self.parameter_rows(), "targets": self.target_rows(),
                "rank": self.rank, "undetermined": list(self.undetermined),
                "null_directions": list(self.null_directions),
                "weakly_determined": list(self.weakly_determined),
                "correlated_pairs": [list(p) for p in self.correlated_pairs],
                "degrees_of_freedom": self.degrees_of_freedom,
                "residual_rms": self.residual_rms, "success": self.success,
                "message": self.message}


def fit_inplane(targets: Sequence[InPlaneTarget], free: Sequence[str],
                start: InPlaneTire | None = None, n_elements: int = 100,
                confidence: float = 0.95, determined_within: float = 0.05) -> InPlaneFitResult:
    """Fit the ``free`` tangential parameters (of :data:`FITTABLE`) to the targets; the
    radial data and the other tangential ones stay at ``start``'s (default: GL073A with the
    shipped tangential estimates). Raises :class:`.fit.FitError` listing every problem."""
    start = start or InPlaneTire()
    targets, free = tuple(targets), tuple(free)
    problems = target_problems(targets, free, n_elements)
    if problems:
        raise FitError(problems)
    measured = np.array([t.value for t in targets])
    weights = np.array([t.weight for t in targets])
    start_values = np.array([getattr(start.tangential, name) for name in free])
    low = np.array([math.log(max(TANGENTIAL_RANGES[n][0], 1e-300) * (1 + 1e-9) / v)
                    for n, v in zip(free, start_values)])
    high = np.array([math.log(TANGENTIAL_RANGES[n][1] / v) for n, v in zip(free, start_values)])

    def model_at(x) -> InPlaneTire:
        values = start_values * np.exp(x)
        return replace(start, tangential=replace(
            start.tangential, **{n: float(v) for n, v in zip(free, values)}))

    def residuals(x) -> np.ndarray:
        return weights * (predictions(model_at(x), targets, n_elements) / measured - 1.0)

    try:
        solution = so.least_squares(residuals, np.zeros(len(free)), bounds=(low, high),
                                    jac="3-point", xtol=1e-12, ftol=1e-12, gtol=1e-12)
    except ParameterError as error:
        raise FitError([f"the model refused a trial tire during the fit: {error}"]) from error
    model = model_at(solution.x)
    values = np.array([getattr(model.tangential, name) for name in free])
    stats = jacobian_statistics(solution.jac, solution.fun, free, values, confidence,
                                determined_within)
    return InPlaneFitResult(
        model=model, start=start, free=free, n_elements=n_elements, targets=targets,
        fitted=predictions(model, targets, n_elements), confidence=confidence,
        determined_within=determined_within, success=bool(solution.success),
        message=str(solution.message), **stats)
