"""Both FMUs' cost per step through fmpy, each beside its floor, printed side by side in one run.

1. Cost per communication step at h = 1e-4 s: setReal of the 4 inputs, doStep, getReal of the
   6 Real outputs, at N = 100 in four regimes: at rest in contact (a 1 mm, 10 Hz road
   undulation), at 20 m/s in contact (the same road through the delay line), at 10 m/s over a
   20 mm x 20 mm cleat with the rim held (core/obstacles.py's cleat read at the zone front as
   the cleat study reads it, one every 0.5 m of road, so that one is under the tread 46 ms of
   every 50: the figure is the cost while the tire rolls over it), and in lift-off at 10 m/s
   (the rim raised 0.1 m, clear of the road: no point pushes). The tire FMUs run each regime
   at the default contact point spacing and at one point per node (contact_point_spacing =
   1 m: the node contact of before the contact points). Each of
       (a) TireModal.fmu, the Python FMU (its compiled step kernel, one ctypes call a step),
       (b) a minimal pythonfmu slave built here with the same 4 inputs and 6 outputs (its
           do_step copies): the floor of any Python FMU,
       (c) TireModalNative.fmu, the native FMU (the same kernel in C),
       (d) a trivial C FMU with the same interface (benchmarks/trivial_fmu/trivial.c, its
           doStep copies): fmpy's own call cost, the floor of any C FMU,
   runs the same precomputed inputs; rounds alternate, so load hits all alike; medians. Aims
   (issue 20, set for the node contact): (a) / (b) <= 1.5 and (c) / (d) <= 1.2.
2. Initialisation (instantiate -> exitInitializationMode) of both FMUs at N = 100 and 400, at
   both spacings, in a warm process (the FMU's modules imported by an earlier instance).
3. First initialisation: the same, each sample in a fresh process on a fresh extraction of
   the FMU (what a host pays once; benchmarks/bench_fmu_init.py splits the Python FMU's into
   its phases). ``--init-only`` runs 2 and 3 alone.
4. Real-time factor at 10 kHz (step cost / 100 us) and its inverse.

    python benchmarks/bench_fmu.py [--rounds 15] [--steps 2000] [--init-repeats 3]
                                   [--init-samples 5] [--init-only] [--record JSON]
"""

from __future__ import annotations

import argparse
import math
import shutil
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

from tire_fmu.core.obstacles import cleat
from tire_fmu.core.parameters import DEFAULT_POINT_SPACING_M
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


#: The cleat of the cleat study (docs/theory.md §4.6): 20 mm x 20 mm, rectangular.
CLEAT = cleat(0.02, 0.02)
CLEAT_SPEED_M_S = 10.0
#: A cleat every 0.5 m: the tread meets one from 0.22 m ahead of the contact centre until it
#: is 0.24 m behind, 46 ms of each 50 ms period.
CLEAT_PERIOD_S = 0.05
#: The precomputed inputs repeat after this: whole periods of the undulation and the cleats.
HORIZON_S = 0.2
#: Lift-off: the rim raised this far above its static height, clear of the road (the static
#: deflection is 18.6 mm).
LIFT_M = 0.1


def over_cleat(t: float) -> list[float]:
    """The cleat's road at the zone front, rim held: its first edge passes the front at the
    start of every period; each sample is the cleat's mean over its own step of road, as
    Obstacle.road_samples gives the cleat study (the slope of a rectangular cleat is 0)."""
    travelled = (t % CLEAT_PERIOD_S) * CLEAT_SPEED_M_S
    height, slope = CLEAT.road_samples(travelled, CLEAT_SPEED_M_S * H)
    return [0.0, 0.0, float(height), float(slope) * CLEAT_SPEED_M_S]


def lifted(t: float) -> list[float]:
    return [LIFT_M, 0.0, 0.0, 0.0]


#: regime: (speed, inputs). The cleat meets the undeformed tread 0.22 m ahead of the contact
#: centre, inside the default zone (0.3 m).
REGIMES = {"at rest, in contact": (0.0, undulation),
           "20 m/s, in contact": (20.0, undulation),
           "10 m/s, 20 mm cleat, rim held": (CLEAT_SPEED_M_S, over_cleat),
           "10 m/s, lift-off (rim 0.1 m up)": (CLEAT_SPEED_M_S, lifted)}
#: The tire FMUs' contact point spacings: the default, and one point per node.
SPACINGS = {f"{DEFAULT_POINT_SPACING_M * 1e3:g} mm points": DEFAULT_POINT_SPACING_M,
            "1 point per node": 1.0}
#: The FMUs whose cost depends on the contact points; the floors (b), (d) do not.
TIRES = ("python", "native")
INIT_ELEMENTS = (100, 400)


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


def init_time(fmu: Opened, parameters: dict, repeats: int) -> float:
    """Median seconds from instantiate to the end of exitInitializationMode, warm process."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        slave = fmu.initialised(parameters)
        times.append(time.perf_counter() - started)
        slave.terminate()
        slave.freeInstance()
    return statistics.median(times)


#: Run in a fresh process: one FMU's first initialisation, timed from instantiate.
FIRST_INIT = """
import sys, time
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave
folder, n_elements, spacing = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
md = read_model_description(folder)
vr = {v.name: v.valueReference for v in md.modelVariables}
started = time.perf_counter()
slave = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="first")
slave.instantiate()
slave.setupExperiment(startTime=0.0)
slave.enterInitializationMode()
slave.setInteger([vr["n_elements"]], [n_elements])
slave.setReal([vr["contact_point_spacing"]], [spacing])
built = time.perf_counter()
slave.exitInitializationMode()
done = time.perf_counter()
print(done - started, done - built)
"""


def first_init(path: Path, n_elements: int, spacing: float, scratch: Path) -> tuple[float, float]:
    """(instantiate -> exitInitializationMode, exitInitializationMode alone) in seconds, in a
    new process on a new extraction (not timed), as a host's first run meets the FMU."""
    folder = Path(extract(str(path), unzipdir=tempfile.mkdtemp(dir=scratch)))
    try:
        done = subprocess.run([sys.executable, "-c", FIRST_INIT, str(folder), str(n_elements),
                               repr(spacing)], capture_output=True, text=True, check=False)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if done.returncode != 0:
        raise SystemExit(f"{path.name}: the process failed:\n{done.stderr[-2000:]}")
    total, exit_s = map(float, done.stdout.split()[-2:])
    return total, exit_s


NAMES = {"python": "(a) TireModal (Python FMU)", "minimal": "(b) minimal pythonfmu slave",
         "native": "(c) TireModalNative (native FMU)", "trivial": "(d) trivial C FMU"}


def build_all(folder: Path, floors: bool) -> dict[str, Path]:
    paths = {"python": build_fmu(folder / "tire"),
             "native": build_native_fmu(folder / "TireModalNative.fmu", platforms=("linux64",))}
    if floors:
        paths["minimal"] = build_minimal(folder / "minimal")
        paths["trivial"] = build_trivial(folder / "trivial")
    return paths


def measure_inits(paths: dict[str, Path], fmus: dict[str, Opened], repeats: int, samples: int,
                  scratch: Path) -> tuple[dict, dict]:
    """Warm and first initialisations of both tire FMUs, per spacing and mesh; the first
    ones alternate FMU, spacing and mesh sample by sample."""
    for kind in TIRES:  # warm: the modules imported (a run with --init-only has not yet)
        init_time(fmus[kind], {}, 1)
    warm = {kind: {label: {n: init_time(fmus[kind], {"n_elements": n,
                                                     "contact_point_spacing": spacing}, repeats)
                           for n in INIT_ELEMENTS}
                   for label, spacing in SPACINGS.items()} for kind in TIRES}
    runs = {(kind, label, n): [] for kind in TIRES for label in SPACINGS for n in INIT_ELEMENTS}
    for _ in range(samples):
        for kind, label, n in runs:
            runs[kind, label, n].append(first_init(paths[kind], n, SPACINGS[label], scratch))
    first = {kind: {label: {n: {"total_s": statistics.median(r[0] for r in runs[kind, label, n]),
                                "exit_s": statistics.median(r[1] for r in runs[kind, label, n])}
                            for n in INIT_ELEMENTS} for label in SPACINGS} for kind in TIRES}
    return warm, first


def print_inits(warm: dict, first: dict, repeats: int, samples: int, number: int) -> None:
    print(f"\n{number}. Initialisation, instantiate -> exitInitializationMode, warm process "
          f"(median of {repeats}), s")
    header = "".join(f" {f'N = {n}':>9}" for n in INIT_ELEMENTS)
    print(f"   {'FMU, contact points':<52}{header}")
    for kind in TIRES:
        for label in SPACINGS:
            row = "".join(f" {warm[kind][label][n]:9.3f}" for n in INIT_ELEMENTS)
            print(f"   {NAMES[kind] + ', ' + label:<52}{row}")
    print(f"\n{number + 1}. First initialisation: a fresh process and extraction per sample "
          f"(median of {samples}), s: instantiate -> exit (of it exitInitializationMode)")
    print(f"   {'FMU, contact points':<52}" + "".join(f" {f'N = {n}':>17}"
                                                        for n in INIT_ELEMENTS))
    for kind in TIRES:
        for label in SPACINGS:
            cells = [first[kind][label][n] for n in INIT_ELEMENTS]
            row = "".join(f" {c['total_s']:7.3f} ({c['exit_s']:6.3f})" for c in cells)
            print(f"   {NAMES[kind] + ', ' + label:<52}{row}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=15, help="alternating rounds (15)")
    parser.add_argument("--steps", type=int, default=2000, help="steps per round (2000)")
    parser.add_argument("--init-repeats", type=int, default=3,
                        help="warm initialisations per case (3)")
    parser.add_argument("--init-samples", type=int, default=5,
                        help="fresh processes per first-initialisation case (5)")
    parser.add_argument("--init-only", action="store_true",
                        help="only the initialisations (2 and 3), not the steps")
    parser.add_argument("--record", metavar="JSON", help="also write the results there (the "
                        "docs quote docs/measured/bench_fmu.json; a full run only)")
    args = parser.parse_args(argv)
    if args.init_only and args.record:
        parser.error("--record takes a full run (the record holds the step costs too)")
    from record import load_average, write_record

    load_at_start = load_average()
    horizon = int(round(HORIZON_S / H))
    with tempfile.TemporaryDirectory(prefix="bench_fmu_") as folder:
        folder = Path(folder)
        paths = build_all(folder, floors=not args.init_only)
        fmus = {kind: Opened(path) for kind, path in paths.items()}
        if not args.init_only:
            cases = {}
            for regime, (speed, signal) in REGIMES.items():
                for kind in NAMES:
                    labels = SPACINGS if kind in TIRES else {"": None}
                    for label, spacing in labels.items():
                        parameters = {} if spacing is None else {
                            "contact_point_spacing": spacing}
                        cases[regime, kind, label] = Case(fmus[kind], speed, signal,
                                                          parameters, horizon)
            for case in cases.values():
                case.run(horizon)  # past the transient and into the delay line
            times = {key: [] for key in cases}
            for _ in range(args.rounds):
                for key, case in cases.items():
                    times[key].append(case.run(args.steps))
            for case in cases.values():
                case.close()
            costs = {key: statistics.median(values) for key, values in times.items()}
        scratch = folder / "first"
        scratch.mkdir()
        warm, first = measure_inits(paths, fmus, args.init_repeats, args.init_samples, scratch)

    number = 1
    if not args.init_only:
        print(f"1. Cost per communication step through fmpy, h = {H:g} s, N = 100 (median of "
              f"{args.rounds} alternating rounds of {args.steps} steps), µs")
        print(f"   {'regime, contact points':<50} {'(a)':>7} {'(b)':>7} {'(a)/(b)':>8} "
              f"{'(c)':>7} {'(d)':>7} {'(c)/(d)':>8}")
        rows = {}
        for regime in REGIMES:
            b, d = (1e6 * costs[regime, kind, ""] for kind in ("minimal", "trivial"))
            for label in SPACINGS:
                a, c = (1e6 * costs[regime, kind, label] for kind in TIRES)
                rows[f"{regime}, {label}"] = {NAMES["python"]: a, NAMES["minimal"]: b,
                                              NAMES["native"]: c, NAMES["trivial"]: d}
                print(f"   {regime + ', ' + label:<50} {a:7.2f} {b:7.2f} {a / b:8.2f} "
                      f"{c:7.2f} {d:7.2f} {c / d:8.2f}")
        for name in NAMES.values():
            print(f"   {name}")
        ratios = {row: {"python_over_minimal": v[NAMES["python"]] / v[NAMES["minimal"]],
                        "native_over_trivial": v[NAMES["native"]] / v[NAMES["trivial"]]}
                  for row, v in rows.items()}
        for label in SPACINGS:
            mine = [r for row, r in ratios.items() if row.endswith(label)]
            worst_python = max(r["python_over_minimal"] for r in mine)
            worst_native = max(r["native_over_trivial"] for r in mine)
            print(f"   {label}: worst (a)/(b) = {worst_python:.2f} "
                  f"({'meets' if worst_python <= 1.5 else 'MISSES'} the aim <= 1.5), worst "
                  f"(c)/(d) = {worst_native:.2f} "
                  f"({'meets' if worst_native <= 1.2 else 'MISSES'} the aim <= 1.2)")
        number = 2
    print_inits(warm, first, args.init_repeats, args.init_samples, number)
    if not args.init_only:
        print(f"\n{number + 2}. Real-time factor at 10 kHz (wall time / simulated time)")
        for row, values in rows.items():
            for kind in TIRES:
                factor = 1e-6 * values[NAMES[kind]] / H
                print(f"   {NAMES[kind][:3]} {row:<50} {factor:6.3f}  ({1 / factor:5.1f} x "
                      "faster than real time)")
    print(textwrap.dedent(f"""
        Python {sys.version.split()[0]}; TireModal's defaults otherwise (N = 100 for the steps).
        """).rstrip())
    if args.record:
        write_record(args.record, {
            "step_us": rows,
            "ratios": ratios,
            "init_s": {str(n): warm["python"][next(iter(SPACINGS))][n] for n in INIT_ELEMENTS},
            "init_repeats": args.init_repeats,
            "warm_init_s": {NAMES[kind]: {label: {str(n): v for n, v in by_n.items()}
                                          for label, by_n in warm[kind].items()}
                            for kind in TIRES},
            "first_init_s": {NAMES[kind]: {label: {str(n): v for n, v in by_n.items()}
                                           for label, by_n in first[kind].items()}
                             for kind in TIRES},
            "init_samples": args.init_samples,
        }, load_at_start)


if __name__ == "__main__":
    main()
