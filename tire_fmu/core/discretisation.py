"""Periodic finite-difference grid and operators around the ring.

Nodes sit at θ_j = j·δθ, δθ = 2π/N (the paper's "δθ = 2πR/N" is an arc length; the stencils
are in θ). θ is measured from the contact centre in the direction of rotation, so node 0 is the
centre of the patch and, for a tire rolling forward, positive θ lies towards the rear of the
patch. Every operator is a circulant stencil; its *symbol* (eigenvalue on e^{inθ}) gives the
discrete dispersion relation used by the analytic checks.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import scipy.sparse as sp

#: Central stencils (offset -> coefficient) before division by δθ^order.
FIRST_DERIVATIVE = {-1: -0.5, 1: 0.5}
SECOND_DERIVATIVE = {-1: 1.0, 0: -2.0, 1: 1.0}
FOURTH_DERIVATIVE = {-2: 1.0, -1: -4.0, 0: 6.0, 1: -4.0, 2: 1.0}


@dataclass(frozen=True)
class Grid:
    """N nodes on a ring of radius R; each node stands for an arc R·δθ of tread and sidewall."""

    n_elements: int
    radius_m: float

    @property
    def dtheta(self) -> float:
        return 2.0 * np.pi / self.n_elements

    @property
    def node_arc_m(self) -> float:
        """Arc length a node stands for: line quantities times this give node quantities."""
        return self.radius_m * self.dtheta

    @cached_property
    def theta(self) -> np.ndarray:
        """Node angles from the contact centre, wrapped to (-π, π]."""
        # j·δθ for j <= N/2 and -(N - j)·δθ beyond, so mirror nodes are exact negatives
        j = np.arange(self.n_elements)
        return np.where(2 * j <= self.n_elements, j, j - self.n_elements) * self.dtheta

    @cached_property
    def mirror_index(self) -> np.ndarray:
        """Index of each node's mirror image about the contact centre (θ -> -θ)."""
        return (-np.arange(self.n_elements)) % self.n_elements

    def wavenumbers(self) -> np.ndarray:
        """Circumferential orders n resolved by the grid, as numpy's FFT orders them."""
        return np.fft.fftfreq(self.n_elements, d=1.0 / self.n_elements).round().astype(int)


def stencil_matrix(n_nodes: int, stencil: dict[int, float], scale: float = 1.0) -> sp.csr_matrix:
    """Periodic (circulant) sparse matrix with ``(A u)_j = scale·Σ_k c_k u_{j+k}``."""
    import scipy.sparse as sp  # only the assembled model needs it (see :mod:`.model`)

    rows, cols, vals = [], [], []
    index = np.arange(n_nodes)
    for offset, coefficient in stencil.items():
        rows.append(index)
        cols.append((index + offset) % n_nodes)
        vals.append(np.full(n_nodes, scale * coefficient))
    matrix = sp.coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(n_nodes, n_nodes),
    )
    return matrix.tocsr()  # duplicates (tiny grids) are summed here


def stencil_symbol(stencil: dict[int, float], orders, dtheta: float, scale: float = 1.0):
    """Eigenvalue of a circulant stencil on the Fourier mode e^{inθ}, for each order n."""
    n = np.asarray(orders, dtype=float)
    return scale * sum(c * np.exp(1j * k * n * dtheta) for k, c in stencil.items())


@dataclass(frozen=True)
class RingOperators:
    """θ-derivatives on a grid: D1 (central), D2 (3-point), D4 (5-point); D1·D1 for convection."""

    grid: Grid

    @cached_property
    def d1(self) -> sp.csr_matrix:
        return stencil_matrix(self.grid.n_elements, FIRST_DERIVATIVE, 1.0 / self.grid.dtheta)

    @cached_property
    def d2(self) -> sp.csr_matrix:
        return stencil_matrix(self.grid.n_elements, SECOND_DERIVATIVE, self.grid.dtheta**-2)

    @cached_property
    def d4(self) -> sp.csr_matrix:
        return stencil_matrix(self.grid.n_elements, FOURTH_DERIVATIVE, self.grid.dtheta**-4)

    @cached_property
    def d1d1(self) -> sp.csr_matrix:
        # The convective Ω²∂θθ is discretised as D1·D1 so that it pairs exactly with the
        # gyroscopic 2Ω∂θ∂t (also D1): the ground-frame spectrum is then the body-frame one
        # shifted by Ω·κ_n with one discrete wavenumber κ_n. Mixing D1 with the 3-point D2
        # gives spurious modes at speed.
        return (self.d1 @ self.d1).tocsr()


def symbols(orders, dtheta: float) -> dict[str, np.ndarray]:
    """Symbols of D1, D2, D4 and D1·D1 on e^{inθ}: iκ, -λ2, λ4, -κ² (κ = sin(nδθ)/δθ)."""
    return {
        "d1": stencil_symbol(FIRST_DERIVATIVE, orders, dtheta, 1.0 / dtheta),
        "d2": stencil_symbol(SECOND_DERIVATIVE, orders, dtheta, dtheta**-2).real,
        "d4": stencil_symbol(FOURTH_DERIVATIVE, orders, dtheta, dtheta**-4).real,
        "d1d1": stencil_symbol(FIRST_DERIVATIVE, orders, dtheta, 1.0 / dtheta) ** 2,
    }
