"""The in-plane step's matrices at a spin: InPlaneSimulator._set_spin (numpy: the inverse by
LAPACK, the products by BLAS, one thread) beside native/c/inplane_build.c (LU with partial
pivoting, plain loops), on reduced simulators (f_max 300 Hz, the FMU's case) at N = 100 and
400, free wheel at 5 m/s.

"C" is the library's call alone on buffers made once; "C wrapper" is c_step_matrices (the
inputs read off the simulator, the outputs allocated, each call). Cases alternate round by
round, so load on the shared machine hits them alike; figures are medians over the rounds.
Each row also prints the worst agreement over the arrays (|C - Python| over the largest
|Python| entry).

    python benchmarks/bench_inplane_build.py [--rounds 7] [--n 100 400]
"""

from __future__ import annotations

import argparse
import ctypes
import os
import statistics
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from benchmarks.record import timed  # noqa: E402
from tire_fmu.core.inplane import InPlaneTire  # noqa: E402
from tire_fmu.core.inplane_contact import InPlaneSimulator  # noqa: E402
from tire_fmu.native.inplane_build import (  # noqa: E402
    _declare,
    build_input,
    build_output,
    c_step_matrices,
    output_arrays,
)
from tire_fmu.native.kernel import load_library  # noqa: E402

SPEED_M_S = 5.0


def _worst(sim, spin) -> float:
    c = c_step_matrices(sim, spin)
    sim._set_spin(spin, SPEED_M_S)
    worst = 0.0
    for name, value in c.items():
        python = getattr(sim, "_" + name)
        for got, want in (zip(value, python) if name.endswith("_parts") else [(value, python)]):
            scale = np.abs(want).max() or 1.0
            worst = max(worst, float(np.abs(np.asarray(got) - want).max() / scale))
    return worst


def _prepared_call(lib, sim, spin):
    """The library's call on buffers made here (kept alive by the closure), and its input."""
    data, keep = build_input(sim)
    arrays = output_arrays(data.ny, data.np)
    out = build_output(arrays)
    work = np.zeros(lib.inplane_build_work_doubles(data.ny, data.np))
    iwork = np.zeros(lib.inplane_build_work_ints(data.ny), dtype=np.int32)
    why = ctypes.create_string_buffer(512)

    def call():
        status = lib.inplane_build(ctypes.byref(data), spin, ctypes.byref(out),
                                   work.ctypes.data, iwork.ctypes.data, why, 512)
        assert status == 0 and keep and arrays, why.value

    return call, data


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--n", type=int, nargs="+", default=[100, 400])
    args = parser.parse_args()
    lib = load_library()  # compiled (or read from the cache) before any timing
    _declare(lib)
    print(f"medians of {args.rounds} rounds (ms), free wheel, f_max 300 Hz, {SPEED_M_S} m/s")
    print(f"{'N':>4s} {'ny':>4s} {'P':>4s} {'Python':>9s} {'C':>9s} {'C wrapper':>10s} "
          f"{'Python/C':>9s} {'worst':>9s}")
    for n in args.n:
        sim = InPlaneSimulator(InPlaneTire(), n, SPEED_M_S, 0.01, f_max_hz=300.0, wheel="free")
        spin = sim.spin_rad_s
        call, data = _prepared_call(lib, sim, spin)
        times = {"python": [], "c": [], "wrapper": []}
        for _ in range(args.rounds):
            times["python"].append(timed(sim._set_spin, spin, SPEED_M_S)[0])
            times["c"].append(timed(call)[0])
            times["wrapper"].append(timed(c_step_matrices, sim, spin, lib)[0])
        python, c, wrapper = (1e3 * statistics.median(times[k]) for k in times)
        print(f"{n:4d} {data.ny:4d} {data.np:4d} {python:9.2f} {c:9.2f} {wrapper:10.2f} "
              f"{python / c:9.2f} {_worst(sim, spin):9.1e}")


if __name__ == "__main__":
    main()
