"""Cost of fitting tire data to a table of 20 measured modes, side by side with its reference.

Times (median and fastest of ``--repeats`` runs, time.perf_counter) of ``fit_tire`` on the
GL073A modes n = 0..9, both branches, with 0.5 % noise, five free parameters
(m_s, k_r1, k_r2, EI, b) started 20-40 % off:

- on the analytic ring, least squares (the default of ``tire-fmu fit``);
- on the FDM model of N = 100 and N = 400 through the per-order symbols (no assembly);
- on the analytic ring with the minimax criterion;

and, as the reference in the same run, one assembled modal analysis at rest
(``real_modes`` of the undeformed tire, N = 100, up to 300 Hz): the cost of a single model
evaluation had the fit assembled the FDM eigenproblem. The budget of issue 15 is 2 s for a fit
of 20 modes.

Run:  python3 benchmarks/bench_fit.py [--repeats K]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BUDGET_S = 2.0


def timed(function, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times), result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    sys.path.insert(0, str(ROOT))
    import numpy as np

    from tire_fmu.core import OperatingPoint, TireParameters, build_model
    from tire_fmu.core.fit import fit_tire, modes_of
    from tire_fmu.core.modal import real_modes

    true = TireParameters()
    rng = np.random.default_rng(0)
    modes = [replace(m, frequency_hz=m.frequency_hz * (1 + 0.005 * rng.standard_normal()))
             for m in modes_of(true, range(10))]
    start = replace(true, m_s=13.0, k_r1=5.0e6, k_r2=6.0e6, EI=40.0, b=0.28)
    free = ("m_s", "k_r1", "k_r2", "EI", "b")
    model = build_model(true, OperatingPoint(patch_length_m=0.0))
    cases = [
        ("fit, analytic ring", lambda: fit_tire(modes, free, start)),
        ("fit, FDM N = 100 (symbols)", lambda: fit_tire(modes, free, start, n_elements=100)),
        ("fit, FDM N = 400 (symbols)", lambda: fit_tire(modes, free, start, n_elements=400)),
        ("fit, analytic ring, minimax", lambda: fit_tire(modes, free, start, criterion="max")),
        ("reference: one assembled modal analysis, N = 100",
         lambda: real_modes(model, f_max_hz=300.0)),
    ]
    print(f"{len(modes)} modes, {len(free)} free parameters, {args.repeats} repeats; "
          f"budget {BUDGET_S:g} s per fit")
    print(f"{'case':52s} {'median [s]':>11s} {'fastest [s]':>12s} {'evaluations':>12s}")
    reference = None
    rows = []
    for label, function in cases:
        median, fastest, result = timed(function, args.repeats)
        evaluations = getattr(result, "evaluations", "")
        rows.append((label, median))
        if label.startswith("reference"):
            reference = median
        print(f"{label:52s} {median:11.4f} {fastest:12.4f} {evaluations!s:>12s}")
    print()
    for label, median in rows[:-1]:
        print(f"{label:52s} {median / BUDGET_S:6.1%} of the budget, "
              f"{median / reference:6.2f} x one assembled modal analysis")
    return 0


if __name__ == "__main__":
    sys.exit(main())
