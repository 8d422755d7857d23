"""Modes of the in-plane ring: per circumferential order, and of the assembled tire.

The free ring with the rim held is circulant, so the Fourier vectors e^{inθ_j} of each field
block-diagonalise its matrices exactly: :func:`order_matrices` gives the small (2 or 4 field)
system of order n, from which the ground-frame frequencies follow without any order-matching
of eigenvectors. :func:`tire_modes` solves the assembled tire (rim held or free) and labels each
mode by its dominant order, its kind (radial, tangential, rotational for the tangential n = 0)
and, with a sidewall mass, whether tread and sidewall move in or out of phase.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from .inplane import InPlaneRing


def _fourier(ring: InPlaneRing, n: int) -> np.ndarray:
    """(n_ring_dof, fields): the unit Fourier vector of order n in each field."""
    column = np.exp(1j * n * ring.theta) / np.sqrt(ring.n_elements)
    return np.kron(np.eye(ring.n_fields), column[:, None])


def order_spectra(ring: InPlaneRing) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M, C, K) on every order at once, each (N, fields, fields) complex, rim held, order n at
    index n mod N. Each field block is circulant (the ring is the same at every node), so its
    value on e^{inθ}/√N is the DFT of its first column: one FFT per block instead of a dense
    projection per order (which made the critical speed cost N³ per matrix at N = 400).
    Kept on the ring: every order reads the same spectra."""
    if ring.rim_free:
        raise ValueError("rim_free: the rim couples orders 0 and 1; use tire_modes")
    cached = ring.__dict__.get("_order_spectra")
    if cached is None:
        n, fields = ring.n_elements, ring.n_fields
        # column q*n of a holds the first column of every block (p, q), by p along the rows
        cached = tuple(np.fft.fft(a[:, ::n].reshape(fields, n, fields), axis=1).transpose(1, 0, 2)
                       for a in (ring.mass, ring.damping, ring.stiffness))
        ring.__dict__["_order_spectra"] = cached
    return cached


def order_matrices(ring: InPlaneRing, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M_n, C_n, K_n): the ring's matrices on order n (rim held), complex (fields x fields)."""
    return tuple(spectrum[n % ring.n_elements] for spectrum in order_spectra(ring))


def quadratic_eigenvalues(mass, damping, stiffness) -> np.ndarray:
    """Eigenvalues s of (s²M + sC + K) q = 0 by the companion form, sorted by |Im s|."""
    size = mass.shape[0]
    inv_m = np.linalg.solve(mass, np.eye(size))
    companion = np.block([[np.zeros((size, size)), np.eye(size)],
                          [-inv_m @ stiffness, -inv_m @ damping]])
    s = scipy.linalg.eigvals(companion)
    return s[np.argsort(np.abs(s.imag), kind="stable")]


def order_frequencies_hz(ring: InPlaneRing, n: int) -> np.ndarray:
    """Signed ground-frame frequencies of order n (Hz), ascending.

    A root s = iω on e^{inθ} is the wave e^{i(nθ + ωt)}: ω > 0 travels against θ, ω < 0 with
    it; the magnitudes of a pair are the two frequencies a ground-fixed sensor sees for order
    |n|. At rest each frequency appears with both signs."""
    m, c, k = order_matrices(ring, n)
    return np.sort(quadratic_eigenvalues(m, c, k).imag) / (2.0 * np.pi)


def order_frequencies_at_rest_hz(ring: InPlaneRing, n: int) -> np.ndarray:
    """Undamped frequencies of order n at rest (Hz, ascending), from the Hermitian pencil."""
    m, _, k = order_matrices(ring, n)
    lam = scipy.linalg.eigvalsh(0.5 * (k + k.conj().T), 0.5 * (m + m.conj().T))
    return np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi)


@dataclass(frozen=True, eq=False)
class InPlaneMode:
    frequency_hz: float
    order: int
    kind: str  # "radial", "tangential", "rotational" or "rigid" (a free rim's zero modes)
    phase: str  # "in", "out" (tread and sidewall) or "" (massless sidewall, or rim rigid)
    tangential_share: float  # share of the ring's kinetic energy in v and v_s


@dataclass(frozen=True, eq=False)
class InPlaneModes:
    ring: InPlaneRing
    modes: tuple[InPlaneMode, ...]
    shapes: np.ndarray  # (n_dof, modes), mass-normalised

    def frequencies_hz(self) -> np.ndarray:
        return np.array([m.frequency_hz for m in self.modes])

    def select(self, *, kind: str | None = None, order: int | None = None,
               phase: str | None = None) -> list[InPlaneMode]:
        return [m for m in self.modes
                if (kind is None or m.kind == kind) and (order is None or m.order == order)
                and (phase is None or m.phase == phase)]

    def to_dict(self) -> dict:
        return {"n_elements": self.ring.n_elements, "rim_free": self.ring.rim_free,
                "modes": [m.__dict__ for m in self.modes]}


#: Frequencies below this (Hz) are the free rim's rigid-body modes.
RIGID_MODE_HZ = 1e-3


def _label(ring: InPlaneRing, shape: np.ndarray, frequency_hz: float) -> InPlaneMode:
    n = ring.n_elements
    fields = {name: shape[ring.field_slice(name)]
              for name in ("w", "v", "w_s", "v_s")[: ring.n_fields]}
    masses = ring.ring_mass.diagonal()
    energy = {name: float(np.sum(masses[ring.field_slice(name)] * np.abs(value) ** 2))
              for name, value in fields.items()}
    total = sum(energy.values()) or 1.0
    tangential = (energy["v"] + energy.get("v_s", 0.0)) / total
    spectrum = sum(np.abs(np.fft.rfft(value)) ** 2 for value in fields.values())
    order = int(np.argmax(spectrum[: n // 2 + 1]))
    if frequency_hz < RIGID_MODE_HZ:
        return InPlaneMode(frequency_hz, order, "rigid", "", tangential)
    kind = "tangential" if tangential > 0.5 else "radial"
    if kind == "tangential" and order == 0:
        kind = "rotational"
    phase = ""
    key = ("w", "w_s") if kind == "radial" else ("v", "v_s")
    if key[1] in fields:  # a tied or massless sidewall has no phase of its own
        phase = "in" if float(np.real(np.vdot(fields[key[0]], fields[key[1]]))) >= 0 else "out"
    return InPlaneMode(frequency_hz, order, kind, phase, tangential)


def tire_modes(ring: InPlaneRing, f_max_hz: float | None = None) -> InPlaneModes:
    """Undamped modes of the assembled tire at rest (rim held or free), labelled."""
    if ring.spin_rad_s != 0.0:
        raise ValueError("tire_modes is the tire at rest; order_frequencies_hz gives the "
                         "rolling ring's ground-frame frequencies")
    k = 0.5 * (ring.stiffness + ring.stiffness.T)
    lam, vec = scipy.linalg.eigh(k, ring.mass)
    freq = np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi)
    keep = slice(None) if f_max_hz is None else freq <= f_max_hz
    freq, vec = freq[keep], vec[:, keep]
    return InPlaneModes(ring, tuple(_label(ring, vec[:, i], freq[i]) for i in range(len(freq))),
                        vec)


#: The spin step (rad/s) of the three rings :func:`critical_speed` reads K's quadratic off
#: (at 0, S, 2S): K is exactly quadratic in the spin, and a step of the critical spins' size
#: keeps K2 = (K(2S) - 2 K(S) + K(0)) / 2S² from losing the digits of K(0)'s stencils that
#: cancel in it (a step of 1 rad/s, with the pencil unscaled, left up to 5e-9 of the critical
#: spin to rounding).
CRITICAL_FIT_STEP_RAD_S = 64.0
#: A spin Ω of the quadratic problem counts as real when |Im Ω| <= this |Ω| (the C's
#: companion form, native/c/inplane_critical.c; the Hermitian pencil here has real roots).
CRITICAL_REAL_TOLERANCE = 1e-9
#: A spin above 1/(this sqrt(|K2| / |K0|)) (Frobenius norms of the order's blocks: the order's
#: own spin scale) is taken as infinite: K2's null directions (the sidewall's, which the spin
#: does not load) are roots at infinite spin, which rounding leaves at large finite ones.
CRITICAL_INFINITE_SHARE = 1e-8


def critical_speed(model, n_elements: int):
    """The lowest speed (m/s) at which a ground-frame frequency of the undamped in-plane ring
    on this mesh reaches zero: a standing wave under the footprint (the radial ring's
    :func:`.standing_waves.critical_speed`, here with the tangential motion).

    A root s = 0 of order n means K_n(Ω) singular. K is quadratic in the spin, so the
    critical spins of order n are the real positive roots Ω of (K0 + Ω K1 + Ω² K2) q = 0,
    K read off the rings at 0, S and 2S (:data:`CRITICAL_FIT_STEP_RAD_S`); the lowest over
    the orders is the critical spin. Damping is left out: it makes the crossing a divergence
    rather than a zero, at the same speed for light damping, and with it goes K1 (the
    damping's circulatory part); the hysteretic loss is left out too (its share of the spin
    is not polynomial in it). Each order's K0 and K2 are then Hermitian and K0, the ring at
    rest with the rim held, is positive definite: the roots are Ω = 1/√ν for the eigenvalues
    ν > 0 of the Hermitian-definite pencil -K2 q = ν K0 q, real by structure (a companion
    form's roots carried rounding's imaginary parts, which a tolerance had to tell from
    complex roots, and at N = 200 it took the tie's top order's for complex). A root beyond
    :data:`CRITICAL_INFINITE_SHARE`'s bound is K2's null direction, at infinite spin.
    Returns a :class:`.standing_waves.CriticalSpeed` whose ``branch`` is the standing
    wave's kind, "radial" or "tangential" (its kinetic energy's larger part)."""
    from dataclasses import replace

    from .inplane import InPlaneRing, quadratic_in_spin
    from .standing_waves import CriticalSpeed

    undamped = replace(model, tire=replace(model.tire, alpha=0.0, beta=0.0))
    step = CRITICAL_FIT_STEP_RAD_S
    rings = [InPlaneRing(undamped, n_elements, spin_rad_s=s, hysteresis=False)
             for s in (0.0, step, 2.0 * step)]
    masses = np.real(np.diag(rings[0].ring_mass))[:: n_elements]  # per field, per node
    tangential_field = np.array([name.startswith("v") for name in rings[0].fields])
    best = (math.inf, None, None)
    for n in range(n_elements // 2 + 1):
        k0, _, k2 = quadratic_in_spin(*(order_matrices(r, n)[2] for r in rings), step)
        nu, vectors = scipy.linalg.eigh(-0.5 * (k2 + k2.conj().T), 0.5 * (k0 + k0.conj().T))
        bound = CRITICAL_INFINITE_SHARE * math.sqrt(np.linalg.norm(k2) / np.linalg.norm(k0))
        for index in np.flatnonzero(nu > bound**2):
            spin = float(1.0 / math.sqrt(nu[index]))
            if spin < best[0]:
                energy = masses * np.abs(vectors[:, index]) ** 2
                kind = ("tangential" if energy[tangential_field].sum() > 0.5 * energy.sum()
                        else "radial")
                best = (spin, n, kind)
    spin, order, kind = best
    radius = model.tire.R
    return CriticalSpeed(spin * radius, spin, order, kind, int(n_elements))


@dataclass(frozen=True, eq=False)
class InPlaneSpeedSweep:
    """Ground-frame frequencies of the undeformed in-plane ring, rim held, order by order
    against the speed (the radial ring's speed sweep, Fig. 19, with the tangential motion).

    ``against_hz`` and ``with_hz`` are (speeds, orders, fields): the waves travelling against
    the rotation (e^{i(nθ + ωt)}, ω > 0) and with it, each ascending, NaN where an order has
    fewer (a wave that turned over at a critical speed); at rest the two are equal."""

    speeds_m_s: np.ndarray
    orders: np.ndarray
    against_hz: np.ndarray
    with_hz: np.ndarray
    n_elements: int
    radius_m: float

    def split_hz(self, order: int, branch: int = 0) -> np.ndarray:
        """(speeds,): the ground-frame split of an order's branch (0: its lowest pair), the
        two frequencies' difference."""
        (j,) = np.flatnonzero(self.orders == order)
        return np.abs(self.against_hz[:, j, branch] - self.with_hz[:, j, branch])

    def to_dict(self) -> dict:
        def listed(a):
            return [[[None if np.isnan(x) else float(x) for x in row] for row in block]
                    for block in a]

        return {"speeds_m_s": self.speeds_m_s.tolist(), "orders": self.orders.tolist(),
                "n_elements": self.n_elements, "against_rotation_hz": listed(self.against_hz),
                "with_rotation_hz": listed(self.with_hz)}


def speed_sweep(model, n_elements: int, speeds_m_s, orders) -> InPlaneSpeedSweep:
    """:class:`InPlaneSpeedSweep` of ``model`` (an InPlaneTire) on N = ``n_elements``: the
    undamped ring's roots per order (:func:`order_frequencies_hz`) at each speed."""
    speeds = np.asarray(speeds_m_s, dtype=float)
    orders = np.asarray(orders, dtype=int)
    against = with_ = None
    for i, speed in enumerate(speeds):
        ring = InPlaneRing(model, n_elements, spin_rad_s=speed / model.tire.R)
        for j, n in enumerate(orders):
            f = order_frequencies_hz(ring, int(n))
            if against is None:
                against = np.full((speeds.size, orders.size, f.size), np.nan)
                with_ = np.full_like(against, np.nan)
            up, down = np.sort(f[f > 0]), np.sort(-f[f < 0])
            against[i, j, :up.size], with_[i, j, :down.size] = up, down
    # the branches no order has at any speed (a root per field each way, below a critical
    # speed) are left out
    kept = ~np.all(np.isnan(against) & np.isnan(with_), axis=(0, 1))
    return InPlaneSpeedSweep(speeds, orders, against[:, :, kept], with_[:, :, kept],
                             int(n_elements), model.tire.R)
