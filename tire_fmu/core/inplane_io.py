"""The in-plane tire at an operating point as a linear input/output system, and its balanced
reduction: the in-plane ring's counterpart of :mod:`.io_model` and :mod:`.reduction`.

**The linearisation.** :func:`.inplane_rolling_modes.rolling_system` freezes the contact,
stick and sliding sets of the steady rolling (at rest: of the static footprint, every element
sticking) and gives ẋ = A x + B₀ u + B₁ u̇ + B₂ ü about it, x = [y_ring, ẏ, e_stick], u =
[torque, rim_x, rim_z, the road under each contact point] as deviations. The rim's forces are
its rows of the tire's forces, -(K y + C ẏ + M ÿ) with ÿ from the same equation, and the
inertia of the rim's translation: y = C x + D₀ u + D₁ u̇ + D₂ ü. The input's derivatives
leave the state equation by the state z = x - B₂ u̇ - (B₁ + A B₂) u, which is exact:

    ż = A z + (B₀ + A B₁ + A² B₂) u,
    y = C z + (D₀ + C (B₁ + A B₂)) u + (D₁ + C B₂) u̇ + D₂ ü.

So the model a host steps takes the inputs with their first and second derivatives, and the
outputs hold them only in feedthroughs (the rim's acceleration moves the tire's mass with it;
a damper passes the rim's velocity straight to its force).

**The road.** Each point reads the road's mean over its own window of road (the simulator's
:meth:`.inplane_contact.InPlaneSimulator.road`); the road travels back at V, so a point reads
the road at the contact zone's front (where an FMU measures it) late by the time the road
takes from there to its window: per point a moving average, (e^{-iωτ₁} - e^{-iωτ₂}) /
(iω(τ₂ - τ₁)) for the window's ends τ₁ < τ₂ behind the front. At rest the road is a plate
under the whole tire (a shaker). The exported model keeps a road input per point with its
window's delays, as the radial model's road groups (:mod:`.io_model`).

**The reduction** is balanced truncation with residualisation (the static gain is kept
exactly) of the dense real system, its Gramians from scipy's Bartels-Stewart solver. Inputs
are weighed by a typical amplitude each (:data:`TYPICAL_INPUT`) and outputs by the inverse of
their peak response to them, so newtons, newton-metres and rad/s weigh alike. The transport's
defective eigenvalues (:mod:`.inplane_rolling_modes`) make a diagonal modal form ill-posed;
the reduced model stays in real state-space form.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg as sla

from .balanced import MINIMAL_RELATIVE_HSV, dense_gramians, psd_factor, residualise
from .inplane_contact import InPlaneSimulator
from .inplane_rolling_modes import RIM_INPUTS, rim_rows, rolling_system
from .parameters import ParameterError, Problem

#: Physical inputs: the wheel's torque (a free wheel's), the rim's fore-aft and vertical
#: displacement, and the road's height at the contact zone's front.
PHYSICAL_INPUTS = ("torque", "rim_x", "rim_z", "road")
INPUT_UNITS = {"torque": "N m", "rim_x": "m", "rim_z": "m", "road": "m"}
#: Outputs: the tire's force and moment on the rim (x forward, z up, My about the axle in
#: the direction of rotation) and a free wheel's spin less the nominal V/R.
OUTPUTS = ("rim_Fx", "rim_Fz", "rim_My", "wheel_rate")
OUTPUT_UNITS = {"rim_Fx": "N", "rim_Fz": "N", "rim_My": "N m", "wheel_rate": "rad/s"}
#: The amplitudes inputs are weighed by for balancing (a brake's kN m; a mm of road or rim).
TYPICAL_INPUT = {"torque": 1000.0, "rim_x": 1e-3, "rim_z": 1e-3, "road": 1e-3}
#: Pairs whose weighted peak is below this share of the largest are not judged by their own
#: peak (a response zero by symmetry, e.g. rim_x -> rim_Fz at rest, is rounding).
NEGLIGIBLE_PAIR = 1e-6


@dataclass(frozen=True, eq=False)
class InPlaneStateSpace:
    """ż = A z + B u, y = C z + D₀ u + D₁ u̇ + D₂ ü: the in-plane tire's deviations from its
    operating point (SI). ``input_names`` are torque, rim_x, rim_z, then road_0, road_1, ...
    (the road under each contact point, front first), whose window of road lies
    ``road_delays_s`` (points, 2: its front and rear end) behind the zone's front in time;
    ``operating_point`` holds what it was linearised about and its static outputs."""

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    d0: np.ndarray
    d1: np.ndarray
    d2: np.ndarray
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]
    road_delays_s: np.ndarray
    operating_point: dict = field(default_factory=dict)
    report: dict = field(default_factory=dict)

    @property
    def n_states(self) -> int:
        return self.a.shape[0]

    @property
    def physical_inputs(self) -> tuple[str, ...]:
        """The physical inputs this model takes (a held wheel takes no torque)."""
        return tuple(name for name in PHYSICAL_INPUTS
                     if name == "road" or name in self.input_names)

    def _input_vector(self, name: str, omega: np.ndarray) -> np.ndarray:
        """(frequencies, inputs): the internal inputs a unit physical input gives."""
        if name not in self.physical_inputs:
            raise ParameterError([Problem("input", name, "",
                                          f"one of {', '.join(self.physical_inputs)}")])
        vector = np.zeros((omega.size, len(self.input_names)), dtype=complex)
        if name != "road":
            vector[:, self.input_names.index(name)] = 1.0
            return vector
        first = len(self.input_names) - self.road_delays_s.shape[0]
        vector[:, first:] = road_window_response(self.road_delays_s, omega)
        return vector

    def transfer(self, freqs_hz) -> np.ndarray:
        """(frequencies, outputs, inputs), complex: C (sI - A)⁻¹ B + D₀ + s D₁ + s² D₂ at
        s = 2πif, each frequency a triangular solve on A's complex Schur form (made once)."""
        s = 2j * np.pi * np.asarray(freqs_hz, dtype=float)
        out = np.empty((s.size, len(self.output_names), len(self.input_names)), dtype=complex)
        if self.n_states:
            a, b, c = scaled(self.a, self.b, self.c)
            t, z = sla.schur(a, output="complex")
            zb, cz = z.conj().T @ b, c @ z
            eye = np.eye(self.n_states)
        for k, sk in enumerate(s):
            out[k] = self.d0 + sk * self.d1 + sk * sk * self.d2
            if self.n_states:
                out[k] += cz @ sla.solve_triangular(sk * eye - t, zb)
        return out

    def frequency_response(self, input_name: str, freqs_hz,
                           transfer: np.ndarray | None = None) -> np.ndarray:
        """(frequencies, outputs), complex: each output per unit of the physical input
        (``transfer``: :meth:`transfer` at these frequencies, if made already)."""
        freqs = np.asarray(freqs_hz, dtype=float)
        u = self._input_vector(input_name, 2 * np.pi * freqs)
        g = self.transfer(freqs) if transfer is None else transfer
        return np.einsum("fok,fk->fo", g, u)

    def static_gain(self) -> np.ndarray:
        """(outputs, inputs): the response to a constant input, -C A⁻¹ B + D₀."""
        return self.d0 - self.c @ np.linalg.solve(self.a, self.b)

    def summary(self) -> dict:
        return {"n_states": self.n_states, "inputs": list(self.input_names),
                "outputs": list(self.output_names), "operating_point": self.operating_point,
                "report": self.report}


def scaled(a, b, c, with_scale: bool = False):
    """(D⁻¹ A D, D⁻¹ B, C D) for the diagonal D that balances A's rows and columns (LAPACK's
    ?gebal): the ring's m and m/s and the elements' m span A's entries by 1e10, and its
    Schur form and Gramians lose digits to that. With ``with_scale``, D's diagonal too."""
    a, (scale, _) = sla.matrix_balance(a, permute=False, separate=True)
    out = (a, b / scale[:, None], c * scale[None, :])
    return (*out, scale) if with_scale else out


def road_window_response(delays_s: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """(frequencies, points): the mean over each point's window of a road read at the zone's
    front, e^{-iωτ} averaged over τ in [τ₁, τ₂] (module doc); a plate (1) where τ₂ = τ₁."""
    early, late = delays_s[:, 0][None, :], delays_s[:, 1][None, :]
    w = np.asarray(omega, dtype=float)[:, None]
    span = w * (late - early)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = (np.exp(-1j * w * early) - np.exp(-1j * w * late)) / (1j * span)
    small = np.abs(span) < 1e-8  # the window's mean of e^{-iωτ} is its centre's there
    return np.where(small, np.exp(-0.5j * w * (early + late)), mean)


def road_delays(sim: InPlaneSimulator) -> np.ndarray:
    """(points, 2): each point's window of road behind the zone's front, in seconds at the
    simulator's speed; zeros at rest (the road is a plate under the tire)."""
    lo, hi = sim._zone.road_windows_m(sim.deflection_m)
    if sim.speed_m_s <= 0.0:
        return np.zeros((lo.size, 2))
    front = float(max(lo.max(), hi.max()))
    return np.stack([front - hi, front - lo], axis=1) / sim.speed_m_s


def linear_model(sim: InPlaneSimulator, torque_n_m: float = 0.0) -> InPlaneStateSpace:
    """The in-plane tire of ``sim`` linearised about its steady rolling under ``torque_n_m``
    (at rest: its static footprint) as an :class:`InPlaneStateSpace` (module doc). The ring
    is ``sim``'s: unreduced, or on its Ritz basis when it has ``f_max_hz``."""
    if sim.wheel == "driven":
        raise ParameterError([Problem("wheel", sim.wheel, "", "'free' or 'held'",
                                      "a driven wheel's spin is a host's input, not a state")])
    system = rolling_system(sim, torque_n_m)
    if sim._free_spin and not system.contact.any():
        raise ParameterError([Problem("wheel", sim.wheel, "", "'held' off the road",
                                      "with no point in contact nothing holds a free wheel's "
                                      "spin (a pole at zero): press the tire "
                                      "(deflection_m > 0) or hold the wheel")])
    a, (b0, b1, b2) = system.a, system.inputs
    nr, ny = system.n_ring, system.n_rate
    vs = slice(nr, nr + ny)
    c_out, _ = rim_rows(sim, system)
    m_rows = sim.rim_force_rows()[2]
    d_out = [-m_rows @ bk[vs] for bk in (b0, b1, b2)]
    translation = sim._rim_rows["m_translation"]
    for name, column in (("rim_x", 0), ("rim_z", 1)):
        d_out[2][:, RIM_INPUTS.index(name)] -= translation[:, column]
    names = OUTPUTS[:3]
    if sim._free_spin:  # the wheel's spin offset ψ̇, a state
        rate = np.zeros((1, a.shape[0]))
        rate[0, nr + ny - 1] = 1.0
        c_out = np.vstack([c_out, rate])
        d_out = [np.vstack([d, np.zeros((1, d.shape[1]))]) for d in d_out]
        names = OUTPUTS
    # the inputs' derivatives out of the state equation (module doc)
    b1_ab2 = b1 + a @ b2
    b = b0 + a @ b1_ab2
    d0 = d_out[0] + c_out @ b1_ab2
    d1 = d_out[1] + c_out @ b2
    points = sim._zone.n_points
    input_names = RIM_INPUTS + tuple(f"road_{j}" for j in range(points))
    keep = np.ones(len(input_names), dtype=bool)
    if not sim._free_spin:  # a held wheel takes no torque
        keep[RIM_INPUTS.index("torque")] = False
    operating = {"speed_m_s": sim.speed_m_s, "deflection_m": sim.deflection_m,
                 "torque_n_m": float(torque_n_m), "wheel": sim.wheel,
                 "n_elements": sim.n_elements, "ring_f_max_hz": sim.f_max_hz,
                 "point_spacing_m": sim.point_spacing_m,
                 "points_in_contact": int(system.contact.sum()),
                 "sliding_points": int(np.sum(system.contact & ~system.stick)),
                 "static_outputs": _operating_outputs(sim, system)}
    return InPlaneStateSpace(a, b[:, keep], c_out, d0[:, keep], d1[:, keep], d_out[2][:, keep],
                             tuple(np.array(input_names)[keep]), names, road_delays(sim),
                             operating)


def _operating_outputs(sim: InPlaneSimulator, system) -> dict:
    """The outputs' values at the operating point (the model gives their deviations)."""
    nr, ny = system.n_ring, system.n_rate
    y = np.zeros(ny)
    y[:nr] = system.steady_x[:nr]
    rate = np.zeros(ny)
    if sim._free_spin:
        rate[-1] = system.steady_x[nr + ny - 1]
    fx, fz, my = sim.rim_force(y, rate, spin_rad_s=sim.spin_rad_s)
    values = {"rim_Fx": float(fx), "rim_Fz": float(fz), "rim_My": float(my)}
    if sim._free_spin:
        values["wheel_rate"] = float(rate[-1])
    return values


# ----- the reduction -----

@dataclass(frozen=True)
class InPlaneReductionSettings:
    """Balanced truncation: the fewest states whose largest relative FRF error over the band
    (each pair's worst |H_r - H| over its own peak |H|) is at most ``target_error``; or
    exactly ``n_states``."""

    target_error: float = 0.01
    band_hz: tuple[float, float] = (0.5, 300.0)
    n_frequencies: int = 160
    n_states: int | None = None

    def __post_init__(self) -> None:
        problems = []
        if not (math.isfinite(self.target_error) and 1e-6 <= self.target_error <= 1.0):
            problems.append(Problem("target_error", self.target_error, "", "in [1e-06, 1]"))
        low, high = self.band_hz
        if not (math.isfinite(low) and math.isfinite(high) and 0 < low < high <= 1e5):
            problems.append(Problem("band_hz", self.band_hz, "Hz",
                                    "(low, high) with 0 < low < high <= 1e+05 Hz"))
        if not (isinstance(self.n_frequencies, int) and 2 <= self.n_frequencies <= 100_000):
            problems.append(Problem("n_frequencies", self.n_frequencies, "",
                                    "an integer in [2, 100000]"))
        if self.n_states is not None and not (isinstance(self.n_states, int)
                                               and self.n_states >= 1):
            problems.append(Problem("n_states", self.n_states, "", "an integer >= 1, or None"))
        if problems:
            raise ParameterError(problems)

    def frequencies_hz(self) -> np.ndarray:
        return np.geomspace(*self.band_hz, self.n_frequencies)


def all_responses(model: InPlaneStateSpace, freqs_hz) -> dict[str, np.ndarray]:
    """{physical input: (frequencies, outputs)} for every input the model takes."""
    transfer = model.transfer(freqs_hz)
    return {name: model.frequency_response(name, freqs_hz, transfer)
            for name in model.physical_inputs}


def pair_errors(reduced: dict, full: dict, output_names) -> dict[str, float]:
    """{"input->output": max |H_r - H| / max |H|} over the frequencies, each pair judged by
    its own peak, except pairs that are negligible (:data:`NEGLIGIBLE_PAIR` of the largest
    response of the same output to a typical input), which are judged by that largest."""
    weighted = {name: np.abs(h).max(axis=0) * TYPICAL_INPUT[name] for name, h in full.items()}
    largest = np.max(np.stack(list(weighted.values())), axis=0)
    errors = {}
    for name, h in full.items():
        difference = np.abs(reduced[name] - h).max(axis=0)
        for k, output in enumerate(output_names):
            peak = np.abs(h[:, k]).max()
            if weighted[name][k] < NEGLIGIBLE_PAIR * largest[k]:
                peak = largest[k] / TYPICAL_INPUT[name]
            errors[f"{name}->{output}"] = float(difference[k] / peak) if peak > 0 else 0.0
    return errors


def reduce_linear_model(full: InPlaneStateSpace,
                        settings: InPlaneReductionSettings | None = None
                        ) -> InPlaneStateSpace:
    """Balanced truncation of ``full`` with residualisation (module doc), its error against
    ``full`` over the band in ``report``."""
    settings = settings or InPlaneReductionSettings()
    freqs = settings.frequencies_hz()
    reference = all_responses(full, freqs)
    input_weight = np.array([TYPICAL_INPUT["road" if name.startswith("road_") else name]
                             for name in full.input_names])
    peak = np.max(np.stack([np.abs(h).max(axis=0) * TYPICAL_INPUT[name]
                            for name, h in reference.items()]), axis=0)
    output_weight = np.where(peak > 0, 1.0 / np.where(peak > 0, peak, 1.0), 0.0)
    balanced = _balance(full.a, full.b * input_weight[None, :],
                        full.c * output_weight[:, None])
    a_bal, b_bal, c_bal, t, t_inv, hsv = balanced
    b_bal = b_bal / input_weight[None, :]
    c_bal = c_bal / np.where(output_weight > 0, output_weight, 1.0)[:, None]
    # an output weighed 0 (no response at all) has its rows unweighted: balancing saw none
    c_bal[output_weight == 0] = (full.c @ t)[output_weight == 0]

    def truncated(k: int) -> InPlaneStateSpace:
        a_k, b_k, c_k, d_k = residualise(a_bal, b_bal, c_bal, full.d0, k)
        return replace(full, a=a_k, b=b_k, c=c_k, d0=d_k, report={})

    def worst(model) -> tuple[float, dict]:
        errors = pair_errors(all_responses(model, freqs), reference, full.output_names)
        return max(errors.values()), errors

    order = a_bal.shape[0]
    if settings.n_states is not None:
        k = min(settings.n_states, order)
        error, errors = worst(truncated(k))
    else:
        k, (error, errors) = order, worst(truncated(order))
        for candidate in range(1, order + 1):
            error_k, errors_k = worst(truncated(candidate))
            if error_k <= settings.target_error:
                k, error, errors = candidate, error_k, errors_k
                break
    report = {"method": "balanced", "n_states": k, "full_states": full.n_states,
              "band_hz": list(settings.band_hz), "target_error": settings.target_error,
              "max_relative_error": error, "per_pair": errors,
              "hankel_singular_values": hsv[: min(hsv.size, 3 * k)].tolist()}
    return replace(truncated(k), report=report)


def _balance(a, b, c):
    """The square-root balanced realisation of a stable (A, B, C), its minimal part: (A, B,
    C, T, T⁻¹, Hankel singular values), x ≈ T x̃."""
    eigenvalues = np.linalg.eigvals(a)
    if np.any(eigenvalues.real >= 0):
        worst = eigenvalues[np.argmax(eigenvalues.real)]
        raise ValueError(f"the linearised tire is not stable (an eigenvalue at {worst:.4g} "
                         "1/s): no balanced reduction")
    # the Gramians of the scaled system (the same balanced realisation, better conditioned)
    a, b, c, scale = scaled(a, b, c, with_scale=True)
    p, q = dense_gramians(a, b, c)
    lp, lq = psd_factor(p), psd_factor(q)
    u, sigma, vt = sla.svd(lq.T @ lp, full_matrices=False)
    minimal = int(np.count_nonzero(sigma > sigma[0] * MINIMAL_RELATIVE_HSV))
    s_inv_half = 1.0 / np.sqrt(sigma[:minimal])
    t = lp @ vt[:minimal].T * s_inv_half[None, :]
    t_inv = (s_inv_half[:, None] * u[:, :minimal].T) @ lq.T
    return t_inv @ a @ t, t_inv @ b, c @ t, scale[:, None] * t, t_inv / scale[None, :], \
        sigma[:minimal]
