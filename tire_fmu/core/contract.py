"""The step contract: everything a time step of the tire reads, built once at initialisation.

The tire is built in two places, by this Python core (where new physics lands first) and by
the native FMU's C at its initialisation, and stepped by one kernel (``native/c/kernel.c``,
with :mod:`.kernel_numpy` as its readable reference). Between the builders and the kernels
stands this contract: the free ring's modes grouped by order, the rim's coupling, the ring's
direct terms, the contact points with their interpolation from the ring's nodes and their
laws, the static state, the road windows and the sub-step. Its layout is one table, the fields
of :class:`StepContract` with their kind and shape; the C struct ``TireContract``
(``native/c/contract.h``) and its ctypes mirror are generated from it, and
:data:`CONTRACT_VERSION` (a hash of the table) is checked wherever one side hands a contract
to the other. A test builds the same tire with both builders and compares the contracts field
by field, so a divergence names the array and the index.

Conventions (SI, θ from the contact centre in the direction of rotation, zone front first):

- Mode k belongs to order ``order_start[n] <= k < order_start[n + 1]``; its complex state q_k
  takes a force f pushing a tread node at θ inwards as q̇_k += beta_k e^{-inθ} f, and reads the
  node's rim-relative radial displacement and rate as Re(gamma_k e^{inθ} q_k) and
  Re(eta_k e^{inθ} q_k); the rim's vertical translation as q̇_k += b_rim_k z_rim, the rim
  forces (rim_Fz, rim_Fx) as Re(c_rim[:, k] q_k), the tread compression at the contact centre
  (deflection) as -Re(gamma_k q_k).
- The zone nodes are the ring nodes at offsets ``zone_offset`` (-half .. half) from the contact
  centre; ``d`` and ``e`` are the ring's direct terms on [rim_z, zone-node forces] (rows
  rim_Fz, rim_Fx, deflection, w and ẇ at each zone node), on the inputs and on their rates.
- Contact point p reads the ring at ``point_support[p, :]`` (zone indices) with
  ``point_weight[p, :]``, and gives its force back to those nodes with the same weights (the
  virtual work of the interpolation). Its penetration into the road along its ray, with the rim
  at z and the road at height r under it, is Σ w_support·weight - (z - r)·sec + pen_static
  - (the static rim and road, zero as deviations); its law is
  f = max(0, k p + c ṗ) while p > 0.
- The road under point p is the mean height over its window: by time, the road that passed
  the zone front between ``window_late_s`` and ``window_early_s`` ago (the road by time); by
  position, the road [x + window_lo_m, x + window_hi_m] with the wheel centre at x along it
  (the road by position, issue 37): the stretch its arc covers at the static deflection.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field, fields

import numpy as np

#: kinds of contract fields and their numpy dtypes
KINDS = {"int": np.dtype(np.int32), "float": np.dtype(np.float64),
         "complex": np.dtype(np.complex128)}


def _field(kind: str, shape: tuple[str, ...] = (), doc: str = ""):
    return field(metadata={"kind": kind, "shape": shape, "doc": doc})


@dataclass(frozen=True, eq=False)
class StepContract:
    """One tire at one operating point, as the step kernels read it (module doc)."""

    # sizes
    n_elements: int = _field("int", doc="nodes around the ring, N")
    n_orders: int = _field("int", doc="circumferential orders 0 .. N/2")
    n_modes: int = _field("int", doc="free-ring modes kept, K")
    n_zone: int = _field("int", doc="zone nodes: the ring nodes the contact points read, Z")
    n_points: int = _field("int", doc="contact points, P")
    n_support: int = _field("int", doc="zone nodes each contact point interpolates, S")
    n_ring_rows: int = _field("int", doc="rows of d and e: 3 + 2 Z")
    n_ring_cols: int = _field("int", doc="columns of d and e: 1 + Z")
    # scalars
    linear: int = _field("int", doc="1: two-sided springs on the static footprint's points")
    centre_point: int = _field("int", doc="the contact point at the contact centre")
    substep_work: int = _field("int", doc="work of one sub-step (units, step_limits)")
    substep_s: float = _field("float", doc="longest internal step (s)")
    speed_m_s: float = _field("float", doc="rolling speed (m/s)")
    static_deflection_m: float = _field("float", doc="the rim's static lowering (m)")
    min_step_s: float = _field("float", doc="shortest step it takes (s), 0 for any")
    # the free ring's modes, grouped by order
    order_start: np.ndarray = _field("int", ("n_orders + 1",), "first mode of each order")
    lam: np.ndarray = _field("complex", ("n_modes",), "eigenvalue (1/s)")
    beta: np.ndarray = _field("complex", ("n_modes",),
                              "input of a node force: beta exp(-i n theta)")
    gamma: np.ndarray = _field("complex", ("n_modes",), "node displacement: gamma exp(i n theta)")
    eta: np.ndarray = _field("complex", ("n_modes",), "node rate: eta exp(i n theta)")
    b_rim: np.ndarray = _field("complex", ("n_modes",), "input of rim_z (order 1 only)")
    c_rim: np.ndarray = _field("complex", ("2", "n_modes"), "rim_Fz, rim_Fx (order 1 only)")
    d: np.ndarray = _field("float", ("n_ring_rows", "n_ring_cols"), "direct term on inputs")
    e: np.ndarray = _field("float", ("n_ring_rows", "n_ring_cols"), "direct term on rates")
    # the zone
    zone_offset: np.ndarray = _field("int", ("n_zone",), "node offset from the centre")
    # contact points, front to rear
    point_support: np.ndarray = _field("int", ("n_points", "n_support"), "zone nodes read")
    point_weight: np.ndarray = _field("float", ("n_points", "n_support"), "their weights")
    point_cos: np.ndarray = _field("float", ("n_points",),
                                   "vertical force on the ring per unit push: (I cos)_p")
    point_sec: np.ndarray = _field("float", ("n_points",), "1/cos of it")
    point_x_road: np.ndarray = _field("float", ("n_points",), "x where its ray meets the road")
    point_stiffness: np.ndarray = _field("float", ("n_points",), "k (N/m)")
    point_damping: np.ndarray = _field("float", ("n_points",), "c (N s/m)")
    f_static: np.ndarray = _field("float", ("n_points",), "static force (N)")
    pen_static: np.ndarray = _field("float", ("n_points",), "static penetration (m)")
    window_early_s: np.ndarray = _field("float", ("n_points",), "road delay, window front (s)")
    window_late_s: np.ndarray = _field("float", ("n_points",), "road delay, window rear (s)")
    window_lo_m: np.ndarray = _field("float", ("n_points",),
                                     "its window's rear end, x from the wheel centre (m)")
    window_hi_m: np.ndarray = _field("float", ("n_points",),
                                     "its window's front end, x from the wheel centre (m)")
    # the static state
    static_ring_out: np.ndarray = _field("float", ("3",),
                                         "static rim_Fz, rim_Fx, tread_deflection")

    def __post_init__(self) -> None:
        problems = layout_problems(self)
        if problems:
            raise ValueError("not a step contract: " + "; ".join(problems))

    def sizes(self) -> dict[str, int]:
        return {f.name: int(getattr(self, f.name)) for f in fields(self)
                if f.name.startswith("n_")}

    def arrays(self) -> dict[str, np.ndarray]:
        return {f.name: getattr(self, f.name) for f in fields(self) if f.metadata["shape"]}

    @property
    def horizon_s(self) -> float:
        """How long the road takes from the zone front to the last point's window (s)."""
        return float(self.window_late_s.max()) if self.n_points else 0.0


def shape_of(spec, sizes: dict[str, int]) -> tuple[int, ...]:
    """A field's shape from its size expressions (``"n_orders + 1"``, ``"2"``)."""
    return tuple(int(eval(term, {"__builtins__": {}}, dict(sizes)))  # noqa: S307 (our table)
                 for term in spec.metadata["shape"])


def layout_problems(contract: StepContract) -> list[str]:
    """What is inconsistent in a contract's layout: kinds, shapes, finite values, indices."""
    sizes = contract.sizes()
    problems = []
    for spec in fields(contract):
        value = getattr(contract, spec.name)
        kind = spec.metadata["kind"]
        if not spec.metadata["shape"]:
            ok = isinstance(value, (int, np.integer)) if kind == "int" else (
                isinstance(value, (int, float, np.floating)) and math.isfinite(value))
            if not ok:
                problems.append(f"{spec.name} = {value!r} is not a finite {kind}")
            continue
        expected = shape_of(spec, sizes)
        if not isinstance(value, np.ndarray) or value.dtype != KINDS[kind] \
                or value.shape != expected or not value.flags.c_contiguous:
            problems.append(f"{spec.name} must be a C-contiguous {KINDS[kind]} array of shape "
                            f"{expected}, not {getattr(value, 'dtype', type(value))} "
                            f"{getattr(value, 'shape', '')}")
        elif kind != "int" and not np.all(np.isfinite(value)):
            problems.append(f"{spec.name} has non-finite values")
    if problems:
        return problems
    start = contract.order_start
    if start[0] != 0 or start[-1] != sizes["n_modes"] or np.any(np.diff(start) < 0):
        problems.append("order_start must rise from 0 to n_modes")
    if np.any(contract.point_support < 0) or np.any(contract.point_support >= sizes["n_zone"]):
        problems.append("point_support must index zone nodes")
    if sizes["n_ring_rows"] != 3 + 2 * sizes["n_zone"] or \
            sizes["n_ring_cols"] != 1 + sizes["n_zone"]:
        problems.append("n_ring_rows and n_ring_cols must be 3 + 2 n_zone and 1 + n_zone")
    return problems


def layout_text() -> str:
    """The table the C struct, the ctypes mirror and the version come from."""
    return "\n".join(f"{f.name} {f.metadata['kind']} {','.join(f.metadata['shape'])}"
                     for f in fields(StepContract))


#: Changes with any field's name, kind, shape or order: a contract crosses from one builder
#: to a kernel only with the same version.
CONTRACT_VERSION = int(hashlib.sha256(layout_text().encode()).hexdigest()[:7], 16)


# -- the Python builder ------------------------------------------------------------------------

def build_contract(contact) -> StepContract:
    """The contract of a :class:`~.contact_dynamics.ContactModel`: its free ring's modes, the
    static footprint on the contact points, the road windows."""
    from .step_limits import MIN_CORRECTED_STEP_S, substep_work

    model, patch, modes = contact.model, contact.patch, contact.modes
    zone, grid = patch.zone, model.grid
    n_zone, n_points = zone.n_nodes, zone.n_points
    # a ring truncated with static correction has a rate term a short step breaks
    truncated = bool(np.any(modes.d[:, 1:]) or np.any(modes.e[:, 1:]))
    offsets = np.arange(n_zone, dtype=np.int32) - n_zone // 2
    pen_static = (patch.footprint.penetration_m if patch.footprint is not None
                  else patch.forces_n / zone.stiffness_n_per_m)
    statics = patch.static_outputs()
    # the road each point reads by position: its arc's stretch of road at the deflection
    window_lo, window_hi = zone.road_windows_m(patch.deflection_m)
    arrays = dict(
        order_start=modes.order_start().astype(np.int32),
        lam=modes.eigenvalues, beta=modes.beta, gamma=modes.gamma, eta=modes.eta,
        b_rim=modes.b_rim, c_rim=modes.c_rim, d=modes.d, e=modes.e,
        zone_offset=offsets,
        point_support=zone.point_support, point_weight=zone.point_weight,
        point_cos=zone.force_cos, point_sec=zone.point_sec,
        point_x_road=zone.road_positions_m(patch.deflection_m),
        point_stiffness=zone.stiffness_n_per_m, point_damping=zone.damping_n_s_per_m,
        f_static=patch.forces_n, pen_static=pen_static,
        window_early_s=patch.road.early_s, window_late_s=patch.road.late_s,
        window_lo_m=window_lo, window_hi_m=window_hi,
        static_ring_out=np.array([statics["rim_Fz"], statics["rim_Fx"],
                                  statics["deflection"]]),
    )
    arrays = {name: np.ascontiguousarray(value, dtype=KINDS[_kind(name)])
              for name, value in arrays.items()}
    return StepContract(
        n_elements=grid.n_elements, n_orders=grid.n_elements // 2 + 1,
        n_modes=modes.n_modes, n_zone=n_zone, n_points=n_points,
        n_support=int(zone.point_support.shape[1]),
        n_ring_rows=3 + 2 * n_zone, n_ring_cols=1 + n_zone,
        linear=int(contact.settings.law == "linear"), centre_point=zone.centre_point,
        substep_work=substep_work(modes.n_modes, grid.n_elements // 2 + 1, n_zone, n_points,
                                  int(zone.point_support.shape[1]), truncated),
        substep_s=float(contact.substep_s), speed_m_s=float(model.speed_m_s),
        static_deflection_m=float(patch.deflection_m),
        min_step_s=float(MIN_CORRECTED_STEP_S if truncated else 0.0), **arrays)


def _kind(name: str) -> str:
    return next(f.metadata["kind"] for f in fields(StepContract) if f.name == name)
