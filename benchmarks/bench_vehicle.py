"""vehicle_demo benchmarks, printed in one run.

1. Wall time of the demo in quick mode, as a user runs it (``python -m vehicle_demo --quick``
   in a fresh process and a fresh output folder, so it includes building both FMUs), and a
   second run that finds the FMUs built.
2. Real-time factor of the two-FMU co-simulation (TireModal.fmu + QuarterCar.fmu through
   fmpy, Gauss-Seidel, h = 1e-4 s): wall time over simulated time, and the cost per
   communication step, at rest (speed 0) and rolling at 20 m/s, N = 100; beside it, the cost
   of stepping each FMU alone through fmpy (set inputs, doStep, get outputs).
3. Sweep throughput, points per minute: the same full-factorial sweep run serially in this
   process and on dask's local scheduler with 2 worker processes (2 cores).

   The machine's load average is printed before and after: the cores are shared, and a
   second busy process takes the parallel gain away.

    python benchmarks/bench_vehicle.py [--sweep-points 8] [--seconds 2]
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # before numpy: see vehicle_demo/__main__.py

import argparse  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from vehicle_demo.cosim import FmuInstance, QuarterCarCoSimulation  # noqa: E402
from vehicle_demo.demo import ensure_fmus  # noqa: E402
from vehicle_demo.quarter_car import QuarterCarParameters  # noqa: E402
from vehicle_demo.sweep import SweepSettings, full_factorial, run_sweep  # noqa: E402
from vehicle_demo.transfer import Multisine  # noqa: E402

H = 1e-4


def demo_wall_time(folder: Path) -> tuple[float, float]:
    """(cold, warm) wall time of ``python -m vehicle_demo --quick`` in a fresh process."""
    times = []
    for _ in range(2):
        started = time.perf_counter()
        subprocess.run([sys.executable, "-m", "vehicle_demo", "--quick", "--no-progress",
                        "--out", str(folder)], check=True, stdout=subprocess.DEVNULL)
        times.append(time.perf_counter() - started)
    return times[0], times[1]


def cosim_cost(fmus, speed: float, seconds: float, n_elements: int = 100) -> dict:
    excitation = Multisine(period_s=seconds / 2, settle_periods=0, average_periods=2,
                           f_min_hz=2 / seconds, rms_velocity_m_s=0.005)
    _, height, velocity = excitation.road(H)
    with QuarterCarCoSimulation(fmus, QuarterCarParameters(),
                                {"n_elements": n_elements, "speed": speed}, H) as sim:
        sim.run(height[:2001], velocity[:2001])  # warm the caches and the kernels
        result = sim.run(height, velocity)
    steps = height.size - 1
    return {"rtf": result.real_time_factor, "us_per_step": 1e6 * result.wall_s / steps}


def single_fmu_cost(path, inputs, outputs, parameters, steps: int = 20000) -> float:
    """µs per communication step of one FMU alone: setReal, doStep, getReal."""
    unit = FmuInstance(path, "bench")
    try:
        unit.start(parameters)
        vin = [unit.vr(n) for n in inputs]
        vout = [unit.vr(n) for n in outputs]
        values = [unit.get([n])[0] if n == "rim_Fz" else 0.0 for n in inputs]
        fmu = unit.fmu
        samples = []
        t = 0.0
        for _ in range(5):
            started = time.perf_counter()
            for _ in range(steps // 5):
                fmu.setReal(vin, values)
                fmu.doStep(t, H)
                fmu.getReal(vout)
                t += H
            samples.append((time.perf_counter() - started) / (steps // 5))
    finally:
        unit.close()
    return 1e6 * statistics.median(samples)


def sweep_throughput(fmus, n_points: int) -> dict:
    loads = np.linspace(20_000.0, 35_000.0, max(1, n_points // 2)).tolist()
    points = full_factorial({"load": loads, "speed": [0.0, 15.0]})[:n_points]
    settings = SweepSettings(n_elements=60, reference=False)
    out = {}
    for label, scheduler in (("serial", "synchronous"), ("dask, 2 processes", "processes")):
        result = run_sweep(points, fmus, settings, scheduler=scheduler, n_workers=2,
                           progress=False)
        failed = int((result.table["status"] != "ok").sum())
        out[label] = (result.points_per_minute, result.wall_s, failed, len(points))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sweep-points", type=int, default=8)
    parser.add_argument("--seconds", type=float, default=2.0, help="simulated s per RTF run")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_vehicle_") as tmp:
        tmp = Path(tmp)
        print(f"vehicle_demo benchmarks (h = {H:g} s, {os.cpu_count()} cores, "
              f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}, load average "
              f"{os.getloadavg()[0]:.1f} at start)\n")
        cold, warm = demo_wall_time(tmp / "demo")
        print("1. demo, quick mode: python -m vehicle_demo --quick")
        print(f"   fresh output folder (builds both FMUs)   {cold:8.1f} s")
        print(f"   FMUs already built                        {warm:8.1f} s\n")

        fmus = ensure_fmus(tmp / "fmus", log=lambda *_: None)
        print(f"2. two-FMU co-simulation, Gauss-Seidel, N = 100, {args.seconds:g} s simulated")
        print(f"   {'case':<36}{'us/step':>10}{'RTF (wall/sim)':>16}{'x real time':>13}")
        for speed in (0.0, 20.0):
            c = cosim_cost(fmus, speed, args.seconds)
            print(f"   {f'tire + quarter car, speed {speed:g} m/s':<36}{c['us_per_step']:10.1f}"
                  f"{c['rtf']:16.3f}{1 / c['rtf']:13.1f}")
        car = QuarterCarParameters()
        tire_alone = single_fmu_cost(fmus.tire, ["rim_z", "rim_vz", "road_z", "road_vz"],
                                     ["rim_Fz", "contact_Fz"], {"load": car.static_tire_load_n})
        car_alone = single_fmu_cost(fmus.quarter_car, ["rim_Fz", "rim_Fz_rate"],
                                    ["wheel_z", "wheel_vz", "wheel_az", "body_z", "body_az"], {})
        print(f"   {'TireModal.fmu alone (fmpy wrappers)':<36}{tire_alone:10.1f}")
        print(f"   {'QuarterCar.fmu alone (fmpy wrappers)':<36}{car_alone:10.1f}\n")

        print(f"3. sweep throughput, {args.sweep_points} points (load x speed, N = 60, "
              "a 6 s multisine each)")
        for label, (rate, wall, failed, n) in sweep_throughput(fmus, args.sweep_points).items():
            print(f"   {label:<20}{rate:8.1f} points/min   ({n} points in {wall:.1f} s, "
                  f"{failed} failed)")
        print(f"\n   load average at the end: {os.getloadavg()[0]:.1f} (1 min)")


if __name__ == "__main__":
    main()
