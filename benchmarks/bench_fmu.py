"""Both FMUs' cost per step through fmpy, each beside its floor, printed side by side in one run.

1. Cost per communication step at h = 1e-4 s: setReal of the 4 inputs, doStep, getReal of the
   6 Real outputs, in three regimes at N = 100: at rest in contact (a 1 mm, 10 Hz road
   undulation), at 20 m/s in contact (the same road through the delay line), and at 10 m/s
   over a 40 mm cleat that lifts the tire off (a cleat every 0.2 s, on a contact zone of
   0.8 m: the default's end is where such a cleat first meets the tread). Each of
       (a) TireModal.fmu, the Python FMU (its compiled step kernel, one ctypes call a step),
       (b) a minimal pythonfmu slave built here with the same 4 inputs and 6 outputs (its
           do_step copies): the floor of any Python FMU,
       (c) TireModalNative.fmu, the native FMU (the same kernel in C),
       (d) a trivial C FMU with the same interface (benchmarks/trivial_fmu/trivial.c, its
           doStep copies): fmpy's own call cost, the floor of any C FMU,
   runs the same precomputed inputs; rounds alternate, so load hits all alike. Aims (issue
   20): (a) / (b) <= 1.5 and (c) / (d) <= 1.2 in every regime.
2. Initialisation of the Python FMU (instantiate -> exitInitializationMode) at N = 100 and 400
   in a warm process (benchmarks/bench_fmu_init.py measures a fresh one).
3. Real-time factor at 10 kHz (step cost / 100 us) and its inverse.

    python benchmarks/bench_fmu.py [--rounds 15] [--steps 2000] [--init-repeats 3]
                                   [--record JSON]
"""

from __future__ import annotations

import argparse
import math
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
import zipfile
from pathlib import Path
from xml.etree import ElementTree

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from tire_fmu.fmu.builder import build_fmu
from tire_fmu.native import build_native_fmu
from tire_fmu.native.builder import c_folder

H = 1e-4
INPUTS = ("rim_z", "rim_vz", "road_z", "road_vz")
OUTPUTS = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length", "tread_deflection")
HERE = Path(__file__).parent

MINIMAL_SLAVE = f'''
from pythonfmu import Fmi2Causality, Fmi2Slave, Real

INPUTS = {INPUTS!r}
OUTPUTS = {OUTPUTS!r}


class BenchMinimal(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name in INPUTS + OUTPUTS:
            setattr(self, name, 0.0)
            causality = Fmi2Causality.input if name in INPUTS else Fmi2Causality.output
            self.register_variable(Real(name, causality=causality))

    def do_step(self, current_time, step_size):
        value = self.rim_z
        self.rim_Fz = self.rim_Fx = self.contact_Fz = value
        self.deflection = self.contact_length = self.tread_deflection = value
        return True
'''


def build_minimal(folder: Path) -> Path:
    from pythonfmu.builder import FmuBuilder

    folder.mkdir(parents=True, exist_ok=True)
    script = folder / "bench_minimal_slave.py"
    script.write_text(MINIMAL_SLAVE)
    try:
        return Path(FmuBuilder.build_FMU(script, dest=folder))
    finally:
        sys.modules.pop(script.stem, None)
        while str(folder) in sys.path:
            sys.path.remove(str(folder))


def build_trivial(folder: Path) -> Path:
    """The copying C FMU with the tire's first value references (inputs 0-3, outputs 4-9)."""
    binary = folder / "binaries" / "linux64" / "Trivial.so"
    binary.parent.mkdir(parents=True)
    subprocess.run(["gcc", "-shared", "-fPIC", "-O2", "-I", str(c_folder()), "-o", str(binary),
                    str(HERE / "trivial_fmu" / "trivial.c")], check=True)
    root = ElementTree.Element("fmiModelDescription", fmiVersion="2.0", modelName="Trivial",
                               guid="{trivial}", numberOfEventIndicators="0")
    ElementTree.SubElement(root, "CoSimulation", modelIdentifier="Trivial",
                           canHandleVariableCommunicationStepSize="true")
    variables = ElementTree.SubElement(root, "ModelVariables")
    for vr, name in enumerate(INPUTS + OUTPUTS):
        causality = "input" if vr < len(INPUTS) else "output"
        v = ElementTree.SubElement(variables, "ScalarVariable", name=name,
                                   valueReference=str(vr), causality=causality,
                                   variability="continuous")
        ElementTree.SubElement(v, "Real", **({"start": "0.0"} if causality == "input" else {}))
    structure = ElementTree.SubElement(root, "ModelStructure")
    outputs = ElementTree.SubElement(structure, "Outputs")
    for index in range(len(INPUTS) + 1, len(INPUTS) + len(OUTPUTS) + 1):
        ElementTree.SubElement(outputs, "Unknown", index=str(index))
    (folder / "modelDescription.xml").write_bytes(ElementTree.tostring(root))
    fmu = folder.parent / "Trivial.fmu"
    with zipfile.ZipFile(fmu, "w") as archive:
        for path in sorted(folder.rglob("*")):
            if path.is_file():
                archive.write(path, path.relative_to(folder).as_posix())
    return fmu


# -- the regimes: the inputs of every step, precomputed -----------------------------------------

def undulation(t: float) -> list[float]:
    w = 2 * math.pi * 10.0  # a 1 mm, 10 Hz road undulation
    return [0.0, 0.0, 1e-3 * math.sin(w * t), 1e-3 * w * math.cos(w * t)]


def cleat(t: float, speed: float = 10.0, height: float = 0.04, length: float = 0.04,
          ramp: float = 0.005, period: float = 0.2) -> list[float]:
    """A 40 mm x 40 mm cleat every 0.2 s at 10 m/s, its edges raised-cosine ramps of 5 mm."""
    x = (t % period) * speed  # road passed the zone front since the cleat's start
    rise, top = ramp, ramp + length

    def edge(s):  # 0 -> 1 over a ramp, and its derivative by s
        return 0.5 - 0.5 * math.cos(math.pi * s), 0.5 * math.pi * math.sin(math.pi * s)

    if x < rise:
        z, dz = edge(x / ramp)
    elif x < top:
        z, dz = 1.0, 0.0
    elif x < top + ramp:
        z, dz = edge(1.0 - (x - top) / ramp)
        dz = -dz
    else:
        z, dz = 0.0, 0.0
    return [0.0, 0.0, height * z, height * dz * speed / ramp]


#: regime: (speed, inputs, other parameters). A 40 mm cleat meets the tread 0.25 m ahead of
#: the contact centre, the end of the default zone: the cleat runs on a longer zone.
REGIMES = {"at rest, in contact": (0.0, undulation, {}),
           "20 m/s, in contact": (20.0, undulation, {}),
           "10 m/s, 40 mm cleat (lift-off)": (10.0, cleat, {"contact_zone_length": 0.8})}


class Opened:
    """An FMU extracted once, whose instances are made initialised."""

    def __init__(self, path: Path):
        self.description = read_model_description(str(path))
        self.folder = extract(str(path))
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}
        self.count = 0

    def initialised(self, parameters: dict) -> FMU2Slave:
        self.count += 1
        slave = FMU2Slave(guid=self.description.guid, unzipDirectory=self.folder,
                          modelIdentifier=self.description.coSimulation.modelIdentifier,
                          instanceName=f"bench{self.count}")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        for name, value in parameters.items():
            if name in self.vr:
                setter = slave.setInteger if isinstance(value, int) else slave.setReal
                setter([self.vr[name]], [value])
        slave.exitInitializationMode()
        return slave


class Case:
    """One FMU instance in one regime: runs the regime's inputs from where it left off."""

    def __init__(self, fmu: Opened, speed: float, signal, parameters: dict, horizon: int):
        self.slave = fmu.initialised({"speed": speed, **parameters})
        self.inputs = [fmu.vr[n] for n in INPUTS]
        self.outputs = [fmu.vr[n] for n in OUTPUTS]
        self.values = [signal(k * H) for k in range(horizon)]
        self.k = 0

    def run(self, steps: int) -> float:
        """Seconds per communication step over ``steps`` steps."""
        set_real, do_step, get_real = self.slave.setReal, self.slave.doStep, self.slave.getReal
        inputs, outputs, values, n = self.inputs, self.outputs, self.values, len(self.values)
        k = self.k
        started = time.perf_counter()
        for _ in range(steps):
            set_real(inputs, values[k % n])
            do_step(k * H, H)
            get_real(outputs)
            k += 1
        elapsed = time.perf_counter() - started
        self.k = k
        return elapsed / steps

    def close(self):
        self.slave.terminate()
        self.slave.freeInstance()


def init_time(fmu: Opened, n_elements: int, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        slave = fmu.initialised({"n_elements": n_elements})
        times.append(time.perf_counter() - started)
        slave.terminate()
        slave.freeInstance()
    return statistics.median(times)


NAMES = {"python": "(a) TireModal (Python FMU)", "minimal": "(b) minimal pythonfmu slave",
         "native": "(c) TireModalNative (native FMU)", "trivial": "(d) trivial C FMU"}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=15, help="alternating rounds (15)")
    parser.add_argument("--steps", type=int, default=2000, help="steps per round (2000)")
    parser.add_argument("--init-repeats", type=int, default=3, help="initialisations (3)")
    parser.add_argument("--record", metavar="JSON", help="also write the results there (the "
                        "docs quote docs/measured/bench_fmu.json)")
    args = parser.parse_args(argv)
    from record import load_average, write_record

    load_at_start = load_average()
    horizon = int(round(0.2 / H))  # one cleat period
    with tempfile.TemporaryDirectory(prefix="bench_fmu_") as folder:
        folder = Path(folder)
        fmus = {"python": Opened(build_fmu(folder / "tire")),
                "minimal": Opened(build_minimal(folder / "minimal")),
                "native": Opened(build_native_fmu(folder / "TireModalNative.fmu",
                                                  platforms=("linux64",))),
                "trivial": Opened(build_trivial(folder / "trivial"))}
        cases = {(regime, kind): Case(fmu, speed, signal, parameters, horizon)
                 for regime, (speed, signal, parameters) in REGIMES.items()
                 for kind, fmu in fmus.items()}
        for case in cases.values():
            case.run(horizon)  # past the transient and into the delay line, one cleat pass
        times = {key: [] for key in cases}
        for _ in range(args.rounds):
            for key, case in cases.items():
                times[key].append(case.run(args.steps))
        for case in cases.values():
            case.close()
        inits = {n: init_time(fmus["python"], n, args.init_repeats) for n in (100, 400)}
    costs = {key: statistics.median(values) for key, values in times.items()}

    print(f"1. Cost per communication step through fmpy, h = {H:g} s, N = 100 (median of "
          f"{args.rounds} alternating rounds of {args.steps} steps), µs")
    print(f"   {'regime':<32} {'(a)':>7} {'(b)':>7} {'(a)/(b)':>8} {'(c)':>7} {'(d)':>7} "
          f"{'(c)/(d)':>8}")
    ratios = {}
    for regime in REGIMES:
        a, b, c, d = (1e6 * costs[regime, kind] for kind in NAMES)
        ratios[regime] = (a / b, c / d)
        print(f"   {regime:<32} {a:7.2f} {b:7.2f} {a / b:8.2f} {c:7.2f} {d:7.2f} {c / d:8.2f}")
    for name in NAMES.values():
        print(f"   {name}")
    worst_python = max(r[0] for r in ratios.values())
    worst_native = max(r[1] for r in ratios.values())
    print(f"   worst (a)/(b) = {worst_python:.2f}: "
          f"{'meets' if worst_python <= 1.5 else 'MISSES'} the aim <= 1.5; worst (c)/(d) = "
          f"{worst_native:.2f}: {'meets' if worst_native <= 1.2 else 'MISSES'} the aim <= 1.2 "
          "(issue 20)")
    print("\n2. Python FMU initialisation, instantiate -> exitInitializationMode, warm process "
          f"(median of {args.init_repeats})")
    for n, seconds in inits.items():
        print(f"   N = {n:<4} {seconds:7.3f} s")
    print("\n3. Real-time factor at 10 kHz (wall time / simulated time)")
    for regime in REGIMES:
        for kind in ("python", "native"):
            factor = costs[regime, kind] / H
            print(f"   {NAMES[kind][:3]} {regime:<32} {factor:6.3f}  ({1 / factor:5.1f} x "
                  "faster than real time)")
    print(textwrap.dedent(f"""
        Python {sys.version.split()[0]}; TireModal's defaults otherwise (N = 100).
        """).rstrip())
    if args.record:
        write_record(args.record, {
            "step_us": {regime: {NAMES[kind]: 1e6 * costs[regime, kind] for kind in NAMES}
                        for regime in REGIMES},
            "ratios": {regime: {"python_over_minimal": r[0], "native_over_trivial": r[1]}
                       for regime, r in ratios.items()},
            "init_s": {str(n): seconds for n, seconds in inits.items()},
            "init_repeats": args.init_repeats,
        }, load_at_start)


if __name__ == "__main__":
    main()
