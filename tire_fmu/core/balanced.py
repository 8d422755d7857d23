"""Balanced truncation of the tire model, delivered in the same diagonal modal form.

The full model is first reduced modally without losing anything that matters (every mode up
to ``settings.f_max_hz``, static correction of the rest), in real block form. Its
controllability and observability Gramians (scipy's Bartels-Stewart Lyapunov solver) are
balanced by the square-root method; the states with the smallest Hankel singular values are
then truncated, or residualised when ``static_correction`` is on (singular perturbation, which
keeps the DC gain exact; python-control's 'matchdc'). Both keep a stable model stable.

Outputs are scaled by their peak response and inputs are all displacements (m), so forces in N
and the deflection in m weigh alike in the balancing.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from .io_model import InputOutputModel
from .modal_form import diagonalise, real_block_form

#: Hankel singular values below this fraction of the largest are treated as zero: their
#: states barely touch the transfer function, and balancing them needs σ^(-1/2) scalings
#: that amplify rounding until the reduced model can turn unstable.
MINIMAL_RELATIVE_HSV = 1e-9


def _psd_factor(gramian: np.ndarray) -> np.ndarray:
    """A factor L with L Lᵀ = G for a symmetric positive semi-definite G (eigh: robust where
    Cholesky fails on numerically singular Gramians)."""
    values, vectors = sla.eigh(0.5 * (gramian + gramian.T))
    return vectors * np.sqrt(np.clip(values, 0.0, None))[None, :]


def hankel_singular_values(a, b, c):
    p = sla.solve_continuous_lyapunov(a, -b @ b.T)
    q = sla.solve_continuous_lyapunov(a.T, -c.T @ c)
    lp, lq = _psd_factor(p), _psd_factor(q)
    u, sigma, vt = sla.svd(lq.T @ lp)
    return sigma, lp, lq, u, vt


class BalancedRealization:
    """The balanced realisation of a generous modal pre-reduction, ready to truncate.

    ``full`` holds the full model's responses over the error band, keyed (input, output row);
    each output is weighted by the inverse of its peak, and outputs that are zero by symmetry
    (absent from ``full``) get no weight at all, so rounding noise is never balanced.
    """

    def __init__(self, decomp, io: InputOutputModel, settings, full: dict):
        from .reduction import static_correction_matrix

        lam = decomp.eigenvalues
        keep = ~settings.above_f_max(lam)
        lam, b, c = lam[keep], decomp.b[keep], decomp.c[:, keep]
        self.d = io.d + static_correction_matrix(io, lam, b, c)
        a_r, b_r, c_r, _, _ = real_block_form(lam, b, c, self.d, io.e)
        weight = np.zeros(c_r.shape[0])
        for (_, row), response in full.items():
            weight[row] = max(weight[row], np.abs(response).max())
        weight = np.divide(1.0, weight, out=np.zeros_like(weight), where=weight > 0)
        sigma, lp, lq, u, vt = hankel_singular_values(a_r, b_r, c_r * weight[:, None])
        # States with σ ~ 0 are uncontrollable or unobservable (e.g. the antisymmetric modes
        # at rest): drop them before balancing, they do not touch the transfer function.
        minimal = int(np.count_nonzero(sigma > sigma[0] * MINIMAL_RELATIVE_HSV))
        s_inv_half = 1.0 / np.sqrt(sigma[:minimal])
        t = lp @ vt[:minimal].T * s_inv_half[None, :]  # x ≈ T x̃
        t_inv = (s_inv_half[:, None] * u[:, :minimal].T) @ lq.T
        self.a, self.b, self.c = t_inv @ a_r @ t, t_inv @ b_r, c_r @ t
        self.hankel_singular_values = sigma[:minimal]
        self.static_correction = settings.static_correction

    @property
    def order(self) -> int:
        return self.a.shape[0]

    def truncate(self, n_states: int):
        """(eigenvalues, B, C, D) in diagonal modal form keeping ``n_states`` states:
        residualised (DC exact) with static correction, plainly truncated without."""
        k = max(1, min(int(n_states), self.order))
        a, b, c, d = self.a, self.b, self.c, self.d
        if self.static_correction and k < self.order:
            solve = sla.lu_factor(a[k:, k:])
            a12, c2 = a[:k, k:], c[:, k:]
            a21_s, b2_s = sla.lu_solve(solve, a[k:, :k]), sla.lu_solve(solve, b[k:])
            a_k, b_k = a[:k, :k] - a12 @ a21_s, b[:k] - a12 @ b2_s
            c_k, d_k = c[:, :k] - c2 @ a21_s, d - c2 @ b2_s
        else:
            a_k, b_k, c_k, d_k = a[:k, :k], b[:k], c[:, :k], d
        form = diagonalise(a_k, b_k, c_k)
        return form.eigenvalues, form.b, form.c, d_k
