"""Reduced-order model: accuracy against the full model, static correction, balanced
truncation, exact stepping against scipy.signal, export round trips."""

import json
import zipfile

import numpy as np
import pytest

from tire_fmu.core import OperatingPoint, ParameterError, TireParameters, build_model
from tire_fmu.core.io_model import OUTPUTS as OUTPUT_NAMES
from tire_fmu.core.io_model import build_io_model, physical_input
from tire_fmu.core.modal_form import diagonalise, modal_frequency_response
from tire_fmu.core.reduction import (
    ReductionSettings,
    ReductionWarning,
    error_report,
    modal_decomposition,
    reduce,
    static_outputs,
)
from tire_fmu.core.stepping import DenseStepper, DiagonalStepper, phi_functions
from tire_fmu.model_files import (
    ModelFileError,
    load_mat,
    load_npz,
    save_mat,
    save_npz,
    state_space_matrices,
)


@pytest.fixture(scope="module")
def tire():
    """The paper's tire (GL073A, its lumped sidewall): this module checks the paper's model."""
    return TireParameters(sidewall_max_order=0.0)


PAPER_SPEED = 20 * np.pi * 0.65


@pytest.fixture(scope="module")
def rest_model(tire):
    return build_model(tire, OperatingPoint(n_elements=100, patch_length_m=0.204))


@pytest.fixture(scope="module")
def rolling_model(tire):
    return build_model(tire, OperatingPoint(n_elements=100, patch_length_m=0.204,
                                            speed_m_s=PAPER_SPEED))


@pytest.fixture(scope="module")
def small_models(tire):
    return {v: build_model(tire, OperatingPoint(n_elements=48, patch_length_m=0.204,
                                                speed_m_s=v)) for v in (0.0, 15.0)}


@pytest.mark.parametrize("which", ["rest_model", "rolling_model"])
def test_default_settings_reach_one_percent_with_fewer_states(which, request):
    model = request.getfixturevalue(which)
    reduced = reduce(model)
    pairs = reduced.report.per_pair
    assert pairs["road->rim_Fz"] <= 0.01
    assert pairs["rim->rim_Fz"] <= 0.01
    assert reduced.n_states < 4 * model.n_elements  # the full model has 4N states
    assert reduced.report.band_hz == (1.0, 300.0)


def test_keeping_every_mode_reproduces_the_full_model(small_models):
    for speed, model in small_models.items():
        reduced = reduce(model, ReductionSettings(target_error=0.0, f_max_hz=1e6),
                         report="exact")
        # at rest the antisymmetric class (one DOF per mirror pair of nodes, tread and
        # sidewall) is unreachable from the symmetric inputs and left out
        mirror_pairs = (model.n_elements - 2) // 2
        expected = 4 * model.n_elements - (4 * mirror_pairs if speed == 0.0 else 0)
        assert reduced.n_states == expected
        assert reduced.report.reference == "exact"
        assert reduced.report.max_relative_error < 1e-8


@pytest.mark.parametrize("speed", [0.0, 15.0])
def test_a_tied_sidewall_reduces_exactly_through_the_general_eigenproblem(speed):
    """The default tire's tie has no damper, so its damping is not proportional: at rest too
    the reduction takes the general eigenproblem, keeping both mirror classes, and with every
    mode kept it is the full model."""
    tied = TireParameters()  # GL073A_tied
    assert tied.sidewall_max_order == 8.0
    model = build_model(tied, OperatingPoint(n_elements=48, patch_length_m=0.204,
                                             speed_m_s=speed))
    assert model.sidewall_tied
    reduced = reduce(model, ReductionSettings(target_error=0.0, f_max_hz=1e6), report="exact")
    assert reduced.n_states == 4 * model.n_elements
    assert reduced.report.max_relative_error < 1e-8


def test_rest_fast_path_equals_the_general_eigensolver(small_models):
    io = build_io_model(small_models[0.0])
    fast = modal_decomposition(io)
    general = diagonalise(io.a.toarray(), io.b, io.c)
    omega = 2 * np.pi * np.array([3.0, 60.0, 170.0, 290.0])
    r = io.physical_input("road", omega)
    h_fast = modal_frequency_response(fast.eigenvalues, fast.b, fast.c, io.d, io.e, r, omega)
    h_gen = modal_frequency_response(general.eigenvalues, general.b, general.c, io.d, io.e,
                                     r, omega)
    # the fast path keeps the symmetric class only: its modes are among the general ones
    gap = np.abs(fast.eigenvalues[:, None] - general.eigenvalues[None, :]).min(axis=1)
    assert np.all(gap <= 1e-10 * np.abs(fast.eigenvalues))
    assert fast.eigenvalues.size == general.eigenvalues.size - (48 - 2)  # one per mirror pair
    np.testing.assert_allclose(h_fast, h_gen, rtol=1e-9, atol=1e-9 * np.abs(h_gen).max())


def test_full_frequency_response_second_order_equals_state_space(small_models):
    io = build_io_model(small_models[15.0])
    freqs = np.array([2.0, 45.0, 210.0])
    h = io.frequency_response("road", freqs)
    a = io.a.toarray()
    for k, f in enumerate(freqs):
        w = 2 * np.pi * f
        r = io.physical_input("road", [w])[:, 0]
        x = np.linalg.solve(1j * w * np.eye(a.shape[0]) - a, io.b @ r)
        np.testing.assert_allclose(io.c @ x + io.d @ r + 1j * w * io.e @ r, h[:, k],
                                   rtol=1e-9, atol=1e-6)


def test_static_correction_makes_the_dc_gain_exact(rest_model):
    # a harsh frequency cut, so that much is dropped; reduce warns that it costs accuracy
    settings = ReductionSettings(f_max_hz=150.0, target_error=0.0)
    with pytest.warns(ReductionWarning, match="frequency cut at 150 Hz drops modes"):
        corrected = reduce(rest_model, settings)
    with pytest.warns(ReductionWarning):
        plain = reduce(rest_model, ReductionSettings(f_max_hz=150.0, target_error=0.0,
                                                     static_correction=False))
    assert max(corrected.report.dc_relative_error.values()) < 1e-9
    assert max(plain.report.dc_relative_error.values()) > 1e-3
    # the static rim stiffness, through the reduced model, is the model's own
    io = build_io_model(rest_model)
    dc = corrected.d + np.real(-(corrected.c / corrected.eigenvalues) @ corrected.b)
    assert -dc[0, 0] == pytest.approx(rest_model.static_vertical_stiffness_n_per_m, rel=1e-9)
    # and rim + road together: no static force change, full and reduced
    np.testing.assert_allclose(io.static_gain()[:3].sum(axis=1), 0.0, atol=1e-6)
    np.testing.assert_allclose(dc[:3].sum(axis=1), 0.0, atol=1e-6)


def test_static_outputs_are_the_equilibrium(rest_model, rolling_model):
    for model in (rest_model, rolling_model):
        static = static_outputs(model)
        assert static["rim_Fz"] == pytest.approx(model.patch.load_n, rel=1e-9)
        assert static["contact_Fz"] == pytest.approx(model.patch.load_n, rel=1e-9)
        # the tread's compression at the patch centre: the chord deflection less the
        # contact spring's give (a fraction of a millimetre)
        assert static["deflection"] == pytest.approx(model.patch.deflection_m, abs=2e-4)
        assert static["deflection"] < model.patch.deflection_m
    assert static_outputs(rolling_model)["rim_Fx"] < 0  # rolling resistance


@pytest.mark.parametrize("speed,counts", [(0.0, (20, 30, 40)), (15.0, (30, 60, 100))])
def test_balanced_truncation_is_stable_and_converges(small_models, speed, counts):
    errors = []
    for states in counts:
        reduced = reduce(small_models[speed], ReductionSettings(method="balanced",
                                                                 n_states=states))
        assert reduced.n_states == states
        assert np.all(reduced.eigenvalues.real < 0)
        assert max(reduced.report.dc_relative_error.values()) < 1e-6  # residualised: matchdc
        errors.append(reduced.report.max_relative_error)
    assert errors[2] < errors[1] < errors[0]
    assert errors[2] < 0.01


@pytest.mark.parametrize("which", ["rest_model", "rolling_model"])
def test_balanced_meets_its_target_with_far_fewer_states_than_modal(which, request):
    model = request.getfixturevalue(which)
    modal = reduce(model)
    balanced = reduce(model, ReductionSettings(method="balanced", target_error=5e-3))
    assert balanced.report.max_relative_error <= 5e-3
    assert balanced.n_states < 0.6 * modal.n_states
    fewer = reduce(model, ReductionSettings(method="balanced", n_states=balanced.n_states - 2))
    assert fewer.report.max_relative_error > 5e-3  # the fewest states that meet it


@pytest.fixture(scope="module")
def loaded_models(tire):
    """N = 100 at the default load, at rest and rolling (the speeds of issue 20)."""
    return {v: build_model(tire, OperatingPoint(n_elements=100, speed_m_s=v))
            for v in (0.0, 10.0)}


def _sparse_solve_responses(model, freqs_hz):
    """The full model's FRFs, one sparse solve of the assembled second-order model per
    frequency, (K - ω²M + iωD) U = (B_z + iωB_v) r, written here apart from the library's
    solvers: {(input, output row): H}, leaving out responses zero by symmetry (rim_Fx at rest),
    which have no relative error."""
    import scipy.sparse.linalg as spla

    io = build_io_model(model)
    omega = 2 * np.pi * np.asarray(freqs_hz)
    out = {}
    for name in ("rim", "road"):
        r = io.physical_input(name, omega)
        h = np.empty((len(OUTPUT_NAMES), omega.size), complex)
        for i, w in enumerate(omega):
            dynamic = (model.stiffness - w * w * model.mass + 1j * w * model.damping).tocsc()
            u = spla.spsolve(dynamic, (io.b_disp + 1j * w * io.b_vel) @ r[:, i])
            h[:, i] = ((io.out_disp + 1j * w * io.out_vel) @ u
                       + (io.d_disp + 1j * w * io.e) @ r[:, i])
        out.update({(name, row): h[row] for row in range(len(OUTPUT_NAMES))})
    largest_force = max(np.abs(h).max() for (_, row), h in out.items()
                        if OUTPUT_NAMES[row] != "deflection")
    return {key: h for key, h in out.items()
            if OUTPUT_NAMES[key[1]] == "deflection" or np.abs(h).max() > 1e-8 * largest_force}


def _max_relative_error(eigenvalues, b, c, d, e, reduced, exact, freqs_hz) -> float:
    omega = 2 * np.pi * np.asarray(freqs_hz)
    worst = 0.0
    for (name, row), h in exact.items():
        r = physical_input(name, reduced.road_windows, omega)
        h_red = modal_frequency_response(eigenvalues, b, c, d, e, r, omega)[row]
        worst = max(worst, float(np.max(np.abs(h_red - h) / np.abs(h))))
    return worst


#: The modal and the exact full responses agree to about 1e-7 at speed (§9.3): the margin
#: by which an error checked against one may differ against the other.
REFERENCE_GAP = 1e-6


@pytest.mark.parametrize("speed", [0.0, 10.0])
def test_modal_selection_meets_its_target_and_no_mode_it_keeps_can_go(loaded_models, speed):
    """The kept modes with their static correction meet target_error against an independent
    sparse solve of the full model, and dropping any one of them (its static part restored)
    breaks it: the selection keeps no more modes than it needs."""
    target = 0.01
    model = loaded_models[speed]
    settings = ReductionSettings(target_error=target)
    reduced = reduce(model, settings)
    freqs = settings.error_frequencies_hz()
    exact = _sparse_solve_responses(model, freqs)
    lam, b, c, d, e = reduced.eigenvalues, reduced.b, reduced.c, reduced.d, reduced.e
    error = _max_relative_error(lam, b, c, d, e, reduced, exact, freqs)
    assert error <= target + REFERENCE_GAP
    assert error == pytest.approx(reduced.report.max_relative_error, abs=REFERENCE_GAP)
    assert reduced.n_states < 4 * model.n_elements
    drop_errors = []
    for k in range(reduced.n_modes):
        keep = np.arange(reduced.n_modes) != k
        d_k = d + np.real(-c[:, k:k + 1] * b[k:k + 1] / lam[k])  # its DC stays exact
        drop_errors.append(_max_relative_error(lam[keep], b[keep], c[:, keep], d_k, e,
                                               reduced, exact, freqs))
    assert min(drop_errors) > target + REFERENCE_GAP


def _former_modal_states(model, target) -> int:
    """States the former selection kept: least contributing modes dropped while the sum of
    the magnitudes of their relative terms (a triangle-inequality bound) stayed in budget."""
    from tire_fmu.core.reduction import full_responses, relative_contributions

    io = build_io_model(model)
    settings = ReductionSettings()
    decomp = modal_decomposition(io)
    shares = relative_contributions(decomp, io, settings,
                                    full_responses(io, settings.error_frequencies_hz(), decomp))
    magnitude = np.abs(shares)
    order = np.argsort(magnitude.max(axis=(0, 2)), kind="stable")
    bound = np.cumsum(magnitude[:, order, :], axis=1).max(axis=(0, 2))
    kept = order[int(np.searchsorted(bound, target, side="right")):]
    return int(np.sum(np.where(decomp.eigenvalues[kept].imag != 0, 2, 1)))


@pytest.mark.parametrize("n_elements, at_most", [(100, 0.98), (200, 0.8)])
def test_modal_selection_keeps_fewer_states_rolling_than_the_summed_bound(tire, n_elements,
                                                                          at_most):
    """At 10 m/s the split pairs' terms cancel, so the former bound (sum of magnitudes) kept
    nearly everything; the exact error lets far more go, increasingly so on finer meshes."""
    model = build_model(tire, OperatingPoint(n_elements=n_elements, speed_m_s=10.0))
    reduced = reduce(model, ReductionSettings(target_error=0.01))
    assert reduced.report.max_relative_error <= 0.01
    assert reduced.n_states < at_most * _former_modal_states(model, 0.01)


def test_n_modes_keeps_the_most_dominant_of_the_selection(loaded_models):
    model = loaded_models[10.0]
    chosen = reduce(model, ReductionSettings(target_error=0.01), report=False)
    capped = reduce(model, ReductionSettings(target_error=0.01, n_modes=20))
    assert capped.n_modes == 20
    assert np.all(np.isin(capped.eigenvalues, chosen.eigenvalues))
    assert capped.report.max_relative_error > 0.01  # the cap wins over the target


def test_the_former_contribution_threshold_is_refused_naming_target_error():
    with pytest.raises(ParameterError) as caught:
        ReductionSettings(contribution_threshold=0.01, n_modes=0)
    assert len(caught.value.problems) == 2
    message = str(caught.value)
    assert "contribution_threshold = 0.01" in message
    assert "give target_error = 0.01" in message


def test_settings_report_every_problem():
    with pytest.raises(ParameterError) as caught:
        ReductionSettings(method="pod", f_max_hz=-1, target_error=2, n_modes=0)
    assert len(caught.value.problems) == 4


def test_phi_functions_are_continuous_across_the_series_switch():
    z = np.array([1e-3 * (1 - 1e-9), 1e-3 * (1 + 1e-9)]) * np.exp(0.3j)
    p1, p2 = phi_functions(z)
    assert abs(p1[0] - p1[1]) < 1e-11 and abs(p2[0] - p2[1]) < 1e-11
    big = np.array([-2.0 + 5j])
    q1, q2 = phi_functions(big)
    assert q1[0] == pytest.approx((np.exp(big[0]) - 1) / big[0])
    assert q2[0] == pytest.approx((np.exp(big[0]) - 1 - big[0]) / big[0] ** 2)


def test_diagonal_and_matrix_exponential_steps_agree(small_models):
    reduced = reduce(small_models[15.0], ReductionSettings(target_error=0.05),
                     report=False)
    diag, dense = DiagonalStepper.from_reduced(reduced), DenseStepper.from_reduced(reduced)
    rng = np.random.default_rng(1)
    q = np.zeros(reduced.n_modes, complex)
    x = np.zeros(dense.a.shape[0])
    for h in (1e-4, 3.7e-4, 1e-3, 1e-4):
        u = rng.normal(size=2 * reduced.n_inputs) * 1e-3
        q, x = diag.step(q, u, h), dense.step(x, u, h)
        y_diag, y_dense = diag.output(q, u), dense.output(x, u)
        np.testing.assert_allclose(y_diag, y_dense, rtol=1e-9, atol=1e-9 * np.abs(y_dense).max())


def test_npz_round_trip_is_bit_exact_and_rejects_tampering(small_models, tmp_path):
    reduced = reduce(small_models[15.0])
    path = save_npz(reduced, tmp_path / "tire.npz")
    back = load_npz(path)
    for name in ("eigenvalues", "b", "c", "d", "e"):
        assert np.array_equal(getattr(back, name), getattr(reduced, name))
        assert getattr(back, name).dtype == getattr(reduced, name).dtype
    assert back.static_outputs == reduced.static_outputs
    assert back.settings == reduced.settings
    assert back.report == reduced.report
    # tampered: one coefficient changed after export
    with np.load(path) as archive:
        contents = {name: archive[name] for name in archive.files}
    contents["d"] = contents["d"].copy()
    contents["d"][0, 0] *= 1.0001
    np.savez(tmp_path / "tampered.npz", **contents)
    with pytest.raises(ModelFileError, match="'d' does not match its checksum"):
        load_npz(tmp_path / "tampered.npz")
    # incomplete: an array missing
    del contents["e"]
    np.savez(tmp_path / "incomplete.npz", **contents)
    with pytest.raises(ModelFileError, match=r"missing \['e'\]"):
        load_npz(tmp_path / "incomplete.npz")
    # truncated file
    (tmp_path / "cut.npz").write_bytes(path.read_bytes()[:500])
    with pytest.raises(ModelFileError, match="not a readable"):
        load_npz(tmp_path / "cut.npz")
    # metadata readable by anyone: plain JSON inside the archive
    with zipfile.ZipFile(path) as archive:
        assert "metadata.npy" in archive.namelist()
    meta = json.loads(str(np.load(path)["metadata"]))
    assert meta["model"]["operating_point"]["speed_m_s"] == 15.0


def _forged(path, tmp_path, edit, arrays=None):
    """The export at ``path`` with its metadata edited by ``edit`` and its arrays replaced
    by ``arrays``, every checksum recomputed: a file made to look right."""
    from tire_fmu.model_files import _checksum, _metadata_checksum

    with np.load(path) as archive:
        contents = {name: archive[name] for name in archive.files}
    meta = json.loads(str(contents.pop("metadata")))
    del meta["checksums"]
    edit(meta)
    contents.update(arrays or {})
    checksums = {name: _checksum(array) for name, array in contents.items()}
    checksums["metadata"] = _metadata_checksum(meta)
    forged = tmp_path / "forged.npz"
    np.savez(forged, metadata=np.array(json.dumps({**meta, "checksums": checksums})),
             **contents)
    return forged


def test_npz_metadata_is_under_the_checksum_too(small_models, tmp_path):
    path = save_npz(reduce(small_models[0.0], report=False), tmp_path / "tire.npz")
    with np.load(path) as archive:
        contents = {name: archive[name] for name in archive.files}
    meta = json.loads(str(contents["metadata"]))
    meta["static_outputs"]["rim_Fz"] = 1e6  # loaded silently before: rim_Fz off by 972 kN
    contents["metadata"] = np.array(json.dumps(meta))
    np.savez(tmp_path / "tampered.npz", **contents)
    with pytest.raises(ModelFileError, match="the metadata does not match its checksum"):
        load_npz(tmp_path / "tampered.npz")


def _delete(key):
    return lambda meta: meta.pop(key)


def _assign(key, value):
    return lambda meta: meta.__setitem__(key, value)


@pytest.mark.parametrize("edit, arrays, message", [
    (_delete("settings"), None, "metadata 'settings' is NoneType, must be dict"),
    (_assign("static_outputs", "x"), None, "metadata 'static_outputs' is str"),
    (lambda m: m["static_outputs"].pop("rim_Fz"), None, "static_outputs"),
    (lambda m: m["static_outputs"].__setitem__("rim_Fz", "heavy"), None, "static_outputs"),
    (_assign("outputs", ["rim_Fz"]), None, "outputs ['rim_Fz']"),
    (_assign("report", 3), None, "metadata 'report' is int"),
    (lambda m: m["settings"].__setitem__("f_max_hz", "high"), None, "settings or report"),
    (lambda m: m.__setitem__("format", "tire_fmu.reduced-model/1"), None, "export it again"),
    (lambda m: None, {"d": np.zeros((4, 3))}, "'d' has 3 along 'm'"),
    (lambda m: None, {"b": np.zeros((3, 3))}, "array 'b' is float64"),
])
def test_forged_npz_parts_are_refused_naming_what_is_wrong(small_models, tmp_path, edit,
                                                          arrays, message):
    path = save_npz(reduce(small_models[0.0], report=False), tmp_path / "tire.npz")
    with pytest.raises(ModelFileError) as caught:
        load_npz(_forged(path, tmp_path, edit, arrays))
    assert message in str(caught.value)


def test_a_file_from_before_target_error_loads_with_its_modal_budget(small_models, tmp_path):
    """Files written before target_error applied to modal truncation hold the modal budget
    as contribution_threshold (and target_error as balanced truncation's)."""
    path = save_npz(reduce(small_models[0.0], report=False), tmp_path / "tire.npz")

    def former(meta):
        meta["settings"]["contribution_threshold"] = 0.02

    assert load_npz(_forged(path, tmp_path, former)).settings.target_error == 0.02


def test_non_finite_arrays_are_refused(small_models, tmp_path):
    reduced = reduce(small_models[0.0], report=False)
    path = save_npz(reduced, tmp_path / "tire.npz")
    d = reduced.d.copy()
    d[0, 0] = np.nan
    with pytest.raises(ModelFileError, match="'d' holds values that are not finite"):
        load_npz(_forged(path, tmp_path, lambda m: None, {"d": d}))


def test_mat_round_trip_is_bit_exact(small_models, tmp_path):
    reduced = reduce(small_models[0.0])
    back = load_mat(save_mat(reduced, tmp_path / "tire.mat"))
    for key, matrix in state_space_matrices(reduced).items():
        assert np.array_equal(back[key], matrix)
    assert back["metadata"]["static_outputs"] == reduced.static_outputs
    # the real form has the same transfer function as the modal form
    a, b, c, d = (back[k] for k in "ABCD")
    w = 2 * np.pi * 50.0
    m = reduced.n_inputs
    r = np.r_[np.ones(m), 1j * w * np.ones(m)]
    y_real = c @ np.linalg.solve(1j * w * np.eye(a.shape[0]) - a, b @ r) + d @ r
    y_modal = reduced.frequency_response(np.ones((m, 1)), np.array([w]))[:, 0]
    np.testing.assert_allclose(y_real, y_modal, rtol=1e-9)
    with pytest.raises(ModelFileError):
        load_mat(tmp_path / "absent.mat")


def test_python_control_state_space(small_models):
    control = pytest.importorskip("control")
    from tire_fmu.model_files import to_control

    reduced = reduce(small_models[0.0])
    system = to_control(reduced)
    assert isinstance(system, control.StateSpace)
    assert system.nstates == reduced.n_states
    assert system.output_labels == list(OUTPUT_NAMES)
    dc = control.dcgain(system)
    assert dc[0, 0] == pytest.approx(-small_models[0.0].static_vertical_stiffness_n_per_m,
                                     rel=1e-9)


def _random_modal_model(rng, complex_modes=12, real_modes=3, inputs=3, outputs=4):
    lam = np.r_[-rng.uniform(0.5, 20, complex_modes) + 1j * rng.uniform(10, 400, complex_modes),
                -rng.uniform(50, 500, real_modes)]
    b = rng.normal(size=(lam.size, inputs)) + 1j * rng.normal(size=(lam.size, inputs))
    c = rng.normal(size=(outputs, lam.size)) + 1j * rng.normal(size=(outputs, lam.size))
    b[complex_modes:] = b[complex_modes:].real
    c[:, complex_modes:] = c[:, complex_modes:].real
    return lam, b, c


def test_cauchy_gramians_equal_bartels_stewart():
    from tire_fmu.core.balanced import (
        dense_gramians,
        real_gramian,
        real_observability_gramian,
    )
    from tire_fmu.core.modal_form import real_block_form

    lam, b, c = _random_modal_model(np.random.default_rng(3))
    a_r, b_r, c_r, _, _ = real_block_form(lam, b, c, np.zeros((4, 3)), np.zeros((4, 3)))
    p_ref, q_ref = dense_gramians(a_r, b_r, c_r)
    np.testing.assert_allclose(real_gramian(lam, b), p_ref, rtol=0,
                               atol=1e-12 * np.abs(p_ref).max())
    np.testing.assert_allclose(real_observability_gramian(lam, c), q_ref, rtol=0,
                               atol=1e-12 * np.abs(q_ref).max())


@pytest.mark.parametrize("speed", [0.0, 15.0])
def test_balanced_low_rank_path_equals_the_dense_lyapunov_path(small_models, speed):
    from tire_fmu.core.balanced import BalancedRealization

    io = build_io_model(small_models[speed])
    decomp = modal_decomposition(io)
    d = io.d + (io.static_gain() - io.d
                - np.real(-(decomp.c / decomp.eigenvalues) @ decomp.b))
    weight = np.array([1e-6, 1e-6, 1e-6, 1e3])
    fast, dense = (BalancedRealization(decomp.eigenvalues, decomp.b, decomp.c, d, weight, True,
                                       gramians=g) for g in ("cauchy", "dense"))
    top = 30
    np.testing.assert_allclose(fast.hankel_singular_values[:top],
                               dense.hankel_singular_values[:top], rtol=1e-7)
    omega = 2 * np.pi * np.geomspace(1, 300, 40)
    r = io.physical_input("road", omega)
    for states in (12, 30):
        h_fast, h_dense = (modal_frequency_response(*real.truncate(states)[:3],
                                                    real.truncate(states)[3], io.e, r, omega)
                           for real in (fast, dense))
        np.testing.assert_allclose(h_fast, h_dense, rtol=0, atol=1e-6 * np.abs(h_dense).max())


@pytest.mark.parametrize("speed,tolerance", [(0.0, 1e-11), (15.0, 1e-7)])
def test_modal_full_responses_equal_the_exact_ones(small_models, speed, tolerance):
    from tire_fmu.core.reduction import full_responses

    io = build_io_model(small_models[speed])
    freqs = np.geomspace(1.0, 300.0, 60)
    exact = full_responses(io, freqs)
    modal = full_responses(io, freqs, modal_decomposition(io))
    assert modal.keys() == exact.keys()
    for key, h in exact.items():
        np.testing.assert_allclose(modal[key], h, rtol=tolerance, atol=0, err_msg=str(key))


def test_exact_responses_equal_the_one_input_solver(small_models):
    from tire_fmu.core.reduction import exact_frequency_responses

    io = build_io_model(small_models[15.0])
    freqs = np.array([2.0, 80.0, 250.0])
    both = exact_frequency_responses(io, freqs)
    for name in ("rim", "road"):
        np.testing.assert_allclose(both[name], io.frequency_response(name, freqs), rtol=1e-12)


def test_report_false_solves_no_full_model_frequency_response(small_models, monkeypatch):
    import tire_fmu.core.reduction as reduction

    def refuse(*args, **kwargs):
        raise AssertionError("the exact full-model responses were computed")

    monkeypatch.setattr(reduction, "exact_frequency_responses", refuse)
    for method in ("modal", "balanced"):
        reduced = reduce(small_models[15.0], ReductionSettings(method=method), report=False)
        assert reduced.report is None
    assert reduce(small_models[0.0]).report.reference == "modal"
    with pytest.raises(AssertionError, match="exact full-model"):
        reduce(small_models[0.0], report="exact")


def test_modal_and_exact_reports_agree(small_models):
    for model in small_models.values():
        modal = reduce(model)
        exact = error_report(modal, build_io_model(model))
        assert exact.reference == "exact"
        # (these small models keep nearly every mode: errors near 1e-10 are rounding, whose
        # two computations agree only in size)
        assert exact.max_relative_error == pytest.approx(modal.report.max_relative_error,
                                                         rel=1e-4, abs=1e-9)
        assert exact.per_pair.keys() == modal.report.per_pair.keys()


def test_reduction_record_is_typed_frozen_and_survives_a_file(small_models, tmp_path):
    from dataclasses import FrozenInstanceError

    model = small_models[15.0]
    reduced = reduce(model, report=False)
    record = reduced.metadata
    assert record.tire == model.tire
    assert record.operating_point.speed_m_s == 15.0
    assert record.operating_point.patch_points == model.patch.contact_points.size
    assert record.operating_point.points_per_node == model.patch.zone.points_per_node
    assert record.full_states == 4 * model.n_elements
    assert record.build_seconds > 0
    with pytest.raises(FrozenInstanceError):
        record.build_seconds = 0.0
    assert load_npz(save_npz(reduced, tmp_path / "m.npz")).metadata == record


def test_rest_decomposition_without_mirror_symmetry_solves_every_dof(small_models):
    """A contact stiffer on one side of the centre breaks the mirror symmetry: the fast path
    must then take every DOF (one problem), and still equal the general eigensolver."""
    from dataclasses import replace

    model = small_models[0.0]
    patch = model.patch
    weights = patch.weights.copy()
    weights[patch.zone.point_theta > 0] *= 1.5  # the θ > 0 side only
    lopsided = replace(model, patch=replace(patch, weights=weights))
    stiffness = lopsided.contact_stiffness.diagonal()[:model.n_elements]  # on the tread
    assert not np.allclose(stiffness, stiffness[model.grid.mirror_index])
    io = build_io_model(lopsided)
    fast, general = modal_decomposition(io), diagonalise(io.a.toarray(), io.b, io.c)
    assert fast.eigenvalues.size == general.eigenvalues.size == 2 * model.n_elements
    omega = 2 * np.pi * np.array([5.0, 90.0, 250.0])
    r = io.physical_input("road", omega)
    h_fast, h_gen = (modal_frequency_response(f.eigenvalues, f.b, f.c, io.d, io.e, r, omega)
                     for f in (fast, general))
    np.testing.assert_allclose(h_fast, h_gen, rtol=1e-9, atol=1e-9 * np.abs(h_gen).max())
