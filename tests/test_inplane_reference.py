"""The cleat test of the in-plane tire against an unreduced integration written here.

The reference takes only the model's ingredients: the ring's M, C and K at three spins
(``InPlaneRing``; C is linear and K quadratic in the spin, so the three give them at the
wheel's current spin) and the contact points with their interpolation, stiffness and road
windows (``contact_zone``); the cleat's road it writes itself. It writes the contact laws
again as an ordinary differential equation and hands it to scipy's adaptive Runge-Kutta (the
system is stiff only to ~1e5 1/s, which an explicit step follows): nothing of the
simulator's implicit step, its active-set passes, its semi-Lagrangian carry, its road reads
or its static solve is used.

- Normal law: f_n = max(0, k_p pen + c_p pen_rate) while pen > 0, pen along the point's ray.
- Tread element: a Kelvin element (k_x, c_x = β k_x) in series with a Coulomb slider, which is
  exact and continuous in time: the slider moves only when |k_x e + c_x s| would exceed μ f_n,
  and then the element's force is the limit. (The simulator holds e at the limit while a
  point slides; the two differ by the element's own relaxation, 1/β ≈ 9e3 1/s.)
- The element field is carried through the footprint by ∂e/∂t = ė_material - Ω ∂e/∂θ, the
  derivative by the same upwind-biased cubic stencil that the simulator's cubic carry tends
  to as its step goes to zero, with the field read past its ends as the simulator's carry reads it
  (`field_gradient`): the comparison then measures the time stepping and the contact and friction
  laws, not the choice of stencil. The stencil is a spatial discretisation of its own: at 10 mm
  points a second-order upwind stencil moves Fx by a few per cent rms, which is what the spacing
  study of test_inplane_contact bounds.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.sparse import csc_array, csr_array
from scipy.sparse.linalg import splu

from tire_fmu.core.contact import contact_zone
from tire_fmu.core.discretisation import Grid
from tire_fmu.core.inplane import InPlaneRing, InPlaneTire
from tire_fmu.core.inplane_contact import InPlaneSimulator, deflection_for_load
from tire_fmu.core.obstacles import cleat
from tire_fmu.core.parameters import DEFAULT_LOAD_N

MODEL = InPlaneTire()
N, SPEED, SPACING, AHEAD, DURATION = 100, 10.0, 0.01, 0.5, 0.11
CLEAT_HEIGHT_M = CLEAT_LENGTH_M = 0.02
CLEAT = cleat(CLEAT_HEIGHT_M, CLEAT_LENGTH_M)  # the simulator's; the reference's is its own


def rms(a):
    return float(np.sqrt(np.mean(np.square(a))))


def spin_weights(spin_rad_s: float, nominal_rad_s: float) -> np.ndarray:
    """Lagrange weights of the spins 0, Ω0, 2Ω0 at Ω: C is linear and K quadratic in the spin,
    so their values at those three spins give them exactly at any other."""
    x = spin_rad_s / nominal_rad_s
    return np.array([0.5 * (x - 1.0) * (x - 2.0), -x * (x - 2.0), 0.5 * x * (x - 1.0)])


def field_gradient(e, on, sticks, pen) -> np.ndarray:
    """dθ × ∂e/∂θ at every point by the upwind-biased cubic (points i-2 .. i+1, weights
    (1, -6, 3, 2)/6), the field read past its ends as it goes on: ahead of a run of points on
    the road linearly through zero at the road's edge (where the penetration, linear between
    the run's first point and the one ahead, is zero; half a spacing ahead with no point
    ahead to tell, at least a thousandth of one), behind a run of sticking points with the
    slope of its last two (or of its edge, for one point alone)."""
    count = e.size
    stencil = np.arange(count)[:, None] + np.arange(-2, 2)
    known = (stencil >= 0) & (stencil < count)
    values = np.where(known, np.where(on, e, 0.0)[np.clip(stencil, 0, count - 1)], 0.0)

    def runs(flags):
        edges = np.diff(np.concatenate([[0], flags.astype(int), [0]]))
        return zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1)

    edge = {}
    for first, last in runs(on):
        ahead_pen = pen[first - 1] if first > 0 else np.nan
        fraction = (pen[first] / (pen[first] - ahead_pen) if ahead_pen <= 0 < pen[first]
                    else 0.5)
        edge[first] = max(fraction, 1e-3)
        for i in range(first, last + 1):
            for k, c in enumerate(stencil[i]):
                if c < first:
                    values[i, k] = e[first] * (1.0 - (first - c) / edge[first])
    for first, last in runs(on & sticks):
        slope = (e[last] - e[last - 1] if last > 0 and on[last - 1]
                 else e[last] / edge[last])
        for i in range(first, last + 1):
            for k, c in enumerate(stencil[i]):
                if c > last:
                    values[i, k] = e[last] + (c - last) * slope
    return values @ np.array([1.0, -6.0, 3.0, 2.0]) / 6.0


class UnreducedCleatRun:
    """The ring on the road as y'' = M⁻¹(f(y, y', e) - C(Ω) y' - K(Ω) y), e' = ... (module
    doc), the spin's terms at the wheel's current spin Ω = Ω0 + ψ' when it turns freely."""

    def __init__(self, deflection_m: float, wheel: str):
        tire, tang = MODEL.tire, MODEL.tangential
        self.spin = SPEED / tire.R
        self.rings = [InPlaneRing(MODEL, N, spin_rad_s=k * self.spin, rim_free=True)
                      for k in range(3)]
        ring = self.rings[1]
        nr = ring.n_ring_dof
        free = wheel == "free"
        ny = nr + free
        # y = [ring rim-relative, the wheel's turn ψ if free]; the rim's x and z held. The
        # mapping and the point Jacobians mirror InPlaneSimulator._build on purpose: the
        # reference takes none of the simulator's assembly, so an error there shows here
        to_abs = np.zeros((ring.n_dof, ny))
        to_abs[:nr, :nr] = np.eye(nr)
        if free:
            to_abs[:nr, nr] = ring.rim_patterns[:, 2]
            to_abs[nr + 2, nr] = 1.0
        mass = to_abs.T @ ring.mass @ to_abs
        stiffness = to_abs.T @ ring.stiffness @ to_abs
        zone = contact_zone(Grid(N, tire.R), tire.k_cw, tire.beta, 0.6, SPACING)
        th = zone.point_theta
        at_points = np.zeros((zone.n_points, N))
        at_points[:, zone.nodes] = zone.interpolation
        w, v = ring.field_slice("w"), ring.field_slice("v")
        self.j_w = np.zeros((zone.n_points, ny))  # the tread's radius at the points
        self.j_w[:, w] = at_points
        j_x = np.zeros((zone.n_points, ny))  # fore-aft position of the material, rim-relative
        j_x[:, w] = -np.sin(th)[:, None] * at_points
        j_x[:, v] = -np.cos(th)[:, None] * at_points
        self.j_l = np.zeros((zone.n_points, ny))  # its part of the convected rate Ω L u
        self.j_l[:, : 2 * N] = j_x[:, : 2 * N] @ ring._pair_L()
        if free:  # the wheel's turn moves the material fore and aft, not the tread's radius
            j_x[:, nr] = -tire.R * np.cos(th)
        self.j_x = j_x
        # the finite-difference matrices are sparse (a few per cent): kept so, with M
        # factorised once, a right-hand side costs tens of microseconds, not a dense M⁻¹K
        self.mass = splu(csc_array(mass))
        self.k_and_c = [csr_array(np.hstack([to_abs.T @ r.stiffness @ to_abs,
                                             to_abs.T @ r.damping @ to_abs]))
                        for r in self.rings]  # [K C] at each of the three spins
        self.to_normal, self.to_tread = csr_array(self.j_w.T), csr_array(j_x.T)
        self.k_n, self.c_n = zone.stiffness_n_per_m, zone.damping_n_s_per_m
        self.k_x = np.full(zone.n_points, tang.k_tx * zone.point_arc_m)
        self.c_x = tire.beta * self.k_x
        self.mu = tang.friction_coefficient
        self.sec = 1.0 / np.cos(th)
        self.pen_flat = tire.R - (tire.R - deflection_m) * self.sec
        self.cos_theta = np.cos(th)
        self.x_lo, self.x_hi = zone.road_windows_m(deflection_m)
        self.dtheta = float(np.mean(np.diff(th)))
        self.to_abs, self.ny, self.stiffness, self.free = to_abs, ny, stiffness, free
        self.j_wl = csr_array(np.vstack([self.j_w, self.j_l]))
        self.j_wx = csr_array(np.vstack([self.j_w, j_x]))
        self.y_static = self._static()

    def _static(self) -> np.ndarray:
        """Pressed onto the flat road at rest, frictionless: K y = -J_wᵀ f_n(y), the wheel's
        turn (which the pushes along the rays do not load) left at zero."""
        nr = self.rings[0].n_ring_dof
        k, j_w = self.stiffness[:nr, :nr], self.j_w[:, :nr]
        active = self.pen_flat > 0
        for _ in range(50):
            a = k + j_w[active].T @ (self.k_n[active, None] * j_w[active])
            ring = np.linalg.solve(a, -j_w[active].T @ (self.k_n[active] * self.pen_flat[active]))
            new = self.pen_flat + j_w @ ring > 0
            if np.array_equal(new, active):
                return np.r_[ring, np.zeros(self.ny - nr)]
            active = new
        raise AssertionError("the reference's static footprint did not settle")

    def road(self, time_s):
        """Window-mean height under each point and its exact rate: the rectangular cleat
        (s in [0, length] behind its first edge) covers a share of each point's window."""
        edge = AHEAD - SPEED * time_s
        lo, hi = self.x_lo - edge, self.x_hi - edge
        width = hi - lo
        covered = np.clip(hi, 0.0, CLEAT_LENGTH_M) - np.clip(lo, 0.0, CLEAT_LENGTH_M)
        on_hi = (hi >= 0.0) & (hi < CLEAT_LENGTH_M)
        on_lo = (lo >= 0.0) & (lo < CLEAT_LENGTH_M)
        rate = SPEED * CLEAT_HEIGHT_M * (on_hi.astype(float) - on_lo) / width
        return CLEAT_HEIGHT_M * covered / width, rate

    def spin_now(self, state) -> tuple[float, np.ndarray]:
        """The wheel's spin and the rates relative to it (the turn's rate is the spin's)."""
        motion = state[: 2 * self.ny].copy()
        if not self.free:
            return self.spin, motion
        spin = self.spin + motion[-1]
        motion[-1] = 0.0
        return spin, motion

    def rhs(self, time_s, state):
        ny = self.ny
        y, e = state[:ny], state[2 * ny:]
        spin, motion = self.spin_now(state)
        yd = motion[ny:]
        height, rate = self.road(time_s)
        w_p, l_p = np.split(self.j_wl @ y, 2)
        w_rate, x_rate = np.split(self.j_wx @ yd, 2)
        pen = self.pen_flat + height * self.sec + w_p
        f_n = np.where(pen > 0, np.maximum(
            self.k_n * pen + self.c_n * (w_rate + rate * self.sec), 0.0), 0.0)
        slip = x_rate + spin * l_p + SPEED - spin * MODEL.tire.R * self.cos_theta
        trial = self.k_x * e + self.c_x * slip
        limit = self.mu * f_n
        sticks = np.abs(trial) <= limit
        e_rate = np.where(sticks, slip, (np.sign(trial) * limit - self.k_x * e) / self.c_x)
        tread = self.k_x * e + self.c_x * e_rate  # the element's pull on the belt, backwards
        gradient = field_gradient(e, f_n > 0, sticks, pen) / self.dtheta
        force = sum(weight * (k_and_c @ motion) for weight, k_and_c in
                    zip(spin_weights(spin, self.spin), self.k_and_c) if weight != 0.0)
        ydd = -self.mass.solve(force + self.to_normal @ f_n + self.to_tread @ tread)
        return np.concatenate([state[ny: 2 * ny], ydd, e_rate - spin * gradient])

    def run(self, times_s):
        start = np.concatenate([self.y_static, np.zeros(self.ny), np.zeros(self.k_n.size)])
        sol = solve_ivp(self.rhs, (0.0, times_s[-1]), start, method="RK45", t_eval=times_s,
                        rtol=1e-6, atol=1e-9)
        assert sol.status == 0, sol.message
        forces = []
        for k, time_s in enumerate(sol.t):
            state = sol.y[:, k]
            ydd = self.rhs(time_s, state)[self.ny: 2 * self.ny]
            spin, motion = self.spin_now(state)
            at = [self.to_abs @ a for a in (motion[: self.ny], motion[self.ny:], ydd)]
            forces.append(sum(weight * ring.rim_force(*at) for weight, ring in
                              zip(spin_weights(spin, self.spin), self.rings)))
        return np.array(forces).T  # (Fx, Fz, My) against time


@pytest.fixture(scope="module")
def deflection():
    return deflection_for_load(MODEL, DEFAULT_LOAD_N, N, point_spacing_m=SPACING)


@pytest.mark.parametrize("wheel", ["held", "free"])
def test_cleat_forces_follow_an_unreduced_integration_written_apart(deflection, wheel):
    """The 20 mm cleat at 10 m/s, axle held: the simulator's Fx and Fz within 5 % rms of the
    reference at its default step and at half of it, Fz closer at the finer step."""
    errors = {}
    for step_s in (1e-4, 5e-5):
        sim = InPlaneSimulator(MODEL, N, SPEED, deflection, point_spacing_m=SPACING,
                               obstacle=CLEAT, obstacle_ahead_m=AHEAD, wheel=wheel,
                               step_s=step_s)
        run = sim.run(DURATION, record_every=int(round(1e-4 / step_s)))
        if step_s == 1e-4:
            reference = UnreducedCleatRun(deflection, wheel)
            np.testing.assert_allclose(reference.y_static, sim.static_state(), rtol=0,
                                       atol=1e-9 * np.abs(reference.y_static).max())
            fx, fz, _ = reference.run(run.time_s)
            rise = fz - DEFAULT_LOAD_N
            assert rise.max() > 0.5 * DEFAULT_LOAD_N  # the cleat is felt in Fz
            assert rms(fx) > 0.1 * DEFAULT_LOAD_N  # and in Fx
            assert run.sliding_points.max() >= 1  # friction is not idle over the cleat
        errors[step_s] = (rms(run.rim_fx_n - fx) / rms(fx),
                          rms(run.rim_fz_n - fz) / rms(rise))
    (fx_coarse, fz_coarse), (fx_fine, fz_fine) = errors[1e-4], errors[5e-5]
    assert max(fx_coarse, fz_coarse, fx_fine, fz_fine) < 0.05, errors
    # Fz converges with the step; Fx to within the two sliding laws (module doc), ~1 %
    assert fz_fine < 0.5 * fz_coarse, errors
