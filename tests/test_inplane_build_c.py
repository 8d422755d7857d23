"""native/c/inplane_build.c against InPlaneSimulator._set_spin: on reduced simulators (the
FMU's case: f_max 300 Hz) with a free and a held wheel, two meshes, two point spacings, three
speeds and a hysteretic tire inside its share's ramp, every matrix the C builds equals the
simulator's own to 1e-12 of its largest entry (the inverse to its conditioning), the carry's
bases exactly; the C's inverse is one of a0 independently of numpy's; the tread's part built at
a spin apart from the ring's is the simulator's too. The C refuses bad input with a sentence
naming the parameter, its value and the allowed range, and writes nothing."""

from __future__ import annotations

import ctypes
import functools
import math
import re

import numpy as np
import pytest

from tire_fmu.core.inplane import HYSTERESIS_FULL_SPEED_M_S, InPlaneTire
from tire_fmu.core.inplane_contact import InPlaneSimulator
from tire_fmu.core.parameters import ParameterError
from tire_fmu.native.inplane_build import (
    InPlaneBuildInput,
    _declare,
    build_input,
    build_output,
    c_step_matrices,
    output_arrays,
)
from tire_fmu.native.kernel import load_library
from tire_fmu.tire_files import read_tire_file

#: Agreement asked of each matrix, relative to its largest entry: the entry-wise ones are the
#: Python's formulas in its order (they agree to the bit), the products round in another order
#: (a few ulps of the largest entry); 1e-12 leaves room for a sum's cancellations.
TOLERANCE = 1e-12
#: The inverse's agreement, relative to its largest entry, per unit of a0's 2-norm condition
#: number times the coordinates' count times the machine epsilon: two backward-stable LU
#: inverses each err by about n eps cond(a0) of the inverse's norm (Higham, ch. 14), so their
#: difference does; at N = 100 (cond about 335, 163 coordinates) the bound is 1.2e-11, the
#: differences seen about 1e-15.
INVERSE_SCALE = 1.0
EPS = np.finfo(float).eps
DEFLECTION_M = 0.01
SPINS_OF_SPEEDS = (0.0, 5.0, 20.0)


@functools.cache
def lossy_model() -> InPlaneTire:
    tire_file = read_tire_file("GL073A_inplane_hysteretic", warn=False)
    return InPlaneTire(tire=tire_file.tire, tangential=tire_file.tangential)


@functools.cache
def simulator(n: int, spacing: float, wheel: str, lossy: bool = False) -> InPlaneSimulator:
    model = lossy_model() if lossy else InPlaneTire()
    return InPlaneSimulator(model, n, 10.0, DEFLECTION_M, f_max_hz=300.0, wheel=wheel,
                            point_spacing_m=spacing)


def full_share_spin(sim) -> float:
    return HYSTERESIS_FULL_SPEED_M_S / sim.model.tire.R


def python_matrices(sim, spin: float, speed: float) -> dict:
    sim._set_spin(spin, speed)
    names = ("c", "k", "c1", "k1s", "k2", "kh", "a0_inv", "yn", "yx", "wnn", "wnx", "gain",
             "kg", "kgn", "kgx", "carry", "carry_weights", "carry_base", "carry_shift",
             "ring_spin", "ring_share", "spin_now") + (("a0_psi",) if sim._driven else ())
    result = {name: np.array(getattr(sim, "_" + name), copy=True) for name in names}
    for name in ("kg", "kgn", "kgx"):
        result[name + "_parts"] = tuple(np.array(a) for a in getattr(sim, f"_{name}_parts"))
    return result


def worst(c_value, python_value) -> float:
    """|C - Python| at its largest over the largest |Python| entry."""
    c_value, python_value = np.asarray(c_value), np.asarray(python_value)
    assert c_value.shape == python_value.shape
    scale = np.abs(python_value).max()
    return float(np.abs(c_value - python_value).max() / (scale if scale else 1.0))


def inverse_tolerance(sim) -> float:
    a0 = 4.0 / sim.step_s**2 * sim._m + 2.0 / sim.step_s * sim._c + sim._k
    return INVERSE_SCALE * np.linalg.cond(a0) * a0.shape[0] * EPS


def assert_agree(sim, spin: float, speed: float) -> dict:
    c = c_step_matrices(sim, spin)
    python = python_matrices(sim, spin, speed)
    assert set(c) == set(python)
    agreement = {}
    for name, expected in python.items():
        if name == "carry_base":
            assert c[name].dtype == np.int32 and np.array_equal(c[name], expected)
            continue
        if name.endswith("_parts"):
            for part, (got, want) in zip("ab", zip(c[name], expected)):
                agreement[f"{name}[{part}]"] = worst(got, want)
            continue
        agreement[name] = worst(c[name], expected)
    for name, value in agreement.items():
        tolerance = inverse_tolerance(sim) if name == "a0_inv" else TOLERANCE
        assert value <= tolerance, (name, value, tolerance)
    return c


CASES = [(n, spacing, wheel, speed) for n in (50, 100) for spacing in (0.01, 0.005)
         for wheel in ("free", "held") for speed in SPINS_OF_SPEEDS]
# a driven wheel: the ring's rows inverted apart, the turn's column kept
CASES += [(50, 0.01, "driven", speed) for speed in SPINS_OF_SPEEDS]


@pytest.mark.parametrize("n, spacing, wheel, speed", CASES)
def test_the_c_builds_the_simulators_step(n, spacing, wheel, speed):
    sim = simulator(n, spacing, wheel)
    assert sim._basis is not None  # reduced: the FMU's case
    assert_agree(sim, speed / sim.model.tire.R, speed)


@pytest.mark.parametrize("wheel", ["free", "held"])
@pytest.mark.parametrize("fraction", [0.4, -0.7, 3.0])
def test_the_hysteretic_share_as_the_simulators(wheel, fraction):
    sim = simulator(100, 0.01, wheel, lossy=True)
    spin = fraction * full_share_spin(sim)
    c = assert_agree(sim, spin, abs(spin) * sim.model.tire.R)
    assert c["ring_share"] == sim._ring_share  # the same formula: to the bit
    assert c["ring_share"] == pytest.approx(max(-1.0, min(1.0, fraction)), rel=1e-14)
    if abs(fraction) < 1.0:  # inside the ramp: the loss's share is in K
        assert 0.0 < abs(c["ring_share"]) < 1.0
        assert np.abs(c["kh"]).max() > 0.0


def test_the_inverse_is_a0s():
    """Independently of numpy's inverse: a0 times the C's is the identity to cond eps."""
    sim = simulator(100, 0.005, "free", lossy=True)
    spin = 0.4 * full_share_spin(sim)
    c = c_step_matrices(sim, spin)
    a0 = 4.0 / sim.step_s**2 * sim._m + 2.0 / sim.step_s * c["c"] + c["k"]
    residual = a0 @ c["a0_inv"] - np.eye(a0.shape[0])
    assert np.abs(residual).max() <= np.linalg.cond(a0) * a0.shape[0] * EPS


def raw_call(sim, spin, change=None, function="inplane_build", tread_spin=None):
    """The C called directly (data changed by ``change``): status, why, the outputs (filled
    with a sentinel before the call) and what was written."""
    lib = load_library()
    _declare(lib)
    data, keep = build_input(sim)
    # copies: a change must not reach the (cached) simulator's own arrays
    keep = [a.copy() for a in keep]
    for (name, _), a in zip(InPlaneBuildInput._fields_[5:], keep):
        setattr(data, name, a.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
    if change is not None:
        change(data, keep)
    arrays = output_arrays(sim._ny, sim._zone.n_points)
    for a in arrays.values():
        a[...] = 7
    out = build_output(arrays)
    out.ring_spin = out.ring_share = out.carry_shift = out.spin_now = 7.0
    work = np.zeros(max(lib.inplane_build_work_doubles(sim._ny, sim._zone.n_points), 1))
    iwork = np.zeros(max(lib.inplane_build_work_ints(sim._ny), 1), dtype=np.int32)
    why = ctypes.create_string_buffer(512)
    if function == "inplane_build_tread":
        status = lib.inplane_build_ring(ctypes.byref(data), float(spin), ctypes.byref(out),
                                        work.ctypes.data, iwork.ctypes.data, why, 512)
        assert status == 0
        before = {name: a.copy() for name, a in arrays.items()}
        status = lib.inplane_build_tread(ctypes.byref(data), float(tread_spin),
                                         ctypes.byref(out), why, 512)
    else:
        before = {name: a.copy() for name, a in arrays.items()}
        status = getattr(lib, function)(ctypes.byref(data), float(spin), ctypes.byref(out),
                                        work.ctypes.data, iwork.ctypes.data, why, 512)
    untouched = all(np.array_equal(before[name], a) for name, a in arrays.items())
    scalars = (out.ring_spin, out.ring_share, out.carry_shift, out.spin_now)
    return status, why.value.decode(), arrays, untouched, scalars


def test_the_tread_follows_the_spin_apart_from_the_ring():
    """The simulator's _take_spins: the ring built at one spin, the tread at another."""
    sim = simulator(50, 0.01, "free", lossy=True)
    ring_spin, tread_spin = 0.3 * full_share_spin(sim), 0.45 * full_share_spin(sim)
    status, why, arrays, _, scalars = raw_call(sim, ring_spin, function="inplane_build_tread",
                                               tread_spin=tread_spin)
    assert status == 0, why
    sim._set_ring_spin(ring_spin)
    sim._set_tread_spin(tread_spin, 1.0)
    for name in ("gain", "kg", "kgn", "kgx", "carry", "carry_weights", "a0_inv"):
        tolerance = inverse_tolerance(sim) if name == "a0_inv" else TOLERANCE
        assert worst(arrays[name], getattr(sim, "_" + name)) <= tolerance, name
    assert np.array_equal(arrays["carry_base"], sim._carry_base)
    assert scalars == (sim._ring_spin, sim._ring_share, sim._carry_shift, sim._spin_now)


def set_field(name, value):
    def change(data, keep):
        setattr(data, name, value)
    return change


def poison(index, row, column, value):
    """An entry of the index-th input array (build_input's order) set to value."""
    def change(data, keep):
        keep[index][row, column] = value
    return change


def flat_theta(data, keep):
    keep[-1][3] = keep[-1][2]


def singular(data, keep):
    for a in keep[:7]:
        a[...] = 0.0


REFUSALS = {
    "zero step": (set_field("h", 0.0), 2, ["h = 0 s", "[1e-07, 0.01] s"]),
    "negative step": (set_field("h", -1e-4), 2, ["h = -0.0001 s", "[1e-07, 0.01] s"]),
    "nan step": (set_field("h", math.nan), 2, ["h = nan", "[1e-07, 0.01] s"]),
    "long step": (set_field("h", 0.1), 2, ["h = 0.1 s", "[1e-07, 0.01] s"]),
    "no coordinates": (set_field("ny", 0), 1, ["ny = 0", "1 to 8192"]),
    "one point": (set_field("np", 1), 1, ["np = 1", "2 to 4096"]),
    "too many coordinates": (set_field("ny", 8193), 1, ["ny = 8193", "1 to 8192"]),
    "nan in m": (poison(0, 2, 5, math.nan), 4, ["m[2, 5] = nan", "finite"]),
    "inf in jxw": (poison(9, 1, 0, math.inf), 4, ["jxw[1, 0] = inf", "finite"]),
    "angles not increasing": (flat_theta, 4, ["point_theta[3]", "must increase"]),
    "singular": (singular, 5, ["singular"]),
}


@pytest.mark.parametrize("label", list(REFUSALS))
@pytest.mark.parametrize("function", ["inplane_build", "inplane_build_ring"])
def test_bad_input_is_refused_and_nothing_written(label, function):
    change, status_expected, phrases = REFUSALS[label]
    sim = simulator(50, 0.01, "held")
    status, why, _, untouched, scalars = raw_call(sim, 1.0, change, function)
    assert status == status_expected, why
    for phrase in phrases:
        assert phrase in why, (phrase, why)
    assert untouched and scalars == (7.0,) * 4


@pytest.mark.parametrize("spin", [math.nan, math.inf, -math.inf, 1e300])
@pytest.mark.parametrize("function", ["inplane_build", "inplane_build_ring",
                                      "inplane_build_tread"])
def test_a_bad_spin_is_refused_and_nothing_written(spin, function):
    sim = simulator(50, 0.01, "held")
    ring_spin = 1.0 if function == "inplane_build_tread" else spin
    status, why, _, untouched, scalars = raw_call(sim, ring_spin, function=function,
                                                  tread_spin=spin)
    assert status == 3, why
    assert why.startswith("spin_rad_s = ") and "finite" in why and "rad/s" in why
    assert untouched
    if function != "inplane_build_tread":
        assert scalars == (7.0,) * 4


def test_the_wrapper_raises_the_cs_sentence():
    sim = simulator(50, 0.01, "held")
    with pytest.raises(ValueError, match="spin_rad_s = nan"):
        c_step_matrices(sim, math.nan)


def header_value(name: str) -> float:
    from importlib import resources

    text = (resources.files("tire_fmu.native") / "c" / "inplane_build.h").read_text()
    match = re.search(rf"#define {name} (\S+)", text)
    assert match, name
    return float(match.group(1))


def test_the_headers_step_range_is_the_simulators():
    """The C refuses the steps the simulator refuses and takes the ones it takes."""
    low, high = header_value("INPLANE_BUILD_MIN_STEP_S"), header_value("INPLANE_BUILD_MAX_STEP_S")
    for step in (np.nextafter(low, 0.0), np.nextafter(high, 1.0)):
        with pytest.raises(ParameterError, match="step_s"):
            InPlaneSimulator(InPlaneTire(), 50, 5.0, DEFLECTION_M, step_s=float(step),
                             f_max_hz=300.0)
    for step in (low, high):
        sim = InPlaneSimulator(InPlaneTire(), 50, 5.0, DEFLECTION_M, step_s=step,
                               f_max_hz=300.0, wheel="held")
        assert worst(c_step_matrices(sim, sim.spin_rad_s)["a0_inv"], sim._a0_inv) \
            <= inverse_tolerance(sim)
        outside = float(np.nextafter(step, 0.0 if step == low else 1.0))
        status, why, _, untouched, _ = raw_call(sim, 1.0, set_field("h", outside))
        assert status == 2 and untouched, why


def test_the_scratch_sizes_refuse_sizes_out_of_range():
    lib = load_library()
    _declare(lib)
    assert lib.inplane_build_work_doubles(0, 10) == 0
    assert lib.inplane_build_work_doubles(10, 1) == 0
    assert lib.inplane_build_work_doubles(8193, 10) == 0
    assert lib.inplane_build_work_ints(0) == 0
    assert lib.inplane_build_work_doubles(10, 3) == 10 * 10 + 10 * 3
