"""Mesh convergence of the loaded in-plane tire: the rotational mode at rest (wheel held and
free, `loaded_modes`) and the free-rolling resistance coefficient at 10 m/s
(`steady_rolling`, -Fx/Fz) of the paper's viscous damping and of the hysteretic tire file
(`GL073A_inplane_hysteretic`, whose loss factor was chosen at N = 100), at N = 100, 200 and
400 and three contact-point spacings, with the change from the next coarser mesh.

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
from tire_fmu.tire_files import read_tire_file  # noqa: E402

#: The tire file whose hysteretic loss is checked for convergence beside the paper's damping.
HYSTERETIC_TIRE = "GL073A_inplane_hysteretic"


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
    hysteretic_file = read_tire_file(HYSTERETIC_TIRE)
    hysteretic = InPlaneTire(hysteretic_file.tire, hysteretic_file.tangential)
    meshes = [int(n) for n in args.meshes.split(",")]
    spacings = [float(s) for s in args.spacings.split(",")]
    print(f"load {DEFAULT_LOAD_N:g} N; rolling resistance at {args.speed:g} m/s, wheel free, "
          "no torque")
    print(f"{'N':>5} {'points mm':>9} {'points':>7} {'held Hz':>9} {'free Hz':>9} "
          f"{'RR coeff':>10} {'dRR %':>7} {'RR hyst':>10} {'dRR %':>7} {'s':>6}")
    for spacing in spacings:
        previous = previous_hysteretic = None
        for n in meshes:
            started = time.perf_counter()
            deflection = deflection_for_load(model, DEFAULT_LOAD_N, n, point_spacing_m=spacing)

            def sim(speed, wheel, tire=model, n=n, spacing=spacing, deflection=deflection):
                return InPlaneSimulator(tire, n, speed, deflection, point_spacing_m=spacing,
                                        wheel=wheel)

            def coefficient(tire):
                rolling = sim(args.speed, "free", tire)
                steady = steady_rolling(rolling, 0.0)
                return -steady.rim_fx_n / steady.rim_fz_n, int(rolling._zone.n_points)

            held, free = rotational_hz(sim(0.0, "held")), rotational_hz(sim(0.0, "free"))
            # the hysteretic loss acts only in rolling, so the static deflection is shared
            (viscous, points), (lossy, _) = coefficient(model), coefficient(hysteretic)
            change = "" if previous is None else f"{100 * (viscous / previous - 1):7.2f}"
            change_lossy = ("" if previous_hysteretic is None
                            else f"{100 * (lossy / previous_hysteretic - 1):7.2f}")
            previous, previous_hysteretic = viscous, lossy
            rows.append({"n_elements": n, "point_spacing_m": spacing, "points": points,
                         "rotational_held_hz": held, "rotational_free_hz": free,
                         "rolling_resistance": viscous,
                         "rolling_resistance_hysteretic": lossy})
            print(f"{n:5d} {spacing * 1e3:9.2f} {points:7d} {held:9.3f} "
                  f"{free:9.3f} {viscous:10.6f} {change:>7} {lossy:10.6f} {change_lossy:>7} "
                  f"{time.perf_counter() - started:6.1f}", flush=True)
    if args.record:
        write_record(args.record, {"load_n": DEFAULT_LOAD_N, "speed_m_s": args.speed,
                                   "hysteretic_tire": HYSTERETIC_TIRE, "rows": rows},
                     load_at_start)


if __name__ == "__main__":
    main()
