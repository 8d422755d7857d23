"""Dispersion relation of the undeformed rolling ring, discrete (FDM symbols) and continuum.

On e^{inθ} every circulant operator of the undeformed model is a number, so the 2N×2N
problem splits into one 2×2 problem per order n. In the body (co-rotating) frame

    M s_b² + C s_b + K*(n, Ω) = 0,   K*_tt = EI/R⁴ λ4 + P*/R² λ2 + k_r1 - ρAΩ²,
                                      K*_ss = k_r1 + k_r2 + G/R² λ2 - m_sΩ², K*_ts = -k_r1,

and the ground-frame eigenvalue is s = s_b - iΩκ_n with iκ_n the symbol of ∂θ. With the FDM
symbols (λ2 = 4sin²(nδθ/2)/δθ², λ4 = λ2², κ = sin(nδθ)/δθ) this is exactly the spectrum of the
assembled undeformed model; with λ2 = n², λ4 = n⁴, κ = n it is the continuum, ω = ω_b(n,Ω) - nΩ.

Sign convention: a mode of order n is the field Re(e^{i(nθ + ωt)}) with ω >= 0. Its phase
moves at dθ/dt = -ω/n: n > 0 travels against the rotation (backward, its ground frequency falls
with speed), n < 0 with it (forward).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .analytic import continuum_symbols, two_mass_eigenvalues
from .discretisation import symbols as fdm_symbols
from .parameters import SIDEWALL_TIE_FACTOR, TireParameters


def order_symbols(orders, n_elements: int | None) -> dict[str, np.ndarray]:
    """FDM symbols on a grid of ``n_elements`` nodes, or the continuum ones for None."""
    if n_elements is None:
        return continuum_symbols(orders)
    return fdm_symbols(orders, 2.0 * np.pi / n_elements)


def lumped_stiffness(tire: TireParameters, sym):
    """Tread and sidewall stiffness per order and metre at rest, without the tie (the lumped
    sidewall's): EI/R⁴ λ4 + P/R² λ2 + k_r1 and k_r1 + k_r2 + G/R² λ2."""
    lam2 = -sym["d2"]
    k0_tt = tire.EI / tire.R**4 * sym["d4"] + tire.pretension_n / tire.R**2 * lam2
    k0_tt = k0_tt + tire.effective_k_r1
    k0_ss = (tire.effective_k_r1 + tire.effective_k_r2
             + tire.effective_sidewall_shear / tire.R**2 * lam2)
    return k0_tt, k0_ss


def sidewall_tie(tire: TireParameters, orders, k0_tt, k0_ss):
    """The tie of the sidewall to the tread above ``sidewall_max_order``, per order and metre:
    (tt, ss, ts) entries of p·[[r², -r], [-r, 1]] with r = k_r1 / k0_ss, zero at and below
    the order (and everywhere for sidewall_max_order = 0).

    Energy ½p(w_s - r w_r)²: with r the sidewall's static share of the tread's displacement,
    the free ring's static state at rest stores none, so static compliances (footprint, vertical
    stiffness) are the lumped sidewall's, while the sidewall's own band, which has no wave speed
    and so would set a critical speed that falls as 1/N, is moved out of those orders: the
    sidewall there rides on the tread. p = SIDEWALL_TIE_FACTOR (k0_tt + k0_ss) rises with the
    tread's bending, so the tie's own branch has a phase speed that grows with n.
    """
    n = np.abs(np.asarray(orders, dtype=float))
    top = tire.sidewall_max_order
    tied = (n > top) if top > 0 else np.zeros(n.shape, dtype=bool)
    ratio = tire.effective_k_r1 / k0_ss
    p = np.where(tied, SIDEWALL_TIE_FACTOR * (k0_tt + k0_ss), 0.0)
    return p * ratio * ratio, p, -p * ratio


def per_order_matrices(tire: TireParameters, sym, spin_rad_s: float, orders):
    """Body-frame 2×2 stiffness (K*) and material damping entries per order, per metre."""
    lam2 = -sym["d2"]
    centrifugal = tire.rhoA * tire.R**2 * spin_rad_s**2
    k_r1 = tire.effective_k_r1  # sidewall stiffnesses at the inflation pressure
    k0_tt, k0_ss = lumped_stiffness(tire, sym)
    # material damping on the lumped structure: the tie is an (elastic) constraint, no damper,
    # so its modes stay oscillatory and apart from the tread's overdamped roots near -1/β
    c_tt = tire.alpha * tire.rhoA + tire.beta * k0_tt
    c_ss = tire.alpha * tire.m_s + tire.beta * k0_ss
    c_ts = -tire.beta * k_r1
    tie_tt, tie_ss, tie_ts = sidewall_tie(tire, orders, k0_tt, k0_ss)
    k0_tt, k0_ss, k0_ts = k0_tt + tie_tt, k0_ss + tie_ss, tie_ts - k_r1
    k_tt = k0_tt + centrifugal / tire.R**2 * lam2 - tire.rhoA * spin_rad_s**2
    k_ss = k0_ss - tire.m_s * spin_rad_s**2
    return (k_tt, k_ss, k0_ts), (c_tt, c_ss, c_ts)


def body_frequencies(tire: TireParameters, orders, spin_rad_s: float = 0.0, n_elements=None):
    """Undamped body-frame frequencies (rad/s) per order: (in-phase, out-of-phase) branches.

    Where spin softening makes K* indefinite the low branch becomes imaginary; it is returned as
    nan, the body-frame ring having buckled.
    """
    sym = order_symbols(orders, n_elements)
    (k_tt, k_ss, k_ts), _ = per_order_matrices(tire, sym, spin_rad_s, orders)
    low, high = two_mass_eigenvalues(k_tt, k_ss, k_ts, tire.rhoA, tire.m_s)
    with np.errstate(invalid="ignore"):
        return np.sqrt(low), np.sqrt(high)


def eigenvalues(tire: TireParameters, orders, spin_rad_s: float = 0.0, n_elements=None):
    """Damped ground-frame eigenvalues s (1/s), shape (len(orders), 4), per order n.

    Each row holds the four roots of det(M(s + iΩκ)² + C(s + iΩκ) + K*) = 0, i.e. the body
    frame roots shifted by -iΩκ_n. Row n and row -n are complex conjugates of each other.
    """
    n = np.atleast_1d(np.asarray(orders, dtype=float))
    sym = order_symbols(n, n_elements)
    (k_tt, k_ss, k_ts), (c_tt, c_ss, c_ts) = per_order_matrices(tire, sym, spin_rad_s, n)
    m_inv = np.array([1.0 / tire.rhoA, 1.0 / tire.m_s])
    companion = np.zeros((n.size, 4, 4))
    companion[:, 0, 2] = companion[:, 1, 3] = 1.0
    stiff = np.stack([np.stack([k_tt, np.full_like(k_tt, k_ts)], -1),
                      np.stack([np.full_like(k_tt, k_ts), k_ss], -1)], -2)
    damp = np.stack([np.stack([c_tt, np.full_like(c_tt, c_ts)], -1),
                     np.stack([np.full_like(c_tt, c_ts), c_ss], -1)], -2)
    companion[:, 2:, :2] = -m_inv[None, :, None] * stiff
    companion[:, 2:, 2:] = -m_inv[None, :, None] * damp
    body = np.linalg.eigvals(companion)
    kappa = (sym["d1"] / 1j).real
    return body - 1j * spin_rad_s * kappa[:, None]


@dataclass(frozen=True, eq=False)
class Dispersion:
    """Ground-frame frequency of every signed order n, both branches, at one spin."""

    orders: np.ndarray  # signed n
    wavenumber_per_m: np.ndarray  # k = n / R
    in_phase_hz: np.ndarray  # ω_b(|n|) - κ_n Ω, may go negative beyond the critical speed
    out_of_phase_hz: np.ndarray
    spin_rad_s: float
    n_elements: int | None  # None: continuum

    def to_dict(self) -> dict:
        return {
            "spin_rad_s": self.spin_rad_s,
            "n_elements": self.n_elements,
            "orders": self.orders.tolist(),
            "wavenumber_per_m": self.wavenumber_per_m.tolist(),
            "in_phase_hz": self.in_phase_hz.tolist(),
            "out_of_phase_hz": self.out_of_phase_hz.tolist(),
        }


def dispersion_relation(
    tire: TireParameters, orders, spin_rad_s: float, n_elements=None
) -> Dispersion:
    """Undamped ground-frame dispersion ω(n) = ω_b(|n|, Ω) - κ_n Ω of the undeformed ring."""
    n = np.asarray(orders, dtype=int)
    low, high = body_frequencies(tire, np.abs(n), spin_rad_s, n_elements)
    kappa = (order_symbols(n, n_elements)["d1"] / 1j).real
    shift = kappa * spin_rad_s
    return Dispersion(
        orders=n,
        wavenumber_per_m=n / tire.R,
        in_phase_hz=(low - shift) / (2.0 * np.pi),
        out_of_phase_hz=(high - shift) / (2.0 * np.pi),
        spin_rad_s=spin_rad_s,
        n_elements=n_elements,
    )
