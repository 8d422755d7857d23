"""Native (C) FMU benchmark through fmpy, printed side by side in one run.

Cost per communication step (setReal of the 4 inputs, doStep, getReal of the 4 outputs) at
h = 1e-4 s, at each operating point asked for (default N = 100, at rest and at 10 m/s):

  (a) the native FMU exported from the reduced model (tire_fmu.native);
  (b) the Python FMU, TireModal.fmu, with the same parameters and default settings;
  (c) the plain fmpy call overhead: an FMU built by the same machinery from the same model
      with its modes removed, so its doStep checks the step and feeds the inputs through but
      has nothing to integrate.

Rounds of (a), (b) and (c) alternate, so load on the machine hits all of them alike; medians
(the target's measure) and minima (the least disturbed round) side by side.
Target: median (a) <= 1.2 x median (c).

    python benchmarks/bench_native.py [--elements 100] [--speeds 0,10] [--rounds 30]
                                      [--steps 2000]
"""

from __future__ import annotations

import argparse
import shlex
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from tire_fmu.core import DEFAULT_LOAD_N, build_model, validate
from tire_fmu.core.reduction import ReductionSettings, reduce
from tire_fmu.fmu.builder import build_fmu
from tire_fmu.native import build_native_fmu

H = 1e-4
INPUTS = ("rim_z", "rim_vz", "road_z", "road_vz")
OUTPUTS = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection")
#: a gentle rim and road motion that stays in contact (no warnings in the loop)
VALUES = [1e-4, 1e-3, 2e-4, -1e-3]


class Stepper:
    """The three calls of a communication step on one initialised FMU instance."""

    def __init__(self, path: Path, name: str, start_values: dict | None = None):
        description = read_model_description(str(path))
        self.slave = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(path)),
                               modelIdentifier=description.coSimulation.modelIdentifier,
                               instanceName=name)
        vr = {v.name: v.valueReference for v in description.modelVariables}
        self.inputs = [vr[n] for n in INPUTS]
        self.outputs = [vr[n] for n in OUTPUTS]
        self.slave.instantiate()
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        for name, value in (start_values or {}).items():
            if isinstance(value, int):
                self.slave.setInteger([vr[name]], [value])
            else:
                self.slave.setReal([vr[name]], [value])
        started = time.perf_counter()
        self.slave.exitInitializationMode()
        self.init_seconds = time.perf_counter() - started
        self.time = 0.0

    def run(self, steps: int) -> float:
        """Seconds per communication step over ``steps`` steps."""
        set_real, do_step, get_real = self.slave.setReal, self.slave.doStep, self.slave.getReal
        inputs, outputs, t = self.inputs, self.outputs, self.time
        started = time.perf_counter()
        for _ in range(steps):
            set_real(inputs, VALUES)
            do_step(t, H)
            get_real(outputs)
            t += H
        elapsed = time.perf_counter() - started
        self.time = t
        return elapsed / steps

    def close(self) -> None:
        self.slave.terminate()
        self.slave.freeInstance()


def without_modes(reduced):
    """The same model with nothing to integrate: the overhead FMU's."""
    m = reduced.n_inputs
    return replace(reduced, eigenvalues=np.zeros(0, complex), b=np.zeros((0, m), complex),
                   c=np.zeros((4, 0), complex))


def bench_point(folder: Path, python_fmu: Path, n_elements: int, speed: float, rounds: int,
                steps: int) -> dict:
    tire, op = validate({}, {"n_elements": n_elements, "load_n": DEFAULT_LOAD_N,
                             "speed_m_s": speed})
    reduced = reduce(build_model(tire, op), ReductionSettings(), report=False)
    tag = f"n{n_elements}_v{speed:g}"
    native = build_native_fmu(reduced, folder / f"native_{tag}.fmu", op)
    overhead = build_native_fmu(without_modes(reduced), folder / f"overhead_{tag}.fmu", op,
                                model_identifier="TireOverhead")
    cases = {
        "(a) native C FMU": Stepper(native, "native"),
        "(b) Python FMU": Stepper(python_fmu, "python", {"n_elements": n_elements,
                                                          "speed": float(speed)}),
        "(c) fmpy overhead": Stepper(overhead, "overhead"),
    }
    for case in cases.values():
        case.run(steps // 10)  # warm up
    times = {name: [] for name in cases}
    for _ in range(rounds):
        for name, case in cases.items():
            times[name].append(case.run(steps))
    result = {
        "reduced": reduced,
        "costs": {name: statistics.median(values) for name, values in times.items()},
        "best": {name: min(values) for name, values in times.items()},
        "init": {name: case.init_seconds for name, case in cases.items()},
    }
    for case in cases.values():
        case.close()
    return result


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, default=100, help="mesh nodes (100)")
    parser.add_argument("--speeds", default="0,10", help="speeds in m/s, comma-separated (0,10)")
    parser.add_argument("--rounds", type=int, default=30, help="alternating rounds (30)")
    parser.add_argument("--steps", type=int, default=2000, help="steps per round (2000)")
    args = parser.parse_args(argv)
    speeds = [float(v) for v in args.speeds.split(",")]

    print("command: " + shlex.join([Path(sys.argv[0]).as_posix(), *sys.argv[1:]]))
    print(f"Cost per communication step through fmpy (setReal 4 inputs, doStep, getReal 4 "
          f"outputs), h = {H:g} s, median of {args.rounds} alternating rounds of "
          f"{args.steps} steps; default reduction settings, N = {args.elements}\n")
    with tempfile.TemporaryDirectory(prefix="bench_native_") as folder:
        folder = Path(folder)
        python_fmu = build_fmu(folder / "python")
        for speed in speeds:
            result = bench_point(folder, python_fmu, args.elements, speed, args.rounds,
                                 args.steps)
            reduced, costs = result["reduced"], result["costs"]
            floor = costs["(c) fmpy overhead"]
            print(f"V = {speed:g} m/s: {reduced.n_states} states ({reduced.n_modes} complex "
                  f"modes), {reduced.n_inputs - 1} road delay group(s)")
            best, best_floor = result["best"], result["best"]["(c) fmpy overhead"]
            print(f"   {'':<22} {'median us':>9} {'x (c)':>6} {'min us':>7} {'x (c)':>6} "
                  f"{'init s':>7}")
            for name, cost in costs.items():
                print(f"   {name:<22} {cost * 1e6:9.2f} {cost / floor:6.2f} "
                      f"{best[name] * 1e6:7.2f} {best[name] / best_floor:6.2f} "
                      f"{result['init'][name]:7.3f}")
            ratio = costs["(a) native C FMU"] / floor
            verdict = "meets" if ratio <= 1.2 else "MISSES"
            print(f"   (a) / (c) = {ratio:.2f}: {verdict} the target <= 1.2; "
                  f"(b) / (a) = {costs['(b) Python FMU'] / costs['(a) native C FMU']:.1f}; "
                  f"C work per step ~ {(costs['(a) native C FMU'] - floor) * 1e6:.2f} us\n")
    print(f"Python {sys.version.split()[0]}; the native FMU compiled with the local gcc -O2 "
          "(tire_fmu.native.builder.COMPILE_FLAGS).")


if __name__ == "__main__":
    main()
