"""The studies behind the paper's Figs. 14 and 17-19, checked against their key numbers."""

import json

import numpy as np
import pytest

from tire_fmu.core import OperatingPoint, ParameterError, TireParameters, build_model, real_modes
from tire_fmu.core.dispersion import body_frequencies
from tire_fmu.core.studies import (
    convergence_study,
    dispersion_at_speed,
    paper_speed_m_s,
    patch_sweep,
    speed_sweep,
)


@pytest.fixture(scope="module")
def tire():
    """The paper's tire (GL073A, its lumped sidewall): this module checks the paper's model."""
    return TireParameters(sidewall_max_order=0.0)


@pytest.fixture(scope="module")
def convergence(tire):
    return convergence_study(tire)


@pytest.fixture(scope="module")
def sweep(tire):
    # 0 to 40 cm in 1 cm steps plus the paper's 20.4 cm (5 nodes at N = 100) at the end
    return patch_sweep(tire, 100, np.r_[np.linspace(0.0, 0.40, 41), 0.204], (1, 2, 3, 4, 5, 6))


# ------------------------------------------------------------------ convergence (Fig. 14)


@pytest.mark.parametrize("phase", ["in", "out"])
def test_fdm_converges_at_second_order(convergence, phase):
    slopes = convergence.convergence_order(phase)
    assert np.isnan(slopes[0])  # n = 0: the stencils are exact on constants
    assert np.all((slopes[1:] > 1.8) & (slopes[1:] < 2.2)), slopes


@pytest.mark.parametrize("phase", ["in", "out"])
def test_400_elements_within_half_a_percent(convergence, phase):
    assert convergence.element_counts[-1] == 400
    error = convergence.relative_error(phase)
    assert np.all(np.abs(error[-1]) < 0.005), error[-1]
    # central differences soften the ring: FDM frequencies approach the exact ones from below
    assert np.all(error[:, 1:] < 0)


def test_assembled_model_equals_the_per_order_symbols(convergence, tire):
    assert convergence.model_symbol_difference < 1e-9
    low, high = body_frequencies(tire, convergence.orders, 0.0, n_elements=100)
    row = list(convergence.element_counts).index(100)
    np.testing.assert_allclose(convergence.in_phase_hz[row], low / (2 * np.pi), rtol=1e-10)
    np.testing.assert_allclose(convergence.out_of_phase_hz[row], high / (2 * np.pi), rtol=1e-10)


def test_orders_a_mesh_cannot_resolve_are_nan(tire):
    result = convergence_study(tire, element_counts=(8, 16), orders=range(0, 7))
    assert np.isnan(result.in_phase_hz[0, 5:]).all()  # n > N/2 = 4 on 8 nodes
    assert np.isfinite(result.in_phase_hz[1]).all()
    json.dumps(result.to_dict())


# ------------------------------------------------------------------ patch sweep (Fig. 17)


@pytest.mark.parametrize("n", [2, 3, 4])
def test_paper_patch_splits_each_pair(sweep, n):
    i, j = sweep.at_length(0.204), list(sweep.orders).index(n)
    assert sweep.lengths_m[i] == pytest.approx(0.204)
    assert 9.0 <= sweep.shift_percent("symmetric")[i, j] <= 13.0
    assert 1.0 <= sweep.shift_percent("antisymmetric")[i, j] <= 3.0


def test_stiffened_members_rise_falls_off_for_higher_orders(sweep):
    rise = sweep.shift_percent("symmetric")[sweep.at_length(0.204)]
    assert rise[3] > rise[4] > rise[5]  # n = 4, 5, 6


def test_shift_grows_with_patch_length(sweep):
    ordered = np.argsort(sweep.lengths_m, kind="stable")
    for symmetry in ("symmetric", "antisymmetric"):
        shift = sweep.shift_percent(symmetry)[ordered]
        assert np.all(np.diff(shift, axis=0) > -1e-9), symmetry
    n2 = list(sweep.orders).index(2)
    sym = sweep.shift_percent("symmetric")
    assert sym[sweep.at_length(0.40), n2] >= sym[sweep.at_length(0.10), n2]
    assert np.all(np.diff(sweep.loads_n[:41]) > 0)  # longer patch, heavier load


def test_shift_is_continuous_in_patch_length(sweep):
    # 1 cm steps from 1 cm on: fractional node weights leave no node-sized staircase. The first
    # centimetre is steep by nature: with the near-rigid k_cw even a sliver of patch pins the
    # centre node (about 8 % for n = 2 within 1 cm, smoothly, see the core tests).
    for symmetry in ("symmetric", "antisymmetric"):
        shift = sweep.shift_percent(symmetry)[1:41]
        assert np.abs(np.diff(shift, axis=0)).max() < 1.5, symmetry


def test_symmetric_member_always_rises_more(sweep):
    loaded = sweep.lengths_m > 0
    sym = sweep.shift_percent("symmetric")[loaded]
    anti = sweep.shift_percent("antisymmetric")[loaded]
    assert np.all(sym > anti)


def test_out_of_phase_members_and_bad_lengths(tire):
    result = patch_sweep(tire, 60, [0.0, 0.204], (2,), phases=("in", "out"))
    assert 0 < result.shift_percent("symmetric", "out")[1, 0] < 2.0
    json.dumps(result.to_dict())
    with pytest.raises(ParameterError, match="lengths_m"):
        patch_sweep(tire, 60, [0.0, 0.9])


# ------------------------------------------------------------------ speed (Figs. 18-19)


def test_speed_sweep_at_rest_is_the_rest_analysis(tire):
    result = speed_sweep(tire, 60, [0.0, 15.0], patch_length_m=0.204, f_max_hz=200.0, nmax=6)
    # undeformed: the FDM frequencies of the mesh at rest, the same for n and -n
    low, _ = body_frequencies(tire, np.abs(result.orders), 0.0, n_elements=60)
    np.testing.assert_allclose(result.undeformed_in_phase_hz[0], low / (2 * np.pi), rtol=1e-12)
    # loaded: the complex modes at V = 0 are the real modes of the loaded tire
    rest = real_modes(build_model(tire, OperatingPoint(60, patch_length_m=0.204)), f_max_hz=200)
    rolling = result.loaded[0].frequencies_hz
    below = rest.frequencies_hz < 195.0
    np.testing.assert_allclose(rolling[: below.sum()], rest.frequencies_hz[below], rtol=1e-9)
    # at speed each undeformed pair splits by 2κΩ: backward (n > 0) falls, forward rises
    column = {int(n): j for j, n in enumerate(result.orders)}
    at_speed = result.undeformed_in_phase_hz[1]
    for n in range(1, 7):
        assert at_speed[column[n]] < result.undeformed_in_phase_hz[0, column[n]] < at_speed[
            column[-n]]
    json.dumps(result.to_dict())


def test_speed_sweep_refuses_a_loaded_sweep_past_the_critical_speed(tire):
    with pytest.raises(ParameterError, match="critical speed"):
        speed_sweep(tire, 100, [0.0, 50.0], patch_length_m=0.204)
    # the undeformed curves need no model and may go past it (negative ground frequencies)
    past = speed_sweep(tire, 100, [0.0, 50.0], patch_length_m=0.0)
    assert past.loaded is None


def test_dispersion_at_the_papers_spin_is_asymmetric(tire):
    result = dispersion_at_speed(tire, 60, patch_length_m=0.0, nmax=6)
    assert result.speed_m_s == pytest.approx(20 * np.pi * tire.R) == paper_speed_m_s(tire)
    curve = result.undeformed
    kappa = 60 / (2 * np.pi) * np.sin(curve.orders * 2 * np.pi / 60)  # FDM symbol of ∂θ
    mirror = curve.in_phase_hz[::-1]  # order -n
    np.testing.assert_allclose(mirror - curve.in_phase_hz,
                               2 * kappa * curve.spin_rad_s / (2 * np.pi), atol=1e-9)
    assert result.loaded is None


def test_progress_is_reported_once_per_step(tire):
    calls = []
    convergence_study(tire, (20, 40), range(3), progress=lambda done, total: calls.append(
        (done, total)))
    patch_sweep(tire, 40, [0.0, 0.1, 0.2], (2,), progress=lambda d, t: calls.append((d, t)))
    assert calls == [(1, 2), (2, 2), (1, 3), (2, 3), (3, 3)]
