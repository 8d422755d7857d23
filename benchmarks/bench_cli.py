"""Command-line start-up and BLAS threads, side by side with their references in one run.

1. ``tire-fmu --help``: wall and CPU time of the whole process (median of ``--repeats``),
   against ``python -c pass`` (the interpreter's floor) and ``python -c "import
   tire_fmu.core"`` (numpy, scipy and the core: what every command, --help included, loaded
   before parsing until the imports became lazy). Target: under 0.3 s.
2. A command that runs dense eigenproblems (``speed-sweep``, N = 100, 21 speeds, and
   ``modes --elements 800``) with the default of one BLAS thread against
   ``--blas-threads 0`` (the library's own default, every core), rounds alternating so that
   load hits both alike. OPENBLAS_NUM_THREADS and friends are removed from the children's
   environment so that the library default really is multithreaded.

    python benchmarks/bench_cli.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
                    "TIRE_FMU_BLAS_THREADS")


def environment() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    env["PYTHONPATH"] = str(ROOT)
    return env


def run_once(argv: list[str]) -> tuple[float, float]:
    """(wall s, CPU s of the child) of one process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(argv, env=environment(), cwd=ROOT, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def compare(cases: dict[str, list[str]], repeats: int) -> dict[str, tuple[float, float]]:
    """Median (wall, CPU) per case, the cases alternating round by round."""
    samples: dict[str, list[tuple[float, float]]] = {name: [] for name in cases}
    for _ in range(repeats):
        for name, argv in cases.items():
            samples[name].append(run_once(argv))
    return {name: (statistics.median(w for w, _ in s), statistics.median(c for _, c in s))
            for name, s in samples.items()}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    py = sys.executable
    cli = [py, "-m", "tire_fmu.cli"]
    print(f"python benchmarks/bench_cli.py --repeats {args.repeats}")
    print(f"{os.cpu_count()} CPUs, load average "
          f"{', '.join(f'{x:.2f}' for x in os.getloadavg())}")

    print("\n1. Start-up (median s of the whole process)")
    results = compare({
        "tire-fmu --help": [*cli, "--help"],
        "ref: python -c pass": [py, "-c", "pass"],
        "ref: import tire_fmu.core (numpy, scipy)": [py, "-c", "import tire_fmu.core"],
    }, args.repeats)
    floor = results["ref: python -c pass"][0]
    print(f"{'':44} {'wall':>7} {'CPU':>7} {'wall - floor':>13}")
    for name, (wall, cpu) in results.items():
        print(f"{name:44} {wall:>7.3f} {cpu:>7.3f} {wall - floor:>13.3f}")

    print("\n2. BLAS threads (median s of the whole process)")
    print(f"{'':44} {'1 thread':>9} {'library':>9} {'ratio':>6}")
    for label, command in (("speed-sweep (N = 100, 21 speeds)", ["speed-sweep", "--json"]),
                           ("modes --elements 800", ["modes", "--elements", "800",
                                                     "--json"])):
        results = compare({"one": [*cli, *command],
                           "library": [*cli, "--blas-threads", "0", *command]},
                          max(1, args.repeats // 2))
        one, lib = results["one"][0], results["library"][0]
        print(f"{label:44} {one:>9.2f} {lib:>9.2f} {lib / one:>6.2f}")
    print("   ratio: library default / one thread; above 1, threads cost more than they give")
    return 0


if __name__ == "__main__":
    sys.exit(main())
