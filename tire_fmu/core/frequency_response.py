"""Frequency responses as result objects: the full model and its reduced models side by side."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .io_model import OUTPUT_UNITS, OUTPUTS, PHYSICAL_INPUTS, build_io_model
from .model import TireModel
from .parameters import ParameterError, Problem
from .reduction import ReducedModel


@dataclass(frozen=True, eq=False)
class FrequencyResponse:
    """H(f) from a unit physical input (rim displacement or road height, m) to one output."""

    frequencies_hz: np.ndarray
    response: np.ndarray  # complex, output unit per m
    input: str
    output: str
    label: str
    input_unit: str = "m"
    output_unit: str | None = None  # None: the radial model's output's (OUTPUT_UNITS)

    @property
    def unit(self) -> str:
        out = OUTPUT_UNITS[self.output] if self.output_unit is None else self.output_unit
        return f"{out}/{self.input_unit}" if " " not in self.input_unit else \
            f"{out}/({self.input_unit})"

    @property
    def magnitude(self) -> np.ndarray:
        return np.abs(self.response)

    @property
    def phase_deg(self) -> np.ndarray:
        return np.degrees(np.unwrap(np.angle(self.response)))

    def relative_error_to(self, reference: FrequencyResponse) -> np.ndarray:
        return np.abs(self.response - reference.response) / np.abs(reference.response)

    def to_dict(self) -> dict:
        return {
            "label": self.label,
            "input": self.input,
            "output": self.output,
            "unit": self.unit,
            "frequencies_hz": self.frequencies_hz.tolist(),
            "magnitude": self.magnitude.tolist(),
            "phase_deg": self.phase_deg.tolist(),
        }


def _check(input_name: str, output_name: str) -> int:
    problems = []
    if input_name not in PHYSICAL_INPUTS:
        problems.append(Problem("input", input_name, "", f"one of {', '.join(PHYSICAL_INPUTS)}"))
    if output_name not in OUTPUTS:
        problems.append(Problem("output", output_name, "", f"one of {', '.join(OUTPUTS)}"))
    if problems:
        raise ParameterError(problems)
    return OUTPUTS.index(output_name)


def full_frequency_response(model: TireModel, input_name: str, output_name: str,
                            freqs_hz) -> FrequencyResponse:
    """Exact FRF of the unreduced model."""
    row = _check(input_name, output_name)
    if input_name == "road" and not model.patch.in_contact:
        raise ParameterError([Problem("input", input_name, "", "'rim' for an undeformed tire",
                                      "the road input needs a contact patch: give a load or "
                                      "a patch length > 0")])
    freqs = np.asarray(freqs_hz, dtype=float)
    response = build_io_model(model).frequency_response(input_name, freqs)[row]
    return FrequencyResponse(freqs, response, input_name, output_name, "full model")


def reduced_frequency_response(reduced: ReducedModel, input_name: str, output_name: str,
                               freqs_hz) -> FrequencyResponse:
    row = _check(input_name, output_name)
    freqs = np.asarray(freqs_hz, dtype=float)
    response = reduced.physical_frequency_response(input_name, freqs)[row]
    label = f"reduced ({reduced.settings.method}, {reduced.n_states} states)"
    return FrequencyResponse(freqs, response, input_name, output_name, label)


def sine_response(times_s, values, omega_rad_s: float, decaying=()) -> np.ndarray:
    """Complex amplitude H of the steady response y = Im(H e^{iωt}) (+ a constant) in sampled
    ``values`` (samples x signals), fitted by least squares together with free decaying
    modes e^{λt} for each ``decaying`` eigenvalue λ (one of each conjugate pair): the fit
    needs no wait for a lightly damped transient to die out."""
    t = np.asarray(times_s, dtype=float)
    columns = [np.sin(omega_rad_s * t), np.cos(omega_rad_s * t), np.ones(t.size)]
    for lam in decaying:
        envelope = np.exp(lam.real * (t - t[0]))
        columns += [envelope * np.cos(lam.imag * t), envelope * np.sin(lam.imag * t)]
    coef = np.linalg.lstsq(np.column_stack(columns), np.asarray(values), rcond=None)[0]
    return coef[0] + 1j * coef[1]


def ringing_modes(a: np.ndarray, f_max_hz: float = 500.0, slowest_decay_s: float = 0.02):
    """Eigenvalues of a state matrix that ring long enough to matter in a fit window (decay
    time above ``slowest_decay_s``, below ``f_max_hz``), one of each conjugate pair. Faster
    modes are better left out and waited for: near the forcing frequency they would make the
    fit ill-conditioned."""
    lam = np.linalg.eigvals(np.asarray(a))
    keep = (lam.imag >= 0) & (-lam.real < 1.0 / slowest_decay_s) \
        & (np.abs(lam) < 2 * np.pi * f_max_hz)
    return lam[keep]
