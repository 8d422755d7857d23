"""Rolling terms of the ground-fixed (Eulerian) ring model.

The road and the contact patch are fixed in space, so the model is written in the ground frame
and the material moves through the mesh at spin Ω = V/R. Every material time derivative becomes
(∂t + Ω∂θ): inertia M(∂t + Ω∂θ)² gives the skew-symmetric gyroscopic matrix 2Ω·M·D1 and the
convective stiffness Ω²·M·D1·D1; material damping C(∂t + Ω∂θ) gives the circulatory stiffness
Ω·C·D1. The spinning ring also carries the centrifugal pre-tension ρA·R²·Ω² (added to P in every
tension term, see :mod:`tire_fmu.core.model`) and the spin softening -Ω²·M.

All of these act on the rim-relative displacement, like every internal force, so a spinning
tire translated rigidly with its rim and the road feels no extra force.
"""

from __future__ import annotations

from dataclasses import dataclass

import scipy.sparse as sp

from .discretisation import RingOperators


@dataclass(frozen=True, eq=False)
class RollingTerms:
    """Speed-dependent matrices on the 2N tread+sidewall DOFs (zero matrices at Ω = 0)."""

    gyroscopic: sp.csr_matrix  # 2Ω M D1, skew-symmetric: joins the velocity terms
    convective: sp.csr_matrix  # Ω² M D1 D1, symmetric
    spin_softening: sp.csr_matrix  # -Ω² M
    circulatory: sp.csr_matrix  # Ω C D1, from material damping

    @property
    def stiffness(self) -> sp.csr_matrix:
        return (self.convective + self.spin_softening + self.circulatory).tocsr()


def rolling_terms(
    ops: RingOperators, mass: sp.spmatrix, material_damping: sp.spmatrix, spin_rad_s: float
) -> RollingTerms:
    """Rolling matrices for spin Ω, given the 2N×2N mass and material damping."""
    d1 = sp.block_diag([ops.d1, ops.d1], format="csr")
    d1d1 = sp.block_diag([ops.d1d1, ops.d1d1], format="csr")
    return RollingTerms(
        gyroscopic=(2.0 * spin_rad_s * (mass @ d1)).tocsr(),
        convective=(spin_rad_s**2 * (mass @ d1d1)).tocsr(),
        spin_softening=(-(spin_rad_s**2) * mass).tocsr(),
        circulatory=(spin_rad_s * (material_damping @ d1)).tocsr(),
    )
