"""The free rolling ring (no contact) in diagonal modal form, order by order.

Without contact the ground-frame ring is circulant: every operator of :mod:`.model` (bending,
tension, foundation springs, material damping, gyroscopic, convective, circulatory and spin
softening terms) is a block-circulant matrix, so the discrete Fourier basis
Φ_n = e^{inθ} ⊗ (tread, sidewall) diagonalises it exactly. Order n is a 2-DOF system

    M ü_n + D_n u̇_n + K_n u_n = F_n,
    K_n = K*_n - Ω²κ_n² M + iΩκ_n C_n,   D_n = C_n + 2iΩκ_n M   (per node, see dispersion),

with F_n = Φ_nᴴ F / N the order's share of the node forces. The rim enters orders ±1 only
(T = -cos θ); a force on one tread node excites every order. Orders n and -n are complex
conjugates, so only n = 0..N/2 are solved, each in the momentum state of :mod:`.io_model`
(x = [u_n, M u̇_n - B_v r]) and diagonalised as a 4x4 system: the whole eigenproblem costs
O(N), not O(N³), and gives exactly the modes of the assembled undeformed model.

Inputs r = [rim_z, f_1 .. f_Z]: the rim displacement and the road's push on each contact-zone
node (newtons, inwards), with their rates ṙ in the direct term. Outputs (deviations):
rim_Fz, rim_Fx (force of the tire on the rim), deflection (-w at the contact centre), then
w_j and ẇ_j at each zone node (rim-relative radial displacement and its rate), which is what
the contact law needs.

Truncation keeps the modes with natural frequency |λ|/2π up to ``f_max_hz`` (and at most
``n_modes``, lowest first); with ``static_correction`` the dropped modes enter quasi-
statically, Σ -c b/λ on r and Σ -c b/λ² on ṙ, so static compliances at the zone nodes and
the rim are exact and the zone rates are the rates of those displacements.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .discretisation import Grid
from .discretisation import symbols as fdm_symbols
from .dispersion import per_order_matrices
from .modal_form import canonical_modes
from .parameters import Problem, TireParameters

RIM_OUTPUTS = ("rim_Fz", "rim_Fx", "deflection")


@dataclass(frozen=True)
class RingTruncation:
    """Which free-ring modes to keep; frequencies in Hz. None keeps everything."""

    f_max_hz: float | None = None
    n_modes: int | None = None
    static_correction: bool = True

    def __post_init__(self) -> None:
        problems = truncation_problems(self.f_max_hz, self.n_modes)
        if problems:
            from .parameters import ParameterError

            raise ParameterError(problems)


#: Allowed truncation settings (as for the reduction): f_max in (0, F_MAX_LIMIT_HZ] Hz and
#: n_modes in [1, N_MODES_LIMIT], or None for no limit.
F_MAX_LIMIT_HZ = 1e7
N_MODES_LIMIT = 100_000


def truncation_problems(f_max_hz, n_modes) -> list[Problem]:
    """Why a truncation setting cannot be used (empty when it can)."""
    problems = []
    if f_max_hz is not None and not (
        isinstance(f_max_hz, (int, float)) and 0 < f_max_hz <= F_MAX_LIMIT_HZ
    ):
        problems.append(Problem("f_max_hz", f_max_hz, "Hz", f"in (0, {F_MAX_LIMIT_HZ:g}] Hz",
                                unset=True))
    if n_modes is not None and (isinstance(n_modes, bool) or not isinstance(n_modes, int)
                                or not 1 <= n_modes <= N_MODES_LIMIT):
        problems.append(Problem("n_modes", n_modes, "", f"an integer in [1, {N_MODES_LIMIT}]",
                                unset=True))
    return problems


@dataclass(frozen=True, eq=False)
class FreeRingModel:
    """The free ring in diagonal modal form q̇ = Λq + B r, y = Re(C q) + D r + E ṙ, with the
    exact static gain and the zone's static compliance alongside."""

    eigenvalues: np.ndarray  # (k,) complex
    b: np.ndarray  # (k, 1 + Z)
    c: np.ndarray  # (3 + 2Z, k), pair factor included
    d: np.ndarray  # (3 + 2Z, 1 + Z)
    e: np.ndarray  # (3 + 2Z, 1 + Z), on ṙ
    static_gain: np.ndarray  # exact DC gain of the whole ring (3 + 2Z, 1 + Z)
    zone_nodes: np.ndarray
    n_elements: int
    total_modes: int  # before truncation
    truncation: RingTruncation

    @property
    def n_zone(self) -> int:
        return self.zone_nodes.size

    @property
    def n_modes(self) -> int:
        return self.eigenvalues.size

    @property
    def n_states(self) -> int:
        return 2 * self.n_modes

    @property
    def zone_compliance(self) -> np.ndarray:
        return zone_compliance(self.static_gain)

    def rows(self, name: str) -> slice | int:
        z = self.n_zone
        if name in RIM_OUTPUTS:
            return RIM_OUTPUTS.index(name)
        return {"w": slice(3, 3 + z), "w_rate": slice(3 + z, 3 + 2 * z)}[name]

    def frequency_response(self, omega) -> np.ndarray:
        """H(iω) (outputs, inputs, freqs) of the modal form, for real signals."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        iw = 1j * omega[None, None, :]
        lam = self.eigenvalues[:, None, None]
        own = self.b[:, :, None] / (iw - lam)
        partner = np.conj(self.b)[:, :, None] / (iw - np.conj(lam))
        modal = 0.5 * (np.einsum("ok,kif->oif", self.c, own)
                       + np.einsum("ok,kif->oif", np.conj(self.c), partner))
        return modal + self.d[:, :, None] + iw * self.e[:, :, None]


def order_sum(weight: np.ndarray, left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """Σ_n w_n Re(left_n @ right_n) over the orders, as one matrix product: the orders'
    (outputs x inputs) products are never formed one by one (at N = 1600 with a long zone
    they were 16 M complex numbers, most of a fine mesh's build)."""
    n, rows, inner = left.shape
    stacked = (weight[:, None, None] * left).transpose(1, 0, 2).reshape(rows, n * inner)
    return np.real(stacked @ right.reshape(n * inner, right.shape[2]))


def _order_weights(n_elements: int, orders: np.ndarray) -> np.ndarray:
    """How many signed orders each half order stands for: 2 for 0 < n < N/2 (n and -n)."""
    return np.where((orders == 0) | (2 * orders == n_elements), 1.0, 2.0)


def order_matrices(tire: TireParameters, grid: Grid, spin_rad_s: float, orders):
    """Per-node ground-frame (M, D_n, K_n) for each order n: M (2,), D and K (n, 2, 2)."""
    orders = np.asarray(orders)
    sym = fdm_symbols(orders, grid.dtheta)
    (k_tt, k_ss, k_ts), (c_tt, c_ss, c_ts) = per_order_matrices(tire, sym, spin_rad_s, orders)
    arc = grid.node_arc_m
    mass = arc * np.array([tire.rhoA, tire.m_s])
    kappa = (sym["d1"] / 1j).real

    def block(tt, ss, ts):
        tt, ss = np.broadcast_to(tt, orders.shape), np.broadcast_to(ss, orders.shape)
        ts = np.broadcast_to(ts, orders.shape)
        return arc * np.stack([np.stack([tt, ts], -1), np.stack([ts, ss], -1)], -2)

    k_star, c_mat = block(k_tt, k_ss, k_ts), block(c_tt, c_ss, c_ts)
    w = (spin_rad_s * kappa)[:, None, None]
    m_mat = np.zeros_like(k_star)
    m_mat[:, 0, 0], m_mat[:, 1, 1] = mass
    stiffness = k_star - w**2 * m_mat + 1j * w * c_mat
    damping = c_mat + 2j * w * m_mat
    return mass, damping, stiffness


@dataclass(frozen=True, eq=False)
class _Orders:
    """Everything per half order n = 0..N/2 before the eigen-decomposition."""

    orders: np.ndarray
    weight: np.ndarray  # signed orders each half order stands for
    mass: np.ndarray  # (2,) per node
    damping: np.ndarray  # (n, 2, 2) complex
    stiffness: np.ndarray
    b_z: np.ndarray  # (n, 2, inputs): forcing on u
    b_v: np.ndarray  # (n, 2, inputs): forcing on u̇ (the rim's damper)
    l_u: np.ndarray  # (n, outputs, 2): readout of u_n
    l_v: np.ndarray  # (n, outputs, 2): readout of u̇_n
    d_direct: np.ndarray  # (outputs, inputs): the rim-relative parts, on r
    e_direct: np.ndarray  # on ṙ

    @cached_property
    def static_gain(self) -> np.ndarray:
        """Exact DC gain: u_n = K_n⁻¹ B_z,n r, summed over the signed orders."""
        k_inv = np.linalg.inv(self.stiffness)
        return order_sum(self.weight, self.l_u @ k_inv, self.b_z) + self.d_direct


def _orders(tire: TireParameters, grid: Grid, spin_rad_s: float,
            zone_nodes: np.ndarray) -> _Orders:
    n_el = grid.n_elements
    n_zone = zone_nodes.size
    n_in, n_out = 1 + n_zone, 3 + 2 * n_zone
    orders = np.arange(n_el // 2 + 1)
    weight = _order_weights(n_el, orders)
    mass, damping, stiffness = order_matrices(tire, grid, spin_rad_s, orders)

    # Patterns: T = -cos θ (rim translation) and S = -sin θ (its forward component), on both
    # blocks, are exactly order ±1: Σ_m T_m e^{inθ_m} = -N/2 and Σ_m S_m e^{inθ_m} = -iN/2 for
    # n = 1, and (1/N) Σ_m T_m e^{-inθ_m} = -1/2; the sums' rounding dust on other orders is
    # no coupling (the C builder takes the same exact values).
    theta = grid.theta
    trans = -np.cos(theta)
    rim = orders == 1
    tau = np.where(rim, -0.5 * n_el, 0.0).astype(complex)
    sig = np.where(rim, -0.5j * n_el, 0.0)
    t_in = np.where(rim, -0.5, 0.0)
    ones = np.ones(2)
    phase = np.exp(1j * np.outer(orders, theta[zone_nodes]))  # e^{inθ_j}, (orders, Z)

    # Per order: B_z, B_v (2 x inputs); output readouts on u and on u̇ (outputs x 2).
    b_z = np.zeros((orders.size, 2, n_in), dtype=complex)
    b_v = np.zeros_like(b_z)
    b_z[:, :, 0] = np.einsum("nij,j->ni", stiffness, ones) * t_in[:, None]
    b_v[:, :, 0] = np.einsum("nij,j->ni", damping, ones) * t_in[:, None]
    b_z[:, 0, 1:] = -np.conj(phase) / n_el  # a push f_j inwards is a force -f_j on u_j
    l_u = np.zeros((orders.size, n_out, 2), dtype=complex)
    l_v = np.zeros_like(l_u)
    k_ones = np.einsum("j,nji->ni", ones, stiffness)  # 1ᵀ K_n
    d_ones = np.einsum("j,nji->ni", ones, damping)
    l_u[:, 0], l_v[:, 0] = tau[:, None] * k_ones, tau[:, None] * d_ones
    l_u[:, 1], l_v[:, 1] = sig[:, None] * k_ones, sig[:, None] * d_ones
    l_u[:, 2, 0] = -1.0  # deflection = -w at node 0
    l_u[:, 3:3 + n_zone, 0] = phase
    l_v[:, 3 + n_zone:, 0] = phase

    # Direct terms not carried by the orders: the rim-relative parts -T z and -T ż.
    d_direct = np.zeros((n_out, n_in))
    e_direct = np.zeros((n_out, n_in))
    # rim forces on the rim's own motion: -pᵀ K_s T z - pᵀ D_s T ż, through order 1
    k_11 = np.einsum("i,nij,j->n", ones, stiffness, ones)
    d_11 = np.einsum("i,nij,j->n", ones, damping, ones)
    for row, pattern in ((0, tau), (1, sig)):
        d_direct[row, 0] = -np.sum(weight * np.real(pattern * t_in * k_11))
        e_direct[row, 0] = -np.sum(weight * np.real(pattern * t_in * d_11))
    d_direct[2, 0] = trans[0]  # deflection = -(u_0 - T_0 z) = -u_0 + T_0 z
    cos_zone = np.cos(theta[zone_nodes])
    d_direct[3:3 + n_zone, 0] = cos_zone  # w_j = u_j - T_j z
    e_direct[3 + n_zone:, 0] = cos_zone  # ẇ_j = u̇_j - T_j ż
    return _Orders(orders, weight, mass, damping, stiffness, b_z, b_v, l_u, l_v,
                   d_direct, e_direct)


def ring_static_gain(tire: TireParameters, grid: Grid, spin_rad_s: float,
                     zone_nodes) -> np.ndarray:
    """The free ring's exact DC gain (outputs x [rim_z, zone forces]) without any modes."""
    return _orders(tire, grid, spin_rad_s, np.asarray(zone_nodes, dtype=int)).static_gain


def zone_compliance(static_gain: np.ndarray) -> np.ndarray:
    """G (Z x Z, m/N) from a ring's static gain: rim-relative radial displacement of zone
    node i per newton pushed outwards at zone node j (the contact forces push inwards,
    so w = -G f)."""
    n_zone = static_gain.shape[1] - 1
    return -static_gain[3:3 + n_zone, 1:]


def momentum_matrices(mass: np.ndarray, damping: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """A_n (orders, 4, 4) of each order in the momentum state x = [u_n, M u̇_n - B_v r]:
    u̇ = M⁻¹ p, ṗ = -K_n u - D_n M⁻¹ p (the input terms apart), from :func:`order_matrices`."""
    m_inv = 1.0 / mass
    a_n = np.zeros((damping.shape[0], 4, 4), dtype=complex)
    a_n[:, 0, 2], a_n[:, 1, 3] = m_inv
    a_n[:, 2:, :2] = -stiffness
    a_n[:, 2:, 2:] = -damping * m_inv[None, None, :]
    return a_n


def order_modes(a_n: np.ndarray, real_orders: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (orders, 4) and eigenvectors (orders, 4, 4, columns) of each order's A_n in
    the canonical normalisation and order (:func:`.modal_form.canonical_modes`); a real order
    (n = 0, N/2: ``real_orders``) is the real system Re A_n, whose pairs are exactly conjugate
    and whose real eigenvalues have real eigenvectors. The native FMU's C builds the same.

    numpy's eig (LAPACK's geev, as scipy's) solves each stack in one call."""
    real_orders = np.asarray(real_orders, dtype=bool)
    values = np.empty(a_n.shape[:2], dtype=complex)
    vectors = np.empty(a_n.shape, dtype=complex)
    for which, stack in ((real_orders, a_n[real_orders].real), (~real_orders, a_n[~real_orders])):
        if stack.shape[0]:
            values[which], vectors[which] = np.linalg.eig(stack)
    return canonical_modes(values, vectors)


@dataclass(frozen=True, eq=False)
class RingModes:
    """The free ring's kept modes grouped by circumferential order, as a step reads them.

    Mode k belongs to order ``orders[k]`` (ascending; an order 0 < n < N/2 stands for n and
    -n, its conjugate). On a tread node at θ_j the mode's complex state q_k takes the road's
    push f_j (newtons, inwards) as q̇_k += beta_k e^{-inθ_j} f_j, and reads back the
    rim-relative radial displacement and its rate as w_j = Σ_k Re(gamma_k e^{inθ_j} q_k) and
    ẇ_j = Σ_k Re(eta_k e^{inθ_j} q_k) (the pair factor 2 is in gamma and eta). The rim's
    translation is order ±1 exactly: q̇_k += b_rim_k z_rim, and the rim forces (rim_Fz,
    rim_Fx) are Re(c_rim[:, k] q_k); both are zero on every other order. ``d``, ``e`` and
    ``static_gain`` are those of :class:`FreeRingModel` (rows rim_Fz, rim_Fx, deflection, w,
    ẇ at the zone nodes; columns rim_z, zone forces).
    """

    orders: np.ndarray  # (K,) int
    eigenvalues: np.ndarray  # (K,) complex
    beta: np.ndarray
    gamma: np.ndarray
    eta: np.ndarray
    b_rim: np.ndarray
    c_rim: np.ndarray  # (2, K)
    d: np.ndarray
    e: np.ndarray
    static_gain: np.ndarray
    zone_nodes: np.ndarray
    n_elements: int
    total_modes: int
    truncation: RingTruncation

    @property
    def n_modes(self) -> int:
        return self.eigenvalues.size

    def order_start(self) -> np.ndarray:
        """Index of each order's first mode (n = 0 .. N/2), and the count at the end."""
        n_orders = self.n_elements // 2 + 1
        return np.searchsorted(self.orders, np.arange(n_orders + 1)).astype(np.int64)

    def modal_form(self, grid: Grid) -> FreeRingModel:
        """The same modes as a dense modal form, sorted by natural frequency."""
        b, c = self.dense(grid.theta[self.zone_nodes])
        order = np.argsort(np.abs(self.eigenvalues), kind="stable")
        return FreeRingModel(
            eigenvalues=self.eigenvalues[order], b=b[order], c=c[:, order], d=self.d,
            e=self.e, static_gain=self.static_gain, zone_nodes=self.zone_nodes,
            n_elements=self.n_elements, total_modes=self.total_modes,
            truncation=self.truncation)

    def dense(self, theta_zone: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(b, c) of the modal form on [rim_z, zone forces] and [rim_Fz, rim_Fx, deflection,
        w, ẇ]: the order structure written out."""
        phase = np.exp(1j * np.outer(self.orders, theta_zone))  # (K, Z)
        b = np.hstack([self.b_rim[:, None], self.beta[:, None] * np.conj(phase)])
        c = np.vstack([self.c_rim, -self.gamma[None, :], (self.gamma[:, None] * phase).T,
                       (self.eta[:, None] * phase).T])
        return b, c


def ring_modes(tire: TireParameters, grid: Grid, spin_rad_s: float, zone_nodes: np.ndarray,
               truncation: RingTruncation | None = None) -> RingModes:
    """The free rolling ring's modes order by order, truncated (see the module doc)."""
    truncation = truncation or RingTruncation()
    n_el = grid.n_elements
    zone_nodes = np.asarray(zone_nodes, dtype=int)
    o = _orders(tire, grid, spin_rad_s, zone_nodes)
    mass, damping, stiffness = o.mass, o.damping, o.stiffness
    m_inv = 1.0 / mass

    # Momentum form per order and its eigen-decomposition (canonical modes).
    a_n = momentum_matrices(mass, damping, stiffness)
    mb_v = o.b_v * m_inv[None, :, None]
    # of the momentum form's input and output maps only the rim's column and rows are read
    # per mode (the zone's are the phases, written out by ``dense``)
    b_n = np.concatenate([mb_v[:, :, :1], o.b_z[:, :, :1] - damping @ mb_v[:, :, :1]],
                         axis=1)
    c_n = np.concatenate([o.l_u[:, :2], o.l_v[:, :2] * m_inv[None, None, :]], axis=2)
    feedthrough = order_sum(o.weight, o.l_v * m_inv[None, None, :], o.b_v)
    real_orders = o.weight == 1.0
    lam_n, vectors_n = order_modes(a_n, real_orders)
    orders, lam, beta, gamma, eta, b_rim, c_rim = [], [], [], [], [], [], []
    for index, n in enumerate(o.orders):
        values, vectors = lam_n[index], vectors_n[index]
        inverse = np.linalg.inv(vectors)
        factor = np.full(values.size, 2.0)  # a complex mode's partner is its conjugate
        if real_orders[index]:  # n = 0 or N/2: one of each conjugate pair, real modes once
            keep = values.imag >= 0.0
            values, vectors, inverse = values[keep], vectors[:, keep], inverse[keep]
            factor = np.where(values.imag == 0.0, 1.0, 2.0)
        orders.append(np.full(values.size, n))
        lam.append(values)
        beta.append(-inverse[:, 2] / n_el)
        gamma.append(factor * vectors[0])
        eta.append(factor * vectors[2] * m_inv[0])
        b_rim.append(inverse @ b_n[index][:, 0])
        c_rim.append(factor[None, :] * (c_n[index] @ vectors))
    orders = np.concatenate(orders)
    lam, beta, gamma, eta = (np.concatenate(x) for x in (lam, beta, gamma, eta))
    b_rim, c_rim = np.concatenate(b_rim), np.hstack(c_rim)
    real_mode = lam.imag == 0.0
    for x in (beta, gamma, eta, b_rim):  # a real eigenvalue has a real eigenvector
        x[real_mode] = x[real_mode].real
    c_rim[:, real_mode] = c_rim[:, real_mode].real
    modes = RingModes(orders, lam, beta, gamma, eta, b_rim, c_rim, np.zeros(0), np.zeros(0),
                      o.static_gain, zone_nodes, n_el, lam.size, truncation)

    # Truncation on the modes sorted by natural frequency (stable: order by order).
    by_size = np.argsort(np.abs(lam), kind="stable")
    keep_sorted = np.ones(lam.size, dtype=bool)
    if truncation.f_max_hz is not None:
        keep_sorted &= np.abs(lam[by_size]) <= 2 * np.pi * truncation.f_max_hz
    if truncation.n_modes is not None:
        keep_sorted &= np.cumsum(keep_sorted) <= truncation.n_modes
    keep = np.zeros(lam.size, dtype=bool)
    keep[by_size[keep_sorted]] = True
    d = o.d_direct + feedthrough
    e = o.e_direct.copy()
    if truncation.static_correction and not keep.all():
        b_all, c_all = modes.dense(grid.theta[zone_nodes])
        kept_dc = np.real(-(c_all[:, keep] / lam[keep]) @ b_all[keep])
        d = o.static_gain - kept_dc  # the exact DC gain, whatever is dropped
        dropped = ~keep
        e = e + np.real(-(c_all[:, dropped] / lam[dropped] ** 2) @ b_all[dropped])
    return RingModes(orders[keep], lam[keep], beta[keep], gamma[keep], eta[keep], b_rim[keep],
                     c_rim[:, keep], d, e, o.static_gain, zone_nodes, n_el, lam.size, truncation)


def free_ring_model(tire: TireParameters, grid: Grid, spin_rad_s: float,
                    zone_nodes: np.ndarray,
                    truncation: RingTruncation | None = None) -> FreeRingModel:
    """Modal form of the free rolling ring with rim and zone-force inputs (module doc), its
    modes sorted by natural frequency."""
    return ring_modes(tire, grid, spin_rad_s, zone_nodes, truncation).modal_form(grid)
