"""Reduced-order models of the tire: modal truncation (with static correction) or balanced
truncation, always delivered in diagonal modal form with an accuracy report.

Modal form: the first-order model ẋ = A x + B r is diagonalised, A = V Λ V⁻¹, q = V⁻¹ x. Of
each complex-conjugate pair only the member with Im λ > 0 is kept: for real inputs its partner
is its conjugate, so the pair's output is 2·Re(c q). The reduced model is therefore

    q̇ = Λ q + B_q r,     y = Re(C_q q) + D r + E ṙ,

with C_q already carrying that factor 2 (1 for real eigenvalues). It works unchanged for the
rolling (gyroscopic, non-symmetric) model.

Which modes to keep, in terms a user can reason about (:class:`ReductionSettings`):
- ``target_error``: the largest relative FRF error over the band allowed, for both methods.
  Modal truncation keeps the fewest modes it finds whose reduced model (with its static
  correction) meets it: each mode's term relative to the full response, frequency by
  frequency, is known exactly, so the error of any set of dropped modes is the magnitude of
  the sum of their terms, with no bound (at speed the terms of a split pair are large and
  cancel, and a sum of magnitudes over-states the error tenfold). Modes are dropped least
  dominant first (dominance: the error a mode's drop alone would leave), as many as the
  exact error allows, then one at a time the mode whose drop leaves the least error, until
  dropping any further mode would break the target;
- ``f_max_hz``: drop the modes whose natural frequency |λ|/2π is above it first (default:
  no cut; modes far above the band still shape it, the contact patch's stiff modes most of
  all, and the target already drops what does not matter);
- ``n_modes``: at most this many, the most dominant first;
- ``static_correction``: add the dropped modes' static (DC) response as a feedthrough, so the
  DC gain is exact (python-control calls this 'matchdc').
``method="balanced"`` instead balances a generous modal pre-reduction and truncates it to
``n_states`` states, or to the fewest that meet ``target_error`` (see
:mod:`tire_fmu.core.balanced`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Mapping
from dataclasses import InitVar, asdict, dataclass, replace
from typing import Any

import numpy as np

from .blas_threads import blas_threads
from .contact import RoadWindows
from .free_ring import F_MAX_LIMIT_HZ
from .io_model import OUTPUTS, PHYSICAL_INPUTS, InputOutputModel, build_io_model, physical_input
from .modal_form import (
    ModalForm,
    diagonalise,
    diagonalise_proportional,
    modal_frequency_response,
    real_block_form,
)
from .model import TireModel, check_resolved
from .parameters import ParameterError, TireParameters

# .modal and .balanced (scipy.sparse.linalg, LAPACK wrappers) are imported by the functions that
# use them: the FMU reads ReductionSettings from this module at start-up and reduces nothing.

METHODS = ("modal", "balanced")


class ReductionWarning(UserWarning):
    """The reduction settings leave more error than they were asked to."""


@dataclass(frozen=True)
class ReductionSettings:
    """How to reduce; see the module docstring. Frequencies in Hz."""

    method: str = "modal"
    f_max_hz: float | None = None  # None: no frequency cut, the error target decides
    n_modes: int | None = None  # modal: at most this many modes, the most dominant first
    static_correction: bool = True
    n_states: int | None = None  # balanced: states kept (None: fewest meeting target_error)
    target_error: float = 5e-3  # max relative FRF error over the band allowed (both methods)
    error_band_hz: tuple[float, float] = (1.0, 300.0)
    error_points: int = 400
    #: the former modal budget (a bound on a sum of mode shares); refused, naming target_error
    contribution_threshold: InitVar[float | None] = None

    def __post_init__(self, contribution_threshold: float | None) -> None:
        from .parameters import Problem

        problems = []
        if self.method not in METHODS:
            problems.append(Problem("method", self.method, "", f"one of {', '.join(METHODS)}"))
        if self.f_max_hz is not None and not (
            _is_number(self.f_max_hz) and 0 < self.f_max_hz <= F_MAX_LIMIT_HZ
        ):
            problems.append(Problem("f_max_hz", self.f_max_hz, "Hz",
                                    f"in (0, {F_MAX_LIMIT_HZ:g}] Hz",
                                    "the highest natural frequency kept", unset=True))
        if contribution_threshold is not None:
            problems.append(Problem(
                "contribution_threshold", contribution_threshold, "", "left out",
                "replaced by target_error, the largest relative FRF error allowed, which modal "
                f"truncation now meets exactly as balanced truncation does: give target_error = "
                f"{contribution_threshold!r}"))
        for name in ("n_modes", "n_states"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int)
                                      or not 1 <= value <= 100_000):
                problems.append(Problem(name, value, "", "an integer in [1, 100000]",
                                        unset=True))
        band = self.error_band_hz
        # far above the ring's modes (the highest: 8.7e6 Hz at N = 1600 with GL073A) the
        # error compares rounding, not the model: it grows with f (7e-6 at 1e12 Hz, 7e82 at
        # 1e100 Hz), so the band ends where f_max does
        if not (isinstance(band, (tuple, list)) and len(band) == 2 and all(map(_is_number, band))
                and 0 <= band[0] < band[1] <= F_MAX_LIMIT_HZ):
            problems.append(Problem("error_band_hz", band, "Hz",
                                    f"(low, high) with 0 <= low < high <= {F_MAX_LIMIT_HZ:g} Hz"))
        if not (_is_number(self.target_error) and 0 <= self.target_error < 1):
            problems.append(Problem("target_error", self.target_error, "", "in [0, 1)",
                                    "0 keeps every mode, or every balanced state"))
        if not (isinstance(self.error_points, int) and 10 <= self.error_points <= 100_000):
            problems.append(Problem("error_points", self.error_points, "",
                                    "an integer in [10, 100000]"))
        if problems:
            raise ParameterError(problems)

    def above_f_max(self, eigenvalues: np.ndarray) -> np.ndarray:
        """Which modes lie above f_max (natural frequency |λ|/2π); none without a cut."""
        if self.f_max_hz is None:
            return np.zeros(eigenvalues.shape, dtype=bool)
        return np.abs(eigenvalues) > 2 * np.pi * self.f_max_hz

    def error_frequencies_hz(self) -> np.ndarray:
        low, high = self.error_band_hz
        return np.geomspace(max(low, 1e-3), high, self.error_points)


@dataclass(frozen=True)
class ErrorReport:
    """Accuracy of a reduced model against the full model over a band.

    ``reference`` says where the full model's responses came from: "modal" (its complete
    modal decomposition, the one the reduction is cut from; equal to the exact responses to
    about 1e-12 at rest and 1e-7 rolling) or "exact" (one sparse solve of the assembled
    second-order model per frequency).
    """

    band_hz: tuple[float, float]
    max_relative_error: float  # over every input/output pair with a non-zero response
    per_pair: dict[str, float]  # "road->rim_Fz": max_ω |H_red - H_full| / |H_full|
    dc_relative_error: dict[str, float]
    reference: str = "exact"

    def to_dict(self) -> dict:
        return asdict(self)


#: Fields of :class:`OperatingPointRecord`, as :meth:`TireModel.summary` names them.
_OPERATING_POINT_FIELDS = ("n_elements", "speed_m_s", "spin_rad_s", "critical_speed_m_s",
                           "patch_length_m", "deflection_m", "load_n",
                           "vertical_stiffness_n_per_m", "patch_points", "points_per_node")


@dataclass(frozen=True)
class OperatingPointRecord:
    """The operating point a reduced model was built at (SI units)."""

    n_elements: int
    speed_m_s: float
    spin_rad_s: float
    critical_speed_m_s: float
    patch_length_m: float
    deflection_m: float
    load_n: float
    vertical_stiffness_n_per_m: float
    patch_points: int  # contact points with a spring in the linearisation
    points_per_node: int  # contact points per node arc (1: the node model)

    @classmethod
    def from_summary(cls, summary: Mapping[str, Any]) -> OperatingPointRecord:
        """From a model summary (or its JSON); keys beyond the record's fields are ignored."""
        summary = dict(summary)
        if "patch_points" not in summary and "patch_nodes" in summary:
            # written before the contact points: one point per node
            summary["patch_points"], summary["points_per_node"] = summary["patch_nodes"], 1
        values = {name: summary[name] for name in _OPERATING_POINT_FIELDS}
        for name in ("n_elements", "patch_points", "points_per_node"):
            values[name] = int(values[name])
        return cls(**values)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class ReductionRecord:
    """Where a reduced model came from: tire data, operating point, size, build time."""

    tire: TireParameters
    operating_point: OperatingPointRecord
    full_states: int
    build_seconds: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "tire": self.tire.as_dict(),
            "operating_point": self.operating_point.to_dict(),
            "full_states": self.full_states,
            "build_seconds": self.build_seconds,
        }

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> ReductionRecord:
        return cls(
            tire=TireParameters(**values["tire"]),
            operating_point=OperatingPointRecord.from_summary(values["operating_point"]),
            full_states=int(values["full_states"]),
            build_seconds=float(values["build_seconds"]),
        )


@dataclass(frozen=True, eq=False)
class ReducedModel:
    """A reduced tire model in diagonal modal form, with what it came from and how good it is.

    Inputs r = [rim_z, road_z under each contact node group] (see ``road_windows``),
    their velocities ṙ feed only the direct term E. Outputs: rim_Fz, rim_Fx, contact_Fz,
    deflection (deviations from the static values in ``static_outputs``).
    """

    eigenvalues: np.ndarray  # (k,) complex
    b: np.ndarray  # (k, n_inputs) complex
    c: np.ndarray  # (n_outputs, k) complex, pair factor 2 included
    d: np.ndarray  # (n_outputs, n_inputs) real
    e: np.ndarray  # (n_outputs, n_inputs) real, on ṙ
    road_windows: RoadWindows
    static_outputs: dict[str, float]
    settings: ReductionSettings
    metadata: ReductionRecord | None = None  # None for a model not built by :func:`reduce`
    report: ErrorReport | None = None
    output_names: tuple[str, ...] = OUTPUTS

    @property
    def n_inputs(self) -> int:
        return self.b.shape[1]

    @property
    def n_states(self) -> int:
        """Real states: 2 per complex mode, 1 per real one."""
        return int(np.sum(np.where(self.eigenvalues.imag != 0, 2, 1)))

    @property
    def n_modes(self) -> int:
        return self.eigenvalues.size

    def frequency_response(self, r: np.ndarray, omega: np.ndarray) -> np.ndarray:
        """Y(ω) (n_outputs, n_freqs) for internal input vectors r(ω) (n_inputs, n_freqs)."""
        return modal_frequency_response(self.eigenvalues, self.b, self.c, self.d, self.e, r, omega)

    def physical_frequency_response(self, name: str, freqs_hz) -> np.ndarray:
        """FRF for a unit harmonic of a physical input, "rim" or "road" (at the zone front)."""
        omega = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
        return self.frequency_response(physical_input(name, self.road_windows, omega), omega)

    def real_form(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Real block-diagonal (A, B, C, D, E): [[σ, -ω], [ω, σ]] per complex mode."""
        return real_block_form(self.eigenvalues, self.b, self.c, self.d, self.e)

    def summary(self) -> dict:
        return {
            "method": self.settings.method,
            "settings": asdict(self.settings),
            "n_states": self.n_states,
            "n_modes": self.n_modes,
            "n_inputs": self.n_inputs,
            "report": self.report.to_dict() if self.report else None,
            **(self.metadata.to_dict() if self.metadata else {}),
        }


#: A class whose input coupling is below this fraction of the model's is uncontrollable.
UNCONTROLLABLE = 1e-12


def _is_number(value) -> bool:
    return (isinstance(value, (int, float, np.integer, np.floating))
            and not isinstance(value, bool) and bool(np.isfinite(value)))


def modal_decomposition(io: InputOutputModel) -> ModalForm:
    """The controllable modes of the full first-order model, one member per conjugate pair.

    At rest the damping is proportional, so a symmetric eigenproblem of half the size gives
    the modes; the model is also mirror-symmetric about the patch centre, so that problem
    splits into a symmetric and an antisymmetric class, and a class the inputs do not reach
    (the antisymmetric one: rim and a resting road push symmetrically) is left out, which
    changes no transfer function; within a class the lumped sidewall is eliminated exactly
    (:func:`~tire_fmu.core.modal.two_level_eigenpairs`), halving the problem again. Rolling
    needs the general (dense LAPACK) eigenproblem, and so does a tied sidewall, whose tie
    carries no damping.
    """
    model = io.model
    # a mode of zero frequency, or one exactly critically damped, divides by zero: checked
    # below, with a message, rather than warned about here
    with np.errstate(divide="ignore", invalid="ignore"):
        # the sidewall's tie (sidewall_max_order) has no damper: C is then not αM + βK
        if model.speed_m_s == 0.0 and not model.sidewall_tied:
            decomp = _resting_decomposition(io)
        else:
            decomp = diagonalise(io.a.toarray(), io.b, io.c)
    check_resolved(decomp.eigenvalues, model)
    if not (np.all(np.isfinite(decomp.b)) and np.all(np.isfinite(decomp.c))):
        from .parameters import ParameterError, Problem

        raise ParameterError([Problem(
            "beta", model.tire.beta, "s", "another value (or alpha another)",
            "a mode is critically damped to the last bit, and its two eigenvalues coincide: "
            "the modal form does not exist")])
    return decomp


def _resting_decomposition(io: InputOutputModel) -> ModalForm:
    """The resting tire's modes, class by class of the mirror symmetry."""
    from .modal import symmetry_bases, two_level_eigenpairs

    model = io.model
    mass = model.mass.diagonal()
    bases = list(symmetry_bases(model.grid).values())
    stiffness = model.stiffness
    coupling = (bases[0].T @ stiffness @ bases[1]).tocoo().data
    if np.abs(coupling).max(initial=0.0) > 1e-12 * np.abs(stiffness.data).max():
        bases = [None]  # not mirror-symmetric: one problem on every DOF
    scale = max(np.abs(io.b_disp).max(), np.abs(io.b_vel).max())
    forms = []
    for basis in bases:
        if basis is None:
            k, m, b_disp, b_vel = stiffness, mass, io.b_disp, io.b_vel
            out_disp, out_vel = io.out_disp, io.out_vel
        else:
            b_disp, b_vel = basis.T @ io.b_disp, basis.T @ io.b_vel
            if max(np.abs(b_disp).max(), np.abs(b_vel).max()) <= UNCONTROLLABLE * scale:
                continue
            k = (basis.T @ stiffness @ basis).tocsr()
            m = basis.multiply(basis).T @ mass  # BᵀMB is diagonal: mirror nodes share a mass
            out_disp, out_vel = io.out_disp @ basis, io.out_vel @ basis
        pairs = two_level_eigenpairs(k, m, k.shape[0]) if basis is not None else None
        forms.append(diagonalise_proportional(k, m, model.tire.alpha, model.tire.beta,
                                              b_disp, b_vel, out_disp, out_vel, pairs))
    values = np.concatenate([f.eigenvalues for f in forms])
    order = np.argsort(np.abs(values), kind="stable")
    return ModalForm(eigenvalues=values[order],
                     b=np.vstack([f.b for f in forms])[order],
                     c=np.hstack([f.c for f in forms])[:, order])


def relative_contributions(decomp: ModalForm, io: InputOutputModel,
                           settings: ReductionSettings, full: dict) -> np.ndarray:
    """Each mode's term relative to the full response: term(ω) / |H_full(ω)|, complex.

    Shape (pairs, modes, frequencies) over every input/output pair in ``full`` and the error
    band. The mode's term is taken without its static part when the static correction will
    restore it, and relative to the full response frequency by frequency, so a mode that
    matters only in an anti-resonance dip still counts. The relative FRF error of dropping a
    set of modes is the magnitude of the sum of their rows.
    """
    omega = 2 * np.pi * settings.error_frequencies_hz()
    lam = decomp.eigenvalues[:, None]
    iw = 1j * omega[None, :]
    dyn = 1.0 / (iw - lam)
    dyn_partner = 1.0 / (iw - np.conj(lam))
    if settings.static_correction:
        dyn = dyn + 1.0 / lam
        dyn_partner = dyn_partner + 1.0 / np.conj(lam)
    forced = {}
    rows = np.empty((len(full), lam.shape[0], omega.size), dtype=complex)
    for k, ((name, row), h_full) in enumerate(full.items()):
        if name not in forced:
            r = physical_input(name, io.road_windows, omega)
            forced[name] = ((decomp.b @ r) * dyn, (np.conj(decomp.b) @ r) * dyn_partner)
        own, partner = forced[name]
        c = decomp.c[row][:, None]
        # where the full response is exactly zero a relative contribution means nothing
        scale = np.where(np.abs(h_full) > 0.0, np.abs(h_full), np.inf)
        rows[k] = 0.5 * (c * own + np.conj(c) * partner) / scale[None, :]
    return rows


#: A response below this fraction of the largest force response is zero by symmetry.
ZERO_RESPONSE = 1e-8


def _physical_inputs(io: InputOutputModel) -> tuple[str, ...]:
    return tuple(name for name in PHYSICAL_INPUTS if not (name == "road" and io.n_inputs == 1))


def exact_frequency_responses(io: InputOutputModel, freqs_hz) -> dict[str, np.ndarray]:
    """Every physical input's FRF (n_outputs, n_freqs) from the assembled second-order model:
    one factorisation per frequency shared by the inputs,
    (K - ω²M + iωD) U = (B_z + iωB_v) R, Y = (C_u + iωC_v) U + (D_u + iωE) R."""
    import scipy.sparse.linalg as spla

    names = _physical_inputs(io)
    omega = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
    r_all = np.stack([io.physical_input(name, omega) for name in names])  # (inputs, r, freqs)
    m, d, k = io.model.mass, io.model.damping, io.model.stiffness
    out = np.empty((len(names), len(io.output_names), omega.size), dtype=complex)
    for i, w in enumerate(omega):
        r = r_all[:, :, i].T  # (r, inputs)
        u = spla.splu((k - w * w * m + 1j * w * d).tocsc()).solve(
            (io.b_disp + 1j * w * io.b_vel) @ r)
        out[:, :, i] = ((io.out_disp + 1j * w * io.out_vel) @ u
                        + (io.d_disp + 1j * w * io.e) @ r).T
    return dict(zip(names, out))


def modal_frequency_responses(io: InputOutputModel, decomp: ModalForm,
                              freqs_hz) -> dict[str, np.ndarray]:
    """The same FRFs from the full model's modal decomposition (no solve per frequency)."""
    omega = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
    return {name: modal_frequency_response(decomp.eigenvalues, decomp.b, decomp.c, io.d, io.e,
                                           io.physical_input(name, omega), omega)
            for name in _physical_inputs(io)}


def full_responses(io: InputOutputModel, freqs_hz,
                   decomp: ModalForm | None = None) -> dict[tuple[str, int], np.ndarray]:
    """Full-model FRFs keyed by (physical input, output row), leaving out the responses that
    vanish by symmetry (rim_Fx at rest), where a relative error means nothing.

    From ``decomp`` (the full model's complete modal decomposition) when given, else exact.
    """
    by_input = (exact_frequency_responses(io, freqs_hz) if decomp is None
                else modal_frequency_responses(io, decomp, freqs_hz))
    out = {(name, row): h[row] for name, h in by_input.items() for row in range(len(OUTPUTS))}
    forces = [np.abs(h).max() for (_, row), h in out.items() if OUTPUTS[row] != "deflection"]
    floor = ZERO_RESPONSE * max(forces)
    return {key: h for key, h in out.items()
            if OUTPUTS[key[1]] == "deflection" or np.abs(h).max() > floor}


def _relative_errors(eigenvalues, b, c, d, e, windows, full: dict,
                     freqs_hz) -> tuple[float, dict[str, float]]:
    """Largest relative FRF error of a diagonal model against ``full``, and per pair."""
    omega = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
    per_pair = {}
    for name in dict.fromkeys(key[0] for key in full):
        h = modal_frequency_response(eigenvalues, b, c, d, e,
                                     physical_input(name, windows, omega), omega)
        for (input_name, row), h_full in full.items():
            if input_name == name:
                per_pair[f"{name}->{OUTPUTS[row]}"] = float(
                    np.max(np.abs(h[row] - h_full) / np.abs(h_full)))
    return (max(per_pair.values()) if per_pair else 0.0), per_pair


def kept_static_gain(eigenvalues, b, c) -> np.ndarray | float:
    """DC gain of the modes' dynamic part, Re(-C Λ⁻¹ B)."""
    return np.real(-(c / eigenvalues[None, :]) @ b) if eigenvalues.size else 0.0


def error_report(reduced: ReducedModel, io: InputOutputModel, full: dict | None = None,
                 static_gain: np.ndarray | None = None) -> ErrorReport:
    """Maximum relative FRF error of ``reduced`` against the full model over the band.

    Without ``full`` the full model's responses are computed exactly (the check on demand);
    :func:`reduce` passes the ones from its modal decomposition.
    """
    freqs = reduced.settings.error_frequencies_hz()
    reference = "exact" if full is None else "modal"
    full = full if full is not None else full_responses(io, freqs)
    worst, per_pair = _relative_errors(reduced.eigenvalues, reduced.b, reduced.c, reduced.d,
                                       reduced.e, reduced.road_windows, full, freqs)
    dc_full = io.static_gain() if static_gain is None else static_gain
    dc_red = reduced.d + kept_static_gain(reduced.eigenvalues, reduced.b, reduced.c)
    dc_rel = {}
    for row, out_name in enumerate(OUTPUTS):
        ref = np.abs(dc_full[row]).max()
        if ref > 0 and ref > 1e-9 * np.abs(dc_full).max():
            dc_rel[out_name] = float(np.abs(dc_red[row] - dc_full[row]).max() / ref)
    return ErrorReport(tuple(reduced.settings.error_band_hz), worst, per_pair, dc_rel,
                       reference)


def static_correction_matrix(io: InputOutputModel, eigenvalues, b, c,
                             static_gain: np.ndarray | None = None) -> np.ndarray:
    """Feedthrough that restores the exact DC gain: full DC minus the kept modes' DC."""
    dc = io.static_gain() if static_gain is None else static_gain
    return dc - io.d - kept_static_gain(eigenvalues, b, c)


def static_outputs(model: TireModel) -> dict[str, float]:
    """Output values at the static equilibrium the deviations are measured from."""
    return model.patch.static_outputs()


@blas_threads()  # small dense problems: see core.blas_threads
def reduce(model: TireModel, settings: ReductionSettings | None = None,
           report: bool | str = True) -> ReducedModel:
    """Reduce the tire at its operating point.

    ``report``: True adds the FRF error against the full model over
    ``settings.error_band_hz``, from the full model's modal decomposition (which the
    reduction needs anyway); "exact" checks against the assembled model solved at every
    frequency instead (slower; the reduction itself is the same); False leaves it out.
    """
    if report not in (True, False, "exact"):
        raise ValueError(f"report = {report!r}: must be True, False or 'exact'")
    settings = settings or ReductionSettings()
    started = time.perf_counter()
    io = build_io_model(model)
    freqs = settings.error_frequencies_hz()
    decomp = modal_decomposition(io)
    full = full_responses(io, freqs, decomp)
    dc = io.static_gain()
    if settings.method == "modal":
        lam, b, c = _select_modes(decomp, io, settings, full)
        d = io.d + (static_correction_matrix(io, lam, b, c, dc)
                    if settings.static_correction else 0)
    else:
        lam, b, c, d = _balanced(decomp, io, settings, full, dc)
    reduced = ReducedModel(
        eigenvalues=lam, b=b, c=c, d=np.asarray(d, dtype=float), e=io.e.copy(),
        road_windows=io.road_windows, static_outputs=static_outputs(model),
        settings=settings,
    )
    quality = None
    if report:
        quality = error_report(reduced, io, None if report == "exact" else full, dc)
    record = ReductionRecord(
        tire=model.tire,
        operating_point=OperatingPointRecord.from_summary(model.summary()),
        full_states=io.n_states,
        build_seconds=time.perf_counter() - started,
    )
    return replace(reduced, metadata=record, report=quality)


#: Orders below the bisection's answer that the balanced order search also tries.
ORDER_SEARCH_WINDOW = 8


def _balanced(decomp: ModalForm, io: InputOutputModel, settings: ReductionSettings, full: dict,
              dc: np.ndarray):
    """Balanced truncation of every mode up to f_max (the rest static) to ``n_states``, or to
    the fewest states whose FRF error over the band meets ``target_error`` (bisection: the
    error falls as states are added; each trial costs one small FRF, no report)."""
    from .balanced import BalancedRealization

    keep = ~settings.above_f_max(decomp.eigenvalues)
    lam, b, c = decomp.eigenvalues[keep], decomp.b[keep], decomp.c[:, keep]
    d = io.d + static_correction_matrix(io, lam, b, c, dc)
    # Each output weighted by the inverse of its peak; outputs that vanish by symmetry
    # (absent from ``full``) get no weight, so rounding noise is never balanced.
    peak = np.zeros(len(OUTPUTS))
    for (_, row), response in full.items():
        peak[row] = max(peak[row], np.abs(response).max())
    weight = np.divide(1.0, peak, out=np.zeros_like(peak), where=peak > 0)
    realization = BalancedRealization(lam, b, c, d, weight, settings.static_correction)
    if settings.n_states is not None:
        return realization.truncate(settings.n_states)
    freqs = settings.error_frequencies_hz()

    def error(k):
        lam_k, b_k, c_k, d_k = realization.truncate(k)
        return _relative_errors(lam_k, b_k, c_k, d_k, io.e, io.road_windows, full, freqs)[0]

    # Bisection; when no order below the realisation's own meets the target it ends there,
    # untested, and the report says the target was missed. The error is not quite monotone
    # (lightly damped modes give near-equal Hankel singular values in pairs, and cutting
    # between the two members costs more than cutting after both), so the orders just below
    # the bisection's answer are tried too.
    low, high = 1, realization.order
    while low < high:
        middle = (low + high) // 2
        if error(middle) <= settings.target_error:
            high = middle
        else:
            low = middle + 1
    if high < realization.order:
        for k in range(max(1, high - ORDER_SEARCH_WINDOW), high):
            if error(k) <= settings.target_error:
                high = k
                break
    return realization.truncate(high)


#: Candidate modes whose drop errors are evaluated together (bounds the work array to
#: about 64 MB at 400 frequencies and 8 input/output pairs).
CANDIDATE_CHUNK = 1024


def _drop_errors(residual: np.ndarray, shares: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Max relative FRF error left if each candidate mode were dropped on top of the modes whose
    summed terms are ``residual`` (pairs, frequencies): max |residual + share_k|, exact."""
    out = np.empty(candidates.size)
    for start in range(0, candidates.size, CANDIDATE_CHUNK):
        chunk = candidates[start:start + CANDIDATE_CHUNK]
        out[start:start + chunk.size] = np.abs(
            residual[:, None, :] + shares[:, chunk, :]).max(axis=(0, 2))
    return out


def _run_errors(residual: np.ndarray, shares: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Max relative FRF error left by dropping the first 1, 2, ... modes of ``order`` on top
    of ``residual``: one running sum, exact."""
    out = np.empty(order.size)
    running = residual
    for start in range(0, order.size, CANDIDATE_CHUNK):
        chunk = order[start:start + CANDIDATE_CHUNK]
        sums = running[:, None, :] + np.cumsum(shares[:, chunk, :], axis=1)
        out[start:start + chunk.size] = np.abs(sums).max(axis=(0, 2))
        running = sums[:, -1, :]
    return out


def _select_modes(decomp: ModalForm, io, settings: ReductionSettings, full):
    """Modes to keep (see :func:`select_by_shares`), as (eigenvalues, B, C)."""
    shares = relative_contributions(decomp, io, settings, full)
    above = settings.above_f_max(decomp.eigenvalues)
    cut = float(np.abs(shares[:, above, :].sum(axis=1)).max(initial=0.0))
    if cut > settings.target_error:
        warnings.warn(
            f"the frequency cut at {settings.f_max_hz:g} Hz drops modes that alone leave a "
            f"relative FRF error up to {cut:.3g} over {settings.error_band_hz[0]:g}-"
            f"{settings.error_band_hz[1]:g} Hz (target_error {settings.target_error:g}); "
            "raise the cut or remove it (the stiff contact-patch modes near 1 kHz matter most)",
            ReductionWarning,
            stacklevel=3,
        )
    kept = select_by_shares(shares, above, settings.target_error, settings.n_modes)
    kept = kept[np.argsort(np.abs(decomp.eigenvalues[kept]), kind="stable")]
    return decomp.eigenvalues[kept], decomp.b[kept], decomp.c[:, kept]


def select_by_shares(shares: np.ndarray, dropped_first: np.ndarray, target_error: float,
                     n_modes: int | None = None) -> np.ndarray:
    """Indices of the modes to keep: the fewest found whose drop leaves a relative FRF error
    of at most ``target_error``; then at most ``n_modes`` of them, the most dominant first.

    ``shares`` (pairs, modes, frequencies) are the modes' terms relative to the full response
    (:func:`relative_contributions`): the reduced model's response is the full one less the
    dropped modes' terms (without their static part when the static correction restores
    it), so the relative error of dropping a set is max over pairs and frequencies of |the
    sum of its shares|, exactly the number the report computes. No bound is used: at speed
    the terms of a split pair are individually large and cancel, and the sum of their
    magnitudes over-states the error tenfold.

    The modes flagged in ``dropped_first`` (those above f_max) go first. The others are
    ranked by dominance, the error their drop alone would leave (max |share|); the longest
    run of least dominant modes whose drop meets the target goes (one running sum gives the
    error of every run), then, one at a time, the kept mode whose drop leaves the least
    error, while the target holds. So every mode kept (below f_max, before the ``n_modes``
    cap) breaks the target when dropped on top of the others.
    """
    residual = shares[:, dropped_first, :].sum(axis=1)
    candidates = np.flatnonzero(~dropped_first)
    dominance = np.abs(shares).max(axis=(0, 2))
    order = candidates[np.argsort(dominance[candidates], kind="stable")]
    meeting = np.flatnonzero(_run_errors(residual, shares, order) <= target_error)
    dropped = meeting[-1] + 1 if meeting.size else 0  # the error is not monotone in the run
    residual = residual + shares[:, order[:dropped], :].sum(axis=1)
    kept = order[dropped:]
    while kept.size:
        errors = _drop_errors(residual, shares, kept)
        best = int(np.argmin(errors))
        if errors[best] > target_error:
            break
        residual = residual + shares[:, kept[best], :]
        kept = np.delete(kept, best)
    if n_modes is not None and kept.size > n_modes:
        kept = kept[np.argsort(dominance[kept], kind="stable")][-n_modes:]
    return kept
