"""Tire data files: the shipped GL073A file is today's defaults exactly, round trips are exact,
bad files name every bad key, every CLI command reads --tire-file under --tire overrides, and
FMUs built with a tire file run in fmpy exactly as the core with that tire."""

import json
import warnings
import zipfile
from dataclasses import fields, replace

import numpy as np
import pytest

from tire_fmu.core import TireParameters, analytic_modes, critical_speed, validate
from tire_fmu.core.parameters import TIRE_FIELDS
from tire_fmu.tire_files import (
    TireFileError,
    read_tire_file,
    shipped_tire_names,
    shipped_tire_path,
    tire_file_text,
    write_tire_file,
)


def test_the_shipped_gl073a_files_are_the_defaults_exactly():
    """GL073A_tied is the default tire; GL073A is the paper's, the same data with the
    lumped sidewall (sidewall_max_order = 0)."""
    tied, shipped = read_tire_file("GL073A_tied"), read_tire_file("GL073A")
    assert tied.tire == TireParameters()
    for f in fields(TireParameters):  # bit for bit, not approximately
        assert getattr(tied.tire, f.name) == f.default
        paper = 0.0 if f.name == "sidewall_max_order" else f.default
        assert getattr(shipped.tire, f.name) == paper
    assert shipped.defaulted == () and shipped.name == "GL073A"
    assert "Liu" in shipped.source
    assert shipped_tire_path("gl073a") == shipped.path  # names are case-insensitive
    assert {"GL073A", "GL073A_shear", "GL073A_tied"} <= set(shipped_tire_names())


def test_any_tire_round_trips_exactly(tmp_path):
    rng = np.random.default_rng(7)
    for _ in range(20):
        tire = TireParameters(**{
            f.name: (float(rng.integers(0, 20)) if TIRE_FIELDS[f.name].integer else
                     f.default * float(rng.uniform(0.5, 1.5)) if f.default else
                     float(rng.uniform(0.0, 1.0))) for f in fields(TireParameters)})
        path = write_tire_file(tmp_path / "t.toml", tire, name='quote " and \\ back',
                               metadata={"fit": {"free": ["k_r1"], "rms": 1e-3,
                                                 "intervals": {"k_r1": [1.0, 2.5e6]}}})
        back = read_tire_file(path)
        assert back.tire == tire
        assert back.name == 'quote " and \\ back'
        assert back.metadata["fit"]["intervals"]["k_r1"] == [1.0, 2.5e6]


def test_a_bad_file_names_every_bad_key(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("\n".join([
        'format = "tire_fmu-tire/1"',
        "colour = 3",
        "[parameters]",
        "R = 650.0",  # mm, say, and the unit says so
        "b = 0.35",  # no unit
        'k_r1 = "stiff"',
        "EI = -1.0",
        "wheel = 2.0",
        "[units]",
        'R = "mm"',
        'k_r1 = "N/m^2"',
        'EI = "N*m^2"',
        'k_r2 = "N/m^2"',
    ]))
    with pytest.raises(TireFileError) as caught:
        read_tire_file(path)
    text = str(caught.value)
    assert text.startswith(str(path))
    for expected in ("unknown key 'colour'",
                     "units.R = 'mm': parameters.R must be given in \"m\"",
                     "units.b missing", "parameters.k_r1 = 'stiff': must be a number",
                     "EI = -1 N*m^2: must be in (0, 1e+08]", "parameters.wheel: not a tire",
                     "units.k_r2: no parameters.k_r2"):
        assert expected in text, expected
    path.write_text("[parameters\nR = 1")
    with pytest.raises(TireFileError, match="not valid TOML"):
        read_tire_file(path)
    with pytest.raises(TireFileError, match="no such file and no shipped tire.*GL073A"):
        read_tire_file("nonesuch")
    with pytest.raises(TireFileError, match="no such file"):
        read_tire_file(tmp_path / "missing.toml")


def test_a_partial_file_warns_and_takes_the_defaults(tmp_path):
    path = tmp_path / "partial.toml"
    path.write_text('[parameters]\nk_r1 = 7e6\nsidewall_pressure_exponent = 0.8\n'
                    '[units]\nk_r1 = "N/m^2"\nsidewall_pressure_exponent = ""\n')
    with pytest.warns(UserWarning, match="does not give R, b, inflation_pressure"):
        partial = read_tire_file(path)
    assert partial.tire == TireParameters(k_r1=7e6, sidewall_pressure_exponent=0.8)
    assert "k_r1" not in partial.defaulted and "EI" in partial.defaulted


def test_a_file_with_a_byte_order_mark_reads_as_without(tmp_path):
    # as Windows Notepad saves UTF-8: it read as "Invalid statement (at line 1, column 1)"
    plain = tire_file_text(TireParameters(k_r1=7e6), name="mark")
    path = tmp_path / "marked.toml"
    path.write_bytes(b"\xef\xbb\xbf" + plain.encode("utf-8"))
    assert read_tire_file(path).tire == TireParameters(k_r1=7e6)


@pytest.mark.parametrize("nested", ["x = " + "[" * 5000 + "]" * 5000,
                                    "x = " + "{a = " * 5000 + "}" * 5000])
def test_a_deeply_nested_file_is_refused_naming_it(tmp_path, capsys, nested):
    from tire_fmu.cli import main

    path = tmp_path / "nested.toml"
    path.write_text(nested + "\n")
    with pytest.raises(TireFileError, match=f"^{path}: not a tire file: arrays or tables "
                                            "nested too deeply"):
        read_tire_file(path)
    assert main(["analytic", "--tire-file", str(path)]) == 2  # not "internal error"
    err = capsys.readouterr().err
    assert err == (f"tire-fmu analytic: error: --tire-file: {path}: not a tire file: arrays or "
                   "tables nested too deeply to read (a tire file nests at most a few "
                   "levels)\n")


def test_written_text_lists_units_and_descriptions():
    text = tire_file_text(TireParameters())
    assert 'k_r1 = "N/m^2"' in text and "# tread-sidewall radial stiffness" in text
    with pytest.raises(TireFileError, match="no null"):
        tire_file_text(TireParameters(), metadata={"fit": {"x": None}})


# -- the command line -------------------------------------------------------------------------

def run(capsys, *argv):
    from tire_fmu.cli import main

    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_every_command_takes_tire_file_and_tire_overrides_it(tmp_path, capsys):
    from tire_fmu.cli import build_parser

    parser = build_parser()
    commands = parser._subparsers._group_actions[0].choices
    with_tire = [name for name, sub in commands.items()
                 if any("--tire" in a.option_strings for a in sub._actions)]
    assert all(any("--tire-file" in a.option_strings for a in commands[name]._actions)
               for name in with_tire)
    assert {"modes", "analytic", "critical-speed", "fit", "build-fmu", "export"} <= \
        set(with_tire)

    shear = read_tire_file("GL073A_shear").tire
    code, out, _ = run(capsys, "analytic", "--nmax", "4", "--tire-file", "GL073A_shear",
                       "--tire", "k_r2=5e6", "--json")
    assert code == 0
    expected = analytic_modes(replace(shear, k_r2=5e6), range(5))
    assert json.loads(out)["in_phase_hz"] == expected.in_phase_hz.tolist()

    code, out, _ = run(capsys, "critical-speed", "--elements", "200", "--tire-file",
                       "GL073A_shear", "--json")
    assert json.loads(out)["critical_speed_m_s"] == critical_speed(shear, 200).speed_m_s

    code, out, _ = run(capsys, "modes", "--elements", "40", "--max-frequency", "80",
                       "--tire-file", str(shipped_tire_path("GL073A_shear")), "--json")
    assert code == 0 and json.loads(out)["modes"]

    code, _, err = run(capsys, "analytic", "--tire-file", "nonesuch")
    assert code == 2 and "--tire-file: tire file 'nonesuch'" in err and err.count("\n") == 1


# -- FMUs built for a tire ----------------------------------------------------------------------

N = 40


@pytest.mark.fmu
def test_python_fmu_built_with_a_tire_file_runs_as_the_core_with_that_tire(tmp_path, capsys):
    fmpy = pytest.importorskip("fmpy")
    pytest.importorskip("pythonfmu")
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    from tire_fmu.core.contact_dynamics import (
        INPUT_NAMES,
        OUTPUT_NAMES,
        ContactSimulator,
        build_contact_model,
    )

    code, out, _ = run(capsys, "build-fmu", str(tmp_path), "--tire-file", "GL073A_shear",
                       "--json")
    assert code == 0
    path = json.loads(out)["path"]
    shear = read_tire_file("GL073A_shear").tire
    description = read_model_description(path)
    starts = {v.name: v.start for v in description.modelVariables}
    for name, value in shear.as_dict().items():
        assert float(starts[name]) == value, name  # the start values are the file's
    with zipfile.ZipFile(path) as archive:
        assert json.loads(archive.read("resources/tire_parameters.json")) == shear.as_dict()

    speed = 12.0
    tire, op = validate(shear.as_dict(), {"n_elements": N, "load_n": 27_000.0,
                                          "speed_m_s": speed})
    core = ContactSimulator(build_contact_model(tire, op))
    refs = {v.name: v.valueReference for v in description.modelVariables}
    fmu = FMU2Slave(guid=description.guid, unzipDirectory=extract(path),
                    modelIdentifier=description.coSimulation.modelIdentifier,
                    instanceName="shear")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([refs["n_elements"]], [N])  # the tire data: the start values, not set
    fmu.setReal([refs["load"], refs["speed"]], [27_000.0, speed])
    fmu.exitInitializationMode()
    h = 1e-4
    t = np.arange(300) * h
    inputs = np.column_stack([2e-3 * np.sin(2 * np.pi * 9 * t),
                              2e-3 * 2 * np.pi * 9 * np.cos(2 * np.pi * 9 * t),
                              1e-3 * np.sin(2 * np.pi * 31 * t),
                              1e-3 * 2 * np.pi * 31 * np.cos(2 * np.pi * 31 * t)])
    got, expected = [], []
    for i, u in enumerate(inputs):
        fmu.setReal([refs[n] for n in INPUT_NAMES], list(u))
        fmu.doStep(i * h, h)
        got.append(fmu.getReal([refs[n] for n in OUTPUT_NAMES]))
        expected.append(core.step(h, *u))
    fmu.terminate()
    fmu.freeInstance()
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12 * 27_000.0)
    # and it is not the paper's tire that ran
    paper, op = validate({}, {"n_elements": N, "load_n": 27_000.0, "speed_m_s": speed})
    other = ContactSimulator(build_contact_model(paper, op))
    differs = np.array([other.step(h, *u) for u in inputs]) - np.array(got)
    assert np.max(np.abs(differs)) > 1.0  # newtons
    del fmpy


@pytest.mark.fmu
def test_native_export_with_a_tire_file_is_built_for_that_tire(tmp_path, capsys):
    pytest.importorskip("fmpy")
    from fmpy import read_model_description

    out = tmp_path / "shear.fmu"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code, _, err = run(capsys, "export", str(out), "--elements", str(N), "--tire-file",
                           "GL073A_shear", "--inflation-pressure", "7e5")
    assert code == 0, err
    starts = {v.name: v.start for v in read_model_description(str(out)).modelVariables}
    expected = replace(read_tire_file("GL073A_shear").tire, inflation_pressure=7e5)
    for name, value in expected.as_dict().items():
        assert float(starts[name]) == value, name


def test_the_inplane_tire_file_ships_the_tangential_data_with_their_units(tmp_path):
    from tire_fmu.core.inplane import TangentialParameters

    shipped = read_tire_file("GL073A_inplane")
    assert shipped.tangential == TangentialParameters()
    assert shipped.tire == read_tire_file("GL073A").tire  # the paper's radial data
    assert read_tire_file("GL073A").tangential is None
    text = shipped.path.read_text().replace('k_tx = "N/m^2"', 'k_tx = "N/mm^2"').replace(
        "EA = 10000000.0", "EA = 'stiff'")
    bad = tmp_path / "bad.toml"
    bad.write_text(text + '\n[extra]\n')
    with pytest.raises(TireFileError) as error:
        read_tire_file(bad)
    message = str(error.value)
    for part in ("tangential_units.k_tx = 'N/mm^2'", "tangential.EA = 'stiff'", "'extra'"):
        assert part in message, part


def test_the_inplane_commands_read_the_tangential_table_and_override_it(tmp_path, capsys):
    import json

    from tire_fmu.cli import main
    from tire_fmu.core.inplane import InPlaneRing, InPlaneTire, TangentialParameters
    from tire_fmu.core.inplane_modes import tire_modes

    text = read_tire_file("GL073A_inplane").path.read_text().replace(
        "k_t1 = 1600000.0", "k_t1 = 3200000.0")
    custom = tmp_path / "stiff_sidewall.toml"
    custom.write_text(text)
    for extra, tangential in (([], TangentialParameters(k_t1=3.2e6)),
                              (["--tangential", "k_t2=2e6"],
                               TangentialParameters(k_t1=3.2e6, k_t2=2e6))):
        assert main(["inplane-modes", "--tire-file", str(custom), "--elements", "32",
                     "--max-frequency", "60", "--json", *extra]) == 0
        data = json.loads(capsys.readouterr().out)
        assert data["tangential"] == tangential.as_dict()
        expected = tire_modes(InPlaneRing(InPlaneTire(read_tire_file(custom).tire, tangential),
                                          32), f_max_hz=60)
        assert [m["frequency_hz"] for m in data["modes"]] == pytest.approx(
            list(expected.frequencies_hz()), rel=1e-12)
