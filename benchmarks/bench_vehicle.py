"""vehicle_demo benchmarks, printed in one run.

1. Wall time of the demo as a user runs it, in a fresh process: quick mode in a fresh output
   folder (so it includes building both FMUs), again with the FMUs built, and the full demo
   (N = 100), whose summary.json gives the agreement figures the docs quote.
2. Real-time factor of the two-FMU co-simulation (the tire + QuarterCar.fmu through fmpy,
   Gauss-Seidel, h = 1e-4 s): wall time over simulated time and the cost per communication
   step, at rest and rolling at 20 m/s, N = 100, with the Python tire (TireModal.fmu) and the
   native C tire (an export at the same load and speed) side by side; beside them, the cost
   of stepping each FMU alone through fmpy's ctypes functions (doStep, get outputs, set
   inputs), the floor the master cannot go below.
3. Sweep throughput, points per minute: the same full-factorial sweep run serially in this
   process, on dask's local scheduler with 2 worker processes, and with the default
   scheduler "auto" (which picks one of the two).

   The machine's load average is printed before and after: the cores are shared, and a
   second busy process takes the parallel gain away.

    python benchmarks/bench_vehicle.py [--sweep-points 8] [--seconds 2] [--record JSON]
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # before numpy: see vehicle_demo/__main__.py

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from record import load_average, write_record  # noqa: E402

from vehicle_demo.cosim import FmuInstance, FmuPaths, QuarterCarCoSimulation, _raw  # noqa: E402
from vehicle_demo.demo import ensure_fmus  # noqa: E402
from vehicle_demo.quarter_car import QuarterCarParameters  # noqa: E402
from vehicle_demo.sweep import SweepSettings, full_factorial, run_sweep  # noqa: E402
from vehicle_demo.transfer import Multisine  # noqa: E402

H = 1e-4


def demo_wall_time(folder: Path) -> dict:
    """Wall times of ``python -m vehicle_demo`` in fresh processes: quick mode cold (building
    the FMUs) and warm, then the full demo, and the full demo's summary."""
    def run(*options) -> float:
        started = time.perf_counter()
        subprocess.run([sys.executable, "-m", "vehicle_demo", *options, "--no-progress",
                        "--out", str(folder)], check=True, stdout=subprocess.DEVNULL)
        return time.perf_counter() - started

    quick_cold, quick_warm = run("--quick"), run("--quick")
    full = run()
    summary = json.loads((folder / "summary.json").read_text())
    return {"quick_cold_s": quick_cold, "quick_warm_s": quick_warm, "full_s": full,
            "full_summary": summary}


def native_tire(folder: Path, speed: float, n_elements: int = 100) -> Path:
    """The native C tire with the car's load and ``speed`` as its start values (it builds its
    model at initialisation for whatever the host sets)."""
    from tire_fmu.native import build_native_fmu
    from tire_fmu.native.builder import parameter_start_values

    start = parameter_start_values(load_n=QuarterCarParameters().static_tire_load_n,
                                   speed_m_s=speed, n_elements=n_elements)
    return build_native_fmu(folder / f"native_{speed:g}.fmu", start, platforms=("linux64",))


def cosim_cost(fmus, speed: float, seconds: float, tire_parameters: dict) -> dict:
    excitation = Multisine(period_s=seconds / 2, settle_periods=0, average_periods=2,
                           f_min_hz=2 / seconds, rms_velocity_m_s=0.005)
    _, height, velocity = excitation.road(H)
    with QuarterCarCoSimulation(fmus, QuarterCarParameters(), tire_parameters, H) as sim:
        sim.run(height[:2001], velocity[:2001])  # warm the caches and the kernels
        result = sim.run(height, velocity)
    steps = height.size - 1
    return {"rtf": result.real_time_factor, "us_per_step": 1e6 * result.wall_s / steps}


def single_fmu_cost(path, inputs, outputs, parameters, steps: int = 20000) -> float:
    """µs per communication step of one FMU alone through fmpy's ctypes functions, as the
    master calls them: doStep, getReal of the outputs, setReal of the inputs."""
    from fmpy.fmi2 import fmi2Real, fmi2True, fmi2ValueReference

    unit = FmuInstance(path, "bench")
    try:
        unit.start(parameters)
        vin = (fmi2ValueReference * len(inputs))(*[unit.vr(n) for n in inputs])
        vout = (fmi2ValueReference * len(outputs))(*[unit.vr(n) for n in outputs])
        values = (fmi2Real * len(inputs))(*[unit.get([n])[0] if n == "rim_Fz" else 0.0
                                            for n in inputs])
        got = (fmi2Real * len(outputs))()
        c = unit.fmu.component
        set_real, do_step, get_real = (_raw(unit.fmu, f) for f in ("SetReal", "DoStep",
                                                                   "GetReal"))
        samples = []
        k = 0
        for _ in range(5):
            started = time.perf_counter()
            for _ in range(steps // 5):
                do_step(c, k * H, H, fmi2True)
                get_real(c, vout, len(outputs), got)
                set_real(c, vin, len(inputs), values)
                k += 1
            samples.append((time.perf_counter() - started) / (steps // 5))
    finally:
        unit.close()
    return 1e6 * statistics.median(samples)


def sweep_throughput(fmus, n_points: int, rounds: int) -> dict:
    """Points per minute of each scheduler: rounds alternate between them (the load of the
    shared cores drifts), the median round counts."""
    loads = np.linspace(20_000.0, 35_000.0, max(1, n_points // 2)).tolist()
    points = full_factorial({"load": loads, "speed": [0.0, 15.0]})[:n_points]
    settings = SweepSettings(n_elements=60, reference=False)
    cases = (("serial", "synchronous"), ("dask, 2 processes", "processes"),
             ("default (auto)", "auto"))
    runs: dict[str, list] = {label: [] for label, _ in cases}
    for _ in range(rounds):
        for label, scheduler in cases:
            runs[label].append(run_sweep(points, fmus, settings, scheduler=scheduler,
                                         n_workers=2, progress=False))
    out = {}
    for label, results in runs.items():
        walls = [r.wall_s for r in results]
        wall = statistics.median(walls)
        out[label] = {"points_per_minute": 60.0 * len(points) / wall, "wall_s": wall,
                      "walls_s": walls, "points": len(points),
                      "failed": sum(int((r.table["status"] != "ok").sum()) for r in results),
                      "scheduler": ", ".join(sorted({r.scheduler for r in results}))}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sweep-points", type=int, default=8)
    parser.add_argument("--sweep-rounds", type=int, default=2,
                        help="alternating rounds of the three schedulers (2)")
    parser.add_argument("--seconds", type=float, default=2.0, help="simulated s per RTF run")
    parser.add_argument("--record", metavar="JSON", help="also write the results there (the "
                        "docs quote docs/measured/bench_vehicle.json)")
    args = parser.parse_args()
    load_at_start = load_average()
    results: dict = {"step_s": H, "seconds_simulated": args.seconds}
    with tempfile.TemporaryDirectory(prefix="bench_vehicle_") as tmp:
        tmp = Path(tmp)
        print(f"vehicle_demo benchmarks (h = {H:g} s, {os.cpu_count()} cores, "
              f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}, load average "
              f"{load_at_start} at start)\n")
        demo = results["demo"] = demo_wall_time(tmp / "demo")
        print("1. demo: python -m vehicle_demo")
        print(f"   --quick, fresh output folder (builds both FMUs) {demo['quick_cold_s']:8.1f} s")
        print(f"   --quick, FMUs already built                     {demo['quick_warm_s']:8.1f} s")
        print(f"   full demo (N = 100), FMUs already built         {demo['full_s']:8.1f} s\n")

        fmus = ensure_fmus(tmp / "fmus", log=lambda *_: None)
        print(f"2. two-FMU co-simulation, Gauss-Seidel, N = 100, {args.seconds:g} s simulated")
        print(f"   {'case':<44}{'us/step':>10}{'RTF (wall/sim)':>16}{'x real time':>13}")
        cosim = results["cosim"] = {}
        for speed in (0.0, 20.0):
            native = FmuPaths(native_tire(tmp, speed), fmus.quarter_car)
            for tire, paths, parameters in (
                    ("python", fmus, {"n_elements": 100, "speed": speed}),
                    ("native", native, {})):  # the native tire's parameters are compiled in
                c = cosim_cost(paths, speed, args.seconds, parameters)
                cosim[f"{tire} tire, {speed:g} m/s"] = c
                label = f"{tire} tire + quarter car, speed {speed:g} m/s"
                print(f"   {label:<44}{c['us_per_step']:10.1f}{c['rtf']:16.3f}"
                      f"{1 / c['rtf']:13.1f}")
        car = QuarterCarParameters()
        alone = results["alone_us"] = {
            "TireModal.fmu": single_fmu_cost(fmus.tire, ["rim_z", "rim_vz", "road_z", "road_vz"],
                                             ["rim_Fz", "contact_Fz"],
                                             {"load": car.static_tire_load_n}),
            "native tire": single_fmu_cost(native_tire(tmp, 0.0),
                                           ["rim_z", "rim_vz", "road_z", "road_vz"],
                                           ["rim_Fz", "contact_Fz"], {}),
            "QuarterCar.fmu": single_fmu_cost(fmus.quarter_car, ["rim_Fz", "rim_Fz_rate"],
                                              ["wheel_z", "wheel_vz", "wheel_az", "body_z",
                                               "body_az"], {}),
        }
        for name, cost in alone.items():
            print(f"   {name + ' alone, speed 0 (ctypes calls)':<44}{cost:10.1f}")
        print()

        print(f"3. sweep throughput, {args.sweep_points} points (load x speed, N = 60, "
              f"a 6 s multisine each), median of {args.sweep_rounds} alternating rounds")
        sweep = results["sweep"] = sweep_throughput(fmus, args.sweep_points, args.sweep_rounds)
        for label, r in sweep.items():
            print(f"   {label:<20}{r['points_per_minute']:8.1f} points/min   ({r['points']} "
                  f"points in {r['wall_s']:.1f} s, {r['failed']} failed; {r['scheduler']})")
        results["sweep_rounds"] = args.sweep_rounds
        print(f"\n   load average at the end: {load_average()} (1 min)")
    if args.record:
        write_record(args.record, results, load_at_start)


if __name__ == "__main__":
    main()
