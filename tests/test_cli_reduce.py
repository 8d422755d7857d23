"""CLI of the reduced-order model: frf, reduce, export."""

import json

import numpy as np
import pytest

from tire_fmu.cli import main
from tire_fmu.core import OperatingPoint, build_model
from tire_fmu.core.frequency_response import full_frequency_response
from tire_fmu.core.reduction import ReductionSettings, reduce
from tire_fmu.model_files import load_mat, load_npz

MODEL = ["--elements", "40", "--patch-length", "0.204"]


def run_json(capsys, *argv):
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_reduce_json_is_the_report_of_the_python_api(capsys, tire):
    data = run_json(capsys, "reduce", *MODEL, "--target-error", "0.01")
    reduced = reduce(build_model(tire, OperatingPoint(n_elements=40, patch_length_m=0.204)),
                     ReductionSettings(target_error=0.01))
    assert data["n_states"] == reduced.n_states
    assert data["report"]["max_relative_error"] == pytest.approx(
        reduced.report.max_relative_error, rel=1e-9)
    assert data["settings"]["target_error"] == 0.01


def test_reduce_exact_report_checks_against_the_assembled_model(capsys, tire):
    modal = run_json(capsys, "reduce", *MODEL)
    exact = run_json(capsys, "reduce", *MODEL, "--exact-report")
    assert (modal["report"]["reference"], exact["report"]["reference"]) == ("modal", "exact")
    assert exact["n_states"] == modal["n_states"]  # the same reduction, checked two ways
    assert exact["report"]["max_relative_error"] == pytest.approx(
        modal["report"]["max_relative_error"], rel=1e-6)


def test_frf_json_matches_the_full_model_and_reports_the_reduced_error(capsys, tire):
    data = run_json(capsys, "frf", *MODEL, "--input", "rim", "--output", "rim_Fz", "--reduced",
                    "--points", "50", "--min-frequency", "1", "--max-frequency", "300")
    full, reduced = data["responses"]
    model = build_model(tire, OperatingPoint(n_elements=40, patch_length_m=0.204))
    ref = full_frequency_response(model, "rim", "rim_Fz", np.geomspace(1, 300, 50))
    np.testing.assert_allclose(full["magnitude"], ref.magnitude, rtol=1e-12)
    error = np.abs(np.array(reduced["magnitude"]) / ref.magnitude - 1).max()
    assert error <= data["max_relative_error"] + 1e-12  # the magnitude error is bounded by it
    assert data["max_relative_error"] < 0.01
    # static vertical stiffness: the rim force falls by K_v per metre of rim rise at DC
    assert full["magnitude"][0] == pytest.approx(model.static_vertical_stiffness_n_per_m,
                                                 rel=1e-3)


def test_frf_plot_is_written(tmp_path, capsys):
    path = tmp_path / "bode.png"
    assert main(["frf", *MODEL, "--reduced", "--points", "40", "--plot", str(path)]) == 0
    assert path.stat().st_size > 10_000


@pytest.mark.parametrize("suffix", ["npz", "mat"])
def test_export_writes_a_file_that_loads(tmp_path, capsys, suffix):
    path = tmp_path / f"tire.{suffix}"
    data = run_json(capsys, "export", str(path), *MODEL, "--method", "balanced",
                    "--n-states", "24")
    assert data["n_states"] == 24 and data["file"] == str(path)
    if suffix == "npz":
        assert load_npz(path).n_states == 24
    else:
        assert load_mat(path)["A"].shape == (24, 24)


def test_bad_reduction_settings_are_all_reported_on_one_line(capsys):
    code = main(["reduce", *MODEL, "--target-error", "2", "--f-max", "-5", "--n-modes", "0"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1
    for fragment in ("--target-error = 2", "--f-max = -5", "--n-modes = 0"):
        assert fragment in err


def test_the_former_threshold_option_is_refused_naming_its_replacement(capsys):
    """--threshold was the modal budget (a bound on summed mode shares); --target-error is the
    error itself, for both methods. The refusal is reported with the other problems."""
    code = main(["reduce", *MODEL, "--threshold", "0.01", "--n-modes", "0"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1
    assert "--threshold = 0.01" in err and "give --target-error 0.01" in err
    assert "--n-modes = 0" in err


@pytest.mark.parametrize("band", ["1,1e100", "1,2e7", "300,1", "-1,300", "1,inf"])
def test_a_band_outside_the_models_range_is_refused_naming_it(capsys, band):
    assert main(["reduce", *MODEL, f"--band={band}"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--band = " in err and "high <= 1e+07 Hz" in err


def test_the_widest_band_allowed_reports_an_error_within_the_modes_budget(capsys):
    """The dropped modes' contributions bound the error over the band (module doc of
    reduction): still so at the band's largest allowed end."""
    data = run_json(capsys, "reduce", *MODEL, "--band", "1,1e7")
    budget = ReductionSettings().target_error
    assert 0 < data["report"]["max_relative_error"] <= budget


def test_road_input_needs_a_patch(capsys):
    assert main(["frf", "--elements", "40", "--patch-length", "0"]) == 2
    assert "needs a contact patch" in capsys.readouterr().err


def test_export_refuses_an_unknown_format(tmp_path, capsys):
    assert main(["export", str(tmp_path / "model.txt"), *MODEL]) == 2
    assert "--format = 'txt'" in capsys.readouterr().err
