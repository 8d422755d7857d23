"""Fresh-process initialisation of TireModal.fmu through fmpy, beside a minimal pythonfmu slave.

What a host pays to bring the Python FMU up once: a new Python process that imports fmpy, then
fmi2Instantiate (pythonfmu's wrapper imports the slave module and constructs the slave),
fmi2SetupExperiment, fmi2EnterInitializationMode and fmi2ExitInitializationMode at the default
parameters (N = 100, at rest). The same for the minimal pythonfmu slave of bench_fmu.py (one
input, one output) is the floor: Python, fmpy and pythonfmu starting, which any Python FMU pays.

Every run gets its own fresh extraction of the FMU (not timed), as fmpy's simulate_fmu gives
each simulation: the resources hold no bytecode cache, so the slave's modules are compiled
from source, as a host's first run compiles them. Cases alternate round by round, so load on
the shared machine hits them alike; figures are medians over the rounds.

1. Wall time from spawning the process to the end of fmi2ExitInitializationMode, and its
   phases: interpreter start-up, the host's ``import fmpy.fmi2``, fmi2Instantiate, the three
   initialisation calls.
2. The same runs again under ``python -X importtime``: what of the time after fmpy's import is
   imports (pythonfmu's, which every Python FMU pays, and the slave's own: its module and
   everything it imports then or later) and what is left (compute: building the model).
   importtime's own overhead makes these a little slower than (1).
3. For comparison, the total for a host that keeps one extraction: the first run there writes
   the bytecode cache (not counted), the later ones read it.

    python benchmarks/bench_fmu_init.py [--rounds 7] [--also OTHER.fmu ...]
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from fmpy import extract, read_model_description

from tire_fmu.fmu.builder import build_fmu

#: The acceptance of issue 20: a fresh process up to the end of initialisation at N = 100.
AIM_S = 0.3
MARK = "bench_fmu_init:"

#: Run in the new process: the host's calls, with time stamps (and importtime markers) between.
CHILD = f'''
import sys, time
started = time.time()
clock = time.perf_counter()
sys.stderr.write("{MARK}host\\n")
from fmpy.fmi2 import FMU2Slave
host = time.perf_counter()
sys.stderr.write("{MARK}slave\\n")
folder, guid, identifier = sys.argv[1:4]
slave = FMU2Slave(guid=guid, unzipDirectory=folder, modelIdentifier=identifier,
                  instanceName="bench")
slave.instantiate()
instantiated = time.perf_counter()
slave.setupExperiment(startTime=0.0)
slave.enterInitializationMode()
slave.exitInitializationMode()
done = time.perf_counter()
print(started, host - clock, instantiated - host, done - instantiated, done - clock)
'''
IMPORT_LINE = re.compile(r"import time:\s+(\d+) \|\s+(\d+) \|( +)(\S+)")


class Case:
    """One FMU: where it is, and what it needs to be instantiated."""

    def __init__(self, label: str, path: Path):
        description = read_model_description(str(path))
        self.label, self.path = label, path
        self.guid = description.guid
        self.identifier = description.coSimulation.modelIdentifier
        self.runs: list[dict] = []
        self.import_runs: list[dict] = []
        self.cached_runs: list[dict] = []
        self.kept: Path | None = None  # the extraction whose bytecode cache is kept

    def run(self, scratch: Path, importtime: bool = False, cached: bool = False) -> None:
        env = dict(os.environ)
        if cached and self.kept is None:  # its first run writes the cache
            self.kept = Path(extract(str(self.path), unzipdir=tempfile.mkdtemp(dir=scratch)))
            env.pop("PYTHONDONTWRITEBYTECODE", None)
        folder = self.kept if cached else Path(extract(str(self.path),
                                                       unzipdir=tempfile.mkdtemp(dir=scratch)))
        command = [sys.executable, *(["-X", "importtime"] if importtime else []), "-c", CHILD,
                   str(folder), self.guid, self.identifier]
        spawned = time.time()
        done = subprocess.run(command, capture_output=True, text=True, env=env)
        if not cached:
            shutil.rmtree(folder, ignore_errors=True)
        if done.returncode != 0:
            raise SystemExit(f"{self.label}: the process failed:\n{done.stderr[-2000:]}")
        started, host, instantiate, initialise, inside = map(float, done.stdout.split()[-5:])
        run = {"total_s": started - spawned + inside, "python_s": started - spawned,
               "host_import_s": host, "instantiate_s": instantiate, "initialise_s": initialise}
        if importtime:
            run.update(import_split(done.stderr, instantiate + initialise))
            self.import_runs.append(run)
        else:
            (self.cached_runs if cached else self.runs).append(run)

    def medians(self) -> dict:
        out = {key: statistics.median(r[key] for r in self.runs) for key in self.runs[0]}
        for key in ("fmpy_imports_s", "pythonfmu_import_s", "slave_imports_s", "compute_s"):
            out[key] = statistics.median(r[key] for r in self.import_runs)
        out["cached_total_s"] = statistics.median(r["total_s"] for r in self.cached_runs)
        out["rounds"] = len(self.runs)
        return out


def import_split(stderr: str, after_host_s: float) -> dict:
    """Seconds of imports by phase, from ``-X importtime`` output with the child's markers."""
    phase, fmpy_us, pythonfmu_us, slave_us = None, 0, None, 0
    for line in stderr.splitlines():
        if line.startswith(MARK):
            phase = line[len(MARK):]
            continue
        match = IMPORT_LINE.match(line)
        if not match or phase is None:
            continue
        cumulative, depth, name = int(match[2]), len(match[3]), match[4]
        if phase == "slave" and name == "pythonfmu" and pythonfmu_us is None:
            pythonfmu_us = cumulative  # inside the slave module's own import, or before it
        if depth == 1:  # a top-level import: its cumulative time holds everything under it
            if phase == "host":
                fmpy_us += cumulative
            else:
                slave_us += cumulative
    pythonfmu_s = (pythonfmu_us or 0) * 1e-6
    slave_s = slave_us * 1e-6 - pythonfmu_s
    return {"fmpy_imports_s": fmpy_us * 1e-6, "pythonfmu_import_s": pythonfmu_s,
            "slave_imports_s": slave_s, "compute_s": after_host_s - pythonfmu_s - slave_s}


def build_minimal(folder: Path) -> Path:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_fmu import build_minimal as build

    return build(folder)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7, help="fresh processes per case and "
                        "kind of run (7; at least 5)")
    parser.add_argument("--also", nargs="*", default=[], metavar="FMU",
                        help="more FMUs to time alike (e.g. TireModal.fmu built from another "
                        "commit), labelled by their paths")
    parser.add_argument("--record", metavar="JSON", help="also write the results there (the "
                        "docs quote docs/measured/bench_fmu_init.json)")
    args = parser.parse_args(argv)
    if args.rounds < 5:
        parser.error(f"--rounds {args.rounds}: at least 5")
    from record import load_average, write_record

    load_at_start = load_average()
    with tempfile.TemporaryDirectory(prefix="bench_fmu_init_") as scratch:
        scratch = Path(scratch)
        (scratch / "minimal").mkdir()
        cases = [Case("TireModal", build_fmu(scratch / "tire")),
                 Case("minimal pythonfmu", build_minimal(scratch / "minimal"))]
        cases += [Case(str(path), Path(path)) for path in args.also]
        for case in cases:  # not counted: the first start-up after a build reads cold files,
            case.run(scratch)  # and the kept extraction's first run writes its cache
            case.run(scratch, cached=True)
            case.runs.clear()
            case.cached_runs.clear()
        for _ in range(args.rounds):
            for case in cases:
                case.run(scratch)
                case.run(scratch, importtime=True)
                case.run(scratch, cached=True)
    results = {case.label: case.medians() for case in cases}

    tire, floor = results["TireModal"], results["minimal pythonfmu"]
    print(f"Fresh process to the end of fmi2ExitInitializationMode through fmpy, default "
          f"parameters (N = 100); median of {args.rounds} processes each")
    rows = [("total", "total_s"), ("  Python start-up", "python_s"),
            ("  import fmpy.fmi2 (host)", "host_import_s"),
            ("  fmi2Instantiate", "instantiate_s"), ("  setup + enter + exit init", "initialise_s"),
            ("-X importtime, after fmpy:", None), ("  pythonfmu import", "pythonfmu_import_s"),
            ("  the slave's imports", "slave_imports_s"), ("  the rest (compute)", "compute_s"),
            ("total, extraction kept (cached)", "cached_total_s")]
    print(f"   {'':<30}" + "".join(f"{label[:22]:>24}" for label in results))
    for title, key in rows:
        cells = "".join(f"{r[key]:>22.3f} s" for r in results.values()) if key else ""
        print(f"   {title:<30}{cells}")
    above = tire["total_s"] - floor["total_s"]
    verdict = "meets" if tire["total_s"] < AIM_S else "MISSES"
    print(f"   TireModal - minimal slave: {above:.3f} s; TireModal {tire['total_s']:.3f} s "
          f"{verdict} the aim < {AIM_S:g} s (issue 20)")
    print(f"   Python {sys.version.split()[0]}, OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS')}, load average {load_at_start} at start")
    if args.record:
        write_record(args.record, {"n_elements": 100, "rounds": args.rounds, "aim_s": AIM_S,
                                   "cases": {label: results[label] for label in
                                             ("TireModal", "minimal pythonfmu")}},
                     load_at_start)


if __name__ == "__main__":
    main()
