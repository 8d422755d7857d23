"""Closed form of the undeformed, non-rotating in-plane ring with the rim held, per order n.

Written from the continuum energy (the one in :mod:`.inplane`'s docstring) without touching the
finite-difference code, so it is an independent reference. For n >= 1 the order's shape is
w = W cos nθ, v = V sin nθ (w_s, v_s likewise); for n = 0 it is w = W, v = V (breathing and
torsion, which separate). Each term of the energy is then a quadratic form in the amplitudes:

    membrane   EA/R²  (W + nV)²              (v' + w = (W + nV) cos nθ)
    bending    EI/R⁴  (n²W + nV)²            (w'' - v' = -(n²W + nV) cos nθ)
    pressure   p₀b/R  (n²W² + n²V² + 2nWV)   (w'² + v'² - 2vw', averaged; 0 at n = 0)
    sidewall   k_r1 (W - W_s)² + k_t1 (V - V_s)² + k_r2 W_s² + k_t2 V_s²

against the kinetic ρA(W² + V²) + m_s(W_s² + V_s²); the frequencies are the generalised
eigenvalues of these 4x4 (2x2 with a massless sidewall: k_r, k_t in series) forms. The rigid
translation W = 1, V = -1 of order 1 stores nothing in the first three lines: with a
massless sidewall and a membrane too stiff to stretch (W + V = 0 enforced) it is the order's
lowest mode, at sqrt((k_r + k_t)/(2ρA)), the ring riding on the foundation alone. The tied
tangential sidewall (V_s = r V, the default of :class:`.inplane.InPlaneTire`) is the 3x3 form
with k_t1(1 - r)² + k_t2 r² on V and r² m_s added to its mass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from .inplane import InPlaneTire


@dataclass(frozen=True, eq=False)
class InPlaneAnalyticModes:
    """Frequencies (Hz, ascending per order) and amplitude vectors of each order."""

    orders: np.ndarray
    frequencies_hz: np.ndarray  # (orders, branches)
    shapes: np.ndarray  # (orders, branches, amplitudes): (W, V[, W_s, V_s]) per branch


def order_forms(model: InPlaneTire, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(stiffness, mass) of order n per metre, amplitudes (W, V[, W_s[, V_s]])."""
    t, tang = model.tire, model.tangential
    radius = t.R
    ea, ei, pb = tang.EA / radius**2, t.EI / radius**4, t.pretension_n / radius**2
    membrane = np.array([1.0, n])
    bending = np.array([n**2, n])
    k = ea * np.outer(membrane, membrane) + ei * np.outer(bending, bending)
    if n:
        k += pb * np.array([[n**2, n], [n, n**2]])
    mass = np.diag([t.rhoA, t.rhoA])
    if not model.sidewall_mass:
        k_r, k_t = model.series_foundation()
        return k + np.diag([k_r, k_t]), mass
    k_r1, k_r2, k_t1, k_t2 = t.effective_k_r1, t.effective_k_r2, tang.k_t1, tang.k_t2
    if model.sidewall_tangential == "tied":
        # V_s = r V with r = k_t1/(k_t1 + k_t2): k_t1 (1 - r)² + k_t2 r² is the series spring
        r = k_t1 / (k_t1 + k_t2)
        full = np.zeros((3, 3))
        full[:2, :2] = k + np.diag([k_r1, k_t1 * (1 - r) ** 2 + k_t2 * r**2])
        full[2, 2] = k_r1 + k_r2
        full[0, 2] = full[2, 0] = -k_r1
        return full, np.diag([t.rhoA, t.rhoA + r**2 * t.m_s, t.m_s])
    full = np.zeros((4, 4))
    full[:2, :2] = k + np.diag([k_r1, k_t1])
    full[2:, 2:] = np.diag([k_r1 + k_r2, k_t1 + k_t2])
    full[:2, 2:] = full[2:, :2] = -np.diag([k_r1, k_t1])
    return full, np.diag([t.rhoA, t.rhoA, t.m_s, t.m_s])


def inplane_analytic_modes(model: InPlaneTire, orders) -> InPlaneAnalyticModes:
    """Every branch of each order n (Hz), lowest first."""
    orders = np.asarray(orders, dtype=int)
    freqs, shapes = [], []
    for n in orders:
        k, m = order_forms(model, int(n))
        lam, vec = scipy.linalg.eigh(k, m)
        freqs.append(np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi))
        shapes.append(vec.T)
    return InPlaneAnalyticModes(orders, np.array(freqs), np.array(shapes))


def inextensible_split_factor(n) -> np.ndarray:
    """n(n²-1)/(n²+1): the ground-frame split of order n of an inextensible ring is 2Ω times
    this (Huang & Soedel, J. Sound Vib. 118, 1987); 0 at n = 1, so the translation does not
    split. A radial-only ring has n instead."""
    n = np.asarray(n, dtype=float)
    return n * (n**2 - 1.0) / (n**2 + 1.0)
