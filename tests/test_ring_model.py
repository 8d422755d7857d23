"""The assembled FDM ring against the closed-form ring, and the contact patch."""

import numpy as np
import pytest

from tire_fmu.core import (
    OperatingPoint,
    TireParameters,
    analytic_modes,
    build_model,
    real_modes,
    undeformed,
)
from tire_fmu.core.contact import contact_zone, patch_weights
from tire_fmu.core.discretisation import Grid
from tire_fmu.core.io_model import build_io_model


@pytest.fixture(scope="module")
def tire():
    """The paper's tire (GL073A, its lumped sidewall): this module checks the paper's model."""
    return TireParameters(sidewall_max_order=0.0)

ORDERS = np.arange(0, 11)


def fdm_frequencies(tire, n_elements, orders=ORDERS):
    """FDM (in-phase, out-of-phase) frequency per order, read off the assembled model."""
    model = build_model(tire, OperatingPoint(n_elements=n_elements, patch_length_m=0.0))
    result = real_modes(model, f_max_hz=400.0)
    out = {}
    for phase in ("in", "out"):
        out[phase] = np.array([result.frequencies_hz[result.select(order=int(n), phase=phase)[0]]
                               for n in orders])
    return out


def test_analytic_roots_solve_eq12(tire):
    modes = analytic_modes(tire, ORDERS)
    a = tire.EI * ORDERS**4 / tire.R**4 + tire.inflation_pressure * tire.b * ORDERS**2 / tire.R \
        + tire.k_r1
    for hz in (modes.in_phase_hz, modes.out_of_phase_hz):
        w2 = (2 * np.pi * hz) ** 2
        det = (a - tire.rhoA * w2) * (tire.k_r1 + tire.k_r2 - tire.m_s * w2) - tire.k_r1**2
        assert np.all(np.abs(det) <= 1e-9 * a * (tire.k_r1 + tire.k_r2))
    assert np.all(modes.in_phase_ratio > 0) and np.all(modes.out_of_phase_ratio < 0)


def test_analytic_table_matches_the_design_reference(tire):
    # Reference values of the design brief (exact roots of eq. 12, default data).
    orders = [0, 1, 2, 3, 4, 5, 6, 8, 10, 12]
    ref_in = [53.41, 57.43, 67.95, 82.18, 97.91, 113.54, 127.67, 147.45, 156.77, 161.03]
    ref_out = [184.20, 184.48, 185.37, 187.03, 189.80, 194.23, 201.18, 225.64, 262.54, 306.11]
    modes = analytic_modes(tire, orders)
    np.testing.assert_allclose(modes.in_phase_hz, ref_in, atol=0.006)
    np.testing.assert_allclose(modes.out_of_phase_hz, ref_out, atol=0.006)


def test_fdm_converges_at_second_order_in_dtheta(tire):
    exact = analytic_modes(tire, ORDERS)
    coarse, fine = fdm_frequencies(tire, 100), fdm_frequencies(tire, 200)
    for phase, ref in (("in", exact.in_phase_hz), ("out", exact.out_of_phase_hz)):
        err_coarse = np.abs(coarse[phase] - ref)[1:]  # n = 0 is exact on any grid
        err_fine = np.abs(fine[phase] - ref)[1:]
        rate = np.log2(err_coarse / err_fine)
        np.testing.assert_allclose(rate, 2.0, atol=0.05)
    # n = 0 has no θ-derivatives: exact to rounding on every mesh
    assert coarse["in"][0] == pytest.approx(exact.in_phase_hz[0], rel=1e-12)


def test_fdm_at_400_elements_within_half_a_percent(tire):
    exact = analytic_modes(tire, ORDERS)
    fdm = fdm_frequencies(tire, 400)
    assert np.max(np.abs(fdm["in"] / exact.in_phase_hz - 1)) < 0.005
    assert np.max(np.abs(fdm["out"] / exact.out_of_phase_hz - 1)) < 0.005


def test_undeformed_modes_are_degenerate_pairs_with_clean_symmetry(tire):
    result = real_modes(build_model(tire, OperatingPoint(n_elements=60, patch_length_m=0.0)),
                        f_max_hz=150)
    for n in range(1, 6):
        pair = result.select(order=n, phase="in")
        assert len(pair) == 2
        assert result.frequencies_hz[pair[0]] == pytest.approx(result.frequencies_hz[pair[1]],
                                                               rel=1e-10)
    # in-phase: tread and sidewall move the same way
    i = result.select(order=3, phase="in")[0]
    assert result.tread(i) @ result.sidewall(i) > 0


def test_patch_splits_pairs_symmetric_member_rises_most(tire):
    loaded = real_modes(build_model(tire, OperatingPoint(n_elements=100, patch_length_m=0.204)),
                        f_max_hz=200)
    free = analytic_modes(tire, [2, 3, 4])
    free_fdm = fdm_frequencies(tire, 100, orders=[2, 3, 4])["in"]
    rises_sym = []
    for k, n in enumerate([2, 3, 4]):
        [sym] = loaded.select(order=n, phase="in", symmetry="symmetric")
        [anti] = loaded.select(order=n, phase="in", symmetry="antisymmetric")
        rise_sym = loaded.frequencies_hz[sym] / free_fdm[k] - 1
        rise_anti = loaded.frequencies_hz[anti] / free_fdm[k] - 1
        assert 0.09 <= rise_sym <= 0.13, (n, rise_sym)
        assert 0.01 <= rise_anti <= 0.03, (n, rise_anti)
        rises_sym.append(rise_sym)
        # the symmetric member is cos nθ-like: an antinode at the patch centre when free,
        # the antisymmetric one a node there (Kindt's "extr" and "0")
        assert abs(loaded.tread(anti)[0]) < 1e-12 * np.abs(loaded.tread(anti)).max() + 1e-15
        assert free.in_phase_hz[k] > 0
    assert rises_sym[2] < rises_sym[1]  # the stiffened member's rise falls off for higher n


@pytest.mark.parametrize("spacing_m", [1.0, 2.5e-3])
def test_patch_weights_are_fractional_and_sum_to_the_patch(tire, spacing_m):
    grid = Grid(100, tire.R)
    zone = contact_zone(grid, tire.k_cw, tire.beta, 0.6, spacing_m)
    for length in (0.0, 0.01, 0.05, 0.204, 0.333):
        weights = patch_weights(zone, length)
        assert np.all((weights >= 0) & (weights <= 1))
        assert weights.sum() * zone.point_arc_m == pytest.approx(length, abs=1e-12)
        np.testing.assert_array_equal(weights, weights[::-1])  # mirror-symmetric
    # the paper's 5 nodes: 5 node arcs (0.204 m is 1e-4 short of them: the end points partly)
    full = np.count_nonzero(patch_weights(zone, 0.204) > 0.99)
    assert 5 * zone.points_per_node - 2 <= full <= 5 * zone.points_per_node


def test_frequencies_vary_continuously_with_patch_length(tire):
    def symmetric_n2(length):
        r = real_modes(build_model(tire, OperatingPoint(n_elements=100, patch_length_m=length)),
                       f_max_hz=80)
        return r.frequencies_hz[r.select(order=2, phase="in", symmetry="symmetric")[0]]

    node = 2 * np.pi * tire.R / 100  # 4.08 cm
    # whole-node patches of 3 and 5 nodes: the staircase step a node-count patch would take
    staircase_step = symmetric_n2(5 * node) - symmetric_n2(3 * node)
    freqs = np.array([symmetric_n2(x) for x in np.linspace(3 * node, 5 * node, 17)])
    steps = np.diff(freqs)
    assert np.all(steps > 0)  # stiffer with every millimetre, no plateaus
    # A near-rigid k_cw makes a node bite hard as soon as it enters, so the curve has kinks
    # there, but no node-sized jumps: continuous at the entry, and each 2.5 mm step well
    # below the staircase step.
    assert steps.max() < 0.4 * staircase_step
    entry = 3 * node
    assert symmetric_n2(entry + 1e-4) - symmetric_n2(entry) < 0.05 * staircase_step


def test_vertical_stiffness_grows_with_patch_length(tire):
    lengths = [0.02, 0.05, 0.1, 0.2, 0.3, 0.4]
    k_v = [build_model(tire, OperatingPoint(patch_length_m=x)).static_vertical_stiffness_n_per_m
           for x in lengths]
    assert np.all(np.diff(k_v) > 0)
    assert 1e6 < k_v[3] < 3e6  # N/m: a plausible truck tire


@pytest.mark.parametrize("op", [dict(patch_length_m=0.25), dict(load_n=27_700.0),
                                dict(load_n=27_700.0, speed_m_s=15.0)])
def test_vertical_stiffness_is_the_rim_force_per_rim_travel(tire, op):
    model = build_model(tire, OperatingPoint(**op))
    dc = build_io_model(model).static_gain()  # outputs x [rim, road groups]
    rim_fz, contact_fz = dc[0, 0], dc[2, 0]
    assert -rim_fz == pytest.approx(model.patch.vertical_stiffness_n_per_m, rel=1e-9)
    assert contact_fz == pytest.approx(rim_fz, rel=1e-9)  # statics: what goes in comes out


@pytest.mark.parametrize("op", [dict(patch_length_m=0.204), dict(load_n=27_700.0),
                                dict(patch_length_m=0.204, speed_m_s=25.0),
                                dict(load_n=27_700.0, speed_m_s=25.0)])
def test_rim_and_road_moving_together_change_no_force(tire, op):
    model = build_model(tire, OperatingPoint(**op))
    dc = build_io_model(model).static_gain()
    together = dc[:, 0] + dc[:, 1:].sum(axis=1)  # rim and every road input up by 1 m
    scale = np.abs(dc[:3]).max()
    assert np.abs(together[:3]).max() < 1e-9 * scale  # rim_Fz, rim_Fx, contact_Fz
    assert abs(together[3]) < 1e-12  # the tread moves with the rim: no compression
    # whereas an absolute coupling (K on u, rim ignored) would feel a spurious spring
    t = model.translation
    assert t @ (model.structure.stiffness @ t) > 1e5


def test_sparse_shift_invert_matches_dense(tire):
    model = build_model(tire, OperatingPoint(n_elements=200, patch_length_m=0.204))
    dense = real_modes(model, f_max_hz=250, method="dense")
    sparse = real_modes(model, f_max_hz=250, method="sparse")
    np.testing.assert_allclose(sparse.frequencies_hz, dense.frequencies_hz, rtol=1e-9)
    assert [m.order for m in sparse.modes] == [m.order for m in dense.modes]


def test_damping_ratio_is_proportional_damping(tire):
    model = build_model(tire, OperatingPoint(n_elements=80, patch_length_m=0.204))
    result = real_modes(model, f_max_hz=300)
    omega = 2 * np.pi * result.frequencies_hz
    np.testing.assert_allclose(result.damping_ratios,
                               tire.alpha / (2 * omega) + tire.beta * omega / 2, rtol=1e-9)


def test_undeformed_helper_drops_the_patch(tire):
    model = build_model(tire, OperatingPoint(patch_length_m=0.2))
    bare = undeformed(model)
    assert bare.patch.length_m == 0 and bare.contact_stiffness.nnz == 0 or \
        not bare.contact_stiffness.diagonal().any()


def test_auto_solver_choice_gives_the_dense_modes(tire):
    """auto takes ARPACK only for a few modes of a large class; both agree with LAPACK."""
    model = build_model(tire, OperatingPoint(n_elements=1280, patch_length_m=0.204))
    dense = real_modes(model, f_max_hz=110, method="dense")
    auto = real_modes(model, f_max_hz=110)  # a few modes per class of 1282 DOFs: ARPACK
    assert 5 <= len(dense.modes) < 30
    np.testing.assert_allclose(auto.frequencies_hz, dense.frequencies_hz, rtol=1e-9)
    assert [(m.order, m.phase, m.symmetry) for m in auto.modes] == \
        [(m.order, m.phase, m.symmetry) for m in dense.modes]


@pytest.mark.parametrize("shear", [0.0, 1e5])
def test_sidewall_elimination_gives_the_full_class_problem(shear):
    """Without sidewall shear the sidewall is eliminated exactly (half-size eigenproblem);
    with it the structure is absent and the full problem is solved: same modes either way."""
    from tire_fmu.core.modal import symmetry_bases, two_level_eigenpairs

    tire = TireParameters(sidewall_shear=shear, sidewall_max_order=0.0)
    model = build_model(tire, OperatingPoint(n_elements=80, patch_length_m=0.204))
    basis = symmetry_bases(model.grid)["symmetric"]
    k = (basis.T @ model.stiffness @ basis).tocsr()
    m = basis.multiply(basis).T @ model.mass.diagonal()
    pairs = two_level_eigenpairs(k, m, 30)
    assert (pairs is None) == (shear > 0)
    auto = real_modes(model, f_max_hz=300)
    dense = real_modes(model, f_max_hz=300, method="dense")
    np.testing.assert_allclose(auto.frequencies_hz, dense.frequencies_hz, rtol=1e-11)
    np.testing.assert_allclose(auto.damping_ratios, dense.damping_ratios, rtol=1e-9)
    assert [(x.order, x.phase, x.symmetry) for x in auto.modes] == \
        [(x.order, x.phase, x.symmetry) for x in dense.modes]
    overlap = np.abs(np.einsum("ij,ij->j", auto.shapes, model.mass @ dense.shapes))
    np.testing.assert_allclose(overlap, 1.0, atol=1e-8)
    if pairs is not None:  # the half-size pairs solve the full class problem
        omega2, shapes = pairs
        residual = k @ shapes - (m[:, None] * shapes) * omega2[None, :]
        assert np.abs(residual).max() < 1e-9 * np.abs(k).max()
        np.testing.assert_allclose(shapes.T @ (m[:, None] * shapes), np.eye(30), atol=1e-10)
