"""Critical (standing-wave) speed: where a ground-frame frequency of the rolling ring reaches 0.

At that speed the contact load, fixed in space, meets a mode of zero ground frequency: a
standing wave. With the paper's lumped sidewall the masses have no circumferential coupling, so
the sidewall band (just below sqrt((k_r1+k_r2)/m_s)/2π) has no wave speed: its ground frequency
ω_s - κ_nΩ first reaches zero at the largest discrete wavenumber κ = 1/δθ, i.e. at
V ≈ ω_s·R·δθ. The critical speed therefore belongs to a mesh and falls as N grows (about 43 m/s
at N = 100, 11 m/s at N = 400). A circumferential sidewall shear G > 0 gives the band a wave
speed ~ sqrt(G/m_s) and a critical speed that converges with N, at first order and to a value
the modal data cap near 27 m/s. A sidewall tied to the tread above ``sidewall_max_order``
(:func:`.dispersion.sidewall_tie`) has no band there: the critical speed is where the in-phase
mode of the top order stands still, and it converges at second order (docs/theory.md §8.10).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .dispersion import body_frequencies, order_symbols
from .parameters import TireParameters

#: Speeds are scanned up to this; a tire with no standing wave below it reports infinity.
MAX_SCANNED_SPEED_M_S = 400.0
#: Spins scanned (evenly, from 0 to the largest) before a crossing is refined with brentq.
SCAN_POINTS = 801
#: Spins whose margins one numpy call evaluates while scanning (the first crossing of the
#: default tire is the 86th spin).
SCAN_CHUNK = 64
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
    for start in range(0, spins.size, SCAN_CHUNK):
        # (branch, spin, order): the same numbers as one spin at a time, in fewer calls
        bad = ~(_margins(tire, orders, kappa, n_elements,
                         spins[start:start + SCAN_CHUNK, None]) > 0.0)
        crossed = np.flatnonzero(bad.any(axis=(0, 2)))
        if not crossed.size:
            continue
        index = start + int(crossed[0])
        previous, spin = (spins[index - 1] if index else 0.0), spins[index]
        # Several orders may cross inside one scan interval: refine each, keep the first.
        candidates = []
        for branch_index, order_index in np.argwhere(bad[:, crossed[0]]):
            n = orders[order_index : order_index + 1]
            k = kappa[order_index : order_index + 1]

            def margin(s, b=branch_index, n=n, k=k):
                value = _margins(tire, n, k, n_elements, s)[b, 0]
                return value if np.isfinite(value) else -1.0

            root = brentq(margin, previous, spin, ROOT_TOLERANCE, ROOT_TOLERANCE)
            candidates.append((root, int(n[0]), ("in", "out")[branch_index]))
        root, order, branch = min(candidates)
        return CriticalSpeed(root * tire.R, root, order, branch, n_elements)
    return CriticalSpeed(np.inf, np.inf, None, None, n_elements)

def brentq(f, a: float, b: float, xtol: float, rtol: float, iterations: int = 100) -> float:
    """A root of ``f`` in [a, b], where f(a) and f(b) differ in sign: Brent's method as
    ``scipy.optimize.brentq`` runs it (scipy's brentq.c, step for step, so the same root to
    the bit), and as the native FMU's numerics.c does.

    Written out here because importing scipy.optimize for it cost the FMU's start-up more
    than the rest of its initialisation (``benchmarks/bench_fmu_init.py``). Raises
    ValueError for a bracket without a sign change and RuntimeError when ``iterations``
    (scipy's default 100) do not converge, as scipy does.
    """
    xpre, xcur = float(a), float(b)
    fpre, fcur = float(f(xpre)), float(f(xcur))
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):  # C's signbit
        raise ValueError("f(a) and f(b) must have different signs")
    xblk = fblk = spre = scur = 0.0
    for _ in range(iterations):
        if fpre != 0 and fcur != 0 and math.copysign(1.0, fpre) != math.copysign(1.0, fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):  # good short step
                spre, scur = scur, stry
            else:  # bisect
                spre = scur = sbis
        else:  # bisect
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
        fcur = float(f(xcur))
    raise RuntimeError(f"brentq: no convergence after {iterations} iterations, "
                       f"last x = {xcur!r}")
