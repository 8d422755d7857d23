"""``TireModal``: the ring tire as a pythonfmu co-simulation slave.

A thin adapter: parameters are FMI variables; when initialisation ends they go through the
core's validation and :func:`~tire_fmu.core.contact_dynamics.build_contact_model` (the static
footprint for the load, the free ring's modes for the speed); ``do_step`` hands the four inputs
to the step kernel (:class:`~tire_fmu.core.contact_dynamics.ContactSimulator`'s). No physics
and no parameter ranges live here, and no FMI rule either: the state machine (which call each
phase allows), every message about a call and the FMU-state byte format are
:mod:`tire_fmu.fmu.spec`'s, which the native FMU's C reads too (spec.h), so the two FMUs
answer alike (tests/test_fmi_behaviour.py runs one suite against both).

How failures surface (docs/fmu.md has the table):

- Every call is checked against the FMI 2.0 co-simulation state machine (spec.CALLS), and
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

import math
import os
import re
import struct
import time
import warnings

from pythonfmu import (
    Boolean,
    Fmi2Causality,
    Fmi2Slave,
    Fmi2Variability,
    Integer,
    Real,
    String,
)
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status

import tire_fmu
from tire_fmu.core import clock, kernel_numpy
from tire_fmu.core.blas_threads import blas_threads, unavailable
from tire_fmu.core.contact_dynamics import (
    MAX_DISPLACEMENT_M,
    MAX_VELOCITY_M_S,
    ContactSettings,
    ContactSimulator,
    StepError,
    build_contact_model,
)
from tire_fmu.core.free_ring import RingTruncation
from tire_fmu.core.parameters import TIRE_FIELDS, ParameterError, validate, value_text
from tire_fmu.file_checks import FileContentError, load_json, read_text
from tire_fmu.fmu.interface import (
    BAKED_PARAMETERS_FILE,
    FMU_NAMES,
    FMU_UNSET,
    IN_CONTACT,
    INPUT_UNIT_LIMITS,
    INPUTS,
    MAX_DELAY_STEPS,
    MAX_STEP_S,
    OUTPUTS,
    TIME_ABS_TOLERANCE_S,
    TIME_REL_TOLERANCE,
    FmuVariable,
    fmu_variables,
    input_limit,
)
from tire_fmu.fmu.spec import (
    CALL_MASKS,
    LOG_CATEGORIES,
    MESSAGES,
    PHASES,
    STATE_GUID_BYTES,
    STATE_MAGIC,
    STATE_MODEL_FLAGS,
    STATE_VERSION,
    Phase,
    fmu_message,
    phase_refusal,
    state_checksum,
    state_fixed_size,
    state_pack,
    state_unpack,
)

MODEL_IDENTIFIER = "TireModal"
_REFUSED = -3  # the step kernels' status for a step their rules refuse (kernel.h)
# the hot path's constants as module globals (cheaper to read than attributes)
_RUNNING = Phase.RUNNING
_MAX_M, _MAX_M_S = MAX_DISPLACEMENT_M, MAX_VELOCITY_M_S

#: pythonfmu's variable class for each FMI type of the shared table
_KINDS = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}
#: The variables' names, types and causalities (start values differ only by the tire data an
#: FMU was built with, which the serialized states do not depend on).
_TABLE = fmu_variables()


def fmi_message(text: str) -> str:
    """``text`` as an FMI log message: a printf format (``%`` doubled) with FMI's variable
    reference escape ``#`` doubled, so that the host shows exactly ``text``."""
    return text.replace("%", "%%").replace("#", "##")


class TireModal(Fmi2Slave):
    """In-plane modal ring tire (GL073A defaults): rim and road motion in, rim force out."""

    #: the name the FMU's messages give it (a subclass is another FMU, with its own)
    model_identifier = MODEL_IDENTIFIER
    author = "tire_fmu contributors"
    description = ("Open in-plane modal ring tire (0-300 Hz): reduced modal model built at "
                   "initialisation for the load and speed; inputs are deviations from static "
                   "equilibrium, forces are totals. Needs Python with numpy and scipy.")
    version = tire_fmu.__version__
    license = "MIT"
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=1e-4)
    # the native FMU's categories too: the lift-off events are logged in logEvents
    log_categories = {**Fmi2Slave.log_categories, "logEvents": LOG_CATEGORIES["logEvents"]}

    def __init__(self, **kwargs):
        # Cheap on purpose: pythonfmu instantiates the slave at build time and on every reset.
        super().__init__(**kwargs)
        self._table = self._variables(_baked_parameter_values(self.resources))
        self._values: list = [v.start for v in self._table]
        self._index = {v.name: vr for vr, v in enumerate(self._table)}
        self._parameter_vrs = [vr for vr, v in enumerate(self._table)
                               if v.causality == "parameter"]
        self._input_vrs = list(range(self._INPUTS.start, self._INPUTS.stop))
        self._output_vrs = list(range(self._OUTPUTS.start, self._OUTPUTS.stop))
        self._contact_vrs = [self._IN_CONTACT]
        self._phase = Phase.INSTANTIATED
        self._error_reason = ""  # in the error phase: why (spec.MESSAGES FAILED, ...)
        self._start_time = 0.0
        self._simulator: ContactSimulator | None = None
        self._built_for: tuple | None = None  # parameter values the simulator was built with
        self._raw_step = None  # the kernel's hot path: (function, handle, inputs, report)
        # the last communication point (the start time before initialisation)
        self._now = 0.0
        self._checked_h = math.nan  # the last step size found good for this simulator
        self._contact_warning_armed = True  # the zone-edge warning, logged once per episode
        self._contact_logged = True  # the in_contact the last lift-off event was logged for
        self._said_blas_unlimited = False  # the warning that BLAS threads cannot be limited
        # Inputs set since the outputs were last computed: the next read recomputes the
        # forces at the current point with them (see ContactSimulator.outputs_with).
        self._stale = False
        for vr, v in enumerate(self._table):
            self._register(vr, v)

    # the variable table and its hot-path blocks (a subclass with other variables sets them)
    _INPUTS, _OUTPUTS, _IN_CONTACT = INPUTS, OUTPUTS, IN_CONTACT

    @staticmethod
    def _variables(parameter_values: dict | None) -> tuple[FmuVariable, ...]:
        return fmu_variables(parameter_values=parameter_values)

    def _register(self, vr: int, v: FmuVariable) -> None:
        # the getter closes over the values list, not over self: a getter holding self would
        # be a reference cycle (self.vars -> variable -> getter -> self), and a freed instance
        # would then wait for the cycle collector, with its whole model, instead of going at
        # fmi2FreeInstance (the list is never rebound, only assigned into)
        values = self._values
        kwargs = dict(causality=Fmi2Causality[v.causality], description=v.description,
                      variability=Fmi2Variability[v.variability],
                      getter=lambda: values[vr], setter=lambda value: None)
        if v.causality == "parameter":
            kwargs.update(initial=Fmi2Initial.exact)
        elif v.causality == "output":  # computed: no start value, listed as initial unknowns
            kwargs.update(initial=Fmi2Initial.calculated)
        # units go into the model description at build time, from the same table
        self.register_variable(_KINDS[v.type](v.name, **kwargs))

    def to_xml(self, model_options=None):
        # pythonfmu's builder reads each start value with get_real and friends, which FMI
        # does not allow while instantiated (refused there): its instance, never a host's,
        # reads them as in initialisation mode, where they are the same values
        phase, self._phase = self._phase, Phase.INITIALISATION
        try:
            return super().to_xml({} if model_options is None else model_options)
        finally:
            self._phase = phase

    # -- messages ----------------------------------------------------------------------------
    def log(self, msg: str, status: Fmi2Status = Fmi2Status.ok, category=None, debug=None):
        super().log(fmi_message(msg), status, category)

    def _refuse(self, call: str, why: str) -> bool:
        """Log that ``call`` was refused and why (status error); nothing was changed."""
        self.log(MESSAGES["REFUSED"] % (call, why), Fmi2Status.error)
        return False

    def _allowed(self, call: str) -> bool:
        if CALL_MASKS[call] >> self._phase & 1:
            return True
        return self._refuse(call, phase_refusal(self._phase, self._error_reason))

    def _fail(self, what: str, cause: str) -> None:
        """An unexpected failure: the FMU goes to the error state (reset or set a state)."""
        self._phase = Phase.ERROR
        self._error_reason = MESSAGES["FAILED"] % (what, cause)
        self.log(self._error_reason, Fmi2Status.error)

    def _contact_event(self, in_contact: bool) -> None:
        """The tread left the road or landed: physics, logged as information (logEvents)."""
        self._contact_logged = in_contact
        self.log(MESSAGES["TOUCH_DOWN" if in_contact else "LIFT_OFF"] % self._now,
                 Fmi2Status.ok, "logEvents")

    # -- lifecycle ---------------------------------------------------------------------------
    def setup_experiment(self, start_time: float, stop_time: float | None = None,
                         tolerance: float | None = None) -> None:
        call = "fmi2SetupExperiment"
        if not self._allowed(call):
            return
        start = repr(float(start_time))
        if not math.isfinite(start_time):
            self._refuse(call, MESSAGES["START_NOT_FINITE"] % start)
        elif not clock.resolves(start_time, MAX_STEP_S):
            self._refuse(call, MESSAGES["START_UNRESOLVED"] % (
                start, clock.resolved_until(MAX_STEP_S) - MAX_STEP_S, MAX_STEP_S))
        elif stop_time is not None and not (math.isfinite(stop_time) and stop_time >= start_time):
            self._refuse(call, MESSAGES["STOP_TIME"] % (repr(float(stop_time)), start))
        elif tolerance is not None and not (math.isfinite(tolerance) and tolerance > 0.0):
            self._refuse(call, MESSAGES["TOLERANCE"] % repr(float(tolerance)))
        else:
            self._start_time = self._now = float(start_time)

    def enter_initialization_mode(self) -> None:
        if self._allowed("fmi2EnterInitializationMode"):
            self._phase = Phase.INITIALISATION

    def exit_initialization_mode(self) -> None:
        if not self._allowed("fmi2ExitInitializationMode"):
            return
        try:
            self._initialise()
        except Exception as error:  # an escaping exception would be fmi2Fatal (module doc)
            self._fail("building the model", _cause(error))

    def terminate(self) -> None:
        if self._allowed("fmi2Terminate"):
            self._phase = Phase.TERMINATED

    def do_step(self, current_time: float, step_size: float) -> bool:
        if self._phase != _RUNNING:
            return self._allowed("fmi2DoStep")
        now = self._now
        values = self._values
        if current_time != now:
            # also refuses a non-finite t: every comparison with nan is false
            if not abs(current_time - now) <= max(TIME_ABS_TOLERANCE_S,
                                                  TIME_REL_TOLERANCE * abs(now)):
                return self._refuse_step(current_time, step_size, MESSAGES["NOT_LAST_POINT"] % (
                    repr(float(current_time)), repr(now)))
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
            self._fail(MESSAGES["STEP_FAILED"] % repr(float(current_time)), _cause(error))
            return False
        if status:
            return self._step_refused(status, current_time, step_size)
        outputs = report[0:6]
        if not math.isfinite(outputs[0] + outputs[1] + outputs[2] + outputs[3] + outputs[5]):
            self._fail(MESSAGES["STEP_FAILED"] % repr(float(current_time)),
                       MESSAGES["NOT_FINITE_OUTPUTS"])
            return False
        values[OUTPUTS] = outputs
        self._now = report[6]
        self._stale = False
        in_contact = values[IN_CONTACT] = outputs[2] > 0.0
        # contact loss is physics (an event, in_contact says it); a footprint at the end of
        # the zone is the model's limit, and warns
        if in_contact is not self._contact_logged:
            self._contact_event(in_contact)
        if report[7]:
            if self._contact_warning_armed:
                self._contact_warning_armed = False
                self.log(MESSAGES["ZONE_EDGE"] % self._now, Fmi2Status.warning)
        elif not self._contact_warning_armed:
            self._contact_warning_armed = True
        return True

    def _step_refused(self, status: int, t: float, h: float) -> bool:
        """A step the kernel did not take: refused for a reason the core names (nothing
        changed), or its memory ran out (the FMU's error state)."""
        if status == _REFUSED:
            try:
                self._simulator._check(h, tuple(self._values[:4]))
            except StepError as error:
                return self._refuse_step(t, h, str(error))
        self._fail(MESSAGES["STEP_FAILED"] % repr(float(t)), MESSAGES["OUT_OF_MEMORY"]
                   if status != _REFUSED else "refused with no reason the core finds")
        return False

    def _step_size_problem(self, h: float) -> str | None:
        if not 0.0 < h <= MAX_STEP_S:  # false for nan too
            return MESSAGES["STEP_RANGE"] % (repr(float(h)), MAX_STEP_S)
        reach = self._simulator.kernel.horizon_s
        if not reach / h <= MAX_DELAY_STEPS:
            return MESSAGES["STEP_DELAY"] % (repr(float(h)), reach / MAX_DELAY_STEPS, reach,
                                             MAX_DELAY_STEPS)
        return None

    def _refuse_step(self, t: float, h: float, why: str) -> bool:
        return self._refuse(MESSAGES["STEP_CALL"] % (repr(float(t)), repr(float(h))), why)

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
                     "contact_zone_length_m": named["contact_zone_length"],
                     "contact_point_spacing_m": named["contact_point_spacing"]}
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
        # the build's BLAS threads limited (numpy's only: this build never loads scipy), the
        # host's given back after
        with warnings.catch_warnings(record=True) as caught, blas_threads(load_scipy=False):
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
        self._say_if_blas_unlimited()
        self._kernel_note = why or "stepping with the compiled kernel"
        return simulator, contact, [fmu_message(str(w.message)) for w in caught]

    def _say_if_blas_unlimited(self) -> None:
        """Warn once (per instance) when the build could not limit BLAS's threads."""
        why = unavailable()
        if why and not self._said_blas_unlimited:
            self._said_blas_unlimited = True
            self.log(why, Fmi2Status.warning)

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
            self._refuse_parameters(_fmu_problems(error))
            return
        for text in said:
            self.log(text, Fmi2Status.warning)
        self._set_simulator(simulator, parameters)
        self._checked_h = math.nan
        self._phase = Phase.RUNNING
        self._contact_warning_armed = True
        self._contact_logged = simulator.in_contact
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

    def _refuse_parameters(self, problems: list[str]) -> None:
        """Log every parameter problem, numbered, and go to the error state: there is no
        model to step, and every later refusal says why."""
        for number, problem in enumerate(problems, 1):
            self.log(MESSAGES["PROBLEM_LINE"] % (number, len(problems), problem),
                     Fmi2Status.error)
        self._phase = Phase.ERROR
        self._error_reason = MESSAGES["PARAMETERS_REFUSED"] % (len(problems),
                                                                "; ".join(problems))
        self.log(MESSAGES["EXIT_REFUSED"] % self._error_reason, Fmi2Status.error)

    def _show(self, outputs: dict, in_contact: bool) -> None:
        for name, value in outputs.items():
            self._values[self._index[name]] = value
        self._values[self._IN_CONTACT] = in_contact

    # -- variable access: pythonfmu's generic versions cost a lambda per value and raise on
    # a bad reference (fmi2Fatal, see the module doc); these index one list and log instead.
    def _refresh(self) -> bool:
        """Outputs at the current time for the inputs set since the last step."""
        values = self._values
        try:
            outputs = self._simulator.outputs_with(values[0], values[1], values[2], values[3])
        except StepError as error:  # the inputs were checked when set: not from a host
            self._fail(MESSAGES["OUTPUTS_FAILED"], str(error))
            return False
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self._fail(MESSAGES["OUTPUTS_FAILED"], _cause(error))
            return False
        self._stale = False
        values[OUTPUTS] = outputs
        values[IN_CONTACT] = outputs[2] > 0.0
        return True

    def get_real(self, vrs):
        if vrs == self._output_vrs and self._phase == _RUNNING:  # the host's usual call
            if self._stale:
                self._refresh()
            return self._values[OUTPUTS]
        return self._get("fmi2GetReal", vrs, "Real", float, 0.0)

    def get_integer(self, vrs):
        return self._get("fmi2GetInteger", vrs, "Integer", int, 0)

    def get_boolean(self, vrs):
        if vrs == self._contact_vrs and self._phase == _RUNNING:  # in_contact, each step
            if self._stale:
                self._refresh()
            return [self._values[IN_CONTACT]]
        return self._get("fmi2GetBoolean", vrs, "Boolean", bool, False)

    def get_string(self, vrs):
        if not any(v.type == "String" for v in self._table):
            if self._allowed("fmi2GetString") and vrs:
                self._refuse("fmi2GetString", MESSAGES["NO_STRINGS"] % self.model_identifier)
            return ["" for _ in vrs]
        return self._get("fmi2GetString", vrs, "String", str, "")

    def _get(self, call, vrs, kind, convert, fallback):
        """Every value, or (refused: the call's phase or a reference) the fallbacks."""
        if not self._allowed(call):
            return [fallback for _ in vrs]
        for vr in vrs:
            problem = self._reference_problem(vr, kind)
            if problem:
                self._refuse(call, problem)
                return [fallback for _ in vrs]
        if self._stale and self._phase == Phase.RUNNING and not self._refresh():
            return [fallback for _ in vrs]
        return [convert(self._values[vr]) for vr in vrs]

    def _reference_problem(self, vr, kind: str) -> str | None:
        if not (isinstance(vr, int) and 0 <= vr < len(self._table)):
            return MESSAGES["REFERENCE_MISSING"] % (vr, self.model_identifier,
                                                 len(self._table))
        v = self._table[vr]
        if v.type != kind:
            return MESSAGES["REFERENCE_TYPE"] % (vr, v.name, v.type, v.type, v.type)
        return None

    def set_real(self, vrs, values):
        if vrs == self._input_vrs and self._phase == _RUNNING:  # the host's usual call
            z, vz, road_z, road_vz = values
            # within the inputs' limits (false for nan): else refused below, naming it
            if (-_MAX_M <= z <= _MAX_M and -_MAX_M <= road_z <= _MAX_M
                    and -_MAX_M_S <= vz <= _MAX_M_S and -_MAX_M_S <= road_vz <= _MAX_M_S):
                self._values[INPUTS] = values
                self._stale = True
                return
        self._set("fmi2SetReal", vrs, values, "Real")

    def set_integer(self, vrs, values):
        self._set("fmi2SetInteger", vrs, values, "Integer")

    def set_boolean(self, vrs, values):
        self._set("fmi2SetBoolean", vrs, [bool(v) for v in values], "Boolean")

    def set_string(self, vrs, values):
        if not any(v.type == "String" for v in self._table):
            if self._allowed("fmi2SetString") and vrs:
                self._refuse("fmi2SetString", MESSAGES["NO_STRINGS"] % self.model_identifier)
            return
        self._set("fmi2SetString", vrs, [str(v) for v in values], "String")

    def _set(self, call, vrs, values, kind) -> None:
        """Set every value or, if one is refused, none."""
        if not self._allowed(call):
            return
        for vr, value in zip(vrs, values):
            problem = self._reference_problem(vr, kind) or self._value_problem(
                self._table[vr], value)
            if problem:
                self._refuse(call, problem)
                return
        for vr, value in zip(vrs, values):
            self._values[vr] = value
            v = self._table[vr]
            if v.causality == "input":
                self._stale = self._stale or self._phase == Phase.RUNNING
            elif v.name == "load" and self._phase != Phase.RUNNING and math.isfinite(value):
                # the outputs echo the static load until initialised
                self._show({"rim_Fz": value, "contact_Fz": value}, value > 0)

    def _value_problem(self, v: FmuVariable, value) -> str | None:
        """Why ``v`` cannot take ``value`` now, or None."""
        if v.causality == "input":
            return _input_problem(v, value)
        text = value_text(value, v.unit)
        if v.causality == "output":
            return MESSAGES["OUTPUT_SET"] % (v.name, text)
        if self._phase == Phase.RUNNING:  # a parameter (other phases refuse every set)
            return MESSAGES["PARAMETER_FIXED"] % (v.name, text)
        return None

    # -- FMU state: the bytes of spec.STATE_LAYOUT, as the native FMU writes them -------------
    def _guid(self) -> str:
        """This FMU's GUID (its modelDescription.xml beside resources/; none in plain
        Python)."""
        return _model_guid(self.resources)

    def _get_fmu_state(self):
        try:
            if self._stale and self._phase == Phase.RUNNING and not self._refresh():
                return b""
            model = b""
            if self._phase in (Phase.RUNNING, Phase.TERMINATED):
                model = (struct.pack("<2i", self._contact_warning_armed, self._contact_logged)
                         + self._model_state_bytes())
            reason = self._error_reason if self._phase == Phase.ERROR else ""
            table = self._table
            return state_pack(self._phase, self._guid(), self._now, self._start_time,
                              self._stale, [0.0 if v.type == "String" else x
                                            for v, x in zip(table, self._values)],
                              model, reason, [x for v, x in zip(table, self._values)
                                              if v.type == "String"])
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self.log(f"fmi2GetFMUstate failed: {_cause(error)}", Fmi2Status.error)
            return b""

    def _set_fmu_state(self, state) -> None:
        try:
            self._restore(bytes(state) if isinstance(state, (bytes, bytearray)) else b"")
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self._refuse("fmi2SetFMUstate", _cause(error))

    def _restore(self, data: bytes) -> None:
        """Everything is checked, and the model built if need be, before anything changes."""
        call = "fmi2SetFMUstate"
        problem = state_problem(data, self._table, self._guid())
        if problem:
            self._refuse(call, problem)
            return
        fields = state_unpack(data, len(self._table))
        strings = iter(state_strings(fields["strings"]))
        values = [float(x) if v.type == "Real" else int(x) if v.type == "Integer"
                  else next(strings) if v.type == "String" else x != 0.0
                  for v, x in zip(self._table, fields["values"])]
        model = fields["model"]
        simulator, built_for = self._simulator, self._built_for
        if model:
            parameters = tuple(values[vr] for vr in self._parameter_vrs)
            if simulator is None or parameters != built_for:
                # a state of other parameters, or restored into a fresh instance: build its
                # model (with the state's start time, which the kernel's state overrides)
                try:
                    simulator = self._build(parameters)[0]
                except ParameterError as error:
                    self._refuse(call, MESSAGES["STATE_PARAMETERS"] % "; ".join(
                        _fmu_problems(error)))
                    return
                built_for = parameters
            problem = self._model_part_problem(simulator, model, values, fields["time"],
                                               fields["start_time"])
            if problem:
                self._refuse(call, problem)
                return
            self._set_model_state(simulator, model[4 * STATE_MODEL_FLAGS:])
            self._set_simulator(simulator, built_for)
            self._contact_warning_armed, self._contact_logged = (
                bool(flag) for flag in struct.unpack_from("<2i", model))
        self._checked_h = math.nan
        self._values[:] = values
        self._phase = fields["phase"]
        self._error_reason = fields["reason"].decode("utf-8", errors="replace")
        self._start_time, self._now = fields["start_time"], fields["time"]
        self._stale = bool(fields["stale"])
        self._restored()

    def _restored(self) -> None:
        """What a subclass derives from the values a state restored (nothing here)."""

    # the model's part of an FMU state (a subclass with another model replaces these)
    def _model_state_bytes(self) -> bytes:
        return self._simulator.kernel.state_bytes()

    @staticmethod
    def _model_part_problem(simulator, model: bytes, values: list, time_s: float,
                            start: float) -> str | None:
        return _model_part_problem(simulator, model, values, time_s, start)

    @staticmethod
    def _set_model_state(simulator, data: bytes) -> None:
        simulator.kernel.set_state_bytes(data)

    @staticmethod
    def _fmu_state_to_bytes(state) -> bytes:
        # the state is its bytes already (spec.STATE_LAYOUT): no pickle, so a state file
        # cannot run code when read
        return bytes(state) if isinstance(state, (bytes, bytearray)) else b""

    @staticmethod
    def _fmu_state_from_bytes(data: bytes):
        # pythonfmu calls this on the class (no instance, no logger, no GUID): the bytes are
        # checked in full when set
        return bytes(data)


def state_problem(data: bytes, table: tuple[FmuVariable, ...], guid: str) -> str | None:
    """Why ``data`` is no FMU state of this FMU, the model part aside (the native FMU's
    fmi2_layer.c state_problem: the same checks, in its order and words), or None."""
    m = MESSAGES
    fixed = state_fixed_size(len(table))
    if len(data) < fixed or data[:8] != STATE_MAGIC.encode():
        return m["STATE_NOT_OURS"] % (m["STATE_TOO_SHORT"] if len(data) < fixed
                                      else m["STATE_NO_HEADER"])
    f = state_unpack(data, len(table))
    if f["size"] != len(data):
        return m["STATE_SIZE"] % (f["size"], len(data))
    if f["checksum"] != state_checksum(data[:-4]):
        return m["STATE_DAMAGED"]
    if f["version"] != STATE_VERSION:
        return m["STATE_VERSION"] % (f["version"], STATE_VERSION)
    if f["guid"] != guid:
        return m["STATE_GUID"] % (f["guid"], guid)
    phase = f["phase"]
    if phase >= len(PHASES):
        return m["STATE_PHASE"] % phase
    time_s, start = f["time"], f["start_time"]
    if not (math.isfinite(time_s) and math.isfinite(start)) or f["stale"] > 1:
        return m["STATE_CLOCK"] % (repr(time_s), repr(start))
    if not clock.resolves(start, MAX_STEP_S):
        return m["STATE_START"] % (m["START_UNRESOLVED"] % (
            repr(start), clock.resolved_until(MAX_STEP_S) - MAX_STEP_S, MAX_STEP_S))
    if phase in (Phase.INSTANTIATED, Phase.INITIALISATION) and time_s != start:
        return m["STATE_BEFORE_INIT"] % (repr(time_s), repr(start))
    for v, x in zip(table, f["values"]):
        if v.causality == "input":
            problem = _input_problem(v, x)
            if problem:
                return m["STATE_INPUT"] % problem
        elif ((v.type == "Integer" and not (math.isfinite(x) and x == math.floor(x)
                                            and abs(x) <= 2147483647.0))
              or (v.type == "Boolean" and x not in (0.0, 1.0))
              or (v.causality == "output" and not math.isfinite(x))):
            # a Real parameter holds whatever a set gave it: checked when it is used
            return m["STATE_VALUE"] % (v.name, v.type)
    model_size, reason_size = f["model_size"], f["reason_size"]
    if model_size + reason_size + f["strings_size"] != len(data) - fixed:
        return m["STATE_MODEL_SIZE"]
    texts = state_strings(f["strings"])
    if texts is None or len(texts) != sum(v.type == "String" for v in table):
        return m["STATE_STRINGS"]
    if (phase in (Phase.RUNNING, Phase.TERMINATED)) != (model_size > 0):
        return m["STATE_MODEL_PHASE"]
    if (phase == Phase.ERROR) != (reason_size > 0):
        return (m["STATE_NO_REASON"] if phase == Phase.ERROR
                else m["STATE_REASON_PHASE"] % Phase.NAMES[phase])
    if b"\0" in f["reason"]:
        return m["STATE_REASON_NUL"]
    return None


def state_strings(data: bytes) -> list[str] | None:
    """The String values of a state's strings section (each UTF-8, ended by a NUL), or None
    when it is no such list."""
    if data and not data.endswith(b"\0"):
        return None
    try:
        return [part.decode("utf-8") for part in data.split(b"\0")[:-1]]
    except UnicodeDecodeError:
        return None


def _model_part_problem(simulator: ContactSimulator, model: bytes, values: list,
                        time_s: float, start: float) -> str | None:
    """Why the model part is no state of this simulator shown by these values at this time
    (tire_model.c's model_state_check: the two flags, the kernel's own checks, then the
    FMU's part against the kernel's), or None."""
    m = MESSAGES
    flags_size = 4 * STATE_MODEL_FLAGS
    if len(model) < flags_size:
        return m["STATE_MODEL_SHORT"] % len(model)
    for i, flag in enumerate(struct.unpack_from(f"<{STATE_MODEL_FLAGS}i", model)):
        if flag not in (0, 1):
            return m["STATE_MODEL_FLAG"] % (i, flag)
    kernel_part = model[flags_size:]
    problem = simulator.kernel.state_problem(kernel_part)  # kernel.c's kernel_state_check
    if problem:
        return problem
    fields = kernel_numpy.state_fields(kernel_part)
    problems = []
    kernel_start = fields["start_time"]
    kernel_time = kernel_start + fields["elapsed_s"]
    if kernel_start != start or kernel_time != time_s:
        problems.append(m["STATE_MODEL_CLOCK"] % (repr(time_s), repr(start), repr(kernel_time),
                                                  repr(kernel_start)))
    outputs = fields["outputs"]
    # (the in-contact flag is the last one an event was logged for, which outputs read
    # after new inputs, before a step, may have left behind)
    if (any(values[OUTPUTS.start + i] != outputs[i] for i in range(len(outputs)))
            or float(values[IN_CONTACT]) != (1.0 if outputs[2] > 0.0 else 0.0)):
        problems.append(m["STATE_MODEL_OUTPUTS"])
    return "; ".join(problems) or None


#: What an input may be, by its unit (interface.INPUT_UNIT_LIMITS; by name: input_limit).
INPUT_LIMITS = INPUT_UNIT_LIMITS


def _input_problem(v: FmuVariable, value) -> str | None:
    """Why input ``v`` cannot take ``value`` (spec INPUT_RANGE), or None."""
    limit = input_limit(v)
    if abs(value) <= limit:
        return None
    return MESSAGES["INPUT_RANGE"] % (v.name, repr(float(value)), v.unit, limit, limit, v.unit)


def _cause(error: Exception) -> str:
    return f"{type(error).__name__}: {error}"


_GUIDS: dict[str, str] = {}


def _model_guid(resources: str | None) -> str:
    """The GUID in the modelDescription.xml of the FMU whose resources/ folder this is (read
    once per process), or "" outside an FMU."""
    folder = os.path.dirname(os.path.abspath(resources)) if resources else ""
    if folder not in _GUIDS:
        guid = ""
        try:
            with open(os.path.join(folder, "modelDescription.xml"), encoding="utf-8",
                      errors="replace") as stream:
                found = re.search(r'\bguid="([^"]*)"', stream.read(4096))
            guid = found.group(1) if found else ""
        except OSError:
            pass
        _GUIDS[folder] = guid[:STATE_GUID_BYTES - 1]
    return _GUIDS[folder]


def _baked_parameter_values(resources: str | None) -> dict | None:
    """Tire data the FMU was built for (resources/tire_parameters.json), if any."""
    if not resources:
        return None
    path = os.path.join(resources, BAKED_PARAMETERS_FILE)
    if not os.path.isfile(path):
        return None
    # written by the builder, yet a file like any other: checked before it is believed
    text = read_text(path, MAX_BAKED_BYTES, "the FMU's baked parameter values")
    values = load_json(text, path, "its JSON", MAX_BAKED_BYTES)
    if not (isinstance(values, dict) and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in values.values())):
        raise FileContentError(f"{path}: must be a JSON object of parameter names and finite "
                               "numbers, as the FMU's builder writes it")
    return {str(k): float(v) for k, v in values.items()}


#: The largest resources/tire_parameters.json read (bytes): the builder writes about 2 kB.
MAX_BAKED_BYTES = 1 << 16


def _fmu_problems(error: ParameterError) -> list[str]:
    """The problems in the FMU's names, in the fields and in the core's words around them."""
    return [fmu_message(text) for text in error.render(FMU_NAMES, FMU_UNSET)]
