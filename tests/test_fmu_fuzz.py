"""Property-based fuzzing of the tire FMUs through fmpy (driver: tests/fuzz_fmu.py).

Each FMU of FUZZ_TARGETS is driven by random FMI call sequences in a subprocess, so that a
crash of the host shows as a failed test with the falsifying calls, not as a dead test run.
The CI profile finishes within a minute; a longer run:

    python3 build_fmu.py -o dist && python3 tests/fuzz_fmu.py dist/TireModal.fmu --profile long
    (likewise the native FMU: ``tire-fmu export dist/TireModalNative.fmu``)

Both FMUs are targets: the Python FMU (pythonfmu) and the native C FMU; another FMU with the
same variables is fuzzed by adding its builder to FUZZ_TARGETS. Every run first replays the
sequences that failed before (``REPLAYS`` in the driver), so CI covers them deterministically.
"""

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")
pytest.importorskip("hypothesis")

pytestmark = pytest.mark.fmu

DRIVER = Path(__file__).with_name("fuzz_fmu.py")
REPLAYS = importlib.import_module("fuzz_fmu").REPLAYS  # after the skips: it needs fmpy
TIMEOUT_S = 300  # the CI profile takes well under a minute; a hang fails, it does not stall


def _python_fmu(folder: Path) -> Path:
    from tire_fmu.fmu.builder import build_fmu

    return build_fmu(folder)


def _native_fmu(folder: Path) -> Path:
    from tire_fmu.native import build_native_fmu

    return build_native_fmu(folder / "TireModalNative.fmu", platforms=("linux64",))


FUZZ_TARGETS = {"python": _python_fmu, "native": _native_fmu}


@pytest.fixture(scope="session", params=sorted(FUZZ_TARGETS))
def fuzz_target(request, tmp_path_factory):
    return FUZZ_TARGETS[request.param](tmp_path_factory.mktemp(f"fuzz_{request.param}"))


def test_random_call_sequences_never_crash_the_host_nor_pass_a_bad_value(fuzz_target):
    root = Path(__file__).resolve().parents[1]
    env = {**os.environ, "PYTHONPATH": str(root) + os.pathsep + os.environ.get("PYTHONPATH", ""),
           "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS", "1")}
    done = subprocess.run([sys.executable, str(DRIVER), str(fuzz_target), "--profile", "ci"],
                          capture_output=True, text=True, timeout=TIMEOUT_S, env=env)
    report = (done.stdout + done.stderr)[-6000:]
    assert done.returncode == 0, f"exit status {done.returncode}:\n{report}"
    assert "no failure found" in done.stdout, report
    assert done.stdout.count("replaying: ") == len(REPLAYS), report
