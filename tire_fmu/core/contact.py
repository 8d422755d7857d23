"""Tread-road contact: the contact zone and its contact points, the unilateral law, the
static footprint, the road under each point, and the paper's prescribed patch. The one home
of everything contact.

**Zone and contact points.** The carrying nodes are the tread nodes around the contact
centre (node 0, θ = 0) whose unloaded ray meets the road within ``zone_length_m / 2``. The
zone is fixed in the ground frame (so it does not move with spin) and is wider than any
footprint the model is asked to carry, so that a cleat is met before it reaches the
footprint. The road meets the tread not at the nodes but at contact points, m per node arc
(m the smallest odd number that puts them at most ``point_spacing_m`` apart), at the centres
of the arc's m equal sub-arcs. A point reads the tread's radial displacement by cubic
Lagrange interpolation of the four nearest nodes, w_p = (I w)_p, and gives its force back to
those nodes as Iᵀ f: the virtual work of the interpolation, so that the springs on the ring
are Iᵀ diag(k) I, symmetric, and a rigid motion of the tread loads it as before. The zone
nodes are the carrying nodes and, for m > 1, the two beyond each end the stencils reach. With
m = 1 each point is its node (I = identity): the node model.

**Law.** Point p meets the road through a radial spring k_p = k_cw·R·δθ/m (the tread rubber's
radial stiffness k_cw per metre of circumference, over the point's arc) and a damper
c_p = β·k_p that can only push: with its penetration p_p (along its ray, positive into the
road) and rate ṗ_p, the road pushes the tread inwards with

    f_p = max(0, k_p p_p + c_p ṗ_p)  while p_p > 0,   f_p = 0 otherwise.

**Gap.** The rim centre is at height H = R - δ + z_rim above the road datum (δ the static
rim deflection), the tread at point p sits on the point's ray at distance R + w_p from the
rim centre (w the rim-relative radial displacement), and the road under it is at height h_p.
Along the ray the road is (H - h_p)/cos θ_p away, so

    p_p = R + w_p - (H - h_p)/cos θ_p ,

which for a flat road is the brief's u_j <= (R - δ)/cos θ_j - R. Rim and road moving
together (z_rim = h_p) leave p_p, and with it every force, unchanged. The vertical force of
the points on the ring is Σ (I cos θ)_p f_p (``force_cos``): the vertical parts of the radial
node forces Iᵀ f.

**Static footprint.** For a given rim deflection the static contact forces solve the linear
complementarity problem f >= 0, f/k - p >= 0, f·(f/k - p) = 0 with p = -g(δ) - G_p f
(G_p = I G Iᵀ, G the ring's static compliance at the zone nodes). Its solution is piecewise
linear in δ, so it is traced exactly by active-set continuation from δ = 0: along each
segment the active set is fixed, and the next point to enter (its penetration reaches 0) or
to leave (its force reaches 0) ends the segment. The load for a deflection and the
deflection for a load are both read off that path, with the tangent stiffness of the segment.

**Footprint length**: the road length between the two places where the penetration, linearly
interpolated between the outermost active point and its inactive neighbour, crosses zero. It
is continuous in the load (a point entering adds length smoothly).

**Road under each point.** Each point stands for a sub-arc of tread whose ray projections
cover a window [x_lo, x_hi] of road; its road height is the average of the profile over that
window (the exact linear part of a Winkler foundation over the arc). ``road_z`` is the height
at the front of the zone; at speed V point p sees the window [x_lo, x_hi] of road that passed
the front (x_front - x)/V earlier. At V = 0 every point sees ``road_z`` at once (a shaker
plate). Why the points converge where the nodes did not: docs/theory.md §4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .discretisation import Grid
from .parameters import (
    DEFAULT_POINT_SPACING_M,
    Problem,
    point_spacing_range_problems,
    render,
)

#: Default length of road under the contact zone (m): wide enough for the largest credible
#: footprint and for a 40 mm cleat to be met before it reaches the footprint.
DEFAULT_ZONE_LENGTH_M = 0.6
#: Default largest distance between contact points along the tread (m): the operating
#: point's (parameters.DEFAULT_POINT_SPACING_M, which says what error it leaves over a cleat),
#: under the contact's own name.
DEFAULT_CONTACT_POINT_SPACING_M = DEFAULT_POINT_SPACING_M
#: The zone may reach at most this far around the ring (|θ| < 60°): beyond, the flat-road
#: ray geometry and the small-deflection ring stop being credible.
MAX_ZONE_HALF_ANGLE = math.pi / 3
#: Relative tolerance on events of the footprint continuation (deflections, in m, of the
#: order of the tire's size).
_EVENT_TOLERANCE = 1e-12
#: Events of the continuation within this relative distance of the first happen together.
EVENTS_TOGETHER = 1e-9
#: Nodes whose unloaded ray is this close to vertical (|cos θ - 1|) touch the road at δ = 0.
TOUCH_ATOL = 1e-14
#: Relative slack on the zone's half angle, so a node exactly at it belongs to the zone.
ZONE_ANGLE_SLACK = 1e-12
#: Segments the footprint continuation may trace: this many per zone node, plus as many more.
SEGMENTS_PER_NODE = 8
#: The static path is traced up to this fraction of R of rim deflection.
MAX_DEFLECTION_FRACTION = 0.5
#: Bisections for the deflection at which the footprint reaches its longest credible length.
LENGTH_BISECTIONS = 60
#: Relative slack on the contact point spacing, so a node arc of exactly m spacings makes m
#: points per node.
POINT_SPACING_SLACK = 1e-9
#: The most contact points a zone may have: the contact solve runs in node space (O(P) a
#: product, step_limits.substep_work counts it so), but its active-set iteration may take up
#: to two passes a point.
MAX_CONTACT_POINTS = 4000
#: How a spacing that makes too many points is refused (printf, so that the native FMU says
#: the same): the smallest spacing allowed; then the points per node, the carrying nodes, the
#: points and the limit.
#: points_per_node counts at most this many (an int in C): far beyond any spacing in range
_MOST_PER_NODE = 100_000_000
POINTS_ALLOWED = "at least %.4g m with this mesh and contact zone"
POINTS_REASON = ("%d points on each of its %d carrying nodes make %d contact points, more than "
                 "the %d the contact solve takes")


# -- the zone ---------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class ContactZone:
    """The tread that may meet the road: its contact points and the ring nodes they read.

    ``nodes``/``theta`` are the zone nodes (front, θ < 0, to rear); the points, front to rear,
    read the ring at ``point_support`` (zone positions) with ``point_weight`` and load those
    nodes with the same weights (module doc). One point per node (``points_per_node = 1``) is
    the node model: point p is zone node p.
    """

    grid: Grid
    nodes: np.ndarray  # tread node indices of the zone nodes
    theta: np.ndarray  # their angles from the contact centre (rad), ascending
    points_per_node: int  # m, odd
    point_theta: np.ndarray  # ray angle of each contact point (rad), ascending
    point_support: np.ndarray  # (P, S) zone positions each point reads
    point_weight: np.ndarray  # (P, S) cubic Lagrange weights (1 for the node model)
    stiffness_n_per_m: np.ndarray  # k_p = k_cw·R·δθ/m per point
    damping_n_s_per_m: np.ndarray  # c_p = β·k_p
    length_m: float  # road length the zone covers when unloaded
    point_spacing_m: float  # the spacing asked for (the points are at most this far apart)

    @property
    def n_nodes(self) -> int:
        return self.nodes.size

    @property
    def n_points(self) -> int:
        return self.point_theta.size

    @property
    def point_arc_m(self) -> float:
        """Tread arc each contact point stands for (m)."""
        return self.grid.node_arc_m / self.points_per_node

    @cached_property
    def interpolation(self) -> np.ndarray:
        """I (P x Z): point p's radial displacement is (I w)_p; node forces are Iᵀ f."""
        out = np.zeros((self.n_points, self.n_nodes))
        rows = np.repeat(np.arange(self.n_points), self.point_support.shape[1])
        np.add.at(out, (rows, self.point_support.ravel()), self.point_weight.ravel())
        return out

    @property
    def point_cos(self) -> np.ndarray:
        """cos of each point's ray: its gap to the road is measured along that ray."""
        return np.cos(self.point_theta)

    @property
    def point_sec(self) -> np.ndarray:
        return 1.0 / np.cos(self.point_theta)

    @cached_property
    def force_cos(self) -> np.ndarray:
        """Vertical force on the ring per unit push of each point: its push reaches the nodes
        as radial forces Iᵀ f, whose vertical parts sum to (I cos θ)_p per newton."""
        return self.interpolation @ np.cos(self.theta)

    @cached_property
    def force_sin(self) -> np.ndarray:
        """The same for the horizontal (x) part: (I sin θ)_p."""
        return self.interpolation @ np.sin(self.theta)

    @property
    def centre(self) -> int:
        """Position of node 0 (the contact centre) among the zone nodes."""
        return int(np.flatnonzero(self.nodes == 0)[0])

    @property
    def centre_point(self) -> int:
        """The contact point at the contact centre (θ = 0; m is odd, so there is one)."""
        return int(np.argmin(np.abs(self.point_theta)))

    def unloaded_gap_m(self, deflection_m: float) -> np.ndarray:
        """Gap along each point's ray between the undeformed tread and a flat road, rim
        lowered by δ."""
        radius = self.grid.radius_m
        return (radius - deflection_m) / self.point_cos - radius

    def road_positions_m(self, deflection_m: float) -> np.ndarray:
        """Where each point's ray meets the road, x forward from the contact centre (m)."""
        return -(self.grid.radius_m - deflection_m) * np.tan(self.point_theta)

    def road_windows_m(self, deflection_m: float) -> tuple[np.ndarray, np.ndarray]:
        """(x_lo, x_hi): the road each point's arc [θ_p - δθ/2m, θ_p + δθ/2m] covers."""
        height = self.grid.radius_m - deflection_m
        half = 0.5 * self.grid.dtheta / self.points_per_node
        return (-height * np.tan(self.point_theta + half),
                -height * np.tan(self.point_theta - half))


def carrying_half_count(grid: Grid, zone_length_m: float) -> int:
    """h: the carrying nodes are j = -h..h, those whose angle |j|·δθ is at most the zone's
    half angle (1 + ZONE_ANGLE_SLACK). The one count of the zone, its point limit and the
    native FMU's contact.c (zone_half_count, the same lines): floor(limit/δθ) alone can round
    to a node whose own angle j·δθ lies just beyond the limit, and a node must belong to the
    zone by its angle, the number each runtime computes for it."""
    half_angle = min(math.atan(0.5 * zone_length_m / grid.radius_m), MAX_ZONE_HALF_ANGLE)
    limit = half_angle * (1 + ZONE_ANGLE_SLACK)
    dtheta = grid.dtheta
    half = int(math.floor(limit / dtheta))
    while half > 0 and half * dtheta > limit:
        half -= 1
    while (half + 1) * dtheta <= limit and 2 * (half + 1) <= grid.n_elements:
        half += 1
    return half


def lagrange_weights(s: np.ndarray) -> np.ndarray:
    """Cubic Lagrange weights (.., 4) on nodes -1, 0, 1, 2 for a point at s in [0, 1)."""
    s = np.asarray(s, dtype=float)[..., None]
    return np.concatenate([-s * (s - 1) * (s - 2) / 6, (s + 1) * (s - 1) * (s - 2) / 2,
                           -(s + 1) * s * (s - 2) / 2, (s + 1) * s * (s - 1) / 6], axis=-1)


def contact_zone(grid: Grid, k_cw: float, beta: float,
                 zone_length_m: float = DEFAULT_ZONE_LENGTH_M,
                 point_spacing_m: float = DEFAULT_CONTACT_POINT_SPACING_M) -> ContactZone:
    """The contact points of the nodes whose unloaded ray meets the road within
    ``zone_length_m / 2``, at most ``point_spacing_m`` apart.

    Each such carrying node's arc holds m points at the centres of its m equal sub-arcs, read
    on the tread by cubic Lagrange interpolation of the four nearest nodes: the interpolant
    of the ring's second-order finite differences, so the tread between nodes is resolved to
    the mesh's own order, and it reproduces a rigid motion of the tread exactly. The zone
    nodes are the carrying nodes and, for m > 1, the two beyond each end the stencils reach.
    """
    half = carrying_half_count(grid, zone_length_m)
    m = points_per_node(grid.node_arc_m, point_spacing_m)
    reach = 0 if m == 1 else 2
    offsets = np.arange(-half - reach, half + reach + 1)
    nodes = np.mod(offsets, grid.n_elements)
    theta = grid.theta[nodes].copy()
    # point u/m node spacings from the centre, u = j m + i - (m - 1)/2 (integers: exact mirror)
    u = (np.arange(-half, half + 1)[:, None] * m + np.arange(m)[None, :] - (m - 1) // 2).ravel()
    if m == 1:
        support = (u + half)[:, None]
        weight = np.ones((u.size, 1))
        point_theta = theta.copy()
    else:
        base = np.floor_divide(u, m)
        support = base[:, None] + np.arange(-1, 3)[None, :] + half + reach
        weight = lagrange_weights((u - base * m) / m)
        point_theta = u * (grid.dtheta / m)
    stiffness = np.full(u.size, k_cw * grid.node_arc_m / m)
    return ContactZone(grid=grid, nodes=nodes, theta=theta, points_per_node=m,
                       point_theta=point_theta, point_support=support.astype(np.intp),
                       point_weight=weight, stiffness_n_per_m=stiffness,
                       damping_n_s_per_m=beta * stiffness, length_m=float(zone_length_m),
                       point_spacing_m=float(point_spacing_m))


def zone_problems(grid: Grid, zone_length_m,
                  point_spacing_m=DEFAULT_CONTACT_POINT_SPACING_M) -> list[Problem]:
    """Why a zone length and point spacing cannot make a usable zone on this mesh (empty when
    they can)."""
    try:
        length = float(zone_length_m)
    except (TypeError, ValueError):
        length = math.nan
    limit = 2 * grid.radius_m * math.tan(MAX_ZONE_HALF_ANGLE)
    problems = point_spacing_range_problems(point_spacing_m)
    if not (math.isfinite(length) and 0 < length <= limit):
        return problems + [Problem(
            "contact_zone_length_m", zone_length_m, "m", f"in (0, {limit:.4g}] m",
            "at most 60 degrees of the ring either side of the contact centre")]
    half_angle = math.atan(0.5 * length / grid.radius_m)
    if half_angle < grid.dtheta:
        need = 2 * grid.radius_m * math.tan(grid.dtheta)
        return problems + [Problem(
            "contact_zone_length_m", length, "m",
            f"at least {need:.4g} m (one node either side), or refine the mesh",
            f"it holds only the centre node of a mesh of {grid.n_elements} elements")]
    return problems or point_count_problems(grid, length, point_spacing_m)


def point_count_problems(grid: Grid, zone_length_m: float, point_spacing_m) -> list[Problem]:
    """Whether a spacing is in range and its zone's contact points stay within
    MAX_CONTACT_POINTS (the native FMU says the same: spec.POINTS_ALLOWED/REASON)."""
    return (point_spacing_range_problems(point_spacing_m)
            or point_spacing_problems(grid, float(zone_length_m), float(point_spacing_m)))


def points_per_node(node_arc_m: float, spacing_m: float) -> int:
    """The smallest odd m with node_arc / m <= spacing (1 + POINT_SPACING_SLACK); odd, so
    that a point sits on every node, the contact centre's among them (the native FMU's
    contact.c counts alike)."""
    limit = spacing_m * (1 + POINT_SPACING_SLACK)
    guess = math.ceil(node_arc_m / limit)
    if not guess <= _MOST_PER_NODE:
        return _MOST_PER_NODE + 1  # (no spacing in range comes near) refused as too many
    m = max(1, int(guess))
    if m % 2 == 0:
        m += 1
    while m > 1 and node_arc_m / (m - 2) <= limit:
        m -= 2
    while node_arc_m / m > limit:
        m += 2
    return m


def _round_up(value: float, digits: int = 4) -> float:
    """``value`` rounded up to ``digits`` significant digits (a bound that, as printed, holds)."""
    step = 10.0 ** (math.floor(math.log10(value)) - digits + 1)
    return math.ceil(value / step) * step


def point_spacing_problems(grid: Grid, zone_length_m: float, spacing_m: float) -> list[Problem]:
    """Why a contact point spacing (in range: parameters.point_spacing_range_problems) makes
    more points than MAX_CONTACT_POINTS on this mesh and zone (empty when it does not)."""
    carrying = 2 * carrying_half_count(grid, zone_length_m) + 1
    m = points_per_node(grid.node_arc_m, spacing_m)
    if carrying * m <= MAX_CONTACT_POINTS:
        return []
    most = max(1, MAX_CONTACT_POINTS // carrying)
    most -= 1 - most % 2  # odd
    smallest = _round_up(grid.node_arc_m / max(most, 1))
    return [Problem("contact_point_spacing_m", float(spacing_m), "m", POINTS_ALLOWED % smallest,
                    POINTS_REASON % (m, carrying, carrying * m, MAX_CONTACT_POINTS))]


# -- the law ----------------------------------------------------------------------------------

def contact_force(penetration_m, rate_m_s, stiffness_n_per_m, damping_n_s_per_m) -> np.ndarray:
    """The unilateral law: f = max(0, k p + c ṗ) where p > 0, else 0 (newtons, pushing)."""
    p = np.asarray(penetration_m, dtype=float)
    push = stiffness_n_per_m * p + damping_n_s_per_m * np.asarray(rate_m_s, dtype=float)
    return np.where(p > 0.0, np.maximum(push, 0.0), 0.0)


# -- static footprint -------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Footprint:
    """The static contact of the ring on a flat road, computed by the model itself.

    Arrays are per contact point (front to rear). ``forces_n`` push the tread inwards;
    ``penetration_m`` is positive into the road (and equals f/k where the point pushes).
    """

    zone: ContactZone
    deflection_m: float  # rim lowered from its unloaded height (road at 0)
    load_n: float  # vertical force of the road on the tire = of the tire on the rim
    forces_n: np.ndarray
    penetration_m: np.ndarray
    active: np.ndarray  # bool: points that push
    tangent_stiffness_n_per_m: float  # dW/dδ on the current segment of the path
    length_m: float  # road length between the interpolated edges
    front_edge_m: float  # x of the front edge (forward positive)
    rear_edge_m: float

    @property
    def in_contact(self) -> bool:
        return bool(self.active.any())

    @property
    def secant_stiffness_n_per_m(self) -> float:
        return self.load_n / self.deflection_m if self.deflection_m > 0 else math.nan

    @property
    def line_pressure_n_per_m(self) -> np.ndarray:
        """Contact force per metre of tread circumference at each contact point."""
        return self.forces_n / self.zone.point_arc_m

    @property
    def longitudinal_force_n(self) -> float:
        """x-component of the road's force on the tire (zero at rest, by symmetry)."""
        return float(self.zone.force_sin @ self.forces_n)

    @property
    def n_active(self) -> int:
        return int(self.active.sum())

    @property
    def tread_displacement_m(self) -> np.ndarray:
        """Rim-relative radial displacement of the tread at each point (p = w - g, g the
        gap)."""
        return self.penetration_m + self.zone.unloaded_gap_m(self.deflection_m)

    def touches_zone_edge(self) -> bool:
        """True when a zone end point pushes: the footprint may extend beyond the zone."""
        return bool(self.active[0] or self.active[-1])

    def to_dict(self) -> dict:
        return {
            "load_n": self.load_n,
            "deflection_m": self.deflection_m,
            "footprint_length_m": self.length_m,
            "front_edge_m": self.front_edge_m,
            "rear_edge_m": self.rear_edge_m,
            "secant_stiffness_n_per_m": self.secant_stiffness_n_per_m,
            "tangent_stiffness_n_per_m": self.tangent_stiffness_n_per_m,
            "contact_points": self.n_active,
            "zone_points": self.zone.n_points,
            "zone_nodes": self.zone.n_nodes,
            "points_per_node": self.zone.points_per_node,
            "contact_point_spacing_m": self.zone.point_arc_m,
            "longitudinal_force_n": self.longitudinal_force_n,
            "theta_rad": self.zone.point_theta.tolist(),
            "line_pressure_n_per_m": self.line_pressure_n_per_m.tolist(),
            "penetration_m": self.penetration_m.tolist(),
        }


class FootprintError(ValueError):
    """A static contact state the model cannot reach (load beyond the credible range);
    ``problem`` says which input to change, and to what."""

    def __init__(self, message: str, problem: Problem | None = None):
        super().__init__(message)
        self.problem = problem or Problem("load_n", math.nan, "N", "a load the model reaches",
                                          message)


@dataclass(frozen=True, eq=False)
class _Segment:
    """A piece of the continuation path: f_A, load and penetrations affine in δ."""

    start_m: float
    active: np.ndarray
    forces_at: tuple[np.ndarray, np.ndarray]  # f = f0 + f1 δ (zeros off the active set)
    penetration_at: tuple[np.ndarray, np.ndarray]  # p = p0 + p1 δ
    load_at: tuple[float, float]  # W = W0 + W1 δ


class _ActiveInverse:
    """(diag(1/k) + G)⁻¹ on the active points, followed as points enter and leave: one point
    changes a segment of the path into the next, and bordering the inverse by it (or taking
    it out, by its Schur complement) costs m² where a new solve costs m³. The path of a
    fine zone has a hundred segments, which made the trace most of a Python FMU's start.
    Rebuilt outright when many points change at once, and every REFRESH updates, so that
    rounding does not accumulate."""

    REFRESH = 64

    def __init__(self, compliance: np.ndarray, flexibility: np.ndarray):
        self.g, self.flexibility = compliance, flexibility
        self.index = np.zeros(0, dtype=int)
        self.matrix = np.zeros((0, 0))
        self.updates = 0

    def _rebuild(self, index: np.ndarray) -> None:
        self.index = index
        self.matrix = np.linalg.inv(np.diag(self.flexibility[index])
                                    + self.g[np.ix_(index, index)])
        self.updates = 0

    def follow(self, active: np.ndarray) -> None:
        """Make this the inverse on ``active``."""
        wanted = np.flatnonzero(active)
        now = set(self.index.tolist())
        leaving = [i for i in self.index.tolist() if not active[i]]
        entering = [int(i) for i in wanted if int(i) not in now]
        if not leaving and not entering:
            return
        if (self.index.size == 0 or len(leaving) + len(entering) > 4
                or self.updates + len(leaving) + len(entering) > self.REFRESH):
            self._rebuild(wanted)
            return
        for point in leaving:
            self._remove(int(np.flatnonzero(self.index == point)[0]))
        for point in entering:
            self._add(point)
        self.updates += len(leaving) + len(entering)

    def _remove(self, k: int) -> None:
        b = self.matrix
        keep = np.arange(b.shape[0]) != k
        self.matrix = b[np.ix_(keep, keep)] - np.outer(b[keep, k], b[k, keep]) / b[k, k]
        self.index = self.index[keep]

    def _add(self, point: int) -> None:
        b, index, g = self.matrix, self.index, self.g
        u, v = g[index, point], g[point, index]
        bu, vb = b @ u, v @ b
        schur = self.flexibility[point] + g[point, point] - v @ bu
        m = b.shape[0]
        out = np.empty((m + 1, m + 1))
        out[:m, :m] = b + np.outer(bu, vb) / schur
        out[:m, m], out[m, :m], out[m, m] = -bu / schur, -vb / schur, 1.0 / schur
        self.matrix, self.index = out, np.append(index, point)


class FootprintPath:
    """The static contact forces as a function of the rim deflection, traced exactly.

    ``compliance`` is G_p = I G Iᵀ (points x points, m/N): the rim-relative radial
    displacement of the tread at point i per newton pushed outwards at point j, at the
    operating speed (:func:`point_compliance`).
    """

    def __init__(self, zone: ContactZone, compliance: np.ndarray, max_deflection_m: float):
        self.zone = zone
        self.compliance = np.asarray(compliance, dtype=float)
        self.max_deflection_m = float(max_deflection_m)
        self.segments = self._trace()

    def _segment(self, start: float, active: np.ndarray,
                 inverse: _ActiveInverse | None = None) -> _Segment:
        # p = -g(δ) - G f with g = (R - δ)/cos - R: -g = R - R/cos + δ/cos
        zone, g = self.zone, self.compliance
        radius, sec = zone.grid.radius_m, zone.point_sec
        p0, p1 = radius - radius * sec, sec
        f0, f1 = np.zeros(zone.n_points), np.zeros(zone.n_points)
        if active.any():
            # f_A = k_A p_A  =>  (diag(1/k_A) + G_AA) f_A = p0_A + p1_A δ
            if inverse is None:
                system = (np.diag(1.0 / zone.stiffness_n_per_m[active])
                          + g[np.ix_(active, active)])
                solved = np.linalg.solve(system, np.column_stack([p0[active], p1[active]]))
                f0[active], f1[active] = solved[:, 0], solved[:, 1]
            else:
                index = inverse.index
                solved = inverse.matrix @ np.column_stack([p0[index], p1[index]])
                f0[index], f1[index] = solved[:, 0], solved[:, 1]
        pen0, pen1 = p0 - g @ f0, p1 - g @ f1
        cos = zone.force_cos
        return _Segment(start, active.copy(), (f0, f1), (pen0, pen1),
                        (float(cos @ f0), float(cos @ f1)))

    def _trace(self) -> list[_Segment]:
        zone = self.zone
        radius = zone.grid.radius_m
        # at δ = 0 the undeformed ring touches the road only where cos θ = 1 (the centre)
        active = np.zeros(zone.n_points, dtype=bool)
        start = 0.0
        segments = []
        inverse = _ActiveInverse(self.compliance, 1.0 / zone.stiffness_n_per_m)
        for _ in range(SEGMENTS_PER_NODE * (zone.n_points + 1)):
            if not active.any():
                # the touching point(s) enter as soon as δ > 0
                active = np.isclose(zone.point_cos, 1.0, rtol=0.0, atol=TOUCH_ATOL)
            inverse.follow(active)
            segment = self._segment(start, active, inverse)
            segments.append(segment)
            (f0, f1), (p0, p1) = segment.forces_at, segment.penetration_at
            # leaving: an active force falls to 0; entering: an inactive penetration rises to 0
            with np.errstate(divide="ignore", invalid="ignore"):
                leave = np.where(active & (f1 < 0), -f0 / f1, np.inf)
                enter = np.where(~active & (p1 > 0), -p0 / p1, np.inf)
            events = np.minimum(leave, enter)
            events[events <= start * (1 + _EVENT_TOLERANCE) + _EVENT_TOLERANCE * radius] = np.inf
            nxt = float(events.min())
            if not math.isfinite(nxt) or nxt >= self.max_deflection_m:
                return segments
            # every event within rounding of the first happens together
            together = events <= nxt * (1 + EVENTS_TOGETHER) + _EVENT_TOLERANCE * radius
            active = active.copy()
            active[together & (leave <= enter)] = False
            active[together & (enter < leave)] = True
            start = nxt
        raise FootprintError("the footprint continuation did not terminate (a degenerate "
                             "contact path); report the tire data")

    def _segment_for_deflection(self, deflection_m: float) -> _Segment:
        starts = [s.start_m for s in self.segments]
        return self.segments[max(0, int(np.searchsorted(starts, deflection_m, "right")) - 1)]

    def at_deflection(self, deflection_m: float) -> Footprint:
        d = float(deflection_m)
        s = self._segment_for_deflection(d)
        forces = s.forces_at[0] + s.forces_at[1] * d
        penetration = s.penetration_at[0] + s.penetration_at[1] * d
        load = s.load_at[0] + s.load_at[1] * d
        active = s.active.copy() if d > 0 else np.zeros_like(s.active)
        forces = np.where(active, forces, 0.0)
        return self._footprint(d, load if d > 0 else 0.0, forces, penetration, active,
                               s.load_at[1])

    def at_load(self, load_n: float) -> Footprint:
        """The static state carrying ``load_n``: the load grows with δ along the path, and is
        affine on each segment, so the deflection follows exactly."""
        w = float(load_n)
        if w <= 0.0:
            return self.at_deflection(0.0)
        ends = [s.start_m for s in self.segments[1:]] + [self.max_deflection_m]
        for segment, end in zip(self.segments, ends):
            w0, w1 = segment.load_at
            if w1 > 0 and w0 + w1 * end >= w:
                return self.at_deflection(max((w - w0) / w1, segment.start_m))
        raise FootprintError(f"load {w:g} N needs a rim deflection beyond "
                             f"{self.max_deflection_m:g} m")

    def _footprint(self, deflection, load, forces, penetration, active, tangent) -> Footprint:
        zone = self.zone
        x = zone.road_positions_m(deflection)
        front, rear = _edges(x, penetration, active)
        return Footprint(zone=zone, deflection_m=float(deflection), load_n=float(load),
                         forces_n=forces, penetration_m=penetration, active=active,
                         tangent_stiffness_n_per_m=float(tangent),
                         length_m=float(front - rear), front_edge_m=float(front),
                         rear_edge_m=float(rear))


def _edges(x: np.ndarray, penetration: np.ndarray, active: np.ndarray) -> tuple[float, float]:
    """Front and rear edge (road x) where the penetration, interpolated linearly between the
    outermost active node and its inactive neighbour, crosses zero."""
    idx = np.flatnonzero(active)
    if not idx.size:
        return 0.0, 0.0

    def crossing(inner: int, outer: int) -> float:
        if outer < 0 or outer >= x.size:
            return float(x[inner])
        p_in, p_out = penetration[inner], penetration[outer]
        # between the two nodes; a neighbour that penetrates without pushing (separating
        # faster than its spring pushes) puts the edge at the neighbour, and a node that
        # pushes from above the road (the linear law's two-sided spring and damper) at itself:
        # the footprint is never shorter than its pushing nodes' span
        share = min(p_in / (p_in - p_out), 1.0) if p_in > max(p_out, 0.0) else 0.0
        return float(x[inner] + share * (x[outer] - x[inner]))

    front = crossing(idx[0], idx[0] - 1)  # x decreases along the zone (front first)
    rear = crossing(idx[-1], idx[-1] + 1)
    return front, rear


# -- the road under each point -----------------------------------------------------------------

@dataclass(frozen=True)
class RoadWindows:
    """For each contact point, the delays (s) after which the ends of its road window have travelled
    from the zone front to under it: it sees the road that passed the front between
    ``late_s`` and ``early_s`` ago, averaged. All zero at V = 0 (a shaker plate)."""

    early_s: np.ndarray  # the window's front end (the road reached it last)
    late_s: np.ndarray  # the window's rear end
    front_m: float  # x of the zone front, where road_z is measured

    @property
    def horizon_s(self) -> float:
        return float(self.late_s.max()) if self.late_s.size else 0.0

    def frequency_response(self, omega) -> np.ndarray:
        """(points, freqs): the road under each point per unit harmonic road height at the front:
        the window average of a delayed harmonic, e^{-iωτ_mid}·sin(ωΔ/2)/(ωΔ/2)."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))[None, :]
        mid = 0.5 * (self.early_s + self.late_s)[:, None]
        half = 0.5 * (self.late_s - self.early_s)[:, None]
        return np.exp(-1j * omega * mid) * np.sinc(omega * half / np.pi)


def road_windows(zone: ContactZone, deflection_m: float, speed_m_s: float) -> RoadWindows:
    x_lo, x_hi = zone.road_windows_m(deflection_m)
    front = float(x_hi.max()) if x_hi.size else 0.0
    if speed_m_s <= 0.0:
        zeros = np.zeros(zone.n_points)
        return RoadWindows(zeros, zeros.copy(), front)
    return RoadWindows((front - x_hi) / speed_m_s, (front - x_lo) / speed_m_s, front)


# -- the paper's prescribed patch ---------------------------------------------------------------

def patch_weights(zone: ContactZone, patch_length_m: float) -> np.ndarray:
    """Fraction of each contact point's arc inside a prescribed patch |θ| <= L/(2R) (0..1).

    The paper's patch (Figs. 17-19) is an input, not a contact solution: each point carries
    k_p times this fraction, so frequencies vary continuously with L.
    """
    half_angle = 0.5 * patch_length_m / zone.grid.radius_m
    arc = zone.grid.dtheta / zone.points_per_node
    distance = np.abs(zone.point_theta)  # |θ| makes the weights exactly mirror-symmetric
    overlap = np.minimum(distance + 0.5 * arc, half_angle) - np.maximum(distance - 0.5 * arc,
                                                                          -half_angle)
    return np.clip(overlap / arc, 0.0, 1.0)


def deflection_from_patch_length(radius_m: float, patch_length_m: float) -> float:
    """Flat-road chord: a prescribed patch of length L on a circle of radius R sits δ below
    its centre (only for the paper's prescribed patch; a computed footprint has its own δ)."""
    half = 0.5 * patch_length_m
    return radius_m - math.sqrt(max(radius_m**2 - half**2, 0.0))


# -- the state a linear model is built about ---------------------------------------------------

@dataclass(frozen=True, eq=False)
class ContactPatch:
    """The static contact a tire model is linearised at: the footprint the model computes for
    a load, or the paper's prescribed patch (an explicit mode, for its Figs. 17-19).

    ``weights`` (per contact point) scale each point's road spring in the linearisation: 1 on
    the footprint's pushing points and 0 elsewhere, or the fraction of the point's arc inside
    a prescribed patch. Every spring acts through the gap of the module docstring, with its
    rate damped by c_p, and the road reaches each point through ``road``.
    """

    zone: ContactZone
    weights: np.ndarray
    deflection_m: float
    load_n: float
    length_m: float
    vertical_stiffness_n_per_m: float  # tangent: rim force per rim travel, road held
    road: RoadWindows
    forces_n: np.ndarray  # static push of the road at each contact point
    centre_compression_m: float  # -w at the contact centre: the static "deflection" output
    footprint: Footprint | None = None  # None for a prescribed patch

    @property
    def prescribed(self) -> bool:
        return self.footprint is None

    @property
    def in_contact(self) -> bool:
        return bool(np.any(self.weights > 0))

    @property
    def contact_points(self) -> np.ndarray:
        """Indices of the contact points with a spring in the linearisation."""
        return np.flatnonzero(self.weights > 0)

    @property
    def node_indices(self) -> np.ndarray:
        """Tread node indices the linearisation's springs load."""
        reached = np.any(self.zone.interpolation[self.contact_points] != 0.0, axis=0)
        return self.zone.nodes[reached]

    @property
    def point_stiffness_n_per_m(self) -> np.ndarray:
        return self.weights * self.zone.stiffness_n_per_m

    @property
    def point_damping_n_s_per_m(self) -> np.ndarray:
        return self.weights * self.zone.damping_n_s_per_m

    def node_stiffness_matrix(self) -> np.ndarray:
        """Iᵀ diag(k_p w_p) I (zone nodes x zone nodes, N/m): the springs on the ring."""
        interp = self.zone.interpolation
        return interp.T @ (self.point_stiffness_n_per_m[:, None] * interp)

    def static_outputs(self) -> dict[str, float]:
        """The FMU outputs at this static state (road on tire = tire on rim in statics)."""
        vertical = float(self.zone.force_cos @ self.forces_n)
        return {"rim_Fz": vertical,
                "rim_Fx": float(self.zone.force_sin @ self.forces_n),
                "contact_Fz": vertical,
                "deflection": self.centre_compression_m}

    def to_dict(self) -> dict:
        out = {
            "contact": "prescribed patch" if self.prescribed else "computed footprint",
            "patch_length_m": self.length_m,
            "deflection_m": self.deflection_m,
            "load_n": self.load_n,
            "vertical_stiffness_n_per_m": self.vertical_stiffness_n_per_m,
            "patch_points": int(self.contact_points.size),
            "points_per_node": self.zone.points_per_node,
            "contact_point_spacing_m": self.zone.point_spacing_m,
            "contact_zone_length_m": self.zone.length_m,
        }
        if self.footprint is not None:
            out["secant_stiffness_n_per_m"] = self.footprint.secant_stiffness_n_per_m
        return out


def point_compliance(zone: ContactZone, node_compliance: np.ndarray) -> np.ndarray:
    """G_p = I G Iᵀ (points x points, m/N) from the zone nodes' compliance G."""
    interp = zone.interpolation
    if zone.points_per_node == 1:
        return np.asarray(node_compliance, dtype=float)[np.ix_(zone.point_support[:, 0],
                                                               zone.point_support[:, 0])]
    return interp @ node_compliance @ interp.T


def linear_vertical_stiffness(zone: ContactZone, compliance: np.ndarray,
                              point_stiffness: np.ndarray) -> float:
    """dW/dδ with the springs ``point_stiffness`` held (road fixed, rim pushed down):
    W = (I cos θ)ᵀ f, (diag(1/k) + G_p) f = δ sec θ_p on the springs' points."""
    on = point_stiffness > 0
    if not on.any():
        return 0.0
    system = np.diag(1.0 / point_stiffness[on]) + compliance[np.ix_(on, on)]
    return float(zone.force_cos[on] @ np.linalg.solve(system, zone.point_sec[on]))


def centre_compression_m(zone: ContactZone, node_compliance: np.ndarray,
                         forces_n: np.ndarray) -> float:
    """-w at the contact centre node under the point forces: (G Iᵀ f) at node 0."""
    return float(node_compliance[zone.centre] @ (zone.interpolation.T @ forces_n))


def computed_patch(zone: ContactZone, compliance: np.ndarray, load_n: float,
                   speed_m_s: float, max_length_m: float) -> ContactPatch:
    """The footprint that carries ``load_n`` (``compliance``: the zone nodes' G);
    FootprintError (with the allowed range) when the footprint would leave the zone or exceed
    ``max_length_m``."""
    path = FootprintPath(zone, point_compliance(zone, compliance),
                         max_deflection_m=MAX_DEFLECTION_FRACTION * zone.grid.radius_m)
    limit = max_credible_load(path, max_length_m)
    if load_n > limit.load_n:
        reason = ("its footprint reaches the end of the contact zone (raise "
                  "contact_zone_length_m)" if limit.touches_zone_edge() else
                  f"its footprint reaches {max_length_m:.4g} m, beyond which the linear ring "
                  "is not credible")
        problem = Problem("load_n", load_n, "N",
                          f"in [0, {limit.load_n:.6g}] N for this tire and mesh; at "
                          f"{limit.load_n:.6g} N (deflection {limit.deflection_m * 1e3:.3g} mm) "
                          + reason)
        raise FootprintError(render(problem), problem)
    return _footprint_patch(zone, compliance, path.at_load(load_n), speed_m_s)


def computed_patch_at_deflection(zone: ContactZone, compliance: np.ndarray,
                                 deflection_m: float, speed_m_s: float) -> ContactPatch:
    """The inverse: the footprint (and its load) for a rim deflection."""
    path = FootprintPath(zone, point_compliance(zone, compliance),
                         max_deflection_m=max(0.5 * zone.grid.radius_m, 2 * deflection_m))
    return _footprint_patch(zone, compliance, path.at_deflection(deflection_m), speed_m_s)


def _footprint_patch(zone, compliance, footprint: Footprint, speed_m_s) -> ContactPatch:
    return ContactPatch(
        zone=zone, weights=footprint.active.astype(float), deflection_m=footprint.deflection_m,
        load_n=footprint.load_n, length_m=footprint.length_m,
        vertical_stiffness_n_per_m=footprint.tangent_stiffness_n_per_m,
        road=road_windows(zone, footprint.deflection_m, speed_m_s),
        forces_n=footprint.forces_n,
        centre_compression_m=centre_compression_m(zone, compliance, footprint.forces_n),
        footprint=footprint)


def max_credible_load(path: FootprintPath, max_length_m: float) -> Footprint:
    """The static state at the largest load the model is credible for: the footprint stays
    inside the zone (an inactive node at each end) and no longer than ``max_length_m``."""
    segments = path.segments
    for index, segment in enumerate(segments):
        start = segment.start_m
        end = (segments[index + 1].start_m if index + 1 < len(segments)
               else path.max_deflection_m)
        if segment.active[0] or segment.active[-1]:
            return path.at_deflection(start)  # a zone end node enters here, with no force yet
        if path.at_deflection(end * (1 - _EVENT_TOLERANCE)).length_m > max_length_m:
            low, high = start, end
            for _ in range(LENGTH_BISECTIONS):  # the length grows continuously along a segment
                middle = 0.5 * (low + high)
                if path.at_deflection(middle).length_m > max_length_m:
                    high = middle
                else:
                    low = middle
            return path.at_deflection(low)
    return path.at_deflection(path.max_deflection_m)


def prescribed_patch(zone: ContactZone, compliance: np.ndarray, patch_length_m: float,
                     speed_m_s: float) -> ContactPatch:
    """The paper's patch |θ| <= L/(2R): fractional point weights, the flat-road chord as its
    deflection and, as the paper's rule, the load K_v·δ: the springs, two-sided and
    unstressed when the undeformed ring touches, carry it with the rim lowered by δ."""
    grid = zone.grid
    weights = patch_weights(zone, patch_length_m)
    deflection = deflection_from_patch_length(grid.radius_m, patch_length_m)
    springs = weights * zone.stiffness_n_per_m
    g_points = point_compliance(zone, compliance)
    k_v = linear_vertical_stiffness(zone, g_points, springs)
    # two-sided springs on the patch, rim lowered by δ: f = k (δ sec - G_p f)
    forces = np.zeros(zone.n_points)
    on = springs > 0
    if on.any():
        system = np.diag(1.0 / springs[on]) + g_points[np.ix_(on, on)]
        forces[on] = np.linalg.solve(system, deflection * zone.point_sec[on])
    return ContactPatch(zone=zone, weights=weights, deflection_m=deflection,
                        load_n=float(zone.force_cos @ forces), length_m=float(patch_length_m),
                        vertical_stiffness_n_per_m=k_v,
                        road=road_windows(zone, deflection, speed_m_s), forces_n=forces,
                        centre_compression_m=centre_compression_m(zone, compliance, forces))
