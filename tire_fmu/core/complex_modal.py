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


#: Relative eigenvalue gap below which inverse iteration could not tell two modes apart.
_CLUSTER_GAP = 1e-7
#: Relative residual an inverse-iteration eigenvector must reach, or the dense solve is used.
_RESIDUAL = 1e-9
#: "auto" uses inverse iteration from this many states on; below, the dense eigenvectors
#: cost less than one factorisation per mode.
SPARSE_MIN_STATES = 1000


def circulant_symbols(model: TireModel) -> tuple[np.ndarray, ...] | None:
    """Per-order 2×2 mass, damping and stiffness (orders 0..N-1, numpy's FFT order) when every
    N×N block of M, D and K is circulant (the undeformed tire at any speed), else None.

    A circulant block C maps e^{inθ} to ĉ_n e^{inθ} with ĉ = FFT of its first column, so the
    2N×2N problem splits exactly into one 2-DOF problem per order, built from the assembled
    matrices themselves.
    """
    n = model.n_elements
    out = []
    for matrix in (model.mass, model.damping, model.stiffness):
        symbol = np.empty((n, 2, 2), dtype=complex)
        for i in range(2):
            for j in range(2):
                block = sp.coo_matrix(matrix[i * n:(i + 1) * n, j * n:(j + 1) * n])
                block.sum_duplicates()
                first = np.zeros(n)
                offset = (block.row - block.col) % n
                first[offset] = block.data
                if block.nnz != n * np.count_nonzero(first) or not np.array_equal(
                        block.data, first[offset]):
                    return None
                symbol[:, i, j] = np.fft.fft(first)
        out.append(symbol)
    return tuple(out)


def _per_order_modes(model: TireModel, symbols,
                     f_max_hz: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The wanted state-space eigenvalues (of 4 per order) and their displacement shapes,
    pure harmonics e^{inθ}·(a_t, a_s), from the per-order quadratic problems
    (s²M_n + sD_n + K_n) a = 0."""
    mass, damping, stiffness = symbols
    n = model.n_elements
    m_inv = np.linalg.inv(mass)
    companion = np.zeros((n, 4, 4), dtype=complex)
    companion[:, 0, 2] = companion[:, 1, 3] = 1.0
    companion[:, 2:, :2] = -m_inv @ stiffness
    companion[:, 2:, 2:] = -m_inv @ damping
    values, vectors = np.linalg.eig(companion)  # (orders, 4), (orders, 4, 4)
    wanted = _wanted(values.ravel(), f_max_hz)
    order, member = np.divmod(wanted, 4)
    harmonic = np.exp(1j * np.outer(model.grid.theta, order))  # (nodes, wanted)
    amplitude = vectors[order, :2, member]  # (wanted, 2): tread and sidewall
    shapes = np.vstack([harmonic * amplitude[None, :, 0], harmonic * amplitude[None, :, 1]])
    return values.ravel()[wanted], shapes


def _inverse_iteration(model: TireModel, values: np.ndarray) -> np.ndarray | None:
    """Displacement shapes for the given eigenvalues by inverse iteration on the sparse
    quadratic pencil s²M + sD + K, or None where one does not converge to a clean
    eigenvector.

    Tread and sidewall DOFs are interleaved node by node, so the pencil is a narrow band
    with periodic corners and factorises without reordering in O(N) per eigenvalue.
    """
    import scipy.sparse.linalg as spla

    n = model.n_elements
    interleave = np.arange(2 * n).reshape(2, n).T.ravel()
    parts = [x.tocsr()[interleave][:, interleave].tocsc() for x in
             (model.mass, model.damping, model.stiffness)]
    pattern = sp.csc_matrix(abs(parts[0]) + abs(parts[1]) + abs(parts[2]))
    pattern.sort_indices()
    rows, cols = pattern.nonzero()
    csc_order = np.lexsort((rows, cols))  # the pattern's own (column-major) order
    rows, cols = rows[csc_order], cols[csc_order]
    m, d, k = (np.asarray(x[rows, cols]).ravel() for x in parts)
    scale = np.abs(k).max() + np.abs(d).max() * np.abs(values).max() + \
        np.abs(m).max() * np.abs(values).max() ** 2
    mass = sp.diags(parts[0].diagonal())
    start = np.exp(0.37j * np.arange(2 * n)) * (1.0 + np.arange(2 * n) % 7)
    shapes = np.empty((2 * n, values.size), dtype=complex)
    for i, s in enumerate(values):
        pencil = sp.csc_matrix(((s * s) * m + s * d + k, pattern.indices, pattern.indptr),
                               shape=pattern.shape)
        solve = spla.splu(pencil, permc_spec="NATURAL").solve
        v = solve(mass @ start)
        v /= np.linalg.norm(v)
        v = solve(mass @ v)
        v /= np.linalg.norm(v)
        if np.linalg.norm(pencil @ v) > _RESIDUAL * scale:
            return None
        shapes[interleave, i] = v
    return shapes


def _wanted(values: np.ndarray, f_max_hz: float | None) -> np.ndarray:
    """One member per conjugate pair; real eigenvalues (overdamped, non-oscillating) are no
    vibration modes and are left out. The band is on the natural frequency |s|/2π, as for
    real_modes, so modes overdamped in the body frame do not enter at their Doppler shift."""
    keep = values.imag > 1e-9 * np.abs(values)
    if f_max_hz is not None:
        keep &= np.abs(values) <= 2 * np.pi * f_max_hz
    return np.flatnonzero(keep)


def _eigenpairs(model: TireModel, f_max_hz: float | None, method: str):
    """Wanted eigenvalues and displacement shapes, by the cheapest exact path available:
    per order for an undeformed tire; with a patch, the dense eigenvalues alone and inverse
    iteration for the modes up to f_max_hz; the dense eigenvectors otherwise."""
    if method in ("auto", "per-order"):
        symbols = circulant_symbols(model)
        if symbols is not None:
            return _per_order_modes(model, symbols, f_max_hz)
        if method == "per-order":
            raise ValueError("method = 'per-order' needs an undeformed tire (no contact patch)")
    a = state_matrix(model)
    if f_max_hz is not None and (method == "sparse" or (method == "auto"
                                                      and a.shape[0] >= SPARSE_MIN_STATES)):
        from scipy.spatial import cKDTree

        values = sla.eigvals(a, overwrite_a=True, check_finite=False)
        wanted = _wanted(values, f_max_hz)
        if wanted.size == 0:
            return values[wanted], np.zeros((model.n_dof, 0), dtype=complex)
        points = np.column_stack([values.real, values.imag])
        nearest, _ = cKDTree(points).query(points[wanted], k=2)  # itself, then its neighbour
        if np.all(nearest[:, 1] > _CLUSTER_GAP * np.abs(values[wanted])):
            shapes = _inverse_iteration(model, values[wanted])
            if shapes is not None:
                return values[wanted], shapes
        a = state_matrix(model)
    values, vectors = sla.eig(a, overwrite_a=True, check_finite=False)
    wanted = _wanted(values, f_max_hz)
    return values[wanted], vectors[: model.n_dof, wanted]


COMPLEX_METHODS = ("auto", "dense", "sparse", "per-order")


def complex_modes(model: TireModel, f_max_hz: float | None = None,
                  method: str = "auto") -> ModalResult:
    """Oscillating modes of the rolling (or resting) tire with natural frequency |s|/2π up to
    ``f_max_hz``, ascending in ground-frame frequency Im(s)/2π.

    ``method``: "dense" (every eigenvector of the 4N state matrix, LAPACK), "per-order" (the
    undeformed tire's exact split into one 2-DOF problem per circumferential order),
    "sparse" (dense eigenvalues, eigenvectors by inverse iteration only for the modes up to
    ``f_max_hz``) or "auto" (per order when undeformed, else sparse with a cut on a large
    mesh, else dense).
    """
    if method not in COMPLEX_METHODS:
        raise ValueError(f"method = {method!r}: must be one of {COMPLEX_METHODS}")
    values, vectors = _eigenpairs(model, f_max_hz, method)
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
    shapes_array = (np.column_stack(shapes) if shapes
                    else np.zeros((model.n_dof, 0), dtype=complex))
    return ModalResult(tuple(modes), shapes_array, model.grid, model.summary(), values)


def modal_analysis(
    model: TireModel, f_max_hz: float | None = None, method: str = "auto"
) -> ModalResult:
    """Real modes at rest (with symmetry labels), complex modes when rolling."""
    from .modal import real_modes

    if model.speed_m_s == 0.0:
        return real_modes(model, f_max_hz, method)
    return complex_modes(model, f_max_hz, method)
