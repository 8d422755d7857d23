"""What a mesh costs to build and reduce, up to the largest one the parameters allow.

Each case runs in a fresh process (so its peak memory is its own): what the FMUs do at
initialisation (``build_contact_model`` at the default load, then one step), then the
``reduce`` command's work (``build_model`` and the default modal truncation, no error report).
It prints seconds and peak resident memory per case beside the N = 100 case of the same run,
at rest and rolling at ``--speed`` (with ``allow_supercritical``: fine meshes have critical
speeds of a few m/s, and the rolling model's dense eigenproblem is what costs). The largest
mesh is ``tire_fmu.core.parameters.MAX_ELEMENTS``.

Run:  python3 benchmarks/bench_mesh_size.py [--meshes 100 400 1600] [--speed 10] [--record JSON]
(docs/fmu.md quotes docs/measured/bench_mesh_size.json).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def one_case(n_elements: int, speed_m_s: float) -> dict:
    import warnings

    from tire_fmu.core import build_model, validate
    from tire_fmu.core.contact_dynamics import ContactSimulator, build_contact_model
    from tire_fmu.core.reduction import ReductionSettings, reduce

    warnings.simplefilter("ignore")
    tire, op = validate({}, {"n_elements": n_elements, "speed_m_s": speed_m_s,
                             "allow_supercritical": True})
    started = time.perf_counter()
    ContactSimulator(build_contact_model(tire, op)).step(1e-4, 0.0, 0.0, 1e-3, 0.0)
    initialised = time.perf_counter()
    init_peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    reduced = reduce(build_model(tire, op), ReductionSettings(), report=False)
    done = time.perf_counter()
    return {"fmu_init_s": initialised - started, "fmu_init_peak_mb": init_peak_mb,
            "reduce_s": done - initialised,
            "states": reduced.n_states,
            "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def main() -> None:
    from tire_fmu.core.parameters import MAX_ELEMENTS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", type=int, nargs="+", default=[100, 400, MAX_ELEMENTS])
    parser.add_argument("--speed", type=float, default=10.0, help="rolling case, m/s")
    parser.add_argument("--case", nargs=2, help=argparse.SUPPRESS)
    parser.add_argument("--record", metavar="JSON", help="also write the results there (the "
                        "docs quote docs/measured/bench_mesh_size.json)")
    args = parser.parse_args()
    if args.case:
        print(json.dumps(one_case(int(args.case[0]), float(args.case[1]))))
        return
    env = dict(os.environ, OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"),
               PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    from record import load_average, write_record

    load_at_start = load_average()
    meshes = sorted(set(args.meshes) | {100})
    cases = []
    print(f"FMU initialisation and reduce, a fresh process per case (MAX_ELEMENTS = "
          f"{MAX_ELEMENTS})")
    print(f"{'N':>6} {'speed m/s':>9} {'init s':>8} {'x N=100':>8} {'states':>6} "
          f"{'reduce s':>8} {'x N=100':>8} {'peak MB':>8} {'x N=100':>8}")
    for speed in (0.0, args.speed):
        reference = None
        for n in meshes:
            done = subprocess.run([sys.executable, __file__, "--case", str(n), str(speed)],
                                  capture_output=True, text=True, env=env, check=True)
            case = json.loads(done.stdout.strip().splitlines()[-1])
            cases.append({"n_elements": n, "speed_m_s": speed, **case})
            reference = reference or (case["fmu_init_s"], case["reduce_s"], case["peak_mb"])
            print(f"{n:>6} {speed:>9g} {case['fmu_init_s']:>8.3f} "
                  f"{case['fmu_init_s'] / reference[0]:>8.1f} {case['states']:>6} "
                  f"{case['reduce_s']:>8.2f} {case['reduce_s'] / reference[1]:>8.1f} "
                  f"{case['peak_mb']:>8.0f} {case['peak_mb'] / reference[2]:>8.1f}", flush=True)
    if args.record:
        write_record(args.record, {"max_elements": MAX_ELEMENTS, "cases": cases}, load_at_start)


if __name__ == "__main__":
    main()
