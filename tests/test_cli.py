"""The ``tire-fmu`` command line: JSON equal to the Python API, figures, one-line errors."""

import json
import subprocess
import sys

import numpy as np
import pytest

from tire_fmu.cli import main
from tire_fmu.cli.common import to_jsonable
from tire_fmu.core import (
    OperatingPoint,
    analytic_modes,
    build_model,
    critical_speed,
    real_modes,
)
from tire_fmu.core.studies import convergence_study, dispersion_at_speed, patch_sweep, speed_sweep

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def run_json(capsys, *argv):
    code, out, err = run(capsys, *argv, "--json")
    assert code == 0, err
    return json.loads(out)


def same(data, result):
    """The JSON equals the API's to_dict() after the CLI's JSON conversion (nan -> null)."""
    assert data == json.loads(json.dumps(to_jsonable(result.to_dict())))


# ------------------------------------------------------------------ JSON equals the API

FAST_COMMANDS = [
    ["modes", "--patch-length", "0.204", "--fmax", "120"],
    ["modes", "--speed", "10", "--fmax", "80", "--elements", "40"],
    ["analytic", "--nmax", "4"],
    ["patch", "--load", "27700"],
    ["convergence", "--elements-list", "20,40", "--nmax", "3"],
    ["patch-sweep", "--elements", "40", "--steps", "3", "--nmax", "2"],
    ["dispersion", "--elements", "40", "--nmax", "3"],
    ["speed-sweep", "--elements", "40", "--steps", "2", "--nmax", "2"],
    ["critical-speed", "--elements", "40"],
]


@pytest.mark.parametrize("argv", FAST_COMMANDS, ids=lambda a: " ".join(a))
def test_every_command_prints_parseable_json_and_text(capsys, argv):
    data = run_json(capsys, *argv)
    assert isinstance(data, dict) and data
    code, out, err = run(capsys, *argv)
    assert code == 0 and out.strip() and "Traceback" not in err


def test_modes_json_equals_real_modes(capsys, tire):
    data = run_json(capsys, "modes", "--patch-length", "0.204")
    expected = real_modes(build_model(tire, OperatingPoint(patch_length_m=0.204)), fmax_hz=300)
    got = np.array([m["frequency_hz"] for m in data["modes"]])
    np.testing.assert_allclose(got, expected.frequencies_hz, rtol=1e-12, atol=0)
    assert [m["symmetry"] for m in data["modes"]] == [m.symmetry for m in expected.modes]


def test_analytic_json_equals_analytic_modes(capsys, tire):
    same(run_json(capsys, "analytic"), analytic_modes(tire, np.arange(13)))


def test_patch_json_equals_the_models_patch(capsys, tire):
    data = run_json(capsys, "patch", "--load", "27700")
    model = build_model(tire, OperatingPoint(load_n=27700))
    assert data == pytest.approx(model.summary(), rel=1e-12)
    assert data["patch_length_m"] == pytest.approx(model.patch.length_m, rel=1e-12)


def test_convergence_json_equals_the_study(capsys, tire):
    data = run_json(capsys, "convergence", "--elements-list", "40,20,80", "--nmax", "5")
    same(data, convergence_study(tire, (20, 40, 80), range(6)))
    assert data["in_phase"]["convergence_order"][0] is None  # n = 0 is exact: no slope


def test_patch_sweep_json_equals_the_study(capsys, tire):
    data = run_json(capsys, "patch-sweep", "--max-length", "0.2", "--steps", "5",
                    "--out-of-phase", "--nmax", "3")
    same(data, patch_sweep(tire, 100, np.linspace(0, 0.2, 5), (1, 2, 3), ("in", "out")))


def test_dispersion_json_equals_the_study(capsys, tire):
    data = run_json(capsys, "dispersion", "--speed", "20", "--patch-length", "0.204",
                    "--nmax", "4")
    same(data, dispersion_at_speed(tire, 100, 20.0, 0.204, 4, 300.0))
    default = run_json(capsys, "dispersion", "--elements", "40")
    assert default["spin_rad_s"] == pytest.approx(20 * np.pi)  # the paper's spin
    assert default["loaded"] is None


def test_speed_sweep_json_equals_the_study(capsys, tire):
    data = run_json(capsys, "speed-sweep", "--max-speed", "20", "--steps", "3",
                    "--elements", "60")
    same(data, speed_sweep(tire, 60, np.linspace(0, 20, 3), 0.204, 200.0, 6))


def test_speed_sweep_default_stops_below_a_fine_meshes_critical_speed(capsys, tire):
    code, out, _ = run(capsys, "speed-sweep", "--elements", "200", "--steps", "2", "--nmax", "2")
    assert code == 0
    assert "critical speed" in out and "95 %" in out
    data = run_json(capsys, "speed-sweep", "--elements", "200", "--steps", "2", "--nmax", "2")
    assert data["speeds_m_s"][-1] == pytest.approx(0.95 * critical_speed(tire, 200).speed_m_s)


def test_critical_speed_json_and_text(capsys, tire):
    assert run_json(capsys, "critical-speed") == to_jsonable(critical_speed(tire, 100).to_dict())
    code, out, _ = run(capsys, "critical-speed")
    assert code == 0 and "lumped" in out and "sidewall_shear" in out
    for n in (50, 100, 200, 400):
        assert f"{critical_speed(tire, n).speed_m_s:.4g}" in out
    sheared = run_json(capsys, "critical-speed", "--tire", "sidewall_shear=1e5")
    assert sheared["critical_speed_m_s"] > 100


def test_python_dash_m_runs_the_cli(tire):
    done = subprocess.run([sys.executable, "-m", "tire_fmu", "analytic", "--json"],
                          capture_output=True, text=True, timeout=60, check=True)
    assert json.loads(done.stdout) == analytic_modes(tire, np.arange(13)).to_dict()


# ------------------------------------------------------------------ figures

PLOTS = [
    ["modes", "--patch-length", "0.204", "--fmax", "100"],
    ["convergence", "--elements-list", "20,40,80", "--nmax", "4"],
    ["patch-sweep", "--elements", "40", "--steps", "4", "--out-of-phase"],
    ["dispersion", "--elements", "40", "--patch-length", "0.204", "--nmax", "6"],
    ["speed-sweep", "--elements", "40", "--steps", "3", "--nmax", "3"],
]


@pytest.mark.parametrize("argv", PLOTS, ids=lambda a: a[0])
def test_plot_writes_a_png(capsys, tmp_path, argv):
    path = tmp_path / f"{argv[0]}.png"
    code, _, err = run(capsys, *argv, "--plot", str(path))
    assert code == 0, err
    assert path.stat().st_size > 10_000
    assert path.read_bytes()[:8] == PNG_SIGNATURE
    assert f"wrote {path}" in err


# ------------------------------------------------------------------ errors

BAD_INPUTS = [
    (["speed-sweep", "--steps", "1", "--nmax", "0", "--max-speed", "-5", "--elements", "3"],
     ["--steps = 1", "--nmax = 0", "--max-speed = -5", "--elements = 3", "4 problems"]),
    (["dispersion", "--speed", "-1", "--tire", "k_r1=-5", "--fmax", "0"],
     ["--speed = -1", "k_r1 = -5", "--fmax = 0", "3 problems"]),
    (["patch-sweep", "--max-length", "0.9", "--steps", "1"],
     ["--max-length = 0.9", "0.5105", "--steps = 1"]),
    (["speed-sweep", "--patch-length", "0.8", "--elements", "2"],
     ["--patch-length = 0.8", "--elements = 2"]),
    (["convergence", "--elements-list", "20,abc", "--nmax", "0"],
     ["--elements-list = '20,abc'", "--nmax = 0"]),
    (["critical-speed", "--elements", "4", "--tire", "EI=-1"], ["--elements = 4", "EI = -1"]),
    (["analytic", "--nmax", "-1", "--inflation-pressure", "-3"],
     ["--nmax = -1", "--inflation-pressure = -3"]),
    (["modes", "--fmax", "-1"], ["--fmax = -1"]),
    (["speed-sweep", "--max-speed", "60"], ["--max-speed = 60", "critical speed 42.67"]),
    (["dispersion", "--speed", "50", "--patch-length", "0.204"],
     ["--speed = 50", "critical speed 42.67"]),
    (["dispersion", "--patch-length", "0.204", "--elements", "200"],
     ["default --speed = 40.84", "critical speed 21.49"]),
]


@pytest.mark.parametrize("argv, fragments", BAD_INPUTS, ids=lambda a: " ".join(a)[:40])
def test_bad_input_is_one_line_naming_every_parameter(capsys, argv, fragments):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert out == ""
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"tire-fmu {argv[0]}: error: ")
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    assert "must be" in lines[0]  # with the allowed range


@pytest.mark.parametrize("command", ["convergence", "patch-sweep", "dispersion", "speed-sweep",
                                     "critical-speed"])
def test_help(capsys, command):
    with pytest.raises(SystemExit) as stop:
        main([command, "--help"])
    assert stop.value.code == 0
    assert "--json" in capsys.readouterr().out


def test_progress_bar_only_on_a_terminal(monkeypatch):
    from tire_fmu.cli.ring import progress_bar

    with progress_bar("x") as progress:  # pytest captures stderr: not a terminal
        assert progress is None
    pytest.importorskip("tqdm")
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    with progress_bar("x") as progress:
        for done in range(1, 4):
            progress(done, 3)
