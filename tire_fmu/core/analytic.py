"""Closed-form frequencies of the undeformed ring tire (eq. 12 of the paper, solved exactly).

For a harmonic u_r = A cos nθ, u_s = B cos nθ, eq. 12 reads

    (a_n - ρA ω²)(k_r1 + k_r2 - m_s ω²) = k_r1²,   a_n = EI n⁴/R⁴ + p₀ b n²/R + k_r1,

a quadratic in ω² whose two roots are the in-phase (A, B same sign) and out-of-phase
frequencies of order n. The paper's eqs. 13-18 print garbled coefficients; this module does not
use them. Nothing here touches the finite-difference code, so it is an independent reference.
The optional sidewall shear G adds G n²/R² to the sidewall stiffness (0 in the paper). The
sidewall stiffnesses are taken at the inflation pressure (``TireParameters.effective_k_r1`` etc.,
the optional pressure law; equal to k_r1, k_r2, G when it is off). Above
``sidewall_max_order`` K > 0 the sidewall is tied to the tread: the energy ½p(B - rA)² with
r = k_r1/(k_r1 + k_r2 + G n²/R²) and p = F·(a_n + k_r1 + k_r2 + G n²/R²), F the tie factor,
adds p r², p and -p r to the three stiffnesses of order n > K (written out here apart from
:func:`tire_fmu.core.dispersion.sidewall_tie`, which the FDM code uses).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .parameters import SIDEWALL_TIE_FACTOR, TireParameters


@dataclass(frozen=True, eq=False)
class AnalyticModes:
    """Exact frequencies per order n of the undeformed, non-rotating tire."""

    orders: np.ndarray
    in_phase_hz: np.ndarray
    out_of_phase_hz: np.ndarray
    #: sidewall/tread amplitude ratio B/A of each branch (positive = in phase)
    in_phase_ratio: np.ndarray
    out_of_phase_ratio: np.ndarray

    def to_dict(self) -> dict:
        return {
            "orders": self.orders.tolist(),
            "in_phase_hz": self.in_phase_hz.tolist(),
            "out_of_phase_hz": self.out_of_phase_hz.tolist(),
            "in_phase_ratio": self.in_phase_ratio.tolist(),
            "out_of_phase_ratio": self.out_of_phase_ratio.tolist(),
        }


def tread_stiffness(tire: TireParameters, orders) -> np.ndarray:
    """a_n = EI n⁴/R⁴ + p₀ b n²/R + k_r1 (N/m per metre), the tread's modal stiffness."""
    n = np.asarray(orders, dtype=float)
    return tire.EI * n**4 / tire.R**4 + tire.pretension_n * n**2 / tire.R**2 + tire.effective_k_r1


def sidewall_stiffness(tire: TireParameters, orders) -> np.ndarray:
    n = np.asarray(orders, dtype=float)
    return (tire.effective_k_r1 + tire.effective_k_r2
            + tire.effective_sidewall_shear * n**2 / tire.R**2)


def two_mass_eigenvalues(k_tread, k_sidewall, k_coupling, m_tread, m_sidewall):
    """Both roots λ = ω² of det([[k_t - m_t λ, -k_c], [-k_c, k_s - m_s λ]]) = 0, low first.

    m_t m_s λ² - (k_t m_s + k_s m_t) λ + (k_t k_s - k_c²) = 0. The discriminant is
    (k_t m_s - k_s m_t)² + 4 m_t m_s k_c² >= 0, so both roots are real.
    """
    quad = m_tread * m_sidewall
    lin = k_tread * m_sidewall + k_sidewall * m_tread
    const = k_tread * k_sidewall - k_coupling**2
    root = np.sqrt((k_tread * m_sidewall - k_sidewall * m_tread) ** 2 + 4.0 * quad * k_coupling**2)
    high = (lin + root) / (2.0 * quad)
    low = const / (quad * high)  # product of roots; avoids cancellation in (lin - root)
    return low, high


def analytic_modes(tire: TireParameters, orders) -> AnalyticModes:
    """Both roots of eq. 12 for each order n (Hz), with their amplitude ratios."""
    n = np.asarray(orders, dtype=int)
    a = tread_stiffness(tire, n)
    side = sidewall_stiffness(tire, n)
    k_r1 = np.full(a.shape, tire.effective_k_r1)
    if tire.sidewall_max_order > 0:
        tie = np.where(np.abs(n) > tire.sidewall_max_order, SIDEWALL_TIE_FACTOR * (a + side), 0.0)
        share = tire.effective_k_r1 / side
        a, side, k_r1 = a + tie * share**2, side + tie, k_r1 + tie * share
    low, high = two_mass_eigenvalues(a, side, k_r1, tire.rhoA, tire.m_s)

    def ratio(lam):  # B/A from the first row of eq. 12
        return (a - tire.rhoA * lam) / k_r1

    return AnalyticModes(
        orders=n,
        in_phase_hz=np.sqrt(low) / (2.0 * np.pi),
        out_of_phase_hz=np.sqrt(high) / (2.0 * np.pi),
        in_phase_ratio=ratio(low),
        out_of_phase_ratio=ratio(high),
    )


def continuum_symbols(orders) -> dict[str, np.ndarray]:
    """Exact θ-derivative symbols on e^{inθ}: the continuum counterpart of the FDM symbols."""
    n = np.asarray(orders, dtype=float)
    return {"d1": 1j * n, "d2": -(n**2), "d4": n**4, "d1d1": -(n**2)}
