"""native/c/inplane_static.c against core/inplane_contact.py's static footprint: the C's
static state equals the Python's static_state to 1e-12 of its largest entry (beyond the
Python's own rounding, which on the nodal ring of 200 elements reaches 1e-12; the C's is
1e-13 at most) with the same
points in contact, its load the Python's static_load_n and its deflection for a load the
Python's deflection_for_load to 1e-12, over meshes of 50, 100 and 200 elements, two point
spacings, the reduced (300 Hz) and the nodal ring, 5, 27.7 and 60 kN, the hysteretic tire
file and the radial tie. Independently of both, at the C's state every point in contact
pushes, every point out of it is off the road, and the ring is in equilibrium with the
points' forces. The C refuses bad input with a sentence and writes nothing; a set that does
not settle is the core's ContactSetError."""

from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest

import tire_fmu.core.inplane_contact as contact
import tire_fmu.native.inplane_static as native_static
from tire_fmu.core.inplane import InPlaneTire
from tire_fmu.core.inplane_contact import ContactSetError, InPlaneSimulator, deflection_for_load
from tire_fmu.core.parameters import TireParameters
from tire_fmu.native.inplane_static import (
    _declare,
    _Footprint,
    c_deflection_search,
    c_static_footprint,
    c_static_load_n,
    c_static_state,
)
from tire_fmu.native.kernel import load_library
from tire_fmu.tire_files import read_tire_file

#: Agreement asked of the C, relative (the state to its largest entry).
TOLERANCE = 1e-12
#: The C's state to the exact solution of its last pass's system (relative to its largest
#: entry): the C refines its solve.
EXACT = 1e-13
#: The equilibrium residual at the solved state, relative to the load.
EQUILIBRIUM = 1e-9
LOADS_N = (5e3, 27.7e3, 60e3)


def _hysteretic():
    file = read_tire_file("GL073A_inplane_hysteretic")
    return InPlaneTire(file.tire, file.tangential)


MODELS = {"hysteretic": _hysteretic, "tied": lambda: InPlaneTire(TireParameters(
    sidewall_max_order=8.0))}


@pytest.fixture(scope="module", params=[(m, n, s, f) for m in MODELS for n in (50, 100, 200)
                                        for s in (0.01, 0.005) for f in (300.0, None)],
                ids=lambda p: f"{p[0]}-N{p[1]}-{p[2]}m-{'reduced' if p[3] else 'nodal'}")
def case(request):
    name, n, spacing, f_max = request.param
    model = MODELS[name]()
    options = {"point_spacing_m": spacing, "f_max_hz": f_max}
    return model, n, options, InPlaneSimulator(model, n, 0.0, 0.0, **options)


def _exact(sim, pen0, active, y):
    """The solution of the pass's system on the set, refined from y with residuals summed in
    long double: what both solves round (the Python's on the nodal ring by up to about 1e-12,
    more than the C's)."""
    nr = sim._n_ring_coords
    jn = sim._jn[active, :nr]
    a = sim._k[:nr, :nr] + jn.T @ (sim._kn[active, None] * jn)
    b = -jn.T @ (sim._kn[active] * pen0[active])
    wide = a.astype(np.longdouble)
    for _ in range(3):
        y = y + np.linalg.solve(a, (b - wide @ y.astype(np.longdouble)).astype(float))
    return y


def _relative(a, b):
    return abs(a - b) / abs(b)


def test_the_c_footprint_is_the_cores(case, monkeypatch):
    """For each load: the C's deflection is the core's, after as many secant iterations, and
    at it the C's state, set and load are the core's; the state is a frictionless contact in
    equilibrium."""
    model, n, options, sim = case
    calls = []
    core_load = InPlaneSimulator.static_load_n

    def counted(self, deflection_m=None):
        calls.append(deflection_m)
        return core_load(self, deflection_m)

    monkeypatch.setattr(InPlaneSimulator, "static_load_n", counted)
    nr = sim._n_ring_coords
    worst = {"deflection": 0.0, "state": 0.0, "load": 0.0, "state_exact": 0.0,
             "python_state": 0.0, "python_load": 0.0}
    row = sim.rim_force_rows(0.0)[0][1, :nr].astype(np.longdouble)
    for load in LOADS_N:
        calls.clear()
        expected = deflection_for_load(model, load, n, **options)
        search = c_deflection_search(sim, load)
        assert search.iterations == len(calls) - 2  # the core's two starts, then one a trial
        at_search = c_static_footprint(sim, search.deflection_m)
        np.testing.assert_array_equal(search.y, at_search.y)
        np.testing.assert_array_equal(search.active, at_search.active)
        y = sim.static_state(expected)
        foot = c_static_footprint(sim, expected)
        state = c_static_state(sim, expected)
        np.testing.assert_array_equal(state[:nr], foot.y)
        assert not state[nr:].any()
        assert _relative(c_static_load_n(sim, expected), load) < 2e-9

        # the Python's own rounding, against the exact solution of the last pass's system
        scale = np.abs(y).max()
        pen0 = model.tire.R - (model.tire.R - expected) * sim._sec
        exact = _exact(sim, pen0, foot.active, y[:nr])
        exact_load = float(-(row @ exact.astype(np.longdouble)))
        python_load = sim.static_load_n(expected)
        state_error = np.abs(y[:nr] - exact).max() / scale
        load_error = _relative(python_load, exact_load)
        # the C to 1e-12 of the Python beyond the Python's own error (on a near-linear piece,
        # load ~ d^p with p >= 1, the deflection's relative error is at most the load's)
        gaps = {"state": (np.abs(state - y).max() / scale, state_error),
                "load": (_relative(foot.load_n, python_load), load_error),
                "deflection": (_relative(search.deflection_m, expected), load_error)}
        for name, (gap, own) in gaps.items():
            assert gap < TOLERANCE + own, f"{name} at {load} N: {gap:.3g} (Python's {own:.3g})"
            worst[name] = max(worst[name], gap)
        worst["python_state"] = max(worst["python_state"], state_error)
        worst["python_load"] = max(worst["python_load"], load_error)
        # the C to its own rounding
        worst["state_exact"] = max(worst["state_exact"], np.abs(foot.y - exact).max() / scale)
        assert worst["state_exact"] < EXACT

        # the core's set, read off its state as the core's last pass does
        pen = pen0 + sim._jn @ y
        np.testing.assert_array_equal(foot.active, pen > 0)

        # independent of both: the points pushing and only those, in equilibrium
        jn = sim._jn[:, :nr]
        pen_c = pen0 + jn @ foot.y
        force = np.where(foot.active, sim._kn * pen_c, 0.0)
        assert (force[foot.active] > 0).all() and foot.active.any()
        assert (pen_c[~foot.active] <= 0).all()
        residual = sim._k[:nr, :nr] @ foot.y + jn.T @ force
        assert np.abs(residual).max() < EQUILIBRIUM * load
    print(", ".join(f"{name} {value:.3g}" for name, value in worst.items()))


def test_a_rolling_simulator_reads_its_own_rows():
    """Built rolling (its K and the rim's rows at the spin), the simulator's static state and
    load are still the core's."""
    sim = InPlaneSimulator(_hysteretic(), 50, 10.0, 0.0, f_max_hz=300.0)
    for deflection in (0.01, 0.03):
        y = sim.static_state(deflection)
        assert np.abs(c_static_state(sim, deflection) - y).max() < TOLERANCE * np.abs(y).max()
        assert _relative(c_static_load_n(sim, deflection),
                         sim.static_load_n(deflection)) < TOLERANCE


@pytest.fixture(scope="module")
def small():
    return InPlaneSimulator(InPlaneTire(), 50, 0.0, 0.0, f_max_hz=300.0)


@pytest.mark.parametrize("deflection", [math.nan, math.inf, -1e-3, 0.3, 1.0])
def test_a_bad_deflection_is_refused(small, deflection):
    if deflection == 0.3:
        deflection = small.model.tire.R
    with pytest.raises(ValueError, match=r"deflection_m = .*: allowed a finite number in \[0, "):
        c_static_footprint(small, deflection)


@pytest.mark.parametrize("load", [0.0, -5e3, math.nan, math.inf])
def test_a_bad_load_is_refused(small, load):
    with pytest.raises(ValueError, match=r"load_n = .* N: allowed a finite number above 0 N"):
        c_deflection_search(small, load)


def test_no_deflection_carries_no_load(small):
    foot = c_static_footprint(small, 0.0)
    assert foot.load_n == 0.0 and not foot.active.any() and not foot.y.any()
    assert small.static_load_n(0.0) == 0.0


def _call(lib, foot, deflection, data=None):
    """inplane_static_state into outputs filled with a sentinel; (status, why, outputs)."""
    y = np.full(foot.n_coords, 7.0)
    active = np.full(foot.n_points, 7, dtype=np.intc)
    load, passes = ctypes.c_double(7.0), ctypes.c_int(7)
    why = ctypes.create_string_buffer(512)
    status = lib.inplane_static_state(ctypes.byref(foot.data if data is None else data),
                                      deflection, y.ctypes.data, active.ctypes.data,
                                      ctypes.byref(load), ctypes.byref(passes),
                                      foot.work.ctypes.data, foot.iwork.ctypes.data, why, 512)
    return status, why.value.decode(), (y, active, load.value, passes.value)


def _untouched(outputs):
    y, active, load, passes = outputs
    return (y == 7.0).all() and (active == 7).all() and load == 7.0 and passes == 7


@pytest.mark.parametrize("field, value, words", [
    ("n_coords", 0, "n_coords = 0: allowed an integer of at least 1"),
    ("n_points", -2, "n_points = -2: allowed an integer of at least 1"),
    ("max_passes", 0, "max_passes = 0: allowed an integer of at least 1"),
    ("radius_m", -0.3, "radius_m = -0.3 m: allowed a finite number above 0 m"),
    ("radius_m", math.nan, "radius_m = nan m: allowed a finite number above 0 m"),
])
def test_bad_sizes_and_data_are_refused_writing_nothing(small, field, value, words):
    lib = load_library()
    _declare(lib)
    foot = _Footprint(small, lib)
    data = native_static.InPlaneStaticData.from_buffer_copy(foot.data)
    setattr(data, field, value)
    status, why, outputs = _call(lib, foot, 0.02, data)
    assert status != 0 and words in why and _untouched(outputs)
    status, why, outputs = _call(lib, foot, -0.02)
    assert status != 0 and "deflection_m = -0.02 m" in why and _untouched(outputs)


def test_a_non_finite_matrix_is_refused_writing_nothing(small):
    lib = load_library()
    _declare(lib)
    foot = _Footprint(small, lib)
    foot.arrays[1][3, 2] = math.nan  # jn, which the struct points at
    status, why, outputs = _call(lib, foot, 0.02)
    assert status != 0 and "jn has a non-finite entry" in why and _untouched(outputs)


def test_a_set_that_does_not_settle_is_the_cores_error(small, monkeypatch):
    """With one pass allowed, a footprint that needs more is refused as the core refuses it."""
    deflection = 0.03
    assert c_static_footprint(small, deflection).passes > 1
    monkeypatch.setattr(contact, "MAX_SET_PASSES", 1)
    monkeypatch.setattr(native_static, "MAX_SET_PASSES", 1)
    with pytest.raises(ContactSetError) as core:
        small.static_state(deflection)
    with pytest.raises(ContactSetError) as ours:
        c_static_footprint(small, deflection)
    assert str(ours.value) == str(core.value)
    lib = load_library()
    _declare(lib)
    status, why, outputs = _call(lib, _Footprint(small, lib), deflection)
    assert status == native_static.UNSETTLED and "did not settle" in why
    assert _untouched(outputs)


def test_a_stiffness_not_symmetric_is_solved_by_lu(small):
    """K made asymmetric (beyond the Cholesky's share) takes the LU: its state is still a
    frictionless contact in equilibrium with that K, and close to the symmetric one's."""
    lib = load_library()
    _declare(lib)
    foot = _Footprint(small, lib)
    k = foot.arrays[0]
    symmetric = c_static_footprint(small, 0.02)
    rng = np.random.default_rng(3)
    k += 1e-9 * np.abs(k).max() * np.triu(rng.standard_normal(k.shape), 1)
    status, why, (y, active, load, passes) = _call(lib, foot, 0.02)
    assert status == 0, why
    active = active.astype(bool)
    pen0 = small.model.tire.R - (small.model.tire.R - 0.02) * small._sec
    pen = pen0 + foot.arrays[1] @ y
    force = np.where(active, small._kn * pen, 0.0)
    assert (force[active] > 0).all() and (pen[~active] <= 0).all()
    assert np.abs(k @ y + foot.arrays[1].T @ force).max() < EQUILIBRIUM * load
    assert np.abs(y - symmetric.y).max() < 1e-3 * np.abs(symmetric.y).max()
