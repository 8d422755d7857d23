"""Recorded benchmark results: the figures the docs quote, with the command that measured them.

``python benchmarks/bench_x.py --record docs/measured/bench_x.json`` writes one JSON file:
``command`` (what to run to measure again), ``recorded`` (UTC date), ``machine`` (cores, the
CPU model, load average at the start and the end, Python, BLAS threads) and ``results``.
``docs/generate.py`` turns the files into the marked sections of README.md and docs/*.md.
"""

from __future__ import annotations

import datetime
import json
import os
import platform
import shlex
import statistics
import sys
import time
from pathlib import Path


def load_average() -> float | None:
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return None


def cpu_model() -> str:
    """The processor's name (Linux's /proc/cpuinfo; else what the platform module knows)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as info:
            for line in info:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def command_line() -> str:
    """This run's command, from the repository root."""
    script = Path(sys.argv[0])
    try:
        script = script.resolve().relative_to(Path(__file__).resolve().parents[1])
    except ValueError:
        pass
    return shlex.join(["python3", script.as_posix(), *sys.argv[1:]])


def write_record(path: str | Path, results: dict, load_at_start: float | None) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    record = {
        "command": command_line(),
        "recorded": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d"),
        "machine": {
            "cores": os.cpu_count(),
            "cpu": cpu_model(),
            "load_average_start": load_at_start,
            "load_average_end": load_average(),
            "python": platform.python_version(),
            "openblas_threads": os.environ.get("OPENBLAS_NUM_THREADS"),
        },
        "results": results,
    }
    path.write_text(json.dumps(record, indent=1, sort_keys=False) + "\n")
    print(f"recorded {path}", file=sys.stderr)
    return path


def median_seconds(function, repeats: int) -> float:
    """The median wall time of ``repeats`` calls of ``function()`` (s)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def timed(function, *args):
    """(seconds, result) of one call: the C bricks' benchmarks time the Python and the C alike."""
    start = time.perf_counter()
    result = function(*args)
    return time.perf_counter() - start, result


def sidewall_tires() -> dict:
    """The in-plane tire with each sidewall model, the C bricks' benchmark cases."""
    from tire_fmu.core.inplane import InPlaneTire

    return {"tied": InPlaneTire(), "lumped": InPlaneTire(sidewall_tangential="lumped"),
            "massless": InPlaneTire(sidewall_mass=False)}
