"""Mesh convergence of the loaded in-plane tire: the rotational mode at rest (wheel held and
free, `loaded_modes`) and the free-rolling resistance coefficient at 10 m/s
(`steady_rolling`, -Fx/Fz), at N = 100, 200 and 400 and three contact-point spacings, with
the change from the next coarser mesh.

    python benchmarks/bench_inplane_convergence.py [--meshes 100,200,400] \
        [--spacings 0.01,0.005,0.0025] [--record docs/measured/bench_inplane_convergence.json]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.record import load_average, write_record  # noqa: E402
from tire_fmu.core.inplane import InPlaneTire  # noqa: E402
from tire_fmu.core.inplane_contact import (  # noqa: E402
    InPlaneSimulator,
    deflection_for_load,
    loaded_modes,
    steady_rolling,
)
from tire_fmu.core.parameters import DEFAULT_LOAD_N  # noqa: E402


def rotational_hz(sim) -> float:
    modes = loaded_modes(sim)
    return float(modes.frequencies_hz[modes.kinds.index("rotational")])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", default="100,200,400")
    parser.add_argument("--spacings", default="0.01,0.005,0.0025")
    parser.add_argument("--speed", type=float, default=10.0)
    parser.add_argument("--record", metavar="JSON", help="write the rows for docs/generate.py")
    args = parser.parse_args()
    load_at_start = load_average()
    rows = []
    model = InPlaneTire()
    meshes = [int(n) for n in args.meshes.split(",")]
    spacings = [float(s) for s in args.spacings.split(",")]
    print(f"load {DEFAULT_LOAD_N:g} N; rolling resistance at {args.speed:g} m/s, wheel free, "
          "no torque")
    print(f"{'N':>5} {'points mm':>9} {'points':>7} {'held Hz':>9} {'free Hz':>9} "
          f"{'RR coeff':>10} {'dRR %':>7} {'s':>6}")
    for spacing in spacings:
        previous = None
        for n in meshes:
            started = time.perf_counter()
            deflection = deflection_for_load(model, DEFAULT_LOAD_N, n, point_spacing_m=spacing)

            def sim(speed, wheel, n=n, spacing=spacing, deflection=deflection):
                return InPlaneSimulator(model, n, speed, deflection, point_spacing_m=spacing,
                                        wheel=wheel)

            held, free = rotational_hz(sim(0.0, "held")), rotational_hz(sim(0.0, "free"))
            rolling = sim(args.speed, "free")
            steady = steady_rolling(rolling, 0.0)
            coefficient = -steady.rim_fx_n / steady.rim_fz_n
            change = "" if previous is None else f"{100 * (coefficient / previous - 1):7.2f}"
            previous = coefficient
            rows.append({"n_elements": n, "point_spacing_m": spacing,
                         "points": int(rolling._zone.n_points), "rotational_held_hz": held,
                         "rotational_free_hz": free, "rolling_resistance": coefficient})
            print(f"{n:5d} {spacing * 1e3:9.2f} {rolling._zone.n_points:7d} {held:9.3f} "
                  f"{free:9.3f} {coefficient:10.6f} {change:>7} "
                  f"{time.perf_counter() - started:6.1f}", flush=True)
    if args.record:
        write_record(args.record, {"load_n": DEFAULT_LOAD_N, "speed_m_s": args.speed,
                                   "rows": rows}, load_at_start)


if __name__ == "__main__":
    main()
