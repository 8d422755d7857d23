"""The native (C) FMU against its references, through fmpy, printed side by side in one run.

1. Initialisation (instantiate, set load and mesh, setupExperiment, enter and exit
   initialisation, which builds the model) against N = 100, 400, 800, 1600 (MAX_ELEMENTS): the
   native FMU against the Python FMU (TireModal.fmu).
2. Cost per communication step at h = 1e-4 s (setReal of the 4 inputs, doStep, getReal of the
   5 outputs) at N = 100: the native FMU against a trivial C FMU with the same interface whose
   doStep copies (benchmarks/trivial_fmu/trivial.c, built here), i.e. fmpy's own call cost; at
   rest and at 20 m/s, in contact (a small road undulation) and during lift-off (the road held
   5 cm below the tread).

Rounds of the cases alternate, so load on the machine hits all alike; medians side by side.
Targets: native initialisation at N = 100 well under 0.1 s; native step <= 1.2-1.5 x the
trivial FMU's. ``--json FILE`` writes the numbers that docs/native.md quotes.

    python benchmarks/bench_native.py [--rounds 15] [--steps 2000] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import shlex
import statistics
import subprocess
import sys
import tempfile
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
OUTPUTS = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length")
HERE = Path(__file__).parent


def trivial_fmu(folder: Path) -> Path:
    """The copying C FMU with the tire's value references 0-8."""
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


class Opened:
    def __init__(self, path: Path):
        self.description = read_model_description(str(path))
        self.folder = extract(str(path))
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}
        self.count = 0

    def instance(self) -> FMU2Slave:
        self.count += 1
        return FMU2Slave(guid=self.description.guid, unzipDirectory=self.folder,
                         modelIdentifier=self.description.coSimulation.modelIdentifier,
                         instanceName=f"bench{self.count}")


def initialise(fmu: Opened, parameters: dict) -> tuple[FMU2Slave, float]:
    started = time.perf_counter()
    slave = fmu.instance()
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for name, value in parameters.items():
        if name in fmu.vr:
            setter = slave.setInteger if isinstance(value, int) else slave.setReal
            setter([fmu.vr[name]], [value])
    slave.exitInitializationMode()
    return slave, time.perf_counter() - started


def loop_seconds(slave: FMU2Slave, fmu: Opened, signal, steps: int, t0: float) -> float:
    inputs = [fmu.vr[n] for n in INPUTS]
    outputs = [fmu.vr[n] for n in OUTPUTS]
    values = [signal(t0 + k * H) for k in range(steps)]
    set_real, do_step, get_real = slave.setReal, slave.doStep, slave.getReal
    started = time.perf_counter()
    for k in range(steps):
        set_real(inputs, values[k])
        do_step(t0 + k * H, H)
        get_real(outputs)
    return (time.perf_counter() - started) / steps


def in_contact(t: float) -> list[float]:
    w = 2 * math.pi * 10.0  # a 1 mm, 10 Hz road undulation
    return [0.0, 0.0, 1e-3 * math.sin(w * t), 1e-3 * w * math.cos(w * t)]


def lifted(t: float) -> list[float]:
    return [0.0, 0.0, -0.05, 0.0]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--json", type=Path, default=None, help="write the numbers here")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        native = Opened(build_native_fmu(tmp / "TireModalNative.fmu", platforms=("linux64",)))
        python = Opened(build_fmu(tmp / "python"))
        trivial = Opened(trivial_fmu(tmp / "trivial"))

        # 1. initialisation against N
        meshes = (100, 400, 800, 1600)
        init = {(kind, n): [] for kind in ("native", "python") for n in meshes}
        for _ in range(max(3, args.rounds // 3)):
            for n in meshes:
                for kind, fmu in (("native", native), ("python", python)):
                    slave, seconds = initialise(fmu, {"n_elements": n})
                    init[kind, n].append(seconds)
                    slave.terminate()
                    slave.freeInstance()

        # 2. cost per step
        cases = {}
        for speed in (0.0, 20.0):
            for regime, signal in (("contact", in_contact), ("lift-off", lifted)):
                tire, _ = initialise(native, {"speed": speed})
                copy, _ = initialise(trivial, {})
                warm = 2000  # past the transient and the road history's general path
                loop_seconds(tire, native, signal, warm, 0.0)
                loop_seconds(copy, trivial, signal, warm, 0.0)
                cases[speed, regime] = (tire, copy, signal, [], [], warm * H)
        for _ in range(args.rounds):
            for (speed, regime), (tire, copy, signal, a, b, t0) in cases.items():
                a.append(loop_seconds(tire, native, signal, args.steps, t0))
                b.append(loop_seconds(copy, trivial, signal, args.steps, t0 + 1.0))
                cases[speed, regime] = (tire, copy, signal, a, b, t0 + args.steps * H)

    median = statistics.median
    print(f"python {sys.version.split()[0]}, {platform.machine()}; command: python "
          f"{' '.join(shlex.quote(a) for a in sys.argv)}")
    print("\ninitialisation (instantiate .. fmi2ExitInitializationMode), median s:")
    print(f"{'N':>6} {'native':>10} {'Python FMU':>12} {'Python/native':>14}")
    result = {"initialisation_s": {}, "step_us": {}}
    for n in meshes:
        a, b = median(init["native", n]), median(init["python", n])
        print(f"{n:>6} {a:>10.4f} {b:>12.4f} {b / a:>14.1f}")
        result["initialisation_s"][str(n)] = {"native": a, "python_fmu": b}
    print(f"\nper step through fmpy (setReal 4, doStep, getReal 5), N = 100, median µs over "
          f"{args.rounds} rounds of {args.steps} steps:")
    print(f"{'speed':>6} {'regime':>9} {'native':>8} {'trivial C':>10} {'native/trivial':>15}")
    for (speed, regime), (tire, copy, _, a, b, _) in cases.items():
        x, y = 1e6 * median(a), 1e6 * median(b)
        print(f"{speed:>6g} {regime:>9} {x:>8.2f} {y:>10.2f} {x / y:>15.2f}")
        result["step_us"][f"{speed:g} m/s, {regime}"] = {"native": x, "trivial": y,
                                                          "ratio": x / y}
        for slave in (tire, copy):
            slave.terminate()
            slave.freeInstance()
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
