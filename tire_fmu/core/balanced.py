"""Balanced truncation of a model in diagonal modal form, delivered in the same form.

The input is the diagonal modal form (eigenvalues Λ, B, C, one member per conjugate pair) of
a generous modal pre-reduction. Its Gramians need no Lyapunov solver: for a diagonal A the
equation Λ P + P Λᴴ + B Bᴴ = 0 is solved entry by entry, P_ij = -b_i b_jᴴ / (λ_i + λ̄_j), a
Cauchy-like matrix, and the Gramians of the real block form follow from it and from its
companion -b_i b_jᵀ / (λ_i + λ_j) (the conjugate members). That costs O(n² m) for n states
and m inputs instead of the O(n³) Bartels-Stewart solves with their large constant. The
Gramians are then factored by pivoted Cholesky (LAPACK ?pstrf), which stops at their numerical
rank, so states that are uncontrollable or unobservable (e.g. the antisymmetric modes at
rest) never enter the square-root balancing, whose SVD is only rank × rank.

The states with the smallest Hankel singular values are then truncated, or residualised when
``static_correction`` is on (singular perturbation, which keeps the DC gain exact;
python-control's 'matchdc'). Both keep a stable model stable.

``gramians="dense"`` keeps the former path (scipy's Bartels-Stewart solver on the real block
form and eigenvalue factors) as an exact reference for tests and benchmarks.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.linalg import lapack

from .modal_form import diagonalise

#: Hankel singular values below this fraction of the largest are treated as zero: their
#: states barely touch the transfer function, and balancing them needs σ^(-1/2) scalings
#: that amplify rounding until the reduced model can turn unstable.
MINIMAL_RELATIVE_HSV = 1e-9

GRAMIANS = ("cauchy", "dense")


def real_state_index(eigenvalues: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Where each mode's real states sit in :func:`~tire_fmu.core.modal_form.real_block_form`:
    (index of ξ1 = Re q per mode, index of ξ2 = Im q per complex mode, total states)."""
    width = np.where(eigenvalues.imag != 0, 2, 1)
    first = np.concatenate([[0], np.cumsum(width)[:-1]]).astype(int)
    return first, first[width == 2] + 1, int(width.sum())


def real_gramian(eigenvalues: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Controllability Gramian of the real block form of q̇ = Λ q + B r (Λ diagonal).

    With M1 = ∫ q qᴴ and M2 = ∫ q qᵀ (both Cauchy-like, closed form), ξ1 = Re q, ξ2 = Im q:
    ξ1ξ1ᵀ = Re(M1 + M2)/2, ξ2ξ2ᵀ = Re(M1 - M2)/2, ξ2ξ1ᵀ = Im(M1 + M2)/2, ξ1ξ2ᵀ = Im(M2 - M1)/2
    (for a real mode ξ1 = q and the formulas reduce to M1 = M2).
    """
    lam = eigenvalues
    m1 = -(b @ b.conj().T) / (lam[:, None] + lam.conj()[None, :])
    m2 = -(b @ b.T) / (lam[:, None] + lam[None, :])
    re, im, size = real_state_index(lam)
    cplx = lam.imag != 0
    plus, minus = m1 + m2, m1 - m2
    p = np.empty((size, size))
    p[np.ix_(re, re)] = 0.5 * plus.real
    p[np.ix_(im, im)] = 0.5 * minus.real[np.ix_(cplx, cplx)]
    p[np.ix_(im, re)] = 0.5 * plus.imag[cplx]
    p[np.ix_(re, im)] = -0.5 * minus.imag[:, cplx]
    return p


def real_observability_gramian(eigenvalues: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Observability Gramian of the real block form with outputs Re(C q).

    It is the controllability Gramian of the dual, whose 2×2 blocks Aᵀ are those of λ̄ and
    whose input rows [Re c; -Im c] are those of the complex row c̄ᵀ.
    """
    return real_gramian(eigenvalues.conj(), c.conj().T)


def psd_factor(gramian: np.ndarray) -> np.ndarray:
    """A factor L with L Lᵀ = G for a symmetric positive semi-definite G (eigh: robust where
    Cholesky fails on numerically singular Gramians)."""
    values, vectors = sla.eigh(0.5 * (gramian + gramian.T))
    return vectors * np.sqrt(np.clip(values, 0.0, None))[None, :]


def _low_rank_factor(gramian: np.ndarray) -> np.ndarray:
    """L (n × rank) with L Lᵀ = G to rounding, by pivoted Cholesky stopping at the numerical
    rank (LAPACK's default tolerance, n·eps·max diag)."""
    if gramian.shape[0] == 0:
        return np.zeros((0, 0))
    factor, piv, rank, info = lapack.dpstrf(gramian, lower=1)
    if info < 0:
        raise ValueError(f"dpstrf: illegal argument {-info}")
    lower = np.tril(factor[:, :rank])
    out = np.empty_like(lower)
    out[piv - 1] = lower  # undo the symmetric pivoting: G = Pᵀ L Lᵀ P
    return out


def dense_gramians(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Controllability and observability Gramians by scipy's Bartels-Stewart solver."""
    p = sla.solve_continuous_lyapunov(a, -b @ b.T)
    q = sla.solve_continuous_lyapunov(a.T, -c.T @ c)
    return p, q


def _real_form(eigenvalues: np.ndarray, b: np.ndarray, c: np.ndarray):
    """(A sparse, B, C) of :func:`~tire_fmu.core.modal_form.real_block_form`, vectorised:
    [[σ, -ω], [ω, σ]] per complex mode, rows [Re b; Im b], columns [Re c, -Im c]."""
    re, im, size = real_state_index(eigenvalues)
    cplx = eigenvalues.imag != 0
    sigma, omega = eigenvalues.real, eigenvalues.imag[cplx]
    rows = np.r_[re, im, re[cplx], im]
    cols = np.r_[re, im, im, re[cplx]]
    vals = np.r_[sigma, sigma[cplx], -omega, omega]
    a = sp.csr_matrix((vals, (rows, cols)), shape=(size, size))
    b_r = np.empty((size, b.shape[1]))
    b_r[re], b_r[im] = b.real, b[cplx].imag
    c_r = np.empty((c.shape[0], size))
    c_r[:, re], c_r[:, im] = c.real, -c[:, cplx].imag
    return a, b_r, c_r


class BalancedRealization:
    """The balanced realisation of a model in diagonal modal form, ready to truncate.

    ``output_weight`` scales each output before balancing (the caller passes the inverse of
    its peak response and 0 for outputs that vanish by symmetry, so forces in N and the
    deflection in m weigh alike and rounding noise is never balanced). ``d`` is the
    feedthrough that goes with the modes given (static correction of the modes left out).
    """

    def __init__(self, eigenvalues, b, c, d, output_weight, static_correction: bool,
                 gramians: str = "cauchy"):
        if gramians not in GRAMIANS:
            raise ValueError(f"gramians = {gramians!r}: must be one of {GRAMIANS}")
        self.d = np.asarray(d, dtype=float)
        weight = np.asarray(output_weight, dtype=float)
        a_r, b_r, c_r = _real_form(eigenvalues, b, c)
        if gramians == "cauchy":
            lp = _low_rank_factor(real_gramian(eigenvalues, b))
            lq = _low_rank_factor(real_observability_gramian(eigenvalues,
                                                             c * weight[:, None]))
        else:
            p, q = dense_gramians(a_r.toarray(), b_r, c_r * weight[:, None])
            lp, lq = psd_factor(p), psd_factor(q)
        u, sigma, vt = sla.svd(lq.T @ lp, full_matrices=False)
        # States with σ ~ 0 are uncontrollable or unobservable: drop them before balancing,
        # they do not touch the transfer function.
        minimal = int(np.count_nonzero(sigma > sigma[0] * MINIMAL_RELATIVE_HSV)) if sigma.size \
            else 0
        s_inv_half = 1.0 / np.sqrt(sigma[:minimal])
        t = lp @ vt[:minimal].T * s_inv_half[None, :]  # x ≈ T x̃
        t_inv = (s_inv_half[:, None] * u[:, :minimal].T) @ lq.T
        self.a, self.b, self.c = t_inv @ (a_r @ t), t_inv @ b_r, c_r @ t
        self.hankel_singular_values = sigma[:minimal]
        self.static_correction = static_correction

    @property
    def order(self) -> int:
        return self.a.shape[0]

    def truncate(self, n_states: int):
        """(eigenvalues, B, C, D) in diagonal modal form keeping ``n_states`` states:
        residualised (DC exact) with static correction, plainly truncated without."""
        k = max(1, min(int(n_states), self.order))
        a, b, c, d = self.a, self.b, self.c, self.d
        if self.static_correction:
            a_k, b_k, c_k, d_k = residualise(a, b, c, d, k)
        else:
            a_k, b_k, c_k, d_k = a[:k, :k], b[:k], c[:, :k], d
        form = diagonalise(a_k, b_k, c_k)
        return form.eigenvalues, form.b, form.c, d_k


def residualise(a, b, c, d, k: int):
    """(A, B, C, D) keeping the first ``k`` states of a balanced (A, B, C, D) and
    residualising the rest (singular perturbation: their rates set to zero, so the static gain
    is kept exactly)."""
    if k >= a.shape[0]:
        return a, b, c, d
    solve = sla.lu_factor(a[k:, k:])
    a12, c2 = a[:k, k:], c[:, k:]
    a21_s, b2_s = sla.lu_solve(solve, a[k:, :k]), sla.lu_solve(solve, b[k:])
    return a[:k, :k] - a12 @ a21_s, b[:k] - a12 @ b2_s, c[:, :k] - c2 @ a21_s, d - c2 @ b2_s
