"""The truck example's real-time factor: the two-axle truck of vehicle_demo/truck.py (four tire
FMUs, heave, pitch and roll) on an ISO 8608 class C OpenCRG road at 15 m/s with a 1 ms host
step, each in-plane FMU in fmpy, the native one in libcosim too, side by side in one run
with the CPU model. The real-time factor is wall time over simulated time (below 1: faster
than real time); the FMUs' builds and initialisations are not in it, the loop is (the host's
calls, the tires' steps, the truck's exact step).

    python3 benchmarks/bench_truck.py [--duration 2] [--repeats 3]
                                      [--record docs/measured/bench_truck.json]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from record import cpu_model, load_average, write_record  # noqa: E402

#: (FMU, hosts) in the order printed: the native one in both masters (the FMUs on the
#: wheel-centre interface)
CASES = (("TireInPlaneNative", ("fmpy", "libcosim")), ("TireInPlane", ("fmpy",)))


def main(argv=None) -> int:
    from vehicle_demo.truck import (
        FADE_IN_M,
        LEVEL_START_M,
        TruckParameters,
        build_tire_fmu,
        run_truck,
        truck_road,
    )

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=2.0, help="simulated time, s")
    parser.add_argument("--speed", type=float, default=15.0, help="m/s")
    parser.add_argument("--step", type=float, default=1e-3, help="host step, s")
    parser.add_argument("--repeats", type=int, default=3, help="runs per case (median)")
    parser.add_argument("--record", help="write the figures to this JSON file")
    args = parser.parse_args(argv)
    load_at_start = load_average()
    truck = TruckParameters()
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        length = LEVEL_START_M + FADE_IN_M + args.speed * args.duration + 2 * truck.wheelbase_m
        road = truck_road(folder / "truck_road.crg", length_m=max(length, 30.0),
                          track_m=truck.track_m)
        for fmu_name, hosts in CASES:
            fmu = build_tire_fmu(fmu_name, folder / fmu_name)
            radii = None
            for host in hosts:
                factors, heave = [], None
                for _ in range(args.repeats):
                    run = run_truck(fmu, road, truck, args.speed, args.duration, args.step,
                                    host, loaded_radii_m=radii)
                    radii = run.wheel_z_m[0]
                    factors.append(run.real_time_factor)
                    heave = run.summary()["body_az_rms_m_s2"]
                row = {"fmu": fmu_name, "host": host,
                       "real_time_factor": statistics.median(factors),
                       "body_az_rms_m_s2": heave}
                rows.append(row)
                print(f"{fmu_name:18s} {host:9s} real-time factor "
                      f"{row['real_time_factor']:7.3f}  body heave acceleration "
                      f"{heave:.4f} m/s^2 rms", flush=True)
    print(f"CPU: {cpu_model()}; {args.duration:g} s at {args.speed:g} m/s, step "
          f"{args.step * 1e3:g} ms, median of {args.repeats}")
    if args.record:
        write_record(args.record, {"duration_s": args.duration, "speed_m_s": args.speed,
                                   "step_s": args.step, "repeats": args.repeats,
                                   "rows": rows}, load_at_start)
    return 0


if __name__ == "__main__":
    sys.exit(main())
