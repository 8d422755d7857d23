"""The step contract: its generated C header, its ctypes mirror, and the two builders (the
Python core and the native FMU's C) compared field by field over random tires, so that a
divergence names the array and the index."""

import ctypes
import math
import shutil
import subprocess
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

from tire_fmu.core.contact_dynamics import ContactSettings, build_contact_model
from tire_fmu.core.contract import CONTRACT_VERSION, StepContract, build_contract
from tire_fmu.core.free_ring import RingTruncation
from tire_fmu.core.parameters import (
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    TireParameters,
)
from tire_fmu.core.standing_waves import critical_speed
from tire_fmu.fmu.interface import fmu_variables
from tire_fmu.native.builder import C_SOURCES, c_folder
from tire_fmu.native.contract import TireContractStruct, c_header, from_ctypes, to_ctypes

#: Relative to each array's largest entry: the two builders do the same arithmetic in the same
#: order except in the eigen-decompositions (LAPACK's and the C's QR of the same matrices).
CONTRACT_RTOL = 1e-12
#: The arrays scaled by eigenvectors: two eigen-solvers agree on a vector to the rounding unit
#: times its condition, which rolling orders near a veering raise (1.1e-11 measured at N = 800
#: and 27.5 m/s, where the eigenvalues still agree to 3e-14).
EIGENVECTOR_RTOL = 2e-11
#: The static footprint too: its forces solve the points' compliance, a sum over those
#: eigenvectors, along a continuation of active-set updates (1.08e-12 of the largest force
#: measured at N = 800 at rest, case 49 of the random tires, with numpy 2.4.6's OpenBLAS).
EIGENVECTOR_FIELDS = ("beta", "gamma", "eta", "b_rim", "c_rim", "f_static", "pen_static")
SHIM = Path(__file__).parent / "native_host" / "contract_shim.c"


def test_contract_header_is_the_generated_one():
    """contract.h is what tire_fmu.native.contract generates from StepContract (regenerate it
    with ``python -c "from tire_fmu.native.contract import c_header; print(c_header(),
    end='')" > tire_fmu/native/c/contract.h``)."""
    assert (Path(str(c_folder())) / "contract.h").read_text() == c_header()
    assert f"#define TIRE_CONTRACT_VERSION {CONTRACT_VERSION}u" in c_header()


def test_a_contract_survives_the_ctypes_mirror(contract_at_rest):
    back = from_ctypes(to_ctypes(contract_at_rest))
    for spec in fields(StepContract):
        assert np.array_equal(getattr(back, spec.name), getattr(contract_at_rest, spec.name)), \
            spec.name


def test_an_inconsistent_contract_is_refused(contract_at_rest):
    values = {spec.name: getattr(contract_at_rest, spec.name) for spec in fields(StepContract)}
    with pytest.raises(ValueError, match="lam must be"):
        StepContract(**{**values, "lam": values["lam"][:-1]})
    with pytest.raises(ValueError, match="order_start must rise"):
        StepContract(**{**values, "order_start": values["order_start"][::-1].copy()})


@pytest.fixture(scope="module")
def contract_at_rest():
    return build_contract(build_contact_model())


# -- the C builder against the Python builder ---------------------------------------------------

class CBuilder:
    """The native FMU's builder (every C file but the FMI layer) in a small library."""

    def __init__(self, folder: Path):
        if shutil.which("gcc") is None:
            pytest.fail("comparing the builders needs gcc")
        c = Path(str(c_folder()))
        target = folder / "contract_shim.so"
        subprocess.run(["gcc", "-std=c99", "-O2", "-shared", "-fPIC", "-I", str(c), "-o",
                        str(target), str(SHIM), *(str(c / s) for s in C_SOURCES
                                                  if s != "fmi2_layer.c"), "-lm"],
                       check=True, capture_output=True)
        self.lib = ctypes.CDLL(str(target))
        self.lib.shim_build.restype = ctypes.c_void_p
        self.lib.shim_build.argtypes = [ctypes.POINTER(ctypes.c_double),
                                        ctypes.POINTER(TireContractStruct), ctypes.c_char_p,
                                        ctypes.c_size_t]
        self.lib.shim_free.argtypes = [ctypes.c_void_p]
        self.table = fmu_variables()

    def build(self, values: dict) -> tuple[StepContract | None, str]:
        """The C's contract for FMU parameter values, or None and its problems."""
        unknown = set(values) - {v.name for v in self.table}
        assert not unknown, unknown
        array = (ctypes.c_double * len(self.table))(*[
            float(values.get(v.name, v.start or 0.0)) for v in self.table])
        out, text = TireContractStruct(), ctypes.create_string_buffer(16384)
        handle = self.lib.shim_build(array, ctypes.byref(out), text, len(text))
        if not handle:
            return None, text.value.decode()
        try:
            return from_ctypes(out), ""
        finally:
            self.lib.shim_free(handle)


@pytest.fixture(scope="module")
def c_builder(tmp_path_factory):
    return CBuilder(tmp_path_factory.mktemp("contract"))


def random_case(rng: np.random.Generator) -> dict:
    """A tire and operating point in range: each tire field within x2 of GL073A's (the
    sidewall laws on or off), a mesh from 8 to 1600 nodes, a load up to 1.3 x the default,
    a speed up to 90 % of the mesh's critical speed, and the truncation and law at random."""
    base = TireParameters()
    tire = {}
    for name, spec in TIRE_FIELDS.items():
        value = getattr(base, name)
        if name == "sidewall_shear":
            value = 0.0 if rng.random() < 0.5 else float(10 ** rng.uniform(3, 5.5))
        elif name == "sidewall_max_order":  # lumped, or tied above a low order
            value = 0.0 if rng.random() < 0.5 else float(rng.integers(1, 13))
        elif name == "sidewall_pressure_exponent":
            value = 0.0 if rng.random() < 0.7 else float(rng.uniform(0.2, 1.5))
        elif value > 0:
            value = float(value * 2.0 ** rng.uniform(-1, 1))
        tire[name] = min(max(value, spec.low if spec.low_inclusive else
                             math.nextafter(spec.low, math.inf)), spec.high)
    n = int(rng.choice([8, 12, 16, 30, 50, 64, 100, 101, 150, 200, 256, 400, 800, 1600],
                       p=[.04, .04, .06, .08, .1, .08, .2, .06, .08, .08, .06, .06, .04, .02]))
    params = TireParameters(**tire)
    critical = critical_speed(params, n).speed_m_s
    speed = 0.0 if rng.random() < 0.4 else float(rng.uniform(0.01, 0.9) * min(critical, 60.0))
    case = {"tire": tire, "n_elements": n, "speed": speed,
            "load": float(rng.uniform(0.0, 1.3) * 27_654.753),
            "f_max": 0.0 if rng.random() < 0.6 else float(10 ** rng.uniform(2, 4)),
            "n_modes": 0 if rng.random() < 0.85 else int(rng.integers(1, 400)),
            "static_correction": bool(rng.random() < 0.8),
            "linear_contact": bool(rng.random() < 0.2)}
    return case


def python_contract(case: dict) -> StepContract:
    tire = TireParameters(**case["tire"])
    op = OperatingPoint(n_elements=case["n_elements"], load_n=case["load"],
                        speed_m_s=case["speed"], contact_point_spacing_m=case.get("spacing", 1.0))
    truncation = RingTruncation(f_max_hz=case["f_max"] or None,
                                n_modes=case["n_modes"] or None,
                                static_correction=case["static_correction"])
    settings = ContactSettings(law="linear" if case["linear_contact"] else "unilateral")
    return build_contract(build_contact_model(tire, op, truncation, settings))


def c_values(case: dict) -> dict:
    return {**case["tire"], "n_elements": case["n_elements"], "load": case["load"],
            "speed": case["speed"], "f_max": case["f_max"], "n_modes": case["n_modes"],
            "static_correction": float(case["static_correction"]),
            "linear_contact": float(case["linear_contact"]),
            "contact_point_spacing": case.get("spacing", 1.0)}


def rounding_scales(case: dict, zone_offset: np.ndarray) -> dict[str, np.ndarray]:
    """Per entry of d and e, the sum of the magnitudes of the terms each builder adds to form
    it: the exact DC gain or direct rate term and every mode's share (c_k b_k/λ_k and
    c_k b_k/λ_k²). A truncated ring's d and e are what is left of such a sum (d = DC gain -
    the kept modes' share, e = direct term + the dropped modes' share), so an entry zero by
    symmetry (rim_Fx on the rim's motion at rest) is rounding of terms of this size in both
    builders, and an array whose largest entry is itself a cancellation residue (a ring cut to
    a mode or two) is no scale for its rounding."""
    from tire_fmu.core.discretisation import Grid
    from tire_fmu.core.free_ring import ring_modes

    tire = TireParameters(**case["tire"])
    grid = Grid(case["n_elements"], tire.R)
    nodes = np.mod(zone_offset, case["n_elements"])
    full = ring_modes(tire, grid, case["speed"] / tire.R, nodes,
                      RingTruncation(f_max_hz=None, n_modes=None))
    b, c = full.dense(grid.theta[nodes])
    lam = full.eigenvalues
    return {"d": np.abs(full.static_gain) + np.abs(c / lam) @ np.abs(b),
            "e": np.abs(full.e) + np.abs(c / lam**2) @ np.abs(b)}


def differences(python: StepContract, native: StepContract,
                scales: dict[str, np.ndarray] | None = None) -> list[str]:
    """Every field where the two contracts differ: integers exactly, numbers and arrays beyond
    CONTRACT_RTOL of their largest entry (or of an entry's own ``scales``, where given: the
    size of the terms summed to form it), naming the worst index."""
    found = []
    scales = scales or {}
    for spec in fields(StepContract):
        a, b = getattr(python, spec.name), getattr(native, spec.name)
        if not isinstance(a, np.ndarray):
            exact = spec.metadata["kind"] == "int"
            if a != b if exact else not abs(a - b) <= CONTRACT_RTOL * abs(a):
                found.append(f"{spec.name}: {a!r} (Python) != {b!r} (C)")
            continue
        if a.shape != b.shape:
            found.append(f"{spec.name}: shape {a.shape} (Python) != {b.shape} (C)")
            continue
        if not a.size:
            continue
        error = np.abs(a - b)
        rtol = EIGENVECTOR_RTOL if spec.name in EIGENVECTOR_FIELDS else CONTRACT_RTOL
        scale = np.maximum(float(np.abs(a).max()), scales.get(spec.name, 0.0))
        scale = np.broadcast_to(np.maximum(scale, 1e-300), a.shape)
        worst = np.unravel_index(int(np.argmax(error / scale)), a.shape)
        if spec.metadata["kind"] == "int" and error.max() > 0 or \
                np.any(error > rtol * scale):
            found.append(f"{spec.name}{list(worst)}: {a[worst]!r} (Python) != {b[worst]!r} "
                         f"(C), {error[worst] / scale[worst]:.2e} of its scale")
    return found


@pytest.mark.parametrize("spacing", [1.0, 2.5e-3])
@pytest.mark.parametrize("speed, n_elements", [(0.0, 100), (20.0, 100), (0.0, 400),
                                               (8.0, 400), (0.0, 1600)])
def test_the_builders_agree_on_the_default_tire(c_builder, speed, n_elements, spacing):
    case = {"tire": TireParameters().as_dict(), "n_elements": n_elements, "speed": speed,
            "load": 27_654.753, "f_max": 0.0, "n_modes": 0, "static_correction": True,
            "linear_contact": False, "spacing": spacing}
    native, problems = c_builder.build(c_values(case))
    assert native is not None, problems
    assert differences(python_contract(case), native) == []


@pytest.mark.parametrize("n_elements, spacing, f_max, static_correction", [
    (100, 2.5e-3, 0.0, True),     # every mode: no rate term on the held forces
    (400, 1.0, 2000.0, True),     # truncated with static correction: the rate term's rows
    (400, 1.0, 2000.0, False),    # truncated without: no rate term
    (800, 6e-4, 0.0, True),       # a fine mesh with fine points
])
def test_the_builders_count_the_same_substep_work(c_builder, n_elements, spacing, f_max,
                                                  static_correction):
    """Both builders put substep_work's one sum on the contract (and refuse by it): the same
    integer, the sum of the kernel's sub-step loops for the contract's sizes; a ring truncated
    with static correction adds its rate term's (3 + 2 Z) x Z entries, one without does not."""
    from tire_fmu.core import step_limits

    case = {**DEFAULT_CASE, "n_elements": n_elements, "spacing": spacing, "f_max": f_max,
            "static_correction": static_correction}
    python = python_contract(case)
    native, problems = c_builder.build(c_values(case))
    assert native is not None, problems
    assert native.substep_work == python.substep_work
    z = python.n_zone
    loops = (step_limits.SUBSTEP_WORK_BASE
             + step_limits.SUBSTEP_WORK_PER_MODE * python.n_modes
             + step_limits.SUBSTEP_WORK_PER_ORDER_NODE * python.n_orders * (z // 2 + 1)
             + step_limits.SUBSTEP_WORK_PER_SUPPORT * python.n_points * python.n_support
             + step_limits.SUBSTEP_WORK_PER_POINT * python.n_points
             + step_limits.SUBSTEP_WORK_PER_NODE_PAIR * z * z)
    rate_term = step_limits.SUBSTEP_WORK_PER_RATE_ENTRY * (3 + 2 * z) * z
    truncated = f_max > 0 and static_correction
    assert (python.min_step_s > 0) == truncated
    assert python.substep_work == loops + (rate_term if truncated else 0)
    # no term of the points' count is quadratic any more: the dense solve's 3 P^2 is gone
    assert python.substep_work < 3 * python.n_points ** 2 or python.n_points < 100


@pytest.mark.slow
def test_the_builders_agree_on_random_tires(c_builder):
    """60 random tires in range (seeded): each either refused by both builders or built to
    the same contract by both; at least 50 of them built, rolling and at rest."""
    rng = np.random.default_rng(20)
    built, rolling, mismatched = 0, 0, []
    for index in range(60):
        case = random_case(rng)
        try:
            python = python_contract(case)
        except ParameterError as error:
            native, _ = c_builder.build(c_values(case))
            if native is not None:
                mismatched.append(f"case {index}: refused by Python only ({error})")
            continue
        native, problems = c_builder.build(c_values(case))
        if native is None:
            mismatched.append(f"case {index}: refused by C only ({problems.strip()})")
            continue
        built += 1
        rolling += case["speed"] > 0
        scales = rounding_scales(case, python.zone_offset)
        mismatched += [f"case {index} (N = {case['n_elements']}, {case['speed']:.3g} m/s): "
                       f"{text}" for text in differences(python, native, scales)]
    assert mismatched == []
    assert built >= 50 and rolling >= 20


# -- contact points: the C builder against points_spec.md, written out here ---------------------

def reference_points(radius: float, n_elements: int, carry: int, m: int) -> dict:
    """The contact points of points_spec.md: m per carrying node -carry .. carry, front to
    rear, each on a cubic Lagrange stencil of four zone nodes (zone offsets -(carry + 2) ..
    carry + 2) when m > 1, the node itself (weight 1) when m = 1."""
    dtheta = 2 * math.pi / n_elements
    half = carry + 2 if m > 1 else carry
    support, weight, theta = [], [], []
    for j in range(-carry, carry + 1):
        for i in range(m):
            u = j * m + i - (m - 1) // 2
            theta.append(u * dtheta / m)
            if m == 1:
                support.append([j + half])
                weight.append([1.0])
                continue
            b = u // m
            s = (u - b * m) / m
            support.append([b - 1 + half, b + half, b + 1 + half, b + 2 + half])
            weight.append([-s * (s - 1) * (s - 2) / 6, (s + 1) * (s - 1) * (s - 2) / 2,
                           -(s + 1) * s * (s - 2) / 2, (s + 1) * s * (s - 1) / 6])
    support, weight, theta = np.array(support), np.array(weight), np.array(theta)
    node_theta = (np.arange(2 * half + 1) - half) * dtheta
    interpolation = np.zeros((theta.size, node_theta.size))
    np.add.at(interpolation, (np.repeat(np.arange(theta.size), support.shape[1]),
                              support.ravel()), weight.ravel())
    return {"half": half, "support": support, "weight": weight, "theta": theta,
            "node_theta": node_theta, "I": interpolation,
            "arc": radius * dtheta, "dtheta": dtheta}


def reference_footprint(points: dict, compliance: np.ndarray, k: float, radius: float,
                        load: float, max_deflection: float):
    """The static active-set continuation on the points, dense: (diag(1/k) + G_p,AA) f_A =
    p0_A + p1_A d with G_p = I G I^T, segment by segment from the centre point; the state at
    ``load`` (forces, penetrations, active set, deflection), or None beyond the path."""
    from tire_fmu.core.contact import _EVENT_TOLERANCE, EVENTS_TOGETHER, TOUCH_ATOL

    interp, cos = points["I"], np.cos(points["theta"])
    load_cos = interp @ np.cos(points["node_theta"])
    g_p = interp @ compliance @ interp.T
    p0, p1 = radius - radius / cos, 1.0 / cos
    active, start = np.zeros(cos.size, dtype=bool), 0.0
    for _ in range(8 * (cos.size + 1)):
        if not active.any():
            active = np.abs(cos - 1.0) <= TOUCH_ATOL
        f0, f1 = np.zeros(cos.size), np.zeros(cos.size)
        system = np.eye(int(active.sum())) / k + g_p[np.ix_(active, active)]
        solved = np.linalg.solve(system, np.column_stack([p0[active], p1[active]]))
        f0[active], f1[active] = solved[:, 0], solved[:, 1]
        pen0, pen1 = p0 - g_p @ f0, p1 - g_p @ f1
        w0, w1 = load_cos @ f0, load_cos @ f1
        with np.errstate(divide="ignore", invalid="ignore"):
            leave = np.where(active & (f1 < 0), -f0 / f1, np.inf)
            enter = np.where(~active & (pen1 > 0), -pen0 / pen1, np.inf)
        events = np.minimum(leave, enter)
        events[events <= start * (1 + _EVENT_TOLERANCE) + _EVENT_TOLERANCE * radius] = np.inf
        end = min(float(events.min()), max_deflection)
        if w1 > 0 and w0 + w1 * end >= load:
            d = max((load - w0) / w1, start)
            return f0 + f1 * d, pen0 + pen1 * d, active.copy(), d
        if end >= max_deflection:
            return None
        together = events <= end * (1 + EVENTS_TOGETHER) + _EVENT_TOLERANCE * radius
        active = active.copy()
        active[together & (leave <= enter)] = False
        active[together & (enter < leave)] = True
        start = end
    raise AssertionError("the reference continuation did not terminate")


def reference_contract(case: dict, m: int) -> StepContract | None:
    """The contract of points_spec.md for a case with m points per node: the free ring's
    modes on the zone nodes (the core's ring_modes), everything about the points here."""
    from tire_fmu.core.contact import MAX_DEFLECTION_FRACTION, contact_zone
    from tire_fmu.core.contact_dynamics import MAX_SUBSTEP_S, MIN_CORRECTED_STEP_S
    from tire_fmu.core.discretisation import Grid
    from tire_fmu.core.free_ring import ring_modes, zone_compliance
    from tire_fmu.core.step_limits import substep_work

    tire = TireParameters(**case["tire"])
    n, speed = case["n_elements"], case["speed"]
    grid = Grid(n, tire.R)
    carry = contact_zone(grid, tire.k_cw, tire.beta, 0.6, 1.0).n_nodes // 2  # carrying
    points = reference_points(tire.R, n, carry, m)
    half, interp = points["half"], points["I"]
    nodes = np.arange(-half, half + 1) % n
    truncation = RingTruncation(f_max_hz=case["f_max"] or None, n_modes=case["n_modes"] or None,
                                static_correction=case["static_correction"])
    modes = ring_modes(tire, grid, speed / tire.R, nodes, truncation)
    compliance = zone_compliance(modes.static_gain)
    k = tire.k_cw * points["arc"] / m
    state = reference_footprint(points, compliance, k, tire.R, case["load"],
                                MAX_DEFLECTION_FRACTION * tire.R)
    if state is None:
        return None
    forces, pen, active, deflection = state
    forces = np.where(active, forces, 0.0) if deflection > 0 else np.zeros_like(forces)
    theta = points["theta"]
    height, sub = tire.R - deflection, 0.5 * points["dtheta"] / m
    x_lo, x_hi = -height * np.tan(theta + sub), -height * np.tan(theta - sub)
    front = x_hi.max()
    early, late = ((front - x_hi) / speed, (front - x_lo) / speed) if speed > 0 else (
        np.zeros(theta.size), np.zeros(theta.size))
    node_forces = interp.T @ forces
    truncated = bool(np.any(modes.d[:, 1:]) or np.any(modes.e[:, 1:]))
    n_zone, n_points, n_support = 2 * half + 1, theta.size, points["support"].shape[1]
    arrays = dict(
        order_start=modes.order_start(), lam=modes.eigenvalues, beta=modes.beta,
        gamma=modes.gamma, eta=modes.eta, b_rim=modes.b_rim, c_rim=modes.c_rim, d=modes.d,
        e=modes.e, zone_offset=np.arange(-half, half + 1), point_support=points["support"],
        point_weight=points["weight"], point_cos=interp @ np.cos(points["node_theta"]),
        point_sec=1.0 / np.cos(theta), point_x_road=-height * np.tan(theta),
        point_stiffness=np.full(n_points, k), point_damping=np.full(n_points, tire.beta * k),
        f_static=forces, pen_static=pen, window_early_s=early, window_late_s=late,
        window_lo_m=x_lo, window_hi_m=x_hi,
        static_ring_out=np.array([np.cos(points["node_theta"]) @ node_forces,
                                  np.sin(points["node_theta"]) @ node_forces,
                                  compliance[half] @ node_forces]))
    kinds = {spec.name: spec.metadata["kind"] for spec in fields(StepContract)}
    arrays = {name: np.ascontiguousarray(value, dtype={"int": np.int32, "float": np.float64,
                                                       "complex": np.complex128}[kinds[name]])
              for name, value in arrays.items()}
    return StepContract(
        n_elements=n, n_orders=n // 2 + 1, n_modes=modes.n_modes, n_zone=n_zone,
        n_points=n_points, n_support=n_support, n_ring_rows=3 + 2 * n_zone,
        n_ring_cols=1 + n_zone, linear=int(case["linear_contact"]),
        centre_point=int(np.flatnonzero(np.abs(theta) == 0.0)[0]),
        substep_work=substep_work(modes.n_modes, n // 2 + 1, n_zone, n_points, n_support,
                                  truncated),
        substep_s=min(MAX_SUBSTEP_S, 1.0 / math.sqrt(tire.k_cw / tire.rhoA)),
        speed_m_s=float(speed), static_deflection_m=float(deflection),
        min_step_s=MIN_CORRECTED_STEP_S if truncated else 0.0, **arrays)


def spacing_for(case: dict, m: int) -> float:
    """The spacing that makes exactly m points per node (the node arc over m)."""
    return case["tire"]["R"] * (2 * math.pi / case["n_elements"]) / m


DEFAULT_CASE = {"tire": TireParameters().as_dict(), "n_elements": 100, "speed": 0.0,
                "load": 27_654.753, "f_max": 0.0, "n_modes": 0, "static_correction": True,
                "linear_contact": False}


@pytest.mark.parametrize("m, speed, n_elements", [(1, 0.0, 100), (3, 0.0, 100),
                                                  (17, 0.0, 100), (15, 12.0, 100),
                                                  (5, 8.0, 400), (3, 0.0, 800)])
def test_the_c_builder_makes_the_contact_points_of_the_spec(c_builder, m, speed, n_elements):
    """Points, weights, laws, the static footprint on the points (a dense continuation here
    against the C's node-space one), the road windows and the static outputs, field by field."""
    case = {**DEFAULT_CASE, "speed": speed, "n_elements": n_elements}
    native, problems = c_builder.build(c_values({**case, "spacing": spacing_for(case, m)}))
    assert native is not None, problems
    assert native.n_points == (2 * (native.n_zone // 2 - (2 if m > 1 else 0)) + 1) * m
    assert differences(reference_contract(case, m), native) == []


def test_the_default_spacing_resolves_a_10_mm_feature(c_builder):
    """At the default spacing (2.5 mm) a 10 mm feature meets at least four points, on any
    mesh: the node arc is split into the fewest odd number of points no longer than it."""
    for n in (100, 400, 1600):
        case = {**DEFAULT_CASE, "n_elements": n}
        native, problems = c_builder.build(c_values({**case, "spacing": 2.5e-3}))
        assert native is not None, problems
        theta = np.arctan(-native.point_x_road / (TireParameters().R -
                                                  native.static_deflection_m))
        spacing = TireParameters().R * np.diff(np.sort(theta)).max()
        arc = TireParameters().R * 2 * math.pi / n
        m = native.n_points // (2 * (native.n_zone // 2 - 2) + 1)
        assert spacing <= 2.5e-3 * (1 + 1e-9) < arc / (m - 2) and m % 2 == 1


def test_the_points_carry_the_nodes_load(c_builder):
    """Statically the road's push on the points equals the rim load (contact_Fz = rim_Fz),
    the points' forces reach the nodes by the virtual work of the interpolation (their
    vertical shares are the point_cos), and the footprint converges with the spacing: the
    deflection at the default load changes by less between m = 9 and 27 than between m = 1
    and 3."""
    deflections = {}
    for m in (1, 3, 9, 27):
        native, problems = c_builder.build(c_values({**DEFAULT_CASE,
                                                     "spacing": spacing_for(DEFAULT_CASE, m)}))
        assert native is not None, problems
        load = native.point_cos @ native.f_static
        assert load == pytest.approx(DEFAULT_CASE["load"], rel=1e-12)
        assert native.static_ring_out[0] == pytest.approx(load, rel=1e-12)
        deflections[m] = native.static_deflection_m
    assert abs(deflections[27] - deflections[9]) < abs(deflections[3] - deflections[1])


@pytest.mark.slow
def test_the_c_builder_makes_the_spec_points_on_random_tires(c_builder):
    """40 random tires in range (seeded), each with a random odd number of points per node
    (up to 1500 points): the C's contract is the spec's, field by field, or both refuse the
    load (the points' footprint carries a little more or less than the nodes')."""
    rng = np.random.default_rng(21)
    built, points_per_node, mismatched = 0, set(), []
    for index in range(40):
        case = random_case(rng)
        try:
            python_contract(case)  # a tire and operating point the core takes (as nodes)
        except ParameterError:
            continue
        nodes = c_builder.build(c_values(case))[0].n_points
        m = int(rng.choice([m for m in (1, 3, 5, 9, 17, 31) if m * nodes <= 1500]))
        native, problems = c_builder.build(c_values({**case, "spacing": spacing_for(case, m)}))
        reference = reference_contract(case, m)
        if native is None or reference is None:
            if not (native is None and problems.count("load = ") == 1):
                mismatched.append(f"case {index} (m = {m}): C {problems.strip() or 'built'}, "
                                  f"reference {'built' if reference else 'beyond its path'}")
            continue
        built += 1
        points_per_node.add(m)
        scales = rounding_scales(case, reference.zone_offset)
        mismatched += [f"case {index} (N = {case['n_elements']}, m = {m}, {case['speed']:.3g} "
                       f"m/s): {text}" for text in differences(reference, native, scales)]
    assert mismatched == []
    assert built >= 25 and len(points_per_node) >= 4


@pytest.mark.parametrize("speed, n_elements, top", [(0.0, 100, 8), (20.0, 100, 8),
                                                    (20.0, 800, 8), (5.0, 64, 1)])
def test_the_builders_agree_on_a_tied_sidewall(c_builder, speed, n_elements, top):
    """The sidewall tied to the tread above sidewall_max_order: both builders, field by
    field (the tie's modes are far above the ring's, so this is also their conditioning)."""
    tire = {**TireParameters().as_dict(), "sidewall_max_order": float(top)}
    case = {"tire": tire, "n_elements": n_elements, "speed": speed, "load": 27_654.753,
            "f_max": 0.0, "n_modes": 0, "static_correction": True, "linear_contact": False,
            "spacing": 2.5e-3}
    native, problems = c_builder.build(c_values(case))
    assert native is not None, problems
    assert differences(python_contract(case), native) == []
