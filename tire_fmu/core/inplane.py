"""The full in-plane ring: radial and tangential motion of tread and sidewall, and the rim's
translation and rotation.

The radial-only ring of the paper (:mod:`.model`) cannot carry a fore-aft force or a moment
about the axle and has no rotational mode. Here every tread node has a radial displacement w
(outwards) and a tangential one v (in the direction of θ, the direction of rotation), and so
does every lumped sidewall mass (w_s, v_s). Per metre of circumference the energy is

    U = ½ ∫ [ EA/R² (v' + w)² + EI/R⁴ (w'' - v')² + p₀b/R (w'² + v'² - 2 v w')
            + k_r1 (w - w_s)² + k_t1 (v - v_s)² + k_r2 w_s² + k_t2 v_s² ] ds,

with ' = ∂/∂θ and every displacement rim-relative (u - P·r, P the patterns of the rim's rigid
motions r = (x, z, ψ)). The pressure term is the inflation pre-tension p₀bR acting on the
second-order (Green-Lagrange) strain ½[(w' - v)² + (v' + w)²]/R² plus the follower pressure's
work on the enclosed area, -p₀b ½(w² + v² + w v' - v w')/R; their sum stores nothing under a
rigid translation (w, v) = (cos θ, -sin θ) or rotation (0, c) of the ring, so a tire translated
or turned with its rim feels no force, and restricted to v = 0 it is the paper's p₀b n²/R.

Rolling at spin Ω in the ground frame: a material particle's velocity is ∂t u + Ω·L u with
L = ∂θ + J, J = [[0, -1], [1, 0]] (the rate of the particle's displacement seen from the ground,
the base vectors turning with it), so the kinetic energy is ½ρA|u̇ + Ω L u|² per metre. Its
Ω² part is cancelled exactly by the tread's centrifugal hoop tension ρA R²Ω² acting on the same
second-order strain ½|Lu|²/R², which is how that tension arises; what is left for the tread is
the gyroscopic 2Ω M L u̇, with the Coriolis coupling of w and v. The sidewall masses' centrifugal
load goes to the rim through their springs, length ℓ = R - rim radius: with the preload's
geometric stiffness, the sidewall keeps -m_s Ω² [|L u_s|² - (R/ℓ) v_s²] on its rim-relative
displacement (derived in docs/theory.md §13, and rigid rotation with the rim stays free of force
at any speed). Material damping C = αM + βK acts on the material rate (∂t + Ω∂θ) of the
rim-relative displacement, giving the circulatory Ω C D1 as in the radial model.

Discretisation (N nodes, δθ = 2π/N): the membrane strain is taken between nodes,
e_{j+½} = (v_{j+1} - v_j)/δθ + (w_j + w_{j+1})/2, so that neither a zig-zag of v nor one of w
escapes the membrane and bending energies (central differences for both would leave the v
zig-zag at the torsional frequency); the curvature change at nodes, (D2 w - D1 v)_j; the
pressure term with forward differences for w'², v'² and D1 for the cross term. The discrete L
is D1 + κ₁J with κ₁ = sin δθ/δθ, the discrete wavenumber of order 1, so that it annihilates the
sampled rigid translation exactly (the continuum L does so for the continuum one).

A sidewall mass m_s = 0 means a massless sidewall: the springs act in series as a plain
foundation k_r = k_r1 k_r2/(k_r1 + k_r2), k_t likewise, and the model has tread DOFs only (the
classical ring on an elastic foundation).

Geometry: θ from the contact centre at the bottom, in the direction of rotation (towards the
rear of the patch for a tire rolling forward), x forward, z up, so the radial unit vector is
(-sin θ, -cos θ) and the tangential one (-cos θ, sin θ) in (x, z); the rim rotation ψ is about
the axle in the direction of rotation (positive y of ISO 8855 for a tire rolling forward).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from functools import cached_property

import numpy as np

from .parameters import ParameterError, Problem, TireParameters

#: The rim radius of a 16.00R20 tire (a 20 inch rim seat), m.
GL073A_RIM_RADIUS_M = 0.254


@dataclass(frozen=True)
class TangentialParameters:
    """What the in-plane ring needs beyond the radial tire data (SI, per metre of circumference
    where a line quantity).

    GL073A's published data (the paper's Table 1) are radial only. Defaults, until measured
    tangential modes identify them (see docs/theory.md §13.6 for the reasoning):

    - ``EA``: the belt's extensional stiffness, 1e7 N: four steel plies of about 45 mm² of cord
      each at 200 GPa over a truck belt's width, halved for the plies' angle;
    - ``k_t1``, ``k_t2``: tangential sidewall stiffnesses, equal halves of a series stiffness
      that puts the rotational mode of the tread with the rim held near 30 Hz, where truck tires'
      first in-plane rotational mode is reported (a truck tire's is below a car tire's 35-45 Hz);
    - ``rim_radius_m``: where the sidewall meets the rim, the 20 inch seat;
    - ``wheel_mass_kg``, ``wheel_inertia_kg_m2``: the rim and wheel, for the modes with the
      rim free (a steel 20 inch truck wheel: about 60 kg and 8 kg m²);
    - ``k_tx``: the tread rubber's fore-aft (shear) stiffness per metre of circumference, the
      bristle of a brush model, 5e7 N/m²: the brush's longitudinal slip stiffness 2 k a² with
      a footprint half-length a of 6-9 cm is then 10-25 times a 27.7 kN load, the range of
      truck tires' C_Fκ/Fz (Pacejka, Tire and Vehicle Dynamics, truck data);
    - ``friction_coefficient``: μ of the tread on the road, 0.8 (dry asphalt, truck tire);
    - ``loss_factor``: η of a hysteretic (rate-independent) loss in rolling, 0: the paper's
      viscous β only, whose rolling resistance grows with speed and is several times below a
      truck tire's (the tire file GL073A_inplane_hysteretic carries a fitted η; module doc).
    """

    EA: float = 1.0e7
    k_t1: float = 1.6e6
    k_t2: float = 1.6e6
    rim_radius_m: float = GL073A_RIM_RADIUS_M
    wheel_mass_kg: float = 60.0
    wheel_inertia_kg_m2: float = 8.0
    k_tx: float = 5.0e7
    friction_coefficient: float = 0.8
    loss_factor: float = 0.0

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


#: The largest hysteretic loss factor the FMUs take (a rolling tire runs on): the loss enters
#: the rolling ring as a circulatory stiffness η K H (the loss per cycle of a material point
#: rolling through the deformation), which pumps energy into the ring's low modes as the
#: viscous damping takes it out; with the GL073A data the ring settles up to 0.1 at every
#: speed from 1 m/s to the critical speed, and grows from 0.15 on
#: (tests/test_inplane_limits.py). The ring itself is built for any η of TANGENTIAL_RANGES.
MAX_LOSS_FACTOR = 0.1

#: Allowed ranges (inclusive) of the tangential parameters, and their units.
TANGENTIAL_RANGES = {
    "EA": (1e3, 1e12, "N"),
    "k_t1": (1e2, 1e12, "N/m^2"),
    "k_t2": (1e2, 1e12, "N/m^2"),
    "rim_radius_m": (1e-3, 10.0, "m"),
    "wheel_mass_kg": (1e-3, 1e5, "kg"),
    "wheel_inertia_kg_m2": (1e-6, 1e5, "kg*m^2"),
    "k_tx": (0.0, 1e12, "N/m^2"),
    "friction_coefficient": (0.0, 3.0, ""),
    "loss_factor": (0.0, 1.0, ""),
}
#: The tangential ranges the FMUs take: the loss up to MAX_LOSS_FACTOR.
HOST_TANGENTIAL_RANGES = {**TANGENTIAL_RANGES, "loss_factor": (0.0, MAX_LOSS_FACTOR, "")}

#: Road speed (m/s) from which the hysteretic rolling loss acts in full: below it its share
#: falls linearly to zero at rest (:func:`hysteresis_share`), so that the loss, which a
#: rate-independent law gives at any speed, vanishes with the rolling and the static footprint
#: stays the static one.
HYSTERESIS_FULL_SPEED_M_S = 0.5


def hysteresis_share(spin_rad_s: float, radius_m: float) -> float:
    """s(Ω) in [-1, 1]: the share of the hysteretic loss at this spin (its sign the
    direction of rolling), linear up to :data:`HYSTERESIS_FULL_SPEED_M_S` of the tread."""
    full = HYSTERESIS_FULL_SPEED_M_S / radius_m
    return max(-1.0, min(1.0, spin_rad_s / full))


def hilbert_circulant(n: int) -> np.ndarray:
    """H (N x N): the discrete Hilbert transform along θ, i·sign(n) on the order-n wave
    e^{inθ} with the sign of the central difference's wavenumber sin(nδθ)/δθ (0 for order 0
    and N/2): D1 with every order's wavenumber scaled to one."""
    orders = np.arange(n)
    symbol = 1j * np.sign(np.round(np.sin(2.0 * math.pi * orders / n), 14))
    column = np.fft.ifft(symbol).real  # H[j, m] = c[(j - m) mod N]
    return column[(orders[:, None] - orders[None, :]) % n]


def tangential_problems(values: TangentialParameters, tread_radius_m: float,
                        ranges: dict | None = None) -> list[Problem]:
    """Every problem with the tangential data at once (the rim must sit inside the tread);
    ``ranges`` (default TANGENTIAL_RANGES: what the ring is built for) narrows them, as the
    FMUs do the loss (HOST_TANGENTIAL_RANGES)."""
    problems = []
    for name, (low, high, unit) in (TANGENTIAL_RANGES if ranges is None else ranges).items():
        value = getattr(values, name)
        if not (isinstance(value, (int, float)) and math.isfinite(value) and low <= value <= high):
            problems.append(Problem(name, value, unit,
                                    f"a number in [{low:g}, {high:g}] {unit}".rstrip()))
    rim = values.rim_radius_m
    if isinstance(rim, (int, float)) and math.isfinite(rim) and rim >= tread_radius_m:
        problems.append(Problem("rim_radius_m", rim, "m",
                                f"below the tread radius R = {tread_radius_m:g} m",
                                "the sidewall spans from the rim to the tread"))
    return problems


@dataclass(frozen=True)
class InPlaneTire:
    """The tire data the in-plane ring is built from: the radial data and the tangential ones.

    ``sidewall_mass=False`` builds the massless sidewall (springs in series, tread DOFs only).
    ``sidewall_tangential`` says how the sidewall moves tangentially: ``"tied"`` (the default)
    rides at its static share r = k_t1/(k_t1 + k_t2) of the tread's tangential displacement,
    the springs then acting in series and the sidewall's mass entering as r² m_s; ``"lumped"``
    gives it its own tangential DOF, as the paper's sidewall has its own radial one. The
    lumped tangential sidewall has no circumferential stiffness, so its masses form a band of
    modes at sqrt((k_t1 + k_t2)/m_s)/2π (90 Hz with the defaults) in every order, inside the
    ride range and with no data to place it: the tie is the sidewall model of the radial ring
    above its ``sidewall_max_order``, applied to the tangential direction in every order.
    """

    tire: TireParameters = field(default_factory=lambda: TireParameters(sidewall_max_order=0.0))
    tangential: TangentialParameters = field(default_factory=TangentialParameters)
    sidewall_mass: bool = True
    sidewall_tangential: str = "tied"

    def __post_init__(self) -> None:
        problems = tangential_problems(self.tangential, self.tire.R)
        if self.sidewall_tangential not in ("tied", "lumped"):
            problems.append(Problem("sidewall_tangential", self.sidewall_tangential, "",
                                    "'tied' or 'lumped'"))
        if self.tire.sidewall_shear > 0:
            problems.append(Problem(
                "sidewall_shear", self.tire.sidewall_shear, "N", "0 for the in-plane ring",
                "its sidewall masses have no circumferential coupling; to move the sidewall's "
                "band out of the high orders tie it instead (sidewall_max_order, e.g. 8)"))
        if problems:
            raise ParameterError(problems)

    @property
    def sidewall_length_m(self) -> float:
        return self.tire.R - self.tangential.rim_radius_m

    @property
    def tangential_share(self) -> float:
        """r = k_t1/(k_t1 + k_t2): the tied sidewall's share of the tread's tangential motion."""
        return self.tangential.k_t1 / (self.tangential.k_t1 + self.tangential.k_t2)

    def series_foundation(self) -> tuple[float, float]:
        """(k_r, k_t): the sidewall's springs in series, N/m² (the massless sidewall)."""
        t = self.tire
        k_r1, k_r2 = t.effective_k_r1, t.effective_k_r2
        k_t1, k_t2 = self.tangential.k_t1, self.tangential.k_t2
        return k_r1 * k_r2 / (k_r1 + k_r2), k_t1 * k_t2 / (k_t1 + k_t2)


def _circulant(n: int, stencil: dict[int, float]) -> np.ndarray:
    """Dense periodic matrix with (A u)_j = Σ_k c_k u_{j+k} (the in-plane ring is small)."""
    a = np.zeros((n, n))
    index = np.arange(n)
    for offset, coefficient in stencil.items():
        np.add.at(a, (index, (index + offset) % n), coefficient)
    return a



def quadratic_in_spin(at_0, at_1, at_2, step_rad_s: float = 1.0) -> tuple:
    """(a0, a1, a2) with a(Ω) = a0 + Ω a1 + Ω² a2 from its values at Ω = 0, step, 2 step
    (rad/s; 1 by default): the ring's C is linear and K quadratic in the spin, so three rings
    give them at any spin."""
    a2 = (at_2 - 2.0 * at_1 + at_0) * (0.5 / step_rad_s**2)
    return at_0, (at_1 - at_0) * (1.0 / step_rad_s) - step_rad_s * a2, a2

@dataclass(frozen=True, eq=False)
class InPlaneRing:
    """Mass, damping (with the gyroscopic part) and stiffness of the in-plane ring at spin Ω
    (dense, SI).

    DOFs: N of each field, absolute (ground frame), in the order of :attr:`fields` (tread w,
    tread v, then sidewall w_s and, with the lumped tangential sidewall, v_s); then, with
    ``rim_free``, the rim's x, z (m) and ψ (rad). Internal forces act on the rim-relative
    displacement; with the rim held (``rim_free=False``) that is the displacement itself. The
    equation of motion is M q̈ + C q̇ + K q = f, C holding material damping and 2Ω M L.
    """

    model: InPlaneTire
    n_elements: int
    spin_rad_s: float = 0.0
    rim_free: bool = False
    #: False leaves the hysteretic loss out of :attr:`stiffness` (it is not polynomial in the
    #: spin: a simulator reads the polynomial off three spins and adds it apart)
    hysteresis: bool = True

    # ----- grid and operators -----
    @property
    def dtheta(self) -> float:
        return 2.0 * math.pi / self.n_elements

    @property
    def node_arc_m(self) -> float:
        return self.model.tire.R * self.dtheta

    @cached_property
    def theta(self) -> np.ndarray:
        return np.arange(self.n_elements) * self.dtheta

    @property
    def fields(self) -> tuple[str, ...]:
        if not self.model.sidewall_mass:
            return ("w", "v")
        return ("w", "v", "w_s") + (("v_s",) if self.model.sidewall_tangential == "lumped"
                                    else ())

    @property
    def n_fields(self) -> int:
        return len(self.fields)

    @property
    def n_ring_dof(self) -> int:
        return self.n_fields * self.n_elements

    @property
    def n_dof(self) -> int:
        return self.n_ring_dof + (3 if self.rim_free else 0)

    def field_slice(self, name: str) -> slice:
        """Where a field's N DOFs sit: one of :attr:`fields`."""
        if name not in self.fields:
            raise KeyError(f"{name}: not a DOF of this ring (its fields are {self.fields})")
        index, n = self.fields.index(name), self.n_elements
        return slice(index * n, (index + 1) * n)

    @property
    def _n_built(self) -> int:
        """Fields of the matrices as built, before the tangential tie: 4, or 2 massless."""
        return 4 if self.model.sidewall_mass else 2

    @cached_property
    def _ops(self) -> dict[str, np.ndarray]:
        n, d = self.n_elements, self.dtheta
        return {
            "d1": _circulant(n, {-1: -0.5 / d, 1: 0.5 / d}),
            "d2": _circulant(n, {-1: d**-2, 0: -2.0 * d**-2, 1: d**-2}),
            "fwd": _circulant(n, {0: -1.0 / d, 1: 1.0 / d}),
            "avg": _circulant(n, {0: 0.5, 1: 0.5}),
        }

    @property
    def kappa1(self) -> float:
        """sin δθ/δθ: the discrete wavenumber of order 1, the weight of J in the discrete L."""
        return math.sin(self.dtheta) / self.dtheta

    def _pair_L(self) -> np.ndarray:
        """Discrete L = D1 + κ₁J on one (w, v) pair of fields (2N x 2N)."""
        d1, eye = self._ops["d1"], np.eye(self.n_elements)
        return np.block([[d1, -self.kappa1 * eye], [self.kappa1 * eye, d1]])

    # ----- the rim's rigid motions -----
    def _patterns(self, fields: int) -> np.ndarray:
        th, radius = self.theta, self.model.tire.R
        radial = np.stack([-np.sin(th), -np.cos(th), np.zeros_like(th)], axis=1)
        tangential = np.stack([-np.cos(th), np.sin(th), np.full_like(th, radius)], axis=1)
        return np.concatenate(([radial, tangential] * 2)[:fields], axis=0)

    @cached_property
    def rim_patterns(self) -> np.ndarray:
        """(n_ring_dof, 3): ring displacement of a unit rim x, z (m) and ψ (rad)."""
        return self._patterns(self.n_fields)

    # ----- matrices as built: 4 fields (2 massless), rim-relative -----
    @cached_property
    def _built_mass(self) -> np.ndarray:
        t, n = self.model.tire, self.n_elements
        masses = [t.rhoA, t.rhoA] + ([t.m_s, t.m_s] if self.model.sidewall_mass else [])
        return np.diag(np.repeat(masses, n) * self.node_arc_m)

    @cached_property
    def _built_elastic(self) -> np.ndarray:
        """K at rest on the rim-relative DOFs: membrane, bending, pressure, sidewall."""
        t, tang, n, ops = self.model.tire, self.model.tangential, self.n_elements, self._ops
        a, radius = self.node_arc_m, t.R
        membrane = np.hstack([ops["avg"], ops["fwd"]])  # e at j+½ from (w, v)
        bending = np.hstack([ops["d2"], -ops["d1"]])  # κ at j
        k = tang.EA / radius**2 * a * membrane.T @ membrane
        k += t.EI / radius**4 * a * bending.T @ bending
        tension = t.pretension_n / radius**2 * a  # p₀b/R per metre (pretension = p₀bR)
        stretch = ops["fwd"].T @ ops["fwd"]
        k += tension * np.block([[stretch, ops["d1"]], [-ops["d1"], stretch]])
        if not self.model.sidewall_mass:
            k_r, k_t = self.model.series_foundation()
            return k + a * np.kron(np.diag([k_r, k_t]), np.eye(n))
        k_r1, k_r2, k_t1, k_t2 = t.effective_k_r1, t.effective_k_r2, tang.k_t1, tang.k_t2
        eye = np.eye(n)
        springs = np.kron(np.array([[k_r1, 0, -k_r1, 0], [0, k_t1, 0, -k_t1],
                                    [-k_r1, 0, k_r1 + k_r2, 0], [0, -k_t1, 0, k_t1 + k_t2]]),
                          eye)
        full = a * springs
        full[: 2 * n, : 2 * n] += k
        return full

    @cached_property
    def _built_tie(self) -> np.ndarray | None:
        """The radial sidewall's tie to the tread above ``sidewall_max_order`` (the radial
        ring's, :func:`.model.sidewall_tie_matrix`: ½p(w_s - r w)² per order, r the static
        share k_r1/(k_r1 + k_r2)), on the rim-relative built DOFs, or None where it does not
        act. Every static state of the ring has w_s = r w, so it stores nothing there (the
        footprint is the lumped sidewall's) and moves the sidewall's band, which sets a
        critical speed falling as 1/N, out of the tied orders. It is elastic: no damper and no
        loss act on it, as in the radial ring."""
        t, n = self.model.tire, self.n_elements
        if not (self.model.sidewall_mass and 0 < t.sidewall_max_order < n // 2):
            return None
        from .discretisation import Grid
        from .model import sidewall_tie_matrix

        tie = sidewall_tie_matrix(t, Grid(n, t.R)).toarray() * self.node_arc_m
        out = np.zeros_like(self._built_elastic)
        w, w_s = slice(0, n), slice(2 * n, 3 * n)
        out[w, w], out[w, w_s] = tie[:n, :n], tie[:n, n:]
        out[w_s, w], out[w_s, w_s] = tie[n:, :n], tie[n:, n:]
        return out

    @cached_property
    def _built_damping(self) -> np.ndarray:
        t = self.model.tire
        return t.alpha * self._built_mass + t.beta * self._built_elastic

    @cached_property
    def _built_gyroscopic(self) -> np.ndarray:
        """2Ω M L on the absolute velocities (skew-symmetric)."""
        L = np.kron(np.eye(self._n_built // 2), self._pair_L())
        # M is diagonal: a row scaling, not an N³ product
        return 2.0 * self.spin_rad_s * np.diag(self._built_mass)[:, None] * L

    @cached_property
    def _built_rolling(self) -> np.ndarray:
        """The speed's stiffness on the rim-relative DOFs: the sidewall's net centrifugal term
        -m_s Ω² [LᵀL - (R/ℓ) E_v] and the circulatory Ω C D1 of material damping."""
        n, omega = self.n_elements, self.spin_rad_s
        # D1 has two entries a row: C D1 as a sparse product (dense, it cost N³)
        import scipy.sparse  # not at import: the FMUs' start loads only what they use

        d1 = scipy.sparse.kron(scipy.sparse.eye_array(self._n_built),
                               scipy.sparse.csr_array(self._ops["d1"]), format="csr")
        k = omega * np.asarray((d1.T @ self._built_damping.T).T)
        if self.model.sidewall_mass and omega != 0.0:
            L = scipy.sparse.csr_array(self._pair_L())
            tangential = np.zeros((2 * n, 2 * n))
            tangential[n:, n:] = np.eye(n) * self.model.tire.R / self.model.sidewall_length_m
            side = slice(2 * n, 4 * n)
            k[side, side] -= omega**2 * self.model.tire.m_s * self.node_arc_m * (
                (L.T @ L).toarray() - tangential)
        return k

    @cached_property
    def _built_hysteretic(self) -> np.ndarray:
        """η K H on the rim-relative DOFs, unscaled by the spin's share: the circulatory term
        Ω β K D1 of viscous damping with β = η/ω_n, ω_n = |Ω sin(nδθ)/δθ| the rate at which
        rolling cycles a material point through order n (a loss per cycle independent of
        the rate). Rigid translation (order 1) goes to rigid translation, rigid rotation
        (order 0) to nothing: K annihilates both."""
        eta = self.model.tangential.loss_factor
        if eta == 0.0:
            return np.zeros_like(self._built_elastic)
        # K (I ⊗ H) block column by block column: N² per block rather than the kron's N³
        h, n, k = hilbert_circulant(self.n_elements), self.n_elements, self._built_elastic
        out = np.empty_like(k)
        for b in range(self._n_built):
            out[:, b * n:(b + 1) * n] = k[:, b * n:(b + 1) * n] @ h
        return eta * out

    @cached_property
    def hysteretic_stiffness(self) -> np.ndarray:
        """The hysteretic loss's stiffness at full share on the DOFs (the stiffness holds
        :func:`hysteresis_share` of it at the ring's spin)."""
        return self._assemble(self._built_hysteretic, relative=True)

    @cached_property
    def _tie(self) -> np.ndarray:
        """(built DOFs [+ rim], DOFs): v_s = r v_rel + rim's motion, or identity."""
        n, built = self.n_elements, self._n_built * self.n_elements
        rim = 3 if self.rim_free else 0
        tie = np.zeros((built + rim, self.n_dof))
        tie[: self.n_ring_dof, : self.n_ring_dof] = np.eye(self.n_ring_dof)
        if rim:
            tie[built:, self.n_ring_dof:] = np.eye(3)
        if self.n_fields == 3:
            r = self.model.tangential_share
            v_s, v = slice(3 * n, 4 * n), self.field_slice("v")
            tie[v_s, v] = r * np.eye(n)
            if rim:  # v_s,rel = r v_rel: v_s = r v + (1 - r) P_v x_rim
                tie[v_s, self.n_ring_dof:] = (1.0 - r) * self._patterns(2)[n:]
        return tie

    def _assemble(self, ring: np.ndarray, relative: bool, rim: np.ndarray | None = None):
        """The built ring matrix on the DOFs: relative ones act on q_ring - P x_rim. The
        transformations are written out (the rim's three columns) and sparse (the tie's one
        or two entries a row): as dense products they cost N³, seconds a matrix at N = 400."""
        if self.rim_free:
            built = ring.shape[0]
            out = np.zeros((built + 3, built + 3))
            out[:built, :built] = ring
            if relative:  # t = [I, -P]: tᵀ R t
                patterns = self._patterns(self._n_built)
                ring_p = ring @ patterns
                out[:built, built:] = -ring_p
                out[built:, :built] = -(patterns.T @ ring)
                out[built:, built:] = patterns.T @ ring_p
            if rim is not None:
                out[built:, built:] += rim
            ring = out
        if self.n_fields != 3:  # the tie is the identity
            return ring
        import scipy.sparse  # not at import: the FMUs' start loads only what they use

        tie = scipy.sparse.csr_array(self._tie)
        return np.asarray(tie.T @ (tie.T @ ring.T).T)

    @cached_property
    def mass(self) -> np.ndarray:
        tang = self.model.tangential
        rim = np.diag([tang.wheel_mass_kg, tang.wheel_mass_kg, tang.wheel_inertia_kg_m2])
        return self._assemble(self._built_mass, relative=False, rim=rim)

    @cached_property
    def stiffness(self) -> np.ndarray:
        """K and the speed's stiffness (not symmetric at speed with damping: circulatory),
        with the hysteretic loss's share at this spin."""
        k = self._built_elastic + self._built_rolling
        if self._built_tie is not None:
            k = k + self._built_tie
        share = hysteresis_share(self.spin_rad_s, self.model.tire.R) if self.hysteresis else 0.0
        if share and self.model.tangential.loss_factor:
            k = k + share * self._built_hysteretic
        return self._assemble(k, relative=True)

    @cached_property
    def damping(self) -> np.ndarray:
        """Material damping on the rim-relative rates and the gyroscopic 2Ω M L."""
        return (self._assemble(self._built_damping, relative=True)
                + self._assemble(self._built_gyroscopic, relative=False))

    @cached_property
    def ring_mass(self) -> np.ndarray:
        """The mass matrix's ring block (diagonal with the rim held)."""
        return self.mass[: self.n_ring_dof, : self.n_ring_dof]

    def rigid_motion(self, x_m: float = 0.0, z_m: float = 0.0, psi_rad: float = 0.0):
        """The DOF vector of the whole tire moved rigidly (with the rim, when it is free)."""
        ring = self.rim_patterns @ np.array([x_m, z_m, psi_rad])
        if self.rim_free:
            return np.concatenate([ring, [x_m, z_m, psi_rad]])
        return ring

    @cached_property
    def _with_free_rim(self) -> InPlaneRing:
        return self if self.rim_free else replace(self, rim_free=True)

    def rim_force(self, q: np.ndarray, qdot: np.ndarray | None = None,
                  qddot: np.ndarray | None = None) -> np.ndarray:
        """(Fx, Fz, My): force (N) and moment about the axle (N m) the tire puts on the rim.

        The rim's rows of the tire's forces K q + C q̇ + M_tire q̈ (the wheel's own inertia
        excluded), negated: what a held rim must resist. With the rim held (no rim DOFs in q)
        they are read from the same tire with the rim free and at rest. They include the
        share of the sidewall's inertia the tie hands to the rim; the gyroscopic forces of
        the tread are the tread's own inertia and reach the rim through the springs."""
        twin = self._with_free_rim

        def embed(x):
            return x if self.rim_free else np.concatenate([x, np.zeros(3)])

        f = twin.stiffness @ embed(q)
        if qdot is not None:
            f = f + twin.damping @ embed(qdot)
        if qddot is not None:
            tang = self.model.tangential
            wheel = np.diag([tang.wheel_mass_kg, tang.wheel_mass_kg, tang.wheel_inertia_kg_m2])
            f = f + twin.mass @ embed(qddot)
            f[-3:] -= wheel @ embed(qddot)[-3:]
        return -f[-3:]
