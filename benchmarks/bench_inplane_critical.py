"""The in-plane critical speed: core/inplane_modes.py's critical_speed (numpy and scipy: three
dense rings, each order's blocks by dense products, a generalised eigenproblem per order)
beside native/c/inplane_critical.c (three C rings, each order's blocks from the field blocks'
first columns, the companion's eigenvalues per order), at N = 100 and 400, for the default
tire (tied tangential sidewall, the radial tie above order 8), the lumped one and the massless
one.

Cases alternate round by round, so load on the shared machine hits them alike; figures are
medians over the rounds (the Python at N = 400 takes tens of seconds a round: --rounds 1 is
enough to see the ratio). Each row also prints how far apart the two critical spins are.

    python benchmarks/bench_inplane_critical.py [--rounds 3] [--n 100 400]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.record import sidewall_tires, timed  # noqa: E402
from tire_fmu.core.inplane_modes import critical_speed  # noqa: E402
from tire_fmu.native.inplane_critical import c_critical_speed  # noqa: E402
from tire_fmu.native.kernel import load_library  # noqa: E402

TIRES = sidewall_tires()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--n", type=int, nargs="+", default=[100, 400])
    args = parser.parse_args()
    library = load_library()  # compiled (or read from the cache) before any timing
    print(f"medians of {args.rounds} rounds (s)")
    print(f"{'tire':9s} {'N':>4s} {'Python':>9s} {'C':>9s} {'ratio':>6s} {'order':>5s} "
          f"{'branch':>10s} {'speed m/s':>11s} {'C/Python-1':>11s}")
    for n in args.n:
        for name, model in TIRES.items():
            times = {"python": [], "c": []}
            for _ in range(args.rounds):
                seconds, python = timed(critical_speed, model, n)
                times["python"].append(seconds)
                seconds, built = timed(c_critical_speed, model, n, library)
                times["c"].append(seconds)
            median = {key: statistics.median(values) for key, values in times.items()}
            apart = (built.spin_rad_s / python.spin_rad_s - 1.0
                     if math.isfinite(python.spin_rad_s) else
                     0.0 if built.spin_rad_s == python.spin_rad_s else math.nan)
            print(f"{name:9s} {n:4d} {median['python']:9.4f} {median['c']:9.4f} "
                  f"{median['python'] / median['c']:6.0f} {built.order!s:>5s} "
                  f"{built.branch!s:>10s} {built.speed_m_s:11.5g} {apart:11.1e}", flush=True)


if __name__ == "__main__":
    main()
