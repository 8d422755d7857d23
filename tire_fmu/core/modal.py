"""Real modal analysis of the tire at rest: frequencies, shapes, damping and mode labels.

At V = 0 the model is symmetric about the patch centre (θ -> -θ), so the problem splits exactly
into a symmetric and an antisymmetric subspace (cos nθ- and sin nθ-like shapes about the
contact centre). Each subspace is solved on its own, which gives every mode a clean symmetry
label even for the undeformed tire, where cos and sin partners are degenerate.

Labels follow each mode continuously from the undeformed tire: adding the patch stiffness only
adds a positive semi-definite term, and within one symmetry class eigenvalues of a one-parameter
symmetric family do not cross, so the i-th mode of a class descends from the i-th undeformed
mode of that class, whose order n and in/out-of-phase branch are known exactly from the FDM
symbols. The dominant Fourier harmonic alone would be ambiguous: the patch mixes neighbouring
orders. The same monotonicity bounds how many modes lie below a frequency, which sizes the
sparse shift-invert solve when only a few modes of a large mesh are wanted.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .analytic import two_mass_eigenvalues
from .discretisation import Grid
from .dispersion import order_symbols, per_order_matrices
from .model import TireModel

#: ARPACK's shift-invert pays off only for a few modes out of a large class: its cost grows
#: with the square of the modes wanted, a dense solve's with the cube of the class size.
SPARSE_MIN_CLASS_SIZE = 600
SPARSE_MAX_FRACTION = 0.1

SYMMETRIC, ANTISYMMETRIC = "symmetric", "antisymmetric"


@dataclass(frozen=True)
class Mode:
    """One mode's labels and scalars (shape lives in :class:`ModalResult`)."""

    frequency_hz: float
    order: int
    phase: str  # "in" or "out": tread and sidewall moving together or against each other
    symmetry: str | None  # about the patch centre; None when rolling
    damping_ratio: float
    direction: str | None = None  # rolling only: "forward" (with the rotation) or "backward"
    body_frequency_hz: float | None = None  # rolling, undeformed: co-rotating-frame frequency

    def to_dict(self) -> dict:
        out = {
            "frequency_hz": self.frequency_hz,
            "order": self.order,
            "phase": self.phase,
            "symmetry": self.symmetry,
            "damping_ratio": self.damping_ratio,
        }
        if self.direction is not None or self.body_frequency_hz is not None:
            out["direction"] = self.direction
            out["body_frequency_hz"] = self.body_frequency_hz
        return out


@dataclass(frozen=True, eq=False)
class ModalResult:
    """Modes of one model, ascending in frequency. ``shapes[:, i]`` is mode i on the 2N DOFs
    (tread then sidewall), mass-normalised; complex when rolling."""

    modes: tuple[Mode, ...]
    shapes: np.ndarray
    grid: Grid
    model_summary: dict = field(default_factory=dict)
    eigenvalues: np.ndarray | None = None  # state-space eigenvalues s (rolling analysis)

    @property
    def frequencies_hz(self) -> np.ndarray:
        return np.array([m.frequency_hz for m in self.modes])

    @property
    def damping_ratios(self) -> np.ndarray:
        return np.array([m.damping_ratio for m in self.modes])

    @property
    def orders(self) -> np.ndarray:
        return np.array([m.order for m in self.modes], dtype=int)

    def tread(self, index: int) -> np.ndarray:
        return self.shapes[: self.grid.n_elements, index]

    def sidewall(self, index: int) -> np.ndarray:
        return self.shapes[self.grid.n_elements :, index]

    def select(self, *, order: int | None = None, phase: str | None = None,
               symmetry: str | None = None) -> list[int]:
        """Indices of the modes matching every label given."""
        return [
            i for i, m in enumerate(self.modes)
            if (order is None or m.order == order)
            and (phase is None or m.phase == phase)
            and (symmetry is None or m.symmetry == symmetry)
        ]

    def to_dict(self) -> dict:
        return {**self.model_summary, "modes": [m.to_dict() for m in self.modes]}


def symmetry_bases(grid: Grid) -> dict[str, sp.csr_matrix]:
    """Orthonormal bases (2N × k) of the DOF vectors even / odd under θ -> -θ."""
    n = grid.n_elements
    mirror = grid.mirror_index
    bases = {}
    for name, sign in ((SYMMETRIC, 1.0), (ANTISYMMETRIC, -1.0)):
        rows, cols, vals = [], [], []
        column = 0
        for offset in (0, n):  # tread block, then sidewall block
            for j in range(n):
                partner = mirror[j]
                if partner < j:
                    continue
                if partner == j:  # node on the symmetry axis: only even vectors live there
                    if sign > 0:
                        rows.append(offset + j)
                        cols.append(column)
                        vals.append(1.0)
                        column += 1
                    continue
                rows += [offset + j, offset + partner]
                cols += [column, column]
                vals += [np.sqrt(0.5), sign * np.sqrt(0.5)]
                column += 1
        bases[name] = sp.csr_matrix((vals, (rows, cols)), shape=(2 * n, column))
    return bases


def undeformed_class_labels(model: TireModel) -> dict[str, list[tuple[float, int, str]]]:
    """(frequency, order, branch) of every undeformed mode in each symmetry class, ascending.

    The symmetric class holds cos nθ for 0 <= n <= N/2, the antisymmetric class sin nθ for
    0 < n < N/2; each order has an in-phase and an out-of-phase member.
    """
    n_el = model.n_elements
    orders = np.arange(0, n_el // 2 + 1)
    tire = model.tire
    sym = order_symbols(orders, n_el)
    (k_tt, k_ss, k_ts), _ = per_order_matrices(tire, sym, 0.0, orders)
    low, high = two_mass_eigenvalues(k_tt, k_ss, k_ts, tire.rhoA, tire.m_s)
    labels: dict[str, list[tuple[float, int, str]]] = {SYMMETRIC: [], ANTISYMMETRIC: []}
    for n, lo, hi in zip(orders, low, high):
        classes = [SYMMETRIC]
        if 0 < n and 2 * n != n_el:
            classes.append(ANTISYMMETRIC)
        for name in classes:
            labels[name] += [(float(np.sqrt(lo)), int(n), "in"),
                             (float(np.sqrt(hi)), int(n), "out")]
    for name in labels:
        labels[name].sort()
    return labels


def _uniform(values: np.ndarray) -> bool:
    """All the same to rounding (a symmetry class scales mirror pairs by √½·√½)."""
    return values.size > 0 and bool(np.all(np.abs(values - values[0])
                                           <= 1e-13 * np.abs(values[0])))


def two_level_eigenpairs(stiffness, mass_diag, count: int):
    """The lowest ``count`` eigenpairs of (K, diag(m)) ascending, mass-normalised, from half
    the problem, or None when K and M lack the structure that allows it.

    With the DOFs ordered tread then sidewall (as in a symmetry class) and a sidewall that
    is a lumped mass between two springs (no shear: its stiffness block d·I, the coupling
    c·I, uniform masses m_t and m_s), the sidewall is eliminated exactly: the tread shape v
    of a mode is an eigenvector of the tread block, A v = κ v, and each κ gives two modes
    (in and out of phase) with sidewall c v / (m_s ω² - d) and ω² the roots of
    (m_t ω² - κ)(m_s ω² - d) = c², eq. 12 of the paper with A in place of a_n. One
    symmetric eigenproblem of half the size replaces the full one.
    """
    size = stiffness.shape[0]
    half = size // 2
    if size % 2 or half == 0:
        return None
    k = sp.csr_matrix(stiffness)
    coupling, side = k[:half, half:], k[half:, half:]
    c, d = coupling.diagonal(), side.diagonal()
    m_t, m_s = mass_diag[:half], mass_diag[half:]
    if not (_uniform(c) and _uniform(d) and _uniform(m_t) and _uniform(m_s)
            and coupling.count_nonzero() == np.count_nonzero(c)
            and side.count_nonzero() == np.count_nonzero(d)
            and abs(k[half:, :half] - coupling.T).max() <= 1e-13 * abs(c[0]) and c[0] != 0):
        return None
    c, d, m_t, m_s = c[0], d[0], m_t[0], m_s[0]
    kappa, tread = sla.eigh(k[:half, :half].toarray(), driver="evd", overwrite_a=True,
                            check_finite=False)
    # m_t m_s x² - (m_t d + m_s κ) x + κ d - c² = 0, both roots real for a definite K
    p_half = 0.5 * (m_t * d + m_s * kappa)
    root = np.sqrt(np.clip(p_half * p_half - m_t * m_s * (kappa * d - c * c), 0.0, None))
    omega2 = np.concatenate([(p_half - root), (p_half + root)]) / (m_t * m_s)
    order = np.argsort(omega2, kind="stable")[:count]
    omega2 = omega2[order]
    ratio = c / (m_s * omega2 - d)  # sidewall per unit tread
    v = tread[:, order % half] / np.sqrt(m_t + m_s * ratio * ratio)[None, :]  # unit modal mass
    return omega2, np.vstack([v, v * ratio[None, :]])


def _class_eigen(stiffness, mass_diag, count, method):
    """Lowest ``count`` eigenpairs of (K, diag(m)), mass-normalised; dense or sparse
    shift-invert. "auto" picks by what is wanted: ARPACK for a few modes of a large class,
    LAPACK otherwise (every mode up to 300 Hz is about half of them: the sidewall band),
    on the tread alone when the sidewall can be eliminated (:func:`two_level_eigenpairs`)."""
    size = stiffness.shape[0]
    count = min(count, size)
    sparse = method == "sparse" or (method == "auto" and size >= SPARSE_MIN_CLASS_SIZE
                                    and count <= SPARSE_MAX_FRACTION * size)
    if not sparse or count >= size - 1:
        if method == "auto":
            pairs = two_level_eigenpairs(stiffness, mass_diag, count)
            if pairs is not None:
                return pairs
        # diagonal mass: the standard problem of M^-1/2 K M^-1/2 gives the same pairs
        # without the generalised reduction; divide and conquer when many are wanted
        scale = 1.0 / np.sqrt(mass_diag)
        scaled = stiffness.toarray() * scale[:, None] * scale[None, :]
        driver = "evd" if count > 0.3 * size else "evr"
        subset = None if driver == "evd" else [0, count - 1]
        values, vectors = sla.eigh(scaled, subset_by_index=subset, driver=driver,
                                   overwrite_a=True, check_finite=False)
        return values[:count], vectors[:, :count] * scale[:, None]
    values, vectors = spla.eigsh(stiffness.tocsc(), k=count, M=sp.diags(mass_diag).tocsc(),
                                 sigma=0.0, which="LM")
    order = np.argsort(values)
    return values[order], vectors[:, order]


def real_modes(model: TireModel, f_max_hz: float | None = None,
               method: str = "auto") -> ModalResult:
    """Modes of the tire at rest, up to ``f_max_hz`` (all modes when None), ascending.

    ``method``: "dense" (LAPACK), "sparse" (ARPACK shift-invert around 0) or "auto".
    """
    if model.speed_m_s != 0.0:
        raise ValueError("real_modes is for V = 0; use complex_modes for a rolling tire")
    if method not in ("auto", "dense", "sparse"):
        raise ValueError(f"method = {method!r}: must be 'auto', 'dense' or 'sparse'")
    stiffness = model.stiffness
    damping = model.damping
    mass_diag = model.mass.diagonal()
    loaded = model.patch.in_contact
    labels = undeformed_class_labels(model)
    found, blocks = [], []
    for name, basis in symmetry_bases(model.grid).items():
        reference = labels[name]
        if f_max_hz is None:
            count = len(reference)
        else:
            # Contact only raises eigenvalues: the undeformed count below fmax bounds ours.
            count = sum(1 for w, _, _ in reference if w <= 2 * np.pi * f_max_hz * (1 + 1e-9))
        if count == 0:
            continue
        k_class = (basis.T @ stiffness @ basis).tocsr()
        m_class = basis.multiply(basis).T @ mass_diag  # BᵀMB is diagonal: pairs share a mass
        values, vectors = _class_eigen(k_class, m_class, count, method)
        shapes = basis @ vectors
        omega = np.sqrt(np.clip(values, 0.0, None))
        modal_damping = np.einsum("ij,ij->j", shapes, damping @ shapes)
        with np.errstate(divide="ignore", invalid="ignore"):
            zeta = np.where(omega > 0, modal_damping / (2.0 * omega), np.nan)
        for rank in range(values.size):
            _, order, branch = reference[rank]
            mode = Mode(float(omega[rank] / (2 * np.pi)), order, branch,
                        name if loaded else None, float(zeta[rank]))
            found.append((mode, len(blocks), rank))
        blocks.append(shapes)
    found.sort(key=lambda item: item[0].frequency_hz)
    if f_max_hz is not None:
        found = [item for item in found if item[0].frequency_hz <= f_max_hz]
    modes = tuple(m for m, _, _ in found)
    shapes = np.empty((model.n_dof, len(found)))
    for column, (_, block, rank) in enumerate(found):
        shapes[:, column] = blocks[block][:, rank]
    return ModalResult(modes, shapes, model.grid, model.summary())
