"""The in-plane FMUs' work bound, measured: the longest call each accepts at its worst settings,
and what it costs.

A host step is refused before any work when its estimate (core/inplane_contact.py's
host_step_work: the tire's steps and at most two rebuilds of the ring's step) exceeds
step_limits.MAX_STEP_WORK, naming the longest step that fits. Here, for TireInPlane and
TireInPlaneNative side by side in one run:

- the default tire (N = 100) and the finest tire step (step_size = 1e-6 s): the longest host
  step accepted, the CPU time of one such call, and the CPU seconds per simulated second;
- the finest mesh accepted (n_elements = 800): the CPU time and the peak memory of its
  initialisation (each in a fresh process).

    python3 benchmarks/bench_inplane_limits.py [--record docs/measured/bench_inplane_limits.json]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from record import cpu_model, load_average, write_record  # noqa: E402

CASES = {"default tire": {}, "step_size = 1e-6 s": {"step_size": 1e-6}}

_INIT = r"""
import json, resource, sys, time
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
path, n = sys.argv[1], int(sys.argv[2])
md = read_model_description(path)
vr = {v.name: v.valueReference for v in md.modelVariables}
fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path),
                modelIdentifier=md.coSimulation.modelIdentifier, instanceName="init")
fmu.instantiate()
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
fmu.setInteger([vr["n_elements"]], [n])
start = time.process_time()
fmu.exitInitializationMode()
cpu = time.process_time() - start
fmu.doStep(0.0, 1e-3)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
print(json.dumps({"cpu_s": cpu, "peak_mb": peak}))
"""


def instance(path, **reals):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="limits")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    for name, value in reals.items():
        fmu.setReal([vr[name]], [value])
    fmu.exitInitializationMode()
    return fmu, vr


def longest_call(path, reals: dict) -> dict:
    """The longest host step the FMU accepts at these settings, its CPU time, per second."""
    from tire_fmu.core.inplane_contact import host_step_work
    from tire_fmu.core.inplane_host import HostSettings, build_host_stepper

    stepper = build_host_stepper(HostSettings(step_s=reals.get("step_size", 1e-4))).stepper
    sim = stepper.sim
    longest = host_step_work(1e-3, sim.step_s, sim._ny, sim._zone.n_points)[3]
    fmu, vr = instance(path, **reals)
    fmu.setReal([vr["wheel_torque"]], [-2000.0])
    start = time.process_time()
    fmu.doStep(0.0, longest)
    cpu = time.process_time() - start
    fmu.terminate()
    fmu.freeInstance()
    return {"longest_step_s": longest, "cpu_s": cpu, "cpu_s_per_simulated_s": cpu / longest}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", help="write the results to this JSON file")
    parser.add_argument("--finest", type=int, default=800, help="the mesh to initialise")
    args = parser.parse_args()
    from tire_fmu.fmu.builder import build_inplane_fmu
    from tire_fmu.native.builder import build_native_inplane_fmu

    load_start = load_average()
    print(f"CPU: {cpu_model()}; load average {load_start}")
    results = {}
    with tempfile.TemporaryDirectory() as folder:
        paths = {"TireInPlane": build_inplane_fmu(Path(folder) / "python"),
                 "TireInPlaneNative": build_native_inplane_fmu(Path(folder) / "native")}
        print(f"{'':22s}{'FMU':20s}{'longest step':>14s}{'CPU':>10s}{'CPU s / sim s':>15s}")
        for case, reals in CASES.items():
            for name, path in paths.items():
                row = longest_call(path, reals)
                results.setdefault(case, {})[name] = row
                print(f"{case:22s}{name:20s}{row['longest_step_s'] * 1e3:11.3f} ms"
                      f"{row['cpu_s']:9.2f} s{row['cpu_s_per_simulated_s']:14.1f}")
        print(f"\ninitialisation at n_elements = {args.finest} (a fresh process each)")
        for name, path in paths.items():
            out = subprocess.run([sys.executable, "-c", _INIT, str(path), str(args.finest)],
                                 capture_output=True, text=True, check=True)
            row = json.loads(out.stdout.strip().splitlines()[-1])
            results.setdefault(f"init n_elements = {args.finest}", {})[name] = row
            print(f"  {name:20s} {row['cpu_s']:7.1f} s CPU, peak {row['peak_mb']:7.0f} MB")
    if args.record:
        write_record(args.record, results, load_start)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
