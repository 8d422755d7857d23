"""Reduced-order models of the tire: modal truncation (with static correction) or balanced
truncation, always delivered in diagonal modal form with an accuracy report.

Modal form: the first-order model ẋ = A x + B r is diagonalised, A = V Λ V⁻¹, q = V⁻¹ x. Of
each complex-conjugate pair only the member with Im λ > 0 is kept: for real inputs its partner
is its conjugate, so the pair's output is 2·Re(c q). The reduced model is therefore

    q̇ = Λ q + B_q r,     y = Re(C_q q) + D r + E ṙ,

with C_q already carrying that factor 2 (1 for real eigenvalues). It works unchanged for the
rolling (gyroscopic, non-symmetric) model.

Which modes to keep, in terms a user can reason about (:class:`ReductionSettings`):
- ``f_max_hz``: modes whose natural frequency |λ|/2π is at most this (default: no cut;
  modes far above the band still shape it, the contact patch's stiff modes most of all, and
  the budget below already drops what does not matter);
- ``contribution_threshold``: of those, the least contributing modes are dropped as long as
  the sum of their contributions, each relative to the full response frequency by frequency
  over the error band, stays within the threshold: a bound on the relative FRF error they
  leave (the dense sidewall band near 160-168 Hz barely moves the rim and drops out here);
- ``n_modes``: at most this many, the largest contributions first;
- ``static_correction``: add the dropped modes' static (DC) response as a feedthrough, so the
  DC gain is exact (python-control calls this 'matchdc').
``method="balanced"`` instead balances a generous modal pre-reduction and truncates it to
``n_states`` states (see :mod:`tire_fmu.core.balanced`).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import asdict, dataclass

import numpy as np

from .io_model import OUTPUTS, PHYSICAL_INPUTS, InputOutputModel, build_io_model, physical_input
from .modal_form import (
    ModalForm,
    diagonalise,
    diagonalise_proportional,
    modal_frequency_response,
    real_block_form,
)
from .model import TireModel

METHODS = ("modal", "balanced")


class ReductionWarning(UserWarning):
    """The reduction settings leave more error than they were asked to."""


@dataclass(frozen=True)
class ReductionSettings:
    """How to reduce; see the module docstring. Frequencies in Hz."""

    method: str = "modal"
    f_max_hz: float | None = None  # None: no frequency cut, the contribution budget decides
    contribution_threshold: float = 5e-3
    n_modes: int | None = None
    static_correction: bool = True
    n_states: int | None = None  # balanced: states kept (None: fewest meeting target_error)
    target_error: float = 5e-3  # balanced with n_states None: max relative FRF error allowed
    error_band_hz: tuple[float, float] = (1.0, 300.0)
    error_points: int = 400

    def __post_init__(self) -> None:
        from .parameters import ParameterError, Problem

        problems = []
        if self.method not in METHODS:
            problems.append(Problem("method", self.method, "", f"one of {', '.join(METHODS)}"))
        if self.f_max_hz is not None and not (
            _is_number(self.f_max_hz) and 0 < self.f_max_hz <= 1e7
        ):
            problems.append(Problem("f_max_hz", self.f_max_hz, "Hz", "in (0, 1e7] Hz",
                                    "the highest natural frequency kept", unset=True))
        if not (_is_number(self.contribution_threshold)
                and 0 <= self.contribution_threshold < 1):
            problems.append(Problem("contribution_threshold", self.contribution_threshold, "",
                                    "in [0, 1)"))
        for name in ("n_modes", "n_states"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int)
                                      or not 1 <= value <= 100_000):
                problems.append(Problem(name, value, "", "an integer in [1, 100000]",
                                        unset=True))
        band = self.error_band_hz
        if not (isinstance(band, (tuple, list)) and len(band) == 2 and all(map(_is_number, band))
                and 0 <= band[0] < band[1]):
            problems.append(Problem("error_band_hz", band, "Hz",
                                    "(low, high) with 0 <= low < high"))
        if not (_is_number(self.target_error) and 0 < self.target_error < 1):
            problems.append(Problem("target_error", self.target_error, "", "in (0, 1)"))
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
    """Accuracy of a reduced model against the full model over a band."""

    band_hz: tuple[float, float]
    max_relative_error: float  # over every input/output pair with a non-zero response
    per_pair: dict[str, float]  # "road->rim_Fz": max_ω |H_red - H_full| / |H_full|
    dc_relative_error: dict[str, float]

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True, eq=False)
class ReducedModel:
    """A reduced tire model in diagonal modal form, with what it came from and how good it is.

    Inputs r = [rim_z, road_z at each patch node] (road nodes delayed by ``input_delays_s``),
    their velocities ṙ feed only the direct term E. Outputs: rim_Fz, rim_Fx, contact_Fz,
    deflection (deviations from the static values in ``static_outputs``).
    """

    eigenvalues: np.ndarray  # (k,) complex
    b: np.ndarray  # (k, n_inputs) complex
    c: np.ndarray  # (n_outputs, k) complex, pair factor 2 included
    d: np.ndarray  # (n_outputs, n_inputs) real
    e: np.ndarray  # (n_outputs, n_inputs) real, on ṙ
    input_delays_s: np.ndarray
    static_outputs: dict[str, float]
    settings: ReductionSettings
    metadata: dict  # tire data, operating point, states kept, timing
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
        """FRF for a unit harmonic of a physical input, "rim" or "road" (leading edge)."""
        omega = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
        return self.frequency_response(physical_input(name, self.input_delays_s, omega), omega)

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
            **self.metadata,
        }




def _is_number(value) -> bool:
    return (isinstance(value, (int, float, np.integer, np.floating))
            and not isinstance(value, bool) and bool(np.isfinite(value)))


def modal_decomposition(io: InputOutputModel) -> ModalForm:
    """Every mode of the full first-order model, one member per conjugate pair.

    At rest the damping is proportional and a symmetric eigenproblem of half the size gives
    the same modes several times faster; rolling needs the general (dense LAPACK) one.
    """
    model = io.model
    # a mode of zero frequency, or one exactly critically damped, divides by zero: checked
    # below, with a message, rather than warned about here
    with np.errstate(divide="ignore", invalid="ignore"):
        if model.speed_m_s == 0.0:
            decomp = diagonalise_proportional(
                model.stiffness, model.mass.diagonal(), model.tire.alpha, model.tire.beta,
                io.b_disp, io.b_vel, io.out_disp, io.out_vel,
            )
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


#: The fastest eigenvalue of a model over its slowest may be at most this: the slowest modes'
#: relative error grows as the rounding unit times this ratio (about 2e-6 at the limit), and
#: near 1e14 they are lost altogether and the outputs turn to nan.
MAX_EIGENVALUE_SPREAD = 1e10


def check_resolved(eigenvalues: np.ndarray, model: TireModel) -> None:
    """Raise ParameterError unless double precision resolves every mode of ``model``.

    The problem names the mass whose light node, against its springs, makes the fastest
    modes: in the model these go as the stiffness-to-mass ratios, and with stiffness-
    proportional damping as beta times them.
    """
    from .parameters import TIRE_FIELDS, ParameterError, Problem

    TIRE_UNITS = {name: spec.unit for name, spec in TIRE_FIELDS.items()}  # noqa: N806
    magnitude = np.abs(eigenvalues)
    if magnitude.size == 0:
        return
    slow, fast = float(magnitude.min()), float(magnitude.max())
    if np.all(np.isfinite(magnitude)) and fast <= MAX_EIGENVALUE_SPREAD * slow:
        return
    tire = model.tire
    step = 2 * np.pi / model.n_elements  # the mesh's shortest wavelength spans two nodes
    ratios = {  # (field to change, which way, the fast modes): stiffness over mass, 1/s^2
        ("m_s", "larger", "the sidewall masses on k_r1 + k_r2"):
            (tire.k_r1 + tire.k_r2) / tire.m_s,
        ("rhoA", "larger", "the tread nodes on k_r1 + k_cw"): (tire.k_r1 + tire.k_cw) / tire.rhoA,
        ("EI", "smaller", "the tread's bending at the mesh's shortest wavelength (fewer "
                          "n_elements lengthen it)"):
            tire.EI * 16 / (step * tire.R) ** 4 / tire.rhoA,
    }
    (field, way, what), ratio = max(ratios.items(), key=lambda item: item[1])
    spread = f"{fast / slow:.2g}" if slow > 0 and np.isfinite(fast) else "beyond 1e16"
    raise ParameterError([Problem(
        field, getattr(tire, field), TIRE_UNITS[field],
        f"{way} here, or beta smaller: the model's eigenvalues span {spread} (fastest over "
        f"slowest) and may span at most {MAX_EIGENVALUE_SPREAD:g}",
        f"beyond that double precision loses the slowest modes; the fastest here are {what}, "
        f"stiffness over mass {ratio:.3g} 1/s^2, with beta = {tire.beta:g} s")])


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
            r = physical_input(name, io.input_delays_s, omega)
            forced[name] = ((decomp.b @ r) * dyn, (np.conj(decomp.b) @ r) * dyn_partner)
        own, partner = forced[name]
        c = decomp.c[row][:, None]
        # where the full response is exactly zero a relative contribution means nothing
        scale = np.where(np.abs(h_full) > 0.0, np.abs(h_full), np.inf)
        rows[k] = 0.5 * (c * own + np.conj(c) * partner) / scale[None, :]
    return rows


def _relative_errors(full: dict, reduced: dict) -> tuple[float, dict[str, float]]:
    per_pair = {}
    for (name, row), h_full in full.items():
        h_red = reduced[(name, row)]
        per_pair[f"{name}->{OUTPUTS[row]}"] = float(np.max(np.abs(h_red - h_full) / np.abs(h_full)))
    return (max(per_pair.values()) if per_pair else 0.0), per_pair


#: A response below this fraction of the largest force response is zero by symmetry.
ZERO_RESPONSE = 1e-8


def full_responses(io: InputOutputModel, freqs_hz) -> dict[tuple[str, int], np.ndarray]:
    """Full-model FRFs keyed by (physical input, output row), leaving out the responses that
    vanish by symmetry (rim_Fx at rest), where a relative error means nothing."""
    out = {}
    for name in PHYSICAL_INPUTS:
        if name == "road" and io.n_inputs == 1:
            continue  # no patch, no road input
        h = io.frequency_response(name, freqs_hz)
        for row in range(len(OUTPUTS)):
            out[(name, row)] = h[row]
    forces = [np.abs(h).max() for (_, row), h in out.items() if OUTPUTS[row] != "deflection"]
    floor = ZERO_RESPONSE * max(forces)
    return {key: h for key, h in out.items()
            if OUTPUTS[key[1]] == "deflection" or np.abs(h).max() > floor}


def error_report(reduced: ReducedModel, io: InputOutputModel,
                 full: dict | None = None) -> ErrorReport:
    """Maximum relative FRF error of ``reduced`` against the full model over the band."""
    freqs = reduced.settings.error_frequencies_hz()
    full = full if full is not None else full_responses(io, freqs)
    red = {}
    for name in {k[0] for k in full}:
        h = reduced.physical_frequency_response(name, freqs)
        for row in range(len(OUTPUTS)):
            red[(name, row)] = h[row]
    worst, per_pair = _relative_errors(full, red)
    dc_full = io.static_gain()
    dc_red = reduced.d + np.real(-(reduced.c / reduced.eigenvalues[None, :]) @ reduced.b)
    dc_rel = {}
    for row, out_name in enumerate(OUTPUTS):
        ref = np.abs(dc_full[row]).max()
        if ref > 0 and ref > 1e-9 * np.abs(dc_full).max():
            dc_rel[out_name] = float(np.abs(dc_red[row] - dc_full[row]).max() / ref)
    return ErrorReport(tuple(reduced.settings.error_band_hz), worst, per_pair, dc_rel)


def static_correction_matrix(io: InputOutputModel, eigenvalues, b, c) -> np.ndarray:
    """Feedthrough that restores the exact DC gain: full DC minus the kept modes' DC."""
    kept_dc = np.real(-(c / eigenvalues[None, :]) @ b) if eigenvalues.size else 0.0
    return io.static_gain() - io.d - kept_dc


def static_outputs(model: TireModel) -> dict[str, float]:
    """Output values at the static equilibrium the deviations are measured from."""
    t, s = model.translation, model.horizontal
    z_rim = -model.patch.deflection_m  # rim below its unloaded height, road at 0
    k_s = model.structure.stiffness
    if model.patch.in_contact:
        import scipy.sparse.linalg as spla

        u = spla.splu(model.stiffness.tocsc()).solve(k_s @ (t * z_rim))
    else:
        u = t * z_rim
    internal = k_s @ (u - t * z_rim)
    contact = -(t @ (model.contact_stiffness @ u))
    return {
        "rim_Fz": float(t @ internal),
        "rim_Fx": float(s @ internal),
        "contact_Fz": float(contact),
        # the model's own compression of the tread at the patch centre, as the dynamic output
        # measures it: the chord deflection less the contact spring's small give
        "deflection": float(-(u[0] - t[0] * z_rim)),
    }


def reduce(model: TireModel, settings: ReductionSettings | None = None,
           report: bool = True) -> ReducedModel:
    """Reduce the tire at its operating point; ``report`` adds the FRF error against the full
    model over ``settings.error_band_hz``."""
    settings = settings or ReductionSettings()
    started = time.perf_counter()
    io = build_io_model(model)
    freqs = settings.error_frequencies_hz()
    full = full_responses(io, freqs)
    decomp = modal_decomposition(io)
    if settings.method == "modal":
        lam, b, c = _select_modes(decomp, io, settings, full)
        d = io.d + (static_correction_matrix(io, lam, b, c) if settings.static_correction else 0)
    else:
        lam, b, c, d = _balanced(decomp, io, settings, full, model)
    metadata = {
        "tire": model.tire.as_dict(),
        "operating_point": model.summary(),
        "full_states": io.n_states,
        "build_seconds": None,
    }
    reduced = ReducedModel(
        eigenvalues=lam, b=b, c=c, d=np.asarray(d, dtype=float), e=io.e.copy(),
        input_delays_s=io.input_delays_s.copy(), static_outputs=static_outputs(model),
        settings=settings, metadata=metadata,
    )
    if report:
        reduced = _with_report(reduced, error_report(reduced, io, full))
    reduced.metadata["build_seconds"] = time.perf_counter() - started
    return reduced


def _balanced(decomp, io, settings: ReductionSettings, full, model):
    """Balanced truncation to ``n_states``, or to the fewest states whose FRF error over the
    band meets ``target_error`` (bisection: the error falls as states are added)."""
    from .balanced import BalancedRealization

    realization = BalancedRealization(decomp, io, settings, full)
    if settings.n_states is not None:
        return realization.truncate(settings.n_states)

    def error(k):
        lam, b, c, d = realization.truncate(k)
        trial = ReducedModel(lam, b, c, np.asarray(d, float), io.e, io.input_delays_s, {},
                             settings, {})
        return error_report(trial, io, full).max_relative_error

    low, high = 1, realization.order
    if error(high) > settings.target_error:
        return realization.truncate(high)  # the report will say the target was missed
    while low < high:
        middle = (low + high) // 2
        if error(middle) <= settings.target_error:
            high = middle
        else:
            low = middle + 1
    return realization.truncate(high)


def _with_report(reduced: ReducedModel, report: ErrorReport) -> ReducedModel:
    from dataclasses import replace

    return replace(reduced, report=report)


def _select_modes(decomp: ModalForm, io, settings: ReductionSettings, full):
    """Modes to keep: drop those above f_max, then the least contributing ones while a bound
    on the relative FRF error left behind stays within ``contribution_threshold``; finally
    cap at ``n_modes``, largest contributions first.

    The bound is |Σ above-f_max terms| (summed coherently: they are known exactly) plus
    Σ |dropped in-band terms| (triangle inequality), the worst over frequencies and pairs.
    """
    lam = decomp.eigenvalues
    shares = relative_contributions(decomp, io, settings, full)
    magnitude = np.abs(shares)
    score = magnitude.max(axis=(0, 2))
    above = settings.above_f_max(lam)
    cut = np.abs(shares[:, above, :].sum(axis=1))
    if cut.size and cut.max() > settings.contribution_threshold:
        warnings.warn(
            f"the frequency cut at {settings.f_max_hz:g} Hz drops modes that alone leave a "
            f"relative FRF error up to {cut.max():.3g} over {settings.error_band_hz[0]:g}-"
            f"{settings.error_band_hz[1]:g} Hz (budget {settings.contribution_threshold:g}); "
            "raise the cut or remove it (the stiff contact-patch modes near 1 kHz matter most)",
            ReductionWarning,
            stacklevel=3,
        )
    candidates = np.flatnonzero(~above)
    order = candidates[np.argsort(score[candidates], kind="stable")]
    bound = (cut[:, None, :] + np.cumsum(magnitude[:, order, :], axis=1)).max(axis=(0, 2))
    droppable = int(np.searchsorted(bound, settings.contribution_threshold, side="right"))
    kept = order[droppable:]
    if settings.n_modes is not None:
        kept = kept[::-1][: settings.n_modes]
    kept = kept[np.argsort(np.abs(lam[kept]), kind="stable")]
    return lam[kept], decomp.b[kept], decomp.c[:, kept]
