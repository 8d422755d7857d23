"""Time stepping of the tire with the unilateral contact: a linear ring, a nonlinear interface.

The ring is linear, so it is stepped exactly in its free modal basis (:mod:`.free_ring`, built
at initialisation for the speed), with the rim motion and the road's push f_j on each
contact-zone node as inputs, each ramped over the step. Only the contact is nonlinear: over a
step t -> t + h the forces ramp from their values at t to unknown values at t + h, and those
are solved so that the law of :mod:`.contact` holds at t + h,

    f_j = max(0, k_j p_j + c_j ṗ_j) where p_j > 0, else 0,
    p(t + h) = a + W_p Δf,  ṗ(t + h) = a' + W_r Δf,

where a, a' are the end-of-step penetrations and rates with the forces held at their deviation
from the static footprint (Δf = f - f_static = 0 at t + h) and W_p, W_r the step's own
interface flexibility (exact, from the modal step coefficients, cached per h). The solve is a
primal-dual active set iteration on the few zone nodes, warm-started from the last step's set;
no node ever pulls. An explicit contact at this stiffness would be unstable at h = 1e-4 s.

The ramp makes the interface second order; like any such scheme it is stable only while
ω_c·h stays small for the contact frequency ω_c = sqrt(k_cw/ρA) (about 5.5e3 rad/s with the
paper's data), so a communication step longer than ``max_substep_s`` is divided into equal
substeps, with the inputs ramped through them.

At the start of each communication step the forces are re-evaluated from the ring's state and
the inputs the host gave for that point (an algebraic evaluation: with every mode kept the
zone displacements do not depend on the forces at an instant), so outputs read after new
inputs, and the step that follows, use them.

The model can also run ``law="linear"``: two-sided springs on the static footprint's nodes,
f = f_static + k Δp + c Δṗ, which is exactly the linearised loaded model (a reference for the
unilateral contact at small amplitude, and what a linear frequency-domain tool assumes).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg.blas import dgemv

from . import clock
from .contact import ContactPatch, RoadWindows, _edges, contact_force
from .free_ring import FreeRingModel, RingTruncation, free_ring_model
from .model import TireModel, build_model, check_resolved
from .parameters import OperatingPoint, TireParameters
from .road import SAME_POINT_EPS, RoadReader
from .stepping import phi_functions

LAWS = ("unilateral", "linear")
#: deflection: the rim's lowering towards the road at the contact centre (as the static
#: footprint's); tread_deflection: the tread's compression there relative to the rim
OUTPUT_NAMES = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length",
                "tread_deflection")
INPUT_NAMES = ("rim_z", "rim_vz", "road_z", "road_vz")
#: Largest input magnitudes a step accepts (m, m/s): far beyond any tire's travel, but
#: finite enough that no product inside a step can overflow.
MAX_DISPLACEMENT_M = 10.0
MAX_VELOCITY_M_S = 1000.0
#: Largest displacement and rate a state may hold (m, m/s): the tread's excursion at the zone
#: nodes from any one mode, penetrations, the rim and road it saw. A step of an FMU moves the
#: rim and road at most MAX_DISPLACEMENT_M + MAX_VELOCITY_M_S x 1 s = 1010 m from equilibrium;
#: these are ten times that (and the rates a thousand times the input limit), so no run within
#: the inputs' limits reaches them, while a state beyond them is no tire's (1e300 in a mode gave
#: outputs of 3e307) and a step from it could overflow.
MAX_STATE_DISPLACEMENT_M = 1e4
MAX_STATE_VELOCITY_M_S = 1e6
#: Longest internal step (s); shorter still if the contact frequency asks for it.
MAX_SUBSTEP_S = 1e-4
#: The shortest contact sub-step a tire may need (s): GL073A needs 1.8e-4 s (so 0.1 ms), and
#: 1e-7 s is 1000 sub-steps per 0.1 ms communication step. Stiffer contacts on lighter treads
#: are refused rather than run for hours (a property test over the ranges found one).
MIN_SUBSTEP_S = 1e-7
#: The shortest step (s) of a ring truncated with static correction. Its dropped modes enter
#: through their static compliance and a rate term E ṙ, which a step of h weighs as E/h: the
#: shorter the step, the more the rate term outweighs the compliance, until the step's contact
#: problem loses its unique solution (from 6e-6 s down, the longest of 40 random tires around
#: GL073A at up to 15 m/s; 1e-6 s at N = 100, 10 m/s, f_max = 150 Hz) and, below 1e-300 s, E/h
#: overflows (found by fuzzing both FMUs). The ring with every mode, or without the static
#: correction, has no rate term and steps any h.
MIN_CORRECTED_STEP_S = 1e-5
#: The refusal of a shorter step: h (repr) and the bound.
SHORT_STEP_TEMPLATE = ("step size h = %s s: must be at least %g s for a ring truncated with "
                       "static correction (the dropped modes' rate term grows as 1/h); keep "
                       "every mode, or turn the static correction off, to step shorter")
_STATE_FORMAT = "tire_fmu.contact-state/2"
_KERNEL_CACHE_SIZE = 32
_SOLVE_CACHE_SIZE = 256
#: Active-set iterations per solve: this many per zone node, plus ACTIVE_SET_EXTRA; then PGS.
ACTIVE_SET_PER_NODE = 2
ACTIVE_SET_EXTRA = 4
#: Projected Gauss-Seidel fallback: sweeps, and the relative change that ends it.
PGS_SWEEPS = 1000
PGS_TOLERANCE = 1e-13
#: A step within this relative distance of a multiple of the substep needs no extra substep.
SUBSTEP_SLACK = 1e-12


class StepError(ValueError):
    """A step the simulator refuses (bad h, non-finite input); nothing was changed."""


class ContactZoneWarning(UserWarning):
    """The footprint reached the end of the contact zone: forces beyond it are missing."""


@dataclass(frozen=True)
class ContactSettings:
    law: str = "unilateral"
    max_substep_s: float = MAX_SUBSTEP_S

    def __post_init__(self) -> None:
        from .parameters import ParameterError, Problem

        problems = []
        if self.law not in LAWS:
            problems.append(Problem("law", self.law, "", f"one of {', '.join(LAWS)}"))
        if not (isinstance(self.max_substep_s, (int, float)) and 0 < self.max_substep_s <= 1.0):
            problems.append(Problem("max_substep_s", self.max_substep_s, "s", "in (0, 1] s"))
        if problems:
            raise ParameterError(problems)


@dataclass(frozen=True, eq=False)
class ContactModel:
    """Everything a contact simulation needs, built once for an operating point."""

    model: TireModel  # the linearised loaded model (its patch is the static footprint)
    ring: FreeRingModel
    settings: ContactSettings
    substep_s: float  # the longest internal step used

    @property
    def patch(self) -> ContactPatch:
        return self.model.patch

    @property
    def windows(self) -> RoadWindows:
        return self.patch.road

    @property
    def static_outputs(self) -> dict[str, float]:
        """The simulator's outputs (OUTPUT_NAMES) at the static footprint."""
        statics = self.patch.static_outputs()  # the linear model's: "deflection" is the tread's
        return {"rim_Fz": statics["rim_Fz"], "rim_Fx": statics["rim_Fx"],
                "contact_Fz": statics["contact_Fz"], "deflection": self.patch.deflection_m,
                "contact_length": self.patch.length_m,
                "tread_deflection": statics["deflection"]}

    def summary(self) -> dict:
        return {**self.model.summary(), "law": self.settings.law,
                "ring_modes": self.ring.n_modes, "ring_states": self.ring.n_states,
                "ring_modes_total": self.ring.total_modes, "zone_nodes": self.ring.n_zone,
                "substep_s": self.substep_s}


def build_contact_model(tire: TireParameters | None = None, op: OperatingPoint | None = None,
                        truncation: RingTruncation | None = None,
                        settings: ContactSettings | None = None) -> ContactModel:
    """The static footprint for the load, the free ring for the speed, the interface."""
    tire = tire or TireParameters()
    op = op or OperatingPoint()
    settings = settings or ContactSettings()
    model = build_model(tire, op)
    ring = free_ring_model(tire, model.grid, model.spin_rad_s, model.patch.zone.nodes,
                           truncation)
    # the free ring's rigid rotation (eigenvalue 0 exactly) is no mode to resolve
    check_resolved(ring.eigenvalues[ring.eigenvalues != 0], model)
    contact_rad_s = math.sqrt(tire.k_cw / tire.rhoA)
    if 1.0 / contact_rad_s < MIN_SUBSTEP_S:
        from .parameters import TIRE_FIELDS, ParameterError, Problem

        raise ParameterError([Problem(
            "k_cw", tire.k_cw, TIRE_FIELDS["k_cw"].unit,
            f"at most {tire.rhoA / MIN_SUBSTEP_S**2:.3g} N/m^2 with rhoA = {tire.rhoA:g} kg/m",
            f"the contact is sub-stepped at 1/sqrt(k_cw/rhoA), which would be below "
            f"{MIN_SUBSTEP_S:g} s: more than 10^4 sub-steps per millisecond")])
    substep = min(settings.max_substep_s, 1.0 / contact_rad_s)
    return ContactModel(model=model, ring=ring, settings=settings, substep_s=substep)


@dataclass(frozen=True, eq=False)
class _Interface:
    """The law's linear part on one problem: [σ; p; ṗ] = base + M f for the total forces f,
    with σ = k p + c ṗ, and the inverses (I - S_AA)⁻¹ of the active sets met so far."""

    m: np.ndarray  # (3Z, Z), Fortran order: [S; W_p; W_r]
    solves: dict = field(default_factory=dict)

    @property
    def s(self) -> np.ndarray:
        return self.m[: self.m.shape[1]]


@dataclass(frozen=True, eq=False)
class _Step:
    """A communication step of length h: ``n_sub`` equal substeps of ``last``."""

    h: float
    n_sub: int
    last: _Kernel
    resolved_until_s: float  # clock.resolved_until(h): where the clock stops resolving h


@dataclass(frozen=True, eq=False)
class _Kernel:
    """One internal step of length h on the simulator's buffer (see ContactSimulator).

    ``base`` @ buffer gives, at t + h with the end forces at their static values, the rows
    [σ0, p, ṗ] of the interface (Z each) and the ring outputs rim_Fz, rim_Fx, deflection;
    ``interface.m`` adds the end forces. ``gain`` @ buffer[inputs] advances q after ``decay``.
    """

    h: float
    decay: np.ndarray  # (K,) complex
    base: np.ndarray  # (3Z + 3, buffer), Fortran order
    out_f: np.ndarray  # (3, Z): ring outputs per unit Δf at t + h
    gain: np.ndarray  # (2K, 2 + 2Z): on [z, ż, Δf(t), Δf(t + h)]
    interface: _Interface


#: Steps in a row with one kernel and active set before the fast step is built for them.
_FAST_AFTER = 8
_FAST_CACHE_SIZE = 32


class _FastStep:
    """A whole step (the start re-solve and the end solve of ContactSimulator) as one linear
    map, for one kernel (the same h as the last step) and one active set.

    With the active set fixed, every quantity of the step is linear in the ring readout
    r = base_q @ q and the contact's state array w: the map is built by running the same
    operations on identity columns, so it is the general path's arithmetic rearranged. A step
    is then: r, y = T @ [r; w], a check that the active set did not change (else the general
    path runs, nothing changed), q advanced by one product, and w's new part copied from y.
    """

    def __init__(self, sim: ContactSimulator, kernel: _Kernel, active: np.ndarray):
        nz, n_read = sim.n_zone, sim._n_read
        n = sim._rw.size
        eye = np.eye(n)
        r = eye[:n_read]
        w = eye[n_read:]
        df, pen, rate = w[:nz], w[nz:2 * nz], w[2 * nz:3 * nz]
        z_s, vz_s = w[3 * nz], w[3 * nz + 1]
        h_s, s_s = w[3 * nz + 2:4 * nz + 2], w[4 * nz + 2:5 * nz + 2]
        ring = w[5 * nz + 2:5 * nz + 5]
        z, vz = w[5 * nz + 5], w[5 * nz + 6]
        heights, slopes = w[5 * nz + 7:6 * nz + 7], w[6 * nz + 7:7 * nz + 7]
        one = w[7 * nz + 7]
        f_s, m = sim.f_static[:, None], kernel.interface.m
        k, c, sec = sim.k[:, None], sim.c[:, None], sim.sec[:, None]
        inverse = np.linalg.inv(np.eye(int(active.sum())) - kernel.interface.s[
            np.ix_(active, active)])

        def solve(base):
            f = np.zeros((nz, n))
            f[active] = inverse @ base[:nz][active]
            return f

        # start: the last step's end solved again with the inputs given now
        pen1 = pen + sim._pen_rim[:, None] * (z - z_s) + sec * (heights - h_s)
        rate1 = rate + sim._rate_rim[:, None] * (vz - vz_s) + sec * (slopes - s_s)
        ring1 = ring + sim._out_rim[:, None] * (z - z_s) + sim._out_rim_rate[:, None] * (vz - vz_s)
        f_old = f_s * one + df
        base1 = np.vstack([k * pen1 + c * rate1, pen1, rate1]) - m @ f_old
        f1 = solve(base1)
        comb1 = base1 + m @ f1
        change = f1 - f_old
        ring1 = ring1 + kernel.out_f @ change
        # the start alone (outputs read after new inputs): the state's first part, then what
        # corrects q, the checks and the contact force, at the current time
        self.start_rows = np.asfortranarray(np.vstack([np.atleast_2d(x) for x in (
            f1 - f_s * one, comb1[nz:2 * nz], comb1[2 * nz:], z, vz, heights, slopes, ring1,
            change, comb1[:nz], comb1[nz:2 * nz], sim.cos[None, :] @ f1)]))
        # a ring truncated to no modes has an empty q: BLAS refuses empty vectors, and there
        # is nothing to read from or to advance (its readout r stays zero)
        self.ring_modes = sim.ring.n_modes > 0
        self.start_change = slice(5 * nz + 5, 6 * nz + 5)
        self.start_checks = slice(6 * nz + 5, 8 * nz + 5)
        self.start_pattern = np.tile(active, 2).tobytes()
        self.start_signs = np.zeros(2 * nz, dtype=bool)
        self.y_start = np.zeros(self.start_rows.shape[0])
        # the substep: its base reads q after the start's correction, q + G_f change
        k2 = 2 * sim.ring.n_modes
        base_q = kernel.base[:, :k2]
        g_f = kernel.gain[:, 2 + nz:]
        df1 = f1 - f_s * one
        buffer_part = kernel.base[:, k2:]  # on [z, ż, Δf(t), Δf(t+h), heights, slopes, 1]
        inputs = np.vstack([z, vz, df1, np.zeros((nz, n)), heights, slopes, one])
        base2 = r + (base_q @ g_f) @ change + buffer_part @ inputs
        f2 = solve(base2)
        comb2 = base2[:3 * nz] + m @ f2
        df2 = f2 - f_s * one
        ring2 = base2[3 * nz:] + kernel.out_f @ df2
        h = kernel.h
        rows = [df2, comb2[nz:2 * nz], comb2[2 * nz:], z + h * vz, vz, heights + h * slopes,
                slopes, ring2]
        self.new_state = 5 * nz + 5  # rows of y that are the state's first part, in order
        rows += [change, z, vz, df1, df2]  # what advances q
        self.q_rows = slice(self.new_state, self.new_state + 3 * nz + 2)
        rows += [comb1[:nz], comb1[nz:2 * nz], comb2[:nz], comb2[nz:2 * nz]]  # the checks
        self.checks = slice(self.q_rows.stop, self.q_rows.stop + 4 * nz)
        rows += [sim.cos[None, :] @ f2]
        self.contact_row = self.checks.stop
        self.t = np.asfortranarray(np.vstack([np.atleast_2d(x) for x in rows]))
        self.base_q = np.asfortranarray(base_q)
        self.g_f = np.asfortranarray(g_f)
        decayed = (g_f[0::2] + 1j * g_f[1::2]) * kernel.decay[:, None]
        self.u = np.asfortranarray(np.hstack([_gain_pairs(decayed), kernel.gain]))
        self.decay = kernel.decay
        self.pattern = np.tile(active, 4).tobytes()
        self.check = not sim.linear
        self.signs = np.zeros(4 * nz, dtype=bool)
        self.y = np.zeros(self.t.shape[0])
        # the footprint's edges lie between the same nodes while the active set holds
        on = np.flatnonzero(active)
        x = sim.x_road
        # (the unilateral law's pushing nodes are the active set; a two-sided spring can pull)
        self.edges = None if sim.linear or not on.size or on[0] == 0 or on[-1] == nz - 1 else (
            int(on[0]), int(on[0] - 1), float(x[on[0]]), float(x[on[0] - 1] - x[on[0]]),
            int(on[-1]), int(on[-1] + 1), float(x[on[-1]]), float(x[on[-1] + 1] - x[on[-1]]))

    def start(self, sim: ContactSimulator, z: float, vz: float) -> bool:
        """ContactSimulator._start as one product, for the inputs given at the current time
        (the road already read into the state); False, with nothing changed, when the
        active set would change."""
        nz = sim.n_zone
        state = sim._state
        state[5 * nz + 5], state[5 * nz + 6] = z, vz
        y = self.y_start
        dgemv(1.0, self.start_rows, sim._rw, 0.0, y, 0, 1, 0, 1, 0, 1)
        if self.check:
            np.greater(y[self.start_checks], 0.0, out=self.start_signs)
            if self.start_signs.tobytes() != self.start_pattern:
                return False
        if self.ring_modes:
            dgemv(1.0, self.g_f, y[self.start_change], 1.0, sim._q_pairs, 0, 1, 0, 1, 0, 1)
        state[:self.new_state] = y[:self.new_state]
        sim._values = self._outputs(sim, float(y[-1]))
        return True

    def _outputs(self, sim: ContactSimulator, contact_fz: float) -> tuple[float, ...]:
        nz = sim.n_zone
        state = sim._state
        rim_fz, rim_fx, tread = (sim.static_ring + state[5 * nz + 2:5 * nz + 5]).tolist()
        # ContactSimulator.deflection, in floats
        deflection = sim.static_deflection + state.item(sim._centre_height) - state.item(3 * nz)
        edges = self.edges
        if edges is None:
            length = sim.contact_length()
        else:  # _edges with the nodes known: the same interpolation, in floats
            pen = sim._s_pen
            a, b, xa, dxa, c, d, xc, dxc = edges
            pa, pb, pc, pd = float(pen[a]), float(pen[b]), float(pen[c]), float(pen[d])
            front = xa + (min(pa / (pa - pb), 1.0) if pa > max(pb, 0.0) else 0.0) * dxa
            rear = xc + (min(pc / (pc - pd), 1.0) if pc > max(pd, 0.0) else 0.0) * dxc
            length = front - rear
        return rim_fz, rim_fx, contact_fz, deflection, length, tread

    def advance(self, sim: ContactSimulator, z: float, vz: float) -> bool:
        nz = sim.n_zone
        state, rw = sim._state, sim._rw
        state[5 * nz + 5], state[5 * nz + 6] = z, vz
        if self.ring_modes:
            dgemv(1.0, self.base_q, sim._q_pairs, 0.0, rw, 0, 1, 0, 1, 0, 1)
        y = self.y
        dgemv(1.0, self.t, rw, 0.0, y, 0, 1, 0, 1, 0, 1)
        if self.check:
            np.greater(y[self.checks], 0.0, out=self.signs)
            if self.signs.tobytes() != self.pattern:
                return False  # the active set changes: the general path takes this step
        if self.ring_modes:
            sim._q *= self.decay
            dgemv(1.0, self.u, y[self.q_rows], 1.0, sim._q_pairs, 0, 1, 0, 1, 0, 1)
        state[:self.new_state] = y[:self.new_state]
        sim._values = self._outputs(sim, float(y[self.contact_row]))
        return True


def _pairs(matrix: np.ndarray) -> np.ndarray:
    """Re(M q) as a real matrix on q stored as (re, im) pairs."""
    out = np.empty((matrix.shape[0], 2 * matrix.shape[1]))
    out[:, 0::2], out[:, 1::2] = matrix.real, -matrix.imag
    return out


def _gain_pairs(gain: np.ndarray) -> np.ndarray:
    """A complex (K, m) gain as (2K, m) real rows, re and im interleaved as q is stored."""
    out = np.empty((2 * gain.shape[0], gain.shape[1]), order="F")
    out[0::2], out[1::2] = gain.real, gain.imag
    return out


class ContactSimulator:
    """Steps a :class:`ContactModel` from communication point to communication point.

    Outputs are totals: rim_Fz, rim_Fx (tire on rim), contact_Fz (road on tire, never
    negative with the unilateral law), deflection (the rim's lowering towards the road at the
    contact centre: the static footprint's, plus the road's rise under the centre node, less
    the rim's: it goes negative when the rim lifts clear), contact_length (footprint length
    on the road, m) and tread_deflection (the tread's compression at the contact centre
    relative to the rim).

    Its clock is the time since ``start_time`` (:mod:`.clock`): the road history is indexed
    by it, so a run gives the same outputs whenever it starts; ``time`` is start + elapsed.

    The state lives in one real buffer [q as (re, im) pairs, z, ż, Δf(t), Δf(t + h), road
    heights, road slopes, 1] that a step reads with one matrix-vector product. Besides q it
    keeps what the contact saw at the current time (penetrations, rates, the inputs the last
    step ramped to), so the forces for new inputs follow by the law alone (module doc).
    """

    def __init__(self, contact: ContactModel, start_time: float = 0.0):
        self.contact = contact
        ring, patch = contact.ring, contact.patch
        self.ring = ring
        self.zone = patch.zone
        self.n_zone = z = ring.n_zone
        self.k = patch.zone.stiffness_n_per_m
        self.c = patch.zone.damping_n_s_per_m
        self.cos = patch.zone.cos
        self.sec = 1.0 / self.cos
        self.f_static = patch.forces_n.copy()
        self.pen_static = (patch.footprint.penetration_m.copy() if patch.footprint is not None
                           else self.f_static / self.k)
        self.static_active = self.f_static > 0
        self.linear = contact.settings.law == "linear"
        self.x_road = self.zone.road_positions_m(patch.deflection_m)
        statics = contact.static_outputs
        self.static_ring = np.array([statics["rim_Fz"], statics["rim_Fx"],
                                     statics["tread_deflection"]])
        self.static_deflection = float(statics["deflection"])
        self._centre = self.zone.centre
        self._centre_height = 3 * z + 2 + self._centre  # in the state array: seen heights
        # each mode's largest reach into a zone displacement and rate (for a state's bounds)
        self._mode_reach = np.abs(ring.c[3:3 + z]).max(axis=0, initial=0.0)
        self._mode_rate = np.abs(ring.c[3 + z:3 + 2 * z]).max(axis=0, initial=0.0)
        self._w, self._rate = slice(3, 3 + z), slice(3 + z, 3 + 2 * z)
        self.road = RoadReader(contact.windows)
        d, e = ring.d, ring.e
        # how the rim's own motion moves the penetrations and the ring outputs at an instant
        self._pen_rim = d[self._w, 0] - self.sec
        self._rate_rim = e[self._rate, 0] - self.sec
        self._out_rim, self._out_rim_rate = d[:3, 0].copy(), e[:3, 0].copy()
        d_f = d[:, 1:]
        self._truncated = bool(np.any(d_f) or np.any(e[:, 1:]))
        self._instant = None
        self.min_step_s = MIN_CORRECTED_STEP_S if self._truncated else 0.0
        if self._truncated:
            m = np.vstack([self.k[:, None] * d_f[self._w] + self.c[:, None] * d_f[self._rate],
                           d_f[self._w], d_f[self._rate]])
            self._instant = _Interface(np.asfortranarray(m))
            self._out_f_instant = d_f[:3].copy()
        k2 = 2 * ring.n_modes
        self._q_slice = slice(0, k2)
        self._in_slice = slice(k2, k2 + 2 + 2 * z)  # z, ż, Δf(t), Δf(t+h)
        self._df0 = slice(k2 + 2, k2 + 2 + z)
        self._df1 = slice(k2 + 2 + z, k2 + 2 + 2 * z)
        self._heights = slice(k2 + 2 + 2 * z, k2 + 2 + 3 * z)
        self._slopes = slice(k2 + 2 + 3 * z, k2 + 2 + 4 * z)
        self._buffer = np.zeros(k2 + 3 + 4 * z)
        self._buffer[-1] = 1.0
        self._q_pairs = self._buffer[self._q_slice]
        self._q = self._q_pairs.view(complex)
        self._kernels: dict[float, _Step] = {}
        # The contact's own state lives in one array behind the ring readout r that the fast
        # step reads (see _FastStep): [r (3Z + 3) | Δf, p, ṗ, seen z, ż, heights, slopes,
        # ring outputs, inputs z, ż, heights, slopes, 1].
        self._n_read = 3 * z + 3
        self._rw = np.zeros(self._n_read + 7 * z + 8)
        self._rw[-1] = 1.0
        state = self._rw[self._n_read:]
        self._state = state
        self._s_df, self._s_pen, self._s_rate = state[:z], state[z:2 * z], state[2 * z:3 * z]
        self._s_seen_h, self._s_seen_s = state[3 * z + 2:4 * z + 2], state[4 * z + 2:5 * z + 2]
        self._s_ring = state[5 * z + 2:5 * z + 5]
        self._s_heights, self._s_slopes = state[5 * z + 7:6 * z + 7], state[6 * z + 7:7 * z + 7]
        self._road_h, self._road_v = self._s_heights, self._s_slopes  # the road reads here
        self._s_road = state[5 * z + 7:7 * z + 7]  # both, contiguous
        self._fast: dict[tuple, _FastStep] = {}
        self._fast_run = 0  # steps in a row with the same kernel and active set
        self.solver_fallbacks = 0
        self.reset(start_time)

    # -- the contact's state, in the state array ---------------------------------------------
    @property
    def df(self) -> np.ndarray:
        return self._s_df

    @df.setter
    def df(self, value) -> None:
        self._s_df[:] = value

    @property
    def penetration(self) -> np.ndarray:
        return self._s_pen

    @penetration.setter
    def penetration(self, value) -> None:
        self._s_pen[:] = value

    @property
    def rate(self) -> np.ndarray:
        return self._s_rate

    @rate.setter
    def rate(self, value) -> None:
        self._s_rate[:] = value

    @property
    def _seen(self) -> tuple:
        z = self.n_zone
        return (float(self._state[3 * z]), float(self._state[3 * z + 1]), self._s_seen_h,
                self._s_seen_s)

    @_seen.setter
    def _seen(self, value) -> None:
        z = self.n_zone
        self._state[3 * z], self._state[3 * z + 1] = value[0], value[1]
        self._s_seen_h[:], self._s_seen_s[:] = value[2], value[3]

    @property
    def _ring_out(self) -> np.ndarray:
        return self._s_ring

    @_ring_out.setter
    def _ring_out(self, value) -> None:
        self._s_ring[:] = value

    # -- state ---------------------------------------------------------------------------
    def reset(self, start_time: float = 0.0) -> None:
        self.start_time = float(start_time)
        self.elapsed_s = 0.0  # time since the start: what the road history is indexed by
        self._carry_s = 0.0  # what the compensated sum of the steps carries (clock.advance)
        self._buffer[:-1] = 0.0
        self._rw[:-1] = 0.0
        self._fast_run = 0
        z = self.n_zone
        self.df = np.zeros(z)  # force deviation from static at `time`
        self.active = self.static_active.copy()
        # what the contact saw at `time`, and the inputs it saw it with
        self.penetration = self.pen_static.copy()
        self.rate = np.zeros(z)
        self._seen = (0.0, 0.0, np.zeros(z), np.zeros(z))  # z, ż, heights, slopes
        self._ring_out = np.zeros(3)  # deviation of rim_Fz, rim_Fx, deflection at `time`
        self._last: _Kernel | None = None  # the last substep, whose end _start may re-solve
        self._last_step_s = math.nan
        self.road.reset(self.start_time)
        self._values = self._outputs()

    @property
    def time(self) -> float:
        """The absolute time: start_time + elapsed_s (what a host's clock shows)."""
        return self.start_time + self.elapsed_s

    @property
    def q(self) -> np.ndarray:
        return self._q.copy()

    @property
    def forces(self) -> np.ndarray:
        """The road's push on each zone node at ``time`` (N)."""
        return self.f_static + self.df

    @property
    def in_contact(self) -> bool:
        return bool(np.any(self.forces > 0.0))

    @property
    def outputs(self) -> np.ndarray:
        return np.array(self._values)

    def output_dict(self) -> dict[str, float]:
        return dict(zip(OUTPUT_NAMES, self._values))

    def at_zone_edge(self) -> bool:
        """Whether a zone end node pushes: the footprint may reach beyond the zone."""
        df, fs = self._s_df, self.f_static
        return df[0] > -fs[0] or df[-1] > -fs[-1]

    # -- stepping ----------------------------------------------------------------------------
    def step(self, h: float, rim_z: float, rim_vz: float, road_z: float, road_vz: float
             ) -> np.ndarray:
        return np.array(self.step_values(h, rim_z, rim_vz, road_z, road_vz))

    def step_values(self, h: float, rim_z: float, rim_vz: float, road_z: float,
                    road_vz: float) -> tuple[float, ...]:
        """Advance from ``time`` to ``time + h`` with the inputs given at ``time`` (ramped
        with their rates); returns the total outputs at the new time."""
        if not (h > 0.0 and math.isfinite(h)) or h < self.min_step_s \
                or (rim_z + rim_vz + road_z + road_vz) * 0.0 != 0.0 \
                or abs(rim_z) > MAX_DISPLACEMENT_M or abs(road_z) > MAX_DISPLACEMENT_M \
                or abs(rim_vz) > MAX_VELOCITY_M_S or abs(road_vz) > MAX_VELOCITY_M_S:
            self._check(h, (rim_z, rim_vz, road_z, road_vz))
        # clock.resolves(time, h), with the limit cached for the h of a cached step
        step = self._kernels.get(h)
        if step is None:
            if not clock.resolves(self.time, h):
                self._check(h, (rim_z, rim_vz, road_z, road_vz))
            step = self._kernel(h)
        elif not abs(self.start_time + self.elapsed_s) + h < step.resolved_until_s:
            self._check(h, (rim_z, rim_vz, road_z, road_vz))
        kernel, n_sub = step.last, step.n_sub
        heights, slopes = self._road_h, self._road_v
        self.road.read(self.elapsed_s, road_z, road_vz, h, self._s_road)
        steady = n_sub == 1 and kernel is self._last
        if steady and self._fast_run >= _FAST_AFTER and self._fast_step(kernel, rim_z, rim_vz):
            self._fast_run += 1
            y = h - self._carry_s  # clock.advance, inlined on the hot path
            elapsed = self.elapsed_s + y
            self._carry_s = (elapsed - self.elapsed_s) - y
            self.elapsed_s = elapsed
            self._last_step_s = h
            return self._values
        before = self.active.copy()
        self._start(rim_z, rim_vz, heights, slopes)
        buffer = self._buffer
        buffer[self._heights], buffer[self._slopes] = heights, slopes
        for i in range(n_sub):
            self._substep(kernel, rim_z + i * kernel.h * rim_vz, rim_vz)
        self.elapsed_s, self._carry_s = clock.advance(self.elapsed_s, self._carry_s, h)
        self._last_step_s = h
        # steps in a row on one kernel that kept their active set: the rule for the fast
        # step, a function of the state alone (so a restored state takes the same path)
        self._fast_run = self._fast_run + 1 if steady and np.array_equal(
            before, self.active) else 0
        self._values = self._outputs()
        return self._values

    def _fast_map(self, kernel: _Kernel) -> _FastStep:
        active = self.static_active if self.linear else self.active
        key = (kernel.h, active.tobytes())
        fast = self._fast.get(key)
        if fast is None:
            fast = _FastStep(self, kernel, active)
            if len(self._fast) >= _FAST_CACHE_SIZE:
                self._fast.pop(next(iter(self._fast)))
            self._fast[key] = fast
        return fast

    def _fast_step(self, kernel: _Kernel, z: float, vz: float) -> bool:
        """The step as one linear map, when the active set stays what it was (see
        _FastStep); False, with nothing changed, when it does not."""
        if not self._fast_map(kernel).advance(self, z, vz):
            self._fast_run = 0
            return False
        return True

    def outputs_with(self, rim_z: float, rim_vz: float, road_z: float, road_vz: float
                     ) -> tuple[float, ...]:
        """Total outputs at ``time`` for inputs given at ``time``; the state keeps the
        re-evaluated forces, which the next step starts from."""
        if (rim_z + rim_vz + road_z + road_vz) * 0.0 != 0.0 or abs(rim_z) > MAX_DISPLACEMENT_M \
                or abs(road_z) > MAX_DISPLACEMENT_M or abs(rim_vz) > MAX_VELOCITY_M_S \
                or abs(road_vz) > MAX_VELOCITY_M_S:
            self._check(None, (rim_z, rim_vz, road_z, road_vz))
        heights, slopes = self._road_h, self._road_v
        # recorded like a step's own sample: the step at this point replaces it
        self.road.read(self.elapsed_s, road_z, road_vz, self._last_step_s, self._s_road)
        last = self._last
        if last is not None and self._fast_run >= _FAST_AFTER:
            if self._fast_map(last).start(self, rim_z, rim_vz):
                return self._values
        self._start(rim_z, rim_vz, heights, slopes)
        self._values = self._outputs()
        return self._values

    def _check(self, h: float | None, values: tuple) -> None:
        """Raise StepError naming every bad value (h, an input outside its range, or a step
        the clock does not resolve at the current time; None: no step, the inputs only)."""
        problems = []
        if h is None:
            pass
        elif not (h > 0.0 and math.isfinite(h)):
            problems.append(f"step size h = {h!r} s: must be finite and > 0")
        elif h < self.min_step_s:
            problems.append(SHORT_STEP_TEMPLATE % (repr(h), self.min_step_s))
        elif not clock.resolves(self.time, h):
            problems.append(clock.resolution_problem(self.time, h))
        for name, value in zip(INPUT_NAMES, values):
            limit, unit = ((MAX_VELOCITY_M_S, "m/s") if name.endswith("vz")
                           else (MAX_DISPLACEMENT_M, "m"))
            if not (math.isfinite(value) and abs(value) <= limit):
                problems.append(f"{name} = {value!r} {unit}: must be in [-{limit:g}, "
                                f"{limit:g}] {unit}")
        if problems:
            raise StepError("; ".join(problems))

    def _start(self, z: float, vz: float, heights: np.ndarray, slopes: np.ndarray) -> None:
        """Forces at ``time`` for the inputs given at ``time``.

        The last step ended with the inputs it ramped to; the host's inputs for this point
        differ from those by O(h²) in position and O(h) in rate, and at a contact this stiff
        (k/K_v ~ 70) that difference matters. So the last step's end is solved again with the
        inputs given now: the penetrations move with the inputs' change (geometry at an
        instant) and with the end forces through the step's own flexibility, and the modal
        state takes the corrected force ramp. Without a previous step (after a reset) the
        forces follow from the law at the instant.
        """
        z_seen, vz_seen, heights_seen, slopes_seen = self._seen
        dz, dvz = z - z_seen, vz - vz_seen
        pen = self.penetration + self._pen_rim * dz + self.sec * (heights - heights_seen)
        rate = self.rate + self._rate_rim * dvz + self.sec * (slopes - slopes_seen)
        self._ring_out = self._ring_out + self._out_rim * dz + self._out_rim_rate * dvz
        last = self._last
        if last is not None:
            f_old = self.f_static + self.df
            m = last.interface.m
            nz = self.n_zone
            base = np.concatenate([self.k * pen + self.c * rate, pen, rate]) - m @ f_old
            f = self._solve(last.interface, base)
            change = f - f_old
            self._q_pairs += last.gain[:, 2 + nz:] @ change
            self._ring_out = self._ring_out + last.out_f @ change
            combined = base + m @ f
            pen, rate = combined[nz:2 * nz], combined[2 * nz:]
        elif self.linear:
            f = np.where(self.static_active, self.f_static + self.k * (pen - self.pen_static)
                         + self.c * rate, 0.0)
        elif self._instant is not None:  # a truncated ring couples the forces at an instant
            f_old = self.f_static + self.df
            base = np.concatenate([self.k * pen + self.c * rate, pen, rate])
            base -= self._instant.m @ f_old
            f = self._solve(self._instant, base)
            self._ring_out = self._ring_out + self._out_f_instant @ (f - f_old)
            combined = base + self._instant.m @ f
            pen, rate = combined[self.n_zone:2 * self.n_zone], combined[2 * self.n_zone:]
        else:
            f = contact_force(pen, rate, self.k, self.c)
            self.active = f > 0.0
        self.df = f - self.f_static
        self.penetration, self.rate = pen, rate
        self._seen = (z, vz, heights.copy(), slopes.copy())

    def _substep(self, k: _Kernel, z: float, vz: float) -> None:
        buffer = self._buffer
        h = k.h
        buffer[self._q_slice.stop], buffer[self._q_slice.stop + 1] = z, vz
        buffer[self._df0] = self.df
        buffer[self._df1] = 0.0
        base = k.base @ buffer
        nz = self.n_zone
        f = self._solve(k.interface, base[:3 * nz])
        df_end = f - self.f_static
        combined = base[:3 * nz] + k.interface.m @ f
        buffer[self._df1] = df_end
        self._q *= k.decay
        buffer[self._q_slice] += k.gain @ buffer[self._in_slice]
        self._ring_out = base[3 * nz:] + k.out_f @ df_end
        self.df = df_end
        self._last = k
        self.penetration = combined[nz:2 * nz]
        self.rate = combined[2 * nz:]
        heights = buffer[self._heights]
        slopes = buffer[self._slopes]
        heights += h * slopes  # the road ramps on into the next substep
        self._seen = (z + h * vz, vz, heights.copy(), slopes.copy())

    def _solve(self, interface: _Interface, base: np.ndarray) -> np.ndarray:
        """Total forces with [σ; p; ṗ] = base + M f and the law (or two-sided springs on the
        static footprint for the linear law)."""
        nz = self.n_zone
        sigma0 = base[:nz]
        if self.linear:
            f = np.zeros(nz)
            f[self.static_active] = self._active_solve(interface, self.static_active, sigma0)
            return f
        active = self.active
        m = interface.m
        for _ in range(ACTIVE_SET_PER_NODE * nz + ACTIVE_SET_EXTRA):
            f = np.zeros(nz)
            if active.any():
                f[active] = self._active_solve(interface, active, sigma0)
            combined = base + m @ f
            new = (combined[nz:2 * nz] > 0.0) & (combined[:nz] > 0.0)
            if np.array_equal(new, active):
                self.active = active
                return np.maximum(f, 0.0)
            active = new
        return self._fallback(interface, base)

    @staticmethod
    def _active_solve(interface: _Interface, active: np.ndarray, sigma0: np.ndarray):
        key = active.tobytes()
        inverse = interface.solves.get(key)
        if inverse is None:
            block = interface.s[np.ix_(active, active)]
            inverse = np.linalg.inv(np.eye(block.shape[0]) - block)
            if len(interface.solves) >= _SOLVE_CACHE_SIZE:
                interface.solves.pop(next(iter(interface.solves)))
            interface.solves[key] = inverse
        return inverse @ sigma0[active]

    def _fallback(self, interface: _Interface, base: np.ndarray) -> np.ndarray:
        """Projected Gauss-Seidel on the same law, for an active set that cycles."""
        self.solver_fallbacks += 1
        nz = self.n_zone
        s, w_p = interface.m[:nz], interface.m[nz:2 * nz]
        f = np.maximum(self.forces, 0.0)
        for _ in range(PGS_SWEEPS):
            previous = f.copy()
            for j in range(nz):
                pen_j = base[nz + j] + w_p[j] @ f
                rest = base[j] + s[j] @ f - s[j, j] * f[j]
                f[j] = max(0.0, rest / (1.0 - s[j, j])) if pen_j > 0.0 else 0.0
            if np.max(np.abs(f - previous)) <= PGS_TOLERANCE * max(1.0, float(np.max(np.abs(f)))):
                break
        self.active = f > 0.0
        return f

    def _kernel(self, h: float) -> _Step:
        """The communication step h: its substep's coefficients, cached per h (a step within
        rounding of a cached one is that step: hosts jitter h in the last bits)."""
        for cached_h, step in self._kernels.items():
            if abs(h - cached_h) <= SAME_POINT_EPS * (abs(self.time) + h):
                return step
        n_sub = max(1, math.ceil(h / self.contact.substep_s * (1 - SUBSTEP_SLACK)))
        step = _Step(h, n_sub, self._make_kernel(h / n_sub), clock.resolved_until(h))
        if len(self._kernels) >= _KERNEL_CACHE_SIZE:
            self._kernels.pop(next(iter(self._kernels)))
        self._kernels[h] = step
        return step

    def _make_kernel(self, h: float) -> _Kernel:
        ring = self.ring
        lam = ring.eigenvalues
        nz = self.n_zone
        phi1, phi2 = phi_functions(lam * h)
        decay = np.exp(lam * h)
        b_rim, b_f = ring.b[:, :1], ring.b[:, 1:]
        # q(t+h) = e^{λh} q + hφ1 b_rim z + h²φ2 b_rim ż + h(φ1 - φ2) b_f Δf(t) + hφ2 b_f Δf(t+h)
        g_in = np.hstack([(h * phi1)[:, None] * b_rim, (h * h * phi2)[:, None] * b_rim,
                          (h * (phi1 - phi2))[:, None] * b_f])
        g_f = (h * phi2)[:, None] * b_f
        c = ring.c
        d_rim, e_rim = ring.d[:, 0], ring.e[:, 0]
        d_f, e_f = ring.d[:, 1:], ring.e[:, 1:]
        # ring outputs at t + h: Re(C q(t+h)) + D r + E ṙ, r = [z + h ż, Δf(t+h)],
        # ṙ = [ż, (Δf(t+h) - Δf(t))/h]
        on_in = np.real(c @ g_in) + np.column_stack([d_rim, h * d_rim + e_rim, -e_f / h])
        on_f = np.real(c @ g_f) + d_f + e_f / h
        on_q = _pairs(c * decay[None, :])
        rows = 3 + 2 * nz
        size = self._buffer.size
        y = np.zeros((rows, size))
        y[:, self._q_slice] = on_q
        y[:, self._q_slice.stop:self._q_slice.stop + 2 + nz] = on_in
        w, rate = self._w, self._rate
        # penetrations and rates at t + h (Δf(t+h) = 0): the gap's rim, road and static parts
        pen = y[w].copy()
        pen[:, self._q_slice.stop] -= self.sec  # -(z + h ż)/cos
        pen[:, self._q_slice.stop + 1] -= h * self.sec
        pen[:, self._heights] += np.diag(self.sec)  # road at t + h: heights + h slopes
        pen[:, self._slopes] += h * np.diag(self.sec)
        pen[:, -1] += self.pen_static
        pen_rate = y[rate].copy()
        pen_rate[:, self._q_slice.stop + 1] -= self.sec
        pen_rate[:, self._slopes] += np.diag(self.sec)
        w_p, w_r = on_f[w], on_f[rate]
        # rows in terms of the total end forces f: Δf(t+h) = f - f_static
        pen[:, -1] -= w_p @ self.f_static
        pen_rate[:, -1] -= w_r @ self.f_static
        sigma0 = self.k[:, None] * pen + self.c[:, None] * pen_rate
        s = self.k[:, None] * w_p + self.c[:, None] * w_r
        base = np.vstack([sigma0, pen, pen_rate, y[:3]])
        interface = _Interface(np.asfortranarray(np.vstack([s, w_p, w_r])))
        return _Kernel(h=h, decay=decay, base=np.ascontiguousarray(base),
                       out_f=on_f[:3].copy(),
                       gain=_gain_pairs(np.hstack([g_in, g_f])), interface=interface)

    # -- outputs -------------------------------------------------------------------------------
    def _outputs(self) -> tuple[float, ...]:
        ring = self.static_ring + self._ring_out
        contact_fz = float(self.cos @ (self.f_static + self.df))
        return (float(ring[0]), float(ring[1]), contact_fz, self.deflection(),
                self.contact_length(), float(ring[2]))

    def deflection(self) -> float:
        """The rim's lowering towards the road at the contact centre at ``time`` (m): the
        static footprint's, plus the rise of the road under the centre node, less the rim's."""
        state = self._state
        return self.static_deflection + state.item(self._centre_height) \
            - state.item(3 * self.n_zone)

    def contact_length(self) -> float:
        """Footprint length on the road (m) at ``time``: between the interpolated edges."""
        active = (self.f_static + self.df) > 0.0
        front, rear = _edges(self.x_road, self.penetration, active)
        return front - rear


# -- state ------------------------------------------------------------------------------------

class StateError(ValueError):
    """A state that is not one of this simulator (format, checksum, shape, or what it holds
    does not mean a state of this tire: see :meth:`ContactSimulator.state_problems`)."""


@dataclass(frozen=True, eq=False)
class ContactState:
    """Everything a :class:`ContactSimulator` needs to resume exactly (copies)."""

    start_time: float
    elapsed_s: float  # time since the start (the road history's clock)
    carry_s: float  # the compensation of the elapsed time's sum (clock.advance)
    last_step_s: float  # the communication step whose end the next start re-solves (nan: none)
    q: np.ndarray  # complex modal state
    df: np.ndarray
    active: np.ndarray
    penetration: np.ndarray
    rate: np.ndarray
    seen: np.ndarray  # [z, ż, heights (Z), slopes (Z)] the contact last saw
    ring_out: np.ndarray
    history_t: np.ndarray
    history_z: np.ndarray
    history_v: np.ndarray
    road_line: np.ndarray  # the delay line's buffer while it runs (empty otherwise)
    road_run: np.ndarray  # uniform samples counted so far (-1: count again)
    fast_run: np.ndarray  # steps in a row that kept their kernel and active set
    outputs: np.ndarray

    _ARRAYS = ("q", "df", "active", "penetration", "rate", "seen", "ring_out", "history_t",
               "history_z", "history_v", "road_line", "road_run", "fast_run", "outputs")
    _SCALARS = ("start_time", "elapsed_s", "carry_s", "last_step_s")

    @property
    def time(self) -> float:
        return self.start_time + self.elapsed_s

    def to_bytes(self) -> bytes:
        """A self-checking byte string: a JSON header (format, scalars, array layout, SHA-256
        of everything after it) on one line, then the raw little-endian arrays."""
        arrays = {name: np.ascontiguousarray(getattr(self, name)) for name in self._ARRAYS}
        payload = b"".join(a.astype(a.dtype.newbyteorder("<")).tobytes()
                           for a in arrays.values())
        header = {"format": _STATE_FORMAT,
                  **{name: getattr(self, name) for name in self._SCALARS},
                  "arrays": {name: [a.dtype.str.replace(">", "<"), list(a.shape)]
                             for name, a in arrays.items()},
                  "sha256": hashlib.sha256(payload).hexdigest()}
        return json.dumps(header, allow_nan=True).encode() + b"\n" + payload

    @classmethod
    def from_bytes(cls, data: bytes) -> ContactState:
        """The state in ``data``, checked for its format, checksum and finite values (what it
        means is checked when it is set: ContactSimulator.state_problems)."""
        data = bytes(data)
        head, sep, payload = data.partition(b"\n")
        try:
            header = json.loads(head.decode("utf-8"))
        except (UnicodeDecodeError, ValueError) as error:
            raise StateError(f"not a tire_fmu contact state: header unreadable ({error})"
                             ) from error
        if not isinstance(header, dict) or header.get("format") != _STATE_FORMAT:
            raise StateError(f"not a tire_fmu contact state of this version: format "
                             f"{header.get('format') if isinstance(header, dict) else header!r}")
        if not sep or hashlib.sha256(payload).hexdigest() != header.get("sha256"):
            raise StateError("contact state damaged: its checksum does not match")
        arrays, offset = {}, 0
        try:
            for name in cls._ARRAYS:
                dtype, shape = header["arrays"][name]
                dtype = np.dtype(dtype)
                count = int(np.prod(shape, dtype=int))
                size = count * dtype.itemsize
                arrays[name] = np.frombuffer(payload, dtype, count, offset).reshape(shape).copy()
                offset += size
            scalars = {name: float(header[name]) for name in cls._SCALARS}
        except (KeyError, TypeError, ValueError) as error:
            raise StateError(f"contact state damaged: {error}") from error
        if offset != len(payload):
            raise StateError(f"contact state damaged: {len(payload) - offset} bytes too many")
        last = scalars["last_step_s"]
        if not all(math.isfinite(scalars[n]) for n in ("start_time", "elapsed_s", "carry_s")) \
                or not (math.isnan(last) or (last > 0 and math.isfinite(last))):
            raise StateError("contact state has start time = {start_time!r}, elapsed time = "
                             "{elapsed_s!r}, carry = {carry_s!r}, last step = {last_step_s!r}"
                             .format(**scalars))
        for name, array in arrays.items():
            if array.dtype.kind in "fc" and not np.all(np.isfinite(array)):
                raise StateError(f"contact state has non-finite values in {name}")
        arrays["active"] = arrays["active"].astype(bool)
        return cls(**scalars, **arrays)


def _state_methods():
    def get_state(self: ContactSimulator) -> ContactState:
        z, vz, heights, slopes = self._seen
        return ContactState(
            start_time=self.start_time, elapsed_s=self.elapsed_s, carry_s=self._carry_s,
            last_step_s=self._last_step_s, q=self._q.copy(), df=self.df.copy(),
            active=self.active.copy(), penetration=self.penetration.copy(),
            rate=self.rate.copy(), seen=np.concatenate([[z, vz], heights, slopes]),
            ring_out=self._ring_out.copy(), **self.road.get_state(),
            fast_run=np.array([self._fast_run], dtype=np.int64),
            outputs=np.array(self._values))

    def state_problems(self: ContactSimulator, state: ContactState) -> list[str]:
        """Everything that makes ``state`` no state of this simulator: empty when it is one.

        Beyond its shapes (the same model), what it holds must mean a state of this tire:
        a clock that a run reaches (time since the start >= 0 and as its steps sum it, a last
        step the clock resolves); a road history as the reader keeps it
        (:meth:`RoadReader.state_problems`); forces that do not pull with the unilateral law;
        displacements and rates within MAX_STATE_DISPLACEMENT_M and MAX_STATE_VELOCITY_M_S
        (each mode's reach into the zone, the penetrations, what the contact saw) and forces
        within what the zone springs give there; and outputs that are the ones the state
        gives. Every problem is listed.
        """
        nz = self.n_zone
        expected = {"q": (self.ring.n_modes,), "df": (nz,), "active": (nz,),
                    "penetration": (nz,), "rate": (nz,), "seen": (2 + 2 * nz,),
                    "ring_out": (3,), "outputs": (len(OUTPUT_NAMES),), "road_run": (1,)}
        wrong = [f"{name} has shape {getattr(state, name).shape}, expected {shape}"
                 for name, shape in expected.items() if getattr(state, name).shape != shape]
        sizes = {state.history_t.shape, state.history_z.shape, state.history_v.shape}
        if len(sizes) != 1 or len(next(iter(sizes))) != 1 or state.road_line.ndim != 1:
            wrong.append("the road history arrays differ in shape")
        if wrong:
            return ["state of another model (build both with the same parameters): "
                    + "; ".join(wrong)]
        problems = []
        elapsed, last = state.elapsed_s, state.last_step_s
        if not (elapsed >= 0.0 and abs(state.carry_s) <= math.ulp(elapsed)):
            problems.append(f"its clock reads {elapsed!r} s since the start with a carry of "
                            f"{state.carry_s!r} s: a run's clock is >= 0, and its carry below "
                            "one rounding of it")
        if math.isnan(last) != (elapsed == 0.0):
            problems.append(f"its clock reads {elapsed!r} s since the start and its last step "
                            f"is {last!r} s: only steps advance the clock")
        elif not math.isnan(last) and not clock.resolves(state.time - last, last):
            problems.append(f"its last step of {last!r} s ends at t = {state.time!r} s, where "
                            "the clock does not resolve it")
        length, rate = MAX_STATE_DISPLACEMENT_M, MAX_STATE_VELOCITY_M_S
        road = RoadReader(self.contact.windows, origin_s=state.start_time)
        problems += road.state_problems(
            {name: getattr(state, name) for name in (
                "history_t", "history_z", "history_v", "road_line", "road_run")},
            elapsed, last, MAX_DISPLACEMENT_M, MAX_VELOCITY_M_S)
        forces = self.f_static + state.df
        force_bound = self.f_static + self.k * (length + np.abs(self.pen_static)) + self.c * rate
        if not self.linear and np.any(forces < 0.0):
            problems.append("its contact forces pull on the tread (the unilateral contact only "
                            "pushes)")
        if not np.all(np.abs(forces) <= force_bound):
            problems.append("its contact forces exceed what the zone springs give at "
                            f"{length:g} m and {rate:g} m/s")
        q = np.abs(state.q)
        seen = state.seen
        for what, values, bound, unit in (
                ("the tread's excursion at the zone nodes from a mode", q * self._mode_reach,
                 length, "m"),
                ("the tread's rate at the zone nodes from a mode", q * self._mode_rate, rate,
                 "m/s"),
                ("its penetrations", state.penetration, length, "m"),
                ("its penetration rates", state.rate, rate, "m/s"),
                ("the rim and road positions it saw", np.r_[seen[0], seen[2:2 + nz]], length,
                 "m"),
                ("the road rates it saw", seen[2 + nz:], rate, "m/s"),
                ("the tread deflection it holds", state.ring_out[2:], length, "m")):
            if not np.all(np.abs(values) <= bound):
                problems.append(f"{what} reach {float(np.max(np.abs(values))):.3g} {unit}, "
                                f"beyond the {bound:g} {unit} a state may hold")
        if not abs(seen[1]) <= MAX_VELOCITY_M_S:
            problems.append(f"the rim velocity it saw, {float(seen[1])!r} m/s, is beyond the "
                            f"input limit {MAX_VELOCITY_M_S:g} m/s")
        if not np.all(np.abs(state.ring_out[:2]) <= force_bound.sum()):
            problems.append("its rim forces exceed what the zone springs give at "
                            f"{length:g} m and {rate:g} m/s")
        if not problems:
            problems += self._output_problems(state, forces)
        return problems

    def _output_problems(self: ContactSimulator, state: ContactState, forces) -> list[str]:
        """The state's outputs against those its own values give (the contact force and the
        footprint to rounding: the fast step sums them in another order)."""
        ring = self.static_ring + state.ring_out
        seen = state.seen
        deflection = float(self.static_deflection + seen[2 + self._centre] - seen[0])
        contact = float(self.cos @ forces)
        front, rear = _edges(self.x_road, state.penetration, forces > 0.0)
        given = dict(zip(OUTPUT_NAMES, (float(x) for x in state.outputs)))
        scale = float(np.abs(forces).sum() + np.abs(self.f_static).sum())
        expected = {"rim_Fz": (float(ring[0]), 0.0), "rim_Fx": (float(ring[1]), 0.0),
                    "contact_Fz": (contact, 1e-9 * scale), "deflection": (deflection, 0.0),
                    "contact_length": (front - rear,
                                       1e-9 * float(self.x_road[0] - self.x_road[-1])),
                    "tread_deflection": (float(ring[2]), 0.0)}
        assert tuple(expected) == OUTPUT_NAMES
        wrong = [f"{name} = {given[name]!r}, but the state gives {value!r}"
                 for name, (value, tolerance) in expected.items()
                 if not abs(given[name] - value) <= tolerance]
        if wrong:
            return [f"its outputs are not the ones it gives: {'; '.join(wrong)}"]
        return []

    def set_state(self: ContactSimulator, state: ContactState) -> None:
        """Continue from ``state``, exactly as the run it was taken from; StateError listing
        every problem (state_problems) changes nothing."""
        problems = self.state_problems(state)
        if problems:
            raise StateError("; ".join(problems))
        nz = self.n_zone
        road = RoadReader(self.contact.windows, origin_s=state.start_time)
        road.set_state({name: getattr(state, name) for name in (
            "history_t", "history_z", "history_v", "road_line", "road_run")})
        self.road = road  # checked in full before anything changes
        self.start_time, self.elapsed_s = state.start_time, state.elapsed_s
        self._carry_s = state.carry_s
        self._q[:] = state.q
        self.df = state.df.copy()
        self.active = state.active.copy()
        self.penetration, self.rate = state.penetration.copy(), state.rate.copy()
        seen = state.seen
        self._seen = (float(seen[0]), float(seen[1]), seen[2:2 + nz].copy(),
                      seen[2 + nz:].copy())
        self._ring_out = state.ring_out.copy()
        self._fast_run = int(state.fast_run[0]) if state.fast_run.size == 1 else 0
        self._last_step_s = state.last_step_s
        self._last = (None if math.isnan(state.last_step_s)
                      else self._kernel(state.last_step_s).last)
        self._values = tuple(float(v) for v in state.outputs)

    return get_state, state_problems, _output_problems, set_state


(ContactSimulator.get_state, ContactSimulator.state_problems,
 ContactSimulator._output_problems, ContactSimulator.set_state) = _state_methods()
