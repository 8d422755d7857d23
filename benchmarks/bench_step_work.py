"""The work of one step, swept over the ranges: the slowest 1 ms step a tire may take.

A tire is refused when a millisecond would take more than ``MAX_STEP_WORK`` units of work
(core/step_limits.py: a stiff contact on a light tread is sub-stepped at 1/sqrt(k_cw/rhoA), and
a sub-step costs more on a finer mesh), and a step longer than the tire allows is refused when
it is taken. This sweeps the meshes and treads of the ranges, each with the stiffest contact the
rule accepts (the costliest tire of its kind), times one 1 ms step with the compiled kernel
(median of repeats, in contact), and prints each beside the budget of about 1 s of CPU, with
the measured cost of a unit of work: the count tracks the time where it stays about constant.

    python benchmarks/bench_step_work.py [--meshes 16 100 400 800 1600] [--loads 100 rated]
                                         [--repeats 3] [--record JSON]

``--fit`` instead times sub-steps of 2 us over meshes, loads, point spacings and truncated
rings, and fits the cost of each term of step_limits.substep_work (ns per loop item, and in
units of the transforms' multiply-add): where its weights come from.

    python benchmarks/bench_step_work.py --fit [--meshes 16 100 400 800 1600]
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

from tire_fmu.core import step_limits  # noqa: E402
from tire_fmu.core.contact_dynamics import (  # noqa: E402
    MAX_SUBSTEP_S,
    MIN_SUBSTEP_S,
    ContactSimulator,
    build_contact_model,
)
from tire_fmu.core.free_ring import RingTruncation  # noqa: E402
from tire_fmu.core.parameters import (  # noqa: E402
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    TireParameters,
)
from tire_fmu.core.step_limits import MAX_STEP_WORK, WORK_INTERVAL_S  # noqa: E402

INTERVAL = WORK_INTERVAL_S  # the 1 ms step
#: The loads swept: a light one (a short footprint, few pushing points) and the rated one
#: (None: OperatingPoint's default), whose longer footprint the node-space solve pays for.
LOADS = {"100": 100.0, "rated": None}


def stiffest_accepted(tire: TireParameters, n_elements: int, load: float | None) -> float:
    """The largest k_cw the work rule (and the shortest sub-step) accepts for this tread and
    mesh: from the work of one sub-step of the default contact, which k_cw does not change."""
    soft = TireParameters(**{**tire.as_dict(), "k_cw": max(TIRE_FIELDS["k_cw"].low,
                                                          tire.rhoA / MAX_SUBSTEP_S**2)})
    probe = build_contact_model(soft, OperatingPoint(n_elements=n_elements, load_n=load))
    work = ContactSimulator(probe, backend="compiled").contract.substep_work
    per_interval = math.floor(MAX_STEP_WORK / work)
    substep = max(INTERVAL / per_interval, MIN_SUBSTEP_S)
    k_cw = tire.rhoA / substep**2 * (1 - 1e-9)
    return min(k_cw, TIRE_FIELDS["k_cw"].high)


def time_one_ms(tire: TireParameters, n_elements: int, load: float | None,
                repeats: int) -> tuple[float, int, int]:
    model = build_contact_model(tire, OperatingPoint(n_elements=n_elements, load_n=load))
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
    parser.add_argument("--loads", nargs="+", default=list(LOADS),
                        help="loads in N, or 'rated'")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--record", metavar="JSON")
    parser.add_argument("--fit", action="store_true",
                        help="fit the weights of substep_work's terms instead")
    args = parser.parse_args(argv)
    if args.fit:
        fit(args.meshes)
        return
    from record import load_average, write_record

    load_at_start = load_average()
    rows = []
    for n in args.meshes:
        for load_name in args.loads:
            load = LOADS[load_name] if load_name in LOADS else float(load_name)
            for tread, rho in (("lightest", TIRE_FIELDS["rhoA"].low),
                               ("GL073A", TireParameters().rhoA)):
                tire = TireParameters(rhoA=rho)
                try:
                    k_cw = stiffest_accepted(tire, n, load)
                    stiff = TireParameters(rhoA=rho, k_cw=k_cw)
                    seconds, n_sub, work = time_one_ms(stiff, n, load, args.repeats)
                except ParameterError as error:  # refused for another reason: nothing to time
                    print(f"   N = {n}, load {load_name}, {tread} tread: refused ({error})")
                    continue
                rows.append({"n_elements": n, "load": load_name, "tread": tread, "rhoA": rho,
                             "k_cw": k_cw, "substeps": n_sub, "substep_work": work,
                             "work": n_sub * work, "cpu_s": seconds,
                             "ns_per_unit": 1e9 * seconds / (n_sub * work)})
    print(f"The costliest accepted tire per mesh, load and tread: one {INTERVAL * 1e3:g} ms "
          f"step, compiled kernel, CPU time (median of {args.repeats}); budget about 1 s "
          f"(MAX_STEP_WORK = {MAX_STEP_WORK} units)")
    print(f"   {'N':>5} {'load N':>6} {'tread':>9} {'k_cw N/m^2':>11} {'sub-steps':>9} "
          f"{'work/sub':>9} {'work':>11} {'CPU s':>8} {'ns/unit':>8}")
    for r in rows:
        print(f"   {r['n_elements']:>5} {r['load']:>6} {r['tread']:>9} {r['k_cw']:11.3g} "
              f"{r['substeps']:>9} {r['substep_work']:>9} {r['work']:11.3g} "
              f"{r['cpu_s']:8.3f} {r['ns_per_unit']:8.2f}")
    units = [r["ns_per_unit"] for r in rows]
    print(f"   ns per unit: {min(units):.2f} to {max(units):.2f} "
          f"({max(units) / min(units):.1f}x over the rows)")
    slowest = max(rows, key=lambda r: r["cpu_s"])
    print(f"   slowest accepted 1 ms step: {slowest['cpu_s']:.3f} s of CPU (N = "
          f"{slowest['n_elements']}, {slowest['tread']} tread): "
          f"{'within' if slowest['cpu_s'] <= 1.0 else 'BEYOND'} the 1 s budget; the default "
          f"contact takes {math.ceil(INTERVAL / MAX_SUBSTEP_S)} sub-steps a millisecond")
    if args.record:
        write_record(args.record, {"rows": rows, "slowest_cpu_s": slowest["cpu_s"]},
                     load_at_start)


#: substep_work's terms, by the loop item each counts, and its weight (units an item).
TERMS = {
    "fixed": ("SUBSTEP_WORK_BASE", lambda c, t: 1),
    "mode": ("SUBSTEP_WORK_PER_MODE", lambda c, t: c.n_modes),
    "order x zone node": ("SUBSTEP_WORK_PER_ORDER_NODE",
                          lambda c, t: c.n_orders * (c.n_zone // 2 + 1)),
    "point x support": ("SUBSTEP_WORK_PER_SUPPORT", lambda c, t: c.n_points * c.n_support),
    "point": ("SUBSTEP_WORK_PER_POINT", lambda c, t: c.n_points),
    "zone node pair": ("SUBSTEP_WORK_PER_NODE_PAIR", lambda c, t: c.n_zone ** 2),
    "rate entry": ("SUBSTEP_WORK_PER_RATE_ENTRY",
                   lambda c, t: (3 + 2 * c.n_zone) * c.n_zone if t else 0),
}


def fit(meshes) -> None:
    """Sub-steps of 2 us (a stiff contact on the GL073A tread, the work rule lifted so that any
    mesh runs) over meshes, loads, spacings and truncation, under a rim moving at 80 Hz (the
    active set changes): CPU time a sub-step, and a non-negative least-squares fit, relative to
    each time, of the cost of each term's loop item."""
    import numpy as np
    from scipy.optimize import nnls

    from tire_fmu.core import contact_dynamics

    def lifted(*sizes):  # the refusal is what this measures for: not applied here
        return 1
    real = step_limits.substep_work
    contact_dynamics.substep_work = step_limits.substep_work = lifted
    substep = 2e-6
    tire = TireParameters(k_cw=TireParameters().rhoA / substep**2 * (1 - 1e-9))
    rows = []
    print("   N   load  spacing truncated     K     Z     P  S   us/sub  work/sub  ns/unit")
    for n in meshes:
        for load in (100.0, None, 8000.0):
            for spacing in (1e-2, 2.5e-3, 6e-4):
                for f_max in (None, 2000.0):
                    op = OperatingPoint(n_elements=n, load_n=load,
                                        contact_point_spacing_m=spacing)
                    try:
                        model = build_contact_model(tire, op, RingTruncation(f_max_hz=f_max))
                    except ParameterError as error:
                        print(f"   N = {n}, load {load}, spacing {spacing}: refused ({error})")
                        continue
                    sim = ContactSimulator(model, backend="compiled")
                    c, n_sub = sim.contract, math.ceil(INTERVAL / model.substep_s * (1 - 1e-12))
                    truncated = c.min_step_s > 0
                    times, t = [], 0.0
                    w = 2 * math.pi * 80.0
                    for _ in range(6):
                        started = time.process_time()
                        sim.step_values(INTERVAL, 1e-4 * math.sin(w * t),
                                        1e-4 * w * math.cos(w * t), 0.0, 0.0)
                        times.append(time.process_time() - started)
                        t += INTERVAL
                    seconds = statistics.median(times[2:]) / n_sub  # the first two warm up
                    work = real(c.n_modes, c.n_orders, c.n_zone, c.n_points, c.n_support,
                                truncated)
                    rows.append(([f(c, truncated) for _, f in TERMS.values()], seconds, work))
                    print(f"   {n:>4} {load or 'rated':>6} {spacing:8.1e} {truncated!s:>9} "
                          f"{c.n_modes:>5} {c.n_zone:>5} {c.n_points:>5} {c.n_support:>2} "
                          f"{seconds * 1e6:8.1f} {work:>9} {1e9 * seconds / work:8.3f}")
    counts = np.array([r[0] for r in rows], dtype=float)
    seconds = np.array([r[1] for r in rows])
    per_unit = 1e9 * seconds / np.array([r[2] for r in rows])
    print(f"   ns per unit with the weights of step_limits: {per_unit.min():.3f} to "
          f"{per_unit.max():.3f} ({per_unit.max() / per_unit.min():.1f}x over the rows)")
    # the terms that grow with the mesh (modes, transforms, node pairs, rate entries) grow
    # together, as do the points' two: the fit apportions their sum loosely between them
    cost, _ = nnls(counts / seconds[:, None], np.ones(seconds.size))
    # a unit: the transforms' multiply-add (an order x zone node item over its weight)
    unit = (cost[list(TERMS).index("order x zone node")]
            / step_limits.SUBSTEP_WORK_PER_ORDER_NODE)
    print("   fitted cost of each loop item, and in units (the transforms' multiply-add):")
    for (name, (weight, _)), ns in zip(TERMS.items(), cost * 1e9):
        print(f"   {name:>18}: {ns:7.3f} ns = {ns / (unit * 1e9):6.1f} units "
              f"({weight} = {getattr(step_limits, weight)})")


if __name__ == "__main__":
    main()
