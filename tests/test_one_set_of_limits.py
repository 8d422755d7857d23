"""One set of limits for the in-plane tire, worded alike wherever it is checked (issue 36).

Both FMUs read the operating point's ranges from the spec (core/inplane_host.py's
HOST_FIELDS, generated into spec.h) and check the contact zone on the mesh as the radial tire
does; at the edges where the runtimes disagreed (load 5e-324, k_cw 1e13, n_elements 8, a
contact point spacing of 1e-4 m, load -1e-300 told "[0, 100000]" although 0 is refused) they
now refuse with the same words, naming the FMU's parameter, never with "ZeroDivisionError",
"ContactSetError" or a C function and core field. The command line checks every number it
takes with the same machinery (FieldSpec, render): every problem at once, in one line,
exit 2.
"""

from __future__ import annotations

import re

import pytest

from tire_fmu.cli import main

pytest.importorskip("fmpy")


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    pytest.importorskip("pythonfmu")
    from tire_fmu.fmu.builder import build_inplane_fmu
    from tire_fmu.native.builder import build_native_inplane_fmu

    folder = tmp_path_factory.mktemp("fmus")
    return {"python": build_inplane_fmu(folder),
            "native": build_native_inplane_fmu(folder, platforms=("linux64",))}


def _problems(path, **parameters) -> list[str]:
    """The parameter problems fmi2ExitInitializationMode logs (it must refuse)."""
    from fmpy.fmi1 import FMICallException
    from inplane_support import Instance

    fmu = Instance(str(path), format_log="Native" in str(path), **parameters)
    try:
        with pytest.raises(FMICallException):
            fmu.start()
        return [re.sub(r"^parameter problem \d+/\d+: ", "", message)
                for _, message in fmu.log if message.startswith("parameter problem")]
    finally:
        fmu.fmu.freeInstance()


INTERNAL = re.compile(r"ZeroDivision|ContactSetError|Error:|inplane_\w+|refused \(status|"
                      r"_m = |load_n|deflection_m|zone_length_m|point_spacing_m")


@pytest.mark.fmu
@pytest.mark.parametrize("parameters, name, words", [
    (dict(load=5e-324), "load", "must be a load whose static footprint the model finds"),
    (dict(load=1e-3), "load", "must be a load whose static footprint the model finds"),
    (dict(k_cw=1e13), "load", "k_cw = 1e+13 N/m^2 and n_elements = 100 its contact set"),
    (dict(n_elements=8), "contact_zone_length",
     "must be at least 1.3 m (one node either side)"),
    (dict(contact_point_spacing=1e-4), "contact_point_spacing",
     "more than the 4000 the contact solve takes"),
    (dict(load=-1e-300), "load", "must be in (0, 100000] N"),
    (dict(load=0.0), "load", "must be in (0, 100000] N"),
    (dict(n_elements=801), "n_elements", "must be an integer in [8, 800]"),
])
def test_both_fmus_refuse_the_edges_with_the_same_words(fmus, parameters, name, words):
    python, native = (_problems(fmus[kind], **parameters) for kind in ("python", "native"))
    assert python == native, (python, native)
    assert len(python) == 1 and python[0].startswith(f"{name} = "), python
    assert words in python[0]
    assert not INTERNAL.search(python[0]), python[0]


@pytest.mark.parametrize("argv, words", [
    (["inplane-modes", "--nmax", "0", "--speed", "5"],
     ["--nmax = 0: must be an integer in [1, 50]"]),
    (["inplane-modes", "--max-frequency", "1e300"],
     ["--max-frequency = 1e+300 Hz: must be in (0, 100000] Hz"]),
    (["inplane-speed-sweep", "--elements", "0"],
     ["--elements = 0: must be an integer in [8, 1600]"]),
    (["inplane-reduce", "--load", "-1e-300", "--elements", "3", "--band", "0,1",
      "--target-error", "nan", "--out", "x.txt"],
     ["5 problems", "--load = -1e-300 N: must be in [0, 100000] N", "--elements = 3",
      "--band = '0,1'", "--target-error = nan: must be a finite number",
      "--out = 'x.txt'"]),
    (["inplane-cleat", "--load", "0.001", "--f-max", "1e9", "--step", "1"],
     ["--f-max = 1e+09 Hz: must be in [1, 100000] Hz (0: every DOF)",
      "--step = 1 s: must be in [1e-06, 0.001] s"]),
    (["frf", "--max-frequency", "1e300", "--f-max", "-1", "--elements", "3"],
     ["3 problems", "--max-frequency = 1e+300 Hz", "--f-max = -1 Hz", "--elements = 3"]),
    (["fit", "--slip-stiffness", "1e300", "--slip-load=-1", "--tangential-mode", "2=inf"],
     ["--slip-stiffness = 1e+300 N: must be in (0, 1e+12] N",
      "--slip-load = -1 N: must be in (0, 100000] N", "HZ = inf: must be a finite number"]),
])
def test_every_number_on_the_command_line_is_checked_in_one_line(argv, words, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, err
    assert "[0, 0]" not in err  # --elements 0 made --nmax's range [0, 0]


def test_a_load_the_footprint_cannot_resolve_is_the_loads_problem_on_the_command_line(capsys):
    """inplane-cleat at 1 mN: ZeroDivisionError inside the footprint's secant, an internal
    error; now the in-plane FMU's words for --load."""
    assert main(["inplane-cleat", "--load", "0.001", "--elements", "20"]) == 2
    err = capsys.readouterr().err
    assert "--load = 0.001 N: must be a load whose static footprint the model finds" in err
    assert "--elements = 20" in err and "internal error" not in err


def test_a_folder_given_for_a_file_is_refused(tmp_path, capsys):
    target = f"{tmp_path / 'x.npz'}/"
    assert main(["inplane-reduce", "--elements", "20", "--out", target]) == 2
    assert "names a folder" in capsys.readouterr().err
    assert not (tmp_path / "x.npz").exists()
