"""FMU benchmarks through fmpy, printed side by side in one run.

1. Cost per communication step (setReal inputs, doStep, getReal outputs) at h = 1e-4 s:
   (a) TireModal.fmu at default settings (N = 100, at rest): 4 inputs, 4 real outputs; the
       same plus getBoolean(in_contact); and, for reference, rolling at 20 m/s;
   (b) a minimal pythonfmu slave built here (one input, one output, do_step copies one to
       the other): the floor for any Python FMU;
   (c) the plain fmpy call overhead: the same three calls on a native C FMU compiled here
       from fmpy's FMI headers (one input, one output, a doStep that copies), skipped
       without a C compiler.
   The rounds of (a), (b) and (c) alternate, so load on the machine hits all of them alike.
   Aims: (a) <= 2 x (b) (issue 10), <= 1.3 x (b) (issue 13).
2. Initialisation time of TireModal (instantiate -> exitInitializationMode) at N = 100, 400.
3. Real-time factor at 10 kHz (step cost / 100 us) and its inverse.

    python benchmarks/bench_fmu.py [--rounds 40] [--steps 2000] [--init-repeats 3]
"""

from __future__ import annotations

import argparse
import inspect
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from tire_fmu.fmu.builder import build_fmu

H = 1e-4
ROLLING_SPEED = 20.0  # m/s: the road reaches the patch nodes through a delay line

MINIMAL_SLAVE = '''
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class BenchMinimal(Fmi2Slave):
    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.u = 0.0
        self.y = 0.0
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.y = self.u
        return True
'''

NATIVE_SOURCE = r'''
#include <stdlib.h>
#include "fmi2Functions.h"

typedef struct { fmi2Real u, y; } Instance;

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }
fmi2Component fmi2Instantiate(fmi2String n, fmi2Type t, fmi2String g, fmi2String r,
                              const fmi2CallbackFunctions* f, fmi2Boolean v, fmi2Boolean l)
{ return calloc(1, sizeof(Instance)); }
void fmi2FreeInstance(fmi2Component c) { free(c); }
fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean a, fmi2Real b, fmi2Real s,
                               fmi2Boolean d, fmi2Real e) { return fmi2OK; }
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { return fmi2OK; }
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real value[])
{ Instance* i = (Instance*)c; for (size_t k = 0; k < n; k++) if (vr[k] == 0) i->u = value[k];
  return fmi2OK; }
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       fmi2Real value[])
{ Instance* i = (Instance*)c; for (size_t k = 0; k < n; k++) value[k] = vr[k] ? i->y : i->u;
  return fmi2OK; }
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean p)
{ Instance* i = (Instance*)c; i->y = i->u; return fmi2OK; }
'''


class Stepper:
    """The three calls of a communication step on one initialised FMU instance; cases that
    share an instance share its ``clock`` (a one-item list: the next communication point)."""

    def __init__(self, slave: FMU2Slave, clock: list, inputs, values, outputs, booleans=()):
        self.slave, self.clock = slave, clock
        self.inputs, self.values = list(inputs), list(values)
        self.outputs, self.booleans = list(outputs), list(booleans)

    def run(self, steps: int) -> float:
        """Seconds per communication step over ``steps`` steps."""
        slave, inputs, values, outputs, booleans = (self.slave, self.inputs, self.values,
                                                    self.outputs, self.booleans)
        t = self.clock[0]
        started = time.perf_counter()
        for _ in range(steps):
            slave.setReal(inputs, values)
            slave.doStep(t, H)
            slave.getReal(outputs)
            if booleans:
                slave.getBoolean(booleans)
            t += H
        elapsed = time.perf_counter() - started
        self.clock[0] = t
        return elapsed / steps


def open_fmu(path: Path, name: str, start_values=None) -> tuple[FMU2Slave, dict]:
    description = read_model_description(str(path))
    slave = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(path)),
                      modelIdentifier=description.coSimulation.modelIdentifier,
                      instanceName=name)
    references = {v.name: v.valueReference for v in description.modelVariables}
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for variable, value in (start_values or {}).items():
        setter = slave.setInteger if isinstance(value, int) else slave.setReal
        setter([references[variable]], [value])
    slave.exitInitializationMode()
    return slave, references


def build_minimal(folder: Path) -> Path:
    from pythonfmu.builder import FmuBuilder

    script = folder / "bench_minimal_slave.py"
    script.write_text(MINIMAL_SLAVE)
    try:
        return Path(FmuBuilder.build_FMU(script, dest=folder))
    finally:
        sys.modules.pop(script.stem, None)
        while str(folder) in sys.path:
            sys.path.remove(str(folder))


def build_native(folder: Path) -> FMU2Slave | None:
    compiler = shutil.which(os.environ.get("CC", "cc"))
    if compiler is None:
        return None
    import fmpy

    source = folder / "native_minimal.c"
    source.write_text(NATIVE_SOURCE)
    # fmpy binds every FMI 2.0 function; the unused ones are stubs, compiled apart from
    # fmi2Functions.h, whose prototypes they do not follow
    implemented = set(re.findall(r"\b(fmi2\w+)\(", NATIVE_SOURCE))
    unused = sorted({name for name, _ in inspect.getmembers(FMU2Slave)
                     if name.startswith("fmi2")} - implemented)
    stubs = folder / "native_stubs.c"
    stubs.write_text("".join(f"int {name}(void) {{ return 3; }}\n" for name in unused))
    library = folder / "native_minimal.so"
    headers = Path(fmpy.__file__).parent / "c-code"
    subprocess.run([compiler, "-O2", "-shared", "-fPIC", f"-I{headers}", str(source),
                    str(stubs), "-o", str(library)], check=True)
    slave = FMU2Slave(guid="native", unzipDirectory=str(folder), modelIdentifier="native",
                      libraryPath=str(library), instanceName="native",
                      requireFunctions=False)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave


def step_costs(tire: Path, minimal: Path, native: FMU2Slave | None, rounds: int,
               steps: int) -> dict[str, float]:
    tire_slave, tire_vr = open_fmu(tire, "tire")
    rolling_slave, _ = open_fmu(tire, "rolling", {"speed": ROLLING_SPEED})
    inputs = [tire_vr[n] for n in ("rim_z", "rim_vz", "road_z", "road_vz")]
    outputs = [tire_vr[n] for n in ("rim_Fz", "rim_Fx", "contact_Fz", "deflection")]
    small = [1e-4, 0.0, 1e-4, 0.0]  # rim and road held 0.1 mm up: stays in contact
    minimal_slave, minimal_vr = open_fmu(minimal, "minimal")
    tire_clock = [0.0]
    cases = {
        "(a) TireModal": Stepper(tire_slave, tire_clock, inputs, small, outputs),
        "(a) + getBoolean": Stepper(tire_slave, tire_clock, inputs, small, outputs,
                                    [tire_vr["in_contact"]]),
        f"(a) at {ROLLING_SPEED:g} m/s": Stepper(rolling_slave, [0.0], inputs, small,
                                                outputs),
        "(b) minimal pythonfmu": Stepper(minimal_slave, [0.0], [minimal_vr["u"]], [1.0],
                                         [minimal_vr["y"]]),
    }
    if native is not None:
        cases["(c) native C (fmpy floor)"] = Stepper(native, [0.0], [0], [1.0], [1])
    times = {name: [] for name in cases}
    for case in cases.values():
        case.run(steps // 10)  # warm up
    for _ in range(rounds):
        for name, case in cases.items():
            times[name].append(case.run(steps))
    for slave in (tire_slave, rolling_slave, minimal_slave):
        slave.terminate()
        slave.freeInstance()
    return {name: statistics.median(values) for name, values in times.items()}


def init_time(tire: Path, n_elements: int, repeats: int) -> float:
    description = read_model_description(str(tire))
    folder = extract(str(tire))
    n_vr = next(v.valueReference for v in description.modelVariables
                if v.name == "n_elements")
    times = []
    for i in range(repeats):
        slave = FMU2Slave(guid=description.guid, unzipDirectory=folder,
                          modelIdentifier=description.coSimulation.modelIdentifier,
                          instanceName=f"init{i}")
        started = time.perf_counter()
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.setInteger([n_vr], [n_elements])
        slave.exitInitializationMode()
        times.append(time.perf_counter() - started)
        slave.terminate()
        slave.freeInstance()
    shutil.rmtree(folder, ignore_errors=True)
    return statistics.median(times)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=40, help="alternating rounds (40)")
    parser.add_argument("--steps", type=int, default=2000, help="steps per round (2000)")
    parser.add_argument("--init-repeats", type=int, default=3, help="initialisations (3)")
    parser.add_argument("--record", metavar="JSON", help="also write the results there (the "
                        "docs quote docs/measured/bench_fmu.json)")
    args = parser.parse_args(argv)
    from record import load_average, write_record

    load_at_start = load_average()
    with tempfile.TemporaryDirectory(prefix="bench_fmu_") as folder:
        folder = Path(folder)
        tire = build_fmu(folder / "tire")
        (folder / "minimal").mkdir()
        minimal = build_minimal(folder / "minimal")
        native = build_native(folder)
        costs = step_costs(tire, minimal, native, args.rounds, args.steps)
        inits = {n: init_time(tire, n, args.init_repeats) for n in (100, 400)}
        if native is not None:
            native.terminate()
            native.fmi2FreeInstance(native.component)  # no freeLibrary: ctypes owns the handle

    print(f"1. Cost per communication step through fmpy, h = {H:g} s "
          f"(median of {args.rounds} alternating rounds of {args.steps} steps)")
    floor = costs["(b) minimal pythonfmu"]
    for name, cost in costs.items():
        print(f"   {name:<28} {cost * 1e6:7.2f} us   {cost / floor:5.2f} x (b)")
    if native is None:
        print("   (c) skipped: no C compiler found")
    ratio = costs["(a) TireModal"] / floor
    verdict = "meets" if ratio <= 2.0 else "MISSES"
    print(f"   (a) / (b) = {ratio:.2f}: {verdict} the aim <= 2 (issue 10; issue 13 asks 1.3)")
    print("\n2. Initialisation, instantiate -> exitInitializationMode "
          f"(median of {args.init_repeats})")
    for n, seconds in inits.items():
        print(f"   N = {n:<4} {seconds:7.3f} s")
    print("\n3. Real-time factor at 10 kHz (wall time / simulated time)")
    for name in ("(a) TireModal", "(a) + getBoolean", f"(a) at {ROLLING_SPEED:g} m/s"):
        factor = costs[name] / H
        print(f"   {name:<28} {factor:6.3f}  ({1 / factor:5.1f} x faster than real time)")
    print(textwrap.dedent(f"""
        Python {sys.version.split()[0]}; (a) runs TireModal's defaults (N = 100, at rest).
        """).rstrip())
    if args.record:
        write_record(args.record, {
            "step_us": {name: cost * 1e6 for name, cost in costs.items()},
            "init_s": {str(n): seconds for n, seconds in inits.items()},
            "init_repeats": args.init_repeats,
        }, load_at_start)


if __name__ == "__main__":
    main()
