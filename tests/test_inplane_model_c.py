"""The reduced in-plane step's set-up in one C call (inplane_model.c) against CAssembled, the
same bricks assembled in Python (tests/test_inplane_c_assembly.py).

Every array the one call builds (the zone's nodes and angles, the basis, the spin terms and rim
rows, the points at the deflection, the step's matrices at the spin, the carry) equals
CAssembled's to 1e-12 of each array's largest entry, its deflection for the load equals the
static brick's on CAssembled at rest, and the C step run on the one call's arrays (the spin's
rebuilds from them too) gives CAssembled's rim forces within 1e-12 of the load over 200 steps
(seen: equal to the last bit; the arrays within 8e-15, the carry the worst). Refusals name
the brick, the parameter and its value and leave the model zeroed; a host whose k-th allocation
fails, for each k of the build's 116 (N = 40), gets every block back once."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest
from test_inplane_c_assembly import BRAKE_N_M, LOAD_N, STEPS, CAssembled, tire

from tire_fmu.core.contact import contact_zone
from tire_fmu.core.discretisation import Grid
from tire_fmu.core.inplane_contact import MAX_SET_PASSES
from tire_fmu.native.inplane_build import _RING, _TREAD, _declare, build_input, build_output
from tire_fmu.native.inplane_model import InPlaneModel, build_model, c_inplane_model, model_input
from tire_fmu.native.inplane_static import c_deflection_search
from tire_fmu.native.inplane_terms import RIM_ROWS, SPIN_TERMS
from tire_fmu.native.kernel import load_library

TOLERANCE = 1e-12  # of each array's largest entry; of the load for the forces
N = 50
INPLANE_PASSES = 50  # inplane_model.h's INPLANE_MODEL_MAX_SET_PASSES
F_MAX_HZ = 300.0


def one_call(sim, model, wheel: str):
    return c_inplane_model(model, sim.n_elements, f_max_hz=F_MAX_HZ,
                           zone_length_m=sim.zone_length_m, point_spacing_m=sim.point_spacing_m,
                           load_n=LOAD_N, speed_m_s=sim.speed_m_s, spin_rad_s=sim.spin_rad_s,
                           step_s=sim.step_s, wheel_free=wheel == "free")


class OneCall(CAssembled):
    """CAssembled whose set-up is the one call's arrays (its spin's rebuilds, as CAssembled's,
    call the build bricks on them)."""

    arrays = None

    def _build(self) -> None:
        a, model, n = self.arrays, self.model, self.n_elements
        t = model.tire
        zone = contact_zone(Grid(n, t.R), t.k_cw, t.beta, self.zone_length_m,
                            self.point_spacing_m)  # the loop's road windows only
        self._basis, self._n_ring_coords = a.basis, a.n_ring_coords
        self._ring, self._zone, self._to_abs = None, zone, a.terms["to_abs"]
        self._rim_inertia = a.terms["rim_inertia"]
        self._rim_rows = {name: a.terms[f"rim_{name}"] for name in RIM_ROWS}
        self._m = a.terms["m"]
        self._spin_terms = {name: a.terms[name] for name in SPIN_TERMS}
        self._rim_on_y, self._rim_rows_at = None, (None,)
        p = a.points
        self._jn, self._jx, self._jnw, self._jxw, self._jl = (
            p[name] for name in ("jn", "jx", "jnw", "jxw", "jl"))
        self._kn, self._cn, self._kx, self._cx = (p[k] for k in ("kn", "cn", "kx", "cx"))
        self._pen0, self._sec = p["pen0"], p["sec"]
        self._cos = 1.0 / p["sec"]
        self._mu = model.tangential.friction_coefficient
        self._x_lo, self._x_hi = zone.road_windows_m(self.deflection_m)
        self._ny, self._free_spin = a.basis.shape[1], self.wheel == "free"
        self._lib = load_library()
        _declare(self._lib)
        self.builds = {"ring": 0, "tread": 0}
        # the step's matrices as the one call left them, in arrays the rebuilds write into
        self._input, self._keep = build_input(self)
        self._arrays = {name: a.build[name].copy() for name, _ in _RING + _TREAD}
        self._arrays["carry_base"] = a.build["carry_base"].copy()
        self._out = build_output(self._arrays)
        for name in ("ring_spin", "ring_share", "carry_shift", "spin_now"):
            setattr(self._out, name, a.build[name])
        b = self._arrays
        self._c, self._k, self._c1, self._k1s, self._k2, self._kh = (
            b[k] for k in ("c", "k", "c1", "k1s", "k2", "kh"))
        self._a0_inv, self._yn, self._yx, self._wnn, self._wnx = (
            b[k] for k in ("a0_inv", "yn", "yx", "wnn", "wnx"))
        for name in ("kg", "kgn", "kgx"):
            setattr(self, f"_{name}_parts", (b[name + "_a"], b[name + "_b"]))
        self._ring_spin, self._ring_share = self._out.ring_spin, self._out.ring_share
        self._gain, self._kg, self._kgn, self._kgx = (b[k] for k in ("gain", "kg", "kgn", "kgx"))
        self._carry, self._carry_weights = b["carry"], b["carry_weights"]
        self._carry_base = b["carry_base"]
        self._carry_shift, self._spin_now = self._out.carry_shift, self._out.spin_now
        self._set_speed(self.speed_m_s)
        self._s0_c = p["s0"]


def one_call_simulator(arrays, model, wheel: str) -> OneCall:
    kind = type("OneCallOf", (OneCall,), {"arrays": arrays})
    return kind(model, N, 10.0, arrays.deflection_m, backend="compiled", f_max_hz=F_MAX_HZ,
                wheel=wheel)


def close(a, b) -> float:
    """|a - b| relative to b's largest entry."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape, (a.shape, b.shape)
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


CASES = [("default", "free"), ("hysteretic", "free"), ("hysteretic", "held")]


@pytest.mark.parametrize(("name", "wheel"), CASES)
def test_the_one_call_builds_the_assembled_arrays(name, wheel):
    model = tire(name)
    options = {"f_max_hz": F_MAX_HZ, "wheel": wheel}
    search = c_deflection_search(CAssembled(model, N, 10.0, 0.0, **options), LOAD_N)
    assembled = CAssembled(model, N, 10.0, search.deflection_m, backend="compiled", **options)
    arrays = one_call(assembled, model, wheel)
    assert INPLANE_PASSES == MAX_SET_PASSES  # the static brick's passes are the core's
    # the deflection: the static brick's on CAssembled at the speed, with its secant and state
    assert abs(arrays.deflection_m - search.deflection_m) <= TOLERANCE * search.deflection_m
    assert arrays.secant_iterations == search.iterations
    assert close(arrays.static_y, search.y) <= 1e-10
    zone = assembled._zone
    assert np.array_equal(arrays.zone_nodes, zone.nodes)
    assert close(arrays.point_theta, zone.point_theta) <= TOLERANCE
    worst = {"basis": close(arrays.basis, assembled._basis),
             "m": close(arrays.terms["m"], assembled._m),
             "to_abs": close(arrays.terms["to_abs"], assembled._to_abs),
             "rim_inertia": close(arrays.terms["rim_inertia"], assembled._rim_inertia)}
    worst |= {term: close(arrays.terms[term], assembled._spin_terms[term])
              for term in SPIN_TERMS}
    worst |= {f"rim_{row}": close(arrays.terms[f"rim_{row}"], assembled._rim_rows[row])
              for row in RIM_ROWS}
    for key in ("jn", "jx", "jnw", "jxw", "jl", "kn", "cn", "kx", "cx", "pen0", "sec"):
        worst[key] = close(arrays.points[key], getattr(assembled, f"_{key}"))
    worst["s0"] = close(arrays.points["s0"], assembled._s0_c)
    for key, _ in _RING + _TREAD:
        worst[key] = close(arrays.build[key], assembled._arrays[key])
    assert np.array_equal(arrays.build["carry_base"], assembled._arrays["carry_base"])
    for key in ("ring_spin", "ring_share", "carry_shift", "spin_now"):
        worst[key] = close(arrays.build[key], getattr(assembled._out, key))
    key = max(worst, key=worst.get)
    print(f"{name}, {wheel}: worst {key} {worst[key]:.1e}")
    assert worst[key] <= TOLERANCE, worst


@pytest.mark.parametrize(("name", "wheel"), CASES)
def test_the_one_call_steps_as_the_assembled(name, wheel):
    model = tire(name)
    options = {"f_max_hz": F_MAX_HZ, "wheel": wheel}
    deflection = c_deflection_search(CAssembled(model, N, 10.0, 0.0, **options),
                                     LOAD_N).deflection_m
    assembled = CAssembled(model, N, 10.0, deflection, backend="compiled", **options)
    arrays = one_call(assembled, model, wheel)
    sim = one_call_simulator(arrays, model, wheel)
    assert sim.stepping_with == "compiled"
    # free: a hard brake (a point slides); held: a slowing road (the tread rebuilt each step)
    run_options = ({"torque_n_m": BRAKE_N_M} if wheel == "free"
                   else {"speed_m_s": lambda t: 10.0 - 50.0 * t})
    duration = STEPS * assembled.step_s
    ref = assembled.run(duration, **run_options)
    run = sim.run(duration, **run_options)
    assert ref.rim_fz_n.size == run.rim_fz_n.size == STEPS
    # the forces move: the brake's to the load's order, the slowing road's less
    assert np.abs(ref.rim_fx_n).max() > (0.1 if wheel == "free" else 5e-3) * LOAD_N
    if wheel == "held":  # the tread's rebuilds on the one call's arrays were exercised
        assert sim.builds["tread"] >= STEPS
    assert abs(ref.rim_fz_n[0] - LOAD_N) < 1e-2 * LOAD_N
    fx = np.abs(run.rim_fx_n - ref.rim_fx_n).max()
    fz = np.abs(run.rim_fz_n - ref.rim_fz_n).max()
    print(f"{name}, {wheel}: {sim.builds}, |dFx| {fx / LOAD_N:.1e}, |dFz| {fz / LOAD_N:.1e}")
    assert fx <= TOLERANCE * LOAD_N and fz <= TOLERANCE * LOAD_N, (fx, fz)


GOOD = {"f_max_hz": F_MAX_HZ, "zone_length_m": 0.3, "point_spacing_m": 0.01, "load_n": LOAD_N,
        "speed_m_s": 10.0, "spin_rad_s": 10.0 / 0.3, "step_s": 1e-4, "wheel_free": True}


@pytest.mark.parametrize(("change", "brick", "words"), [
    ({"n_elements": 3}, "inplane_ring_check", ["n_elements", "3"]),
    ({"f_max_hz": 0.5}, "inplane_ritz_build", ["f_max_hz", "0.5"]),
    ({"zone_length_m": 5.0}, "inplane_points_count", ["zone_length_m", "5 m"]),
    ({"point_spacing_m": -1.0}, "inplane_points_count", ["point_spacing_m", "-1"]),
    ({"load_n": -10.0}, "inplane_deflection_for_load", ["load", "-10"]),
    ({"step_s": 1.0}, "inplane_build", ["1"]),
    ({"spin_rad_s": float("nan")}, "inplane_points_build", ["spin_rad_s", "nan"]),
    ({"R": -0.3}, "inplane_ring_check", ["R", "-0.3"]),
])
def test_a_refusal_names_the_brick_parameter_and_value_and_frees_all(change, brick, words):
    model = tire("default")
    values = GOOD | {k: v for k, v in change.items() if k not in ("n_elements", "R")}
    inputs = model_input(model, change.get("n_elements", 40), **values)
    if "R" in change:
        inputs.tire.R = change["R"]
    lib = load_library()
    for _ in range(30):  # a leak of the arrays taken before the refusal would show as growth
        status, why, out = build_model(inputs, lib)
        assert status != 0
        assert brick in why and all(w in why for w in words), why
        # refused: nothing held, every field zero
        assert bytes(out) == bytes(InPlaneModel()), why
    if brick == "inplane_build":
        assert "step" in why or " h " in why or "h =" in why, why
    print(why)


def test_built_and_freed_many_times_the_model_is_the_same():
    model, lib = tire("default"), load_library()
    inputs = model_input(model, 40, **GOOD)
    first = None
    for _ in range(20):
        status, why, out = build_model(inputs, lib)
        assert status == 0, why
        row = np.ctypeslib.as_array(out.build.a0_inv, (out.ny * out.ny,)).copy()
        first = row if first is None else first
        assert np.array_equal(row, first)
        lib.inplane_model_free(ctypes.byref(out))
        assert bytes(out) == bytes(InPlaneModel())


def test_out_of_memory_at_any_allocation_frees_everything_taken():
    """A host whose k-th allocation fails, for every k the build makes: each refusal names the
    memory, and every block taken is given back once (none kept, none freed twice)."""
    libc = ctypes.CDLL(None)
    libc.calloc.restype, libc.calloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t] * 2
    libc.free.restype, libc.free.argtypes = None, [ctypes.c_void_p]
    allocate_t = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t)
    release_t = ctypes.CFUNCTYPE(None, ctypes.c_void_p)
    state = {"calls": 0, "fail_at": 0, "live": set(), "bad_frees": 0}

    def allocate(count, size):
        state["calls"] += 1
        if state["calls"] == state["fail_at"]:
            return None
        pointer = libc.calloc(count, size)
        state["live"].add(pointer)
        return pointer

    def release(pointer):
        if pointer not in state["live"]:
            state["bad_frees"] += 1
            return
        state["live"].remove(pointer)
        libc.free(pointer)

    class Memory(ctypes.Structure):
        _fields_ = [("allocate", allocate_t), ("release", release_t)]

    memory = Memory(allocate_t(allocate), release_t(release))
    lib = load_library()
    build_model(model_input(tire("default"), 16, **GOOD), lib)  # declares the functions
    lib.inplane_model_build.argtypes = [lib.inplane_model_build.argtypes[0],
                                        lib.inplane_model_build.argtypes[1],
                                        ctypes.POINTER(Memory), ctypes.c_char_p,
                                        ctypes.c_size_t]
    inputs = model_input(tire("default"), 40, **GOOD)
    why = ctypes.create_string_buffer(1024)
    try:
        out = InPlaneModel()
        assert lib.inplane_model_build(ctypes.byref(inputs), ctypes.byref(out),
                                       ctypes.byref(memory), why, 1024) == 0, why.value
        total = state["calls"]
        print(f"{total} allocations")
        assert state["live"] and total > 20
        lib.inplane_model_free(ctypes.byref(out))
        assert not state["live"] and state["bad_frees"] == 0
        for k in range(1, total + 1):
            state.update(calls=0, fail_at=k)
            out = InPlaneModel()
            status = lib.inplane_model_build(ctypes.byref(inputs), ctypes.byref(out),
                                             ctypes.byref(memory), why, 1024)
            text = why.value.decode()
            assert status != 0 and "memory" in text, (k, text)
            assert not state["live"] and state["bad_frees"] == 0, (k, text)
            assert bytes(out) == bytes(InPlaneModel())
    finally:
        _declare_model_again(lib)


def _declare_model_again(lib) -> None:
    lib.inplane_model_build.argtypes = [lib.inplane_model_build.argtypes[0],
                                        lib.inplane_model_build.argtypes[1], ctypes.c_void_p,
                                        ctypes.c_char_p, ctypes.c_size_t]
