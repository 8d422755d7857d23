"""Random FMI call sequences against a tire FMU through fmpy: the fuzz driver.

Run by tests/test_fmu_fuzz.py in a subprocess (so that a crash is a failed test, not a dead
test run), or by hand for a longer run:

    python3 tests/fuzz_fmu.py dist/TireModal.fmu --profile long

A hypothesis state machine instantiates the FMU, mostly initialises it (with good or bad
parameters), then calls at random: setupExperiment, enter and exit initialisation, set
parameters and inputs, doStep (good and bad communication points and step sizes), get
outputs, get/set/serialize/deserialize the FMU state (with bytes cut, flipped, extended or
made up), terminate and reset. Values come from NaN, infinities, huge, negative, denormal and
ordinary numbers. After every call it checks:

- the status is fmi2OK or fmi2Error: never Fatal (an exception escaped), nor Discard;
- no output comes with status OK unless it is finite;
- a call that returns an error logged a message at status error saying why, with the
  variable and the value where the call gave one;
- a refused call changed nothing: every variable reads the same, and a probe step from the
  state before and from the state after gives the same outputs.

It knows the FMU only through its model description and FMI, so any tire FMU with these
variables can be driven (see FUZZ_TARGETS in tests/test_fmu_fuzz.py). Before the random
sequences it replays the ones that failed before (REPLAYS), with the same checks. Exit status
0: no failure found.
"""

from __future__ import annotations

import argparse
import math
import random
import sys
from ctypes import byref

import hypothesis.strategies as st
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2LastSuccessfulTime,
)
from fmpy.logging import addLoggerProxy
from hypothesis import HealthCheck, Phase, Verbosity, settings
from hypothesis.stateful import (
    Bundle,
    RuleBasedStateMachine,
    consumes,
    initialize,
    invariant,
    precondition,
    rule,
)

from tire_fmu.core.parameters import MAX_ELEMENTS

OK, ERROR = 0, 3
INPUTS = ("rim_z", "rim_vz", "road_z", "road_vz")
OUTPUTS = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection")

SPECIAL = [0.0, -0.0, 1e-3, -1e-3, 1.0, -1.0, 1e6, -1e6, 1e300, -1e300, 5e-324, -5e-324,
           2.2250738585072014e-308, math.nan, math.inf, -math.inf]
special = st.sampled_from(SPECIAL)
anything = st.one_of(special, st.floats(allow_nan=True, allow_infinity=True))
small = st.floats(-5e-3, 5e-3)
inputs = st.one_of(small, small, small, anything)  # mostly ordinary, so that runs go on
steps = st.one_of(st.sampled_from([1e-4, 1e-3, 1e-3, 2.5e-3]), special,
                  st.floats(1e-6, 1e-2))
good_meshes = st.sampled_from([8, 12, 16, 24])
# refused meshes: the one past the limit follows it (a fixed 1001 became a valid mesh that takes
# seconds to build when the limit rose, and timed the CI profile out)
meshes = st.one_of(good_meshes, good_meshes, good_meshes,
                   st.sampled_from([0, -1, 7, MAX_ELEMENTS + 1, 2**31 - 1]))
start_times = st.one_of(st.just(0.0), st.just(0.0), st.just(1.5), special)
bad_parameters = st.one_of(st.just([]), st.just([]), st.lists(
    st.tuples(st.sampled_from(["load", "speed", "R", "m_s", "k_cw", "beta", "f_max", "n_modes"]),
              anything), min_size=1, max_size=2))

# CI: no shrinking (it can take minutes); the failing calls are printed as found
settings.register_profile("ci", max_examples=100, stateful_step_count=50, deadline=None,
                          database=None, print_blob=True,
                          phases=[Phase.explicit, Phase.reuse, Phase.generate],
                          suppress_health_check=list(HealthCheck))
settings.register_profile("long", max_examples=400, stateful_step_count=60, deadline=None,
                          print_blob=True, suppress_health_check=list(HealthCheck))
settings.register_profile("verbose", parent=settings.get_profile("ci"),
                          verbosity=Verbosity.verbose)

PATH = ""
CALLS: dict[str, list[int]] = {}  # what -> [calls, refused]: printed at the end of a run
CASES = [0]  # call sequences run (one FMU instance each), replays included


def value_forms(value) -> list[str]:
    """How a message may show ``value``: repr, or the shortest exact form."""
    forms = [repr(value)]
    if isinstance(value, float) and math.isfinite(value):
        forms.append(f"{value:g}")
        if float(forms[-1]) != value:
            forms.pop()
    return forms


class FmuMachine(RuleBasedStateMachine):
    states = Bundle("states")
    blobs = Bundle("blobs")

    def __init__(self):
        super().__init__()
        CASES[0] += 1
        description = read_model_description(PATH)
        self.variables = {v.name: v for v in description.modelVariables}
        self.parameters = [v for v in description.modelVariables
                           if v.causality == "parameter"]
        self.log: list[tuple[int, str]] = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda env, name, status, category, message: self.log.append(
                (status, message.decode("utf-8", "replace"))))
        addLoggerProxy(byref(self.callbacks))  # printf, as a C host formats the messages
        self.fmu = FMU2Slave(guid=description.guid, unzipDirectory=FOLDER,
                             modelIdentifier=description.coSimulation.modelIdentifier,
                             instanceName="fuzz")
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=True)
        self.time = None  # the communication point, while the FMU runs
        self.start_time = 0.0
        # where the FMU is in FMI's state machine: a refusal of a call that is out of order
        # need not name a value
        self.phase = "instantiated"
        self.inputs = dict.fromkeys(INPUTS, 0.0)
        self.owned = []  # FMU states to free at the end

    # -- calling and checking ------------------------------------------------------------
    def call(self, what, function, *args, named=()):
        """Call; check the status, the message of a refusal, and that a refusal changed
        nothing. ``named``: (name, value) pairs a refusal's message may name."""
        before = self.observe() if what != "observe" else None
        state_before = self.state_or_none()
        mark = len(self.log)
        status, result = OK, None
        try:
            result = function(*args)
        except FMICallException as error:
            status = error.status
        said = self.log[mark:]
        counts = CALLS.setdefault(what, [0, 0])
        counts[0] += 1
        counts[1] += status != OK
        assert status in (OK, ERROR), f"{what}: status {status}; it logged {said}"
        if status == ERROR:
            errors = [m for s, m in said if s >= ERROR]
            assert errors, f"{what} returned fmi2Error and logged no error: {said}"
            if named:
                assert any(name in m and any(form in m for form in value_forms(value))
                           for m in errors for name, value in named), \
                    f"{what}: no message names one of {named}: {errors}"
            after = self.observe()
            assert same(before, after), f"{what} was refused but changed {before} -> {after}"
            self.probe_unchanged(state_before, what)
        if state_before is not None:
            self.fmu.freeFMUstate(state_before)
        return status, result

    def observe(self) -> dict:
        """Every variable's value (or the status of the read), and the last successful
        time; no OK read may give a non-finite output."""
        seen = {}
        for kind, getter in (("Real", self.fmu.getReal), ("Integer", self.fmu.getInteger),
                             ("Boolean", self.fmu.getBoolean)):
            vrs = [v.valueReference for v in self.variables.values() if v.type == kind]
            try:
                seen[kind] = list(getter(vrs))
            except FMICallException as error:
                seen[kind] = f"status {error.status}"
        if isinstance(seen["Real"], list):
            names = [v.name for v in self.variables.values() if v.type == "Real"]
            for name, value in zip(names, seen["Real"]):
                if name in OUTPUTS:
                    assert math.isfinite(value), f"getReal gave {name} = {value} with OK"
        try:  # the native FMU answers it only once a step can have succeeded
            seen["time"] = self.fmu.getRealStatus(fmi2LastSuccessfulTime)
        except FMICallException as error:
            seen["time"] = f"status {error.status}"
        return seen

    def state_or_none(self):
        try:
            return self.fmu.getFMUstate()
        except FMICallException as error:
            raise AssertionError(f"fmi2GetFMUstate failed with status {error.status}: "
                                 f"{self.log[-3:]}") from error

    def probe_unchanged(self, state_before, what):
        """The same step from the state before a refused call and from the one after it."""
        if state_before is None or self.time is None:
            return
        after = self.fmu.getFMUstate()
        outcomes = []
        for state in (state_before, after):
            self.fmu.setFMUstate(state)
            outcomes.append(self.probe_step())
        self.fmu.setFMUstate(after)
        self.fmu.freeFMUstate(after)
        assert same(*outcomes), f"{what} was refused but a step after it differs: {outcomes}"

    def probe_step(self):
        vrs = [self.variables[n].valueReference for n in INPUTS]
        try:
            self.fmu.setReal(vrs, [1e-4, 0.0, 0.0, 0.0])
            self.fmu.doStep(self.time, 1e-3)
            return self.fmu.getReal([self.variables[n].valueReference for n in OUTPUTS])
        except FMICallException as error:
            return f"status {error.status}"

    def set_values(self, what, pairs):
        by_type = {}
        for name, value in pairs:
            by_type.setdefault(self.variables[name].type, []).append((name, value))
        setters = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
                   "Boolean": self.fmu.setBoolean}
        status = OK
        for kind, items in by_type.items():
            vrs = [self.variables[name].valueReference for name, _ in items]
            allowed = self.phase in ("instantiated", "initialisation", "running")
            status = max(status, self.call(what, setters[kind], vrs, [v for _, v in items],
                                           named=tuple(items) if allowed else ())[0])
        return status

    # -- the run ---------------------------------------------------------------------------
    @initialize(start=start_times, mesh=meshes, bad=bad_parameters,
                go=st.sampled_from(["run", "run", "run", "run", "setup", "nothing"]))
    def begin(self, start, mesh, bad, go):
        if go == "nothing":
            return
        self.setup_experiment(start)
        if go == "setup":
            return
        self.enter_initialization()
        self.set_values("set parameters", [("n_elements", mesh)] + [
            (n, int(v) if self.variables[n].type == "Integer" and math.isfinite(v)
             and abs(v) < 2**31 else (v if self.variables[n].type == "Real" else 0))
            for n, v in bad])
        self.exit_initialization()

    @rule(values=st.lists(inputs, min_size=4, max_size=4))
    def set_inputs(self, values):
        if self.set_values("set inputs", list(zip(INPUTS, values))) == OK:
            self.inputs = dict(zip(INPUTS, values))

    @rule(h=steps, offset=st.sampled_from([0.0] * 6 + [1e-15, 1e-6, -1e-3, math.nan, math.inf]))
    def do_step(self, h, offset):
        t = (self.time if self.time is not None else self.start_time) + offset
        named = [("t", t), ("h", h)] + [(n, v) for n, v in self.inputs.items()
                                        if not (math.isfinite(v) and abs(v) <= 1e6)]
        status, _ = self.call("doStep", self.fmu.doStep, t, h,
                              named=named if self.phase == "running" else ())
        if status == OK:
            self.time = t + h

    @rule(n=st.integers(1, 20), h=st.sampled_from([1e-4, 1e-3]), seed=st.integers(0, 99))
    def run_steps(self, n, h, seed):
        """A stretch of ordinary steps with small random inputs, from wherever it is."""
        rng = random.Random(seed)
        vrs = [self.variables[name].valueReference for name in INPUTS]
        for _ in range(n):
            values = [rng.uniform(-2e-3, 2e-3) for _ in INPUTS]
            if self.call("set inputs", self.fmu.setReal, vrs, values)[0] == OK:
                self.inputs = dict(zip(INPUTS, values))
            if self.time is None or self.call("doStep", self.fmu.doStep, self.time,
                                              h)[0] != OK:
                return
            self.time += h
            self.observe()

    @rule()
    def get_outputs(self):
        self.call("observe", self.observe)

    @rule(name=st.sampled_from(["load", "speed", "n_elements", "R", "static_correction"]),
          value=anything)
    def set_parameter(self, name, value):
        kind = self.variables[name].type
        if kind == "Integer":
            value = int(value) if math.isfinite(value) and abs(value) < 2**31 else 0
            if name == "n_elements" and 24 < value <= MAX_ELEMENTS:
                value = 24  # valid meshes this fine take seconds to build: not what is fuzzed
        elif kind == "Boolean":
            value = bool(value == value and value)
        self.set_values("set a parameter", [(name, value)])

    @rule(start=start_times)
    def setup_experiment(self, start):
        named = (("startTime", start),) if self.phase == "instantiated" else ()
        if self.call("setupExperiment", self.fmu.setupExperiment, None, start,
                     named=named)[0] == OK:
            self.start_time = start

    @rule()
    def enter_initialization(self):
        if self.call("enterInitializationMode", self.fmu.enterInitializationMode)[0] == OK:
            self.phase = "initialisation"

    @rule()
    def exit_initialization(self):
        status = self.call("exitInitializationMode", self.fmu.exitInitializationMode)[0]
        if status == OK:
            self.time, self.phase = self.start_time, "running"
        elif self.phase == "initialisation":  # refused parameters: the error state
            self.phase = "error"

    @rule()
    def terminate(self):
        if self.call("terminate", self.fmu.terminate)[0] == OK:
            self.time, self.phase = None, "terminated"

    @rule()
    def reset(self):
        if self.call("reset", self.fmu.reset)[0] == OK:
            self.time, self.start_time, self.phase = None, 0.0, "instantiated"
            self.inputs = dict.fromkeys(INPUTS, 0.0)

    @rule(target=states)
    def get_state(self):
        status, state = self.call("getFMUstate", self.fmu.getFMUstate)
        assert status == OK
        self.owned.append(state)
        return (state, self.time, self.start_time, dict(self.inputs), self.phase)

    @rule(saved=states)
    def set_state(self, saved):
        state, *then = saved
        if self.call("setFMUstate", self.fmu.setFMUstate, state)[0] == OK:
            self.adopt(then)

    def adopt(self, then):
        time, start, inputs_then, phase = then
        self.time, self.start_time, self.inputs, self.phase = time, start, dict(inputs_then), \
            phase

    @rule(target=blobs, saved=states)
    def serialize(self, saved):
        status, data = self.call("serializeFMUstate", self.fmu.serializeFMUstate, saved[0])
        assert status == OK
        return (bytes(data), *saved[1:])

    @rule(blob=blobs, how=st.sampled_from(["as is", "flip", "cut", "append", "garbage",
                                           "empty", "printf"]), where=st.integers(0, 10**6),
          seed=st.integers(0, 2**32 - 1))
    def deserialize_and_set(self, blob, how, where, seed):
        data, *then = blob
        rng = random.Random(seed)
        if how == "flip" and data:
            i = where % len(data)
            data = data[:i] + bytes([data[i] ^ (1 << rng.randrange(8))]) + data[i + 1:]
        elif how == "cut":
            data = data[:where % max(len(data), 1)]
        elif how == "append":
            data = data + bytes(rng.randrange(256) for _ in range(1 + where % 16))
        elif how == "garbage":
            data = bytes(rng.randrange(256) for _ in range(where % 4096))
        elif how == "empty":
            data = b""
        elif how == "printf":
            data = b"%s%n%x" * (1 + where % 8) + data
        status, state = self.call("deSerializeFMUstate", self.fmu.deSerializeFMUstate, data)
        if status != OK:
            return
        self.owned.append(state)
        status, _ = self.call("setFMUstate", self.fmu.setFMUstate, state)
        if how != "as is":
            assert status == ERROR, f"setFMUstate accepted bytes that were changed ({how})"
        else:
            assert status == OK, f"setFMUstate refused a state it serialized: {self.log[-2:]}"
            self.adopt(then)

    @rule(saved=consumes(states))
    def free_state(self, saved):
        self.owned.remove(saved[0])
        self.call("freeFMUstate", self.fmu.freeFMUstate, saved[0])

    @precondition(lambda self: self.time is not None)
    @invariant()
    def outputs_are_finite_when_read(self):
        self.observe()

    def teardown(self):
        for state in self.owned:
            self.fmu.freeFMUstate(state)
        try:
            self.fmu.terminate()
        except FMICallException:
            pass
        self.fmu.freeInstance()


#: Call sequences that failed, found by this fuzz: replayed, rule by rule with the same checks,
#: before every run (so CI covers them whatever hypothesis draws). Each: why it failed, calls.
REPLAYS = {
    "outputs read after inputs that lift the tread off, then a refused input: the native FMU "
    "refused to restore the state it had just taken (its in-contact event flag was compared "
    "with the outputs)": [
        ("begin", {"start": 0.0, "mesh": 16, "bad": [], "go": "run"}),
        ("set_inputs", {"values": [0.0, 0.0, -0.01, 0.0]}),
        ("get_outputs", {}),
        ("set_inputs", {"values": [0.0, 0.0, 1e6, 0.0]}),
    ],
    "no ring mode kept (f_max = 1e-3 Hz, below the lowest): after 8 steps on one active set, "
    "BLAS refused the fast step's products on the empty modal state (the Python FMU went to "
    "its error state)": [
        ("begin", {"start": 0.0, "mesh": 16, "bad": [("load", 0.0), ("f_max", 1e-3)],
                   "go": "run"}),
        ("run_steps", {"n": 11, "h": 1e-4, "seed": 3}),
        ("get_outputs", {}),
    ],
    "a step of 5e-324 s on a ring truncated with static correction: the dropped modes' rate "
    "term E/h overflowed, the outputs were not finite and both FMUs went to their error state": [
        ("begin", {"start": 0.0, "mesh": 16, "bad": [("f_max", 150.0)], "go": "run"}),
        ("do_step", {"h": 5e-324, "offset": 0.0}),
        ("run_steps", {"n": 3, "h": 1e-4, "seed": 0}),
        ("get_outputs", {}),
    ],
}


def replay(calls) -> None:
    """The calls on a fresh machine, checking as the fuzz does after every call."""
    machine = FmuMachine()
    try:
        for rule, arguments in calls:
            getattr(machine, rule)(**arguments)
            if machine.time is not None:
                machine.outputs_are_finite_when_read()
    finally:
        machine.teardown()


def same(a, b) -> bool:
    """Equal, with nan equal to nan."""
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(map(same, a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    return a == b


def main() -> int:
    global PATH, FOLDER
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fmu")
    parser.add_argument("--profile", default="ci", choices=["ci", "long", "verbose"])
    args = parser.parse_args()
    PATH, FOLDER = args.fmu, str(extract(args.fmu))
    # first: a machine made for a replay fixes FmuMachine.TestCase's settings (hypothesis
    # caches them), which then run with hypothesis's defaults instead of the profile
    settings.load_profile(args.profile)
    for why, calls in REPLAYS.items():
        print(f"replaying: {why}", flush=True)
        replay(calls)
    test = FmuMachine.TestCase()
    assert test.settings.max_examples == settings.default.max_examples, test.settings
    test.runTest()
    print(f"cases: {CASES[0]} call sequences ({len(REPLAYS)} replayed)")
    print("calls (refused):", ", ".join(f"{what} {n} ({refused})"
                                        for what, (n, refused) in sorted(CALLS.items())))
    print("no failure found")
    return 0


FOLDER = ""

if __name__ == "__main__":
    sys.exit(main())
