"""native/c/inplane_critical.c against core/inplane_modes.py's critical_speed: the C critical
spin equals the Python's to 1e-10 over random tires, meshes from 8 to 400, every sidewall model,
with and without the radial tie and with a hysteretic loss (which neither lets in: the
undamped problem has none), with the same order and kind. Independently of both, the ring
built at that spin (no polynomial in the spin) has a singular K_n there, every order's K_n is
definite below it, and the critical order's is not just above it. The C refuses bad input
with a sentence and writes nothing."""

from __future__ import annotations

import ctypes
import math
from dataclasses import replace

import numpy as np
import pytest
from test_inplane_ring_c import fixed_case, model_of, random_case

from tire_fmu.core.inplane import InPlaneRing
from tire_fmu.core.inplane_modes import critical_speed, order_matrices
from tire_fmu.native.inplane_critical import _declare, c_critical_speed
from tire_fmu.native.inplane_ring import c_inplane_ring, n_fields, ring_data
from tire_fmu.native.kernel import load_library

#: Agreement asked of the C's critical spin, relative.
TOLERANCE = 1e-10
#: K_n at the critical spin: smallest singular value over the largest below this.
SINGULAR = 1e-9
N_RANDOM = 24

CASES = {f"random{seed}": random_case(seed) for seed in range(N_RANDOM)}
CASES.update({
    "tied_8": fixed_case("tied", 8, 0.0, False),
    "lumped_8_tie_0": fixed_case("lumped", 8, 0.0, False),
    "massless_8": fixed_case("massless", 8, 0.0, False),
    "lumped_100_tie_0": fixed_case("lumped", 100, 0.0, False, 0.0, 0.0),
    "lumped_100_tie_8_lossy": fixed_case("lumped", 100, 0.0, False, 0.05, 8.0),
    "tied_100_tie_8": fixed_case("tied", 100, 0.0, False, 0.0, 8.0),
    "tied_101_tie_0_lossy": fixed_case("tied", 101, 0.0, False, 0.3, 0.0),
    "massless_100_lossy": fixed_case("massless", 100, 0.0, False, 0.05, 8.0),
    # the GL073A_inplane_hysteretic loss with the GL073A_tied tie
    "tied_400_tie_8_lossy": fixed_case("tied", 400, 0.0, False, 0.05, 8.0),
})
#: The cases whose Python ring is cheap enough to build at several more spins.
CHECKED = [label for label, case in CASES.items() if case["n"] <= 160]


def lossless(model):
    return replace(model, tangential=replace(model.tangential, loss_factor=0.0))


@pytest.fixture(scope="module")
def python_results():
    return {}


def python_result(cache, label):
    if label not in cache:
        case = CASES[label]
        cache[label] = critical_speed(model_of(case), case["n"])
    return cache[label]


@pytest.mark.parametrize("label", list(CASES))
def test_c_critical_speed_equals_the_python_one(label, python_results):
    case = CASES[label]
    model, n = model_of(case), case["n"]
    py, c = python_result(python_results, label), c_critical_speed(model, n)
    assert (c.order, c.branch, c.n_elements) == (py.order, py.branch, py.n_elements), (
        f"C order {c.order} {c.branch}, Python order {py.order} {py.branch}")
    if py.order is None:  # no standing wave on this mesh: both infinite
        assert c.spin_rad_s == py.spin_rad_s == math.inf and c.speed_m_s == math.inf
        return
    assert abs(c.spin_rad_s - py.spin_rad_s) <= TOLERANCE * py.spin_rad_s, (
        f"C {c.spin_rad_s!r} rad/s, Python {py.spin_rad_s!r} rad/s: "
        f"{abs(c.spin_rad_s / py.spin_rad_s - 1):.3g} apart")
    assert c.speed_m_s == c.spin_rad_s * model.tire.R


def test_the_cases_cover_the_sidewalls_ties_losses_and_meshes(python_results):
    """What the agreement above spans, so that a change of the generators cannot thin it."""
    kinds = {(c["sidewall"], c["tire"].sidewall_max_order == 0.0,
              c["tangential"].loss_factor > 0.0) for c in CASES.values()}
    assert {(s, untied, lossy) for s in ("tied", "lumped") for untied in (True, False)
            for lossy in (True, False)} <= kinds
    assert {c["n"] for c in CASES.values()} >= {8, 100, 101, 400}
    results = [python_result(python_results, k).branch for k in CHECKED]
    assert {"radial", "tangential", None} <= set(results)


@pytest.mark.parametrize("label", [k for k in CASES if CASES[k]["tangential"].loss_factor
                                   and CASES[k]["n"] <= 160])
def test_the_loss_is_not_in_the_undamped_problem(label, python_results):
    """Python and C alike give the lossy tire the critical speed of the same tire without the
    loss, to the bit (the Python once fitted the loss's share of the spin as a polynomial)."""
    case = CASES[label]
    model, n = model_of(case), case["n"]
    assert python_result(python_results, label) == critical_speed(lossless(model), n)
    assert c_critical_speed(model, n) == c_critical_speed(lossless(model), n)


def order_stiffnesses(model, n_elements, spin, orders=None):
    """(n, K_n) at the spin from the Python ring built there (undamped, no loss), Hermitian,
    for the orders (all by default)."""
    undamped = replace(model, tire=replace(model.tire, alpha=0.0, beta=0.0))
    ring = InPlaneRing(undamped, n_elements, spin_rad_s=spin, hysteresis=False)
    for order in range(n_elements // 2 + 1) if orders is None else orders:
        k = order_matrices(ring, order)[2]
        yield order, 0.5 * (k + k.conj().T)


def order_stiffness(model, n_elements, spin, order):
    return next(order_stiffnesses(model, n_elements, spin, [order]))[1]


@pytest.mark.parametrize("label", CHECKED)
def test_the_c_critical_spin_is_the_first_singular_k_n(label):
    """At the C's critical spin the ring built there has its order's K_n singular; at spins
    below it every order's K_n is positive definite (as at rest, rim held: no root crossed);
    just above it the critical order's has a negative eigenvalue (the root is a crossing).
    Without a root (the massless sidewall here), K_n is definite at every spin sampled."""
    case = CASES[label]
    model, n = model_of(case), case["n"]
    found = c_critical_speed(model, n)
    if found.order is None:
        for spin in (10.0, 100.0, 1000.0, 1e4):
            for order, k in order_stiffnesses(model, n, spin):
                assert np.linalg.eigvalsh(k)[0] > 0.0, f"order {order} at {spin} rad/s"
        return
    spin = found.spin_rad_s
    sigma = np.linalg.svd(order_stiffness(model, n, spin, found.order), compute_uv=False)
    assert sigma[-1] < SINGULAR * sigma[0], (
        f"order {found.order} at {spin} rad/s: smallest singular value {sigma[-1]:.3g}, "
        f"{sigma[-1] / sigma[0]:.3g} of the largest")
    for share in (0.3, 0.7, 0.95, 0.999):
        for order, k in order_stiffnesses(model, n, share * spin):
            lowest = np.linalg.eigvalsh(k)[0]
            assert lowest > 0.0, (f"order {order} at {share} of the critical spin: lowest "
                                  f"eigenvalue {lowest:.3g}")
    above = np.linalg.eigvalsh(order_stiffness(model, n, 1.001 * spin, found.order))
    assert above[0] < 0.0


def c_ring_order_stiffnesses(model, n_elements, spin, orders=None):
    """(n, K_n) for the orders (all by default) from the C ring built at the spin (undamped,
    no loss; held to the Python ring by test_inplane_ring_c), by dense Fourier products,
    Hermitian."""
    undamped = replace(model, tire=replace(model.tire, alpha=0.0, beta=0.0))
    k = c_inplane_ring(undamped, n_elements, spin, hysteresis=False).stiffness
    theta = 2.0 * np.pi * np.arange(n_elements) / n_elements
    fields = k.shape[0] // n_elements
    for order in range(n_elements // 2 + 1) if orders is None else orders:
        f = np.kron(np.eye(fields), np.exp(1j * order * theta)[:, None]) / np.sqrt(n_elements)
        block = f.conj().T @ k @ f
        yield order, 0.5 * (block + block.conj().T)


def test_at_n_400_the_c_critical_spin_is_the_first_singular_k_n():
    """The check above at N = 400, on the C ring (the Python ring's there cost minutes)."""
    case = CASES["tied_400_tie_8_lossy"]
    model, n = model_of(case), case["n"]
    found = c_critical_speed(model, n)
    spin = found.spin_rad_s
    ((_, k),) = c_ring_order_stiffnesses(model, n, spin, [found.order])
    sigma = np.linalg.svd(k, compute_uv=False)
    assert sigma[-1] < SINGULAR * sigma[0]
    for share in (0.5, 0.999):
        lowest = {order: np.linalg.eigvalsh(k)[0]
                  for order, k in c_ring_order_stiffnesses(model, n, share * spin)}
        assert min(lowest.values()) > 0.0, (share, min(lowest, key=lowest.get))
    ((_, above),) = c_ring_order_stiffnesses(model, n, 1.001 * spin, [found.order])
    assert np.linalg.eigvalsh(above)[0] < 0.0


# ----- refusals -----

def call(model, n_elements, fields=None, data=None, null_output=False):
    """inplane_critical_speed's status, sentence and outputs (preset to sentinels)."""
    lib = load_library()
    _declare(lib)
    fields = n_fields(model) if fields is None else fields
    data = ring_data(model) if data is None else data
    size = lib.inplane_critical_work_doubles(int(n_elements), int(fields))
    work = np.zeros(max(size, 1))
    spin, speed = ctypes.c_double(-7.0), ctypes.c_double(-8.0)
    order, branch = ctypes.c_int(-9), ctypes.c_int(-10)
    why = ctypes.create_string_buffer(512)
    status = lib.inplane_critical_speed(
        ctypes.byref(data), int(n_elements), int(fields), ctypes.byref(spin),
        None if null_output else ctypes.byref(speed), ctypes.byref(order), ctypes.byref(branch),
        work.ctypes.data, why, 512)
    return status, why.value.decode(), (spin.value, speed.value, order.value, branch.value), size


UNTOUCHED = (-7.0, -8.0, -9, -10)


@pytest.mark.parametrize("n_elements, fields, words", [
    (7, 3, ("n_elements = 7", "[8, 1600]")),
    (1601, 3, ("n_elements = 1601", "[8, 1600]")),
    (40, 1, ("n_fields = 1", "2 (massless sidewall), 3 (tied) or 4 (lumped)")),
    (40, 5, ("n_fields = 5", "2 (massless sidewall), 3 (tied) or 4 (lumped)")),
])
def test_c_refuses_a_bad_mesh_or_field_count_and_writes_nothing(n_elements, fields, words):
    from tire_fmu.core.inplane import InPlaneTire

    status, why, outputs, size = call(InPlaneTire(), n_elements, fields)
    assert status != 0 and size == 0
    assert all(w in why for w in words), why
    assert outputs == UNTOUCHED


@pytest.mark.parametrize("field, value", [("R", -0.3), ("EA", math.nan), ("rhoA", 0.0),
                                          ("loss_factor", 2.0), ("alpha", -1.0)])
def test_c_refuses_bad_tire_data_naming_it_and_writes_nothing(field, value):
    from tire_fmu.core.inplane import InPlaneTire

    model = InPlaneTire()
    data = ring_data(model)
    setattr(data, field, value)
    status, why, outputs, _ = call(model, 40, data=data)
    assert status != 0 and why.startswith(f"{field} = "), why
    assert "allowed" in why and outputs == UNTOUCHED


def test_c_refuses_a_missing_output_and_the_wrapper_raises_the_sentence():
    from tire_fmu.core.inplane import InPlaneTire

    status, why, outputs, _ = call(InPlaneTire(), 40, null_output=True)
    assert status != 0 and "missing" in why and outputs == UNTOUCHED
    with pytest.raises(ValueError, match=r"n_elements = 7: allowed an integer in \[8, 1600\]"):
        c_critical_speed(InPlaneTire(), 7)


def test_the_c_and_the_python_read_the_same_rules():
    """The fit step, the real tolerance and the infinite bound are written in both (the core
    imports nothing of the C): the header's values must be the module's."""
    import re
    from pathlib import Path

    from tire_fmu.core import inplane_modes

    header = (Path(inplane_modes.__file__).parents[1] / "native" / "c"
              / "inplane_critical.h").read_text()
    for name in ("CRITICAL_FIT_STEP_RAD_S", "CRITICAL_REAL_TOLERANCE", "CRITICAL_INFINITE_SHARE"):
        (value,) = re.findall(rf"#define INPLANE_{name} (\S+)", header)
        assert float(value) == getattr(inplane_modes, name), name
