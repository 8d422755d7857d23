"""The in-plane tire's linear model and its balanced reduction (core/inplane_io.py) at several
operating points: the full model's states, the states the reduction keeps for 1 % and 0.1 %
of FRF error over 0.5-300 Hz and the error it reaches, what building and reducing cost, and
the cost of a time step of the reduced model (its exact discretisation, a matrix-vector
product) beside a step of the simulator it linearises (the FMUs' Ritz basis to 300 Hz), both
timed in this run (medians).

    python benchmarks/bench_inplane_reduction.py
    python benchmarks/bench_inplane_reduction.py --record docs/measured/bench_inplane_reduction.json
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402

from benchmarks.record import load_average, median_seconds, write_record  # noqa: E402
from tire_fmu.core.inplane import InPlaneTire  # noqa: E402
from tire_fmu.core.inplane_contact import InPlaneSimulator, deflection_for_load  # noqa: E402
from tire_fmu.core.inplane_io import (  # noqa: E402
    InPlaneReductionSettings,
    linear_model,
    reduce_linear_model,
)
from tire_fmu.core.parameters import DEFAULT_LOAD_N  # noqa: E402

SPACING = 0.01
STEP_S = 1e-4
CASES = (  # N, speed m/s, wheel, torque N m
    (100, 0.0, "free", 0.0),
    (100, 10.0, "free", 0.0),
    (100, 10.0, "free", -3000.0),
    (100, 20.0, "free", 0.0),
    (100, 10.0, "held", 0.0),
    (200, 10.0, "free", 0.0),
)




def step_costs(reduced, sim: InPlaneSimulator, steps: int) -> tuple[float, float]:
    """(reduced model, simulator) seconds per step of STEP_S, medians of blocks of steps."""
    n, m = reduced.n_states, reduced.b.shape[1]
    # exact zero-order-hold discretisation of ż = A z + B u
    block = np.zeros((n + m, n + m))
    block[:n, :n], block[:n, n:] = reduced.a * STEP_S, reduced.b * STEP_S
    phi = scipy.linalg.expm(block)
    a_d, b_d = phi[:n, :n], phi[:n, n:]
    z, u = np.zeros(n), np.zeros(m)
    u[1] = 1e-4

    def linear_steps():
        nonlocal z
        for _ in range(steps):
            z = a_d @ z + b_d @ u
            _ = reduced.c @ z + reduced.d0 @ u

    per_linear = median_seconds(linear_steps, 5) / steps
    sim_steps = 200
    per_sim = median_seconds(lambda: sim.run(sim_steps * STEP_S), 3) / sim_steps
    return per_linear, per_sim


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--record", metavar="JSON",
                        help="write the figures to this file (docs/measured/...)")
    args = parser.parse_args()
    load_at_start = load_average()
    model = InPlaneTire()
    rows = []
    print("| N | speed | wheel | torque | full states | 1 %: states (error) | 0.1 %: states "
          "(error) | build | reduce (1 %) | step: reduced / simulator |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n, speed, wheel, torque in CASES:
        deflection = deflection_for_load(model, DEFAULT_LOAD_N, n, point_spacing_m=SPACING)
        sim = InPlaneSimulator(model, n, speed, deflection, wheel=wheel,
                               point_spacing_m=SPACING)
        build_s = median_seconds(lambda s=sim, t=torque: linear_model(s, t), 3)
        full = linear_model(sim, torque)
        start = time.perf_counter()
        one = reduce_linear_model(full, InPlaneReductionSettings(target_error=0.01))
        reduce_s = time.perf_counter() - start
        tenth = reduce_linear_model(full, InPlaneReductionSettings(target_error=0.001))
        stepped = InPlaneSimulator(model, n, speed, deflection, wheel=wheel,
                                   point_spacing_m=SPACING, f_max_hz=300.0,
                                   torque_n_m=torque)
        per_linear, per_sim = step_costs(one, stepped, 2000)
        row = {"n_elements": n, "speed_m_s": speed, "wheel": wheel, "torque_n_m": torque,
               "full_states": full.n_states,
               "points_in_contact": full.operating_point["points_in_contact"],
               "sliding_points": full.operating_point["sliding_points"],
               "states_1pc": one.n_states, "error_1pc": one.report["max_relative_error"],
               "states_01pc": tenth.n_states, "error_01pc": tenth.report["max_relative_error"],
               "build_s": build_s, "reduce_s": reduce_s,
               "step_reduced_s": per_linear, "step_simulator_s": per_sim}
        rows.append(row)
        print(f"| {n} | {speed:g} m/s | {wheel} | {torque:g} N m | {full.n_states} | "
              f"{one.n_states} ({one.report['max_relative_error']:.2%}) | {tenth.n_states} "
              f"({tenth.report['max_relative_error']:.3%}) | {build_s:.2f} s | "
              f"{reduce_s:.1f} s | {per_linear * 1e6:.1f} / {per_sim * 1e6:.0f} µs |",
              flush=True)
    if args.record:
        write_record(args.record, {"spacing_m": SPACING, "load_n": DEFAULT_LOAD_N,
                                   "step_s": STEP_S, "rows": rows}, load_at_start)


if __name__ == "__main__":
    main()
