"""Parameter studies behind the paper's figures: mesh convergence (Fig. 14), contact-patch length
(Fig. 17) and speed (Figs. 18-19).

Each study is a plain function over the assembled model that returns a frozen result object with
``to_dict()``; the CLI prints and the plots draw from these, nothing here reads files or plots.
Long loops take an optional ``progress(done, total)`` callback so a front end can show a bar.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace

import numpy as np

from .analytic import analytic_modes
from .complex_modal import complex_modes
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
