"""Ground-frame rolling model: dispersion, material damping, critical speed, invariance."""

import warnings

import numpy as np
import pytest

import tire_fmu.core.dispersion as disp
from tire_fmu.core import (
    OperatingPoint,
    ParameterError,
    SupercriticalSpeedWarning,
    TireParameters,
    build_model,
    complex_modes,
    critical_speed,
    real_modes,
)
from tire_fmu.core.complex_modal import state_matrix


@pytest.fixture(scope="module")
def tire():
    """The paper's tire (GL073A, its lumped sidewall): this module checks the paper's model."""
    return TireParameters(sidewall_max_order=0.0)

PAPER_SPEED = 20 * np.pi * 0.65  # Ω = 20π rad/s, V ≈ 40.8 m/s


def rolling(tire, n_elements, speed, patch=0.0, **kw):
    return build_model(tire, OperatingPoint(n_elements=n_elements, patch_length_m=patch,
                                            speed_m_s=speed, **kw))


def all_orders(n_elements):
    return np.arange(-(n_elements // 2) + 1, n_elements // 2 + 1)


@pytest.mark.parametrize("n_elements,speed", [(40, 30.0), (100, 40.0), (100, PAPER_SPEED)])
def test_undeformed_spectrum_is_the_discrete_dispersion_relation(tire, n_elements, speed):
    model = rolling(tire, n_elements, speed)
    full = np.linalg.eigvals(state_matrix(model))
    per_order = disp.eigenvalues(tire, all_orders(n_elements), model.spin_rad_s,
                                 n_elements).ravel()
    assert full.size == per_order.size
    # match each FDM eigenvalue to its nearest per-order one, both ways
    gap = np.abs(full[:, None] - per_order[None, :])
    assert np.max(gap.min(axis=1) / np.abs(full)) < 1e-8
    assert np.max(gap.min(axis=0) / np.abs(per_order)) < 1e-8


def test_low_orders_match_the_continuum_at_400_elements(tire):
    spin = 8.0 / tire.R  # below the N = 400 critical speed (10.8 m/s)
    orders = np.arange(-8, 9)
    discrete = disp.dispersion_relation(tire, orders, spin, n_elements=400)
    continuum = disp.dispersion_relation(tire, orders, spin, n_elements=None)
    np.testing.assert_allclose(discrete.in_phase_hz, continuum.in_phase_hz, rtol=0.01)
    np.testing.assert_allclose(discrete.out_of_phase_hz, continuum.out_of_phase_hz, rtol=0.01)
    # and the continuum is the body-frame ring shifted by -nΩ
    body_low, body_high = disp.body_frequencies(tire, np.abs(orders), spin)
    np.testing.assert_allclose(2 * np.pi * continuum.in_phase_hz, body_low - orders * spin)
    # the FDM model at 400 elements has these modes too
    model = rolling(tire, 400, 8.0)
    modes = complex_modes(model, f_max_hz=200)
    for n in (-3, 2, 5):
        [i] = [k for k, m in enumerate(modes.modes) if m.order == n and m.phase == "in"]
        assert modes.frequencies_hz[i] == pytest.approx(
            continuum.in_phase_hz[orders == n][0], rel=0.01)


def test_rest_reduces_to_the_ring_model(tire):
    model = rolling(tire, 60, 0.0, patch=0.204)
    real = real_modes(model, f_max_hz=300)
    cplx = complex_modes(model, f_max_hz=320)
    s = cplx.eigenvalues[np.abs(cplx.eigenvalues) / (2 * np.pi) <= 300]
    np.testing.assert_allclose(np.sort(np.abs(s)) / (2 * np.pi), real.frequencies_hz, rtol=1e-9)
    zeta = -s.real / np.abs(s)
    np.testing.assert_allclose(np.sort(zeta), np.sort(real.damping_ratios), rtol=1e-7)


@pytest.mark.slow
@pytest.mark.parametrize("n_elements", [100, 200])
@pytest.mark.parametrize("patch", [0.0, 0.204])
def test_material_damping_is_stable_up_to_one_and_a_half_critical(tire, n_elements, patch):
    critical = critical_speed(tire, n_elements).speed_m_s
    worst = -np.inf
    for speed in np.linspace(0.0, 1.5 * critical, 7):
        model = rolling(tire, n_elements, speed, patch, allow_supercritical=True)
        worst = max(worst, np.linalg.eigvals(state_matrix(model)).real.max())
    assert worst < -1.0  # 1/s: every mode decays


def test_damping_on_the_ground_rate_goes_unstable_past_critical(tire):
    """The paper's eq. 30 damps ∂t u only: drop the circulatory term Ω·C·D1 and see."""
    model = rolling(tire, 200, PAPER_SPEED, allow_supercritical=True)
    n = model.n_dof
    a = state_matrix(model)
    k_paper = (model.stiffness - model.structure.rolling.circulatory).toarray()
    a[n:, :n] = -k_paper / model.mass.diagonal()[:, None]
    assert np.linalg.eigvals(a).real.max() > 1.0  # growing modes at 40.8 m/s, N = 200
    assert np.linalg.eigvals(state_matrix(model)).real.max() < 0  # material damping: stable


def test_undeformed_decay_rates_are_those_of_the_co_rotating_ring(tire):
    model = rolling(tire, 100, 30.0)
    ground = np.linalg.eigvals(state_matrix(model))
    body = disp.eigenvalues(tire, all_orders(100), model.spin_rad_s, 100) \
        + 1j * model.spin_rad_s * np.sin(all_orders(100) * 2 * np.pi / 100)[:, None] \
        / (2 * np.pi / 100)
    np.testing.assert_allclose(np.sort(ground.real), np.sort(body.ravel().real), rtol=1e-8,
                               atol=1e-9)
    # the transport terms change no decay rate; only centrifugal stiffening does, slightly
    rest = np.linalg.eigvals(state_matrix(rolling(tire, 100, 0.0)))
    np.testing.assert_allclose(np.sort(ground.real), np.sort(rest.real), rtol=0.02)


def test_mode_labels_at_speed(tire):
    model = rolling(tire, 100, 20.0)
    modes = complex_modes(model, f_max_hz=120)
    for m in modes.modes:
        if m.order > 0:
            assert m.direction == "backward"
        elif m.order < 0:
            assert m.direction == "forward"
        # co-rotating view: the same body frequency for ±n
        assert m.body_frequency_hz is not None
    by_order = {(m.order, m.phase): m for m in modes.modes}
    for n in (1, 2, 3):
        plus, minus = by_order[(n, "in")], by_order[(-n, "in")]
        assert plus.body_frequency_hz == pytest.approx(minus.body_frequency_hz, rel=1e-9)
        assert plus.frequency_hz < minus.frequency_hz  # backward waves slow down


def test_critical_speed_values_and_mesh_dependence(tire):
    speeds = {n: critical_speed(tire, n).speed_m_s for n in (100, 200, 400)}
    assert speeds[100] == pytest.approx(43.0, abs=1.0)
    assert speeds[400] == pytest.approx(11.0, abs=0.5)
    # lumped sidewall: V ≈ ω_s R δθ, halves with every doubling of N
    assert speeds[200] / speeds[100] == pytest.approx(0.5, abs=0.02)
    # and the ground-frame frequency really reaches zero there
    info = critical_speed(tire, 100)
    d = disp.dispersion_relation(tire, [info.order], info.spin_rad_s, n_elements=100)
    assert abs(d.in_phase_hz[0]) < 1e-6


def test_sidewall_shear_gives_a_converging_critical_speed():
    tire = TireParameters(sidewall_shear=1e5, sidewall_max_order=0.0)
    wave_speed = np.sqrt(1e5 / tire.m_s)  # m/s
    speeds = [critical_speed(tire, n).speed_m_s for n in (100, 200, 400, 800)]
    gaps = np.abs(np.array(speeds) - wave_speed)
    assert np.all(np.diff(gaps) < 0)
    assert gaps[-1] / gaps[-2] == pytest.approx(0.5, abs=0.1)  # first-order approach
    assert speeds[-1] == pytest.approx(wave_speed, rel=0.05)


def test_speed_at_or_above_critical_is_refused_unless_allowed(tire):
    critical = critical_speed(tire, 100).speed_m_s
    with pytest.raises(ParameterError, match="critical"):
        rolling(tire, 100, critical * 1.01)
    rolling(tire, 100, critical * 1.01, allow_supercritical=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rolling(tire, 100, critical * 0.9)
    assert any(issubclass(w.category, SupercriticalSpeedWarning) for w in caught)


def test_rolling_static_contact_gives_rolling_resistance(tire):
    """Material damping in steady rolling: the deformation trails, the rim feels a drag."""
    model = rolling(tire, 100, 20.0, patch=0.25)
    t, s = model.translation, model.horizontal
    z_rim = -model.patch.deflection_m
    k_s = model.structure.stiffness
    u = np.linalg.solve(model.stiffness.toarray(), k_s @ (t * z_rim))
    internal = k_s @ (u - t * z_rim)
    fx, fz = s @ internal, t @ internal
    assert fz > 0
    assert fx < 0  # pulls the rim backwards
    assert 0.0 < -fx / fz < 0.05  # a rolling-resistance coefficient, not a brake
    at_rest = rolling(tire, 100, 0.0, patch=0.25)
    u0 = np.linalg.solve(at_rest.stiffness.toarray(), at_rest.structure.stiffness @ (t * z_rim))
    assert abs(s @ (at_rest.structure.stiffness @ (u0 - t * z_rim))) < 1e-6 * fz


@pytest.mark.parametrize("patch,speed", [(0.0, 20.0), (0.0, 0.0), (0.204, 20.0)])
def test_fast_complex_modes_equal_the_dense_eigensolver(tire, patch, speed):
    """Per order (undeformed) or inverse iteration (with a patch): the same modes, labels and
    shapes as every eigenvector of the dense state matrix."""
    model = rolling(tire, 60, speed, patch=patch)
    dense = complex_modes(model, f_max_hz=300, method="dense")
    fast = complex_modes(model, f_max_hz=300, method="per-order" if patch == 0.0 else "sparse")
    assert len(fast.modes) == len(dense.modes) > 50
    np.testing.assert_allclose(fast.eigenvalues, dense.eigenvalues, rtol=1e-11)
    if speed == 0.0:
        return  # cos/sin pairs are degenerate: any basis of each pair is as good
    assert [(m.order, m.phase, m.direction) for m in fast.modes] == \
        [(m.order, m.phase, m.direction) for m in dense.modes]
    np.testing.assert_allclose(fast.frequencies_hz, dense.frequencies_hz, rtol=1e-11)
    np.testing.assert_allclose(fast.damping_ratios, dense.damping_ratios, rtol=1e-9)
    # unit modal mass both: the shapes agree up to a phase factor
    overlap = np.abs(np.einsum("ij,ij->j", dense.shapes.conj(), model.mass @ fast.shapes))
    np.testing.assert_allclose(overlap, 1.0, atol=1e-9)


def test_per_order_is_refused_with_a_patch_and_auto_falls_back(tire):
    model = rolling(tire, 40, 10.0, patch=0.204)
    with pytest.raises(ValueError, match="per-order"):
        complex_modes(model, f_max_hz=200, method="per-order")
    auto = complex_modes(model, f_max_hz=200)
    dense = complex_modes(model, f_max_hz=200, method="dense")
    np.testing.assert_allclose(auto.eigenvalues, dense.eigenvalues, rtol=1e-11)


# -- the critical speed's root finder and scan, without scipy.optimize ---------------------------

def _scipy_critical_speed(tire, n_elements):
    """The scan as it was written with scipy.optimize.brentq: one spin at a time."""
    from scipy.optimize import brentq

    from tire_fmu.core.standing_waves import (
        MAX_SCANNED_SPEED_M_S,
        ROOT_TOLERANCE,
        SCAN_POINTS,
        _margins,
    )

    orders = np.arange(1, n_elements // 2 + 1)
    kappa = (disp.order_symbols(orders, n_elements)["d1"] / 1j).real
    previous = 0.0
    for spin in np.linspace(0.0, MAX_SCANNED_SPEED_M_S / tire.R, SCAN_POINTS)[1:]:
        bad = ~(_margins(tire, orders, kappa, n_elements, spin) > 0.0)
        if bad.any():
            candidates = []
            for b, i in np.argwhere(bad):
                def margin(s, b=b, i=i):
                    value = _margins(tire, orders[i:i + 1], kappa[i:i + 1], n_elements, s)[b, 0]
                    return value if np.isfinite(value) else -1.0

                root = brentq(margin, previous, spin, xtol=ROOT_TOLERANCE, rtol=ROOT_TOLERANCE)
                candidates.append((root, int(orders[i]), ("in", "out")[b]))
            return min(candidates)
        previous = spin
    return (np.inf, None, None)


@pytest.mark.parametrize("n_elements", [8, 101, 400])
@pytest.mark.parametrize("change", [{}, {"sidewall_shear": 1e5}, {"EI": 5.0}, {"k_r2": 1.3e7}])
def test_critical_speed_is_the_one_scipy_brentq_found_to_the_bit(tire, n_elements, change):
    from dataclasses import replace

    tire = replace(tire, **change)
    found = critical_speed(tire, n_elements)
    assert (found.spin_rad_s, found.order, found.branch) == _scipy_critical_speed(tire,
                                                                                  n_elements)


@pytest.mark.parametrize("f,a,b,tol", [
    (lambda x: x**3 - 2 * x - 5, 2.0, 3.0, 1e-12),
    (lambda x: np.cos(x) - x, 0.0, 1.0, 1e-12),
    (lambda x: np.expm1(x) - 1e-9, -1.0, 4.0, 1e-12),
    (lambda x: (x - 0.3) ** 3, 0.0, 1.0, 1e-6),  # flat at its root: 49 mixed steps
    (lambda x: np.sign(x - 1 / 3), 0.0, 1.0, 1e-12),  # a jump, no root: bisection finds it
    (lambda x: x, 0.0, 1.0, 1e-12),  # a root at an end
])
def test_brentq_takes_scipys_steps(f, a, b, tol):
    from scipy.optimize import brentq as scipy_brentq

    from tire_fmu.core.standing_waves import brentq

    assert brentq(f, a, b, tol, tol) == scipy_brentq(f, a, b, xtol=tol, rtol=tol)


def test_brentq_refuses_what_scipy_refuses():
    from tire_fmu.core.standing_waves import brentq

    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x * x + 1, -1.0, 1.0, 1e-12, 1e-12)
    with pytest.raises(RuntimeError, match="100 iterations"):  # scipy: "Failed to converge"
        brentq(lambda x: (x - 0.3) ** 3, 0.0, 1.0, 1e-12, 1e-12)
