"""The docs stay true: generated sections equal what docs/generate.py makes of the code and of
the recorded benchmark results, and the README's fmpy example runs cleanly."""

from __future__ import annotations

import importlib.util
import json
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _generate():
    spec = importlib.util.spec_from_file_location("docs_generate", ROOT / "docs" / "generate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_generated_sections_are_current():
    generate = _generate()
    assert generate.stale_sections() == [], "run python3 docs/generate.py"


def test_every_section_has_a_generator_and_every_generator_a_section():
    generate = _generate()
    used = set()
    for name in generate.FILES:
        _, names = generate.render((ROOT / name).read_text())
        used |= set(names)
    assert used == set(generate.GENERATORS)


def test_recorded_results_say_how_they_were_measured():
    records = sorted((ROOT / "docs" / "measured").glob("*.json"))
    assert records
    for path in records:
        data = json.loads(path.read_text())
        assert re.fullmatch(r"python3 benchmarks/bench_\w+\.py .*--record docs/measured/"
                            + re.escape(path.name) + r".*", data["command"]), data["command"]
        assert re.fullmatch(r"\d{4}-\d\d-\d\d", data["recorded"])
        assert data["machine"]["cores"] >= 1


def test_a_hand_edited_number_is_found(tmp_path, monkeypatch):
    generate = _generate()
    (tmp_path / "docs").mkdir()
    shutil.copy(ROOT / "docs" / "vehicle_demo.md", tmp_path / "docs" / "vehicle_demo.md")
    path = tmp_path / "docs" / "vehicle_demo.md"
    text = path.read_text()
    edited = re.sub(r"(<!-- generated: demo-agreement -->\n.*?)(\d+\.\d+) dB", r"\g<1>0.015 dB",
                    text, count=1, flags=re.S)
    assert edited != text
    path.write_text(edited)
    monkeypatch.setattr(generate, "ROOT", tmp_path)
    assert generate.stale_sections(["docs/vehicle_demo.md"]) == [
        "docs/vehicle_demo.md: demo-agreement"]


@pytest.mark.fmu
def test_the_readme_fmpy_example_runs_without_warnings(tmp_path, capsys, monkeypatch):
    pytest.importorskip("fmpy")
    from tire_fmu.fmu.builder import build_fmu

    readme = (ROOT / "README.md").read_text()
    (snippet,) = [block for block in re.findall(r"```python\n(.*?)```", readme, re.S)
                  if "simulate_fmu" in block]
    fmu = build_fmu(tmp_path / "dist")
    monkeypatch.chdir(tmp_path)
    capsys.readouterr()
    exec(compile(snippet, "README.md", "exec"), {})  # noqa: S102 -- the README's own code
    out = capsys.readouterr().out
    assert "Warning" not in out and "missing input" not in out, out
    low, high = (float(x) for x in out.split())
    assert low < 27_700.0 < high  # the bump moves the rim force around the static load
    assert fmu.is_file()
