"""The in-plane static footprint: core/inplane_contact.py's static_state, static_load_n and
deflection_for_load (numpy: an LU of the coordinates' size per active-set pass) beside
native/c/inplane_static.c (one factor of K per call, each pass by the Woodbury identity on the
points in contact, refined), on the reduced ring (300 Hz) at N = 100 and 400, the default
tire, 27.7 kN.

Both run on one simulator built beforehand: the core's deflection_for_load builds its own,
so here it is handed the built one (its constructor replaced for the timing), and what is
timed is its secant alone. Cases alternate round by round, so load on the shared machine hits
them alike; figures are medians over the rounds. Each row also prints how far apart the two
results are (relative).

    python benchmarks/bench_inplane_static.py [--rounds 5] [--n 100 400]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from functools import partial
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

import tire_fmu.core.inplane_contact as contact  # noqa: E402
from tire_fmu.core.inplane import InPlaneTire  # noqa: E402
from tire_fmu.native.inplane_static import (  # noqa: E402
    c_deflection_for_load,
    c_static_load_n,
    c_static_state,
)
from tire_fmu.native.kernel import load_library  # noqa: E402

LOAD_N = 27.7e3
F_MAX_HZ = 300.0


def _timed(function, *args):
    start = time.perf_counter()
    result = function(*args)
    return time.perf_counter() - start, result


def _python_secant(sim, load_n):
    """The core's deflection_for_load on the built simulator (its constructor replaced)."""
    built = contact.InPlaneSimulator
    contact.InPlaneSimulator = lambda *args, **kwargs: sim
    try:
        return contact.deflection_for_load(sim.model, load_n, sim.n_elements,
                                           f_max_hz=F_MAX_HZ)
    finally:
        contact.InPlaneSimulator = built


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--n", type=int, nargs="+", default=[100, 400])
    args = parser.parse_args()
    library = load_library()  # compiled (or read from the cache) before any timing
    model = InPlaneTire()
    print(f"medians of {args.rounds} rounds (s), reduced to {F_MAX_HZ:g} Hz, {LOAD_N:g} N")
    print(f"{'N':>4s} {'what':20s} {'Python':>9s} {'C':>9s} {'ratio':>6s} {'apart':>9s}")
    for n in args.n:
        sim = contact.InPlaneSimulator(model, n, 0.0, 0.0, f_max_hz=F_MAX_HZ)
        deflection = _python_secant(sim, LOAD_N)
        state_apart = lambda a, b: np.abs(a - b).max() / np.abs(a).max()  # noqa: E731
        scalar_apart = lambda a, b: abs(a - b) / abs(a)  # noqa: E731
        cases = {
            "static_state": (sim.static_state, c_static_state, deflection, state_apart),
            "static_load_n": (sim.static_load_n, c_static_load_n, deflection, scalar_apart),
            "deflection_for_load": (partial(_python_secant, sim), c_deflection_for_load,
                                    LOAD_N, scalar_apart),
        }
        for name, (python, native, value, apart) in cases.items():
            times = {"python": [], "c": []}
            for _ in range(args.rounds):
                seconds, expected = _timed(python, value)
                times["python"].append(seconds)
                seconds, built = _timed(native, sim, value, library)
                times["c"].append(seconds)
            median = {key: statistics.median(values) for key, values in times.items()}
            print(f"{n:4d} {name:20s} {median['python']:9.4f} {median['c']:9.4f} "
                  f"{median['python'] / median['c']:6.2f} {apart(expected, built):9.1e}",
                  flush=True)


if __name__ == "__main__":
    main()
