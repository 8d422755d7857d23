"""What the docs, help texts and shipped data files say an input, output or example means is
what the code does: road_z's reference point, rim_Fx's content and limits, the critical-speed
explanation for the tire in use, the orders of the shipped mode table, the README's fit."""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import numpy as np
import pytest

from tire_fmu.cli import build_parser, main
from tire_fmu.core import DEFAULT_LOAD_N, OperatingPoint, TireParameters, build_model, validate
from tire_fmu.core.contact_dynamics import ContactSimulator, build_contact_model

ROOT = Path(__file__).resolve().parents[1]


def _section(path: str, heading: str) -> str:
    text = (ROOT / path).read_text()
    start = text.index(heading)
    end = text.find("\n#", start + len(heading))
    return text[start:end if end > 0 else None]


# -- road_z: at the front of the contact zone -------------------------------------------------

def test_frf_help_measures_the_road_where_the_fmu_does():
    parser = build_parser()
    frf = parser._subparsers._group_actions[0].choices["frf"]
    text = " ".join(frf.format_help().split())
    assert "front of the contact zone" in text and "leading edge" not in text


@pytest.mark.parametrize("path, heading", [
    ("docs/theory.md", "### 9.1 The input/output model"),
    ("docs/vehicle_demo.md", "## The models"),
    ("docs/vehicle_demo.md", "## Estimation details"),
])
def test_the_docs_measure_the_road_at_the_front_of_the_contact_zone(path, heading):
    text = " ".join(_section(path, heading).split())
    assert "front of the contact zone" in text
    assert "leading edge" not in text


def test_the_road_of_the_io_model_is_measured_at_the_zone_front():
    """What §9.1 now says: the windows start at the zone front, not at the patch's edge."""
    model = build_model(TireParameters(), OperatingPoint(patch_length_m=0.204,
                                                         speed_m_s=20.0))
    zone, windows = model.patch.zone, model.patch.road
    assert windows.front_m == pytest.approx(zone.road_windows_m(model.patch.deflection_m)[1]
                                            .max())
    assert windows.front_m > model.patch.length_m  # well ahead of the patch


# -- rim_Fx: a projection of radial forces ----------------------------------------------------

def test_rim_fx_is_described_with_its_limits():
    from tire_fmu.fmu.interface import fmu_variables

    (rim_fx,) = [v for v in fmu_variables() if v.name == "rim_Fx"]
    for words in ("projection", "radial", "no tangential", "friction"):
        assert words in rim_fx.description
    for path in ("README.md", "docs/fmu.md", "docs/theory.md"):
        text = " ".join((ROOT / path).read_text().split())
        assert "projection of the ring's radial forces" in text, path


def test_rim_fx_is_zero_at_rest_and_a_rolling_resistance_at_speed():
    """What docs/fmu.md says rim_Fx holds on a flat road: nothing at rest, whatever the
    vertical motion; rolling, the horizontal projection of the footprint's radial forces,
    pointing backwards."""
    tire, op = validate({}, {"n_elements": 40})
    sim = ContactSimulator(build_contact_model(tire, op))
    fx = [sim.step(1e-4, 1e-4 * np.sin(k / 5), 0.0, 2e-4 * np.sin(k / 3), 0.0)[1]
          for k in range(200)]
    assert np.max(np.abs(fx)) < 1e-9 * DEFAULT_LOAD_N
    tire, op = validate({}, {"n_elements": 100, "speed_m_s": 20.0})
    footprint = build_model(tire, op).patch.footprint
    assert footprint.n_active > 1
    zone = footprint.zone  # the points' forces reach the nodes through Iᵀ, radially
    projection = float(footprint.forces_n @ (zone.interpolation @ np.sin(zone.theta)))
    sim = ContactSimulator(build_contact_model(tire, op))
    rolling = sim.step(1e-4, 0.0, 0.0, 0.0, 0.0)[1]
    assert rolling == pytest.approx(projection, rel=1e-9)
    assert rolling < -1e-3 * DEFAULT_LOAD_N


# -- critical speed: the explanation fits the tire --------------------------------------------

def test_critical_speed_explains_the_shear_tire_with_its_wave_speed(capsys):
    from tire_fmu.tire_files import read_tire_file

    assert main(["critical-speed", "--tire-file", "GL073A_shear", "--elements", "40"]) == 0
    sheared = capsys.readouterr().out
    shear = read_tire_file("GL073A_shear").tire
    assert f"{np.sqrt(shear.sidewall_shear / shear.m_s):.4g} m/s" in sheared
    assert "artefact of the lumped sidewall" not in sheared
    assert main(["critical-speed", "--elements", "40", "--tire-file", "GL073A"]) == 0
    assert "artefact of the lumped sidewall" in capsys.readouterr().out
    assert main(["critical-speed", "--elements", "40"]) == 0  # the default, tied sidewall
    tied = capsys.readouterr().out
    assert "artefact of the lumped sidewall" not in tied and "§8.10" in tied


# -- the shipped mode table -------------------------------------------------------------------

def test_the_mode_tables_header_names_the_orders_it_holds():
    from tire_fmu.measurements import read_modes
    from tire_fmu.tire_files import shipped_tire_path

    path = shipped_tire_path("GL073A").with_name("GL073A_modes.csv")
    header = " ".join(line.lstrip("# ") for line in path.read_text().splitlines()
                      if line.startswith("#"))
    stated = re.search(r"orders n = ([\d, ]+)", header)
    assert stated, header
    orders = sorted(int(n) for n in stated.group(1).replace(",", " ").split())
    modes = read_modes(path)
    for branch in ("in", "out"):
        assert sorted(m.order for m in modes if m.branch == branch) == orders


# -- the README's fit recovers a tire it did not start from -----------------------------------

def test_the_readme_fit_starts_far_from_gl073a_and_recovers_it(capsys, monkeypatch):
    readme = (ROOT / "README.md").read_text()
    section = re.search(r"<!-- generated: readme-fit -->\n```bash\n(.*?)```", readme, re.S)
    assert section, "README.md has no generated fit example"
    command = section.group(1).replace("\\\n", " ").split()
    assert command[:2] == ["tire-fmu", "fit"]
    monkeypatch.chdir(ROOT)
    assert main([*command[1:], "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)
    truth = TireParameters()
    for p in fit["parameters"]:
        known = getattr(truth, p["name"])
        assert abs(p["start"] / known - 1) > 0.2, p["name"]  # a start worth fitting from
        assert p["value"] == pytest.approx(known, rel=1e-6), p["name"]


# -- the demo's figures as the docs describe them ---------------------------------------------

def test_the_ride_figure_row_says_when_coherence_is_drawn():
    spec = importlib.util.spec_from_file_location("docs_generate",
                                                  ROOT / "docs" / "generate.py")
    generate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate)
    (row,) = [line for line in (ROOT / "docs/vehicle_demo.md").read_text().splitlines()
              if line.startswith("| `ride_transfer_functions.png` |")]
    assert "<!-- value: demo-coherence-drawn -->" in row
    assert generate.value_text("demo-coherence-drawn") in row


# -- the default contact point spacing, as its comment describes it ----------------------------

def test_the_default_spacing_comment_quotes_the_cleat_record():
    """parameters.DEFAULT_POINT_SPACING_M's comment: the error the default spacing leaves over
    a 20 mm and a 10 mm cleat, rounded to whole per cent, is the record's (docs/theory.md
    §4.6 quotes it to 0.1 %), and it is first order in the spacing."""
    from tire_fmu.core.studies import richardson

    spec = importlib.util.spec_from_file_location("docs_generate",
                                                  ROOT / "docs" / "generate.py")
    generate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate)
    lines = (ROOT / "tire_fmu/core/parameters.py").read_text().split("\n")
    at = next(i for i, line in enumerate(lines) if line.startswith("DEFAULT_POINT_SPACING_M"))
    start = at
    while lines[start - 1].startswith("#:"):
        start -= 1
    comment = " ".join(line[2:].strip() for line in lines[start:at])
    assert "first order in the spacing" in comment
    quoted = re.search(r"20 mm cleat comes out about (\d+) % and over a 10 mm one about (\d+) %",
                       comment)
    assert quoted, comment
    for text, cleat_m in zip(quoted.groups(), (0.02, 0.01)):
        recorded = float(generate.value_text(f"cleat-spacing-deficit-{cleat_m * 1e3:g}mm")
                         .rstrip(" %"))
        assert int(text) == round(recorded)
    _, results = generate._cleat_record()
    for cleat_m in (0.01, 0.02):
        rows = sorted((r for r in results["spacing"]["rows"] if r["cleat_m"] == cleat_m),
                      key=lambda r: -r["point_spacing_m"])
        _, order = richardson([r["point_arc_m"] for r in rows], [r["peak_rise_kn"] for r in rows])
        assert 0.8 < order < 1.5
