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


def balanced_reduction(decomp, io: InputOutputModel, settings):
    """(eigenvalues, B, C, D) of the balanced reduced model in diagonal modal form."""
    from .reduction import static_correction_matrix

    lam = decomp.eigenvalues
    keep = np.abs(lam) <= 2 * np.pi * settings.f_max_hz
    lam, b, c = lam[keep], decomp.b[keep], decomp.c[:, keep]
    d = io.d + static_correction_matrix(io, lam, b, c)
    a_r, b_r, c_r, _, _ = real_block_form(lam, b, c, d, io.e)

    dc = io.static_gain()
    scale = np.maximum(np.abs(dc).max(axis=1), 1e-300)  # per output, its static magnitude
    c_scaled = c_r / scale[:, None]
    sigma, lp, lq, u, vt = hankel_singular_values(a_r, b_r, c_scaled)
    count = settings.n_states
    if count is None:
        tail = 2.0 * np.cumsum(sigma[::-1])[::-1]  # tail[k] = 2 Σ_{i>=k} σ_i, the H∞ bound
        ok = np.flatnonzero(tail <= settings.balanced_tolerance * sigma[0])
        count = int(ok[0]) if ok.size else sigma.size
    # States with σ ~ 0 are uncontrollable or unobservable (e.g. the antisymmetric modes at
    # rest): drop them exactly before balancing, they do not touch the transfer function.
    minimal = int(np.count_nonzero(sigma > sigma[0] * 1e-12))
    count = max(1, min(count, minimal))
    s_inv_half = 1.0 / np.sqrt(sigma[:minimal])
    t = lp @ vt[:minimal].T * s_inv_half[None, :]  # x ≈ T x̃
    t_inv = (s_inv_half[:, None] * u[:, :minimal].T) @ lq.T
    a_b, b_b, c_b = t_inv @ a_r @ t, t_inv @ b_r, c_r @ t

    k = count
    if settings.static_correction and k < a_b.shape[0]:
        a11, a12, a21, a22 = a_b[:k, :k], a_b[:k, k:], a_b[k:, :k], a_b[k:, k:]
        solve = sla.lu_factor(a22)
        a_k = a11 - a12 @ sla.lu_solve(solve, a21)
        b_k = b_b[:k] - a12 @ sla.lu_solve(solve, b_b[k:])
        c_k = c_b[:, :k] - c_b[:, k:] @ sla.lu_solve(solve, a21)
        d_k = d - c_b[:, k:] @ sla.lu_solve(solve, b_b[k:])
    else:
        a_k, b_k, c_k, d_k = a_b[:k, :k], b_b[:k], c_b[:, :k], d

    form = diagonalise(a_k, b_k, c_k)
    return form.eigenvalues, form.b, form.c, d_k

