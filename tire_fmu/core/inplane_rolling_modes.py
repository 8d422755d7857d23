"""Loaded modes of the rolling tire: :class:`.inplane_contact.InPlaneSimulator` linearised
about its steady rolling (:func:`.inplane_contact.steady_rolling`).

At rest (:func:`.inplane_contact.loaded_modes`) the footprint's tread elements stick as
springs on the material's fore-aft displacement. Rolling renews them: an element enters the
footprint undeflected and is carried out at the back, so what it holds is the slip integrated
along its path, and on the wheel's turn the footprint acts as a slip damper (≈ C_κ R²/V)
more than as a spring. The elements' transport must therefore be states.

**Formulation.** With the contact, stick and sliding-direction sets of the steady state frozen,
the simulator's laws are affine in its state (the transport speed and C(Ω), K(Ω) are the
nominal spin's, as in the step), so the linearisation is the model itself with the sets held.
The state is x = [y_ring, ẏ, e_stick]: the ring's rim-relative coordinates (the wheel's angle
ψ moves no force, so only its rate ψ̇ is a state), their rates, and the sticking points'
element deflections. The ring obeys M ÿ + C ẏ + K y = f_ext - J_nᵀ f_n - J_xᵀ t with
f_n = k_n pen + c_n pen_rate at the points in contact, and the element's pull t = k_x e + c_x s
while it sticks, σ μ f_n while it slides (its e then slaved to σ μ f_n / k_x). The transport
∂e/∂t + Ω ∂e/∂θ = s is discretised by the box scheme between neighbouring points,

    ½ (ė_j + ė_{j-1}) + Ω (e_j - e_{j-1}) / Δθ = ½ (s_j + s_{j-1}),

and ė_j + Ω e_j / (δ_j Δθ) = s_j at a point entering contact, e = 0 at the road's edge δ_j spacings
ahead (:func:`.inplane_contact.entering_fractions`; the edge moves with the penetrations, and its
motion is linearised with the rest). (A box over that part cell, ½ ė_j = s_j - ..., doubles the
entering element's stiffness as the speed goes to zero, and the box's recursion carries the error
down the footprint with alternating sign.) Both have steady_rolling's trapezoidal transport as their
steady state, so the linear system's equilibrium is steady_rolling's state (tested to round-off); as
the speed goes to zero, ė = s at every sticking point, which is loaded_modes' springs. The box
scheme
carries a wave without numerical damping; an upwind difference would damp the elements'
field by a fraction that grows with the spacing, as linear interpolation did in the step
(:func:`.inplane_contact.carry_matrix`). After a sliding point, ė_{j-1} is the rate of its
slaved value and holds the ring's acceleration, which is eliminated through M.

The other way, the eigenvalues of the step's own one-step map with its sets frozen
(log λ / h), would reproduce the step's semi-Lagrangian transport but not steady_rolling's
equilibrium, and would hold the step size; the continuous system holds neither.

A transport through a finite footprint has no modes of its own (a field is flushed out in the
passage time); its discretisation adds eigenvalues near -2Ω/Δθ, a defective cluster that the
modes of the tire are told from by their share of the energy: ``transport`` marks the
eigenvalues whose energy lies mostly in the tread elements' springs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .inplane_contact import (
    InPlaneSimulator,
    SteadyRolling,
    entering_fraction_slopes,
    entering_fractions,
    steady_rolling,
)
from .parameters import ParameterError, Problem

#: An eigenvalue whose energy is more than this share in the tread elements' springs is the
#: transport's (module doc), not a mode of the tire.
TRANSPORT_SHARE = 0.5


@dataclass(frozen=True, eq=False)
class RollingModes:
    """Modes of the tire rolling steadily, lowest damped frequency first (SI)."""

    frequencies_hz: np.ndarray  # damped: Im(λ)/2π
    decay_rates_1_s: np.ndarray  # -Re(λ)
    damping_ratios: np.ndarray  # -Re(λ)/|λ|
    kinds: tuple[str, ...]  # "rotational" for the one the turning dominates, else ""
    shapes: np.ndarray  # (n_states, modes), complex: [y_ring, ẏ, e_stick]
    element_shares: np.ndarray  # share of each mode's energy in the elements' springs
    points_in_contact: int
    sliding_points: int
    speed_m_s: float
    torque_n_m: float


#: The linearisation's inputs before the road's: the torque on the wheel (N m, + driving; a
#: free wheel's), the rim's fore-aft and vertical displacement from where it is held (m, x
#: forward, z up); then the road's height under each contact point (m: the window mean the
#: point reads, as :meth:`.inplane_contact.InPlaneSimulator.road` gives it).
RIM_INPUTS = ("torque", "rim_x", "rim_z")


@dataclass(frozen=True, eq=False)
class RollingSystem:
    """The linearisation ẋ = A x + b + Σ_k B_k u⁽ᵏ⁾ about the steady rolling (at rest: the
    static footprint), x = [y_ring, ẏ, e_stick] (at rest [y_ring, ẏ] and a free wheel's
    angle ψ: the elements are springs on the material's displacement), u = [torque, rim_x,
    rim_z, road under each
    point] (:data:`RIM_INPUTS`) as deviations, and its derivatives up to the second (the
    rim's acceleration loads the ring through its inertia, a road's or the rim's rate the
    points' dampers, and a sliding point's element follows the rate of its normal force)."""

    a: np.ndarray
    b: np.ndarray
    inputs: np.ndarray  # (3, n_x, n_u): B_0, B_1, B_2 on u, u̇, ü
    steady_x: np.ndarray  # steady_rolling's state in these coordinates
    n_ring: int  # rim-relative ring coordinates
    n_rate: int  # rates (ring and, with the wheel free, ψ̇)
    stick_points: np.ndarray  # indices of the sticking points (the e states)
    contact: np.ndarray
    stick: np.ndarray


def rolling_system(sim: InPlaneSimulator, torque_n_m: float = 0.0,
                   sets: tuple | None = None) -> RollingSystem:
    """The simulator's laws with steady_rolling's sets frozen, as a first-order system.
    ``sets`` (contact, stick, sliding sign; boolean, boolean and ±1 per point) freezes others
    instead, e.g. a run's: their system's equilibrium is then not steady_rolling's state,
    which ``steady_x`` still holds. At rest (``sim.speed_m_s`` = 0, no torque) the system is
    the static footprint's with every element sticking, :func:`.inplane_contact.loaded_modes`'
    springs (the elements' deflections the material's fore-aft displacement)."""
    steady = _operating_point(sim, torque_n_m)
    contact, stick, sign = steady_sets(sim, steady) if sets is None else (
        np.asarray(sets[0], dtype=bool), np.asarray(sets[1], dtype=bool) | ~np.asarray(
            sets[0], dtype=bool), np.asarray(sets[2], dtype=float))
    nr, ny = sim._n_ring_coords, sim._ny
    omega = sim.spin_rad_s
    th = sim._zone.point_theta
    spacing = float(np.diff(th).mean())
    m_inv = np.linalg.inv(sim._m)
    # the road's edges where the steady rolling has them; they move with the penetrations
    pen_steady = sim._pen0 + sim._jn[:, :nr] @ steady.state[:nr]
    delta = entering_fractions(pen_steady, contact)
    delta_slopes = entering_fraction_slopes(pen_steady, contact)
    # at rest nothing renews the elements: each is a spring on the material's fore-aft
    # displacement from the static state (loaded_modes), with the wheel's angle ψ a state
    # in place of theirs (as states, e_j - J_x,j y would each be conserved: zero eigenvalues)
    at_rest = omega == 0.0
    rows_st = np.flatnonzero(contact & stick) if not at_rest else np.zeros(0, dtype=int)
    ns = rows_st.size
    index = -np.ones(th.size, dtype=int)
    index[rows_st] = np.arange(ns)
    n_psi = 1 if at_rest and sim._free_spin else 0
    n_x = nr + ny + ns + n_psi
    ys, vs, es = slice(0, nr), slice(nr, nr + ny), slice(nr + ny, nr + ny + ns)
    # every point quantity as affine in x and the inputs: q = Q x + U [u, u̇, ü] + q0, the
    # input part U (points, 3 n_u) by derivative blocks (module constant RIM_INPUTS)
    n_u = len(RIM_INPUTS) + th.size
    torque_in, x_in, z_in = (RIM_INPUTS.index(name) for name in RIM_INPUTS)
    road_in = len(RIM_INPUTS) + np.arange(th.size)
    points = np.arange(th.size)
    jn = np.zeros((th.size, n_x))
    jn[:, ys] = sim._jn[:, :nr]
    pen_q, pen_0 = jn, sim._pen0
    pen_u = np.zeros((th.size, 3 * n_u))  # the road along each ray, h - z
    pen_u[points, road_in], pen_u[:, z_in] = sim._sec, -sim._sec
    rate_q = np.zeros((th.size, n_x))
    rate_q[:, vs] = sim._jn
    rate_u = np.roll(pen_u, n_u, axis=1)  # the same on the rates
    fn_q = np.where(contact[:, None], sim._kn[:, None] * pen_q + sim._cn[:, None] * rate_q, 0)
    fn_u = np.where(contact[:, None], sim._kn[:, None] * pen_u + sim._cn[:, None] * rate_u, 0)
    fn_0 = np.where(contact, sim._kn * pen_0, 0.0)
    s_q = np.zeros((th.size, n_x))  # the material's fore-aft speed against the road
    s_q[:, vs] = sim._jxw
    s_q[:, ys] += omega * sim._jl[:, :nr]
    s_u = np.zeros((th.size, 3 * n_u))  # the rim's forward speed adds to the road's
    s_u[:, n_u + x_in] = 1.0
    s_0 = sim._s0
    e_q = np.zeros((th.size, n_x))  # every point's e: a state, slaved, or zero
    e_u = np.zeros((th.size, 3 * n_u))
    e_0 = np.zeros(th.size)
    e_q[rows_st, nr + ny + np.arange(ns)] = 1.0
    if at_rest:
        e_q[:, ys] = sim._jxw[:, :nr]
        if n_psi:
            e_q[:, -1] = sim._jxw[:, nr]
        e_0 = -sim._jxw[:, :nr] @ steady.state[:nr]
        e_q[~contact], e_0[~contact] = 0.0, 0.0
    slide = contact & ~stick
    slave = (sign * sim._mu / sim._kx)[:, None]
    e_q[slide] = slave[slide] * fn_q[slide]
    e_u[slide] = slave[slide] * fn_u[slide]
    e_0[slide] = slave[slide, 0] * fn_0[slide]
    # the element's pull on the belt, backwards
    t_q = np.where(stick[:, None], sim._kx[:, None] * e_q + sim._cx[:, None] * s_q,
                   (sign * sim._mu)[:, None] * fn_q)
    t_u = np.where(stick[:, None], sim._kx[:, None] * e_u + sim._cx[:, None] * s_u,
                   (sign * sim._mu)[:, None] * fn_u)
    t_0 = np.where(stick, sim._kx * e_0 + sim._cx * s_0, sign * sim._mu * fn_0)
    t_q[~contact], t_u[~contact], t_0[~contact] = 0.0, 0.0, 0.0
    # M ÿ = f_ext - C ẏ - K y - J_nᵀ f_n - J_xᵀ t
    force_q = -sim._jnw.T @ fn_q - sim._jxw.T @ t_q
    force_q[:, ys] -= sim._k[:, :nr]
    force_q[:, vs] -= sim._c
    force_u = -sim._jnw.T @ fn_u - sim._jxw.T @ t_u
    if sim._free_spin:
        force_u[-1, torque_in] += 1.0
    # the rim's translation loads the rim-relative ring through its inertia alone
    force_u[:, 2 * n_u + x_in] -= sim._rim_inertia[:, 0]
    force_u[:, 2 * n_u + z_in] -= sim._rim_inertia[:, 1]
    force_0 = sim._f_ext(0.0, torque_n_m) - sim._jnw.T @ fn_0 - sim._jxw.T @ t_0
    a = np.zeros((n_x, n_x))
    b = np.zeros(n_x)
    b_u = np.zeros((n_x, 3 * n_u))
    a[ys, vs] = np.eye(ny)[:nr]
    if n_psi:
        a[-1, nr + ny - 1] = 1.0  # ψ̇
    a[vs] = m_inv @ force_q
    b[vs] = m_inv @ force_0
    b_u[vs] = m_inv @ force_u

    def rate_of(u_part):  # d/dt of an input part: u -> u̇ -> ü (nothing reaches past ü)
        if np.any(u_part[2 * n_u:]):
            raise AssertionError("rolling_system: an input's third derivative")
        return np.roll(u_part, n_u)
    # the box scheme, row by row in the order of transport: E ė_st = rhs, with ė of a
    # sliding neighbour its slaved value's rate (through ẋ = A x + b, already known rows)
    for j in rows_st:
        row = nr + ny + index[j]
        entering = j == 0 or not contact[j - 1]
        if entering:  # e = 0 δ_j spacings ahead, ė_j + Ω e_j / (δ_j Δθ) = s_j (module doc)
            q = -omega / (delta[j] * spacing) * e_q[j] + s_q[j]
            q0 = s_0[j]
            q_u = s_u[j]
            if j > 0 and delta_slopes[j].any():  # -Ω e/(δ Δθ) about the edge's motion
                held = omega * steady.element_deflection_m[j] / (delta[j] ** 2 * spacing)
                g_ahead, g_here = held * delta_slopes[j]
                q = q + g_ahead * pen_q[j - 1] + g_here * pen_q[j]
                q_u = q_u + g_ahead * pen_u[j - 1] + g_here * pen_u[j]
                q0 = q0 + (g_ahead * (pen_0[j - 1] - pen_steady[j - 1])
                           + g_here * (pen_0[j] - pen_steady[j]))
            a[row], b[row], b_u[row] = q, q0, q_u
            continue
        q = (-2.0 * omega / spacing * (e_q[j] - e_q[j - 1]) + s_q[j] + s_q[j - 1])
        q_u = -2.0 * omega / spacing * (e_u[j] - e_u[j - 1]) + s_u[j] + s_u[j - 1]
        q0 = -2.0 * omega / spacing * (e_0[j] - e_0[j - 1]) + s_0[j] + s_0[j - 1]
        # minus ė_{j-1}: a state's row (done, the order is the transport's) or a slaved rate
        prev_q = e_q[j - 1] @ a
        prev_u = e_q[j - 1] @ b_u + rate_of(e_u[j - 1])
        prev_0 = e_q[j - 1] @ b
        a[row], b[row], b_u[row] = q - prev_q, q0 - prev_0, q_u - prev_u
    steady_x = np.zeros(n_x)
    steady_x[ys] = steady.state[:nr]
    if sim._free_spin:
        steady_x[nr + ny - 1] = steady.state[-1]  # the wheel's steady spin offset ψ̇
    steady_x[es] = steady.element_deflection_m[rows_st]
    inputs = b_u.reshape(n_x, 3, n_u).transpose(1, 0, 2)
    return RollingSystem(a, b, inputs, steady_x, nr, ny, rows_st, contact, stick)


def _operating_point(sim: InPlaneSimulator, torque_n_m: float):
    """steady_rolling's state, or at rest the static footprint with no element deflected
    (every element sticks: at rest the road renews none)."""
    if sim.speed_m_s > 0.0:
        return steady_rolling(sim, torque_n_m)
    if torque_n_m != 0.0:
        raise ParameterError([Problem("torque_n_m", torque_n_m, "N m", "0 at rest",
                                      "a torque at rest winds the elements up: no steady "
                                      "state to linearise about")])
    y = sim.static_state()
    fx, fz, my = sim.rim_force(y, np.zeros_like(y), spin_rad_s=0.0)
    return SteadyRolling(float(fx), float(fz), float(my), 0.0, 0.0, 0,
                         np.zeros(sim._zone.n_points), y)


def steady_sets(sim: InPlaneSimulator, steady) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(contact, stick, sliding sign) of the steady state, recovered from it."""
    nr = sim._n_ring_coords
    y = steady.state
    pen = sim._pen0 + sim._jn[:, :nr] @ y[:nr]
    f_n = sim._kn * pen
    contact = (pen > 0) & (f_n > 0)
    e = steady.element_deflection_m
    limit = sim._mu * f_n / sim._kx
    sliding = contact & np.isclose(np.abs(e), limit, rtol=1e-9, atol=0.0)
    if int(sliding.sum()) != steady.sliding_points:
        raise RuntimeError(f"rolling_system: {int(sliding.sum())} points at the friction limit, "
                           f"steady_rolling reports {steady.sliding_points} sliding")
    return contact, ~sliding, np.where(sliding, np.sign(e), 1.0)


def rolling_modes(sim: InPlaneSimulator, torque_n_m: float = 0.0,
                  f_max_hz: float = 200.0, sets: tuple | None = None) -> RollingModes:
    """The modes of the tire rolling steadily at ``sim.speed_m_s`` under ``torque_n_m``
    (linearised about :func:`.inplane_contact.steady_rolling`, its sets frozen; module doc),
    the oscillating ones whose natural frequency |λ|/2π is at most ``f_max_hz`` (as
    loaded_modes' undamped one), lowest damped frequency first; overdamped ones are left
    out. ``kinds``: "transport" for the transport's eigenvalues (more than
    :data:`TRANSPORT_SHARE` of their energy in the elements' springs), "rotational" for the
    mode of the tire with the largest share of its kinetic energy in turning, of the tread
    as a whole and of the wheel (as :func:`.inplane_contact.loaded_modes` labels it).
    ``sets`` freezes other sets than the steady rolling's (:func:`rolling_system`)."""
    import scipy.linalg

    if not (np.isfinite(f_max_hz) and f_max_hz > 0):
        raise ParameterError([Problem("f_max_hz", f_max_hz, "Hz", "> 0 Hz")])
    system = rolling_system(sim, torque_n_m, sets)
    lam, vectors = scipy.linalg.eig(system.a)
    keep = (lam.imag > 1e-9 * np.abs(lam)) & (np.abs(lam) / (2 * np.pi) <= f_max_hz)
    lam, vectors = lam[keep], vectors[:, keep]
    order = np.argsort(lam.imag)
    lam, vectors = lam[order], vectors[:, order]
    nr, ny = system.n_ring, system.n_rate
    ns = system.stick_points.size  # at rest: none, the wheel's angle after the rates
    y, rate, e = vectors[:nr], vectors[nr:nr + ny], vectors[nr + ny:nr + ny + ns]
    kinetic = np.real(np.einsum("ij,ij->j", rate.conj(), sim._m @ rate))
    k_ring = 0.5 * (sim._k[:nr, :nr] + sim._k[:nr, :nr].T)
    strain = np.abs(np.einsum("ij,ij->j", y.conj(), k_ring @ y))
    elements = sim._kx[system.stick_points] @ np.abs(e) ** 2
    element_share = elements / (kinetic + strain + elements)
    t, tang = sim.model.tire, sim.model.tangential
    wheel_turn = rate[-1] if sim._free_spin else np.zeros(lam.size)
    ring_rate = rate[: sim._n_ring_coords]
    if sim._basis is not None:
        ring_rate = sim._basis[: sim._ring.n_ring_dof, : sim._n_ring_coords] @ ring_rate
    tread_turn = ring_rate[sim._ring.field_slice("v")].mean(axis=0) / t.R + wheel_turn
    tread_inertia = 2 * np.pi * t.R**3 * t.rhoA
    turning = (tread_inertia * np.abs(tread_turn) ** 2
               + tang.wheel_inertia_kg_m2 * np.abs(wheel_turn) ** 2) / kinetic
    transport = element_share > TRANSPORT_SHARE
    kinds = ["transport" if tr else "" for tr in transport]
    if not transport.all():
        kinds[int(np.argmax(np.where(transport, -1.0, turning)))] = "rotational"
    return RollingModes(lam.imag / (2 * np.pi), -lam.real, -lam.real / np.abs(lam),
                        tuple(kinds), vectors, element_share, int(system.contact.sum()),
                        int(np.sum(system.contact & ~system.stick)), sim.speed_m_s,
                        float(torque_n_m))


@dataclass(frozen=True, eq=False)
class TorqueStep:
    """The linear response of Fx to a torque step from one steady rolling to another, by the
    modes of the second: Fx(t) = fx_after + Σ_k Re(amplitude_k e^{λ_k t}) over every
    eigenvalue (each of a complex pair counted, so the sum is real)."""

    eigenvalues: np.ndarray  # λ_k (1/s), all of them
    fx_amplitudes_n: np.ndarray  # complex, per eigenvalue
    fx_before_n: float
    fx_after_n: float

    def fx(self, time_s: np.ndarray) -> np.ndarray:
        """Fx (N) at times after the step."""
        t = np.asarray(time_s, dtype=float)
        return self.fx_after_n + np.real(np.exp(np.multiply.outer(t, self.eigenvalues))
                                         @ self.fx_amplitudes_n)

    def dominant(self, count: int = 3, max_damping_ratio: float = 0.5
                 ) -> list[tuple[float, float, float]]:
        """(damped frequency Hz, decay rate 1/s, Fx amplitude N) of the ringing modes
        (damping ratio at most ``max_damping_ratio``) with the largest part in Fx, largest
        first (a pair's amplitude is its cosine's)."""
        lam = self.eigenvalues
        up = np.flatnonzero((lam.imag > 0) & (-lam.real <= max_damping_ratio * np.abs(lam)))
        order = up[np.argsort(-np.abs(self.fx_amplitudes_n[up]))][:count]
        return [(float(self.eigenvalues[k].imag / (2 * np.pi)), float(-self.eigenvalues[k].real),
                 float(2 * abs(self.fx_amplitudes_n[k]))) for k in order]


def rim_rows(sim: InPlaneSimulator, system: RollingSystem) -> tuple[np.ndarray, np.ndarray]:
    """(C, c0), (3, states) and (3,): the rim's (Fx, Fz, My) = C x + c0 on the system's
    trajectories with the inputs at rest (the rim's rows of
    :meth:`.inplane_contact.InPlaneSimulator.rim_force`, the acceleration from ẋ = A x + b)."""
    nr, ny = system.n_ring, system.n_rate
    k, c, m = (-rows for rows in sim.rim_force_rows())
    out = m @ system.a[nr:nr + ny]
    out[:, :nr] += k[:, :nr]
    out[:, nr:nr + ny] += c
    return out, m @ system.b[nr:nr + ny]


def fx_rows(sim: InPlaneSimulator, system: RollingSystem) -> tuple[np.ndarray, float]:
    """(c, c0) with the rim's Fx = c·x + c0 (:func:`rim_rows`' first row)."""
    rows, constant = rim_rows(sim, system)
    return rows[0], float(constant[0])


def torque_step(sim: InPlaneSimulator, torque_before_n_m: float,
                torque_after_n_m: float) -> TorqueStep:
    """Fx after a step of the wheel's torque, from the steady rolling under the first torque,
    linearised about the steady rolling under the second (its sets frozen)."""
    import scipy.linalg

    before = steady_rolling(sim, torque_before_n_m)
    system = rolling_system(sim, torque_after_n_m)
    nr, ny = system.n_ring, system.n_rate
    x0 = np.zeros_like(system.steady_x)
    x0[:nr] = before.state[:nr]
    if sim._free_spin:
        x0[nr + ny - 1] = before.state[-1]
    x0[nr + ny:nr + ny + system.stick_points.size] = \
        before.element_deflection_m[system.stick_points]
    c, c0 = fx_rows(sim, system)
    lam, left, right = scipy.linalg.eig(system.a, left=True, right=True)
    weights = (left.conj().T @ (x0 - system.steady_x)) / np.einsum("ij,ij->j", left.conj(),
                                                                     right)
    return TorqueStep(lam, (c @ right) * weights, float(c @ x0 + c0),
                      float(c @ system.steady_x + c0))


def fit_ringing(time_s: np.ndarray, signal: np.ndarray, seeds) -> tuple[list, float]:
    """Fit a sum of damped cosines and a linear drift to ``signal``, one for each seed
    (frequency Hz, decay rate 1/s, ...): ([(frequency, decay rate), ...], rms residual).
    Each frequency is held within 30 % of its seed and each decay rate in [0, 4 x seed + 50],
    so that the fit follows the seeded modes (a free fit of several heavily damped modes
    trades one for another)."""
    from scipy.optimize import least_squares

    t = np.asarray(time_s, dtype=float) - float(time_s[0])
    y = np.asarray(signal, dtype=float)
    seeds = [(float(s[0]), float(s[1])) for s in seeds]

    def curve(p):
        out = p[-2] + p[-1] * t
        for i in range(len(seeds)):
            a, b, f, decay = p[4 * i: 4 * i + 4]
            out = out + np.exp(-decay * t) * (a * np.cos(2 * np.pi * f * t)
                                              + b * np.sin(2 * np.pi * f * t))
        return out

    span = float(np.ptp(y)) + 1.0
    p0, lo, hi = [], [], []
    for f, decay in seeds:
        p0 += [0.0, 0.0, f, decay]
        lo += [-10 * span, -10 * span, 0.7 * f, 0.0]
        hi += [10 * span, 10 * span, 1.3 * f, 4 * decay + 50.0]
    p0 += [y[-1], 0.0]
    lo += [-np.inf, -np.inf]
    hi += [np.inf, np.inf]
    fit = least_squares(lambda p: curve(p) - y, p0, bounds=(lo, hi), x_scale="jac")
    modes = [(float(fit.x[4 * i + 2]), float(fit.x[4 * i + 3])) for i in range(len(seeds))]
    return modes, float(np.sqrt(np.mean(fit.fun**2)))
