"""How the tire meets a master's inputs: the error of a 1 ms (and 2 ms) host step against
0.1 ms, as a master that sets the inputs at t (fmpy's simulate_fmu, libcosim, ecos, fmusim)
gives them.

Two parts, printed side by side and recorded with ``--record``:

1. **The choice** (core/host_inputs.py): the in-plane tire's stepper, its rim hopping 1 mm at
   12 Hz at 10 m/s, with the inputs extended over the step three ways: held (the values at t,
   no rate), along the rate only, and along the rate and its last two changes (what the FMUs
   do). The error is the largest difference of rim_Fz and rim_Fx at 1 ms from 0.1 ms, over
   their range at 0.1 ms.
2. **The four FMUs** through fmpy's FMU2Slave in a plain master loop: the wheel hopping 1 mm at
   12 Hz (and half of it fore and aft) and a 10 mm rounded bump at the zone front, 10 m/s (the
   in-plane FMUs: the wheel centre, and the bump on the host's road by position, road_x_i
   out, road_z_i in).

    python3 benchmarks/bench_host_timing.py [--record docs/measured/bench_host_timing.json]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tire_fmu.fmu.interface import ROAD_QUERIES

sys.path.insert(0, str(Path(__file__).resolve().parent))
from record import cpu_model, load_average, write_record  # noqa: E402

SPEED = 10.0
DURATION = 0.25
SCHEMES = {"held": (0.0, 0.0, 0.0), "rate": (1.0, 0.0, 0.0), "rate and its changes":
           (1.0, 1.0, 1.0)}


def hop(t):
    """The wheel hopping 1 mm at 12 Hz from rest (sin³), half of it fore and aft, and a 10 mm
    rounded bump, 0.5 m long, at the zone front from 0.1 s on: values and rates at t."""
    w = 2 * math.pi * 12.0
    s, c = math.sin(w * t), math.cos(w * t)
    z, vz = 1e-3 * s**3, 3e-3 * w * s * s * c
    u = (SPEED * t - 1.0) / 0.5
    bump = rate = 0.0
    if 0.0 <= u <= 1.0:
        bump = 5e-3 * (1 - math.cos(2 * math.pi * u))
        rate = 5e-3 * 2 * math.pi * math.sin(2 * math.pi * u) * SPEED / 0.5
    return {"rim_z": z, "rim_vz": vz, "rim_x": 0.5 * z, "rim_vx": 0.5 * vz, "road_z": bump,
            "road_vz": rate}


def error_of(coarse: np.ndarray, fine: np.ndarray, every: int) -> list[float]:
    fine = fine[every - 1::every]
    return [float(np.abs(coarse[:, i] - fine[:, i]).max() / np.ptp(fine[:, i]))
            for i in range(coarse.shape[1])]


def core_scheme(scheme: str, h: float) -> np.ndarray:
    """The in-plane stepper with the inputs extended as ``scheme`` says: rim_Fz, rim_Fx."""
    import tire_fmu.core.inplane_contact as contact
    from tire_fmu.core.host_inputs import input_path
    from tire_fmu.core.inplane_host import HostSettings, build_host_stepper

    rate_on, change_on, jerk_on = SCHEMES[scheme]

    def path(value, rate, acceleration, jerk=0.0):
        return input_path(value, rate * rate_on, acceleration * change_on, jerk * jerk_on)

    stepper = build_host_stepper(HostSettings(speed_m_s=SPEED)).stepper
    original, contact.input_path = contact.input_path, path
    try:
        rows = []
        for k in range(int(round(DURATION / h))):
            s = hop(k * h)
            out = stepper.advance(h, s["rim_x"], s["rim_vx"], s["rim_z"], s["rim_vz"], 0.0,
                                  s["road_z"], s["road_vz"], at_time_s=k * h)
            rows.append((out.rim_fz_n, out.rim_fx_n))
    finally:
        contact.input_path = original
    return np.array(rows)


def fmu_run(path, h: float) -> np.ndarray:
    """A plain master: the inputs at t, then fmi2DoStep(t, h); rim_Fz and rim_Fx."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr["speed"]], [SPEED])
    centre = "wheel_z" in vr  # the in-plane FMUs: the wheel centre, the host's road by position
    if centre:
        fmu.setReal([vr["wheel_vx"]], [SPEED])
    fmu.exitInitializationMode()
    if centre:
        radius = fmu.getReal([vr["loaded_radius"]])[0]
        asked = [vr[f"road_x_{i}"] for i in range(1, ROAD_QUERIES + 1)]
        heights = [vr[f"road_z_{i}"] for i in range(1, ROAD_QUERIES + 1)]
    rows, outputs = [], [vr["rim_Fz"], vr["rim_Fx"]]
    for k in range(int(round(DURATION / h))):
        inputs = hop(k * h)
        if centre:  # the same motion; the bump where the zone's front (0.15 m) meets it
            inputs = {"wheel_x": SPEED * k * h + inputs["rim_x"],
                      "wheel_vx": SPEED + inputs["rim_vx"],
                      "wheel_z": radius + inputs["rim_z"], "wheel_vz": inputs["rim_vz"]}
            u = np.clip((np.array(fmu.getReal(asked)) - 1.15) / 0.5, 0.0, 1.0)
            fmu.setReal(heights, list(5e-3 * (1 - np.cos(2 * np.pi * u))))
        inputs = {n: v for n, v in inputs.items() if n in vr}
        fmu.setReal([vr[n] for n in inputs], list(inputs.values()))
        fmu.doStep(k * h, h)
        rows.append(fmu.getReal(outputs))
    fmu.terminate()
    fmu.freeInstance()
    return np.array(rows)


def build_fmus(folder: Path) -> dict:
    from tire_fmu.fmu.builder import build_fmu, build_inplane_fmu
    from tire_fmu.native import build_native_fmu
    from tire_fmu.native.builder import build_native_inplane_fmu

    return {"TireModal": build_fmu(folder / "modal"),
            "TireModalNative": build_native_fmu(folder / "TireModalNative.fmu"),
            "TireInPlane": build_inplane_fmu(folder / "inplane"),
            "TireInPlaneNative": build_native_inplane_fmu(folder / "inplane_native")}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", help="write the results to this JSON file")
    args = parser.parse_args()
    load_start = load_average()
    print(f"CPU: {cpu_model()}; load average {load_start}")
    started = time.perf_counter()
    choice = {}
    fine = {scheme: core_scheme(scheme, 1e-4) for scheme in SCHEMES}
    print("\n1. extending the inputs over the step (in-plane core, error at 1 ms vs 0.1 ms, "
          "of the range)")
    print(f"   {'scheme':24s} {'rim_Fz':>8s} {'rim_Fx':>8s}")
    for scheme in SCHEMES:
        fz, fx = error_of(core_scheme(scheme, 1e-3), fine[scheme], 10)
        choice[scheme] = {"rim_Fz": fz, "rim_Fx": fx}
        print(f"   {scheme:24s} {100 * fz:7.2f}% {100 * fx:7.2f}%")
    fmus = {}
    with tempfile.TemporaryDirectory() as folder:
        paths = build_fmus(Path(folder))
        print("\n2. the four FMUs through a plain master (error of the range vs 0.1 ms)")
        print(f"   {'FMU':18s} {'h':>6s} {'rim_Fz':>8s} {'rim_Fx':>8s}")
        for name, path in paths.items():
            reference = fmu_run(path, 1e-4)
            fmus[name] = {}
            for h in (1e-3, 2e-3):
                fz, fx = error_of(fmu_run(path, h), reference, int(round(h / 1e-4)))
                fmus[name][f"{h:g}"] = {"rim_Fz": fz, "rim_Fx": fx}
                print(f"   {name:18s} {h * 1e3:4.0f}ms {100 * fz:7.2f}% {100 * fx:7.2f}%")
    print(f"\n{time.perf_counter() - started:.0f} s")
    if args.record:
        write_record(args.record, {"schemes": choice, "fmus": fmus,
                                   "speed_m_s": SPEED, "duration_s": DURATION}, load_start)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
