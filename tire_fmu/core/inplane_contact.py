"""The in-plane ring on the road: normal contact and a brush of tread elements with Coulomb
friction at the contact points, stepped in time with the unreduced ring.

**Points.** The contact points of :func:`.contact.contact_zone` (ground-fixed, at most
``point_spacing_m`` apart, each reading the tread by cubic Lagrange interpolation of the
nearest nodes and loading them by the same weights). Point p at ray angle θ_p reads the
tread's rim-relative (w_p, v_p); the material there sits at height
z_p = -(R + w_p) cos θ_p + v_p sin θ_p below the axle and x_p = -(R + w_p) sin θ_p -
v_p cos θ_p ahead of it.

**Normal law.** As in the radial model: the road at height h_p under the point is met along
the point's ray, where the tread's surface sits at radius R + w_p whatever the tangential
displacement (which slides material along the surface); the penetration is
pen_p = R + w_p - (R - δ - h_p)/cos θ_p, δ the rim's static deflection, and the road pushes
the tread inwards along the ray with f_n = max(0, k_p pen + c_p pen_rate) while pen > 0
(k_p = k_cw over the point's arc, c_p = β k_p). A push along the ray has no moment about the
axle. (A vertical push read at the material point instead made a turn of the tread against
the rim change the penetration, antisymmetrically about the contact centre, and so the
pressure's moment: a spurious coupling of the rotational modes to the footprint.)

**Tread elements and friction.** Each point carries a tread element (a bristle) of fore-aft
stiffness k_x,p = k_tx over its arc between the belt and the road. Its deflection e (the belt
end ahead of the road end) is a field fixed in the ground, carried through the footprint by
the rolling: ∂e/∂t + Ω ∂e/∂θ = s, with s the belt's fore-aft velocity relative to the road,

    s_p = [(∂t + Ω L) u]_x,p - Ω R cos θ_p + V,

the material velocity of the tread at the point (rim-relative L u: a rigid turn of the wheel
moves no geometry) plus the road's speed V. It is zero when the point leaves the road and
enters at zero at the road's edge (:func:`entering_fractions`). The element pulls the belt
with f_x = -k_x,p e while it sticks, |k_x,p e| <= μ f_n; beyond, the element slides and e
is held at the limit. The element's stiffness is the regularisation of Coulomb's law: stick
is elastic, with the tread's own shear compliance, and no other parameter enters.

**Forces on the ring.** The normal push acts on w (-∂pen/∂q), the fore-aft force on the
material's fore-aft motion ∂x_p/∂q, which includes the wheel's rotation ψ: the road's drag has
a moment about the axle. An asymmetric pressure (material damping loads the front of the
footprint more) has a horizontal resultant, the rolling resistance, that the tread elements
and the wheel's moment balance carry.

**Stepping.** Trapezoidal rule (Newmark, average acceleration) on the ring with the rim's
translation held and its rotation free (wheel inertia, a torque applied) or held at the
nominal spin; the contact forces are implicit in the step, solved by an active-set iteration
on (in contact, sticking). The element's convection is semi-Lagrangian (its state at
θ_p - Ωh by cubic Lagrange interpolation, :func:`carry_matrix`, plus the step's slip by the
trapezoidal rule).
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import dataclass, field

import numpy as np

from . import clock
from .contact import DEFAULT_ZONE_LENGTH_M, contact_zone
from .discretisation import Grid
from .host_inputs import MIN_STEP_S, input_path, rate_changes, substeps
from .inplane import InPlaneRing, InPlaneTire, hysteresis_share, quadratic_in_spin
from .obstacles import HostRoad, Obstacle
from .parameters import ParameterError, Problem
from .step_limits import MAX_HISTORY_SAMPLES
from .wheel_centre import effective_rolling_radius, longitudinal_slip, road_queries

#: The arithmetic a step runs on: the C of native/c/inplane_step.c, numpy's (the readable
#: reference), or the C when it can be had.
BACKENDS = ("numpy", "compiled", "auto")
#: How the wheel turns (InPlaneSimulator's ``wheel``).
WHEELS = ("free", "held", "driven")
#: Most active-set passes one step may take before it is refused.
MAX_SET_PASSES = 50
#: Passes after which the sets may only shrink (see the step).
SETTLE_PASSES = 12
#: How far (a fraction of the spin, at least 1 rad/s) a free wheel's spin may move from the
#: one the step was built at before it is rebuilt at the new spin, when the speed changes.
SPIN_REBUILD_FRACTION = 2e-3
#: How far (the same measure) the spin may move from the one the ring's step (its inverse)
#: was built at before that is rebuilt: up to it the step adds the spin's terms for the
#: difference explicitly, from the state predicted at the step's end.
RING_REBUILD_FRACTION = 5e-2


class StepRefused(RuntimeError):
    """A step the tire will not take: its state is to be rolled back (nothing changed)."""


class ContactSetError(StepRefused):
    """The step's contact and stick sets did not settle."""


class RunningLimitError(StepRefused):
    """The step took the tire outside the range it was built and verified for."""


#: The most a tire's force on the rim may reach, in loads, before a step is refused: a cleat
#: or a pothole at speed reaches a few loads; beyond this the inputs drive the tire outside
#: what the model represents (the footprint off its zone, the ring far off its linear range).
MAX_FORCE_LOADS = 20.0
#: How the running limits refuse a step (t since the start, the value, the limit ...): the
#: same words in both runtimes (spec.MESSAGES).
SPIN_LIMIT_TEMPLATE = (
    "step at t = %.6g s: the wheel's spin reached %.6g rad/s, beyond the %.6g rad/s the tire "
    "was built and verified for (%g of the critical speed %.6g m/s of this mesh, over R): "
    "less wheel_torque or wheel_rate; a tied sidewall or fewer elements raise the critical "
    "speed")
SPEED_LIMIT_TEMPLATE = (
    "step at t = %.6g s: the road's speed under the axle reached %.6g m/s (speed + rim_vx), "
    "beyond the %.6g m/s the tire was built and verified for (%g of the critical speed "
    "%.6g m/s of this mesh)")
FORCE_LIMIT_TEMPLATE = (
    "step at t = %.6g s: the tire's force on the rim reached %.6g N, beyond %g times the load "
    "(%.6g N): the inputs drive the tire outside what the model represents")


def sets_settled(old, new) -> bool:
    """Whether a pass left the sets (in contact, sticking, sliding direction) as they were:
    the same points on the road, the same ones sticking among them, the sliding ones sliding
    the same way (off the road, sticking means nothing)."""
    (contact, stick, sign), (new_contact, new_stick, new_sign) = old, new
    return bool(np.array_equal(new_contact, contact)
                and np.array_equal(new_stick | ~new_contact, stick | ~contact)
                and np.array_equal(new_sign[new_contact & ~new_stick], sign[contact & ~stick]))


@dataclass(frozen=True)
class InPlaneRun:
    """Histories of a run (SI): rim force and moment on the rim, contact totals, wheel spin."""

    time_s: np.ndarray
    rim_fx_n: np.ndarray
    rim_fz_n: np.ndarray
    rim_my_n_m: np.ndarray
    contact_fz_n: np.ndarray  # road's vertical push on the tread, summed
    contact_fx_n: np.ndarray  # road's fore-aft force on the tread, summed (+ forward)
    spin_rad_s: np.ndarray  # the wheel's spin (nominal + ψ̇)
    sliding_points: np.ndarray  # how many points slide
    speed_m_s: np.ndarray  # the road's (the vehicle's) speed

    def to_dict(self) -> dict:
        return {k: v.tolist() for k, v in self.__dict__.items()}


@dataclass
class StepState:
    """What a step carries to the next: the ring's coordinates, rates and accelerations, the
    tread elements' deflections, the contact and stick sets and the points' normal forces."""

    y: np.ndarray
    yd: np.ndarray
    ydd: np.ndarray
    e: np.ndarray
    contact: np.ndarray
    stick: np.ndarray
    slip_sign: np.ndarray
    f_n: np.ndarray


@dataclass
class InPlaneSimulator:
    """Unreduced in-plane tire on a road moving at ``speed_m_s`` under a held axle.

    ``wheel`` is ``"free"`` (ψ a DOF with the wheel inertia; apply ``torque_n_m``),
    ``"held"`` (spin fixed at the nominal V/R) or ``"driven"`` (ψ a DOF whose rate a host
    gives, as it models the wheel's body itself: :class:`InPlaneStepper`'s ``wheel_rate``;
    its equation is not stepped, the rim's moment My is what the host's wheel feels).
    ``obstacle`` starts ``obstacle_ahead_m`` in front of the contact centre (road distance).
    ``f_max_hz`` steps a reduced ring instead (:func:`ritz_basis`: the free ring's modes up to
    it and the static shapes of every zone node's radial and tangential load); None steps
    every DOF."""

    model: InPlaneTire
    n_elements: int = 100
    speed_m_s: float = 10.0
    deflection_m: float = 0.0
    step_s: float = 1e-4
    wheel: str = "free"
    zone_length_m: float = DEFAULT_ZONE_LENGTH_M
    point_spacing_m: float = 0.01
    obstacle: Obstacle | None = None
    obstacle_ahead_m: float = 0.5
    torque_n_m: float = 0.0
    f_max_hz: float | None = None
    backend: str = "numpy"
    library: object = field(default=None, repr=False)
    _state: dict = field(default_factory=dict, repr=False)
    #: a driven wheel (set by _build), and its spin less the tread's at the step's end
    _driven = False
    #: the length of the step the matrices are built for (None: step_s; set_step_length)
    _h = None
    _driven_rate = 0.0

    def __post_init__(self) -> None:
        problems = []
        if not (math.isfinite(self.speed_m_s) and 0.0 <= self.speed_m_s <= 150.0):
            problems.append(Problem("speed_m_s", self.speed_m_s, "m/s", "in [0, 150] m/s"))
        if not (math.isfinite(self.step_s) and MIN_STEP_S <= self.step_s <= 1e-2):
            problems.append(Problem("step_s", self.step_s, "s", f"in [{MIN_STEP_S:g}, 0.01] s"))
        if self.wheel not in WHEELS:
            problems.append(Problem("wheel", self.wheel, "", "'free', 'held' or 'driven'"))
        if self.f_max_hz is not None and not (math.isfinite(self.f_max_hz)
                                              and 1.0 <= self.f_max_hz <= 1e5):
            problems.append(Problem("f_max_hz", self.f_max_hz, "Hz",
                                    "in [1, 1e+05] Hz, or None for every DOF", ""))
        if not (math.isfinite(self.deflection_m) and 0.0 <= self.deflection_m < 0.2 *
                self.model.tire.R):
            problems.append(Problem("deflection_m", self.deflection_m, "m",
                                    f"in [0, {0.2 * self.model.tire.R:g}) m"))
        if self.backend not in BACKENDS:
            problems.append(Problem("backend", self.backend, "", f"one of {', '.join(BACKENDS)}"))
        if problems:
            raise ParameterError(problems)
        self._build()
        self._kernel = self._compiled_kernel()

    def _compiled_kernel(self):
        """The C step (``native/c/inplane_step.c``) for backend "compiled" or "auto" (when
        it can be had: else numpy, with a warning), or None for numpy's."""
        if self.backend == "numpy":
            return None
        try:  # outside the core (ctypes and a C compiler): imported only when asked for
            from ..native.inplane_kernel import InPlaneKernel
            from ..native.kernel import KernelUnavailable
        except ImportError:
            if self.backend == "compiled":
                raise
            return None
        try:
            return InPlaneKernel(self, self.library)
        except KernelUnavailable as error:
            if self.backend == "compiled":
                raise
            import warnings

            from .simulator import KernelFallbackWarning

            warnings.warn(f"{error}; the in-plane tire steps with numpy", KernelFallbackWarning,
                          stacklevel=3)
            return None

    @property
    def stepping_with(self) -> str:
        """"compiled" or "numpy": which arithmetic steps this simulator."""
        return "numpy" if self._kernel is None else "compiled"

    # ----- set-up -----
    @property
    def spin_rad_s(self) -> float:
        return self.speed_m_s / self.model.tire.R

    def _build(self) -> None:
        t, tang = self.model.tire, self.model.tangential
        # C and K are polynomials in the spin (C linear, K quadratic): read them off three
        # spins, so that the step can follow the wheel's spin as it changes
        rings = [InPlaneRing(self.model, self.n_elements, spin_rad_s=spin, rim_free=True,
                             hysteresis=False) for spin in (0.0, 1.0, 2.0)]
        ring = rings[0]
        zone = contact_zone(Grid(self.n_elements, t.R), t.k_cw, t.beta, self.zone_length_m,
                            self.point_spacing_m)
        nr, n = ring.n_ring_dof, self.n_elements
        # a driven wheel's turn is a coordinate as a free one's, its rate given
        free_spin = self.wheel in ("free", "driven")
        self._driven = self.wheel == "driven"
        self._driven_rate = 0.0  # a driven wheel's spin less the tread's, at the step's end
        ny = nr + (1 if free_spin else 0)
        # y = [ring rim-relative, ψ]: ring absolute = ring_rel + P_ψ ψ, the rim's x, z held
        to_abs = np.zeros((ring.n_dof, ny))
        to_abs[:nr, :nr] = np.eye(nr)
        if free_spin:
            to_abs[:nr, nr] = ring.rim_patterns[:, 2]
            to_abs[nr + 2, nr] = 1.0
        # to_abs is an identity and the turn's column: sparse, its products cost N², not N³
        import scipy.sparse  # not at import: the FMUs' start loads only what they use

        to_abs_sparse = scipy.sparse.csr_array(to_abs)

        def on_y(a):
            return np.asarray(to_abs_sparse.T @ (to_abs_sparse.T @ a.T).T)

        mass = on_y(ring.mass)
        c_at = [on_y(r.damping) for r in rings]
        k_at = [on_y(r.stiffness) for r in rings]
        k0, k1, k2 = quadratic_in_spin(*k_at)
        # the hysteretic loss, added apart at its share of the spin (not polynomial in it)
        hysteretic = rings[0].hysteretic_stiffness
        spin_terms = {"c0": c_at[0], "c1": c_at[1] - c_at[0], "k0": k0, "k1": k1, "k2": k2,
                      "kh": on_y(hysteretic)}

        interp = np.zeros((zone.n_points, n))
        interp[:, zone.nodes] = zone.interpolation  # zone nodes -> ring nodes
        th = zone.point_theta
        w, v = ring.field_slice("w"), ring.field_slice("v")
        jn = np.zeros((zone.n_points, ny))  # ∂pen/∂y on the geometry (rim-relative)
        jn[:, w] = interp  # the gap along the point's ray: the surface's radius R + w_p
        jx = np.zeros((zone.n_points, ny))  # ∂x_p/∂y of the geometry
        jx[:, w] = -np.sin(th)[:, None] * interp
        jx[:, v] = -np.cos(th)[:, None] * interp
        jn_work, jx_work = jn.copy(), jx.copy()  # the material's motion, with the wheel's turn
        if free_spin:  # the radial push has no moment about the axle; the fore-aft one has
            jx_work[:, nr] = -t.R * np.cos(th)
        tread_L = ring._pair_L()
        jl = np.zeros((zone.n_points, ny))  # x part of L u at the points
        jl[:, : 2 * n] = jx[:, : 2 * n] @ tread_L
        arc = zone.point_arc_m
        self._basis = None
        self._n_ring_coords = nr
        if self.f_max_hz is not None:
            basis = ritz_basis(self.model, self.n_elements, zone.nodes, self.f_max_hz)
            if free_spin:
                basis = np.block([[basis, np.zeros((nr, 1))],
                                  [np.zeros((1, basis.shape[1])), np.ones((1, 1))]])
            self._basis = basis
            self._n_ring_coords = basis.shape[1] - (1 if free_spin else 0)
            mass = basis.T @ mass @ basis
            spin_terms = {k: basis.T @ a @ basis for k, a in spin_terms.items()}
            jn, jx, jn_work, jx_work, jl = (a @ basis for a in (jn, jx, jn_work, jx_work, jl))
            to_abs = to_abs @ basis
            ny = basis.shape[1]
        self._ring, self._zone, self._to_abs = ring, zone, to_abs
        # the rim's translation (x, z) as the host moves it: the whole tire moved rigidly.
        # Rigid translation stores no force (K and C annihilate it, at any spin), so on the
        # rim-relative coordinates it enters through the inertia alone: -to_absᵀ M P r̈
        translation = np.stack([ring.rigid_motion(x_m=1.0), ring.rigid_motion(z_m=1.0)], 1)
        self._rim_inertia = to_abs.T @ ring.mass @ translation
        # the rim's rows of the tire's forces (InPlaneRing.rim_force), as polynomials in spin
        rows_k = [r.stiffness[-3:] for r in rings]
        rows_c = [r.damping[-3:] for r in rings]
        mass_rows = ring.mass[-3:].copy()
        mass_rows[:, -3:] -= np.diag([tang.wheel_mass_kg, tang.wheel_mass_kg,
                                      tang.wheel_inertia_kg_m2])
        rk0, rk1, rk2 = quadratic_in_spin(*rows_k)
        self._rim_rows = {"k0": rk0, "k1": rk1, "k2": rk2, "kh": hysteretic[-3:],
                          "c0": rows_c[0], "c1": rows_c[1] - rows_c[0], "m": mass_rows,
                          "m_translation": mass_rows @ translation}
        self._m, self._spin_terms = mass, spin_terms
        self._rim_on_y = None
        self._rim_rows_at = (None,)
        self._jn, self._jx, self._jnw, self._jxw, self._jl = jn, jx, jn_work, jx_work, jl
        self._kn = zone.stiffness_n_per_m
        self._cn = zone.damping_n_s_per_m
        self._kx = np.full(zone.n_points, tang.k_tx * arc)
        self._mu = tang.friction_coefficient
        self._pen0 = t.R - (t.R - self.deflection_m) / np.cos(th)
        self._sec = 1.0 / np.cos(th)
        self._cos = np.cos(th)
        self._x_lo, self._x_hi = zone.road_windows_m(self.deflection_m)
        self._ny, self._free_spin = ny, free_spin
        self._cx = t.beta * self._kx
        # the length of the step the matrices are built for: step_s, or a host's step that is
        # no whole number of it, cut into equal shorter ones (set_step_length)
        self._h = self.step_s
        self._set_spin(self.spin_rad_s, self.speed_m_s)

    def _set_spin(self, spin_rad_s: float, speed_m_s: float) -> None:
        """Build the whole step at this spin (the reference the wheel's ψ̇ is measured from)
        and road speed: the ring's step (:meth:`_set_ring_spin`) and the tread's
        (:meth:`_set_tread_spin`)."""
        self._set_ring_spin(spin_rad_s)
        self._set_tread_spin(spin_rad_s, speed_m_s)

    def _set_ring_spin(self, spin_rad_s: float) -> None:
        """The ring's step at this spin: C and K, the step's inverse and the ring's response to
        the points' forces (the costly part: an inverse of the coordinates' size). Between
        these builds the step adds the spin's terms for the difference to the wheel's actual
        spin explicitly (:meth:`_spin_correction`)."""
        h, o = self.step_length_s, spin_rad_s
        terms = self._spin_terms
        self._ring_spin = o
        self._c = terms["c0"] + o * terms["c1"]
        self._k = terms["k0"] + o * terms["k1"] + o**2 * terms["k2"]
        # K(o + d) - K(o) = d (k1 + 2 o k2) + d² k2
        self._c1, self._k1s, self._k2 = terms["c1"], terms["k1"] + 2.0 * o * terms["k2"], \
            terms["k2"]
        self._kh, self._ring_share = terms["kh"], self._share(o)
        if self._ring_share:
            self._k = self._k + self._ring_share * self._kh
        a0 = 4.0 / h**2 * self._m + 2.0 / h * self._c + self._k
        if self._driven:
            # the turn is given: the step solves the ring's rows for the ring's coordinates,
            # the turn's column a load (its row of the inverse zero: no force moves it)
            self._a0_inv = np.zeros_like(a0)
            self._a0_inv[:-1, :-1] = np.linalg.inv(a0[:-1, :-1])
            self._a0_psi = a0[:, -1].copy()
        else:
            self._a0_inv = np.linalg.inv(a0)
        self._yn = self._a0_inv @ self._jnw.T  # ring response to unit point forces
        self._yx = self._a0_inv @ self._jxw.T
        self._wnn, self._wnx = self._jn @ self._yn, self._jn @ self._yx
        # the tread element's force on y is linear in the tread's spin (kg_a + o kg_b), and
        # so are its products with the responses: kept apart, the tread follows the spin
        # without a product of the coordinates' size
        kx, cx, jxw, jl = self._kx[:, None], self._cx[:, None], self._jxw, self._jl
        self._kg_parts = (kx * jxw + cx * (2.0 / h * jxw), kx * (0.5 * h * jl) + cx * jl)
        self._kgn_parts = tuple(a @ self._yn for a in self._kg_parts)
        self._kgx_parts = tuple(a @ self._yx for a in self._kg_parts)

    def _set_tread_spin(self, spin_rad_s: float, speed_m_s: float) -> None:
        """The tread's step at this spin and road speed: the slip's reference, the elements'
        gain and force on the ring, their carry through the footprint (cheap: points-sized)."""
        h, o = self.step_length_s, spin_rad_s
        self._spin_now = o
        self._set_speed(speed_m_s)
        (ka, kb), (na, nb), (xa, xb) = self._kg_parts, self._kgn_parts, self._kgx_parts
        if not hasattr(self, "_gain"):
            self._gain, self._kg, self._kgn, self._kgx = (np.empty_like(a)
                                                          for a in (ka, ka, na, xa))
        # written in place: the C step keeps their addresses (a ringing wheel moves them
        # every few steps)
        # e = γ + G y while a point sticks (trapezoidal slip over the step)
        np.add(self._jxw, (0.5 * h * o) * self._jl, out=self._gain)
        # the tread element's force k_x e + c_x ė (ė = s while it sticks) on y: t = t0 + K_G y
        for out, (a, b) in ((self._kg, (ka, kb)), (self._kgn, (na, nb)), (self._kgx, (xa, xb))):
            np.multiply(b, o, out=out)
            out += a
        self._carry = carry_matrix(self._zone.point_theta, o * h, getattr(self, "_carry", None))
        base, weights = carry_stencil(self._zone.point_theta, o * h)
        theta = self._zone.point_theta
        self._carry_shift = o * h * (theta.size - 1) / (theta[-1] - theta[0])  # in spacings
        if not hasattr(self, "_carry_base"):
            self._carry_base, self._carry_weights = base.astype(np.int32), weights
        else:  # in place, as the carry (the C step keeps the addresses)
            self._carry_base[:], self._carry_weights[...] = base, weights

    @property
    def basis_fingerprint(self) -> int:
        """CRC-32 of the map from the coordinates to the tire's absolute DOFs (``to_abs``): two
        simulators whose fingerprints agree step the same coordinates; another BLAS, thread
        count or CPU may build the reduced basis with other signs or rotations of its modes,
        and then a state's coordinates mean another shape here (:meth:`coordinates_of`)."""
        if getattr(self, "_fingerprint", None) is None:
            self._fingerprint = zlib.crc32(np.ascontiguousarray(self._to_abs, "<f8").tobytes())
        return self._fingerprint

    def coordinates_of(self, dofs: np.ndarray) -> tuple[np.ndarray | None, float]:
        """This simulator's coordinates of the tire's absolute DOFs (rows: DOFs; columns: the
        shapes to map, e.g. displacement, rate, acceleration), and how far the shapes lie
        outside its basis: the largest residual of the ring's DOFs over their largest value
        (None when that exceeds :data:`STATE_BASIS_TOLERANCE`: the DOFs were stepped in a
        basis that spans another subspace)."""
        to_abs = self._to_abs
        if getattr(self, "_to_abs_pinv", None) is None:
            self._to_abs_pinv = np.linalg.pinv(to_abs)
        y = self._to_abs_pinv @ dofs
        residual = to_abs @ y - dofs
        # the last DOF is the rim's turn (it grows as the wheel rolls): checked on its own
        ring = np.abs(residual[:-1]).max(initial=0.0) / max(np.abs(dofs[:-1]).max(initial=0.0),
                                                            1e-12)
        turn = np.abs(residual[-1]).max(initial=0.0) / max(np.abs(dofs[-1]).max(initial=0.0),
                                                           1.0)
        worst = max(ring, turn)
        return (y if worst <= STATE_BASIS_TOLERANCE else None), worst

    @property
    def translation_projection(self) -> np.ndarray:
        """(coordinates, 2): the coordinates' change that holds the tire's material where it
        is while the rim translates by (x, z) (m): minus the rigid translation's share in the
        coordinates, M⁻¹ (to_absᵀ M P), mass-weighted, so that a jump of the rim keeps the
        tire's momentum (a driven wheel's given turn excluded)."""
        if getattr(self, "_projection", None) is None:
            projection = np.linalg.solve(self._m, self._rim_inertia)
            if self._driven:
                projection[-1] = 0.0
            self._projection = projection
        return self._projection

    @property
    def step_length_s(self) -> float:
        """The length of the step the matrices are built for (s): ``step_s`` unless a host's
        step that is no whole number of it has cut it shorter (:meth:`set_step_length`)."""
        return self.step_s if self._h is None else self._h

    def set_deflection(self, deflection_m: float) -> None:
        """Press the tire onto the road by ``deflection_m`` (m): only the points' penetrations
        and their windows of road depend on it, not the ring's step."""
        if not (math.isfinite(deflection_m) and 0.0 <= deflection_m < 0.2 * self.model.tire.R):
            raise ParameterError([Problem("deflection_m", deflection_m, "m",
                                          f"in [0, {0.2 * self.model.tire.R:g}) m")])
        self.deflection_m = deflection_m
        t = self.model.tire
        self._pen0 = t.R - (t.R - deflection_m) * self._sec
        self._x_lo, self._x_hi = self._zone.road_windows_m(deflection_m)

    def set_step_length(self, h: float) -> None:
        """Build the step for steps of ``h`` (s) at the current spins: what depends on the
        step's length (the ring's inverse, the tread's gain and carry) is built again; the
        state carries over (the trapezoidal rule takes any sequence of step lengths)."""
        if h == self._h:
            return
        if not (math.isfinite(h) and MIN_STEP_S <= h <= self.step_s):
            raise ParameterError([Problem("h", h, "s",
                                          f"in [{MIN_STEP_S:g}, {self.step_s:g}] s")])
        self._h = h
        self._set_ring_spin(self._ring_spin)
        self._set_tread_spin(self._spin_now, self._speed_now)

    def _take_spins(self, ring_spin: float, spin: float, speed: float,
                    length_s: float | None = None) -> None:
        """Rebuild what differs from these spins (a state taken back): the ring's step at
        ``ring_spin``, the tread's at ``spin`` and ``speed``, for steps of ``length_s``."""
        if length_s is not None and length_s != self._h:
            self._h = length_s
            self._ring_spin = math.nan  # both parts again, at the spins below
        rebuilt = ring_spin != self._ring_spin
        if rebuilt:
            self._set_ring_spin(ring_spin)
        if rebuilt or spin != self._spin_now:
            self._set_tread_spin(spin, speed)
        self._set_speed(speed)

    def _set_speed(self, speed_m_s: float) -> None:
        """The road's speed, and the slip's reference s0 it gives at the tread's spin."""
        self._speed_now = speed_m_s
        self._s0 = speed_m_s - self._spin_now * self.model.tire.R * self._cos

    def _share(self, spin_rad_s: float) -> float:
        """The hysteretic loss's share at this spin (0 without one)."""
        if not self.model.tangential.loss_factor:
            return 0.0
        return hysteresis_share(spin_rad_s, self.model.tire.R)

    def _road_share(self, rim=None) -> float:
        """The hysteretic loss's share at the road's speed under the axle (the road's speed,
        plus the rim's own fore-aft speed ``rim[1]``). It follows the road, which a host moves
        smoothly, not the wheel's spin: a share that follows the spin makes the loss a switch
        on the spin's sign at rest, which a braked wheel held there rings on (a limit cycle of
        ±20 kN at 0.05); rolling, the two differ by the slip only."""
        speed = self._speed_now + (float(rim[1]) if rim is not None else 0.0)
        return self._share(speed / self.model.tire.R)

    def _share_offset(self, yd: np.ndarray, rim=None) -> float:
        """The hysteretic share at the road's speed less the one the ring was built at."""
        return self._road_share(rim) - self._ring_share

    def spin_total_rad_s(self, yd: np.ndarray) -> float:
        """The wheel's spin (rad/s): the reference plus a free wheel's offset ψ̇."""
        return self._spin_now + (float(yd[-1]) if self._free_spin else 0.0)

    def _ring_offset(self, yd: np.ndarray) -> float:
        """How far the wheel's spin is from the one the ring's step was built at (rad/s)."""
        return self.spin_total_rad_s(yd) - self._ring_spin

    def _spin_correction(self, y, yd, ydd, offset: float, share: float) -> np.ndarray:
        """The spin's terms the ring's step lacks, -(ΔC ẏ + ΔK y) at the step's end, on the
        state predicted from the step's start, for a spin ``offset`` from the ring's and a
        hysteretic ``share`` change (explicit: ΔC and ΔK are the spin's small change, d c1
        and d (k1 + 2 o k2) + d² k2, and the share's change times kh, below its full speed)."""
        h = self.step_length_s
        v_end = yd + h * ydd
        y_end = y + h * yd + 0.5 * h * h * ydd
        out = -(offset * (self._c1 @ v_end + self._k1s @ y_end)
                + offset * offset * (self._k2 @ y_end))
        if share:
            out -= share * (self._kh @ y_end)
        return out

    def road(self, time_s: float, distance_m: float | None = None,
             speed_m_s: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(height, rate) of the road under each point: the obstacle moves back from
        ``obstacle_ahead_m`` in front of the contact centre by the road's travel against the
        axle, ``distance_m`` (V t at a constant speed), at ``speed_m_s`` (default: the
        current road speed; a moving rim adds its own)."""
        zero = np.zeros(self._zone.n_points)
        if self.obstacle is None:
            return zero, zero
        travelled = self.speed_m_s * time_s if distance_m is None else distance_m
        edge = self.obstacle_ahead_m - travelled
        speed = self._speed_now if speed_m_s is None else speed_m_s

        def height(at_edge):
            return self.obstacle.mean_height(self._x_lo - at_edge, self._x_hi - at_edge)

        # the rate by a central difference of the window means over a hundredth of a step
        dt = 1e-2 * self.step_s
        rate = (height(edge - speed * dt) - height(edge + speed * dt)) / (2 * dt)
        return height(edge), rate

    # ----- static state -----
    def static_state(self, deflection_m: float | None = None) -> np.ndarray:
        """The tire pressed onto the flat road at the deflection (default: the simulator's),
        frictionless, at rest."""
        nr = self._n_ring_coords
        k = self._k[:nr, :nr]
        jn = self._jn[:, :nr]
        pen0 = self._pen0 if deflection_m is None else (
            self.model.tire.R - (self.model.tire.R - deflection_m) * self._sec)
        active = pen0 > 0
        y = np.zeros(nr)
        for _ in range(MAX_SET_PASSES):
            a = k + jn[active].T @ (self._kn[active, None] * jn[active])
            b = -jn[active].T @ (self._kn[active] * pen0[active])
            y = np.linalg.solve(a, b)
            pen = pen0 + jn @ y
            force = self._kn * pen
            new = np.where(active, force > 0, pen > 0)
            if np.array_equal(new, active):
                break
            active = new
        else:
            raise ContactSetError("the static footprint did not settle")
        out = np.zeros(self._ny)
        out[:nr] = y
        return out

    # ----- stepping -----
    def run(self, duration_s: float, torque_n_m=None, record_every: int = 1,
            progress=None, speed_m_s=None, vehicle_mass_kg: float | None = None,
            rim_motion=None) -> InPlaneRun:
        """Step from the static state (rolling starts at t = 0) for ``duration_s``.
        ``torque_n_m`` (a constant or a function of time) turns the wheel (+ in the direction
        of rotation; a brake is negative). ``speed_m_s``, a function of time, changes the
        road's speed during the run (it starts at the simulator's ``speed_m_s``): the step
        follows the wheel's spin, rebuilt at the current spin whenever it has moved by
        :data:`SPIN_REBUILD_FRACTION` (every step with the wheel held, whose spin is V/R).
        ``vehicle_mass_kg`` instead lets the road's speed be the vehicle's, which the tire's
        fore-aft force on the axle drives (m dV/dt = Fx, the axle's height held): a braking
        or driven quarter car in the fore-aft direction.

        ``rim_motion``, a function of time giving (x, vx, ax, z, vz, az) (m, m/s, m/s²; x
        forward, z up), moves the rim from its held position, as a host moves the axle: the
        road under the points is then h - z (and its rate h' - vz) along the rays, the road's
        speed against the axle V + vx, and the tire's inertia loads the ring
        (-to_absᵀ M P r̈, P the rigid translation); rim_Fx and rim_Fz include it. It should
        start at rest at 0: the run starts from the static state."""
        if speed_m_s is not None and vehicle_mass_kg is not None:
            raise ValueError("run: give speed_m_s (a road) or vehicle_mass_kg (a vehicle)")
        if self._driven:
            raise ValueError("run: wheel = 'driven' takes its spin from a host: step it with "
                             "InPlaneStepper(sim).advance(..., wheel_rate_rad_s=...)")
        if vehicle_mass_kg is not None and not (math.isfinite(vehicle_mass_kg)
                                                and vehicle_mass_kg > 0):
            raise ParameterError([Problem("vehicle_mass_kg", vehicle_mass_kg, "kg", "> 0 kg")])
        h, ny = self.step_s, self._ny

        def rim_at(t):
            return np.zeros(6) if rim_motion is None else np.asarray(rim_motion(t), float)

        rim = rim_at(0.0)
        self.set_step_length(self.step_s)
        self._set_spin(self.spin_rad_s, self.speed_m_s)
        speed_now, distance = self.speed_m_s, 0.0
        steps = int(round(duration_s / h))
        torque = self.torque_n_m if torque_n_m is None else torque_n_m
        y = self.static_state()
        yd, ydd = np.zeros(ny), np.zeros(ny)
        e = np.zeros(self._zone.n_points)
        ring_forces = self._contact_and_rates(y, yd, e, 0.0, rim)
        ydd = np.linalg.solve(self._m, self._f_ext(0.0, torque, rim) + ring_forces[0]
                              - self._c @ yd - self._k @ y)
        state = StepState(y, yd, ydd, e, *ring_forces[1:5])
        records = {k: [] for k in InPlaneRun.__dataclass_fields__}
        fx_axle = 0.0
        for i in range(1, steps + 1):
            time = i * h
            if speed_m_s is not None or vehicle_mass_kg is not None:
                if vehicle_mass_kg is not None:  # explicit: the vehicle is heavy
                    speed_new = max(speed_now + h * fx_axle / vehicle_mass_kg, 0.0)
                else:
                    speed_new = float(speed_m_s(time))
                if not (math.isfinite(speed_new) and 0.0 <= speed_new <= 150.0):
                    raise ParameterError([Problem("speed_m_s", speed_new, "m/s",
                                                  "in [0, 150] m/s", f"at t = {time:g} s")])
                distance += 0.5 * h * (speed_now + speed_new)
                speed_now = speed_new
                state.yd = self._follow_spin(state.yd, speed_now)
            else:
                distance = self.speed_m_s * time
                if rim_motion is not None and self._free_spin:
                    # the axle's own fore-aft speed changes the free wheel's spin: follow it
                    state.yd = self._follow_spin(state.yd, self.speed_m_s)
            rim_old, rim = rim, rim_at(time)
            height, rate = self.road(time, distance + rim[0], self._speed_now + rim[1])
            height, rate = height - rim[3], rate - rim[4]
            state = self._step(state, time, torque, rim_old, rim, height, rate)
            y, yd, ydd, e = state.y, state.yd, state.ydd, state.e
            contact, stick, f_n = state.contact, state.stick, state.f_n
            if vehicle_mass_kg is not None:
                fx_axle = self.rim_force(y, yd, ydd, rim)[0]
            if i % record_every == 0:
                f_x = -self._kx * e
                rim_f = self.rim_force(y, yd, ydd, rim)
                records["time_s"].append(time)
                records["rim_fx_n"].append(rim_f[0])
                records["rim_fz_n"].append(rim_f[1])
                records["rim_my_n_m"].append(rim_f[2])
                records["contact_fz_n"].append(f_n.sum())
                records["contact_fx_n"].append(f_x.sum())
                records["spin_rad_s"].append(self._spin_now + (yd[-1] if self._free_spin
                                                              else 0.0))
                records["sliding_points"].append(int(np.sum(contact & ~stick)))
                records["speed_m_s"].append(speed_now)
            if progress is not None:
                progress(i, steps)
        self._state = {"y": y, "yd": yd, "e": e}
        return InPlaneRun(**{k: np.asarray(v) for k, v in records.items()})

    def _step(self, state: StepState, time, torque, rim_old, rim, height, rate) -> StepState:
        """One trapezoidal step to ``time`` from ``state``: the road under the points
        (``height``, ``rate``, the rim's z already taken off), the rim's motion before and
        after (x, vx, ax, z, vz, az) and the torque. Returns the new state."""
        if self._kernel is not None:
            value = torque(time) if callable(torque) else torque
            status, new = self._kernel.step(state, height, rate, value, rim_old, rim)
            if status == 0:
                return new
            raise ContactSetError(f"step at t = {time:g} s: the contact and stick sets did "
                                  + (f"not settle in {MAX_SET_PASSES} passes" if status == 1
                                     else "not give a solvable point solve"))
        h = self.step_length_s
        y, yd, ydd, e = state.y, state.yd, state.ydd, state.e
        contact, stick, slip_sign = state.contact, state.stick, state.slip_sign
        s_old = self._slip(y, yd)
        # the element field carried back by Ωh through the points (its ends: carry_edges)
        e_conv = self._carry @ e
        r = 2.0 / h * y + yd
        b0 = (self._m @ (4.0 / h**2 * y + 4.0 / h * yd + ydd) + self._c @ (2.0 / h * y + yd)
              + self._f_ext(time, torque, rim))
        offset, share = self._ring_offset(yd), self._share_offset(yd, rim)
        if offset or share:
            b0 += self._spin_correction(y, yd, ydd, offset, share)
        pen_const = self._pen0 + height * self._sec
        # the runs' ends (carry_edges): the edges of the ring as it starts the step on the
        # road as it ends it (explicit in the ring, as the carry is)
        if contact.any():
            delta = np.maximum(entering_fractions(pen_const + self._jn @ y, contact),
                               self._carry_shift)
            e_conv += carry_edges(e, contact, stick, self._carry_base,
                                  self._carry_weights, delta)
        a_n = self._kn + 2.0 * self._cn / h
        beta_n = self._kn * pen_const + self._cn * (rate * self._sec - self._jn @ r)
        # e = e_conv + h/2 (s_n + s_{n+1}), s = (the ring part) + s0
        # (the rim's forward speed adds to the road's against the axle)
        s0_new = self._s0 + rim[1]
        gamma = (e_conv + 0.5 * h * (s_old - self._jxw @ r)
                 + 0.5 * h * (self._s0 + rim_old[1] + s0_new))
        # the ring's step is linear: y = z0 - Y_n f_n + Y_x f_x with the points' forces,
        # so each pass solves for the 2P forces only (module doc: point laws)
        if self._driven:  # the turn at the step's end, trapezoidal from the rate given
            psi_new = self._driven_psi(y, yd)
            z0 = self._a0_inv @ (b0 - self._a0_psi * psi_new)
            z0[-1] = psi_new
        else:
            z0 = self._a0_inv @ b0
        n_z0 = self._jn @ z0
        t0 = self._kx * gamma + self._cx * (s0_new - self._jxw @ r)
        t_z0 = t0 + self._kg @ z0
        for passes in range(MAX_SET_PASSES):
            f_n, f_x = self._point_forces(contact, stick, slip_sign, a_n, beta_n, n_z0,
                                          t_z0)
            y_new = z0 - self._yn @ f_n + self._yx @ f_x
            pen = pen_const + self._jn @ y_new
            f_trial = a_n * (self._jn @ y_new) + beta_n
            e_trial = gamma + self._gain @ y_new
            tread = t0 + self._kg @ y_new  # the element's pull on the belt, backwards
            new_contact = (pen > 0) & (f_trial > 0)
            limit = self._mu * np.maximum(f_trial, 0.0)
            new_stick = np.abs(tread) <= limit * (1 + 1e-12)
            new_sign = np.where(new_stick, slip_sign, np.sign(tread))
            if passes >= SETTLE_PASSES:
                # a set that cycles (a point sliding, then sticking at the limit, ...):
                # from here a sliding point slides on and a point that let go stays off,
                # so the sets can only shrink and the passes end
                new_stick &= stick | ~contact
                new_contact &= contact
            if sets_settled((contact, stick, slip_sign), (new_contact, new_stick, new_sign)):
                break
            contact, stick, slip_sign = new_contact, new_stick, new_sign
        else:
            raise ContactSetError(f"step at t = {time:g} s: the contact and stick sets "
                                  f"did not settle in {MAX_SET_PASSES} passes")
        f_n = f_trial
        yd_new = 2.0 / h * (y_new - y) - yd
        ydd = 4.0 / h**2 * (y_new - y) - 4.0 / h * yd - ydd
        if self._driven:
            # a driven turn's rate is the host's, linear over the step: its acceleration is
            # that line's slope (the trapezoidal recurrence would carry any change of slope on
            # as an undamped alternation of sign, and the rim's moment with it)
            ydd[-1] = (yd_new[-1] - yd[-1]) / h
        y, yd = y_new, yd_new
        f_n = np.where(contact, f_n, 0.0)
        e = np.where(contact, np.where(stick, e_trial,
                                       slip_sign * limit / np.maximum(self._kx, 1e-300)),
                     0.0)
        return StepState(y, yd, ydd, e, contact, stick, slip_sign, f_n)

    def _driven_psi(self, y, yd) -> float:
        """A driven wheel's turn at the step's end: the trapezoid of its rates, the step's
        start's and the given one (so that the step's ψ̇ is the host's exactly)."""
        return float(y[-1] + 0.5 * self.step_length_s * (yd[-1] + self._driven_rate))

    def _point_forces(self, contact, stick, slip_sign, a_n, beta_n, n_z0, t_z0):
        """(f_n, f_x) of the step for given sets: the point laws with y eliminated, solved
        for the points in contact only (the others carry no force: a third of the zone's
        points at the default load, and the solve is cubic in their count)."""
        p = contact.size
        f_n, f_x = np.zeros(p), np.zeros(p)
        on = np.flatnonzero(contact)
        m = on.size
        if m == 0:
            return f_n, f_x
        st = stick[on]
        sl = ~st
        rows = np.arange(m)
        matrix = np.zeros((2 * m, 2 * m))
        rhs = np.zeros(2 * m)
        block = np.ix_(on, on)
        # contact: f_n - a_n(jn z0 - Wnn f_n + Wnx f_x) = β_n
        a = a_n[on, None]
        matrix[:m, :m] = a * self._wnn[block]
        matrix[:m, m:] = -a * self._wnx[block]
        rhs[:m] = beta_n[on] + a_n[on] * n_z0[on]
        # stick: f_x + t0 + K_G (z0 - Y_n f_n + Y_x f_x) = 0
        sticking = on[st]
        matrix[m + rows[st], :m] = -self._kgn[np.ix_(sticking, on)]
        matrix[m + rows[st], m:] = self._kgx[np.ix_(sticking, on)]
        rhs[m + rows[st]] = -t_z0[sticking]
        # slip: f_x + μσ f_n = 0
        matrix[m + rows[sl], rows[sl]] = self._mu * slip_sign[on[sl]]
        matrix[np.arange(2 * m), np.arange(2 * m)] += 1.0
        forces = np.linalg.solve(matrix, rhs)
        f_n[on], f_x[on] = forces[:m], forces[m:]
        return f_n, f_x

    def _follow_spin(self, yd: np.ndarray, speed: float, ring: bool = True) -> np.ndarray:
        """The step at the road's new speed: s0 always; the tread's terms when the wheel's
        spin has moved by :data:`SPIN_REBUILD_FRACTION` (a free wheel's offset ψ̇ is then
        measured from the new spin); the ring's step when it has moved by
        :data:`RING_REBUILD_FRACTION` from the ring's (up to that the step adds the
        difference's terms explicitly), unless ``ring`` is false."""
        spin = speed / self.model.tire.R if not self._free_spin else self._spin_now + yd[-1]
        scale = max(abs(self._spin_now), 1.0)
        if not self._free_spin and spin != self._spin_now:  # a held wheel's spin is V/R
            self._set_tread_spin(spin, speed)
        elif abs(spin - self._spin_now) > SPIN_REBUILD_FRACTION * scale:
            yd = yd.copy()
            yd[-1] = 0.0
            self._set_tread_spin(spin, speed)
        else:
            self._set_speed(speed)
        if ring and abs(spin - self._ring_spin) > RING_REBUILD_FRACTION * scale:
            self._set_ring_spin(spin)
            self._set_tread_spin(self._spin_now, self._speed_now)
        return yd

    def _f_ext(self, time_s, torque, rim=None) -> np.ndarray:
        f = np.zeros(self._ny)
        if self._free_spin:
            f[-1] = torque(time_s) if callable(torque) else torque
        if rim is not None and (rim[2] or rim[5]):  # a still rim adds nothing
            f -= self._rim_inertia @ rim[[2, 5]]
        return f

    def _slip(self, y, yd) -> np.ndarray:
        """Fore-aft velocity of the tread at each point relative to the road, less s0."""
        return self._jxw @ yd + self._spin_now * (self._jl @ y)

    def _contact_and_rates(self, y, yd, e, time_s, rim):
        height, rate = self.road(time_s, self.speed_m_s * time_s + rim[0],
                                 self._speed_now + rim[1])
        height, rate = height - rim[3], rate - rim[4]
        pen = self._pen0 + height * self._sec + self._jn @ y
        f_n = np.where(pen > 0, np.maximum(self._kn * pen + self._cn * (self._jn @ yd
                                                                        + rate * self._sec),
                                           0.0), 0.0)
        forces = -self._jnw.T @ f_n - self._jxw.T @ (self._kx * e)
        contact = f_n > 0
        return forces, contact, np.ones_like(contact), np.ones(contact.size), f_n

    def rim_force(self, y, yd, ydd=None, rim=None, spin_rad_s: float | None = None
                  ) -> np.ndarray:
        """(Fx, Fz, My) the tire puts on the rim (N, N, N m): the rim's rows of the tire's
        forces at the wheel's spin (:meth:`InPlaneRing.rim_force`; ``spin_rad_s`` takes them
        at another, e.g. the nominal one a linear analysis holds); ``rim`` (x, vx, ax, z, vz,
        az) adds the inertia of the rim's translation."""
        o = self.spin_total_rad_s(yd) if spin_rad_s is None else spin_rad_s
        # the spin's polynomial on the products, not on the rows (the spin moves every step):
        # rows [k0 c0 m; k1 c1 0; k2 0 0; kh 0 0] on [y, ẏ, ÿ], by [1, Ω, Ω², s(Ω)]
        motion = np.concatenate([y, yd, np.zeros_like(y) if ydd is None else ydd])
        f = (self._rim_stack() @ motion).reshape(4, 3).T @ np.array([1.0, o, o * o,
                                                                      self._road_share(rim)])
        if rim is not None:
            f += self._rim_rows["m_translation"] @ rim[[2, 5]]
        return -f

    def rim_force_rows(self, spin_rad_s: float | None = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(K, C, M), each (3, coordinates): the rim's rows of the tire's stiffness, damping
        and mass on the simulator's coordinates at ``spin_rad_s`` (default: the reference
        spin), so that the force on the rim is -(K y + C ẏ + M ÿ) (a host reads it every
        step: the spin's polynomial is put on the coordinates once, and combined per spin)."""
        o = self._spin_now if spin_rad_s is None else spin_rad_s
        self._rim_stack()
        if self._rim_rows_at[0] != o:
            p = self._rim_on_y
            self._rim_rows_at = (o, p["k0"] + o * p["k1"] + o**2 * p["k2"]
                                 + self._share(o) * p["kh"],
                                 p["c0"] + o * p["c1"], p["m"])
        return self._rim_rows_at[1:]

    def _rim_stack(self) -> np.ndarray:
        """The rim's rows of the spin's terms on the coordinates, (12, 3 coordinates):
        [k0 c0 m; k1 c1 0; k2 0 0; kh 0 0] (made once)."""
        if self._rim_on_y is None:
            rows = self._rim_rows
            p = {name: rows[name] @ self._to_abs
                 for name in ("k0", "k1", "k2", "kh", "c0", "c1", "m")}
            zero = np.zeros_like(p["m"])
            self._rim_on_y = p
            self._rim_stack_rows = np.block([[p["k0"], p["c0"], p["m"]],
                                             [p["k1"], p["c1"], zero],
                                             [p["k2"], zero, zero],
                                             [p["kh"], zero, zero]])
        return self._rim_stack_rows

    def static_load_n(self, deflection_m: float | None = None) -> float:
        """The vertical load a deflection (default: the simulator's) carries at rest (N)."""
        return float(self.rim_force(self.static_state(deflection_m), np.zeros(self._ny))[1])


@dataclass(frozen=True)
class InPlaneOutputs:
    """What a host reads after a step (SI): the forces and moment on the rim, the road's
    totals on the tread, the wheel's spin and the points sliding."""

    rim_fx_n: float
    rim_fz_n: float
    rim_my_n_m: float
    contact_fz_n: float
    contact_fx_n: float
    spin_rad_s: float
    sliding_points: int


class InPlaneStepper:
    """:class:`InPlaneSimulator` stepped by a host one communication step at a time, as an
    FMU steps. The host gives, at each communication point t, the rim's fore-aft and vertical
    position and velocity (x, vx, z, vz; m, m/s, deviations from the static state, x forward,
    z up), the torque on the wheel and with ``host_road`` the road at the zone front: the
    values AT t, as every co-simulation master sets them. Over the step to t + h the tire
    extends them as :func:`input_path` says (a position along its rate, the rate along its last
    change; the torque held) and cuts the step into its own (:func:`substeps`). Where the
    host's next values differ from where that extension ended, the rim goes there at once and
    the tire's own motion carries on: its coordinates take the rim's jump off
    (:attr:`InPlaneSimulator.translation_projection`, the tire's momentum kept), so an
    inconsistent input (a position step with its rate zero) moves the rim, not the tire's
    mass, and the forces stay those of the stretched sidewall. A free wheel's spin follows
    the axle's speed.

    The road is the simulator's (its obstacle, at its speed), or with ``host_road`` the one
    the host gives: ``road_z`` and ``road_vz`` at the front of the contact zone, as the radial
    FMU takes them (extended over the step as the rim is, kept along the road as it passes,
    :class:`~.obstacles.HostRoad`). At rest (``sim.speed_m_s`` = 0) the road does not pass,
    and the host's road moves under every point at once, a shaker plate."""

    #: The running limits (set by inplane_host.build_host_stepper; none for a stepper built
    #: directly): the wheel's spin (rad/s) and the road's speed under the axle (m/s), a
    #: fraction of the mesh's critical speed, and the force on the rim (N), MAX_FORCE_LOADS.
    spin_limit_rad_s = math.inf
    speed_limit_m_s = math.inf
    force_limit_n = math.inf
    #: what the limits' messages cite: the critical speed (m/s) and the load (N)
    critical_speed_m_s = math.nan
    load_n = math.nan

    def __init__(self, sim: InPlaneSimulator, torque_n_m: float = 0.0, host_road: bool = False,
                 position_road=None):
        """Start from the static state, with ``torque_n_m`` on the wheel at t = 0.
        ``position_road``: the road by position along it (anything with
        ``window_reads(s_lo, s_hi, speed)``: a road file's ProfileRoad, the host's
        PositionRoad), read at the wheel centre's position at every step of the tire's: the
        wheel-centre mode of :meth:`advance_wheel` (the FMUs')."""
        self.sim = sim
        self.road: HostRoad | None = None
        self.position_road = position_road
        # where the wheel-centre mode's coordinates start: the wheel's position along the road
        # and the road's height under it at the first step (None before it)
        self._origin: tuple[float, float] | None = None
        if host_road:
            if sim.obstacle is not None:
                raise ValueError("InPlaneStepper(host_road=True): the simulator already has "
                                 "a road (its obstacle); build it without one")
            front, rear = float(sim._x_hi.max()), float(sim._x_lo.min())
            # the windows reach back to the zone's rear; the rim may move back by the
            # largest displacement a host may give
            self.road = HostRoad(front, front - rear + HOST_ROAD_MARGIN_M)
            self.road.record(0.0, 0.0)
            sim.obstacle, sim.obstacle_ahead_m = self.road, 0.0  # the road travels from here
        sim.set_step_length(sim.step_s)
        sim._set_spin(sim.spin_rad_s, sim.speed_m_s)
        ny = sim._ny
        y = sim.static_state()
        e = np.zeros(sim._zone.n_points)
        self._rim = np.zeros(6)
        forces = sim._contact_and_rates(y, np.zeros(ny), e, 0.0, self._rim)
        load = sim._f_ext(0.0, torque_n_m, self._rim) + forces[0] - sim._k @ y
        if sim._driven:  # the host's wheel starts at its steady spin: ψ̈ = 0
            ydd = np.zeros(ny)
            ydd[:-1] = np.linalg.solve(sim._m[:-1, :-1], load[:-1])
        else:
            ydd = np.linalg.solve(sim._m, load)
        self.state = StepState(y, np.zeros(ny), ydd, e, *forces[1:5])
        self.steps = 0  # the tire's own steps taken
        self.elapsed_s, self._carry_s = 0.0, 0.0  # their lengths summed (clock.advance)
        # the host's values at the last communication point (x, vx, z, vz, road z, road vz),
        # the wheel_rate given there and the step that followed (0 before the first step):
        # the rates' last change is the extension's acceleration
        self._given = np.zeros(6)
        self._rate_given = 0.0
        self._h_given = 0.0
        self._accel, self._h_accel = np.zeros(3), 0.0

    @property
    def time_s(self) -> float:
        return self.elapsed_s

    def advance(self, step_s: float, x_m: float = 0.0, vx_m_s: float = 0.0, z_m: float = 0.0,
                vz_m_s: float = 0.0, torque_n_m: float = 0.0, road_z_m: float = 0.0,
                road_vz_m_s: float = 0.0, wheel_rate_rad_s: float = 0.0,
                at_time_s: float = 0.0) -> InPlaneOutputs:
        """Advance by ``step_s`` from the communication point where the rim's state (and with
        ``host_road`` the road's at the zone front) is the one given (the values at the
        step's start); returns the outputs at its end. ``at_time_s`` is the host's time there
        (only the resolution of its clock is read, :func:`substeps`). A driven wheel
        (``sim.wheel == "driven"``) spins at ``speed / R + wheel_rate_rad_s`` at the step's
        start; over the step its spin goes on linearly from the tire's to that rate extended
        by its last change (its turn itself is immaterial: a rigid turn of the rim and tire
        stores nothing); ``torque_n_m`` is then not read, else it is held over the step."""
        sim = self.sim
        count, h = substeps(step_s, sim.step_s, at_time_s)
        sim.set_step_length(h)
        given = np.array([x_m, vx_m_s, z_m, vz_m_s, road_z_m, road_vz_m_s], dtype=float)
        known = self._h_given > 0.0
        accel, jerk = rate_changes(given[1::2], self._given[1::2], self._h_given,
                                   self._accel, self._h_accel)
        paths = [input_path(given[2 * i], given[2 * i + 1], accel[i], jerk[i])
                 for i in range(3)]
        # the last change of the rates, over the step it was made in (0: none yet)
        self._accel = (given[1::2] - self._given[1::2]) / self._h_given if known else accel
        self._h_accel = self._h_given
        self._take_rim_jump(given)
        if sim._driven:  # the wheel's spin at the start and the end (rad/s)
            spin_start = sim.spin_total_rad_s(self.state.yd)
            change = ((wheel_rate_rad_s - self._rate_given) / self._h_given * step_s
                      if known else 0.0)
            spin_end = sim.spin_rad_s + wheel_rate_rad_s + change
        rim, road, plate = self._rim, self.road, sim.speed_m_s == 0.0
        x_path, z_path, front_path = paths
        rim = np.array([*x_path(0.0), *z_path(0.0)])
        start_s = self.elapsed_s
        for k in range(1, count + 1):
            self.steps += 1
            tau = k * h
            time = start_s + tau
            rim_old, rim = rim, np.array([*x_path(tau), *z_path(tau)])
            if sim._free_spin:
                # the ring's step (an inverse) rebuilt at most once a communication step, at
                # its start: the work a step may take is bounded (step_work)
                self.state.yd = sim._follow_spin(self.state.yd, sim.speed_m_s, ring=k == 1)
            if sim._driven:
                spin = spin_start + (spin_end - spin_start) * (k / count)
                sim._driven_rate = spin - sim._spin_now
            distance = sim.speed_m_s * time + rim[0]
            if self.position_road is not None:
                x_origin, z_origin = self._origin
                height, rate = self.position_road.window_reads(
                    sim._x_lo + (x_origin + distance), sim._x_hi + (x_origin + distance),
                    sim._speed_now + rim[1])
                height = height - z_origin
            elif road is not None:
                front, front_rate, _ = front_path(tau)
                if plate:
                    height = np.full(sim._zone.n_points, front)
                    rate = np.full(sim._zone.n_points, front_rate)
                else:
                    road.record(distance, front)
                    speed = sim._speed_now + rim[1]
                    if sim._kernel is not None:  # the same reads in C
                        height, rate = sim._kernel.window_reads(road, distance, speed)
                    else:
                        height, rate = road.window_reads(sim._x_lo + distance,
                                                         sim._x_hi + distance, speed)
            else:
                height, rate = sim.road(time, distance, sim._speed_now + rim[1])
            self.state = sim._step(self.state, time, torque_n_m, rim_old, rim,
                                   height - rim[3], rate - rim[4])
            self._check_running(time, sim.spin_total_rad_s(self.state.yd),
                                sim._speed_now + rim[1])
        self._rim = rim
        self.elapsed_s, self._carry_s = clock.advance(self.elapsed_s, self._carry_s, count * h)
        self._given, self._rate_given, self._h_given = given, float(wheel_rate_rad_s), step_s
        out = self.outputs()
        force = max(abs(out.rim_fz_n), abs(out.rim_fx_n))
        if not force <= self.force_limit_n:
            raise RunningLimitError(FORCE_LIMIT_TEMPLATE % (self.elapsed_s, force,
                                                            MAX_FORCE_LOADS, self.load_n))
        return out

    def _check_running(self, time_s: float, spin_rad_s: float, speed_m_s: float) -> None:
        """The running limits after a step of the tire's: refused (RunningLimitError) where
        the wheel's spin or the road's speed left the range the tire was built for."""
        if not abs(spin_rad_s) <= self.spin_limit_rad_s:
            raise RunningLimitError(SPIN_LIMIT_TEMPLATE % (
                time_s, spin_rad_s, self.spin_limit_rad_s, _critical_fraction(),
                self.critical_speed_m_s))
        if not abs(speed_m_s) <= self.speed_limit_m_s:
            raise RunningLimitError(SPEED_LIMIT_TEMPLATE % (
                time_s, speed_m_s, self.speed_limit_m_s, _critical_fraction(),
                self.critical_speed_m_s))

    def advance_wheel(self, step_s: float, wheel_x_m: float, wheel_vx_m_s: float,
                      wheel_z_m: float, wheel_vz_m_s: float, torque_n_m: float = 0.0,
                      wheel_spin_rad_s: float | None = None, at_time_s: float = 0.0,
                      road_positions=None, road_heights=None) -> InPlaneOutputs:
        """Advance by ``step_s`` from the wheel centre's state at the step's start: its position
        along the road and height above the road's datum (m), their rates (m/s), the torque,
        and a driven wheel's spin (rad/s). The road is :attr:`position_road`'s, read at the
        wheel's position; the tire is the one built at ``sim.speed_m_s`` and its static load,
        its rim at the loaded radius above the road there. The coordinates start at the first
        step's position and the road's height under it, so that nothing far from the road's
        origin enters a step's arithmetic. ``road_positions`` and ``road_heights``: the host's
        road there (the samples its road_queries asked for), taken before the step."""
        if self.position_road is None:
            raise ValueError("advance_wheel: the stepper has no position_road (the FMUs' "
                             "wheel-centre mode); advance() takes the deviation inputs")
        sim = self.sim
        if road_positions is not None:
            self.position_road.set_samples(road_positions, road_heights)
        if self._origin is None:
            self._origin = (float(wheel_x_m), self.road_height(wheel_x_m))
        x_origin, z_origin = self._origin
        rate = 0.0 if wheel_spin_rad_s is None else wheel_spin_rad_s - sim.spin_rad_s
        return self.advance(step_s, wheel_x_m - x_origin - sim.speed_m_s * self.elapsed_s,
                            wheel_vx_m_s - sim.speed_m_s,
                            wheel_z_m - z_origin - self.loaded_radius_m, wheel_vz_m_s,
                            torque_n_m, 0.0, 0.0, rate, at_time_s)

    @property
    def loaded_radius_m(self) -> float:
        """The wheel centre's height above a flat road when the tire carries its static load
        (m): the tread radius less the static deflection (a host places its wheel so)."""
        return self.sim.model.tire.R - self.sim.deflection_m

    def road_height(self, x_m: float) -> float:
        """The road's height at ``x_m`` along it (m, in the road's datum)."""
        height, _ = self.position_road.profile(np.array([float(x_m)]))
        return float(height[0])

    def wheel_centre(self) -> tuple[float, float, float]:
        """Where the last step left the wheel centre (m, m/s, m): its position along the road,
        its speed and its height above the road's datum, on the path the step extended the
        host's values along (the host gives the values at the next step's start after)."""
        x_origin, z_origin = self._origin
        sim, rim = self.sim, self._rim
        return (x_origin + sim.speed_m_s * self.elapsed_s + rim[0], sim.speed_m_s + rim[1],
                z_origin + self.loaded_radius_m + rim[3])

    def wheel_outputs(self, wheel_x_m: float, wheel_vx_m_s: float, wheel_z_m: float
                      ) -> dict[str, float]:
        """What a host reads besides the forces, with the wheel centre at ``wheel_x_m``,
        ``wheel_vx_m_s``, ``wheel_z_m`` (:meth:`wheel_centre` after a step): the loaded radius
        (the wheel centre's height above the road under it), the effective rolling radius
        (speed over spin; R when the wheel barely turns), the longitudinal slip ((spin R -
        speed) / max(|speed|, 0.1 m/s), R the tread radius) and the contact length (the road
        the pushing points' windows cover)."""
        sim, st = self.sim, self.state
        spin = sim.spin_total_rad_s(st.yd)
        radius = sim.model.tire.R
        on = np.flatnonzero(st.f_n > 0.0)
        return {
            "loaded_radius": float(wheel_z_m - self.road_height(wheel_x_m)),
            "effective_rolling_radius": float(effective_rolling_radius(wheel_vx_m_s, spin,
                                                                       radius)),
            "longitudinal_slip": float(longitudinal_slip(spin, radius, wheel_vx_m_s)),
            "contact_length": (float(sim._x_hi[on].max() - sim._x_lo[on].min()) if on.size
                               else 0.0),
        }

    def road_queries(self, count: int, wheel_x_m: float, wheel_vx_m_s: float,
                     step_s: float) -> np.ndarray:
        """Where the tire needs the host's road next (m along it): :func:`.wheel_centre.
        road_queries` for this tire's contact zone and points."""
        sim = self.sim
        held = self.position_road.s if hasattr(self.position_road, "s") else np.zeros(0)
        return road_queries(count, wheel_x_m, wheel_vx_m_s, step_s, float(sim._x_lo.min()),
                            float(sim._x_hi.max()), sim.point_spacing_m, held)

    def _road_store(self):
        """The road whose samples are part of the state: the legacy HostRoad, or the host's
        PositionRoad (a road file's is the file's: nothing to keep)."""
        if self.road is not None:
            return self.road
        return self.position_road if hasattr(self.position_road, "restore") else None

    def _take_rim_jump(self, given: np.ndarray) -> None:
        """The rim from where the last step's extension left it to the host's values now: its
        jump (position and rate) is taken off the tire's coordinates, so that the tire's own
        motion (its momentum) carries on through it."""
        rim = self._rim
        dp = np.array([given[0] - rim[0], given[2] - rim[3]])
        dv = np.array([given[1] - rim[1], given[3] - rim[4]])
        if not (dp.any() or dv.any()):
            return
        projection = self.sim.translation_projection
        st = self.state
        st.y = st.y - projection @ dp
        st.yd = st.yd - projection @ dv

    def outputs(self) -> InPlaneOutputs:
        """What the host reads at the last step's end."""
        sim, st = self.sim, self.state
        fx, fz, my = sim.rim_force(st.y, st.yd, st.ydd, self._rim)
        return InPlaneOutputs(
            float(fx), float(fz), float(my), float(st.f_n.sum()),
            float(-(sim._kx * st.e).sum()),
            float(sim._spin_now + (st.yd[-1] if sim._free_spin else 0.0)),
            int(np.sum(st.contact & ~st.stick)))

    def checkpoint(self) -> tuple:
        """What :meth:`rollback` needs to undo the steps after it (cheap: a step makes a new
        StepState, and the host's road only appends or rewrites its newest sample)."""
        sim, road = self.sim, self.road
        kept_road = None
        if road is not None:
            last = road._buffer[:, road._hi - 1].copy() if road._hi > road._lo else None
            kept_road = (road._buffer, road._lo, road._hi, last)
        elif hasattr(self.position_road, "state"):  # the host's samples (a few hundred)
            kept_road = self.position_road.state()
        return (StepState(**vars(self.state)), self.steps, self.elapsed_s, self._carry_s,
                self._given, self._rate_given, self._h_given, self._accel, self._h_accel,
                self._rim, sim.step_length_s,
                sim._ring_spin, sim._spin_now, sim._speed_now, sim._s0, kept_road,
                self._origin)

    def rollback(self, checkpoint: tuple) -> None:
        """Back to the :meth:`checkpoint` (a step that failed leaves the stepper as it was)."""
        (state, steps, elapsed, carry, given, rate_given, h_given, accel, h_accel, rim, length,
         ring_spin, spin, speed, s0, kept_road, origin) = checkpoint
        self._origin = origin
        self.sim._take_spins(ring_spin, spin, speed, length)
        self.sim._s0 = s0
        self.state, self.steps, self._rim = state, steps, rim
        self.elapsed_s, self._carry_s = elapsed, carry
        self._given, self._rate_given, self._h_given = given, rate_given, h_given
        self._accel, self._h_accel = accel, h_accel
        if kept_road is not None and self.road is None:
            self.position_road.restore(kept_road)
        elif kept_road is not None:
            buffer, lo, hi, last = kept_road
            road = self.road
            road._buffer, road._lo, road._hi = buffer, lo, hi
            if last is not None:
                buffer[:, hi - 1] = last

    # -- the stepper's state as bytes (an FMU's state): everything a step reads ---------------
    def state_bytes(self) -> bytes:
        """The stepper's state: :data:`STEPPER_STATE_HEAD`, then the doubles
        (:data:`STEPPER_SCALARS` scalars, y, ẏ, ÿ, e, f_n, the road's samples) and flags."""
        st, sim = self.state, self.sim
        store = self._road_store()
        road = store.state() if store is not None else np.zeros((0, 3))
        to_abs = sim._to_abs
        head = struct.pack(STEPPER_STATE_HEAD, STEPPER_STATE_MAGIC, st.y.size, st.e.size,
                           road.shape[0], self.steps, to_abs.shape[0], sim.basis_fingerprint)
        scalars = [*self._given, *self._rim, sim._spin_now, sim._speed_now, sim._ring_spin,
                   self._rate_given, self._h_given, self.elapsed_s, self._carry_s,
                   sim.step_length_s, *self._accel, self._h_accel,
                   *(self._origin if self._origin is not None else (math.nan, math.nan))]
        # the coordinates, and what they are in the tire's own DOFs (what another basis of the
        # same tire takes them back from)
        dofs = to_abs @ np.column_stack([st.y, st.yd, st.ydd])
        doubles = np.concatenate([scalars, st.y, st.yd, st.ydd, st.e, st.f_n, road.ravel(),
                                  dofs.T.ravel()])
        flags = np.concatenate([st.contact, st.stick]).astype(np.int8)
        return head + doubles.astype("<f8").tobytes() + flags.tobytes() + np.asarray(
            st.slip_sign, dtype=np.int8).tobytes()

    def state_problem(self, data: bytes) -> str | None:
        """Why ``data`` is no state of this stepper, or None."""
        head = struct.calcsize(STEPPER_STATE_HEAD)
        if len(data) < head:
            return f"its stepper part is {len(data)} bytes, shorter than its header"
        magic, ny, points, samples, steps, n_dof, _ = struct.unpack_from(STEPPER_STATE_HEAD,
                                                                         data)
        if magic != STEPPER_STATE_MAGIC:
            return "its stepper part is not an in-plane tire's"
        own_dof = self.sim._to_abs.shape[0]
        if n_dof != own_dof or points != self.state.e.size:
            return (f"its stepper part has {n_dof} DOFs and {points} points, this tire "
                    f"{own_dof} and {self.state.e.size}")
        store = self._road_store()
        if (samples > 0 and store is None) or (isinstance(store, HostRoad) and samples == 0) \
                or steps < 0:
            return "its stepper part's road or step count does not fit this tire"
        if not 0 < ny <= n_dof:
            return f"its stepper part has {ny} coordinates for {n_dof} DOFs"
        if samples > min((len(data) - head) // 24, MAX_ROAD_SAMPLES):
            return (f"its road history holds {samples} samples; the tire keeps at most "
                    f"{MAX_ROAD_SAMPLES} (one a step over the zone's reach)")
        doubles = STEPPER_SCALARS + 3 * ny + 2 * points + 3 * samples + 3 * n_dof
        if len(data) != head + 8 * doubles + 3 * points:
            return "its stepper part has the wrong size"
        values = np.frombuffer(data, "<f8", doubles, head)
        origin = values[24:26]
        finite = np.isfinite(values)
        finite[24:26] = np.all(np.isfinite(origin)) or np.all(np.isnan(origin))
        if not np.all(finite):
            return "its stepper part holds values that are not finite"
        flags = np.frombuffer(data, np.int8, 3 * points, head + 8 * doubles)
        if np.any((flags[:2 * points] != 0) & (flags[:2 * points] != 1)) or np.any(
                np.abs(flags[2 * points:]) > 1):
            return "its stepper part's contact flags are not flags"
        spin, speed, ring_spin = values[12], values[13], values[14]
        h_given, elapsed, length, h_accel = values[16], values[17], values[19], values[23]
        if speed != self.sim.speed_m_s:
            return f"its road speed {speed!r} m/s is not this tire's {self.sim.speed_m_s!r}"
        most = (self.spin_limit_rad_s if math.isfinite(self.spin_limit_rad_s)
                else STATE_SPIN_FACTOR * max(self.sim.spin_rad_s, 1.0))
        for value in (spin, ring_spin):
            if not abs(value) <= most:
                return f"its wheel spin {value!r} rad/s is beyond what this tire can hold"
        if not (0.0 <= h_given and 0.0 <= h_accel and 0.0 <= elapsed
                and MIN_STEP_S <= length <= self.sim.step_s):
            return (f"its clock (elapsed {elapsed!r} s, last step {h_given!r} s, the tire's "
                    f"step {length!r} s) is no clock of this tire (step_size "
                    f"{self.sim.step_s!r} s)")
        if samples > 1:
            road_at = STEPPER_SCALARS + 3 * ny + 2 * points
            s = values[road_at:road_at + 3 * samples:3]
            if not np.all(np.diff(s) > 0):
                return "its road's samples are not in order along the road"
        coordinates, problem = self._state_coordinates(data)
        if problem:
            return problem
        return self._state_meaning_problem(values, coordinates, ny, points)

    def _state_meaning_problem(self, values, coordinates, ny: int, points: int) -> str | None:
        """What a state of sound layout must mean to be this tire's: the tire's deformation
        within what its zone and the road's reach allow, and the forces it gives (on the rim,
        at each point) within the running limit (a forged coordinate of 1000 gave 5e16 N)."""
        sim = self.sim
        y, yd, ydd = coordinates
        # the ring's DOFs relative to the rim (the wheel's turn, which grows as it rolls, out)
        cols = y.size - 1 if sim._free_spin else y.size
        deformation = np.abs(sim._to_abs[:-3, :cols] @ y[:cols]).max(initial=0.0)
        if not deformation <= STATE_DEFORMATION_FRACTION * sim.model.tire.R:
            return (f"its tire deforms by {deformation:.3g} m, beyond the "
                    f"{STATE_DEFORMATION_FRACTION * sim.model.tire.R:.3g} m a state may hold "
                    f"({STATE_DEFORMATION_FRACTION:g} of R)")
        rim = values[6:12]
        spin = values[12] + (yd[-1] if sim._free_spin else 0.0)
        force = np.abs(sim.rim_force(y, yd, ydd, rim, spin_rad_s=spin)[:2]).max()
        at = STEPPER_SCALARS + 3 * ny
        e, f_n = values[at:at + points], values[at + points:at + 2 * points]
        point = max(np.abs(f_n).max(initial=0.0), np.abs(sim._kx * e).max(initial=0.0))
        limit = self.force_limit_n
        if math.isfinite(limit) and not max(force, point) <= limit:
            return (f"its forces reach {max(force, point):.4g} N (on the rim {force:.4g} N, at "
                    f"a point {point:.4g} N), beyond {MAX_FORCE_LOADS:g} times the load "
                    f"({self.load_n:.6g} N)")
        return None

    def _state_coordinates(self, data: bytes) -> tuple[np.ndarray | None, str | None]:
        """(y, ẏ, ÿ) of a state whose layout is sound, in this simulator's coordinates: its own
        where its basis is this one's (the same fingerprint), else its DOFs taken into this
        basis; or why they cannot be."""
        head = struct.calcsize(STEPPER_STATE_HEAD)
        _, ny, p, samples, _, n_dof, fingerprint = struct.unpack_from(STEPPER_STATE_HEAD, data)
        values = np.frombuffer(data, "<f8", STEPPER_SCALARS + 3 * ny + 2 * p + 3 * samples
                               + 3 * n_dof, head)
        sim = self.sim
        if fingerprint == sim.basis_fingerprint and ny == self.state.y.size:
            return values[STEPPER_SCALARS:STEPPER_SCALARS + 3 * ny].reshape(3, ny).copy(), None
        dofs = values[-3 * n_dof:].reshape(3, n_dof).T
        y, off = sim.coordinates_of(dofs)
        if y is None:
            return None, (f"its tire's shape lies outside this FMU's reduced basis ({off:.2g} of "
                          "it): it was stepped in a basis built differently (another BLAS, "
                          "thread count or CPU can build the modes otherwise), whose span this "
                          "build does not reproduce; restore it in the process that saved it")
        return y.T.copy(), None

    def set_state_bytes(self, data: bytes) -> None:
        """Take back a state :meth:`state_bytes` wrote (checked with :meth:`state_problem`)."""
        problem = self.state_problem(data)
        if problem:
            raise ValueError(problem)
        head = struct.calcsize(STEPPER_STATE_HEAD)
        _, ny, p, samples, steps, n_dof, _ = struct.unpack_from(STEPPER_STATE_HEAD, data)
        doubles = STEPPER_SCALARS + 3 * ny + 2 * p + 3 * samples + 3 * n_dof
        values = np.frombuffer(data, "<f8", doubles, head).copy()
        flags = np.frombuffer(data, np.int8, 3 * p, head + 8 * doubles)
        cut = np.cumsum([6, 6, 3, 5, 4, 2, ny, ny, ny, p, p, 3 * samples])
        given, rim, spins, clocks, changes, origin, _, _, _, e, f_n, road, _ = np.split(values,
                                                                                      cut)
        self._origin = None if np.isnan(origin[0]) else (float(origin[0]), float(origin[1]))
        (y, yd, ydd), _ = self._state_coordinates(data)
        rate_given, h_given, elapsed, carry, length = (float(v) for v in clocks)
        self._accel, self._h_accel = changes[:3].copy(), float(changes[3])
        self.sim._take_spins(float(spins[2]), float(spins[0]), float(spins[1]), length)
        self.state = StepState(y, yd, ydd, e, flags[:p] == 1, flags[p:2 * p] == 1,
                               flags[2 * p:].astype(float), f_n)
        self._given, self._rim, self.steps = given, rim, int(steps)
        self._rate_given, self._h_given = rate_given, h_given
        self.elapsed_s, self._carry_s = elapsed, carry
        store = self._road_store()
        if store is not None:
            store.restore(road)


#: A host's road is kept this far behind the zone's rear (m): the rim may move back by up to
#: the largest displacement an FMU input takes.
HOST_ROAD_MARGIN_M = 1.0
#: A state's spins may be at most this many times the nominal one (or 1 rad/s).
STATE_SPIN_FACTOR = 10.0
#: The stepper's state: magic, coordinates, points, road samples, the tire's steps taken, the
#: tire's absolute DOFs and its basis' fingerprint (InPlaneSimulator.basis_fingerprint).
STEPPER_STATE_HEAD = "<8sIIIqII"
#: The most a state's tire may deform (any DOF from the rim, a fraction of R): the static
#: deflection itself is at most inplane_host.MAX_DEFLECTION_FRACTION of R.
STATE_DEFORMATION_FRACTION = 0.5
#: The most road samples a state may hold: one a step of the tire's over the zone's reach
#: (step_limits.MAX_HISTORY_SAMPLES, the radial tire's rule).
MAX_ROAD_SAMPLES = MAX_HISTORY_SAMPLES
#: How far (relative) a state's DOFs may lie outside the basis they are restored into: a basis
#: of the same span reproduces them to rounding.
STATE_BASIS_TOLERANCE = 1e-9
STEPPER_STATE_MAGIC = b"INPLANE3"
#: Its scalars: the host's values at the last communication point (6), the rim (6), the
#: spins (the tread's, the road speed, the ring's), the wheel_rate given, the last host step,
#: the elapsed time and its Kahan carry, the tire's step length, the rates' last change (3)
#: and the step it was made over, the wheel-centre mode's origin (position, road height; nan
#: before its first step).
STEPPER_SCALARS = 26


def step_work(ny: int, points: int) -> float:
    """The work of one of the in-plane tire's own steps (step_limits' units, about one
    multiply-add): the ring's dense products on its coordinates, the points' Jacobians and
    responses over a few passes of the sets, the dense solve of the points in contact (a
    third of them at the load)."""
    return 8.0 * ny * ny + 24.0 * points * ny + math.floor(points**3 / 27.0) + 1000.0


def rebuild_work(ny: int, points: int) -> float:
    """The work of rebuilding the ring's step (its inverse and the points' responses): at most
    twice a communication step (its length, its spin)."""
    return float(ny) ** 3 + 4.0 * points * float(ny) ** 2


def host_step_work(step_s: float, tire_step_s: float, ny: int, points: int,
                   at_time_s: float = 0.0) -> tuple[int, float, int, float, bool]:
    """What a host's step costs: (the tire's steps, their length, the work of each with the
    rebuilds shared out, the longest host step within MAX_STEP_WORK, whether it exceeds it)."""
    from .step_limits import MAX_STEP_WORK

    count, length = substeps(step_s, tire_step_s, at_time_s)
    each, rebuilds = step_work(ny, points), 2.0 * rebuild_work(ny, points)
    per = min(each + math.ceil(rebuilds / count), 2147483647.0)
    longest = max(math.floor((MAX_STEP_WORK - rebuilds) / each), 0.0) * tire_step_s
    return count, length, int(per), longest, count * each + rebuilds > MAX_STEP_WORK


def _critical_fraction() -> float:
    from .inplane_host import CRITICAL_SPEED_FRACTION  # the host's rule (no import circle)

    return CRITICAL_SPEED_FRACTION


def _not_driven(sim: InPlaneSimulator, what: str) -> None:
    """The modes and steady states are the tire's with its wheel free or held: a driven
    wheel's turn is the host's, not the tire's."""
    if sim.wheel == "driven":
        raise ValueError(f"{what}: wheel = 'driven' turns as a host says; build the simulator "
                         "with wheel = 'free' (the wheel's inertia in the tire) or 'held'")


@dataclass(frozen=True, eq=False)
class LoadedModes:
    """Modes of the pressed tire at rest, linearised about its static footprint: the points in
    contact as springs k_p on their penetration, the tread elements sticking (k_x on the
    material's fore-aft displacement), the wheel free to turn or held."""

    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    kinds: tuple[str, ...]  # "rotational" for the mode the wheel's turn dominates, else ""
    shapes: np.ndarray  # (ny, modes)
    points_in_contact: int


def loaded_modes(sim: InPlaneSimulator, f_max_hz: float = 200.0) -> LoadedModes:
    """The loaded tire's modes at rest (``sim.speed_m_s`` must be 0), lowest first.

    The footprint's springs act on the rim-relative geometry and do work on the material's
    motion (module doc): with the wheel free, the moment of a change of pressure turns it but
    turning it moves no geometry, so K is not symmetric; the eigenproblem is the general one.
    The mode whose kinetic energy is most in the wheel's rotation ψ is labelled rotational."""
    if sim.speed_m_s != 0.0:
        raise ValueError("loaded_modes: the tire at rest only (speed_m_s = 0)")
    _not_driven(sim, "loaded_modes")
    import scipy.linalg

    y = sim.static_state()
    pen = sim._pen0 + sim._jn @ y
    active = pen > 0
    k = sim._k + sim._jnw[active].T @ (sim._kn[active, None] * sim._jn[active])
    k = k + sim._jxw[active].T @ (sim._kx[active, None] * sim._jxw[active])
    c = sim._c + sim._jnw[active].T @ (sim._cn[active, None] * sim._jn[active])
    c = c + sim._jxw[active].T @ (sim._cx[active, None] * sim._jxw[active])
    # undamped frequencies from (K, M); each mode's damping from the damping it meets
    lam, vectors = scipy.linalg.eig(k, sim._m)
    keep = (lam.real > 0) & (np.sqrt(np.abs(lam)) / (2 * np.pi) <= f_max_hz)
    lam, vectors = lam[keep].real, np.real(vectors[:, keep])
    order = np.argsort(lam)
    lam, vectors = lam[order], vectors[:, order]
    omega = np.sqrt(lam)
    modal_mass = np.einsum("ij,ij->j", vectors, sim._m @ vectors)
    zeta = np.einsum("ij,ij->j", vectors, c @ vectors) / (2 * omega * modal_mass)
    # the rotational mode: the largest share of its kinetic energy in turning, of the tread
    # as a whole (its mean tangential displacement) and of the wheel
    t, tang = sim.model.tire, sim.model.tangential
    v = sim._ring.field_slice("v")
    wheel_turn = vectors[-1] if sim._free_spin else np.zeros(lam.size)
    ring_part = vectors[: sim._n_ring_coords]
    if sim._basis is not None:
        ring_part = sim._basis[: sim._ring.n_ring_dof, : sim._n_ring_coords] @ ring_part
    tread_turn = ring_part[v].mean(axis=0) / t.R + wheel_turn
    tread_inertia = 2 * np.pi * t.R**3 * t.rhoA
    turning = (tread_inertia * tread_turn**2 + tang.wheel_inertia_kg_m2 * wheel_turn**2) / (
        modal_mass)
    kinds = [""] * lam.size
    kinds[int(np.argmax(turning))] = "rotational"
    return LoadedModes(omega / (2 * np.pi), zeta, tuple(kinds), vectors, int(active.sum()))


@dataclass(frozen=True)
class SteadyRolling:
    """The tire rolling steadily under a torque: rim force, spin, slip, tread elements."""

    rim_fx_n: float
    rim_fz_n: float
    rim_my_n_m: float
    spin_rad_s: float  # the wheel's spin: nominal V/R plus the steady offset
    slip_ratio: float  # (spin R - V)/V with R the tread radius (negative braking)
    sliding_points: int
    element_deflection_m: np.ndarray  # e at the points
    state: np.ndarray  # y with the wheel's spin offset in the ψ slot


def steady_rolling(sim: InPlaneSimulator, torque_n_m: float = 0.0) -> SteadyRolling:
    """The steady state of :class:`InPlaneSimulator` on a flat road, solved directly (no time
    stepping): ∂/∂t = 0 in the ground frame, the ring rim-relative and still, the wheel turning
    at a steady offset ω from the nominal spin (ψ = ωt), and the tread elements' field solving
    Ω de/dθ = s along the points (trapezoidal from the front, an element entering at the
    road's edge, :func:`entering_fractions`). The contact and stick sets, and the edges, are
    iterated as in a step. With the wheel held, ω = 0 and the torque is what holds it.

    The spin's terms (the ring's C and K, the elements' transport) are the nominal spin's:
    the solve is linear about it, as :mod:`.inplane_rolling_modes` is (a step takes them at
    the wheel's actual spin; at the slip of a −3 kN m brake the two settle within the
    tolerance the tests state)."""
    if sim.obstacle is not None:
        raise ValueError("steady_rolling: a flat road only (obstacle = None)")
    _not_driven(sim, "steady_rolling")
    if sim.spin_rad_s <= 0.0:
        raise ValueError("steady_rolling: the tire must roll (speed_m_s > 0)")
    sim._take_spins(sim.spin_rad_s, sim.spin_rad_s, sim.speed_m_s)  # after a run: nominal
    nr, ny, p = sim._n_ring_coords, sim._ny, sim._zone.n_points
    omega = sim.spin_rad_s
    spacing = np.diff(sim._zone.point_theta).mean()
    # unknowns u = [y_rel (nr), ω (if free), e (P)]: the ring's rows, then the elements'
    nu = ny + p
    ring_cols = slice(0, ny)
    # s = A_s u_ring + s0: the material's fore-aft speed against the road
    a_s = omega * sim._jl.copy()
    if sim._free_spin:
        a_s[:, -1] = sim._jxw[:, -1]
    base = np.zeros((ny, ny))
    base[:, :nr] = sim._k[:, :nr]
    if sim._free_spin:
        base[:, -1] = sim._c[:, -1]  # the wheel's steady turn meets the damping (Coriolis)
    rhs_ring = sim._f_ext(0.0, torque_n_m)
    contact = sim._pen0 > 0
    stick = np.ones(p, dtype=bool)
    sign = np.ones(p)
    delta = entering_fractions(sim._pen0, contact)
    for _ in range(MAX_SET_PASSES):
        a = np.zeros((nu, nu))
        b = np.zeros(nu)
        a[:ny, ring_cols] = base
        b[:ny] = rhs_ring
        c = contact
        # normal pushes: + Jnᵀ k (pen0 + Jn y) on the left
        a[:ny, ring_cols] += sim._jnw[c].T @ (sim._kn[c, None] * sim._jn[c])
        b[:ny] -= sim._jnw[c].T @ (sim._kn[c] * sim._pen0[c])
        st, sl = c & stick, c & ~stick
        # sticking elements pull with -(k_x e + c_x s): -J_xᵀ f_x = J_xᵀ(k_x e + c_x s)
        rows = np.flatnonzero(st)
        a[:ny, ny + rows] += sim._jxw[rows].T * sim._kx[rows]
        a[:ny, ring_cols] += sim._jxw[rows].T @ (sim._cx[rows, None] * a_s[rows])
        b[:ny] -= sim._jxw[rows].T @ (sim._cx[rows] * sim._s0[rows])
        # sliding ones pull with -σ μ f_n
        rows = np.flatnonzero(sl)
        mu_sign = sim._mu * sign[rows]
        a[:ny, ring_cols] += sim._jxw[rows].T @ ((mu_sign * sim._kn[rows])[:, None]
                                                  * sim._jn[rows])
        b[:ny] -= sim._jxw[rows].T @ (mu_sign * sim._kn[rows] * sim._pen0[rows])
        # the elements' field
        for j in range(p):
            row = ny + j
            a[row, ny + j] = 1.0
            if not c[j]:
                continue  # e = 0 off the road
            if sl[j]:  # held at the friction limit
                a[row, ring_cols] -= sign[j] * sim._mu * sim._kn[j] / sim._kx[j] * sim._jn[j]
                b[row] = sign[j] * sim._mu * sim._kn[j] * sim._pen0[j] / sim._kx[j]
                continue
            entering = j == 0 or not c[j - 1]
            # from the road's edge δ_j spacings ahead, or trapezoidal from the point ahead
            weight = spacing / omega * (delta[j] if entering else 0.5)
            a[row, ring_cols] -= weight * a_s[j]
            b[row] = weight * sim._s0[j]
            if not entering:
                a[row, ny + j - 1] = -1.0
                a[row, ring_cols] -= weight * a_s[j - 1]
                b[row] += weight * sim._s0[j - 1]
        u = np.linalg.solve(a, b)
        y, e = u[:ny], u[ny:]
        pen = sim._pen0 + sim._jn @ y
        f_n = sim._kn * pen
        slip_speed = a_s @ y + sim._s0
        # each point's element as it would arrive sticking, carried from the point ahead
        # (a sliding point is judged by this, not by the limit it is held at)
        carried = np.concatenate([[0.0], e[:-1]])
        ahead = np.concatenate([[0.0], slip_speed[:-1]])
        entering = ~np.concatenate([[False], c[:-1]])
        new_contact = (pen > 0) & (f_n > 0)
        new_delta = entering_fractions(pen, new_contact)
        e_trial = np.where(entering, spacing / omega * new_delta * slip_speed,
                           carried + spacing / (2 * omega) * (ahead + slip_speed))
        tread = sim._kx * e_trial + sim._cx * slip_speed
        new_stick = np.abs(tread) <= sim._mu * np.maximum(f_n, 0) * (1 + 1e-12)
        new_sign = np.where(new_stick, sign, np.sign(tread))
        # the edges move with the solve: their fractions settle with the sets
        if (sets_settled((contact, stick, sign), (new_contact, new_stick, new_sign))
                and np.allclose(new_delta, delta, rtol=1e-11, atol=1e-13)):
            break
        contact, stick, sign, delta = new_contact, new_stick, new_sign, new_delta
    else:
        raise ContactSetError("steady_rolling: the contact and stick sets did not settle")
    rate = np.zeros(ny)
    if sim._free_spin:
        rate[-1] = y[-1]
    state = y.copy()
    if sim._free_spin:
        state[-1] = 0.0  # the angle: rigid, moves no force
    fx, fz, my = sim.rim_force(state, rate, spin_rad_s=omega)
    spin = omega + (y[-1] if sim._free_spin else 0.0)
    return SteadyRolling(float(fx), float(fz), float(my), float(spin),
                         float(spin * sim.model.tire.R / sim.speed_m_s - 1.0),
                         int(np.sum(contact & ~stick)), np.where(contact, e, 0.0), y)


def ritz_basis(model: InPlaneTire, n_elements: int, zone_nodes: np.ndarray,
               f_max_hz: float) -> np.ndarray:
    """An orthonormal basis (ring DOFs x r) of the free ring's undamped modes at rest up to
    ``f_max_hz`` (rim held) and the static shapes of a unit radial and tangential load at each
    zone node: every contact force reaches the ring through the zone nodes, so the static
    part of any footprint's response lies in the basis, and the modes above f_max enter
    through it statically."""
    import scipy.linalg

    from .inplane_modes import tire_modes

    ring = InPlaneRing(model, n_elements)
    modes = tire_modes(ring, f_max_hz=f_max_hz)
    k = 0.5 * (ring.stiffness + ring.stiffness.T)
    loads = np.zeros((ring.n_ring_dof, 2 * zone_nodes.size))
    w, v = ring.field_slice("w"), ring.field_slice("v")
    for i, node in enumerate(zone_nodes):
        loads[w.start + node, 2 * i] = 1.0
        loads[v.start + node, 2 * i + 1] = 1.0
    static = np.linalg.solve(k, loads)
    shapes = np.hstack([modes.shapes, static / np.abs(static).max(axis=0)])
    return scipy.linalg.orth(shapes, rcond=1e-10)


#: The least entering fraction (a point may sit just behind the road's edge): its element
#: then holds a thousandth of a spacing's slip rather than a division by zero.
MIN_ENTERING_FRACTION = 1e-3


def entering_fractions(pen: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """δ (P,): for each point that begins a run of points in contact, how far ahead of it, in
    spacings, its elements enter the footprint: where the penetration, linear between it and
    the point ahead, crosses zero (the road's edge). 1/2 where there is no point ahead out of
    contact to tell (the zone's first point, or one ahead pressed but pushing nothing); 1 at
    the other points, where it is not used. With a fixed half spacing, the entering element
    held the same slip however lightly the point was pressed, so a point just behind the edge
    slid where the next one pressed in would stick, and the footprint's forces jumped as the
    edge crossed a point; with δ they follow the edge continuously."""
    delta = np.ones(pen.size)
    on = np.asarray(contact, dtype=bool)
    starts = np.flatnonzero(on & ~np.concatenate([[False], on[:-1]]))
    delta[starts] = 0.5
    inside = starts[starts > 0]
    ahead = pen[inside - 1]
    edge = (ahead <= 0.0) & (pen[inside] > 0.0)
    j = inside[edge]
    delta[j] = np.maximum(pen[j] / (pen[j] - pen[j - 1]), MIN_ENTERING_FRACTION)
    return delta


def entering_fraction_slopes(pen: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """∂δ_j/∂pen_{j-1} and ∂δ_j/∂pen_j (P, 2) of :func:`entering_fractions`: the road's edge
    moves with the penetrations (zero where δ is not the edge's: 1/2, the least, or unused)."""
    slopes = np.zeros((pen.size, 2))
    delta = entering_fractions(pen, contact)
    on = np.asarray(contact, dtype=bool)
    j = np.flatnonzero(on & ~np.concatenate([[False], on[:-1]]))
    j = j[j > 0]
    j = j[(pen[j - 1] <= 0.0) & (pen[j] > 0.0) & (delta[j] > MIN_ENTERING_FRACTION)]
    gap = (pen[j] - pen[j - 1]) ** 2
    slopes[j, 0], slopes[j, 1] = pen[j] / gap, -pen[j - 1] / gap
    return slopes


def carry_stencil(theta: np.ndarray, shift_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """(base (P,) int, weights (P, 4)): the departure point θ_p - shift of each point lies
    between points base and base + 1, and the cubic Lagrange weights on points base - 1 ...
    base + 2 interpolate the field there (points may be out of range)."""
    from .contact import lagrange_weights

    count = theta.size
    spacing = (theta[-1] - theta[0]) / (count - 1)
    position = (theta - shift_rad - theta[0]) / spacing
    base = np.floor(position).astype(int)
    return base, lagrange_weights(position - base)


def carry_matrix(theta: np.ndarray, shift_rad: float, out: np.ndarray | None = None
                 ) -> np.ndarray:
    """B (P x P): the field at the points carried by ``shift_rad`` in the direction of θ,
    e_new = B e, by cubic Lagrange interpolation at the departure points θ_p - shift (zero
    from ahead of the first point; :func:`carry_edges` corrects the stencils that reach past
    a run of points in contact). Linear interpolation damps a field carried through the
    footprint by a fraction that grows with the spacing; that numerical damping set the
    amplitude of the tread's fore-aft ringing, so the fore-aft force did not converge with
    the spacing. ``out`` (P x P) is written instead of a new array."""
    count = theta.size
    base, weights = carry_stencil(theta, shift_rad)
    if out is None:
        out = np.zeros((count, count))
    else:
        out[...] = 0.0
    for k, offset in enumerate(range(-1, 3)):
        column = base + offset
        ok = (column >= 0) & (column < count)
        out[np.flatnonzero(ok), column[ok]] = weights[ok, k]
    return out


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) of each run of consecutive true flags."""
    on = np.asarray(flags, dtype=bool)
    starts = np.flatnonzero(on & ~np.concatenate([[False], on[:-1]]))
    ends = np.flatnonzero(on & ~np.concatenate([on[1:], [False]]))
    return list(zip(starts.tolist(), ends.tolist()))


def carry_edges(e: np.ndarray, contact: np.ndarray, stick: np.ndarray, base: np.ndarray,
                weights: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """What the carry's stencils get wrong at the ends of the elements' field (P,), to add to
    B e. The cubic through a point reads one point behind it and two ahead, but the field is
    transported from ahead only, and it has ends:

    - ahead of each run of points in contact, the elements hold nothing (e = 0), yet the
      field a cubic interpolates across the road's edge goes on linearly through the zero
      where the elements enter, δ_j spacings ahead of the run's first point j
      (:func:`entering_fractions`, as steady_rolling's and the rolling modes' transports
      take it): e_j (1 - k/δ_j) at k spacings ahead. Read as zero, the entering element
      settled at 0.8 of a spacing's slip whatever δ, so a lightly pressed first point slid in
      the step where it stuck in the steady solve;
    - behind each run of sticking points, the point behind slides (its element held at the
      friction limit) or is off the road: the sticking field goes on with the slope of its
      last two points, so that the kink where sliding begins does not reach back into the
      points that stick.

    ``delta``: the entering fractions, at least the step's shift in spacings (an element that
    entered during the step is carried from zero)."""
    p = e.size
    correction = np.zeros(p)
    columns = base[:, None] + np.arange(-1, 3)
    real = np.where((columns >= 0) & (columns < p), e[np.clip(columns, 0, p - 1)], 0.0)
    for first, last in _runs(contact):
        rows = slice(first, last + 1)
        virtual = (1.0 - (first - columns[rows]) / delta[first]) * e[first]
        correction[rows] += np.sum(np.where(columns[rows] < first,
                                            weights[rows] * (virtual - real[rows]), 0.0), axis=1)
    for first, last in _runs(contact & stick):
        rows = slice(first, last + 1)
        slope = (e[last] - e[last - 1] if last > 0 and contact[last - 1]
                 else e[last] / delta[last])
        virtual = e[last] + (columns[rows] - last) * slope
        correction[rows] += np.sum(np.where(columns[rows] > last,
                                            weights[rows] * (virtual - real[rows]), 0.0), axis=1)
    return correction


def deflection_for_load(model: InPlaneTire, load_n: float, n_elements: int = 100,
                        **options) -> float:
    """The rim deflection (m) that carries ``load_n`` at rest, by the secant method on the
    piecewise linear static footprint."""
    # the static footprint at rest does not depend on the simulator's own deflection
    # (only its penetrations do): one simulator serves every trial
    return deflection_carrying(InPlaneSimulator(model, n_elements, 0.0, 0.0, **options), load_n)


def deflection_carrying(sim: InPlaneSimulator, load_n: float) -> float:
    """The rim deflection (m) whose static footprint carries ``load_n`` on this simulator, at
    its speed (the spin's stiffness and the loss at their values there; at rest, rest's), by
    the secant method on the piecewise linear static footprint. At speed the tire rolling
    steadily then carries the load to the small share the friction and damping move."""

    def load(deflection):
        return sim.static_load_n(deflection)

    lo, hi = 0.005, 0.04
    f_lo, f_hi = load(lo), load(hi)
    for _ in range(40):
        if f_hi == f_lo:  # (the C's INPLANE_STATIC_FLAT_SECANT) a load below what it resolves
            raise ContactSetError(f"the static footprint's load is the same ({f_hi:g} N) at "
                                  f"deflections {lo:g} m and {hi:g} m: the secant for "
                                  f"load_n = {load_n:g} N has no next deflection")
        mid = hi - (f_hi - load_n) * (hi - lo) / (f_hi - f_lo)
        f_mid = load(mid)
        if abs(f_mid - load_n) < 1e-9 * load_n:
            return mid
        lo, f_lo, hi, f_hi = hi, f_hi, mid, f_mid
    return mid
