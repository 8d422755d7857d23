"""Contact points written apart from tire_fmu.core.contact, for the tests to check it against:
the points of each node arc at its sub-arc centres, and their interpolation weights from a
Vandermonde solve on the four nearest nodes (not the closed-form Lagrange polynomials the core
uses)."""

import math

import numpy as np


def points_per_node(node_arc_m: float, spacing_m: float) -> int:
    m = 1
    while node_arc_m / m > spacing_m * (1 + 1e-9):
        m += 2
    return m


def reference_points(n_elements: int, radius_m: float, spacing_m: float, max_angle: float):
    """(theta (P,), interpolation (P, N) on the ring's nodes, m) for every node within
    ``max_angle`` of the contact centre."""
    dtheta = 2 * math.pi / n_elements
    m = points_per_node(radius_m * dtheta, spacing_m)
    thetas, rows = [], []
    reach = int(max_angle / dtheta)
    for j in range(-reach, reach + 1):
        for i in range(m):
            theta = (j + (i + 0.5) / m - 0.5) * dtheta  # centre of sub-arc i of node j's arc
            row = np.zeros(n_elements)
            if m == 1:
                row[j % n_elements] = 1.0
            else:
                x = theta / dtheta
                left = math.floor(x + 1e-12)
                stencil = np.arange(left - 1, left + 3)
                # weights w with sum_k w_k x_k^q = x^q, q = 0..3: exact for cubics
                vander = np.vander(stencil.astype(float), 4, increasing=True).T
                weights = np.linalg.solve(vander, x ** np.arange(4))
                np.add.at(row, stencil % n_elements, weights)
            thetas.append(theta)
            rows.append(row)
    return np.array(thetas), np.array(rows), m


def zone_length_rounding_to_node(n_elements: int, radius_m: float, node: int) -> float:
    """A zone length whose half angle, with the zone's slack (1e-12), divided by δθ rounds to
    ``node`` although node·δθ lies just beyond it: floor(limit/δθ) takes the node into the
    zone, its angle leaves it out (found within a few ulps of the length that puts the limit
    on the node)."""
    dtheta = 2 * math.pi / n_elements
    start = 2 * radius_m * math.tan(node * dtheta / (1 + 1e-12))
    for ulps in sorted(range(-64, 65), key=abs):
        length = start + ulps * math.ulp(start)
        limit = min(math.atan(0.5 * length / radius_m), math.pi / 3) * (1 + 1e-12)
        if math.floor(limit / dtheta) == node and node * dtheta > limit:
            return length
    raise AssertionError(f"no such zone length near {start!r} m for node {node} of "
                         f"{n_elements}")
