"""The work of one step, swept over the ranges: the slowest 1 ms step a tire may take.

A tire is refused when a millisecond would take more than ``MAX_STEP_WORK`` units of work
(core/step_limits.py: a stiff contact on a light tread is sub-stepped at 1/sqrt(k_cw/rhoA), and
a sub-step costs more on a finer mesh), and a step longer than the tire allows is refused when
it is taken. This sweeps the meshes and treads of the ranges, each with the stiffest contact the
rule accepts (the costliest tire of its kind), times one 1 ms step with the compiled kernel
(median of repeats, in contact), and prints each beside the budget of about 1 s of CPU, with
the measured cost of a unit of work.

    python benchmarks/bench_step_work.py [--meshes 16 100 400 800 1600] [--repeats 3]
                                         [--record JSON]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tire_fmu.core.contact_dynamics import (  # noqa: E402
    MAX_SUBSTEP_S,
    MIN_SUBSTEP_S,
    ContactSimulator,
    build_contact_model,
)
from tire_fmu.core.parameters import (  # noqa: E402
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    TireParameters,
)
from tire_fmu.core.step_limits import MAX_STEP_WORK, WORK_INTERVAL_S  # noqa: E402

INTERVAL = WORK_INTERVAL_S  # the 1 ms step


def stiffest_accepted(tire: TireParameters, n_elements: int) -> float:
    """The largest k_cw the work rule (and the shortest sub-step) accepts for this tread and
    mesh: from the work of one sub-step of the default contact, which k_cw does not change."""
    soft = TireParameters(**{**tire.as_dict(), "k_cw": max(TIRE_FIELDS["k_cw"].low,
                                                          tire.rhoA / MAX_SUBSTEP_S**2)})
    probe = build_contact_model(soft, OperatingPoint(n_elements=n_elements, load_n=100.0))
    work = ContactSimulator(probe, backend="compiled").contract.substep_work
    per_interval = math.floor(MAX_STEP_WORK / work)
    substep = max(INTERVAL / per_interval, MIN_SUBSTEP_S)
    k_cw = tire.rhoA / substep**2 * (1 - 1e-9)
    return min(k_cw, TIRE_FIELDS["k_cw"].high)


def time_one_ms(tire: TireParameters, n_elements: int, repeats: int) -> tuple[float, int, int]:
    model = build_contact_model(tire, OperatingPoint(n_elements=n_elements, load_n=100.0))
    sim = ContactSimulator(model, backend="compiled")
    times = []
    for _ in range(repeats):
        started = time.process_time()
        sim.step_values(INTERVAL, 1e-4, 0.0, 0.0, 0.0)
        times.append(time.process_time() - started)
    n_sub = math.ceil(INTERVAL / model.substep_s * (1 - 1e-12))
    return statistics.median(times), n_sub, sim.contract.substep_work


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", type=int, nargs="+", default=[16, 100, 400, 800, 1600])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--record", metavar="JSON")
    args = parser.parse_args(argv)
    from record import load_average, write_record

    load_at_start = load_average()
    rows = []
    for n in args.meshes:
        for tread, rho in (("lightest", TIRE_FIELDS["rhoA"].low),
                           ("GL073A", TireParameters().rhoA)):
            tire = TireParameters(rhoA=rho)
            try:
                k_cw = stiffest_accepted(tire, n)
                stiff = TireParameters(rhoA=rho, k_cw=k_cw)
                seconds, n_sub, work = time_one_ms(stiff, n, args.repeats)
            except ParameterError as error:  # refused for another reason: nothing to time
                print(f"   N = {n}, {tread} tread: refused ({error})")
                continue
            rows.append({"n_elements": n, "tread": tread, "rhoA": rho, "k_cw": k_cw,
                         "substeps": n_sub, "substep_work": work,
                         "work": n_sub * work, "cpu_s": seconds,
                         "ns_per_unit": 1e9 * seconds / (n_sub * work)})
    print(f"The costliest accepted tire per mesh and tread: one {INTERVAL * 1e3:g} ms step, "
          f"compiled kernel, CPU time (median of {args.repeats}); budget about 1 s "
          f"(MAX_STEP_WORK = {MAX_STEP_WORK} units)")
    print(f"   {'N':>5} {'tread':>9} {'k_cw N/m^2':>11} {'sub-steps':>9} {'work/sub':>9} "
          f"{'work':>11} {'CPU s':>8} {'ns/unit':>8}")
    for r in rows:
        print(f"   {r['n_elements']:>5} {r['tread']:>9} {r['k_cw']:11.3g} {r['substeps']:>9} "
              f"{r['substep_work']:>9} {r['work']:11.3g} {r['cpu_s']:8.3f} "
              f"{r['ns_per_unit']:8.2f}")
    slowest = max(rows, key=lambda r: r["cpu_s"])
    print(f"   slowest accepted 1 ms step: {slowest['cpu_s']:.3f} s of CPU (N = "
          f"{slowest['n_elements']}, {slowest['tread']} tread): "
          f"{'within' if slowest['cpu_s'] <= 1.0 else 'BEYOND'} the 1 s budget; the default "
          f"contact takes {math.ceil(INTERVAL / MAX_SUBSTEP_S)} sub-steps a millisecond")
    if args.record:
        write_record(args.record, {"rows": rows, "slowest_cpu_s": slowest["cpu_s"]},
                     load_at_start)


if __name__ == "__main__":
    main()
