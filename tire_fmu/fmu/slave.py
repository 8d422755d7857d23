"""``TireModal``: the ring tire as a pythonfmu co-simulation slave.

A thin adapter: parameters are FMI variables; when initialisation ends they go through the
core's validation and :func:`~tire_fmu.core.contact_dynamics.build_contact_model` (the static
footprint for the load, the free ring's modes for the speed); ``do_step`` hands the four inputs
to :class:`~tire_fmu.core.contact_dynamics.ContactSimulator`. No physics and no parameter
ranges live here.

How failures surface (docs/fmu.md has the table):

- Every call is checked against the FMI 2.0 co-simulation state machine (:data:`ALLOWED`), and
  every value against what it may be. A refused call logs one message at status error that
  names the call and the variable and value it refuses, and changes nothing.
- The FMU's Linux binary (``pythonfmu_guard.c``, in front of pythonfmu's wrapper) returns
  fmi2Error for a call during which the slave logged an error. pythonfmu's own wrapper (the
  win64 binary) cannot: there only a refused ``do_step`` shows, as fmi2Discard.
- Nothing raises: a Python exception that escapes becomes fmi2Fatal, and pythonfmu's wrapper
  then releases the Python instance while keeping its pointer. Every entry point catches.
- Messages are printf formats for the host (pythonfmu passes them as the format argument):
  :func:`fmi_message` doubles ``%`` and FMI's escape ``#``. The slave never logs in
  ``__init__``: pythonfmu delivers messages after each call, except after a reset's
  constructor, and would deliver those to a freed logger when the instance is freed next.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
import warnings
from dataclasses import dataclass

from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status

import tire_fmu
from tire_fmu.core import clock
from tire_fmu.core.contact_dynamics import (
    ContactSettings,
    ContactSimulator,
    ContactState,
    StateError,
    StepError,
    build_contact_model,
)
from tire_fmu.core.free_ring import RingTruncation
from tire_fmu.core.parameters import TIRE_FIELDS, ParameterError, validate, value_text
from tire_fmu.fmu.interface import (
    BAKED_PARAMETERS_FILE,
    FMU_NAMES,
    FMU_UNSET,
    IN_CONTACT,
    INPUTS,
    MAX_DELAY_STEPS,
    MAX_HISTORY_SAMPLES,
    MAX_STEP_S,
    OUTPUTS,
    TIME_ABS_TOLERANCE_S,
    TIME_REL_TOLERANCE,
    FmuVariable,
    fmu_variables,
)
from tire_fmu.fmu.spec import MESSAGES, fmu_message

#: pythonfmu's variable class for each FMI type of the shared table
_KINDS = {"Real": Real, "Integer": Integer, "Boolean": Boolean}
#: The variables' names, types and causalities (start values differ only by the tire data an
#: FMU was built with, which the serialized states do not depend on).
_TABLE = fmu_variables()


def fmi_message(text: str) -> str:
    """``text`` as an FMI log message: a printf format (``%`` doubled) with FMI's variable
    reference escape ``#`` doubled, so that the host shows exactly ``text``."""
    return text.replace("%", "%%").replace("#", "##")


class Phase:
    """Where the slave is in the FMI 2.0 co-simulation state machine."""

    INSTANTIATED = "instantiated"
    INITIALISING = "initialisation mode"
    RUNNING = "running"
    TERMINATED = "terminated"
    ERROR = "error"  # the parameters were refused, or a step failed unexpectedly

    ALL = (INSTANTIATED, INITIALISING, RUNNING, TERMINATED, ERROR)


#: The calls each phase allows (FMI 2.0, section 4.3); getters and the FMU state functions
#: are allowed in every phase. Which variable a set may change is decided per variable.
ALLOWED = {
    "fmi2SetupExperiment": {Phase.INSTANTIATED},
    "fmi2EnterInitializationMode": {Phase.INSTANTIATED},
    "fmi2ExitInitializationMode": {Phase.INITIALISING},
    "fmi2DoStep": {Phase.RUNNING},
    "fmi2Terminate": {Phase.RUNNING},
    "fmi2SetReal": {Phase.INSTANTIATED, Phase.INITIALISING, Phase.RUNNING},
    "fmi2SetInteger": {Phase.INSTANTIATED, Phase.INITIALISING, Phase.RUNNING},
    "fmi2SetBoolean": {Phase.INSTANTIATED, Phase.INITIALISING, Phase.RUNNING},
}

#: What each phase is, for the message of a call it does not allow.
_PHASE_TEXT = {
    Phase.INSTANTIATED: "instantiated (call fmi2SetupExperiment and "
                        "fmi2EnterInitializationMode first)",
    Phase.INITIALISING: "in initialisation mode (call fmi2ExitInitializationMode first)",
    Phase.RUNNING: "running (initialisation ended; fmi2Reset starts over)",
    Phase.TERMINATED: "terminated (fmi2Reset starts over)",
    Phase.ERROR: "in the error state",
}

_STATE_MAGIC = b"tire_fmu.fmu-state/2"
_DIGEST_HEX = 64  # sha256
_MAX_STATE_BYTES = 1 << 30


@dataclass(frozen=True, eq=False)
class _Snapshot:
    """An FMU state: every variable's value, the phase, the simulator's state and flags."""

    values: tuple
    phase: str
    why_not_running: str
    start_time: float
    simulator: ContactState | None
    contact_warning_armed: bool
    stale: bool


@dataclass(frozen=True)
class _InvalidState:
    """What deserialising bad bytes gives: setting it is refused with ``reason``."""

    reason: str


class TireModal(Fmi2Slave):
    """In-plane modal ring tire (GL073A defaults): rim and road motion in, rim force out."""

    author = "tire_fmu contributors"
    description = ("Open in-plane modal ring tire (0-300 Hz): reduced modal model built at "
                   "initialisation for the load and speed; inputs are deviations from static "
                   "equilibrium, forces are totals. Needs Python with numpy and scipy.")
    version = tire_fmu.__version__
    license = "MIT"
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=1e-4)

    def __init__(self, **kwargs):
        # Cheap on purpose: pythonfmu instantiates the slave at build time and on every reset.
        super().__init__(**kwargs)
        self._table = fmu_variables(parameter_values=_baked_parameter_values(self.resources))
        self._values: list = [v.start for v in self._table]
        self._index = {v.name: vr for vr, v in enumerate(self._table)}
        self._parameter_vrs = [vr for vr, v in enumerate(self._table)
                               if v.causality == "parameter"]
        self._input_vrs = list(range(INPUTS.start, INPUTS.stop))
        self._output_vrs = list(range(OUTPUTS.start, OUTPUTS.stop))
        self._phase = Phase.INSTANTIATED
        self._why_not_running = _PHASE_TEXT[Phase.INSTANTIATED]
        self._start_time = 0.0
        self._simulator: ContactSimulator | None = None
        self._built_for: tuple | None = None  # parameter values the simulator was built with
        self._raw_step = None  # the kernel's hot path: (function, handle, inputs, report)
        self._now = math.nan  # the simulator's time, as its last step reported it
        self._checked_h = math.nan  # the last step size found good for this simulator
        self._contact_warning_armed = True  # the zone-edge warning, logged once per episode
        # Inputs set since the outputs were last computed: the next read recomputes the
        # forces at the current point with them (see ContactSimulator.outputs_with).
        self._stale = False
        for vr, v in enumerate(self._table):
            self._register(vr, v)

    def _register(self, vr: int, v: FmuVariable) -> None:
        kwargs = dict(causality=Fmi2Causality[v.causality], description=v.description,
                      variability=Fmi2Variability[v.variability],
                      getter=lambda: self._values[vr], setter=lambda value: None)
        if v.causality == "parameter":
            kwargs.update(initial=Fmi2Initial.exact)
        elif v.causality == "output":  # computed: no start value, listed as initial unknowns
            kwargs.update(initial=Fmi2Initial.calculated)
        # units go into the model description at build time, from the same table
        self.register_variable(_KINDS[v.type](v.name, **kwargs))

    # -- messages ----------------------------------------------------------------------------
    def log(self, msg: str, status: Fmi2Status = Fmi2Status.ok, category=None, debug=None):
        super().log(fmi_message(msg), status, category)

    def _refuse(self, call: str, why: str) -> bool:
        """Log that ``call`` was refused and why (status error); nothing was changed."""
        self.log(f"{call} refused: {why}; nothing changed", Fmi2Status.error)
        return False

    def _allowed(self, call: str) -> bool:
        if self._phase in ALLOWED[call]:
            return True
        why = ((self._why_not_running or f"the FMU is {_PHASE_TEXT[Phase.ERROR]}; reset it or "
                "set an FMU state") if self._phase == Phase.ERROR
               else f"the FMU is {_PHASE_TEXT[self._phase]}")
        return self._refuse(call, why)

    def _fail(self, what: str, error: Exception) -> None:
        """An unexpected failure: the FMU goes to the error state (reset or set a state)."""
        self._phase = Phase.ERROR
        self._why_not_running = (f"the FMU is in the error state: {what} failed "
                                 f"({type(error).__name__}: {error}); reset it or set an FMU "
                                 "state")
        self.log(self._why_not_running, Fmi2Status.error)

    def _warn_zone_edge(self, at_time: float) -> None:
        self._contact_warning_armed = False
        self.log(f"t = {at_time:.9g} s: the footprint reached the end of the contact zone, so "
                 "road forces beyond it are missing; raise contact_zone_length (logged once "
                 "until the footprint is back inside)", Fmi2Status.warning)

    # -- lifecycle ---------------------------------------------------------------------------
    def setup_experiment(self, start_time: float, stop_time: float | None = None,
                         tolerance: float | None = None) -> None:
        call = "fmi2SetupExperiment"
        if not self._allowed(call):
            return
        if not math.isfinite(start_time):
            self._refuse(call, f"startTime = {start_time!r} s: must be finite")
        elif not clock.resolves(start_time, MAX_STEP_S):
            self._refuse(call, MESSAGES["START_UNRESOLVED"] % (
                repr(float(start_time)), clock.resolved_until(MAX_STEP_S) - MAX_STEP_S,
                MAX_STEP_S))
        elif stop_time is not None and not (math.isfinite(stop_time) and stop_time >= start_time):
            self._refuse(call, f"stopTime = {stop_time!r} s: must be finite and >= startTime "
                         f"= {start_time!r} s")
        elif tolerance is not None and not (math.isfinite(tolerance) and tolerance > 0.0):
            self._refuse(call, f"tolerance = {tolerance!r}: must be finite and > 0")
        else:
            self._start_time = float(start_time)

    def enter_initialization_mode(self) -> None:
        if self._allowed("fmi2EnterInitializationMode"):
            self._phase = Phase.INITIALISING
            self._why_not_running = _PHASE_TEXT[Phase.INITIALISING]

    def exit_initialization_mode(self) -> None:
        if not self._allowed("fmi2ExitInitializationMode"):
            return
        try:
            self._initialise()
        except Exception as error:  # an escaping exception would be fmi2Fatal (module doc)
            self._fail("building the model", error)

    def terminate(self) -> None:
        if self._allowed("fmi2Terminate"):
            self._phase = Phase.TERMINATED
            self._why_not_running = f"the FMU is {_PHASE_TEXT[Phase.TERMINATED]}"

    def do_step(self, current_time: float, step_size: float) -> bool:
        if self._phase != Phase.RUNNING:
            return self._allowed("fmi2DoStep")
        now = self._now
        values = self._values
        if current_time != now:
            # also refuses a non-finite t: every comparison with nan is false
            if not abs(current_time - now) <= max(TIME_ABS_TOLERANCE_S,
                                                  TIME_REL_TOLERANCE * abs(now)):
                return self._refuse_step(
                    current_time, step_size,
                    f"t = {current_time!r} s: must be the last communication point t = {now!r} "
                    "s (roll back with fmi2SetFMUstate to step from an earlier time)")
        if step_size != self._checked_h:  # false for nan too: checked, and refused
            problem = self._step_size_problem(step_size)
            if problem:
                return self._refuse_step(current_time, step_size, problem)
            self._checked_h = step_size
        # one call of the step kernel (the inputs are value references 0-3, INPUTS); it
        # checks them and the clock itself, and its own clock goes on: the host's t, within
        # rounding of it, would bring its clock's rounding into the road history (core.clock)
        step, handle, kernel_inputs, report = self._raw_step
        kernel_inputs[0], kernel_inputs[1], kernel_inputs[2], kernel_inputs[3] = values[:4]
        try:
            status = step(handle, step_size, kernel_inputs, report)
        except Exception as error:  # an escaping exception would be fmi2Fatal (numpy kernel)
            self._fail(f"the step from t = {current_time!r} s", error)
            return False
        if status:
            return self._step_refused(status, current_time, step_size)
        outputs = report[0:6]
        if not math.isfinite(outputs[0] + outputs[1] + outputs[2] + outputs[3] + outputs[5]):
            self._fail(f"the step from t = {current_time!r} s",
                       ArithmeticError(f"non-finite outputs {outputs}"))
            return False
        values[OUTPUTS] = outputs
        self._now = report[6]
        self._stale = False
        values[IN_CONTACT] = outputs[2] > 0.0
        # contact loss is physics (logged by nobody, in_contact says it); a footprint at the
        # end of the zone is the model's limit, and warns
        if report[7]:
            if self._contact_warning_armed:
                self._warn_zone_edge(self._now)
        elif not self._contact_warning_armed:
            self._contact_warning_armed = True
        return True

    def _step_refused(self, status: int, t: float, h: float) -> bool:
        """A step the kernel did not take: refused for a reason the core names (nothing
        changed), or its memory ran out (the FMU's error state)."""
        if status == -3:
            try:
                self._simulator._check(h, tuple(self._values[:4]))
            except StepError as error:
                return self._refuse_step(t, h, str(error))
            status = "refused with no reason the core finds"
        self._fail(f"the step from t = {t!r} s", MemoryError(f"step kernel status {status}"))
        return False

    def _step_size_problem(self, h: float) -> str | None:
        if not 0.0 < h <= MAX_STEP_S:  # false for nan too
            return f"step size h = {h!r} s: must be in (0, {MAX_STEP_S:g}] s"
        reach = self._simulator.contact.windows.horizon_s
        if not reach / h <= MAX_DELAY_STEPS:
            return (f"step size h = {h!r} s: must be at least {reach / MAX_DELAY_STEPS:.3g} s "
                    f"at this speed: the road reaches the contact zone's last node "
                    f"{reach:.3g} s after its front, and the FMU keeps at most "
                    f"{MAX_DELAY_STEPS} steps of its history")
        return None

    def _refuse_step(self, t: float, h: float, why: str) -> bool:
        return self._refuse(f"fmi2DoStep(t = {t!r} s, h = {h!r} s)", why)

    def _set_simulator(self, simulator, built_for) -> None:
        self._simulator, self._built_for = simulator, built_for
        if simulator is not None:
            self._raw_step = simulator.kernel.raw_step()
            self._now = simulator.time

    # -- building the model ------------------------------------------------------------------
    def _parameter_values(self) -> tuple:
        return tuple(self._values[vr] for vr in self._parameter_vrs)

    def _build(self, parameters: tuple) -> tuple:
        """Validate every parameter and build the contact model: (simulator, contact model,
        warnings). Raises ParameterError listing every problem; changes nothing."""
        named = {self._table[vr].name: value for vr, value in zip(self._parameter_vrs,
                                                                   parameters)}
        tire_values = {name: named[name] for name in TIRE_FIELDS}
        op_values = {"n_elements": named["n_elements"], "load_n": named["load"],
                     "speed_m_s": named["speed"],
                     "allow_supercritical": bool(named["allow_supercritical"]),
                     "contact_zone_length_m": named["contact_zone_length"]}
        problems = []
        f_max, n_modes = named["f_max"], named["n_modes"]
        truncation = None
        try:
            truncation = RingTruncation(f_max_hz=None if f_max == 0 else float(f_max),
                                        n_modes=None if n_modes == 0 else int(n_modes),
                                        static_correction=bool(named["static_correction"]))
        except ParameterError as error:
            problems += error.details
        settings = ContactSettings(law="linear" if named["linear_contact"] else "unilateral")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:  # the load and speed checks need the assembled model: build it if we can
                tire, op = validate(tire_values, op_values)
                contact = build_contact_model(tire, op, truncation, settings)
            except ParameterError as error:
                problems += error.details
            if problems:
                raise ParameterError(problems)
        library, why = self._kernel_library()
        simulator = ContactSimulator(contact, start_time=self._start_time,
                                     backend="compiled" if library else "numpy",
                                     library=library)
        self._kernel_note = why or "stepping with the compiled kernel"
        return simulator, contact, [fmu_message(str(w.message)) for w in caught]

    def _kernel_library(self) -> tuple:
        """The compiled step kernel this FMU carries for the platform it runs on (loaded
        once per process), or None and why the numpy reference kernel steps instead."""
        from tire_fmu.native.kernel import PLATFORMS, KernelUnavailable, host_platform, load_library

        platform = host_platform()
        name = PLATFORMS[platform][3] if platform in PLATFORMS else None
        folder = os.path.dirname(os.path.abspath(self.resources)) if self.resources else ""
        path = os.path.join(folder, "binaries", platform or "", name or "")
        if name is None or not os.path.isfile(path):
            return None, (f"stepping with the numpy reference kernel: this FMU carries no "
                          f"compiled step kernel for {platform or 'this platform'} (it was "
                          "built without a C compiler for it; the outputs are the same, each "
                          "step slower)")
        try:
            return load_library(path), ""
        except KernelUnavailable as error:
            return None, (f"stepping with the numpy reference kernel: {error} (the outputs "
                          "are the same, each step slower)")

    def _initialise(self) -> None:
        started = time.perf_counter()
        parameters = self._parameter_values()
        try:
            simulator, contact, said = self._build(parameters)
        except ParameterError as error:
            problems = _fmu_problems(error)
            for number, problem in enumerate(problems, 1):
                self.log(f"parameter problem {number}/{len(problems)}: {problem}",
                         Fmi2Status.error)
            self._phase = Phase.ERROR
            self._why_not_running = (
                f"the parameters were refused at fmi2ExitInitializationMode ({len(problems)} "
                f"problem(s): {'; '.join(problems)}); reset the FMU and set valid parameters")
            self.log("fmi2ExitInitializationMode refused: " + self._why_not_running,
                     Fmi2Status.error)
            return
        for text in said:
            self.log(text, Fmi2Status.warning)
        self._set_simulator(simulator, parameters)
        self._checked_h = math.nan
        self._phase, self._why_not_running = Phase.RUNNING, ""
        self._contact_warning_armed = True
        self._show(simulator.output_dict(), simulator.in_contact)
        # inputs set during initialisation feed through on the first read
        self._stale = any(self._values[INPUTS])
        summary = contact.summary()
        self.log(
            f"TireModal ready in {time.perf_counter() - started:.2f} s: N = "
            f"{summary['n_elements']}, {summary['ring_modes']} of {summary['ring_modes_total']} "
            f"ring modes, {summary['zone_nodes']} contact-zone nodes, footprint "
            f"{summary['patch_length_m'] * 100:.3g} cm at {summary['load_n']:.6g} N, deflection "
            f"{summary['deflection_m'] * 1e3:.4g} mm, vertical stiffness "
            f"{summary['vertical_stiffness_n_per_m']:.6g} N/m, critical speed "
            f"{summary['critical_speed_m_s']:.4g} m/s, {contact.settings.law} contact, "
            f"{self._kernel_note}; core "
            f"tire_fmu {tire_fmu.__version__} from {tire_fmu.__file__}")

    def _show(self, outputs: dict, in_contact: bool) -> None:
        for name, value in outputs.items():
            self._values[self._index[name]] = value
        self._values[IN_CONTACT] = in_contact

    # -- variable access: pythonfmu's generic versions cost a lambda per value and raise on
    # a bad reference (fmi2Fatal, see the module doc); these index one list and log instead.
    def _refresh(self) -> None:
        """Outputs at the current time for the inputs set since the last step."""
        values = self._values
        try:
            outputs = self._simulator.outputs_with(values[0], values[1], values[2], values[3])
        except StepError as error:
            self.log(f"the outputs at t = {self._simulator.time!r} s cannot follow the inputs "
                     f"set there ({error}): they are those of the last step", Fmi2Status.error)
            return
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self._fail("computing the outputs", error)
            return
        self._stale = False
        values[OUTPUTS] = outputs
        values[IN_CONTACT] = outputs[2] > 0.0

    def get_real(self, vrs):
        if self._stale:
            self._refresh()
        if vrs == self._output_vrs:  # the host's usual call: the four forces, in order
            return self._values[OUTPUTS]
        return self._get("fmi2GetReal", vrs, "Real", float, 0.0)

    def get_integer(self, vrs):
        return self._get("fmi2GetInteger", vrs, "Integer", int, 0)

    def get_boolean(self, vrs):
        if self._stale:
            self._refresh()
        return self._get("fmi2GetBoolean", vrs, "Boolean", bool, False)

    def get_string(self, vrs):
        if vrs:
            self._refuse("fmi2GetString", f"value references {list(vrs)}: TireModal has no "
                         "String variables")
        return ["" for _ in vrs]

    def _get(self, call, vrs, kind, convert, fallback):
        result = []
        for vr in vrs:
            problem = self._reference_problem(vr, kind)
            if problem:
                self.log(f"{call} refused for value reference {vr!r}: {problem}; "
                         f"{fallback!r} returned", Fmi2Status.error)
                result.append(fallback)
            else:
                result.append(convert(self._values[vr]))
        return result

    def _reference_problem(self, vr, kind: str) -> str | None:
        if not (isinstance(vr, int) and 0 <= vr < len(self._table)):
            return f"it does not exist (TireModal has {len(self._table)} variables)"
        v = self._table[vr]
        if v.type != kind:
            return f"{v.name} has FMI type {v.type}: use fmi2Get{v.type} and fmi2Set{v.type}"
        return None

    def set_real(self, vrs, values):
        if vrs == self._input_vrs and self._phase == Phase.RUNNING:  # the host's usual call
            self._values[INPUTS] = values
            self._stale = True
        else:
            self._set("fmi2SetReal", vrs, values, "Real")

    def set_integer(self, vrs, values):
        self._set("fmi2SetInteger", vrs, values, "Integer")

    def set_boolean(self, vrs, values):
        self._set("fmi2SetBoolean", vrs, [bool(v) for v in values], "Boolean")

    def set_string(self, vrs, values):
        if vrs:
            self._refuse("fmi2SetString", f"value references {list(vrs)}: TireModal has no "
                         "String variables")

    def _set(self, call, vrs, values, kind) -> None:
        """Set every value or, if one is refused, none."""
        if not self._allowed(call):
            return
        for vr, value in zip(vrs, values):
            problem = self._reference_problem(vr, kind)
            if problem:
                self._refuse(call, f"value reference {vr!r}: {problem}")
                return
            v = self._table[vr]
            problem = self._value_problem(v)
            if problem:
                self._refuse(call, f"{v.name} = {value_text(value, v.unit)}: {problem}")
                return
        for vr, value in zip(vrs, values):
            self._values[vr] = value
            v = self._table[vr]
            if v.causality == "input":
                self._stale = self._phase == Phase.RUNNING
            elif v.name == "load" and math.isfinite(value):
                # the outputs echo the static load until initialised
                self._show({"rim_Fz": value, "contact_Fz": value}, value > 0)

    def _value_problem(self, v: FmuVariable) -> str | None:
        """Why ``v`` cannot be set now, or None."""
        if v.causality == "output":
            return "it is an output"
        if v.causality == "parameter" and self._phase not in (Phase.INSTANTIATED,
                                                              Phase.INITIALISING):
            return ("parameters are fixed after initialisation (they define the reduced "
                    "basis); reset the FMU to change them")
        return None

    # -- FMU state ---------------------------------------------------------------------------
    def _get_fmu_state(self):
        try:
            simulator = self._simulator.get_state() if self._simulator is not None else None
            return _Snapshot(tuple(self._values), self._phase, self._why_not_running,
                             self._start_time, simulator, self._contact_warning_armed,
                             self._stale)
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self.log(f"fmi2GetFMUstate failed: {type(error).__name__}: {error}",
                     Fmi2Status.error)
            return _InvalidState(f"it was taken when fmi2GetFMUstate failed ({error})")

    def _set_fmu_state(self, state) -> None:
        try:
            self._restore(state)
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self._refuse("fmi2SetFMUstate", f"{type(error).__name__}: {error}")

    def _restore(self, state) -> None:
        """Everything is checked, and the model built if need be, before anything changes."""
        call = "fmi2SetFMUstate"
        if isinstance(state, _InvalidState):
            self._refuse(call, state.reason)
            return
        if not isinstance(state, _Snapshot):
            self._refuse(call, f"it is not a TireModal state ({type(state).__name__})")
            return
        parameters = tuple(state.values[vr] for vr in self._parameter_vrs)
        simulator, built_for = None, None
        if state.simulator is not None:
            simulator, built_for = self._simulator, self._built_for
            if parameters != self._built_for:
                # a state of other parameters, or restored into a fresh instance: build its
                # model (with the state's start time, which the simulator state overrides)
                try:
                    simulator = self._build(parameters)[0]
                except ParameterError as error:
                    self._refuse(call, "its parameters do not build a model: "
                                 + "; ".join(_fmu_problems(error)))
                    return
                built_for = parameters
            try:
                simulator.set_state(state.simulator)  # checks the shapes before it changes
            except StateError as error:
                self._refuse(call, str(error))
                return
        self._set_simulator(simulator, built_for)
        self._checked_h = math.nan
        self._values[:] = state.values
        self._phase, self._why_not_running = state.phase, state.why_not_running
        self._start_time = state.start_time
        self._contact_warning_armed = state.contact_warning_armed
        self._stale = state.stale and simulator is not None  # nothing to feed through else

    @staticmethod
    def _fmu_state_to_bytes(state) -> bytes:
        # A line with the format and a sha256 of the rest, a JSON header, a newline (JSON
        # escapes its own), then the simulator's npz bytes: no pickle, so a state file cannot
        # run code when read, and the checksum refuses any byte changed, cut or appended.
        if isinstance(state, _InvalidState):
            header, payload = {"invalid": state.reason}, b""
        else:
            payload = state.simulator.to_bytes() if state.simulator is not None else b""
            header = {"values": list(state.values), "phase": state.phase,
                      "why_not_running": state.why_not_running, "start_time": state.start_time,
                      "contact_warning_armed": state.contact_warning_armed,
                      "stale": state.stale, "simulator_bytes": len(payload)}
        body = json.dumps(header, sort_keys=True).encode() + b"\n" + payload
        return _STATE_MAGIC + b" " + hashlib.sha256(body).hexdigest().encode() + b"\n" + body

    @staticmethod
    def _fmu_state_from_bytes(data: bytes):
        try:
            return _decode_state(bytes(data))
        except Exception as error:  # an escaping exception would be fmi2Fatal
            return _InvalidState(f"the bytes are not a TireModal state "
                                 f"({type(error).__name__}: {error})")


def _decode_state(data: bytes) -> _Snapshot | _InvalidState:
    """Check serialized state bytes in full: format, checksum, then every field."""
    magic = _STATE_MAGIC + b" "
    if not data.startswith(magic):
        return _InvalidState(f"they do not start with {_STATE_MAGIC.decode()!r} (they start "
                             f"with {data[:len(magic)]!r}): not a TireModal state of this "
                             "version")
    if len(data) > _MAX_STATE_BYTES:
        return _InvalidState(f"{len(data)} bytes: a TireModal state is far smaller")
    digest, newline, body = data[len(magic):].partition(b"\n")
    if not newline or hashlib.sha256(body).hexdigest().encode() != digest:
        return _InvalidState("the checksum does not match: the bytes were changed, cut or "
                             "extended after fmi2SerializeFMUstate")
    head, _, payload = body.partition(b"\n")
    header = json.loads(head.decode())
    if not isinstance(header, dict):
        return _InvalidState("the header is not a JSON object")
    if "invalid" in header:
        return _InvalidState(str(header["invalid"]))
    problems = _header_problems(header)
    if not problems and header["simulator_bytes"] != len(payload):
        problems.append(f"the header announces {header['simulator_bytes']} bytes of simulator "
                        f"state and {len(payload)} follow")
    simulator = None
    if not problems and payload:
        simulator, problem = _simulator_state(payload)
        if problem:
            problems.append(problem)
    if not problems and simulator is None and header["phase"] in (Phase.RUNNING,
                                                                   Phase.TERMINATED):
        problems.append(f"phase {header['phase']!r} needs a simulator state and there is none")
    if not problems:
        problems += _snapshot_problems(header, simulator)
    if problems:
        return _InvalidState("; ".join(problems))
    values = tuple(float(x) if v.type == "Real" else x
                   for v, x in zip(_TABLE, header["values"]))
    phase = next(p for p in Phase.ALL if p == header["phase"])  # the constant itself
    return _Snapshot(values, phase, header["why_not_running"],
                     float(header["start_time"]), simulator, header["contact_warning_armed"],
                     header["stale"])


def _header_problems(header: dict) -> list[str]:
    problems = []
    expected = {"values": list, "phase": str, "why_not_running": str, "start_time": float,
                "contact_warning_armed": bool, "stale": bool, "simulator_bytes": int}
    for key, kind in expected.items():
        value = header.get(key)
        ok = (isinstance(value, (int, float)) and not isinstance(value, bool)
              and math.isfinite(value)) if kind is float else (
            isinstance(value, kind) and not (kind is int and isinstance(value, bool)))
        if not ok:
            problems.append(f"{key} = {value!r}: must be {kind.__name__}"
                            + (" and finite" if kind is float else ""))
    unknown = sorted(set(header) - set(expected))
    if unknown:
        problems.append(f"unknown header fields {unknown}")
    if problems:
        return problems
    if header["phase"] not in Phase.ALL:
        problems.append(f"phase = {header['phase']!r}: must be one of {list(Phase.ALL)}")
    values = header["values"]
    if len(values) != len(_TABLE):
        return problems + [f"{len(values)} values: TireModal has {len(_TABLE)} variables"]
    for v, value in zip(_TABLE, values):
        problem = _state_value_problem(v, value)
        if problem:
            problems.append(problem)
    return problems


def _snapshot_problems(header: dict, simulator: ContactState | None) -> list[str]:
    """What the FMU's part of a state says against itself and its simulator's part, and
    what the FMU would never hold (the simulator's part alone is checked when it is set:
    ContactSimulator.state_problems)."""
    problems = []
    phase = header["phase"]
    if phase == Phase.ERROR and not header["why_not_running"].strip():
        problems.append("its phase is 'error' without the reason (why_not_running is empty): "
                        "it would refuse every call without saying why")
    if not clock.resolves(header["start_time"], MAX_STEP_S):
        problems.append("its " + MESSAGES["START_UNRESOLVED"] % (
            repr(float(header["start_time"])), clock.resolved_until(MAX_STEP_S) - MAX_STEP_S,
            MAX_STEP_S))
    if simulator is None:
        return problems
    if header["start_time"] != simulator.start_time:
        problems.append(f"its start time is {header['start_time']!r} s, but its simulator "
                        f"started at {simulator.start_time!r} s")
    if simulator.history_t.size > MAX_HISTORY_SAMPLES:
        problems.append(f"its road history holds {simulator.history_t.size} samples; the FMU "
                        f"keeps at most {MAX_HISTORY_SAMPLES} (one a step, over at most "
                        f"{MAX_DELAY_STEPS} steps)")
    if simulator.last_step_s > MAX_STEP_S:
        problems.append(f"its last step is {simulator.last_step_s!r} s; the FMU takes at most "
                        f"{MAX_STEP_S:g} s")
    if phase in (Phase.RUNNING, Phase.TERMINATED):
        values = header["values"]
        outputs = [float(x) for x in simulator.outputs]
        if values[OUTPUTS] != outputs or values[IN_CONTACT] is not (outputs[2] > 0.0):
            problems.append(f"the outputs it shows, {values[OUTPUTS]} and in_contact = "
                            f"{values[IN_CONTACT]!r}, are not its simulator's, {outputs}")
    return problems


def _state_value_problem(v: FmuVariable, value) -> str | None:
    if v.type == "Boolean":
        return None if isinstance(value, bool) else f"{v.name} = {value!r}: must be a Boolean"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"{v.name} = {value!r}: must be a number"
    if v.type == "Integer" and not (isinstance(value, int) and -2**31 <= value < 2**31):
        return f"{v.name} = {value!r}: must be an integer of 32 bits (fmi2Integer)"
    if v.causality == "output" and not math.isfinite(value):
        return f"{v.name} = {value!r}: an output must be finite"
    return None  # inputs and parameters are checked when they are used, as when set


def _simulator_state(payload: bytes) -> tuple[ContactState | None, str | None]:
    """The simulator's part, checked by the core (format, checksum, finite values)."""
    try:
        return ContactState.from_bytes(payload), None
    except StateError as error:
        return None, str(error)


def _baked_parameter_values(resources: str | None) -> dict | None:
    """Tire data the FMU was built for (resources/tire_parameters.json), if any."""
    if not resources:
        return None
    path = os.path.join(resources, BAKED_PARAMETERS_FILE)
    if not os.path.isfile(path):
        return None
    with open(path, encoding="utf-8") as stream:  # written by the builder: small, trusted
        return {str(k): float(v) for k, v in json.load(stream).items()}


def _fmu_problems(error: ParameterError) -> list[str]:
    """The problems in the FMU's names, in the fields and in the core's words around them."""
    return [fmu_message(text) for text in error.render(FMU_NAMES, FMU_UNSET)]
