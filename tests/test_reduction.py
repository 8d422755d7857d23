"""Reduced-order model: accuracy against the full model, static correction, balanced
truncation, exact stepping against scipy.signal, export round trips."""

import json
import zipfile

import numpy as np
import pytest
import scipy.signal as ss

from tire_fmu.core import OperatingPoint, ParameterError, build_model
from tire_fmu.core.export import (
    ModelFileError,
    load_mat,
    load_npz,
    save_mat,
    save_npz,
    state_space_matrices,
)
from tire_fmu.core.io_model import build_io_model
from tire_fmu.core.modal_form import diagonalise, modal_frequency_response
from tire_fmu.core.reduction import (
    ReductionSettings,
    ReductionWarning,
    modal_decomposition,
    reduce,
    static_outputs,
)
from tire_fmu.core.simulation import OUTPUT_NAMES, StepError, TireSimulator
from tire_fmu.core.stepping import DenseStepper, DiagonalStepper, phi_functions

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
    for model in small_models.values():
        reduced = reduce(model, ReductionSettings(contribution_threshold=0.0, f_max_hz=1e6))
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
    np.testing.assert_allclose(np.sort_complex(fast.eigenvalues),
                               np.sort_complex(general.eigenvalues), rtol=1e-10)
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
    settings = ReductionSettings(f_max_hz=150.0, contribution_threshold=0.0)
    with pytest.warns(ReductionWarning, match="frequency cut at 150 Hz drops modes"):
        corrected = reduce(rest_model, settings)
    with pytest.warns(ReductionWarning):
        plain = reduce(rest_model, ReductionSettings(f_max_hz=150.0, contribution_threshold=0.0,
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


def test_settings_report_every_problem():
    with pytest.raises(ParameterError) as caught:
        ReductionSettings(method="pod", f_max_hz=-1, contribution_threshold=2, n_modes=0)
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
    reduced = reduce(small_models[15.0], ReductionSettings(contribution_threshold=0.05),
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


@pytest.mark.parametrize("speed", [0.0, 15.0])
def test_variable_steps_equal_fixed_steps_where_they_coincide(small_models, speed):
    """Ramped inputs are what a step integrates exactly, so any step sequence reaching the
    same time gives the same state. At speed the road is only known at the communication
    points and read back through the delay line, so there the road is held (a level road
    reads back exactly) while the rim ramps."""
    reduced = reduce(small_models[speed], report=False)
    slope = 2e-3  # m/s
    road_slope = slope if speed == 0.0 else 0.0

    def run(steps):
        sim = TireSimulator(reduced)
        for h in steps:
            t = sim.time
            sim.step(h, 0.3 * slope * t, 0.3 * slope, 1e-3 + road_slope * t, road_slope)
        return sim

    fixed = run([1e-3] * 12)
    variable = run([1e-3, 2e-3, 4e-3, 5e-4, 5e-4, 2e-3, 2e-3])
    assert variable.time == pytest.approx(fixed.time, abs=1e-15)
    np.testing.assert_allclose(variable.outputs, fixed.outputs, rtol=1e-10)
    np.testing.assert_allclose(variable.q, fixed.q, rtol=1e-8, atol=1e-14)


def _simulate(reduced, t, z, vz):
    sim = TireSimulator(reduced)
    out = [sim.outputs.copy()]
    for k in range(t.size - 1):
        out.append(sim.step(t[k + 1] - t[k], 0.0, 0.0, z[k], vz[k]).copy())
    static = np.array([reduced.static_outputs[n] for n in OUTPUT_NAMES])
    return np.array(out) - static


@pytest.mark.parametrize("signal", ["step", "sweep"])
def test_stepping_matches_scipy_signal_on_the_full_model_at_rest(small_models, signal):
    model = small_models[0.0]
    reduced = reduce(model)
    io = build_io_model(model)
    h = 1e-4
    t = np.arange(0.0, 0.25, h)
    if signal == "step":
        z = np.where(t >= 0.01, 1e-3, 0.0)
    else:
        z = 1e-3 * ss.chirp(t, 2.0, t[-1], 300.0, method="logarithmic", phi=-90)
    vz = np.r_[np.diff(z) / h, 0.0]  # secant slopes: the ramps lsim's linear hold also sees
    ours = _simulate(reduced, t, z, vz)
    inputs = np.column_stack([np.zeros_like(z), z])
    _, full, _ = ss.lsim(ss.StateSpace(io.a.toarray(), io.b, io.c, io.d), inputs, t,
                         interp=True)
    full = full + np.column_stack([np.zeros_like(z), np.r_[0.0, vz[:-1]]]) @ io.e.T
    for row in (0, 2, 3):  # rim_Fx is zero by symmetry at rest
        scale = np.abs(full[:, row]).max()
        error = np.abs(ours[:, row] - full[:, row]).max() / scale
        assert error < 5 * reduced.report.max_relative_error + 1e-6, (OUTPUT_NAMES[row], error)


def test_stepping_matches_scipy_signal_on_the_full_model_rolling(small_models):
    """At speed each patch-node group sees the road delayed; scipy gets the same delayed
    road, sampled from the exact signal, on a fine step."""
    model = small_models[15.0]
    reduced = reduce(model)
    io = build_io_model(model)
    h = 2.5e-5
    t = np.arange(0.0, 0.12, h)
    f0, f1, duration = 5.0, 200.0, t[-1]
    k = (f1 / f0) ** (1 / duration)

    def road(time):  # a smooth sweep that starts at rest
        time = np.clip(time, 0.0, None)
        phase = 2 * np.pi * f0 * (k**time - 1) / np.log(k)
        return 1e-3 * (1 - np.cos(phase)), 1e-3 * np.sin(phase) * 2 * np.pi * f0 * k**time

    z, vz = road(t)
    ours = _simulate(reduced, t, z, vz)
    delays = io.input_delays_s
    r = np.column_stack([np.zeros_like(t)] + [road(t - d)[0] for d in delays[1:]])
    # the direct velocity term reads the slope the step ramped with: the one at its start
    rdot = np.column_stack([np.zeros_like(t)] + [road(t - h - d)[1] for d in delays[1:]])
    _, full, _ = ss.lsim(ss.StateSpace(io.a.toarray(), io.b, io.c, io.d), r, t, interp=True)
    full = full + rdot @ io.e.T
    for row in range(4):
        scale = np.abs(full[:, row]).max()
        error = np.abs(ours[:, row] - full[:, row]).max() / scale
        assert error < 5 * reduced.report.max_relative_error + 1e-3, (OUTPUT_NAMES[row], error)


def test_simulator_refuses_bad_steps_and_keeps_its_state(small_models):
    sim = TireSimulator(reduce(small_models[0.0], report=False))
    sim.step(1e-3, 0.0, 0.0, 1e-3, 0.0)
    before = sim.get_state()
    for bad in ((0.0, 0, 0, 0, 0), (-1e-3, 0, 0, 0, 0), (1e-3, np.nan, 0, 0, 0),
                (1e-3, 0, 0, np.inf, 0)):
        with pytest.raises(StepError):
            sim.step(*bad)
    after = sim.get_state()
    assert after.time == before.time and np.array_equal(after.q, before.q)


def test_simulator_state_round_trip_reproduces_a_step(small_models):
    sim = TireSimulator(reduce(small_models[15.0], report=False))
    for i in range(20):
        sim.step(1e-3, 0.0, 0.0, 1e-3 * np.sin(i), 0.0)
    saved = sim.get_state().to_bytes()
    first = sim.step(1e-3, 0.0, 0.0, 2e-3, 0.0).copy()
    sim.step(1e-3, 0.0, 0.0, -1e-3, 0.0)
    sim.set_state(type(sim.get_state()).from_bytes(saved))
    again = sim.step(1e-3, 0.0, 0.0, 2e-3, 0.0)
    np.testing.assert_array_equal(first, again)


def test_npz_round_trip_is_bit_exact_and_rejects_tampering(small_models, tmp_path):
    reduced = reduce(small_models[15.0])
    path = save_npz(reduced, tmp_path / "tire.npz")
    back = load_npz(path)
    for name in ("eigenvalues", "b", "c", "d", "e", "input_delays_s"):
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
    from tire_fmu.core.export import _checksum, _metadata_checksum

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
    from tire_fmu.core.export import to_control

    reduced = reduce(small_models[0.0])
    system = to_control(reduced)
    assert isinstance(system, control.StateSpace)
    assert system.nstates == reduced.n_states
    assert system.output_labels == list(OUTPUT_NAMES)
    dc = control.dcgain(system)
    assert dc[0, 0] == pytest.approx(-small_models[0.0].static_vertical_stiffness_n_per_m,
                                     rel=1e-9)


@pytest.mark.parametrize("speed", [0.0, 15.0])
def test_feedthrough_at_the_ramp_end_is_the_step_output(small_models, speed):
    sim = TireSimulator(reduce(small_models[speed], report=False))
    h = 2e-4
    for _ in range(40):
        t = sim.time
        z, v = 1e-3 * np.sin(60 * t), 6e-2 * np.cos(60 * t)
        stepped = sim.step(h, 0.5 * z, 0.5 * v, z, v).copy()
    again = sim.outputs_with(0.5 * (z + v * h), 0.5 * v, z + v * h, v)
    # at rest the step's own end-of-ramp inputs give its outputs back to rounding; at speed
    # the delayed road is read from the history with the new sample in it rather than
    # extrapolated along each group's ramp, which differs at O(h²)
    np.testing.assert_allclose(again, stepped, rtol=1e-11 if speed == 0 else 2e-4, atol=1e-9)
    # a different rim velocity now moves the rim force by the rim dampers, -Tᵀ D_s T per m/s
    faster = sim.outputs_with(0.5 * (z + v * h), 0.5 * v + 0.1, z + v * h, v)
    damper = build_io_model(small_models[speed]).e[0, 0]
    assert faster[0] - again[0] == pytest.approx(0.1 * damper, rel=1e-9)


def test_feedthrough_read_with_the_new_inputs_converges_at_second_order(small_models):
    """The contact force passes the road velocity straight through the contact damper, and
    the stiff contact amplifies any lag. Read at a communication point with that point's
    inputs (outputs_with), it converges at second order in h to the continuous response; the
    outputs a step reports at its end, with the slope it ramped with, only at first order."""
    model = small_models[0.0]
    reduced = reduce(model, ReductionSettings(contribution_threshold=0.0))
    io = build_io_model(model)
    static = np.array([reduced.static_outputs[n] for n in OUTPUT_NAMES])
    duration, f0, f1 = 0.1, 2.0, 300.0
    growth = (f1 / f0) ** (1 / duration)

    def road(t):
        phase = 2 * np.pi * f0 * (growth**t - 1) / np.log(growth)
        return 1e-3 * (1 - np.cos(phase)), 1e-3 * np.sin(phase) * 2 * np.pi * f0 * growth**t

    fine = 5e-6  # the continuous response: scipy on a step 20 times finer
    t_ref = np.arange(0.0, duration, fine)
    z_ref, v_ref = road(t_ref)
    _, reference, _ = ss.lsim(ss.StateSpace(io.a.toarray(), io.b, io.c, io.d),
                              np.column_stack([0 * z_ref, z_ref]), t_ref, interp=True)
    reference = reference[:, 2] + v_ref * io.e[2, 1]
    errors = {}
    for h in (1e-4, 5e-5):
        t = np.arange(0.0, duration - h, h)
        z, v = road(t)
        sim = TireSimulator(reduced)
        stepped, read = [], []
        for k in range(t.size - 1):
            stepped.append(sim.step(h, 0.0, 0.0, z[k], v[k])[2] - static[2])
            read.append(sim.outputs_with(0.0, 0.0, z[k + 1], v[k + 1])[2] - static[2])
        exact = reference[np.round(t[1:] / fine).astype(int)]
        scale = np.abs(exact).max()
        errors[h] = (np.abs(np.array(stepped) - exact).max() / scale,
                     np.abs(np.array(read) - exact).max() / scale)
    (step_coarse, read_coarse), (step_fine, read_fine) = errors[1e-4], errors[5e-5]
    assert read_coarse < 0.2 * step_coarse
    assert read_coarse / read_fine > 3.2  # second order
    assert step_coarse / step_fine < 2.5  # first order
    assert read_fine < 0.02
