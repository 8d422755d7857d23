"""The docs stay true: generated sections and values equal what docs/generate.py makes of the
code and of the recorded benchmark results, no measured-looking number is typed into the
checked prose, and the README's fmpy example runs cleanly."""

from __future__ import annotations

import functools
import importlib.util
import json
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@functools.cache
def _generate():
    """docs/generate.py, loaded once: its generators' texts are made once per process."""
    spec = importlib.util.spec_from_file_location("docs_generate", ROOT / "docs" / "generate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_generated_sections_are_current():
    generate = _generate()
    assert generate.stale_sections() == [], "run python3 docs/generate.py"


def _used_names(generate, files=None) -> set[str]:
    used = set()
    for name in files or generate.FILES:
        _, names = generate.render((ROOT / name).read_text())
        used |= set(names)
    return used


def test_every_section_has_a_generator_and_every_generator_a_section():
    generate = _generate()
    used = {name for name in _used_names(generate) if not name.startswith("spec:")}
    assert used == set(generate.GENERATORS) | set(generate.VALUES)


def test_no_measured_number_is_typed_into_the_checked_prose():
    generate = _generate()
    typed = [x for name in generate.PROSE_CHECKED for x in generate.typed_numbers(name)]
    assert typed == [], "generate these (docs/generate.py): " + "; ".join(typed)


def test_every_definition_allowed_in_prose_is_in_its_file():
    generate = _generate()
    for name, phrases in generate.DEFINITIONS.items():
        text = (ROOT / name).read_text()
        for phrase in phrases:
            assert phrase in text, (name, phrase)


@pytest.mark.parametrize("name, typed", [
    ("docs/vehicle_demo.md", "the tire's damping is 215 N·s/m"),
    ("docs/vehicle_demo.md", "with m ≈ 39 kg"),
    ("docs/vehicle_demo.md", "(ζ ≈ 0.16)"),
    ("docs/vehicle_demo.md", "the largest stable step is **7.4 ms**"),
    ("docs/vehicle_demo.md", "wheel hop from 12.7 Hz to 11.9 Hz"),
    ("docs/fmu.md", "`n_elements` stops at 1000"),
    ("docs/fmu.md", "and about a minute and 1 GB rolling"),
])
def test_a_number_typed_into_prose_is_found(name, typed):
    generate = _generate()
    text = (ROOT / name).read_text() + f"\nA sentence added by hand: {typed}.\n"
    found = generate.typed_numbers(name, text)
    assert len(found) >= 1 and all(x.startswith(f"{name}:{text.count(chr(10))}:")
                                   for x in found), found


def test_numbers_in_code_generated_values_and_definitions_are_not_typed():
    generate = _generate()
    text = ("Run `tire-fmu modes --speed 20` (N = 100, n = 4, ISO 8608, §4.5, pythonfmu 0.7.0): "
            "<!-- value: demo-f-max -->300 Hz<!-- /value -->, Welch's 95 % band.\n"
            "```\nh = 1e-4 s\n```\n")
    assert generate.typed_numbers("docs/vehicle_demo.md", text) == []


def test_the_numbers_the_issue_found_typed_are_generated():
    """docs/vehicle_demo.md's damping, rim-side mass, wheel-hop shift, stable steps and damping
    ratios, and docs/fmu.md's mesh limit and variable count, come from records and code."""
    generate = _generate()
    demo = _used_names(generate, ["docs/vehicle_demo.md"])
    assert {"demo-damping", "demo-rim-side-mass", "demo-wheel-hop-shift", "demo-stable-steps",
            "demo-zetas", "demo-coherence-drawn"} <= demo
    fmu = _used_names(generate, ["docs/fmu.md"])
    assert {"spec:MAX_ELEMENTS", "mesh-size-cost", "fmu-msg-reference"} <= fmu
    from tire_fmu.fmu.interface import fmu_variables

    assert f"TireModal has {len(fmu_variables())} variables" in generate.value_text(
        "fmu-msg-reference")


def test_a_hand_edited_value_is_found(tmp_path, monkeypatch):
    generate = _generate()
    (tmp_path / "docs").mkdir()
    text = (ROOT / "docs" / "fmu.md").read_text()
    edited = re.sub(r"(<!-- value: spec:MAX_ELEMENTS -->)\d+", r"\g<1>1000", text, count=1)
    assert edited != text
    (tmp_path / "docs" / "fmu.md").write_text(edited)
    monkeypatch.setattr(generate, "ROOT", tmp_path)
    assert generate.stale_sections(["docs/fmu.md"]) == ["docs/fmu.md: spec:MAX_ELEMENTS"]


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
def test_the_readme_fmpy_example_runs_without_warnings(tmp_path):
    """The README's fmpy example, its commands as they stand there (the road, then the
    example script on the FMU it builds), prints its line and no warning of fmpy's."""
    import shlex
    import subprocess
    import sys

    readme = (ROOT / "README.md").read_text()
    (block,) = [b for b in re.findall(r"```bash\n(.*?)```", readme, re.S)
                if "docs/examples/" in b]
    out = ""
    for line in block.strip().splitlines():
        words = shlex.split(line.split("#")[0])
        if words[0] == "tire-fmu":
            words = [sys.executable, "-m", "tire_fmu", *words[1:]]
        else:  # python3 docs/examples/...: the repository's script
            words = [sys.executable, str(ROOT / words[1]), *words[2:]]
        done = subprocess.run(words, cwd=tmp_path, capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, done.stderr
        out = done.stdout + done.stderr
    assert "Warning" not in out and "missing input" not in out, out
    assert "rim_Fz from" in out and "peak" in out
