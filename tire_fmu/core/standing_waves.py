"""Critical (standing-wave) speed: where a ground-frame frequency of the rolling ring reaches 0.

At that speed the contact load, fixed in space, meets a mode of zero ground frequency: a
standing wave. With the paper's lumped sidewall the masses have no circumferential coupling, so
the sidewall band (just below sqrt((k_r1+k_r2)/m_s)/2π) has no wave speed: its ground frequency
ω_s - κ_nΩ first reaches zero at the largest discrete wavenumber κ = 1/δθ, i.e. at
V ≈ ω_s·R·δθ. The critical speed therefore belongs to a mesh and falls as N grows (about 43 m/s
at N = 100, 11 m/s at N = 400). A circumferential sidewall shear G > 0 gives the band a wave
speed ~ sqrt(G/m_s) and a critical speed that converges with N.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.optimize as so

from .dispersion import body_frequencies, order_symbols
from .parameters import TireParameters

#: Speeds are scanned up to this; a tire with no standing wave below it reports infinity.
MAX_SCANNED_SPEED_M_S = 400.0
#: Spins scanned (evenly, from 0 to the largest) before a crossing is refined with brentq.
SCAN_POINTS = 801
#: brentq's absolute and relative tolerance on the critical spin (rad/s).
ROOT_TOLERANCE = 1e-12


@dataclass(frozen=True)
class CriticalSpeed:
    speed_m_s: float
    spin_rad_s: float
    order: int | None  # the |n| whose ground frequency reaches zero first
    branch: str | None  # "in" (sidewall band) or "out"
    n_elements: int

    def to_dict(self) -> dict:
        return {
            "critical_speed_m_s": self.speed_m_s,
            "critical_speed_km_h": self.speed_m_s * 3.6,
            "spin_rad_s": self.spin_rad_s,
            "order": self.order,
            "branch": self.branch,
            "n_elements": self.n_elements,
        }


def _margins(tire: TireParameters, orders, kappa, n_elements, spin):
    """Lowest ground frequency per order and branch (rad/s); <= 0 or nan means critical."""
    low, high = body_frequencies(tire, orders, spin, n_elements)
    return np.stack([low - kappa * spin, high - kappa * spin])


def critical_speed(tire: TireParameters, n_elements: int) -> CriticalSpeed:
    """Lowest speed at which an undeformed ground-frame frequency of this mesh reaches zero."""
    return _critical_speed(tire, int(n_elements))


@lru_cache(maxsize=64)
def _critical_speed(tire: TireParameters, n_elements: int) -> CriticalSpeed:
    orders = np.arange(1, n_elements // 2 + 1)
    kappa = (order_symbols(orders, n_elements)["d1"] / 1j).real
    spins = np.linspace(0.0, MAX_SCANNED_SPEED_M_S / tire.R, SCAN_POINTS)[1:]
    previous = 0.0
    for spin in spins:
        margins = _margins(tire, orders, kappa, n_elements, spin)
        bad = ~(margins > 0.0)
        if bad.any():
            # Several orders may cross inside one scan interval: refine each, keep the first.
            candidates = []
            for branch_index, order_index in np.argwhere(bad):
                n = orders[order_index : order_index + 1]
                k = kappa[order_index : order_index + 1]

                def margin(s, b=branch_index, n=n, k=k):
                    value = _margins(tire, n, k, n_elements, s)[b, 0]
                    return value if np.isfinite(value) else -1.0

                root = so.brentq(margin, previous, spin, xtol=ROOT_TOLERANCE, rtol=ROOT_TOLERANCE)
                candidates.append((root, int(n[0]), ("in", "out")[branch_index]))
            root, order, branch = min(candidates)
            return CriticalSpeed(root * tire.R, root, order, branch, n_elements)
        previous = spin
    return CriticalSpeed(np.inf, np.inf, None, None, n_elements)
