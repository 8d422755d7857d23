"""Complex (state-space) modal analysis of the rolling tire, eq. 33 of the paper in our frame.

The ground-frame model M ü + D u̇ + K u = 0 (D with the skew gyroscopic term, K with the
circulatory term) is non-symmetric, so its modes are complex: x = [u, u̇], ẋ = A x. Each
conjugate pair gives one physical mode, kept here with Im(s) >= 0: its ground-frame frequency
Im(s)/2π, damping ratio -Re(s)/|s| and complex shape.

Labels: the signed order n is the dominant Fourier harmonic e^{inθ} of the shape (mass
weighted over tread and sidewall), with the convention of :mod:`tire_fmu.core.dispersion`:
n > 0 travels against the rotation ("backward"), n < 0 with it ("forward"). The phase label
compares tread and sidewall (Re of their inner product). For the undeformed tire the modes are
pure harmonics and the co-rotating-frame frequency is Im(s) + κ_n Ω; with a patch the
harmonics mix and the labels are the dominant one, stated as such.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .discretisation import symbols as fdm_symbols
from .modal import ModalResult, Mode
from .model import TireModel


def state_matrix(model: TireModel) -> np.ndarray:
    """Dense first-order matrix A of ẋ = A x, x = [u, u̇] (2·n_dof square)."""
    n = model.n_dof
    m_inv = sp.diags(1.0 / model.mass.diagonal())
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -(m_inv @ model.stiffness).toarray()
    a[n:, n:] = -(m_inv @ model.damping).toarray()
    return a


def dominant_order(model: TireModel, shape: np.ndarray) -> int:
    """Signed order n whose harmonic e^{inθ} carries most of the shape's kinetic weight."""
    n_el = model.n_elements
    spectrum = np.zeros(n_el)
    for block, line_mass in ((shape[:n_el], model.tire.rhoA), (shape[n_el:], model.tire.m_s)):
        # u_j = Σ c_n e^{inθ_j}: numpy's forward FFT uses e^{-2πijk/N}, θ_j = 2πj/N.
        spectrum += line_mass * np.abs(np.fft.fft(block)) ** 2
    return int(model.grid.wavenumbers()[np.argmax(spectrum)])


def _phase_label(model: TireModel, shape: np.ndarray) -> str:
    n_el = model.n_elements
    return "in" if np.real(np.vdot(shape[:n_el], shape[n_el:])) >= 0.0 else "out"


def _normalise(model: TireModel, shape: np.ndarray) -> np.ndarray:
    """Unit modal mass (φᴴMφ = 1), largest tread entry real and positive."""
    shape = shape / np.sqrt(np.real(np.vdot(shape, model.mass @ shape)))
    n_el = model.n_elements
    peak = shape[np.argmax(np.abs(shape[:n_el]))]
    return shape * (abs(peak) / peak) if peak != 0 else shape


def complex_modes(model: TireModel, f_max_hz: float | None = None) -> ModalResult:
    """Oscillating modes of the rolling (or resting) tire with natural frequency |s|/2π up to
    ``f_max_hz``, ascending in ground-frame frequency Im(s)/2π."""
    n = model.n_dof
    values, vectors = sla.eig(state_matrix(model))
    # One member per conjugate pair; real eigenvalues (overdamped, non-oscillating) are no
    # vibration modes and are left out. The band is on the natural frequency |s|/2π, as for
    # real_modes, so modes overdamped in the body frame do not enter at their Doppler shift.
    keep = values.imag > 1e-9 * np.abs(values)
    values, vectors = values[keep], vectors[:n, keep]
    if f_max_hz is not None:
        inside = np.abs(values) <= 2 * np.pi * f_max_hz
        values, vectors = values[inside], vectors[:, inside]
    order = np.argsort(values.imag)
    values, vectors = values[order], vectors[:, order]
    undeformed = not model.patch.in_contact
    spin = model.spin_rad_s
    modes, shapes = [], []
    for s, raw in zip(values, vectors.T):
        shape = _normalise(model, raw)
        n = dominant_order(model, shape)
        body = None
        if undeformed:
            kappa = (fdm_symbols([n], model.grid.dtheta)["d1"][0] / 1j).real
            body = float((s.imag + kappa * spin) / (2 * np.pi))
        direction = None if spin == 0.0 or n == 0 else ("backward" if n > 0 else "forward")
        modes.append(
            Mode(
                frequency_hz=float(s.imag / (2 * np.pi)),
                order=n,
                phase=_phase_label(model, shape),
                symmetry=None,
                damping_ratio=float(-s.real / abs(s)) if s != 0 else np.nan,
                direction=direction,
                body_frequency_hz=body,
            )
        )
        shapes.append(shape)
    shapes_array = np.column_stack(shapes) if shapes else np.zeros((n, 0), dtype=complex)
    return ModalResult(tuple(modes), shapes_array, model.grid, model.summary(), values)


def modal_analysis(
    model: TireModel, f_max_hz: float | None = None, method: str = "auto"
) -> ModalResult:
    """Real modes at rest (with symmetry labels), complex modes when rolling."""
    from .modal import real_modes

    if model.speed_m_s == 0.0:
        return real_modes(model, f_max_hz, method)
    return complex_modes(model, f_max_hz)
