"""native/c/inplane_points.c against core/inplane_contact.py's InPlaneSimulator: the C's
point Jacobians (jn, jx, jnw, jxw, jl) and point data (kn, cn, kx, cx, pen0, sec, s0) equal
the simulator's own arrays to 1e-13 of each array's largest entry (the largest difference
met: 6e-16 on the Jacobians, 2e-16 on sec θ, 0 on kn, cn, kx, cx, 7e-15 on pen0 and 5e-15 on
s0, whose R - (R - d) sec θ and V - ΩR cos θ cancel: the C's angle u δθ/m rounds apart from
the core's u (δθ/m)), over meshes
of 50, 100 and 200 elements, spacings of 0.01, 0.005 and 0.0025 m, zones of 0.6 and 0.4 m,
the wheel free and held, the reduced (300 Hz) and the nodal ring, 0 and 10 m/s, at the
deflection for the load. The zone the C builds them on (contact.c's zone_build) is the
core's contact_zone: the same nodes, weights, angles, arcs, stiffness and damping.

Apart from both, the C's Jacobians obey the ring's geometry: the wheel's rigid turn, put on
the tread as ring motion, moves every point fore-aft by -R cos θ (jxw's ψ column) and not
radially; a rigid translation moves every point by itself, to the cubic interpolation's
bound (9/16)/24 δθ⁴, exactly at the points on nodes; and the discrete L = D1 + κ1 J
annihilates the rigid translations (κ1 = sin δθ/δθ: D1 sin = κ1 cos exactly), so jl on them
is rounding. The C refuses bad input with a sentence naming the parameter and writes
nothing."""

from __future__ import annotations

import ctypes
import functools
import math

import numpy as np
import pytest

from tire_fmu.core.contact import contact_zone, points_per_node
from tire_fmu.core.discretisation import Grid
from tire_fmu.core.inplane import InPlaneRing, InPlaneTire
from tire_fmu.core.inplane_contact import InPlaneSimulator, deflection_for_load
from tire_fmu.core.parameters import TireParameters
from tire_fmu.native.inplane_points import (
    JACOBIANS,
    POINT_DATA,
    c_point_data,
    c_points,
    simulator_inputs,
)
from tire_fmu.native.kernel import load_library

#: Agreement asked of the C, relative to each array's largest entry.
TOLERANCE = 1e-13
#: Rounding allowed on an identity that holds exactly (relative to the terms' size).
ROUNDING = 1e-13
LOAD_N = 27.7e3
MODEL = InPlaneTire(TireParameters())


@functools.cache
def _deflection(n: int, spacing: float, zone: float) -> float:
    return deflection_for_load(MODEL, LOAD_N, n, zone_length_m=zone, point_spacing_m=spacing)


@functools.lru_cache(maxsize=4)
def _simulator(n, spacing, zone, wheel, f_max, speed):
    return InPlaneSimulator(MODEL, n, speed, _deflection(n, spacing, zone), wheel=wheel,
                            zone_length_m=zone, point_spacing_m=spacing, f_max_hz=f_max)


CASES = [(n, s, z, wheel, f, v) for n in (50, 100, 200) for s in (0.01, 0.005, 0.0025)
         for z in (0.6, 0.4) for f in (300.0, None) for wheel in ("free", "held")
         for v in (0.0, 10.0)]


def _relative(c, py) -> float:
    scale = np.max(np.abs(py)) if py.size else 0.0
    if scale == 0.0:
        return 0.0 if np.array_equal(c, py) else math.inf
    return float(np.max(np.abs(c - py)) / scale)


@pytest.mark.parametrize("case", CASES, ids=lambda c: "N{}-{}m-zone{}-{}-{}-{}ms".format(
    c[0], c[1], c[2], c[3], "reduced" if c[4] else "nodal", c[5]))
def test_points_equal_the_simulators(case):
    sim = _simulator(*case)
    ours = c_point_data(sim)
    assert set(ours) == set(JACOBIANS + POINT_DATA)
    for name, value in ours.items():
        theirs = getattr(sim, "_" + name)
        assert value.shape == np.shape(getattr(sim, "_" + name)), name
        assert _relative(value, theirs) <= TOLERANCE, (name, _relative(value, theirs))


# ----- the zone: contact.c's zone_build against core/contact.py's contact_zone -----
class _Zone(ctypes.Structure):
    """tire.h's Zone."""

    _P = ctypes.POINTER(ctypes.c_double)
    _fields_ = [(name, ctypes.c_int) for name in (
        "n_zone", "half", "centre", "carry", "per_node", "n_points", "n_support",
        "centre_point")] + [("radius", ctypes.c_double), ("dtheta", ctypes.c_double),
                            ("theta", _P), ("cos", _P), ("sin", _P),
                            ("support", ctypes.POINTER(ctypes.c_int)), ("weight", _P),
                            ("point_theta", _P), ("ray_cos", _P), ("sec", _P),
                            ("load_cos", _P), ("load_sin", _P), ("stiffness", ctypes.c_double),
                            ("damping", ctypes.c_double)]


@pytest.mark.parametrize("n", (50, 100, 200))
@pytest.mark.parametrize("spacing", (0.01, 0.005, 0.0025))
@pytest.mark.parametrize("zone_length", (0.6, 0.4))
def test_c_zone_is_the_cores(n, spacing, zone_length):
    t = MODEL.tire
    lib = load_library()
    lib.zone_half_count.restype = ctypes.c_int
    lib.zone_half_count.argtypes = [ctypes.c_double, ctypes.c_int, ctypes.c_double]
    lib.points_per_node.restype = ctypes.c_int
    lib.points_per_node.argtypes = [ctypes.c_double, ctypes.c_double]
    lib.mem_default.restype = ctypes.c_void_p
    lib.zone_build.restype = ctypes.c_int
    lib.zone_build.argtypes = [ctypes.POINTER(_Zone), ctypes.c_void_p, ctypes.c_int,
                               ctypes.c_double, ctypes.c_double, ctypes.c_double,
                               ctypes.c_int, ctypes.c_int]
    lib.zone_free.argtypes = [ctypes.POINTER(_Zone), ctypes.c_void_p]
    grid = Grid(n, t.R)
    py = contact_zone(grid, t.k_cw, t.beta, zone_length, spacing)
    carry = lib.zone_half_count(t.R, n, zone_length)
    m = lib.points_per_node(grid.node_arc_m, spacing)
    assert m == py.points_per_node == points_per_node(grid.node_arc_m, spacing)
    zone = _Zone()
    assert lib.zone_build(ctypes.byref(zone), lib.mem_default(), n, t.R, t.k_cw, t.beta,
                          carry, m) == 0
    try:
        p, s, z = zone.n_points, zone.n_support, zone.n_zone
        assert (p, z) == (py.n_points, py.nodes.size)
        nodes = np.mod(np.arange(z) - zone.half, n)
        np.testing.assert_array_equal(nodes, py.nodes)
        support = np.ctypeslib.as_array(zone.support, (p, s))
        weight = np.ctypeslib.as_array(zone.weight, (p, s))
        np.testing.assert_array_equal(support, py.point_support)
        np.testing.assert_allclose(weight, py.point_weight, rtol=0, atol=1e-15)
        interp = np.zeros((p, z))
        np.add.at(interp, (np.repeat(np.arange(p), s), support.ravel()), weight.ravel())
        np.testing.assert_allclose(interp, py.interpolation, rtol=0, atol=1e-15)
        theta = np.ctypeslib.as_array(zone.point_theta, (p,))
        np.testing.assert_allclose(theta, py.point_theta, rtol=0, atol=1e-15)
        arc = zone.radius * zone.dtheta / zone.per_node
        assert arc == pytest.approx(py.point_arc_m, rel=1e-15)
        np.testing.assert_allclose(zone.stiffness, py.stiffness_n_per_m, rtol=1e-15)
        np.testing.assert_allclose(zone.damping, py.damping_n_s_per_m, rtol=1e-15)
    finally:
        lib.zone_free(ctypes.byref(zone), lib.mem_default())


# ----- the geometry, apart from both -----
@pytest.mark.parametrize("n", (50, 100, 200))
@pytest.mark.parametrize("spacing", (0.01, 0.0025))
def test_rigid_motions_move_the_points_as_the_geometry_says(n, spacing):
    t = MODEL.tire
    ring = InPlaneRing(MODEL, n)
    rows = ring.n_ring_dof + 1
    ours = c_points(n, ring.n_fields, 1, np.eye(rows), t.R, t.k_cw, t.beta,
                    MODEL.tangential.k_tx, 0.6, spacing, 0.02, 10.0, 10.0 / t.R)
    zone = contact_zone(Grid(n, t.R), t.k_cw, t.beta, 0.6, spacing)
    th = zone.point_theta
    moves = np.vstack([ring.rim_patterns, np.zeros((1, 3))])  # as ring motion: ψ's own 0
    x, z, turn = moves.T
    jn, jx, jxw, jl = (ours[k] for k in ("jn", "jx", "jxw", "jl"))
    # the turn: -R cos θ fore-aft (the free wheel's ψ column), nothing radial
    np.testing.assert_allclose(jx @ turn, -t.R * np.cos(th), rtol=0, atol=ROUNDING * t.R)
    np.testing.assert_allclose(jxw[:, -1], -t.R * np.cos(th), rtol=0, atol=ROUNDING * t.R)
    np.testing.assert_allclose(jn @ turn, 0.0, rtol=0, atol=ROUNDING * t.R)
    # a unit translation moves each point by itself, to the cubic's bound; exactly on nodes
    bound = 9.0 / 16.0 / 24.0 * (2 * math.pi / n) ** 4 + ROUNDING
    on_node = np.isclose(np.mod(th * n / (2 * math.pi) + 0.5, 1.0), 0.5, atol=1e-9)
    for move, fore_aft, radial in ((x, 1.0, -np.sin(th)), (z, 0.0, -np.cos(th))):
        assert np.max(np.abs(jx @ move - fore_aft)) <= bound
        assert np.max(np.abs(jn @ move - radial)) <= bound
        np.testing.assert_allclose((jx @ move)[on_node], fore_aft, rtol=0, atol=ROUNDING)
        np.testing.assert_allclose((jn @ move)[on_node], radial[on_node], rtol=0,
                                   atol=ROUNDING)
        # L u is the material derivative of the motion: none for a translation
        scale = np.max(np.abs(jl)) * np.abs(move).sum(axis=0)
        assert np.max(np.abs(jl @ move)) <= ROUNDING * scale
    # but not for the turn: L on (w, v) = (0, R) is (-κ1 R, 0), jl reads κ1 R sin θ
    kappa1 = math.sin(2 * math.pi / n) / (2 * math.pi / n)
    np.testing.assert_allclose(jl @ turn, kappa1 * t.R * np.sin(th), rtol=0,
                               atol=ROUNDING * t.R * np.max(np.abs(jl)))


@pytest.mark.parametrize("wheel", ("free", "held"))
def test_a_reduced_basis_is_the_nodal_rows_times_it(wheel):
    sim = _simulator(100, 0.005, 0.6, wheel, 300.0, 10.0)
    inputs = simulator_inputs(sim)
    reduced = c_points(**inputs)
    nodal = c_points(**{**inputs, "basis": np.eye(inputs["basis"].shape[0])})
    for name in JACOBIANS:
        expected = nodal[name] @ inputs["basis"]
        assert _relative(reduced[name], expected) <= TOLERANCE, name
    for name in POINT_DATA:
        np.testing.assert_array_equal(reduced[name], nodal[name])


# ----- refusals -----
def _good():
    t = MODEL.tire
    ring = InPlaneRing(MODEL, 50)
    return {"n_elements": 50, "n_fields": ring.n_fields, "wheel_free": 0,
            "basis": np.eye(ring.n_ring_dof), "radius_m": t.R, "k_cw": t.k_cw,
            "beta": t.beta, "k_tx": MODEL.tangential.k_tx, "zone_length_m": 0.6,
            "point_spacing_m": 0.01, "deflection_m": 0.02, "speed_m_s": 10.0,
            "spin_rad_s": 10.0 / t.R}


@pytest.mark.parametrize("change, words", [
    ({"deflection_m": -1e-3}, ("deflection_m", "-0.001", "[0, ")),
    ({"deflection_m": MODEL.tire.R}, ("deflection_m", "[0, ")),
    ({"deflection_m": math.nan}, ("deflection_m", "nan")),
    ({"point_spacing_m": 0.0}, ("point_spacing_m", "= 0 m", "[0.0001, 1] m")),
    ({"point_spacing_m": -0.01}, ("point_spacing_m", "-0.01")),
    ({"zone_length_m": 0.0}, ("zone_length_m", "(0, ")),
    ({"zone_length_m": 0.01}, ("zone_length_m", "one node either side")),
    ({"radius_m": math.inf}, ("radius_m", "inf", "> 0")),
    ({"k_cw": -1.0}, ("k_cw", ">= 0")),
    ({"beta": math.nan}, ("beta", "nan")),
    ({"k_tx": math.inf}, ("k_tx", "inf")),
    ({"speed_m_s": math.nan}, ("speed_m_s", "finite")),
    ({"spin_rad_s": math.inf}, ("spin_rad_s", "finite")),
    ({"n_elements": 3, "basis": None}, ("n_elements = 3", "[4, ")),
    ({"n_fields": 5, "basis": None}, ("n_fields = 5", "[2, 4]")),
    ({"wheel_free": 2, "basis": None}, ("wheel_free = 2",)),
])
def test_bad_input_is_refused_with_a_sentence(change, words):
    inputs = {**_good(), **change}
    if inputs["basis"] is None:
        inputs["basis"] = np.eye(inputs["n_fields"] * inputs["n_elements"]
                                 + inputs["wheel_free"])
    with pytest.raises(ValueError) as error:
        c_points(**inputs)
    for word in words:
        assert word in str(error.value)


def test_a_non_finite_basis_entry_is_named():
    inputs = _good()
    inputs["basis"] = inputs["basis"].copy()
    inputs["basis"][7, 3] = math.nan
    with pytest.raises(ValueError, match=r"basis\[7, 3\] = nan: must be finite"):
        c_points(**inputs)


def test_a_refusal_writes_nothing():
    """Outputs filled with a marker stay so when the C refuses (here: a deflection beyond R,
    passed straight to the library with a count taken from good input)."""
    from tire_fmu.native import inplane_points as native

    lib = load_library()
    native._declare(lib)
    good = _good()
    basis = np.ascontiguousarray(good.pop("basis"))

    def struct(**values):
        merged = {**good, **values}
        return native.InPlanePointsInput(
            merged["n_elements"], merged["n_fields"], merged["wheel_free"], basis.shape[1],
            basis.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            *(float(merged[k]) for k in ("radius_m", "k_cw", "beta", "k_tx", "zone_length_m",
                                         "point_spacing_m", "deflection_m", "speed_m_s",
                                         "spin_rad_s")))

    count = ctypes.c_int(0)
    assert lib.inplane_points_count(ctypes.byref(struct()), ctypes.byref(count), None, 0) == 0
    p, r = count.value, basis.shape[1]
    out = {k: np.full((p, r), 7.0) for k in JACOBIANS}
    out.update({k: np.full(p, 7.0) for k in POINT_DATA})
    pointers = native.InPlanePoints(p, *(out[k].ctypes.data_as(ctypes.POINTER(ctypes.c_double))
                                         for k in JACOBIANS + POINT_DATA))
    why = ctypes.create_string_buffer(256)
    for bad in ({"deflection_m": 2.0}, {"point_spacing_m": 0.0}):
        assert lib.inplane_points_build(ctypes.byref(struct(**bad)), ctypes.byref(pointers),
                                        None, why, 256) != 0
        assert next(iter(bad)) in why.value.decode()
    wrong = native.InPlanePoints(p + 1, *(out[k].ctypes.data_as(ctypes.POINTER(ctypes.c_double))
                                          for k in JACOBIANS + POINT_DATA))
    assert lib.inplane_points_build(ctypes.byref(struct()), ctypes.byref(wrong), None, why,
                                    256) == 1
    assert f"n_points = {p + 1}: must be {p}" in why.value.decode()
    for value in out.values():
        assert np.all(value == 7.0)
    assert lib.inplane_points_build(ctypes.byref(struct()), ctypes.byref(pointers), None,
                                    why, 256) == 0
    assert not np.all(out["jn"] == 7.0)
