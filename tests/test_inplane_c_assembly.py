"""The in-plane step built from the C bricks alone, run against the simulator's own.

Every array the step reads comes from the C: the Ritz basis (inplane_ritz.c, on the zone's
nodes), the spin terms, mass and rim rows (inplane_terms.c), the points (inplane_points.c),
the deflection for the load (inplane_static.c, on the C-built simulator at rest), the step's
matrices at each spin (inplane_build.c: the ring's part and the tread's apart, as the
simulator rebuilds them) and the step (inplane_step.c). The run's loop is the simulator's
(its road, torque and records); the rim's forces are read from the C's rim rows. The C basis
spans the Python's subspace but is another matrix, so the states differ by a change of
coordinates: the forces on the rim are compared, to 1e-9 of the load, over 200 steps of a
braking run with a free wheel (reduced, f_max 300 Hz, the FMU's case): seen within 1e-10 of the
load for the default tire and GL073A_inplane_hysteretic (3e-11 and 2e-11 of it). With the
spin moving (a quarter car braking hard, a held wheel on a slowing road) the C rebuilds the
ring's part at one spin and the tread's apart at another as the simulator asks: within 8e-11."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

from tire_fmu.core.contact import contact_zone
from tire_fmu.core.discretisation import Grid
from tire_fmu.core.inplane import InPlaneTire
from tire_fmu.core.inplane_contact import InPlaneSimulator
from tire_fmu.native.inplane_build import _declare, build_input, build_output, output_arrays
from tire_fmu.native.inplane_points import c_points
from tire_fmu.native.inplane_ring import n_fields
from tire_fmu.native.inplane_ritz import c_ritz_basis
from tire_fmu.native.inplane_static import c_deflection_for_load, c_static_state
from tire_fmu.native.inplane_terms import c_spin_terms_of
from tire_fmu.native.kernel import load_library
from tire_fmu.tire_files import read_tire_file

LOAD_N = 4000.0
STEPS = 200
BRAKE_N_M = -1500.0  # enough for a point to slide at the zone's rear
TOLERANCE = 1e-9  # of the load


class CAssembled(InPlaneSimulator):
    """InPlaneSimulator whose set-up is the C's: ``_build`` and the spin's rebuilds call the
    C bricks; nothing of the Python's build is computed (an array it forgot would be missing,
    not silently the Python's)."""

    def _build(self) -> None:
        model, n = self.model, self.n_elements
        t, tang = model.tire, model.tangential
        free = self.wheel == "free"
        fields = n_fields(model)
        # the zone's nodes and angles, as the points' C builds them (inplane_points.c takes
        # the zone from contact.c; the basis is asked on the simulator's zone nodes)
        zone = contact_zone(Grid(n, t.R), t.k_cw, t.beta, self.zone_length_m,
                            self.point_spacing_m)
        basis = c_ritz_basis(model, n, zone.nodes, self.f_max_hz)
        terms = c_spin_terms_of(model, n, free, basis)
        r = basis.shape[1]
        ext = basis
        if free:
            ext = np.block([[basis, np.zeros((basis.shape[0], 1))],
                            [np.zeros((1, r)), np.ones((1, 1))]])
        spin = self.spin_rad_s
        points = c_points(n, fields, int(free), ext, t.R, t.k_cw, t.beta, tang.k_tx,
                          self.zone_length_m, self.point_spacing_m, self.deflection_m,
                          self.speed_m_s, spin)
        assert points["kn"].size == zone.n_points
        self._basis, self._n_ring_coords = ext, r
        self._ring, self._zone, self._to_abs = None, zone, terms["to_abs"]
        self._rim_inertia, self._rim_rows = terms["rim_inertia"], terms["rim_rows"]
        self._m = terms["m"]
        self._spin_terms = {name: terms[name] for name in ("c0", "c1", "k0", "k1", "k2", "kh")}
        self._rim_on_y, self._rim_rows_at = None, (None,)
        self._jn, self._jx, self._jnw, self._jxw, self._jl = (
            points[name] for name in ("jn", "jx", "jnw", "jxw", "jl"))
        self._kn, self._cn, self._kx, self._cx = (points[k] for k in ("kn", "cn", "kx", "cx"))
        self._pen0, self._sec = points["pen0"], points["sec"]
        self._cos = 1.0 / points["sec"]
        self._mu = tang.friction_coefficient
        self._x_lo, self._x_hi = zone.road_windows_m(self.deflection_m)
        self._ny, self._free_spin = ext.shape[1], free
        self._lib = load_library()
        _declare(self._lib)
        self.builds = {"ring": 0, "tread": 0}
        self._h = self.step_s
        self._set_spin(spin, self.speed_m_s)
        self._s0_c = points["s0"]

    def _set_ring_spin(self, spin_rad_s: float) -> None:
        lib = self._lib
        self.builds["ring"] += 1
        self._input, self._keep = build_input(self)
        ny, p = self._input.ny, self._input.np
        self._arrays = output_arrays(ny, p)  # new arrays: the C step reads them afresh
        self._out = build_output(self._arrays)
        work = np.zeros(max(lib.inplane_build_work_doubles(ny, p), 1))
        iwork = np.zeros(max(lib.inplane_build_work_ints(ny), 1), dtype=np.int32)
        why = ctypes.create_string_buffer(512)
        status = lib.inplane_build_ring(ctypes.byref(self._input), float(spin_rad_s),
                                        ctypes.byref(self._out), work.ctypes.data,
                                        iwork.ctypes.data, why, 512)
        assert status == 0, why.value
        a = self._arrays
        self._c, self._k, self._c1, self._k1s, self._k2, self._kh = (
            a[k] for k in ("c", "k", "c1", "k1s", "k2", "kh"))
        self._a0_inv, self._yn, self._yx, self._wnn, self._wnx = (
            a[k] for k in ("a0_inv", "yn", "yx", "wnn", "wnx"))
        for name in ("kg", "kgn", "kgx"):
            setattr(self, f"_{name}_parts", (a[name + "_a"], a[name + "_b"]))
        self._ring_spin, self._ring_share = self._out.ring_spin, self._out.ring_share

    def _set_tread_spin(self, spin_rad_s: float, speed_m_s: float) -> None:
        self.builds["tread"] += 1
        why = ctypes.create_string_buffer(512)
        status = self._lib.inplane_build_tread(ctypes.byref(self._input), float(spin_rad_s),
                                               ctypes.byref(self._out), why, 512)
        assert status == 0, why.value
        a = self._arrays
        self._gain, self._kg, self._kgn, self._kgx = (a[k] for k in ("gain", "kg", "kgn",
                                                                       "kgx"))
        self._carry, self._carry_weights = a["carry"], a["carry_weights"]
        self._carry_base = a["carry_base"]
        self._carry_shift, self._spin_now = self._out.carry_shift, self._out.spin_now
        self._set_speed(speed_m_s)

    def static_state(self, deflection_m: float | None = None) -> np.ndarray:
        return c_static_state(self, deflection_m)


def tire(name: str) -> InPlaneTire:
    if name == "hysteretic":
        file = read_tire_file("GL073A_inplane_hysteretic", warn=False)
        return InPlaneTire(tire=file.tire, tangential=file.tangential)
    return InPlaneTire()


@pytest.mark.parametrize("name", ["default", "hysteretic"])
def test_the_c_assembled_step_brakes_as_the_simulator(name):
    model, n = tire(name), 50
    options = {"f_max_hz": 300.0, "wheel": "free"}
    at_rest = CAssembled(model, n, 0.0, 0.0, backend="compiled", **options)
    deflection = c_deflection_for_load(at_rest, LOAD_N)
    python = InPlaneSimulator(model, n, 10.0, deflection, backend="numpy", **options)
    # the C's deflection carries the load on the Python's simulator too
    assert abs(InPlaneSimulator(model, n, 0.0, 0.0, **options).static_load_n(deflection)
               - LOAD_N) < 1e-8 * LOAD_N
    assembled = CAssembled(model, n, 10.0, deflection, backend="compiled", **options)
    assert assembled.stepping_with == "compiled"
    assert abs(assembled._s0 - assembled._s0_c).max() < 1e-12 * 10.0
    duration = STEPS * python.step_s
    ref = python.run(duration, BRAKE_N_M)
    run = assembled.run(duration, BRAKE_N_M)
    assert ref.rim_fz_n.size == run.rim_fz_n.size == STEPS
    # the brake is felt: the fore-aft force grows to the load's order, a point slides and
    # the wheel slows (the step's explicit spin correction at work: the ring is built once)
    assert np.abs(ref.rim_fx_n).max() > 0.25 * LOAD_N
    assert run.sliding_points.max() >= 1 and ref.sliding_points.max() >= 1
    assert ref.spin_rad_s[-1] < ref.spin_rad_s[0] - 0.1
    # rolling from the static state, the tire carries about its load from the first step
    assert abs(ref.rim_fz_n[0] - LOAD_N) < 1e-2 * LOAD_N
    for key in ("rim_fx_n", "rim_fz_n", "rim_my_n_m", "contact_fz_n", "spin_rad_s"):
        assert getattr(ref, key).shape == getattr(run, key).shape
    fx = np.abs(run.rim_fx_n - ref.rim_fx_n).max()
    fz = np.abs(run.rim_fz_n - ref.rim_fz_n).max()
    print(f"{name}: |dFx| {fx / LOAD_N:.2e}, |dFz| {fz / LOAD_N:.2e} of the load")
    assert fx <= TOLERANCE * LOAD_N and fz <= TOLERANCE * LOAD_N, (fx, fz)


@pytest.mark.parametrize(("wheel", "run_options", "rebuilds"), [
    # a quarter car braking hard: the spin falls by 9 %, past the ring's rebuild fraction
    ("free", {"torque_n_m": -6000.0, "vehicle_mass_kg": 300.0}, {"ring": 2, "tread": 3}),
    # a held wheel on a road slowing by 10 %: its spin is V/R, the tread rebuilt every step
    ("held", {"speed_m_s": lambda t: 10.0 - 50.0 * t}, {"ring": 2, "tread": STEPS}),
])
def test_the_c_assembled_step_follows_the_spin_as_the_simulator(wheel, run_options, rebuilds):
    """The spin's rebuilds (the ring's at one spin, the tread's apart at another, as the
    simulator's _follow_spin asks them) in C give the simulator's forces too."""
    model, n = tire("hysteretic"), 50
    options = {"f_max_hz": 300.0, "wheel": wheel}
    deflection = c_deflection_for_load(CAssembled(model, n, 0.0, 0.0, **options), LOAD_N)
    python = InPlaneSimulator(model, n, 10.0, deflection, backend="numpy", **options)
    assembled = CAssembled(model, n, 10.0, deflection, backend="compiled", **options)
    duration = STEPS * python.step_s
    ref = python.run(duration, **run_options)
    assembled.builds = {"ring": 0, "tread": 0}
    run = assembled.run(duration, **run_options)
    for kind, least in rebuilds.items():
        assert assembled.builds[kind] >= least, assembled.builds
    assert abs(ref.speed_m_s[-1] - ref.speed_m_s[0]) > 0.05
    fx = np.abs(run.rim_fx_n - ref.rim_fx_n).max()
    fz = np.abs(run.rim_fz_n - ref.rim_fz_n).max()
    print(f"{wheel}: {assembled.builds}, |dFx| {fx / LOAD_N:.2e}, |dFz| {fz / LOAD_N:.2e}")
    assert fx <= TOLERANCE * LOAD_N and fz <= TOLERANCE * LOAD_N, (fx, fz)
