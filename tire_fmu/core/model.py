"""Assembly of the ring tire at an operating point: mass, damping and stiffness with contact.

Degrees of freedom are the radial displacements of the N tread nodes followed by the N sidewall
nodes, absolute (ground frame). Per metre of circumference the model is (paper eqs. 10-11,
rolling terms from :mod:`tire_fmu.core.rotation`)

    ρA ü_r + EI/R⁴ ∂⁴w_r - P*/R² ∂²w_r + k_r1 (w_r - w_s) = -f
    m_s ü_s + k_r1 (w_s - w_r) + k_r2 w_s - G/R² ∂²w_s = 0,     w = u - T z_rim,

with P* = p₀bR + ρA R²Ω², G the optional sidewall shear, and above ``sidewall_max_order`` the
sidewall's tie to the tread (:func:`.dispersion.sidewall_tie`, dense circulant blocks here,
undamped), T(θ) = -cos θ the radial pattern of a rigid upward translation and
f the road's push on the tread (:mod:`.contact`). Internal forces act on the rim-relative
displacement w; inertia stays absolute. A rigid translation of rim and road together
(u = T z, z_rim = z_road = z) leaves every force unchanged: a radial-only ring is not
stress-free under rigid translation, and coupling the rim to absolute displacements would add
a spurious ground spring of about 0.5 MN/m.

The model here is *linear*: the contact is linearised about a static state
(:class:`~.contact.ContactPatch`): by default the footprint the model computes for the load,
with k_j on each pushing node acting on the linearised gap
p_j = w_j + (z_road,j - z_rim)/cos θ_j (+ const), or the paper's prescribed patch. Time
stepping with the unilateral law itself is :mod:`.contact_dynamics`.

Node quantities are line quantities times R·δθ, so matrices are in kg, N·s/m and N/m.
Damping: material C = αM + βK₀ (K₀ the structure at rest, contact and sidewall tie excluded)
acting on the
material rate of w; the contact damper c_j = β·k_j acts on the ground-frame rate of p_j.

:func:`build_model` finds the grid, the static footprint and the critical speed; the sparse
matrices are assembled when first asked for (:attr:`TireModel.structure` and the matrices
built on it). The contact simulator and the FMU, which work per order and on the contact
zone, never ask, and so never import scipy.sparse.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from .blas_threads import blas_threads
from .contact import (
    ContactPatch,
    FootprintError,
    computed_patch,
    computed_patch_at_deflection,
    contact_zone,
    point_count_problems,
    prescribed_patch,
    zone_problems,
)
from .discretisation import Grid
from .free_ring import ring_static_gain, zone_compliance
from .parameters import (
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    Problem,
    TireParameters,
    conditioning_problems,
)

if TYPE_CHECKING:
    import scipy.sparse as sp

    from .rotation import RollingTerms

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
    import scipy.sparse as sp

    from .discretisation import RingOperators
    from .rotation import rolling_terms

    n = grid.n_elements
    ops = RingOperators(grid)
    eye = sp.identity(n, format="csr")
    arc = grid.node_arc_m
    k_r1 = tire.effective_k_r1  # sidewall stiffnesses at the inflation pressure
    tread = tire.EI / tire.R**4 * ops.d4 - tire.pretension_n / tire.R**2 * ops.d2 + k_r1 * eye
    sidewall = ((k_r1 + tire.effective_k_r2) * eye
                - tire.effective_sidewall_shear / tire.R**2 * ops.d2)
    coupling = -k_r1 * eye
    lumped = arc * sp.bmat([[tread, coupling], [coupling, sidewall]], format="csr")
    mass = arc * sp.diags(np.r_[np.full(n, tire.rhoA), np.full(n, tire.m_s)], format="csr")
    damping = (tire.alpha * mass + tire.beta * lumped).tocsr()  # the tie has no damper
    stiffness = lumped
    if 0 < tire.sidewall_max_order < n // 2:  # (TireModel.sidewall_tied)
        stiffness = (lumped + arc * sidewall_tie_matrix(tire, grid)).tocsr()
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


def sidewall_tie_matrix(tire: TireParameters, grid: Grid) -> sp.csr_matrix:
    """The sidewall's tie to the tread (:func:`.dispersion.sidewall_tie`) on the nodes, per
    metre: three circulant blocks with the tie's per-order values as their symbols. They are
    dense (the tie acts on orders, not on neighbours), which the assembled model can afford
    where the per-order code (the FMU, the simulator) never builds it."""
    import scipy.linalg as sla
    import scipy.sparse as sp

    from .dispersion import lumped_stiffness, order_symbols, sidewall_tie

    n = grid.n_elements
    orders = np.arange(n // 2 + 1)
    k0_tt, k0_ss = lumped_stiffness(tire, order_symbols(orders, n))
    # a real even symbol s_n (n = 0..N/2) is the circulant whose first column is its inverse DFT
    tt, ss, ts = (sla.circulant(np.fft.irfft(symbol, n=n))
                  for symbol in sidewall_tie(tire, orders, k0_tt, k0_ss))
    return sp.csr_matrix(np.block([[tt, ts], [ts, ss]]))


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


@dataclass(frozen=True, eq=False)
class TireModel:
    """The linear ring tire at one operating point (mesh, contact patch, speed).

    Defined by its fields; the assembled matrices follow from them on first use.
    """

    tire: TireParameters
    grid: Grid
    speed_m_s: float
    patch: ContactPatch
    critical_speed_m_s: float

    @cached_property
    def structure(self) -> StructuralMatrices:
        return structural_matrices(self.tire, self.grid, self.spin_rad_s)

    @cached_property
    def contact_stiffness(self) -> sp.csr_matrix:
        """The road springs of the patch on the tread DOFs: Iᵀ diag(k_p) I over the zone
        nodes (diagonal for one point per node)."""
        patch = self.patch
        return _on_tread(self.n_dof, patch.zone.nodes, patch.node_stiffness_matrix())

    @property
    def n_elements(self) -> int:
        return self.grid.n_elements

    @property
    def sidewall_tied(self) -> bool:
        """Whether the sidewall's tie acts on this mesh (some order above sidewall_max_order)."""
        return 0 < self.tire.sidewall_max_order < self.grid.n_elements // 2

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


def _on_tread(n_dof: int, nodes: np.ndarray, block: np.ndarray) -> sp.csr_matrix:
    """An n_dof x n_dof matrix holding ``block`` on the tread DOFs ``nodes``."""
    import scipy.sparse as sp

    rows, cols = np.nonzero(block)
    return sp.csr_matrix((block[rows, cols], (nodes[rows], nodes[cols])),
                         shape=(n_dof, n_dof))


def contact_patch(tire: TireParameters, grid: Grid, op: OperatingPoint) -> ContactPatch:
    """The static contact ``op`` asks for: the computed footprint for its load, or the
    paper's prescribed patch. Raises ParameterError with the allowed range of the load."""
    spin = op.speed_m_s / tire.R
    zone_length = op.contact_zone_length_m
    if op.patch_length_m is not None:
        # the patch must lie inside the zone: widen it if the patch asks for more
        zone_length = max(zone_length, 2 * tire.R * math.tan(
            0.5 * op.patch_length_m / tire.R + grid.dtheta))
    problems = (zone_problems(grid, zone_length, op.contact_point_spacing_m)
                if op.patch_length_m is None else
                point_count_problems(grid, zone_length, op.contact_point_spacing_m))
    if problems:
        raise ParameterError(problems)
    zone = contact_zone(grid, tire.k_cw, tire.beta, zone_length, op.contact_point_spacing_m)
    compliance = zone_compliance(ring_static_gain(tire, grid, spin, zone.nodes))
    if op.patch_length_m is not None:
        return prescribed_patch(zone, compliance, float(op.patch_length_m), op.speed_m_s)
    try:
        return computed_patch(zone, compliance, float(op.requested_load_n), op.speed_m_s,
                              tire.max_patch_length_m)
    except FootprintError as error:
        raise ParameterError([error.problem]) from error


def footprint_for_deflection(model: TireModel, deflection_m: float) -> ContactPatch:
    """The static footprint, and the load that makes it, for a rim deflection (m)."""
    zone = model.patch.zone
    compliance = zone_compliance(ring_static_gain(model.tire, model.grid, model.spin_rad_s,
                                                  zone.nodes))
    return computed_patch_at_deflection(zone, compliance, float(deflection_m),
                                        model.speed_m_s)


@blas_threads()  # small dense problems: see core.blas_threads
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
            f"m/s of this mesh (n_elements = {op.n_elements}); with sidewall_max_order = 0 a finer "
            "mesh lowers it, sidewall_max_order = 8 (the GL073A_tied tire) makes it converge, "
            "allow_supercritical runs anyway")])
    if CRITICAL_SPEED_WARNING_FRACTION * critical <= speed < critical:
        warnings.warn(
            f"speed {speed:g} m/s is {100 * speed / critical:.0f} % of the critical speed "
            f"{critical:.4g} m/s (n_elements = {op.n_elements}): modes near zero ground "
            "frequency dominate the response",
            SupercriticalSpeedWarning,
            stacklevel=2,
        )
    return TireModel(
        tire=tire,
        grid=grid,
        speed_m_s=speed,
        patch=contact_patch(tire, grid, op),
        critical_speed_m_s=critical,
    )


def undeformed(model: TireModel) -> TireModel:
    """The same tire, mesh and speed without contact (for mode continuation and checks)."""
    patch = model.patch
    free = replace(patch, weights=np.zeros_like(patch.weights), deflection_m=0.0, load_n=0.0,
                   length_m=0.0, vertical_stiffness_n_per_m=0.0, footprint=None,
                   forces_n=np.zeros_like(patch.forces_n), centre_compression_m=0.0)
    return replace(model, patch=free)


#: The fastest eigenvalue of a model over its slowest may be at most this: the slowest modes'
#: relative error grows as the rounding unit times this ratio (about 2e-6 at the limit), and
#: near 1e14 they are lost altogether and the outputs turn to nan.
MAX_EIGENVALUE_SPREAD = 1e10
#: What the check says (printf, so the native FMU renders the same).
RESOLVED_ALLOWED = ("%s here, or beta smaller: the model's eigenvalues span %s (fastest over "
                    "slowest) and may span at most %g")
RESOLVED_REASON = ("beyond that double precision loses the slowest modes; the fastest here "
                   "are %s, stiffness over mass %.3g 1/s^2, with beta = %g s")
RESOLVED_SPREAD = "%.2g"
RESOLVED_SPREAD_UNBOUNDED = "beyond 1e16"
#: (field to change, which way, what the fast modes are), in the order the check weighs them
RESOLVED_CANDIDATES = (
    ("m_s", "larger", "the sidewall masses on k_r1 + k_r2"),
    ("rhoA", "larger", "the tread nodes on k_r1 + k_cw"),
    ("EI", "smaller", "the tread's bending at the mesh's shortest wavelength (fewer "
                      "n_elements lengthen it)"),
)


def check_resolved(eigenvalues: np.ndarray, model: TireModel) -> None:
    """Raise ParameterError unless double precision resolves every mode of ``model``.

    The problem names the mass whose light node, against its springs, makes the fastest
    modes: in the model these go as the stiffness-to-mass ratios, and with stiffness-
    proportional damping as beta times them.
    """
    TIRE_UNITS = {name: spec.unit for name, spec in TIRE_FIELDS.items()}  # noqa: N806
    magnitude = np.abs(eigenvalues)
    if magnitude.size == 0:
        return
    slow, fast = float(magnitude.min()), float(magnitude.max())
    if np.all(np.isfinite(magnitude)) and fast <= MAX_EIGENVALUE_SPREAD * slow:
        return
    tire = model.tire
    step = 2 * np.pi / model.n_elements  # the mesh's shortest wavelength spans two nodes
    ratios = dict(zip(RESOLVED_CANDIDATES, (  # stiffness over mass, 1/s^2
        (tire.k_r1 + tire.k_r2) / tire.m_s,
        (tire.k_r1 + tire.k_cw) / tire.rhoA,
        tire.EI * 16 / (step * tire.R) ** 4 / tire.rhoA)))
    (field, way, what), ratio = max(ratios.items(), key=lambda item: item[1])
    spread = RESOLVED_SPREAD % (fast / slow) if slow > 0 and np.isfinite(fast) else \
        RESOLVED_SPREAD_UNBOUNDED
    raise ParameterError([Problem(
        field, getattr(tire, field), TIRE_UNITS[field],
        RESOLVED_ALLOWED % (way, spread, MAX_EIGENVALUE_SPREAD),
        RESOLVED_REASON % (what, ratio, tire.beta))])
