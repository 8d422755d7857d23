"""TireInPlane.fmu's cost per step through fmpy, beside the radial FMUs and the floors, in one run.

1. Cost per communication step at h = 1e-4 s (one of the in-plane tire's own steps): setReal
   of the inputs, doStep, getReal of the outputs, at N = 100, in four regimes: at rest (a
   1 mm, 10 Hz road undulation), free rolling at 10 m/s, braking at 10 m/s (-3 kN m on the
   wheel) and at 10 m/s over 20 mm x 20 mm cleats read at the zone front (one every 0.5 m).
       (a) TireInPlane.fmu, the in-plane tire (Python FMU, its step in C: inplane_step.c),
       (b) TireModal.fmu, the radial Python FMU (its compiled kernel), same regime without
           the torque,
       (c) TireModalNative.fmu, the radial native FMU,
       (d) a minimal pythonfmu slave (benchmarks/bench_fmu.py's), the floor of a Python FMU,
       (e) a trivial C FMU (benchmarks/trivial_fmu), the floor of a C FMU,
       (f) TireInPlaneNative.fmu, the in-plane tire in C (no Python): its cost against (e)
           is the tire's own, against (a) what the Python FMU layer costs.
   Rounds alternate, medians. ``--numpy`` also runs the in-plane FMU with its numpy step
   (the FMU without its compiled library).
2. Initialisation (instantiate -> exitInitializationMode, warm process) of TireInPlane and
   TireInPlaneNative at N = 100 and 400 (``--init-elements`` chooses), at rest and rolling at
   5 m/s (below N = 400's critical speed), beside TireModal's.

    python benchmarks/bench_inplane_fmu.py [--rounds 5] [--steps 200] [--init-elements 100]
        [--record JSON]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
import zipfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from bench_fmu import Opened, build_minimal, build_trivial, init_time  # noqa: E402

from tire_fmu.core.obstacles import cleat  # noqa: E402
from tire_fmu.fmu.builder import build_fmu, build_inplane_fmu  # noqa: E402
from tire_fmu.fmu.interface import ROAD_QUERIES  # noqa: E402
from tire_fmu.native import build_native_fmu, build_native_inplane_fmu  # noqa: E402

H = 1e-4
RADIAL_INPUTS = ("rim_z", "rim_vz", "road_z", "road_vz")
#: The in-plane FMUs': the wheel centre, the torque and spin, the host's road (here the
#: signal's height at every position asked: the cost of the call, a level road moving)
INPLANE_INPUTS = ("wheel_x", "wheel_vx", "wheel_z", "wheel_vz", "wheel_torque",
                  "wheel_rate") + tuple(f"road_z_{i}" for i in range(1, ROAD_QUERIES + 1))
RADIAL_OUTPUTS = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length",
                  "tread_deflection")
INPLANE_OUTPUTS = ("rim_Fz", "rim_Fx", "rim_My", "contact_Fz", "contact_Fx", "wheel_spin",
                   "sliding_points")
CLEAT = cleat(0.02, 0.02)
INIT_ELEMENTS = (100, 400)


def undulation(t):
    w = 2 * math.pi * 10.0
    return [0.0, 0.0, 1e-3 * math.sin(w * t), 1e-3 * w * math.cos(w * t), 0.0, 0.0, 0.0]


def rolling(t):
    return [0.0] * 7


def braking(t):
    return [0.0] * 6 + [-3000.0]


def over_cleats(t):
    s = (10.0 * t) % 0.5 - 0.25  # a cleat every 0.5 m, met at the zone front
    z, slope = CLEAT.profile([s])
    return [0.0, 0.0, float(z[0]), float(10.0 * slope[0]), 0.0, 0.0, 0.0]


REGIMES = {"at rest": (0.0, undulation), "10 m/s, free rolling": (10.0, rolling),
           "10 m/s, braking -3 kN m": (10.0, braking), "10 m/s, over cleats": (10.0, over_cleats)}
NAMES = {"inplane": "(a) TireInPlane (Python FMU, C step)",
         "inplane_numpy": "(a') TireInPlane, numpy step (its C library taken out)",
         "python": "(b) TireModal (radial Python FMU)",
         "native": "(c) TireModalNative (radial native FMU)",
         "minimal": "(d) minimal pythonfmu slave", "trivial": "(e) trivial C FMU",
         "inplane_native": "(f) TireInPlaneNative (in-plane native FMU)"}
#: The FMUs whose initialisation is timed.
INIT_KINDS = ("inplane", "inplane_native", "python")


class Case:
    def __init__(self, fmu: Opened, kind: str, speed: float, signal, steps: int):
        tire = kind not in ("minimal", "trivial")
        self.slave = fmu.initialised({"speed": speed} if tire else {})
        inplane = kind.startswith("inplane")
        inputs = INPLANE_INPUTS if inplane else RADIAL_INPUTS
        outputs = INPLANE_OUTPUTS if inplane else RADIAL_OUTPUTS
        self.inputs = [fmu.vr[n] for n in inputs]
        self.outputs = [fmu.vr[n] for n in outputs]
        self.values = [signal(k * H)[:7 if inplane else 4] for k in range(steps)]
        self.k = 0
        if inplane:  # the wheel centre rolling at the speed, from the loaded radius
            radius = self.slave.getReal([fmu.vr["loaded_radius"]])[0]
            self.values = [[speed * k * H, speed + v[5], radius + v[0], v[1], v[6], 0.0,
                            *([v[2]] * ROAD_QUERIES)] for k, v in enumerate(self.values)]

    def run(self, steps: int) -> float:
        set_real, do_step, get_real = self.slave.setReal, self.slave.doStep, self.slave.getReal
        values, n, k = self.values, len(self.values), self.k
        started = time.perf_counter()
        for _ in range(steps):
            set_real(self.inputs, values[k % n])
            do_step(k * H, H)
            get_real(self.outputs)
            k += 1
        self.k = k
        return (time.perf_counter() - started) / steps

    def close(self):
        self.slave.terminate()
        self.slave.freeInstance()


def without_kernel(fmu: Path, dest: Path) -> Path:
    """A copy of the FMU without its compiled kernel libraries: it steps with numpy."""
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(dest, "w") as copy:
        for item in source.infolist():
            if Path(item.filename).stem != "tire_kernel":
                copy.writestr(item, source.read(item.filename))
    return dest


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5, help="alternating rounds (5)")
    parser.add_argument("--steps", type=int, default=200, help="steps per round (200)")
    parser.add_argument("--init-repeats", type=int, default=1,
                        help="warm initialisations per case (1)")
    parser.add_argument("--init-elements", type=int, nargs="+", default=list(INIT_ELEMENTS),
                        metavar="N", help="meshes whose initialisation is timed (100 400)")
    parser.add_argument("--numpy", action="store_true",
                        help="also run the in-plane FMU with its numpy step")
    parser.add_argument("--record", metavar="JSON", help="also write the results there")
    args = parser.parse_args(argv)
    from record import load_average, write_record

    load_at_start = load_average()
    with tempfile.TemporaryDirectory(prefix="bench_inplane_fmu_") as folder:
        folder = Path(folder)
        paths = {"inplane": build_inplane_fmu(folder / "inplane"),
                 "python": build_fmu(folder / "radial"),
                 "native": build_native_fmu(folder / "TireModalNative.fmu",
                                            platforms=("linux64",)),
                 "minimal": build_minimal(folder / "minimal"),
                 "trivial": build_trivial(folder / "trivial"),
                 "inplane_native": build_native_inplane_fmu(
                     folder / "TireInPlaneNative.fmu", platforms=("linux64",))}
        names = dict(NAMES)
        if args.numpy:
            paths["inplane_numpy"] = without_kernel(paths["inplane"], folder / "numpy.fmu")
        else:
            del names["inplane_numpy"]
        fmus = {kind: Opened(path) for kind, path in paths.items()}
        horizon = 2000
        cases = {(regime, kind): Case(fmus[kind], kind, speed, signal, horizon)
                 for regime, (speed, signal) in REGIMES.items() for kind in names}
        for case in cases.values():
            case.run(50)  # past the first steps' transient
        times = {key: [] for key in cases}
        for _ in range(args.rounds):
            for key, case in cases.items():
                times[key].append(case.run(args.steps))
        for case in cases.values():
            case.close()
        costs = {key: 1e6 * statistics.median(v) for key, v in times.items()}
        for kind in INIT_KINDS:
            init_time(fmus[kind], {}, 1)  # the modules imported, the library loaded
        inits = {kind: {f"N = {n}, {speed:g} m/s": init_time(
            fmus[kind], {"n_elements": n, "speed": speed}, args.init_repeats)
            for n in args.init_elements for speed in (0.0, 5.0)} for kind in INIT_KINDS}

    print(f"1. Cost per communication step through fmpy, h = {H:g} s, N = 100 (median of "
          f"{args.rounds} alternating rounds of {args.steps} steps), µs")
    print(f"   {'regime':<26}" + "".join(f" {key.split()[0]:>9}" for key in names.values())
          + f" {'(a)/(b)':>8} {'(a)/(d)':>8} {'(b)/(d)':>8} {'(a)/(f)':>8} {'(f)/(e)':>8}")
    rows = {}
    for regime in REGIMES:
        c = {kind: costs[regime, kind] for kind in names}
        rows[regime] = {names[kind]: c[kind] for kind in names}
        print(f"   {regime:<26}" + "".join(f" {c[kind]:9.1f}" for kind in names)
              + f" {c['inplane'] / c['python']:8.1f} {c['inplane'] / c['minimal']:8.1f} "
              f"{c['python'] / c['minimal']:8.2f} {c['inplane'] / c['inplane_native']:8.1f} "
              f"{c['inplane_native'] / c['trivial']:8.1f}")
    for name in names.values():
        print(f"   {name}")
    for kind in ("inplane", "inplane_native"):
        worst = max(r[names[kind]] for r in rows.values())
        print(f"   {names[kind].split(' (')[0]} at its slowest: {worst * 1e-6 / H:.2f} s of "
              f"wall time per simulated second at h = {H:g} s")
    print(f"\n2. Initialisation, instantiate -> exitInitializationMode, warm process "
          f"(median of {args.init_repeats}), s")
    labels = list(inits["inplane"])
    print(f"   {'FMU':<44}" + "".join(f" {label:>16}" for label in labels))
    for kind in INIT_KINDS:
        print(f"   {names[kind]:<44}" + "".join(f" {inits[kind][label]:16.2f}"
                                                  for label in labels))
    print(f"\nPython {sys.version.split()[0]}; each FMU's defaults otherwise.")
    if args.record:
        write_record(args.record, {"step_us": rows, "init_s": {names[k]: v
                                                              for k, v in inits.items()}},
                     load_at_start)


if __name__ == "__main__":
    main()
