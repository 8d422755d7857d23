"""The ``tire-fmu`` command line: JSON equal to the Python API, figures, one-line errors."""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tire_fmu.cli import build_parser, main
from tire_fmu.cli.common import to_jsonable
from tire_fmu.core import (
    DEFAULT_LOAD_N,
    OperatingPoint,
    ParameterError,
    TireParameters,
    analytic_modes,
    build_model,
    critical_speed,
    real_modes,
)
from tire_fmu.core.studies import (
    CLEAT_STEP_S,
    cleat_convergence,
    convergence_study,
    dispersion_at_speed,
    patch_sweep,
    speed_sweep,
)

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
    ["modes", "--patch-length", "0.204", "--max-frequency", "120"],
    ["modes", "--speed", "10", "--max-frequency", "80", "--elements", "40"],
    ["analytic", "--nmax", "4"],
    ["patch", "--load", "27700"],
    ["convergence", "--elements-list", "20,40", "--nmax", "3"],
    ["patch-sweep", "--elements", "40", "--steps", "3", "--nmax", "2"],
    ["dispersion", "--elements", "40", "--nmax", "3"],
    ["speed-sweep", "--elements", "40", "--steps", "2", "--nmax", "2"],
    ["critical-speed", "--elements", "40"],
    ["cleat", "--elements-list", "20", "--length", "0.01"],
    ["inplane-modes", "--elements", "40", "--max-frequency", "80"],
    ["inplane-modes", "--elements", "40", "--speed", "10", "--nmax", "3"],
    ["inplane-speed-sweep", "--elements", "40", "--speeds", "3", "--nmax", "3"],
]


@pytest.mark.parametrize("argv", FAST_COMMANDS, ids=lambda a: " ".join(a))
def test_every_command_prints_parseable_json_and_text(capsys, argv):
    data = run_json(capsys, *argv)
    assert isinstance(data, dict) and data
    code, out, err = run(capsys, *argv)
    assert code == 0 and out.strip() and "Traceback" not in err


def test_modes_json_equals_real_modes(capsys, tire):
    data = run_json(capsys, "modes", "--patch-length", "0.204")
    expected = real_modes(build_model(tire, OperatingPoint(patch_length_m=0.204)), f_max_hz=300)
    got = np.array([m["frequency_hz"] for m in data["modes"]])
    np.testing.assert_allclose(got, expected.frequencies_hz, rtol=1e-12, atol=0)
    assert [m["symmetry"] for m in data["modes"]] == [m.symmetry for m in expected.modes]


def test_analytic_json_equals_analytic_modes(capsys, tire):
    same(run_json(capsys, "analytic"), analytic_modes(tire, np.arange(13)))


def test_patch_json_equals_the_models_footprint(capsys, tire):
    data = run_json(capsys, "patch", "--load", "27700")
    fp = build_model(tire, OperatingPoint(load_n=27700)).patch.footprint
    assert data["footprint"]["load_n"] == pytest.approx(27700, rel=1e-12)
    expected = to_jsonable(fp.to_dict())
    # key by key: pytest.approx refuses a dict of lists from pytest 9 on
    assert data["footprint"].keys() == expected.keys()
    for key, value in expected.items():
        assert data["footprint"][key] == pytest.approx(value, rel=1e-12), key
    assert data["patch_length_m"] == pytest.approx(fp.length_m, rel=1e-12)
    # the inverse: the deflection that footprint needs gives the load back
    again = run_json(capsys, "patch", "--deflection", repr(fp.deflection_m))
    assert again["load_n"] == pytest.approx(27700, rel=1e-9)
    # the paper's prescribed patch stays an explicit mode
    paper = run_json(capsys, "patch", "--patch-length", "0.204")
    assert paper["contact"] == "prescribed patch" and paper["patch_length_m"] == 0.204


def test_patch_shows_the_contact_points_the_point_spacing_sets(capsys, tire):
    from tire_fmu.core.contact import DEFAULT_CONTACT_POINT_SPACING_M

    default = run_json(capsys, "patch", "--load", "27700")["footprint"]
    arc = 2 * np.pi * tire.R / 100
    # the default spacing: the fewest (odd) points per node arc that are no farther apart
    m = default["points_per_node"]
    assert m % 2 == 1 and arc / m <= DEFAULT_CONTACT_POINT_SPACING_M < arc / (m - 2)
    assert len(default["theta_rad"]) == default["zone_points"] > default["contact_points"]
    nodes = run_json(capsys, "patch", "--load", "27700", "--point-spacing", "1")["footprint"]
    assert nodes["points_per_node"] == 1 and nodes["zone_points"] == nodes["zone_nodes"]
    fine = run_json(capsys, "patch", "--load", "27700", "--point-spacing", "5e-4")["footprint"]
    assert fine["contact_point_spacing_m"] <= 5e-4 < fine["contact_point_spacing_m"] * (
        fine["points_per_node"] / (fine["points_per_node"] - 2))
    # the help states the core's default (the CLI parses without numpy, so it is typed)
    with pytest.raises(SystemExit):
        main(["patch", "--help"])
    stated = re.search(r"--point-spacing M.*?\(default ([0-9.e-]+);", " ".join(
        capsys.readouterr().out.split()))
    assert float(stated.group(1)) == DEFAULT_CONTACT_POINT_SPACING_M


def test_convergence_json_equals_the_study(capsys, tire):
    data = run_json(capsys, "convergence", "--elements-list", "40,20,80", "--nmax", "5")
    same(data, convergence_study(tire, (20, 40, 80), range(6)))
    assert data["in_phase"]["convergence_order"][0] is None  # n = 0 is exact: no slope


def test_cleat_json_equals_the_study(capsys, tire):
    from tire_fmu.core.obstacles import pothole

    data = run_json(capsys, "cleat", "--elements-list", "40,20", "--pothole", "--height",
                    "0.03", "--length", "0.1", "--speed", "5", "--histories")
    study = cleat_convergence(tire, pothole(0.03, 0.1), 5.0, (20, 40)).to_dict()
    for record in (data, study):
        record.pop("run_s")  # wall time
    assert data == json.loads(json.dumps(to_jsonable(study)))
    assert len(data["rim_fz_n"]) == 2 and len(data["time_s"]) == len(data["rim_fz_n"][0])


def test_cleat_defaults_are_the_studys():
    from tire_fmu.cli import cleat
    from tire_fmu.core.contact import DEFAULT_CONTACT_POINT_SPACING_M

    assert cleat.DEFAULT_STEP_S == CLEAT_STEP_S
    assert cleat.DEFAULT_POINT_SPACING_M == DEFAULT_CONTACT_POINT_SPACING_M


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


def test_speed_sweep_default_stops_below_a_fine_meshes_critical_speed(capsys):
    paper = ("--tire-file", "GL073A")  # the lumped sidewall: 21.5 m/s at N = 200
    code, out, _ = run(capsys, "speed-sweep", "--elements", "200", "--steps", "2", "--nmax", "2",
                       *paper)
    assert code == 0
    assert "critical speed" in out and "95 %" in out
    data = run_json(capsys, "speed-sweep", "--elements", "200", "--steps", "2", "--nmax", "2",
                    *paper)
    lumped = TireParameters(sidewall_max_order=0.0)
    assert data["speeds_m_s"][-1] == pytest.approx(0.95 * critical_speed(lumped, 200).speed_m_s)


def test_critical_speed_json_and_text(capsys, tire):
    assert run_json(capsys, "critical-speed") == to_jsonable(critical_speed(tire, 100).to_dict())
    code, out, _ = run(capsys, "critical-speed")
    assert code == 0 and "tied to the tread" in out and "converges" in out
    for n in (50, 100, 200, 400):
        assert f"{critical_speed(tire, n).speed_m_s:.4g}" in out
    code, out, _ = run(capsys, "critical-speed", "--tire-file", "GL073A")
    assert code == 0 and "lumped" in out and "sidewall_shear" in out
    sheared = run_json(capsys, "critical-speed", "--tire", "sidewall_shear=1e5")
    assert sheared["critical_speed_m_s"] > 100


def test_python_dash_m_runs_the_cli(tire):
    done = subprocess.run([sys.executable, "-m", "tire_fmu", "analytic", "--json"],
                          capture_output=True, text=True, timeout=60, check=True)
    assert json.loads(done.stdout) == analytic_modes(tire, np.arange(13)).to_dict()


# ------------------------------------------------------------------ figures

PLOTS = [
    ["modes", "--patch-length", "0.204", "--max-frequency", "100"],
    ["convergence", "--elements-list", "20,40,80", "--nmax", "4"],
    ["patch-sweep", "--elements", "40", "--steps", "4", "--out-of-phase"],
    ["dispersion", "--elements", "40", "--patch-length", "0.204", "--nmax", "6"],
    ["speed-sweep", "--elements", "40", "--steps", "3", "--nmax", "3"],
    ["patch", "--load", "27700"],
    ["cleat", "--elements-list", "20,40", "--length", "0.01"],
]


@pytest.mark.parametrize("argv", PLOTS, ids=lambda a: a[0])
def test_plot_writes_a_png(capsys, tmp_path, argv):
    path = tmp_path / f"{argv[0]}.png"
    code, _, err = run(capsys, *argv, "--plot", str(path))
    assert code == 0, err
    assert path.stat().st_size > 10_000
    assert path.read_bytes()[:8] == PNG_SIGNATURE
    assert f"wrote {path}" in err


def _figures(monkeypatch):
    """The figures the plots module saves, kept open for inspection."""
    import tire_fmu.plots as plots

    saved = []
    original = plots._save

    def keep(fig, plt, path):
        saved.append(fig)
        fig.canvas.draw()  # lay out the texts so their extents are real
        return original(fig, plt, path)

    monkeypatch.setattr(plots, "_save", keep)
    return saved


def _legend_texts(fig):
    return [t.get_text() for ax in fig.axes if ax.get_legend()
            for t in ax.get_legend().get_texts()]


def test_patch_sweep_legend_says_what_the_members_are(capsys, monkeypatch, tmp_path):
    saved = _figures(monkeypatch)
    assert main(["patch-sweep", "--elements", "40", "--steps", "3", "--plot",
                 str(tmp_path / "p.png")]) == 0
    texts = " | ".join(_legend_texts(saved[0]))
    assert "(extr)" not in texts and "(0)" not in texts
    assert "antinode at the patch centre" in texts and "node at the patch centre" in texts


def test_speed_sweep_figure_shows_the_data_not_the_sidewall_band(capsys, monkeypatch,
                                                                  tmp_path):
    saved = _figures(monkeypatch)
    assert main(["speed-sweep", "--elements", "60", "--steps", "4", "--plot",
                 str(tmp_path / "s.png")]) == 0
    fig = saved[0]
    ax = fig.axes[0]
    # the critical speed is named in the legend, not written over the curves
    assert not any("critical" in t.get_text() for t in ax.texts)
    assert any(t.startswith("critical (standing-wave) speed") for t in _legend_texts(fig))
    # the loaded modes outside the shown orders are one shaded span, not hundreds of dots
    points = [len(c.get_offsets()) for c in ax.collections if hasattr(c, "get_offsets")
              and len(c.get_offsets()) and c.get_label().startswith("loaded in-phase")]
    assert len(points) == 1  # only the coloured markers of the orders shown
    legend = ax.get_legend()
    assert legend.get_window_extent().y1 < ax.get_window_extent().y0  # below the axes


def test_convergence_table_says_exact_instead_of_nan(capsys):
    code, out, _ = run(capsys, "convergence", "--elements-list", "20,40", "--nmax", "2")
    assert code == 0 and "nan" not in out
    rows = [line.split() for line in out.splitlines() if line.startswith("0 ")]
    assert len(rows) == 2 and all(row[-1] == "exact" for row in rows)  # both n = 0 rows


# ------------------------------------------------------------------ errors

BAD_INPUTS = [
    (["speed-sweep", "--steps", "1", "--nmax", "0", "--max-speed", "-5", "--elements", "3"],
     ["--steps = 1", "--nmax = 0", "--max-speed = -5", "--elements = 3", "4 problems"]),
    (["dispersion", "--speed", "-1", "--tire", "k_r1=-5", "--max-frequency", "0"],
     ["--speed = -1", "k_r1 = -5", "--max-frequency = 0", "3 problems"]),
    (["patch-sweep", "--max-length", "0.9", "--steps", "1"],
     ["--max-length = 0.9", "0.5105", "--steps = 1"]),
    (["speed-sweep", "--patch-length", "0.8", "--elements", "2"],
     ["--patch-length = 0.8", "--elements = 2"]),
    (["convergence", "--elements-list", "20,abc", "--nmax", "0"],
     ["--elements-list = '20,abc'", "--nmax = 0"]),
    (["critical-speed", "--elements", "4", "--tire", "EI=-1"], ["--elements = 4", "EI = -1"]),
    (["analytic", "--nmax", "-1", "--inflation-pressure", "-3"],
     ["--nmax = -1", "--inflation-pressure = -3"]),
    (["modes", "--max-frequency", "-1"], ["--max-frequency = -1"]),
    # the paper's lumped sidewall, whose critical speed falls with the mesh
    (["speed-sweep", "--max-speed", "60", "--tire-file", "GL073A"],
     ["--max-speed = 60", "critical speed 42.67"]),
    (["dispersion", "--speed", "50", "--patch-length", "0.204", "--tire-file", "GL073A"],
     ["--speed = 50", "critical speed 42.67"]),
    (["dispersion", "--patch-length", "0.204", "--elements", "200", "--tire-file", "GL073A"],
     ["default --speed = 40.84", "critical speed 21.49"]),
    (["modes", "--speed", "90"], ["--speed = 90", "speed 83.36 m/s of this mesh"]),
    # tiny values: named with their range, not as a critical speed of 0 m/s, a load in
    # [0, 0] N or a singular matrix
    (["modes", "--tire", "rhoA=1e-301"], ["rhoA = 1e-301 kg/m", "[1e-06, 10000] kg/m"]),
    (["modes", "--tire", "m_s=1e-301", "--speed", "5", "--allow-supercritical"],
     ["m_s = 1e-301 kg/m", "[1e-06, 10000] kg/m"]),
    (["frf", "--tire", "k_cw=5e-324", "--elements", "40"], ["k_cw = 4.94066e-324 N/m^2",
                                                            "[10000, 1e+13] N/m^2"]),
    (["reduce", "--tire", "k_cw=5e-324", "--allow-supercritical", "--speed", "5"],
     ["k_cw = 4.94066e-324 N/m^2", "[10000, 1e+13] N/m^2"]),
    (["patch", "--load", "2e4", "--point-spacing", "1e-5", "--elements", "3"],
     ["--point-spacing = 1e-05 m: must be in [0.0001, 1] m", "--elements = 3"]),
    (["frf", "--elements", "1600", "--point-spacing", "1e-4"],
     ["--point-spacing = 0.0001 m: must be at least"]),
    (["modes", "--tire", "sidewall_pressure_exponent=1", "--inflation-pressure", "1e-300"],
     ["--inflation-pressure = 1e-300 Pa: must be at least 10000 Pa"]),
    (["cleat", "--elements-list", "20,x", "--height", "0", "--speed", "-1", "--step", "1",
      "--point-spacing", "2", "--load", "-5"],
     ["--elements-list = '20,x'", "--height = 0", "--speed = -1", "--step = 1",
      "--point-spacing = 2", "--load = -5", "6 problems"]),
    (["cleat", "--elements-list", "100", "--zone-length", "0.3"],
     ["--zone-length = 0.3 m: must be at least", "meets the undeformed tread"]),
    (["cleat", "--elements-list", "800", "--tire-file", "GL073A"],
     ["--speed = 10 m/s: must be below the critical"]),
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
                                     "critical-speed", "cleat"])
def test_help(capsys, command):
    with pytest.raises(SystemExit) as stop:
        main([command, "--help"])
    assert stop.value.code == 0
    assert "--json" in capsys.readouterr().out


def test_progress_bar_only_on_a_terminal(monkeypatch, capsys):
    from tire_fmu.cli.ring import progress_bar

    with progress_bar("meshes") as progress:  # pytest captures stderr: not a terminal
        assert progress is None
    assert capsys.readouterr().err == ""
    tqdm = pytest.importorskip("tqdm")
    closed = []

    class Recording(tqdm.tqdm):
        def close(self):
            if not self.disable:
                closed.append((self.desc, self.n, self.total))
            super().close()

    monkeypatch.setattr(tqdm, "tqdm", Recording)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    with progress_bar("meshes") as progress:
        assert callable(progress)
        for done in range(1, 4):
            progress(done, 3)
    assert closed == [("meshes", 3, 3)]  # one bar, counted to the total, then closed
    assert "meshes" in capsys.readouterr().err  # drawn on stderr


# ------------------------------------------------------------------ the command line itself

def test_a_reader_that_stops_early_ends_the_output_quietly():
    # `tire-fmu analytic --json | head -c 0`: the pipe's read end is already closed. No
    # message (the reader chose to stop), but not success either: 141, as a C tool stopped
    # by SIGPIPE reports, so that `set -o pipefail` sees it
    read, write = os.pipe()
    os.close(read)
    try:
        done = subprocess.run([sys.executable, "-m", "tire_fmu", "analytic", "--json"],
                              stdout=write, stderr=subprocess.PIPE, text=True, timeout=60)
    finally:
        os.close(write)
    assert done.returncode == 141 and done.stderr == ""


def test_debug_is_accepted_before_and_after_the_command(capsys):
    with pytest.raises(ParameterError):  # --debug: the traceback, not the one-line message
        main(["modes", "--elements", "3", "--debug"])
    with pytest.raises(ParameterError):
        main(["--debug", "modes", "--elements", "3"])
    assert main(["modes", "--elements", "3"]) == 2
    assert capsys.readouterr().err.startswith("tire-fmu modes: error: ")


def _options():
    parser = build_parser()
    (commands,) = [a for a in parser._actions if a.dest == "command"]
    for name, command in commands.choices.items():
        yield name, [o for a in command._actions for o in a.option_strings if o.startswith("--")]


def test_one_option_name_per_idea():
    # --fmax and --f-max on one command meant two things: no two names may differ only by
    # dashes, and the reduction's mode cut is --f-max (the FMU's f_max) everywhere
    for command, options in _options():
        squeezed = [o.replace("-", "") for o in options]
        assert len(set(squeezed)) == len(squeezed), (command, options)
        assert not {"--fmax", "--fmin"} & set(options), command
    package = Path(__file__).resolve().parents[1]
    for source in [*package.glob("tire_fmu/**/*.py"), *package.glob("vehicle_demo/*.py")]:
        assert not re.search(r"\bfmax_hz\b", source.read_text()), source  # f_max_hz only


@pytest.mark.parametrize("spelling", ["rim_Fz", "RIM_FZ", "rim_fz"])
def test_frf_names_outputs_as_the_fmu_does_in_any_case(capsys, spelling):
    data = run_json(capsys, "frf", "--elements", "40", "--load", "27700", "--output", spelling,
                    "--points", "3")
    assert data["responses"][0]["output"] == "rim_Fz"
    with pytest.raises(SystemExit) as stop:
        main(["frf", "--elements", "40", "--output", "rim_Fy"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and "'rim_Fz', 'rim_Fx', 'contact_Fz', 'deflection'" in err


def _no_computation(*_, **__):
    pytest.fail("computed before the command line was checked")


BAD_PATHS = [
    ("x.xyz", "unknown figure format .xyz"),
    ("x", "no file extension"),
    ("{file}/x.png", "is a file, not a folder"),
    ("missing/x.png", "does not exist"),
]


@pytest.mark.parametrize("plot, fragment", BAD_PATHS)
def test_a_bad_plot_path_is_refused_before_computing(capsys, monkeypatch, tmp_path, plot,
                                                     fragment):
    import tire_fmu.cli.ring as ring

    monkeypatch.setattr(ring, "convergence_study", _no_computation)
    (tmp_path / "file").write_text("")
    path = str(tmp_path / plot.format(file="file"))
    code, out, err = run(capsys, "convergence", "--plot", path)
    assert code == 2 and out == ""
    assert err.startswith("tire-fmu convergence: error: --plot = ") and fragment in err
    assert err.count("\n") == 1


@pytest.mark.parametrize("command", ["build-fmu", "export"])
@pytest.mark.parametrize("out, fragment", [
    ("missing/t.fmu", "folder '{tmp}/missing' does not exist"),
    ("file/t.fmu", "folder '{tmp}/file' is a file, not a folder"),
    ("t.zip", "must be a file name ending in .fmu"),
])
def test_fmu_outputs_are_checked_alike_before_building(capsys, monkeypatch, tmp_path, command,
                                                       out, fragment):
    import tire_fmu.cli.reduce as reduce_cli
    import tire_fmu.fmu.builder as builder

    monkeypatch.setattr(reduce_cli, "reduce", _no_computation)
    monkeypatch.setattr(builder, "build_fmu", _no_computation)
    (tmp_path / "file").write_text("")
    extra = ["--format", "fmu"] if command == "export" else []
    code, _, err = run(capsys, command, str(tmp_path / out), *extra)
    assert code == 2
    assert err.startswith(f"tire-fmu {command}: error: OUT = ")
    assert fragment.format(tmp=tmp_path) in err, err


def test_export_without_fmpy_names_the_extra(capsys, monkeypatch, tmp_path):
    import tire_fmu.cli.reduce as reduce_cli

    monkeypatch.setattr(reduce_cli, "reduce", _no_computation)
    monkeypatch.setitem(sys.modules, "fmpy", None)  # import fmpy now raises ImportError
    code, _, err = run(capsys, "export", str(tmp_path / "t.fmu"))
    assert code == 2 and "pip install 'tire_fmu[fmu]'" in err


# ------------------------------------------------------------------ messages a user can act on

def _tire_fmu(*argv, stdout=subprocess.PIPE) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "tire_fmu", *argv], stdout=stdout,
                          stderr=subprocess.PIPE, text=True, timeout=120)


def _one_line(err: str, start: str) -> str:
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(start), err
    return lines[0]


ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("argv, prog, named, suggested", [
    (["-m", "tire_fmu", "patch", "--laod", "5"], "tire-fmu patch", "--laod", "--load"),
    (["-m", "tire_fmu", "patch", "--lo", "27000"], "tire-fmu patch", "--lo", "--load"),
    (["-m", "tire_fmu", "--debu", "modes"], "tire-fmu", "--debu", "--debug"),
    (["build_fmu.py", "--out", "dist"], "build_fmu.py", "--out", "--out-dir"),
    (["-m", "vehicle_demo", "--qu"], "python -m vehicle_demo", "--qu", "--quick"),
])
def test_an_unknown_or_abbreviated_option_is_named_with_the_one_meant(tmp_path, argv, prog,
                                                                       named, suggested):
    # `patch --laod` said only that one of --load --deflection --patch-length is required,
    # and `--lo 27000` ran as --load 27000: options are taken only as spelled
    done = subprocess.run([sys.executable, *argv], capture_output=True, text=True, timeout=120,
                          cwd=ROOT)
    assert done.returncode == 2 and done.stdout == ""
    line = _one_line(done.stderr, f"{prog}: error: unknown option {named} ")
    assert f"(did you mean {suggested}?)" in line
    assert not (ROOT / "dist").exists() or "build_fmu" not in argv[0]


@pytest.mark.parametrize("argv, named", [
    (["modes", "--max-frequency", "-1"], "--max-frequency = -1"),
    (["modes", "--elements=-3"], "--elements = -3"),
    (["modes", "--tire", "k_r1=-5"], "k_r1 = -5"),
])
def test_a_negative_number_after_an_option_is_its_value(capsys, argv, named):
    code, _, err = run(capsys, *argv)
    assert code == 2 and named in err and "unknown option" not in err


def test_stdout_that_cannot_take_the_output_is_one_line_and_a_failure(tmp_path):
    with open("/dev/full", "w") as full:
        done = _tire_fmu("analytic", "--nmax", "3", stdout=full)
    assert done.returncode == 2
    _one_line(done.stderr, "tire-fmu analytic: error: cannot write the output to stdout: "
                           "No space left on device")
    script = ("import runpy, sys, tire_fmu.fmu.builder as b\n"
              "b.build_fmu = lambda out: 'dist/TireModal.fmu'\n"
              "sys.argv = ['build_fmu.py']\n"
              "runpy.run_path('build_fmu.py', run_name='__main__')\n")
    with open("/dev/full", "w") as full:
        done = subprocess.run([sys.executable, "-c", script], cwd=ROOT, stdout=full,
                              stderr=subprocess.PIPE, text=True, timeout=120)
    assert done.returncode == 2
    _one_line(done.stderr, "build_fmu.py: error: cannot write the output to stdout")


#: Ctrl-C, as the terminal sends it, at the point named: SIGINT to the process itself.
# A user's Ctrl-C comes from a terminal, where SIGINT has Python's handler; a process started
# in the background of a non-interactive shell inherits SIGINT ignored, and Python then installs
# none, so the child restores it first (the suite failed so when run by a shell script's `&`).
CTRL_C = ("import os, signal, time\n"
          "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
          "def ctrl_c(*_, **__):\n"
          "    os.kill(os.getpid(), signal.SIGINT)\n"
          "    time.sleep(30)\n")


@pytest.mark.fmu
def test_ctrl_c_in_build_fmu_py_is_one_line_status_130_and_leaves_nothing(tmp_path):
    # during the build, after pythonfmu has written its FMU
    script = CTRL_C + ("import runpy, sys, tire_fmu.fmu.builder as b\n"
                       "b.compile_guard = ctrl_c\n"
                       f"sys.argv = ['build_fmu.py', '-o', {str(tmp_path / 'dist')!r}]\n"
                       "runpy.run_path('build_fmu.py', run_name='__main__')\n")
    done = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 130 and done.stdout == ""
    assert done.stderr == "build_fmu.py: interrupted\n"
    assert list((tmp_path / "dist").iterdir()) == []


def test_ctrl_c_anywhere_in_tire_fmu_is_one_line_status_130():
    # before the command's own work (parsing, loading numpy and scipy) as well as during it
    for where in ("cli.build_parser", "ring.analytic_modes"):
        script = CTRL_C + ("import sys, tire_fmu.cli as cli, tire_fmu.cli.ring as ring\n"
                           f"{where} = ctrl_c\n"
                           "sys.exit(cli.main(['analytic']))\n")
        done = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True,
                              text=True, timeout=120)
        assert done.returncode == 130, (where, done.stderr)
        assert done.stderr == "tire-fmu analytic: interrupted\n", where


def test_an_unwritable_plot_names_the_option_and_the_path(capsys, monkeypatch, tmp_path):
    import tire_fmu.cli.ring as ring

    folder = tmp_path / "a.png"
    folder.mkdir()  # a folder where the figure would go: refused before computing
    monkeypatch.setattr(ring, "analytic_modes", _no_computation)
    code, _, err = run(capsys, "modes", "--elements", "20", "--plot", str(folder))
    assert code == 2
    assert _one_line(err, "tire-fmu modes: error: --plot = ").endswith("is a folder: give a "
                                                                      "file name")
    monkeypatch.undo()
    # a folder that exists but cannot be written (as root too: /proc takes no new files)
    code, _, err = run(capsys, "modes", "--elements", "20", "--max-frequency", "60",
                       "--plot", "/proc/tire.png")
    assert code == 2
    line = _one_line(err, "tire-fmu modes: error: --plot = '/proc/tire.png': cannot write it: ")
    assert "Errno" not in line


def test_export_writes_to_an_unwritable_path_naming_out(capsys):
    code, _, err = run(capsys, "export", "/proc/tire.npz", "--elements", "20")
    assert code == 2
    _one_line(err, "tire-fmu export: error: OUT = '/proc/tire.npz': cannot write it: ")


def test_the_speed_error_names_the_command_line_flag(capsys):
    code, _, err = run(capsys, "modes", "--speed", "90")
    line = _one_line(err, "tire-fmu modes: error: --speed = 90 m/s: must be below the critical")
    assert "--allow-supercritical runs anyway" in line and "(--elements = 100)" in line
    assert not re.search(r"(?<!-)allow_supercritical", line)


def _fake_native_build(out, start_values, platforms=None):
    import zipfile

    with zipfile.ZipFile(out, "w") as archive:
        archive.writestr("binaries/linux64/TireModalNative.so", b"")
    return Path(out)


def test_export_of_a_native_fmu_reports_its_file_once(capsys, monkeypatch, tmp_path):
    import tire_fmu.native as native

    monkeypatch.setattr(native, "build_native_fmu", _fake_native_build)
    target = tmp_path / "tire_c.fmu"
    code, out, err = run(capsys, "export", str(target), "--elements", "40")
    assert code == 0
    assert (out + err).count("wrote") == 1 and f"wrote {target}" in err
    assert "binaries: linux64" in out


def test_fmu_outputs_may_name_a_folder_still_to_be_made(capsys, monkeypatch, tmp_path):
    # README order: `tire-fmu build-fmu dist` before dist/ exists (as build_fmu.py -o dist)
    import tire_fmu.native as native

    monkeypatch.setattr(native, "build_native_fmu", _fake_native_build)
    code, _, err = run(capsys, "export", "--format", "fmu", str(tmp_path / "new" / "dist"),
                       "--elements", "40")
    assert code == 0, err
    assert (tmp_path / "new" / "dist" / "TireModalNative.fmu").is_file()


@pytest.mark.fmu
def test_build_fmu_into_a_folder_that_does_not_exist_yet(capsys, tmp_path):
    from fmpy.validation import validate_fmu

    code, out, err = run(capsys, "build-fmu", str(tmp_path / "dist"))
    assert code == 0, err
    assert validate_fmu(str(tmp_path / "dist" / "TireModal.fmu")) == []


LOAD_DEFAULTS = {"modes": 0.0, "frf": DEFAULT_LOAD_N, "reduce": DEFAULT_LOAD_N,
                 "export": DEFAULT_LOAD_N, "cleat": DEFAULT_LOAD_N,
                 "inplane-cleat": DEFAULT_LOAD_N, "inplane-frf": DEFAULT_LOAD_N,
                 "inplane-reduce": DEFAULT_LOAD_N}


def _load_help(command: str) -> str:
    parser = build_parser([command])
    (commands,) = [a for a in parser._actions if a.dest == "command"]
    (load,) = [a for a in commands.choices[command]._actions if "--load" in a.option_strings]
    return " ".join(load.help.split())


def test_every_load_option_says_its_default_and_what_0_means():
    with_load = [name for name, options in _options() if "--load" in options]
    assert sorted(with_load) == sorted([*LOAD_DEFAULTS, "patch", "fit", "inplane-modes"])
    for command in with_load:
        text = _load_help(command)
        if command in LOAD_DEFAULTS:
            assert re.search(r"default ([\d.]+) N", text), (command, text)
        else:
            assert "no default" in text, (command, text)
        if command != "fit":  # fit's load is a measurement's, > 0
            assert "0 N: the tire touches the road without pressing on it" in text, command


@pytest.mark.parametrize("command", sorted(LOAD_DEFAULTS))
def test_the_default_load_a_help_states_is_the_one_used(capsys, monkeypatch, tmp_path, command):
    stated = float(re.search(r"default ([\d.]+) N", _load_help(command)).group(1))
    assert stated == LOAD_DEFAULTS[command]
    if command == "export":
        import tire_fmu.native as native

        monkeypatch.setattr(native, "build_native_fmu", _fake_native_build)
        data = run_json(capsys, "export", str(tmp_path / "t.fmu"), "--elements", "20")
        assert data["start_values"]["load"] == stated
        used = data["model_at_start_values"]["load_n"]
    else:
        extra = {"modes": ["--elements", "20", "--max-frequency", "60"],
                 "frf": ["--elements", "20", "--points", "3"], "reduce": ["--elements", "20"],
                 "cleat": ["--elements-list", "20", "--length", "0.01"],
                 "inplane-cleat": ["--point-spacing", "0.01", "--f-max", "150", "--speed", "20"],
                 "inplane-frf": ["--point-spacing", "0.01", "--ring-f-max", "150", "--points",
                                 "3"],
                 "inplane-reduce": ["--point-spacing", "0.01", "--ring-f-max", "150",
                                    "--n-states", "10"]}
        data = run_json(capsys, command, *extra[command])
        used = data.get("operating_point", data)["load_n"]
    assert used == pytest.approx(stated, rel=1e-12)


#: In a child: a build without a compiler for win64 (as on a machine without mingw-w64), each
#: entry point's build ended right after the kernels (not timed here: the rest of a build).
NO_WIN64_COMPILER = (
    "import runpy, sys\n"
    "from pathlib import Path\n"
    "scratch = Path(sys.argv[1])\n"
    "import tire_fmu.fmu.builder as b, tire_fmu.native.kernel as k\n"
    "def compile_kernel(destination, platform='linux64'):\n"
    "    if platform == 'win64':\n"
    "        raise k.KernelUnavailable('no C compiler for win64 found (install '\n"
    "                                  'x86_64-w64-mingw32-gcc)')\n"
    "    Path(destination).parent.mkdir(parents=True, exist_ok=True)\n"
    "    Path(destination).write_bytes(b'')\n"
    "    return Path(destination)\n"
    "k.compile_kernel = compile_kernel\n"
    "def build(out, **_):\n"
    "    b.compile_kernels(scratch / 'kernels', 'TireModal.fmu')\n"
    "    path = b.fmu_destination(out, 'TireModal')\n"
    "    path.parent.mkdir(parents=True, exist_ok=True)\n"
    "    path.write_bytes(b'')\n"
    "    return path\n"
    "b.build_fmu = build\n")
WIN64_ADVICE = ("warning: no C compiler for win64 found (install x86_64-w64-mingw32-gcc), then "
                "build again: without it TireModal.fmu steps on win64 with the numpy reference "
                "kernel (the same outputs, slower)")


@pytest.mark.parametrize("entry", ["tire-fmu", "build_fmu.py", "vehicle_demo"])
def test_a_build_warning_is_one_line_that_says_what_to_do(tmp_path, entry):
    """Without a win64 compiler the demo printed Python's raw warning, its file, line and
    source line (`KernelMissingWarning`)."""
    run = {
        "tire-fmu": ("import tire_fmu.cli as cli\n"
                     "sys.exit(cli.main(['build-fmu', sys.argv[1]]))\n"),
        "build_fmu.py": ("sys.argv = ['build_fmu.py', '-o', sys.argv[1]]\n"
                         "runpy.run_path('build_fmu.py', run_name='__main__')\n"),
        "vehicle_demo": ("import vehicle_demo.demo as demo\n"
                         "from vehicle_demo.__main__ import main\n"
                         "def ensure_fmus(folder, *_, **__):\n"
                         "    build(folder)\n"
                         "    raise demo.DemoError('stopped after the build')\n"
                         "demo.ensure_fmus = ensure_fmus\n"
                         "sys.exit(main(['--out', sys.argv[1] + '/out', '--quick']))\n"),
    }[entry]
    done = subprocess.run([sys.executable, "-c", NO_WIN64_COMPILER + run, str(tmp_path)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    prog = {"tire-fmu": "tire-fmu build-fmu", "build_fmu.py": "build_fmu.py",
            "vehicle_demo": "vehicle_demo"}[entry]
    said = [line for line in done.stderr.splitlines()
            if ": warning:" in line or "MissingWarning" in line]
    assert said == [f"{prog}: {WIN64_ADVICE}"], done.stderr
    # no file, line number or source line of Python's
    assert not re.search(r"\.py:\d+|warnings\.warn|Traceback", done.stderr), done.stderr
