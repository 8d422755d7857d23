"""docs/fmu.md's examples, run as a user runs them: the road commands their
docstrings give, then the script on the FMU it is written for; what each prints is checked
against what the tire must do there."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from tire_fmu.core.parameters import TireParameters
from vehicle_demo.truck import build_tire_fmu

pytestmark = pytest.mark.fmu

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
#: each example's script and the FMU it is written for
SCRIPTS = {"cleat_road_file.py": "TireInPlane",
           "quarter_car_road_file.py": "TireInPlaneNative",
           "tire_inplane_braking.py": "TireInPlane",
           "tire_inplane_native_host_road.py": "TireInPlaneNative"}
NUMBER = r"(-?[\d.]+)"


def _run(script: str, folder: Path) -> str:
    """Run the road commands of the script's docstring in ``folder``, then the script on its
    FMU and road (the docstring's own arguments); what it printed."""
    text = (EXAMPLES / script).read_text()
    docstring = text.split('"""')[1]
    for line in docstring.splitlines():
        if not line.strip().startswith("tire-fmu road "):
            continue
        words = shlex.split(line.split("#")[0])
        if words:
            subprocess.run([sys.executable, "-m", "tire_fmu", *words[1:]], cwd=folder,
                           check=True, capture_output=True, text=True)
    command = next(shlex.split(line.split("#")[0]) for line in docstring.splitlines()
                   if line.strip().startswith(f"python docs/examples/{script}"))
    fmu = build_tire_fmu(SCRIPTS[script], folder / "dist")
    assert Path(command[2]).name == fmu.name
    done = subprocess.run([sys.executable, str(EXAMPLES / script), str(fmu), command[3]],
                          cwd=folder, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_every_example_is_in_the_docs_whole():
    import importlib.util

    spec = importlib.util.spec_from_file_location("docs_generate",
                                                  EXAMPLES.parent / "generate.py")
    generate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate)
    shown = generate.EXAMPLES
    assert sorted(shown.values()) == sorted(SCRIPTS)
    fmu_md = (EXAMPLES.parent / "fmu.md").read_text()
    for name in shown:
        assert f"<!-- generated: {name} -->" in fmu_md


def test_the_tire_over_a_cleat_file(tmp_path):
    out = _run("cleat_road_file.py", tmp_path)
    start, peak = map(float, re.search(rf"rim_Fz from {NUMBER} N to a peak of {NUMBER} N",
                                       out).groups())
    # wheel_z's start value carries the default load; the 20 mm cleat is more than the
    # tire's static deflection, so the force over it rises far above that
    from tire_fmu.fmu.interface import inplane_fmu_variables

    load = next(v.start for v in inplane_fmu_variables() if v.name == "load")
    assert start == pytest.approx(load, rel=1e-3)
    assert peak > 1.5 * load
    radius = float(re.search(rf"loaded radius {NUMBER} m", out).group(1))
    assert 0.9 * TireParameters().R < radius < TireParameters().R


def test_the_quarter_car_on_a_road_file(tmp_path):
    out = _run("quarter_car_road_file.py", tmp_path)
    peak, share = map(float, re.search(rf"was {NUMBER} N \({NUMBER} %", out).groups())
    # a class C road at 15 m/s loads the tire dynamically by a tenth of its load or so,
    # never by more than the load (it would leave the road)
    assert 2.0 < share < 100.0


def test_the_in_plane_tire_brakes_the_corner(tmp_path):
    out = _run("tire_inplane_braking.py", tmp_path)
    radius = float(re.search(rf"effective radius of {NUMBER} m", out).group(1))
    force, slip, end = map(float, re.search(
        rf"rim_Fx {NUMBER} N, slip {NUMBER} %, 20 -> {NUMBER} m/s", out).groups())
    # free rolling, the tire rolls on a radius between its loaded one and its tread's
    assert 0.95 * TireParameters().R < radius < TireParameters().R
    # the brake's 2 kN m over a 0.65 m tire: a drag of the order of 3 kN, a small slip
    assert -6000.0 < force < -1000.0 and -5.0 < slip < 0.0
    # the corner slowed under the tire's own force: 0.8 s at about 1 m/s^2
    assert 18.5 < end < 19.8


def test_the_host_road_and_the_same_road_as_a_file_give_the_same_forces(tmp_path):
    out = _run("tire_inplane_native_host_road.py", tmp_path)
    host, file = map(float, re.search(rf"{NUMBER} N on the host's road, {NUMBER} N on the",
                                      out).groups())
    assert host > 1.3 * 27654.0  # the 15 mm bump loads the tire
    assert host == pytest.approx(file, rel=1e-3)
