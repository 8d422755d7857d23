"""``TireModal``: the ring tire as a pythonfmu co-simulation slave.

A thin adapter: parameters are FMI variables; when initialisation ends they go through the
core's validation and :func:`~tire_fmu.core.contact_dynamics.build_contact_model` (the static
footprint for the load, the free ring's modes for the speed); ``do_step`` hands the four inputs
to :class:`~tire_fmu.core.contact_dynamics.ContactSimulator`. No physics and no parameter
ranges live here.

How failures surface, given what pythonfmu 0.7 can express (see docs/fmu.md):

- A Python exception that escapes becomes fmi2Fatal, and pythonfmu's C wrapper then releases
  the Python instance while keeping its pointer, so the host may crash later. Nothing here
  raises: every entry point catches and logs.
- The wrapper returns fmi2Error only for C++ failures, never for a Python method, and every
  hook except ``do_step`` returns fmi2OK. The one refusal a slave can make is ``do_step``
  returning False: fmi2Discard. So rejected parameters are logged (each problem at status
  error) when initialisation ends, and every ``doStep`` after that returns fmi2Discard with a
  message saying why; a bad step (t off the last communication point, h <= 0, a non-finite
  input) is refused the same way and leaves the state untouched, so the host may retry.
- Messages reach the host only when it instantiates with ``loggingOn = true`` (pythonfmu's
  logger filters every status on it).
"""

from __future__ import annotations

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
from tire_fmu.core.contact_dynamics import (
    ContactSettings,
    ContactSimulator,
    ContactState,
    StepError,
    build_contact_model,
)
from tire_fmu.core.free_ring import RingTruncation
from tire_fmu.core.parameters import (
    TIRE_FIELDS,
    ParameterError,
    validate,
)
from tire_fmu.fmu.interface import (
    BAKED_PARAMETERS_FILE,
    IN_CONTACT,
    INPUTS,
    OUTPUTS,
    TIME_ABS_TOLERANCE_S,
    TIME_REL_TOLERANCE,
    FmuVariable,
    fmu_variables,
)
from tire_fmu.fmu.spec import fmu_message

_STATE_FORMAT = "tire_fmu.fmu-state/1"


#: pythonfmu's variable class for each FMI type of the shared table
_KINDS = {"Real": Real, "Integer": Integer, "Boolean": Boolean}


class _Phase:
    """Where the slave is in the FMI lifecycle, as far as it needs to know."""

    INSTANTIATED = "instantiated"  # parameters may change
    INITIALISING = "initialisation mode"  # parameters may change
    RUNNING = "running"
    REJECTED = "rejected"  # the parameters were refused when initialisation ended
    BROKEN = "broken"  # an FMU state could not be restored
    TERMINATED = "terminated"


@dataclass(frozen=True, eq=False)
class _Snapshot:
    """An FMU state: every variable's value, the simulator's state and the warning latch."""

    values: tuple
    phase: str
    simulator: ContactState | None
    contact_warning_armed: bool


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
        self._phase = _Phase.INSTANTIATED
        self._why_not_running = "the FMU is not initialised (call fmi2ExitInitializationMode)"
        self._start_time = 0.0
        self._simulator: ContactSimulator | None = None
        self._built_for: tuple | None = None  # parameter values the simulator was built with
        self._running: ContactSimulator | None = None  # the simulator while do_step may run
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

    # -- lifecycle ---------------------------------------------------------------------------
    def setup_experiment(self, start_time: float, stop_time: float | None = None,
                         tolerance: float | None = None) -> None:
        self._start_time = float(start_time)

    def enter_initialization_mode(self) -> None:
        if self._phase == _Phase.INSTANTIATED:
            self._phase = _Phase.INITIALISING

    def exit_initialization_mode(self) -> None:
        try:
            self._initialise(self._parameter_values())
        except Exception as error:  # an escaping exception would be fmi2Fatal (see module doc)
            why = f"building the model failed ({type(error).__name__}: {error})"
            self.log(f"TireModal cannot run: {why}", Fmi2Status.error)
            self._stop(_Phase.REJECTED, why + "; reset the FMU")

    def terminate(self) -> None:
        self._stop(_Phase.TERMINATED, "the FMU was terminated (fmi2Terminate)")

    def do_step(self, current_time: float, step_size: float) -> bool:
        simulator = self._running
        if simulator is None:
            return self._discard(f"doStep at t = {current_time!r} s refused: "
                                 f"{self._why_not_running}")
        now = simulator.time
        if current_time != now:
            if abs(current_time - now) > max(TIME_ABS_TOLERANCE_S, TIME_REL_TOLERANCE * abs(now)):
                return self._discard(
                    f"doStep at t = {current_time!r} s refused: the last communication point "
                    f"is t = {now!r} s, and a step must start there (roll back with "
                    "fmi2SetFMUstate to step from an earlier time); state unchanged")
            simulator.time = current_time  # the host's clock is the reference: no drift
        values = self._values
        try:  # the inputs are value references 0-3 (INPUTS); indexing beats *args here
            outputs = simulator.step_values(step_size, values[0], values[1], values[2],
                                            values[3])
        except StepError as error:
            simulator.time = now
            return self._discard(f"doStep at t = {current_time!r} s refused: {error}; "
                                 "state unchanged")
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self._stop(_Phase.BROKEN, f"the step at t = {current_time!r} s failed "
                       f"({type(error).__name__}: {error}); reset the FMU")
            return self._discard(f"doStep at t = {current_time!r} s failed: {error}")
        values[OUTPUTS] = outputs
        self._stale = False
        values[IN_CONTACT] = outputs[2] > 0.0
        if simulator.at_zone_edge():
            if self._contact_warning_armed:
                self._warn_zone_edge(simulator.time)
        elif not self._contact_warning_armed:
            self._contact_warning_armed = True
        return True

    # -- building the model ------------------------------------------------------------------
    def _parameter_values(self) -> tuple:
        return tuple(self._values[vr] for vr in self._parameter_vrs)

    def _initialise(self, parameters: tuple) -> None:
        """Validate every parameter, build the contact model, prepare the simulator."""
        started = time.perf_counter()
        named = {self._table[vr].name: value for vr, value in zip(self._parameter_vrs,
                                                                   parameters)}
        tire_values = {name: named[name] for name in TIRE_FIELDS}
        op_values = {"n_elements": named["n_elements"], "load_n": named["load"],
                     "speed_m_s": named["speed"],
                     "allow_supercritical": bool(named["allow_supercritical"]),
                     "contact_zone_length_m": named["contact_zone_length"]}
        problems, contact = [], None
        f_max, n_modes = named["f_max"], named["n_modes"]
        truncation = None
        try:
            truncation = RingTruncation(f_max_hz=None if f_max == 0 else float(f_max),
                                        n_modes=None if n_modes == 0 else int(n_modes),
                                        static_correction=bool(named["static_correction"]))
        except ParameterError as error:
            problems += error.problems
        settings = ContactSettings(law="linear" if named["linear_contact"] else "unilateral")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:  # the load and speed checks need the assembled model: build it if we can
                tire, op = validate(tire_values, op_values)
                contact = build_contact_model(tire, op, truncation, settings)
            except ParameterError as error:
                problems += error.problems
            if problems:
                self._reject(problems)
                return
        for warning in caught:
            self.log(_fmu_wording(str(warning.message)), Fmi2Status.warning)
        simulator = ContactSimulator(contact, start_time=self._start_time)
        self._simulator, self._built_for = simulator, parameters
        self._running, self._phase = simulator, _Phase.RUNNING
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
            f"{summary['critical_speed_m_s']:.4g} m/s, {settings.law} contact; core tire_fmu "
            f"{tire_fmu.__version__} from {tire_fmu.__file__}")

    def _reject(self, problems: list[str]) -> None:
        for number, problem in enumerate(problems, 1):
            self.log(f"parameter problem {number}/{len(problems)}: {_fmu_wording(problem)}",
                     Fmi2Status.error)
        self._stop(_Phase.REJECTED,
                   f"the parameters were rejected when initialisation ended "
                   f"({len(problems)} problem(s), logged then: "
                   f"{'; '.join(_fmu_wording(p) for p in problems)}); reset the FMU and set "
                   "valid parameters")
        self.log("TireModal cannot run: " + self._why_not_running, Fmi2Status.error)

    def _stop(self, phase: str, why: str) -> None:
        self._phase, self._why_not_running, self._running = phase, why, None

    def _show(self, outputs: dict, in_contact: bool) -> None:
        for name, value in outputs.items():
            self._values[self._index[name]] = value
        self._values[self._index["in_contact"]] = in_contact

    # -- messages ----------------------------------------------------------------------------
    def _discard(self, message: str) -> bool:
        self.log(message, Fmi2Status.discard)
        return False

    def _warn_zone_edge(self, at_time: float) -> None:
        self._contact_warning_armed = False
        self.log(f"t = {at_time:.9g} s: the footprint reached the end of the contact zone, so "
                 "road forces beyond it are missing; raise contact_zone_length (logged once "
                 "until the footprint is back inside)", Fmi2Status.warning)

    # -- variable access: pythonfmu's generic versions cost a lambda per value and raise on
    # a bad reference (fmi2Fatal, see the module doc); these index one list and log instead.
    def _refresh(self) -> None:
        """Outputs at the current time for the inputs set since the last step."""
        self._stale = False
        values = self._values
        try:
            outputs = self._running.outputs_with(values[0], values[1], values[2], values[3])
        except StepError as error:
            self.log(f"outputs kept from the last step: {error}", Fmi2Status.warning)
            return
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self.log(f"outputs kept from the last step: {type(error).__name__}: {error}",
                     Fmi2Status.error)
            return
        values[OUTPUTS] = outputs
        values[IN_CONTACT] = outputs[2] > 0.0

    def get_real(self, vrs):
        if self._stale:
            self._refresh()
        values = self._values
        if vrs == self._output_vrs:  # the host's usual call: the four forces, in order
            return values[OUTPUTS]
        try:
            return [values[vr] for vr in vrs]
        except (IndexError, TypeError):
            return self._get_checked(vrs, float, math.nan)

    def get_integer(self, vrs):
        return self._get_checked(vrs, int, 0)

    def get_boolean(self, vrs):
        if self._stale:
            self._refresh()
        return self._get_checked(vrs, bool, False)

    def get_string(self, vrs):
        if vrs:
            self.log(f"fmi2GetString{list(vrs)}: TireModal has no String variables",
                     Fmi2Status.error)
        return ["" for _ in vrs]

    def set_real(self, vrs, values):
        if vrs == self._input_vrs:  # the host's usual call: all four inputs, in order
            self._values[INPUTS] = values
            self._stale = self._running is not None
        else:
            for vr, value in zip(vrs, values):
                self._set(vr, value, "Real")

    def set_integer(self, vrs, values):
        for vr, value in zip(vrs, values):
            self._set(vr, value, "Integer")

    def set_boolean(self, vrs, values):
        for vr, value in zip(vrs, values):
            self._set(vr, bool(value), "Boolean")

    def set_string(self, vrs, values):
        if vrs:
            self.log(f"fmi2SetString{list(vrs)}: TireModal has no String variables",
                     Fmi2Status.error)

    def _get_checked(self, vrs, convert, fallback):
        result = []
        for vr in vrs:
            try:
                result.append(convert(self._values[vr]))
            except (IndexError, TypeError, ValueError, OverflowError):
                self.log(f"value reference {vr!r} cannot be read as {convert.__name__} "
                         f"(TireModal has {len(self._values)} variables)", Fmi2Status.error)
                result.append(fallback)
        return result

    def _set(self, vr, value, kind) -> None:
        if not (isinstance(vr, int) and 0 <= vr < len(self._table)):
            self.log(f"value reference {vr!r} does not exist (TireModal has "
                     f"{len(self._table)} variables); ignored", Fmi2Status.error)
            return
        v = self._table[vr]
        if v.type != kind:
            self.log(f"{v.name} has FMI type {v.type}: set it with fmi2Set{v.type}; "
                     "ignored", Fmi2Status.error)
        elif v.causality == "output":
            self.log(f"{v.name} is an output; ignored", Fmi2Status.error)
        elif v.causality == "parameter" and self._phase not in (
                _Phase.INSTANTIATED, _Phase.INITIALISING):
            self.log(f"{v.name} = {value!r} ignored: parameters are fixed after "
                     "initialisation (they define the reduced basis); reset the FMU to change "
                     "them", Fmi2Status.error)
        else:
            self._values[vr] = value
            if v.causality == "input":
                self._stale = self._running is not None
            if v.name == "load":  # the outputs echo the static load until initialised
                self._show({"rim_Fz": value, "contact_Fz": value}, value > 0)

    # -- FMU state ---------------------------------------------------------------------------
    def _get_fmu_state(self):
        try:
            simulator = self._simulator.get_state() if self._simulator is not None else None
            return _Snapshot(tuple(self._values), self._phase, simulator,
                             self._contact_warning_armed)
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self.log(f"fmi2GetFMUstate failed: {type(error).__name__}: {error}",
                     Fmi2Status.error)
            return _InvalidState(f"it was taken when fmi2GetFMUstate failed ({error})")

    def _set_fmu_state(self, state) -> None:
        try:
            self._restore(state)
        except Exception as error:  # an escaping exception would be fmi2Fatal
            self._refuse_state(f"{type(error).__name__}: {error}")

    def _restore(self, state) -> None:
        if isinstance(state, _InvalidState):
            self._refuse_state(state.reason)
            return
        if not isinstance(state, _Snapshot) or len(state.values) != len(self._values):
            self._refuse_state(f"it is not a TireModal state ({type(state).__name__})")
            return
        parameters = tuple(state.values[vr] for vr in self._parameter_vrs)
        if state.simulator is not None and parameters != self._built_for:
            # a state of other parameters, or restored into a fresh instance: build its model
            self._initialise(parameters)
            if self._simulator is None or self._built_for != parameters:
                self._refuse_state("its parameters do not build a model (logged above)")
                return
        if state.simulator is not None:
            self._simulator.set_state(state.simulator)
        self._values[:] = state.values
        self._contact_warning_armed = state.contact_warning_armed
        self._stale = False  # the snapshot's outputs belong to its inputs
        self._phase = state.phase
        self._running = self._simulator if state.phase == _Phase.RUNNING else None
        if state.phase != _Phase.RUNNING:
            self._why_not_running = (f"the restored FMU state was taken in phase "
                                     f"'{state.phase}'")

    def _refuse_state(self, reason: str) -> None:
        self._stop(_Phase.BROKEN, f"an FMU state could not be restored ({reason}); set a valid "
                   "state or reset the FMU")
        self.log(f"fmi2SetFMUstate refused: {reason}; doStep returns fmi2Discard until a valid "
                 "state is set or the FMU is reset", Fmi2Status.error)

    @staticmethod
    def _fmu_state_to_bytes(state) -> bytes:
        # JSON header, a newline (JSON escapes its own), then the simulator's npz bytes: no
        # pickle, so a state file cannot run code when read.
        if isinstance(state, _InvalidState):
            header = {"format": _STATE_FORMAT, "invalid": state.reason}
            return json.dumps(header).encode() + b"\n"
        header = {"format": _STATE_FORMAT, "values": list(state.values), "phase": state.phase,
                  "contact_warning_armed": state.contact_warning_armed}
        simulator = state.simulator.to_bytes() if state.simulator is not None else b""
        return json.dumps(header).encode() + b"\n" + simulator

    @staticmethod
    def _fmu_state_from_bytes(data: bytes):
        try:
            head, _, simulator = bytes(data).partition(b"\n")
            header = json.loads(head.decode())
            if header.get("format") != _STATE_FORMAT:
                return _InvalidState(f"unknown state format {header.get('format')!r}")
            if "invalid" in header:
                return _InvalidState(header["invalid"])
            return _Snapshot(tuple(header["values"]), header["phase"],
                             ContactState.from_bytes(simulator) if simulator else None,
                             bool(header["contact_warning_armed"]))
        except Exception as error:  # an escaping exception would be fmi2Fatal
            return _InvalidState(f"the serialized bytes are not a TireModal state ({error})")


def _baked_parameter_values(resources: str | None) -> dict | None:
    """Tire data the FMU was built for (resources/tire_parameters.json), if any."""
    if not resources:
        return None
    path = os.path.join(resources, BAKED_PARAMETERS_FILE)
    if not os.path.isfile(path):
        return None
    with open(path, encoding="utf-8") as stream:  # written by the builder: small, trusted
        return {str(k): float(v) for k, v in json.load(stream).items()}


def _fmu_wording(message: str) -> str:
    """A core message in the FMU's variable names (the wording the native FMU uses too)."""
    return fmu_message(message)
