"""Assembly of the ring tire at an operating point: mass, damping and stiffness with contact.

Degrees of freedom are the radial displacements of the N tread nodes followed by the N sidewall
nodes, absolute (ground frame). Per metre of circumference the model is (paper eqs. 10-11,
rolling terms from :mod:`tire_fmu.core.rotation`)

    ρA ü_r + EI/R⁴ ∂⁴w_r - P*/R² ∂²w_r + k_r1 (w_r - w_s) + k_cw χ (u_r - T z_road) = 0
    m_s ü_s + k_r1 (w_s - w_r) + k_r2 w_s - G/R² ∂²w_s = 0,     w = u - T z_rim,

with P* = p₀bR + ρA R²Ω², χ the patch indicator and T(θ) = -cos θ the radial pattern of a
rigid upward translation. Internal forces act on the rim-relative displacement w; inertia stays
absolute; the contact spring acts between the tread and the road. A rigid translation of rim
and road together (u = T z, z_rim = z_road = z) therefore leaves every force unchanged: a
radial-only ring is not stress-free under rigid translation, and coupling the rim to absolute
displacements would add a spurious ground spring of about 0.5 MN/m.

Node quantities are line quantities times R·δθ, so matrices are in kg, N·s/m and N/m.
Damping: material C = αM + βK₀ (K₀ the structure at rest, contact excluded) acting on the
material rate of w; the contact spring carries β·k_cw acting on the ground-frame rate.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import scipy.optimize as so
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .contact import (
    ContactPatch,
    deflection_from_patch_length,
    patch_weights,
    road_delays_s,
)
from .discretisation import Grid, RingOperators
from .parameters import (
    OperatingPoint,
    ParameterError,
    Problem,
    TireParameters,
    conditioning_problems,
)
from .rotation import RollingTerms, rolling_terms

#: Fraction of the critical speed above which building a model warns.
CRITICAL_SPEED_WARNING_FRACTION = 0.8


class SupercriticalSpeedWarning(UserWarning):
    """The speed is close to the critical (standing-wave) speed of the mesh."""


@dataclass(frozen=True, eq=False)
class StructuralMatrices:
    """The tire without contact, at spin Ω: all terms act on rim-relative displacement."""

    mass: sp.csr_matrix
    stiffness_at_rest: sp.csr_matrix  # K₀: bending, inflation tension, foundation springs
    material_damping: sp.csr_matrix  # C = αM + βK₀
    rolling: RollingTerms
    tension_stiffness_from_spin: sp.csr_matrix  # -ρA R²Ω²/R² D2 on the tread (centrifugal P)

    @property
    def stiffness(self) -> sp.csr_matrix:
        total = self.stiffness_at_rest + self.tension_stiffness_from_spin + self.rolling.stiffness
        return total.tocsr()

    @property
    def damping(self) -> sp.csr_matrix:
        return (self.material_damping + self.rolling.gyroscopic).tocsr()


def structural_matrices(
    tire: TireParameters, grid: Grid, spin_rad_s: float = 0.0
) -> StructuralMatrices:
    """Mass, stiffness and damping of tread + sidewall (no contact), node-scaled."""
    n = grid.n_elements
    ops = RingOperators(grid)
    eye = sp.identity(n, format="csr")
    arc = grid.node_arc_m
    tread = tire.EI / tire.R**4 * ops.d4 - tire.pretension_n / tire.R**2 * ops.d2 + tire.k_r1 * eye
    sidewall = (tire.k_r1 + tire.k_r2) * eye - tire.sidewall_shear / tire.R**2 * ops.d2
    coupling = -tire.k_r1 * eye
    stiffness = arc * sp.bmat([[tread, coupling], [coupling, sidewall]], format="csr")
    mass = arc * sp.diags(np.r_[np.full(n, tire.rhoA), np.full(n, tire.m_s)], format="csr")
    damping = (tire.alpha * mass + tire.beta * stiffness).tocsr()
    centrifugal_tension = tire.rhoA * tire.R**2 * spin_rad_s**2
    tension = sp.block_diag(
        [-arc * centrifugal_tension / tire.R**2 * ops.d2, sp.csr_matrix((n, n))], format="csr"
    )
    return StructuralMatrices(
        mass=mass,
        stiffness_at_rest=stiffness,
        material_damping=damping,
        rolling=rolling_terms(ops, mass, damping, spin_rad_s),
        tension_stiffness_from_spin=tension,
    )


def contact_stiffness(tire: TireParameters, grid: Grid, patch_length_m: float) -> sp.csr_matrix:
    """k_cw·R·δθ times each tread node's in-patch fraction, on the tread DOFs."""
    weights = patch_weights(grid, patch_length_m)
    diagonal = np.r_[tire.k_cw * grid.node_arc_m * weights, np.zeros(grid.n_elements)]
    return sp.diags(diagonal, format="csr")


def translation_pattern(grid: Grid) -> np.ndarray:
    """Radial displacement of every DOF for a unit upward translation: T = -cos θ."""
    t = -np.cos(grid.theta)
    return np.r_[t, t]


def horizontal_pattern(grid: Grid) -> np.ndarray:
    """Forward (x) component of each DOF's outward radial unit vector: -sin θ.

    θ runs with the rotation, rearwards at the patch when rolling forward, so a node at θ > 0
    near the patch points backwards.
    """
    s = -np.sin(grid.theta)
    return np.r_[s, s]


def vertical_stiffness(structure_stiffness, contact, translation) -> float:
    """Static vertical stiffness K_v = Tᵀ K_s (K_s + K_c)⁻¹ K_c T (rim force per rim travel).

    Rim pushed down by z with the road fixed: (K_s + K_c) u = K_s T z_rim, and the force on
    the rim is Tᵀ K_s (u - T z_rim); eliminating u gives the series combination above.
    """
    if contact.nnz == 0 or not np.any(contact.diagonal()):
        return 0.0
    solve = spla.splu((structure_stiffness + contact).tocsc())
    return float(translation @ (structure_stiffness @ solve.solve(contact @ translation)))


@dataclass(frozen=True, eq=False)
class TireModel:
    """The linear ring tire at one operating point (mesh, contact patch, speed)."""

    tire: TireParameters
    grid: Grid
    speed_m_s: float
    structure: StructuralMatrices
    contact_stiffness: sp.csr_matrix
    patch: ContactPatch
    critical_speed_m_s: float

    @property
    def n_elements(self) -> int:
        return self.grid.n_elements

    @property
    def n_dof(self) -> int:
        return 2 * self.grid.n_elements

    @property
    def spin_rad_s(self) -> float:
        return self.speed_m_s / self.tire.R

    @property
    def mass(self) -> sp.csr_matrix:
        return self.structure.mass

    @cached_property
    def contact_damping(self) -> sp.csr_matrix:
        # The contact spring stands for tread rubber in the patch: same β, but it deforms
        # against the road, so it is damped on the ground-frame rate, not the material rate.
        return (self.tire.beta * self.contact_stiffness).tocsr()

    @cached_property
    def stiffness(self) -> sp.csr_matrix:
        """Total stiffness (structure + contact) on absolute displacements."""
        return (self.structure.stiffness + self.contact_stiffness).tocsr()

    @cached_property
    def damping(self) -> sp.csr_matrix:
        """Total velocity matrix: material damping, gyroscopic terms, contact damping."""
        return (self.structure.damping + self.contact_damping).tocsr()

    @cached_property
    def translation(self) -> np.ndarray:
        return translation_pattern(self.grid)

    @cached_property
    def horizontal(self) -> np.ndarray:
        return horizontal_pattern(self.grid)

    @property
    def static_vertical_stiffness_n_per_m(self) -> float:
        return self.patch.vertical_stiffness_n_per_m

    def summary(self) -> dict:
        return {
            "n_elements": self.n_elements,
            "speed_m_s": self.speed_m_s,
            "spin_rad_s": self.spin_rad_s,
            "critical_speed_m_s": self.critical_speed_m_s,
            **self.patch.to_dict(),
        }


def _patch_state(tire, grid, structure, length_m, speed_m_s):
    contact = contact_stiffness(tire, grid, length_m)
    k_v = vertical_stiffness(structure.stiffness, contact, translation_pattern(grid))
    deflection = deflection_from_patch_length(tire.R, length_m)
    patch = ContactPatch(
        length_m=float(length_m),
        deflection_m=deflection,
        load_n=k_v * deflection,
        vertical_stiffness_n_per_m=k_v,
        weights=patch_weights(grid, length_m),
        road_delays_s=road_delays_s(grid, length_m, speed_m_s),
    )
    return contact, patch


def patch_for_load(tire: TireParameters, grid: Grid, structure, load_n: float, speed_m_s: float):
    """Patch length whose secant load K_v(L)·δ(L) equals ``load_n`` (bisection on L).

    Raises ParameterError when the load exceeds what the longest credible patch carries.
    """
    if load_n == 0.0:
        return _patch_state(tire, grid, structure, 0.0, speed_m_s)
    max_length = tire.max_patch_length_m
    _, longest = _patch_state(tire, grid, structure, max_length, speed_m_s)
    if load_n > longest.load_n:
        raise ParameterError([Problem(
            "load_n", load_n, "N", f"in [0, {longest.load_n:.6g}] N",
            f"for this tire: the longest credible patch ({max_length:.3g} m, deflection "
            f"{longest.deflection_m * 1e3:.3g} mm) carries {longest.load_n:.6g} N")])

    def excess(length):
        return _patch_state(tire, grid, structure, length, speed_m_s)[1].load_n - load_n

    length = so.brentq(excess, 0.0, max_length, xtol=1e-10, rtol=1e-12)
    return _patch_state(tire, grid, structure, length, speed_m_s)


def build_model(tire: TireParameters | None = None, op: OperatingPoint | None = None) -> TireModel:
    """Assemble the tire at an operating point.

    Refuses (ParameterError) a load the linear model cannot carry and, unless
    ``op.allow_supercritical``, a speed at or above the mesh's critical speed; warns
    (SupercriticalSpeedWarning) above 80 % of it.
    """
    from .standing_waves import critical_speed  # rolling module builds on this one

    tire = tire or TireParameters()
    op = op or OperatingPoint()
    problems = conditioning_problems(tire, op.n_elements)
    if problems:
        raise ParameterError(problems)
    grid = Grid(op.n_elements, tire.R)
    speed = float(op.speed_m_s)
    critical = critical_speed(tire, op.n_elements).speed_m_s
    if speed >= critical and not op.allow_supercritical:
        raise ParameterError([Problem(
            "speed_m_s", speed, "m/s", f"below the critical (standing-wave) speed {critical:.4g} "
            "m/s of this mesh", f"n_elements = {op.n_elements}; a finer mesh lowers it, "
            "sidewall_shear > 0 raises it, allow_supercritical runs anyway")])
    if CRITICAL_SPEED_WARNING_FRACTION * critical <= speed < critical:
        warnings.warn(
            f"speed {speed:g} m/s is {100 * speed / critical:.0f} % of the critical speed "
            f"{critical:.4g} m/s (n_elements = {op.n_elements}): sidewall modes near zero "
            "frequency dominate the response",
            SupercriticalSpeedWarning,
            stacklevel=2,
        )
    structure = structural_matrices(tire, grid, speed / tire.R)
    if op.patch_length_m is not None:
        contact, patch = _patch_state(tire, grid, structure, float(op.patch_length_m), speed)
    else:
        contact, patch = patch_for_load(tire, grid, structure, float(op.requested_load_n), speed)
    return TireModel(
        tire=tire,
        grid=grid,
        speed_m_s=speed,
        structure=structure,
        contact_stiffness=contact,
        patch=patch,
        critical_speed_m_s=critical,
    )


def undeformed(model: TireModel) -> TireModel:
    """The same tire, mesh and speed without contact (for mode continuation and checks)."""
    contact, patch = _patch_state(model.tire, model.grid, model.structure, 0.0, model.speed_m_s)
    return replace(model, contact_stiffness=contact, patch=patch)
