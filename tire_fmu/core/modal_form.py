"""Diagonal modal form shared by every reduced model: q̇ = Λq + B r, y = Re(C q) + D r + E ṙ.

Of each complex-conjugate pair of eigenvalues only the member with Im λ > 0 is kept; for real
input signals its partner's state is its conjugate, so the pair's output is 2·Re(c q) and C
carries that factor 2 (1 for real eigenvalues, whose eigenvectors are real).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class ModalForm:
    eigenvalues: np.ndarray  # (k,) complex, ascending |λ|
    b: np.ndarray  # (k, n_inputs) complex
    c: np.ndarray  # (n_outputs, k) complex, pair factor included


#: Relative tolerance of the ties in :func:`canonical_modes` (the C reads it from spec.h): wide
#: enough for the rounding of any two eigen-solvers on the ring's orders, narrow enough that
#: values it ties are equal for every purpose of the model.
MODE_TIE_TOLERANCE = 1e-6


def canonical_modes(values: np.ndarray, vectors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The modes of an eigenproblem (or a stack of them: ``values`` (..., m), eigenvectors the
    columns of ``vectors`` (..., m, m)) in the canonical normalisation and order, which the
    Python core and the native FMU's C (``canonical_modes`` in numerics.c) both follow, so that
    two builders' modal data compare array by array:

    - each eigenvector is scaled to unit 2-norm and then by the unit complex factor that makes
      its pivot real and positive; the pivot is the component of lowest index whose magnitude is
      at least (1 - MODE_TIE_TOLERANCE) times the largest, so that components equal but for
      rounding count as tied and the first of them wins;
    - the modes are sorted by Im λ, then by Re λ, each compared with a tie: λ_a goes before λ_b
      when Im λ_a < Im λ_b by more than MODE_TIE_TOLERANCE max(|λ_a|, |λ_b|), or, their
      imaginary parts so tied, when Re λ_a < Re λ_b by more than the same; otherwise the two keep
      their order. The sort is an insertion sort (stable; the same steps in the C), so values
      within the tie of each other come out in the solver's order, which differs between
      solvers only for eigenvalues that rounding cannot separate anyway.

    Products such as c·b of a modal form do not depend on either choice.
    """
    values = np.array(values, dtype=complex)
    vectors = np.array(vectors, dtype=complex)
    size = np.abs(vectors)
    norm = np.linalg.norm(vectors, axis=-2)
    big = size.max(axis=-2)
    pivot = np.argmax(size >= (1.0 - MODE_TIE_TOLERANCE) * big[..., None, :], axis=-2)
    p = np.take_along_axis(vectors, pivot[..., None, :], axis=-2)[..., 0, :]
    p_size = np.abs(p)
    vectors *= (np.conj(p) * (1.0 / (p_size * norm)))[..., None, :]
    np.put_along_axis(vectors, pivot[..., None, :], (p_size / norm)[..., None, :] + 0j, axis=-2)
    m = values.shape[-1]
    for i in range(1, m):  # insertion sort, every stack at once: moving[...] while it moves
        moving = np.ones(values.shape[:-1], dtype=bool)
        for j in range(i, 0, -1):
            a, b = values[..., j], values[..., j - 1]
            tie = MODE_TIE_TOLERANCE * np.maximum(np.abs(a), np.abs(b))
            by_im = np.abs(a.imag - b.imag) > tie
            by_re = np.abs(a.real - b.real) > tie
            before = np.where(by_im, a.imag < b.imag, by_re & (a.real < b.real))
            moving &= before
            if not moving.any():
                break
            values[..., [j - 1, j]] = np.where(moving[..., None], values[..., [j, j - 1]],
                                               values[..., [j - 1, j]])
            vectors[..., [j - 1, j]] = np.where(moving[..., None, None],
                                                vectors[..., [j, j - 1]],
                                                vectors[..., [j - 1, j]])
    return values, vectors


def diagonalise(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> ModalForm:
    """Modal form of a real (A, B, C): eigenvectors V, B_q = V⁻¹B, C_q = C V.

    B_q comes from one real solve: LAPACK returns each conjugate pair's vectors as v and v̄,
    and x = Σ 2 Re(v q) = Σ (2 Re v) Re q - (2 Im v) Im q over the kept members, so the real
    matrix [2 Re v, -2 Im v] maps (Re q, Im q) to x (a quarter of the complex solve's work).
    """
    import scipy.linalg as sla  # loaded when a modal form is built, not at start-up

    values, vectors = sla.eig(a, overwrite_a=False, check_finite=False)
    real = values.imag == 0
    keep = (values.imag > 0) | real
    kept = np.flatnonzero(keep)
    cplx = values[kept].imag != 0
    width = np.where(cplx, 2, 1)
    first = np.concatenate([[0], np.cumsum(width)[:-1]]).astype(int)
    if width.sum() != a.shape[0]:  # pairs LAPACK did not return as v, v̄: solve in complex
        b_modal = sla.solve(vectors, b)[kept]
    else:
        basis = np.empty(a.shape)
        basis[:, first] = np.where(cplx, 2.0, 1.0)[None, :] * vectors[:, kept].real
        basis[:, first[cplx] + 1] = -2.0 * vectors[:, kept[cplx]].imag
        coordinates = sla.solve(basis, b, check_finite=False)
        b_modal = coordinates[first].astype(complex)
        b_modal[cplx] += 1j * coordinates[first[cplx] + 1]
    c_modal = c @ vectors[:, kept]
    b_modal[~cplx] = b_modal[~cplx].real  # real eigenvalue, real eigenvector: drop rounding dust
    c_modal[:, ~cplx] = c_modal[:, ~cplx].real
    factor = np.where(cplx, 2.0, 1.0)
    order = np.argsort(np.abs(values[kept]), kind="stable")
    return ModalForm(
        eigenvalues=values[kept][order],
        b=b_modal[order],
        c=(c_modal * factor[None, :])[:, order],
    )


def diagonalise_proportional(stiffness, mass_diag, alpha, beta, b_disp, b_vel, out_disp,
                             out_vel, eigenpairs=None) -> ModalForm:
    """Modal form of M ü + (αM + βK) u̇ + K u = B_z r + B_v ṙ from the real modes of (K, M).

    Proportional damping decouples the real modes, so the state-space modes follow from one
    symmetric eigenproblem of half the size: per mode (unit modal mass) η̈ + c η̇ + ω² η = ...
    with c = α + βω², written in the same momentum-like state as the full model,
    p = η̇ - φᵀB_v r:  [η̇, ṗ] = [[0, 1], [-ω², -c]] [η, p] + [φᵀB_v, φᵀB_z - c φᵀB_v] r,
    whose 2×2 eigenproblem is solved in closed form. ``eigenpairs`` (ω², mass-normalised
    shapes) of (K, M), when the caller has them, spare the symmetric eigenproblem.
    """
    import scipy.linalg as sla  # loaded when a modal form is built, not at start-up
    import scipy.sparse as sp

    if eigenpairs is None:
        dense = stiffness.toarray() if sp.issparse(stiffness) else np.asarray(stiffness)
        omega2, phi = sla.eigh(dense, np.diag(mass_diag))
    else:
        omega2, phi = eigenpairs
    omega2 = np.clip(omega2, 0.0, None)
    c = alpha + beta * omega2
    beta_v = phi.T @ b_vel
    beta_z = phi.T @ b_disp
    in_1, in_2 = beta_v, beta_z - c[:, None] * beta_v  # the mode's [η, p] input rows
    out_1, out_2 = out_disp @ phi, out_vel @ phi  # outputs from η and p
    root = np.sqrt((c * c - 4 * omega2).astype(complex))
    lam_a, lam_b = (-c + root) / 2, (-c - root) / 2  # lam_a: Im >= 0 (numpy's principal root)
    real = (c * c - 4 * omega2) > 0
    values, rows, cols = [], [], []
    # eigenvector of [[0,1],[-ω²,-c]] for λ is [1, λ]; left rows from the 2×2 inverse
    for lam, other, keep_all in ((lam_a, lam_b, True), (lam_b, lam_a, False)):
        use = np.ones_like(real) if keep_all else real  # the Im < 0 member only when real
        gap = (other - lam)[use]
        values.append(lam[use])
        rows.append((other[use, None] * in_1[use] - in_2[use]) / gap[:, None])
        factor = np.where(real[use], 1.0, 2.0)
        cols.append((out_1[:, use] + lam[use][None, :] * out_2[:, use]) * factor[None, :])
    values = np.concatenate(values)
    b = np.vstack(rows)
    c_out = np.hstack(cols)
    b[values.imag == 0] = b[values.imag == 0].real
    c_out[:, values.imag == 0] = c_out[:, values.imag == 0].real
    order = np.argsort(np.abs(values), kind="stable")
    return ModalForm(eigenvalues=values[order], b=b[order], c=c_out[:, order])


def real_block_form(eigenvalues, b, c, d, e):
    """Real (A, B, C, D, E) of a diagonal model whose outputs are Re(C q)."""
    import scipy.linalg as sla  # loaded when a modal form is built, not at start-up

    blocks, rows_b, cols_c = [], [], []
    for lam, b_row, c_col in zip(eigenvalues, b, c.T):
        if lam.imag == 0.0:
            blocks.append(np.array([[lam.real]]))
            rows_b.append(b_row.real[None, :])
            cols_c.append(c_col.real[:, None])
        else:
            # q = ξ1 + iξ2: ξ̇ = [[σ, -ω], [ω, σ]] ξ + [Re b; Im b] r, Re(c q) = Re c ξ1 - Im c ξ2
            blocks.append(np.array([[lam.real, -lam.imag], [lam.imag, lam.real]]))
            rows_b.append(np.vstack([b_row.real, b_row.imag]))
            cols_c.append(np.column_stack([c_col.real, -c_col.imag]))
    a = sla.block_diag(*blocks) if blocks else np.zeros((0, 0))
    b_real = np.vstack(rows_b) if rows_b else np.zeros((0, b.shape[1]))
    c_real = np.hstack(cols_c) if cols_c else np.zeros((c.shape[0], 0))
    return a, b_real, c_real, np.array(d, dtype=float), np.array(e, dtype=float)


def modal_frequency_response(eigenvalues, b, c, d, e, r, omega) -> np.ndarray:
    """Y(ω) of q̇ = Λq + B r, y = Re(C q) + D r + E ṙ for real signals with spectra r(ω)."""
    omega = np.asarray(omega, dtype=float)
    iw = 1j * omega[None, :]
    modal = (b @ r) / (iw - eigenvalues[:, None])
    # Re(C q) = (C q + conj(C q)) / 2 and conj(q) has the spectrum conj(B) r / (iω - conj(λ)).
    partner = (np.conj(b) @ r) / (iw - np.conj(eigenvalues)[:, None])
    return 0.5 * (c @ modal + np.conj(c) @ partner) + d @ r + iw * (e @ r)


