"""Contact-patch geometry: node weights, chord geometry and road delays.

The patch is the arc |θ| <= L/(2R) centred on node 0. Each tread node carries k_cw·R·δθ
times the fraction of its own arc [θ_j - δθ/2, θ_j + δθ/2] inside the patch, so frequencies and
stiffness vary continuously with patch length instead of in node-sized steps.

Load and patch length are tied through the flat-road chord, L = 2·sqrt(2Rδ - δ²), and the
model's own static vertical stiffness K_v(L) (see :mod:`tire_fmu.core.model`): the load that
makes patch L is W(L) = K_v(L)·δ(L), the secant force of the linear model deflected by the
geometric deflection of that patch. W grows monotonically with L, so either one fixes the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .discretisation import Grid


def patch_weights(grid: Grid, patch_length_m: float) -> np.ndarray:
    """Fraction of each node's arc inside the patch (0..1), symmetric about node 0."""
    half_angle = 0.5 * patch_length_m / grid.radius_m
    distance = np.abs(grid.theta)  # |θ| makes the weights exactly mirror-symmetric
    lo = distance - 0.5 * grid.dtheta
    hi = distance + 0.5 * grid.dtheta
    overlap = np.minimum(hi, half_angle) - np.maximum(lo, -half_angle)
    return np.clip(overlap / grid.dtheta, 0.0, 1.0)


def patch_node_centroids(grid: Grid, patch_length_m: float) -> np.ndarray:
    """Angle of the centroid of each node's in-patch arc (nan for nodes outside the patch)."""
    half_angle = 0.5 * patch_length_m / grid.radius_m
    lo = np.maximum(grid.theta - 0.5 * grid.dtheta, -half_angle)
    hi = np.minimum(grid.theta + 0.5 * grid.dtheta, half_angle)
    return np.where(hi > lo, 0.5 * (lo + hi), np.nan)


def road_delays_s(grid: Grid, patch_length_m: float, speed_m_s: float) -> np.ndarray:
    """Delay after which each patch node sees the road height measured at the leading edge.

    Rolling forward, road points enter the patch at θ = -L/(2R) (the leading edge: θ runs
    with the rotation, rearwards at the patch) and travel to +L/(2R) at speed V. At V = 0 the
    whole patch sees the road at once, a shaker plate. Nodes outside the patch get nan.
    """
    centroid = patch_node_centroids(grid, patch_length_m)
    if speed_m_s <= 0.0:
        return np.where(np.isnan(centroid), np.nan, 0.0)
    half_angle = 0.5 * patch_length_m / grid.radius_m
    return grid.radius_m * (centroid + half_angle) / speed_m_s


def deflection_from_patch_length(radius_m: float, patch_length_m: float) -> float:
    """Flat-road chord: a patch of length L on a circle of radius R sits δ below its centre."""
    half = 0.5 * patch_length_m
    return radius_m - math.sqrt(max(radius_m**2 - half**2, 0.0))


def patch_length_from_deflection(radius_m: float, deflection_m: float) -> float:
    d = min(max(deflection_m, 0.0), radius_m)
    return 2.0 * math.sqrt(max(2.0 * radius_m * d - d * d, 0.0))


@dataclass(frozen=True)
class ContactPatch:
    """The static contact state a model was linearised at."""

    length_m: float
    deflection_m: float
    load_n: float
    vertical_stiffness_n_per_m: float
    weights: np.ndarray
    road_delays_s: np.ndarray

    @property
    def in_contact(self) -> bool:
        return self.length_m > 0.0

    @property
    def node_indices(self) -> np.ndarray:
        return np.flatnonzero(self.weights > 0.0)

    def to_dict(self) -> dict:
        return {
            "patch_length_m": self.length_m,
            "deflection_m": self.deflection_m,
            "load_n": self.load_n,
            "vertical_stiffness_n_per_m": self.vertical_stiffness_n_per_m,
            "patch_nodes": int(self.node_indices.size),
        }
