"""Everything the Python FMU and the native C FMU must agree on, written once.

The native FMU's C reads these values from ``spec.h``, which :func:`c_header` generates from
this module (``tire_fmu/native/c/spec.h`` is that output, checked in so that the C builds on
its own; a test regenerates it and compares). The values themselves come from the core and
from :mod:`.interface`, which the Python FMU uses directly, so the two runtimes cannot drift:

- numerical rules: time-point tolerance, the step cache (a step within ``SAME_POINT_EPS`` of a
  cached one is that step), substeps, the active-set and Gauss-Seidel limits of the contact
  solve, the footprint continuation's tolerances, the delay line's lag rule, the critical-speed
  scan;
- the variable table: names, types, causalities, value references, start values;
- the parameter ranges (:data:`~tire_fmu.core.parameters.TIRE_FIELDS` and the operating-point
  limits) and the problem messages: printf templates that, filled in with Python's ``%``, give
  exactly the core's messages in the FMU's names (``tests/test_native_fmu.py`` checks each
  against the core), and that the C fills in with the same values;
- the FMI layer: the co-simulation state machine (:data:`PHASES`, :data:`CALLS`: which call
  each phase allows), every message either FMU logs about a call, and the one FMU-state byte
  format (:data:`STATE_LAYOUT`, :func:`state_checksum`), written by the Python FMU's slave and
  by the native FMU's ``fmi2_layer.c``; ``tests/test_fmi_behaviour.py`` runs one suite
  against both.
"""

from __future__ import annotations

import math
import re
import struct
import zlib

from ..core import (
    clock,
    contact,
    contact_dynamics,
    free_ring,
    host_inputs,
    inplane,
    inplane_contact,
    inplane_host,
    kernel_numpy,
    modal_form,
    model,
    parameters,
    road,
    standing_waves,
    step_limits,
    stepping,
    wheel_centre,
)
from .interface import (
    FMU_NAMES,
    FMU_UNSET,
    IN_CONTACT,
    INPUTS,
    MAX_DELAY_STEPS,
    MAX_HISTORY_SAMPLES,
    MAX_STEP_S,
    OUTPUTS,
    ROAD_QUERIES,
    TIME_ABS_TOLERANCE_S,
    TIME_REL_TOLERANCE,
    FmuVariable,
    fmu_variables,
    input_limit,
)

#: Core names -> the FMU's names for the same thing, applied to every core message an FMU logs.
FMU_WORDING = tuple(FMU_NAMES.items())

#: Numbers both runtimes use, by the C name they get in spec.h.
CONSTANTS: dict[str, float | int] = {
    # communication points and the step cache
    "TIME_ABS_TOLERANCE_S": TIME_ABS_TOLERANCE_S,
    "TIME_REL_TOLERANCE": TIME_REL_TOLERANCE,
    "MAX_STEP_S": MAX_STEP_S,
    "MAX_DELAY_STEPS": MAX_DELAY_STEPS,
    "MAX_HISTORY_SAMPLES": MAX_HISTORY_SAMPLES,
    "SAME_POINT_EPS": road.SAME_POINT_EPS,
    "LAG_SLACK": road.LAG_SLACK,
    "MAX_SUBSTEP_S": contact_dynamics.MAX_SUBSTEP_S,
    "MIN_CORRECTED_STEP_S": contact_dynamics.MIN_CORRECTED_STEP_S,
    "MIN_SUBSTEP_S": contact_dynamics.MIN_SUBSTEP_S,
    "SUBSTEP_WORK_BASE": step_limits.SUBSTEP_WORK_BASE,
    "SUBSTEP_WORK_PER_MODE": step_limits.SUBSTEP_WORK_PER_MODE,
    "SUBSTEP_WORK_PER_ORDER_NODE": step_limits.SUBSTEP_WORK_PER_ORDER_NODE,
    "SUBSTEP_WORK_PER_SUPPORT": step_limits.SUBSTEP_WORK_PER_SUPPORT,
    "SUBSTEP_WORK_PER_POINT": step_limits.SUBSTEP_WORK_PER_POINT,
    "SUBSTEP_WORK_PER_NODE_PAIR": step_limits.SUBSTEP_WORK_PER_NODE_PAIR,
    "SUBSTEP_WORK_PER_RATE_ENTRY": step_limits.SUBSTEP_WORK_PER_RATE_ENTRY,
    "MAX_STEP_WORK": step_limits.MAX_STEP_WORK,
    "WORK_INTERVAL_S": step_limits.WORK_INTERVAL_S,
    "SUBSTEP_SLACK": kernel_numpy.SUBSTEP_SLACK,
    "SERIES_LIMIT": stepping.SERIES_LIMIT,
    "KERNEL_CACHE_SIZE": kernel_numpy.KERNEL_CACHE_SIZE,
    # the inputs a step accepts (beyond them a product inside the step could overflow)
    "MAX_DISPLACEMENT_M": contact_dynamics.MAX_DISPLACEMENT_M,
    "MAX_VELOCITY_M_S": contact_dynamics.MAX_VELOCITY_M_S,
    "MAX_ROAD_POSITION_M": step_limits.MAX_ROAD_POSITION_M,
    "MAX_TORQUE_N_M": step_limits.MAX_TORQUE_N_M,
    # what an FMU state may hold (a state is checked for what it means)
    "MAX_STATE_DISPLACEMENT_M": contact_dynamics.MAX_STATE_DISPLACEMENT_M,
    "MAX_STATE_VELOCITY_M_S": contact_dynamics.MAX_STATE_VELOCITY_M_S,
    # the contact solve
    "ACTIVE_SET_PER_NODE": kernel_numpy.ACTIVE_SET_PER_NODE,
    "ACTIVE_SET_EXTRA": kernel_numpy.ACTIVE_SET_EXTRA,
    "PGS_SWEEPS": kernel_numpy.PGS_SWEEPS,
    "PGS_TOLERANCE": kernel_numpy.PGS_TOLERANCE,
    # the zone and the static footprint
    "DEFAULT_ZONE_LENGTH_M": contact.DEFAULT_ZONE_LENGTH_M,
    "MAX_ZONE_HALF_ANGLE": contact.MAX_ZONE_HALF_ANGLE,
    "ZONE_ANGLE_SLACK": contact.ZONE_ANGLE_SLACK,
    "EVENT_TOLERANCE": contact._EVENT_TOLERANCE,
    "EVENTS_TOGETHER": contact.EVENTS_TOGETHER,
    "TOUCH_ATOL": contact.TOUCH_ATOL,
    "SEGMENTS_PER_NODE": contact.SEGMENTS_PER_NODE,
    "MAX_DEFLECTION_FRACTION": contact.MAX_DEFLECTION_FRACTION,
    "LENGTH_BISECTIONS": contact.LENGTH_BISECTIONS,
    # the contact points
    "DEFAULT_POINT_SPACING_M": parameters.DEFAULT_POINT_SPACING_M,
    "MIN_POINT_SPACING_M": parameters.MIN_POINT_SPACING_M,
    "MAX_POINT_SPACING_M": parameters.MAX_POINT_SPACING_M,
    "POINT_SPACING_SLACK": contact.POINT_SPACING_SLACK,
    "MAX_CONTACT_POINTS": contact.MAX_CONTACT_POINTS,
    "MOST_POINTS_PER_NODE": contact._MOST_PER_NODE,
    "MAX_PATCH_FRACTION": parameters.MAX_PATCH_FRACTION,
    # the free ring's modes: their canonical normalisation and order
    "MODE_TIE_TOLERANCE": modal_form.MODE_TIE_TOLERANCE,
    # the critical speed
    "CRITICAL_SPEED_WARNING_FRACTION": model.CRITICAL_SPEED_WARNING_FRACTION,
    "MAX_SCANNED_SPEED_M_S": standing_waves.MAX_SCANNED_SPEED_M_S,
    "SCAN_POINTS": standing_waves.SCAN_POINTS,
    "ROOT_TOLERANCE": standing_waves.ROOT_TOLERANCE,
    # parameter limits
    "MIN_ELEMENTS": parameters.MIN_ELEMENTS,
    "MAX_ELEMENTS": parameters.MAX_ELEMENTS,
    "F_MAX_LIMIT_HZ": free_ring.F_MAX_LIMIT_HZ,
    "N_MODES_LIMIT": free_ring.N_MODES_LIMIT,
    "MIN_ROLLING_SPEED_M_S": parameters.MIN_ROLLING_SPEED_M_S,
    "MIN_LAW_PRESSURE_PA": parameters.MIN_LAW_PRESSURE_PA,
    "SIDEWALL_TIE_FACTOR": parameters.SIDEWALL_TIE_FACTOR,
    # the in-plane ring's hysteretic loss: the road speed of its full share
    "HYSTERESIS_FULL_SPEED_M_S": inplane.HYSTERESIS_FULL_SPEED_M_S,
    # the in-plane FMU's operating point and its step's rules (core/inplane_host.py,
    # core/inplane_contact.py)
    "INPLANE_CRITICAL_SPEED_FRACTION": inplane_host.CRITICAL_SPEED_FRACTION,
    "INPLANE_MAX_DEFLECTION_FRACTION": inplane_host.MAX_DEFLECTION_FRACTION,
    "INPLANE_HOST_ROAD_MARGIN_M": inplane_contact.HOST_ROAD_MARGIN_M,
    "INPLANE_SPIN_REBUILD_FRACTION": inplane_contact.SPIN_REBUILD_FRACTION,
    "INPLANE_RING_REBUILD_FRACTION": inplane_contact.RING_REBUILD_FRACTION,
    "INPLANE_MAX_SET_PASSES": inplane_contact.MAX_SET_PASSES,
    "INPLANE_SETTLE_PASSES": inplane_contact.SETTLE_PASSES,
    "INPLANE_MIN_ENTERING_FRACTION": inplane_contact.MIN_ENTERING_FRACTION,
    "INPLANE_STATE_SPIN_FACTOR": inplane_contact.STATE_SPIN_FACTOR,
    "INPLANE_MIN_STEP_S": host_inputs.MIN_STEP_S,
    "INPLANE_STATE_BASIS_TOLERANCE": inplane_contact.STATE_BASIS_TOLERANCE,
    "INPLANE_MAX_FORCE_LOADS": inplane_contact.MAX_FORCE_LOADS,
    "INPLANE_STATE_DEFORMATION_FRACTION": inplane_contact.STATE_DEFORMATION_FRACTION,
    "INPLANE_MAX_ROAD_SAMPLES": inplane_contact.MAX_ROAD_SAMPLES,
    "SLIP_SPEED_FLOOR_M_S": wheel_centre.SLIP_SPEED_FLOOR_M_S,
    "ROAD_QUERY_SLACK_M": wheel_centre.ROAD_QUERY_SLACK_M,
    "ROAD_QUERY_FLOOR_SHARE": wheel_centre.QUERY_FLOOR_SHARE,
    "ROAD_QUERIES": ROAD_QUERIES,
    # what double precision resolves
    "MAX_STIFFNESS_RATIO": parameters.MAX_STIFFNESS_RATIO,
    "MAX_EIGENVALUE_SPREAD": model.MAX_EIGENVALUE_SPREAD,
}

#: Problem messages, as printf templates. A value is passed as the core's
#: :func:`~tire_fmu.core.parameters.value_text` writes it (the C has value_text for it, with
#: the unit), ``%g`` and friends take numbers. Each is the core's own text for that problem
#: (tests/test_native_fmu.py renders both and compares).
MESSAGES: dict[str, str] = {
    # how any problem reads: name, value text, what is allowed; then the reason
    "PROBLEM": parameters.PROBLEM_TEMPLATE,
    "REASON": parameters.REASON_TEMPLATE,
    # tire data (TIRE_FIELDS): name, value text, range text, description
    "FIELD_NOT_FINITE": "%s = %s: must be a finite number in %s (%s)",
    "FIELD_RANGE": "%s = %s: must be in %s (%s)",
    "FIELD_INTEGER": "%s = %s: must be an integer in %s (%s)",
    # the pressure law (inflation_pressure as a value text, the floor, the exponent)
    "PRESSURE_LAW": (f"inflation_pressure = %s: must be {parameters.PRESSURE_LAW_ALLOWED} "
                     f"({parameters.PRESSURE_LAW_REASON})"),
    # operating point
    "ELEMENTS_RANGE": f"n_elements = %d: must be an integer in [%d, %d] "
                      f"({parameters.ELEMENTS_REASON})",
    "NOT_NONNEGATIVE": "%s = %s: must be a finite number >= 0 %s",
    "MIN_ROLLING_SPEED": "speed = %s: must be 0 or at least %g m/s (slower is at rest to "
                         "rounding, and the road would take days to cross the patch)",
    # truncation
    "F_MAX_RANGE": "f_max = %s: must be in (0, %g] Hz, or 0 for no limit",
    "N_MODES_RANGE": "n_modes = %d: must be an integer in [1, %d], or 0 for no limit",
    # the conditioning of the static solution (parameters.conditioning_problems)
    "CONDITIONING_REASON": parameters.CONDITIONING_REASON,
    "CONDITIONING_STIFF_ALLOWED": parameters.CONDITIONING_STIFF_ALLOWED,
    "CONDITIONING_WEAK_ALLOWED": parameters.CONDITIONING_WEAK_ALLOWED,
    "CONDITIONING_WEAK_LARGER": parameters.CONDITIONING_WEAK_LARGER,
    **{f"STIFF_TERM_{field.upper()}": what for field, what in parameters.STIFF_TERMS.items()},
    # what needs the model
    "SUPERCRITICAL": "speed = %s: must be below the critical (standing-wave) speed %.4g m/s "
                     "of this mesh (n_elements = %d); with sidewall_max_order = 0 a finer mesh "
                     "lowers it, sidewall_max_order = 8 (the GL073A_tied tire) makes it "
                     "converge, allow_supercritical runs anyway",
    "NEAR_CRITICAL": "speed %g m/s is %.0f %% of the critical speed %.4g m/s (n_elements = %d): "
                     "modes near zero ground frequency dominate the response",
    "ZONE_RANGE": "contact_zone_length = %s: must be in (0, %.4g] m (at most 60 degrees of "
                  "the ring either side of the contact centre)",
    "ZONE_TOO_SHORT": "contact_zone_length = %s: must be at least %.4g m (one node either "
                      "side), or refine the mesh (it holds only the centre node of a mesh of %d "
                      "elements)",
    "POINT_SPACING_ALLOWED": parameters.POINT_SPACING_ALLOWED,
    "POINT_SPACING_REASON": parameters.POINT_SPACING_REASON,
    "POINTS_ALLOWED": contact.POINTS_ALLOWED,
    "POINTS_REASON": contact.POINTS_REASON,
    "LOAD_RANGE": "load = %s: must be in [0, %.6g] N for this tire and mesh; at %.6g N "
                  "(deflection %.3g mm) %s",
    # the in-plane FMU's static footprint not found (the load, k_cw as a value, n_elements)
    "INPLANE_FOOTPRINT_ALLOWED": inplane_host.FOOTPRINT_ALLOWED,
    "INPLANE_FOOTPRINT_REASON": inplane_host.FOOTPRINT_REASON,
    "LOAD_REASON_ZONE": "its footprint reaches the end of the contact zone (raise "
                        "contact_zone_length)",
    "LOAD_REASON_LENGTH": "its footprint reaches %.4g m, beyond which the linear ring is not "
                          "credible",
    # the eigenvalues double precision resolves (model.check_resolved)
    "RESOLVED_ALLOWED": model.RESOLVED_ALLOWED,
    "RESOLVED_REASON": model.RESOLVED_REASON,
    "RESOLVED_SPREAD": model.RESOLVED_SPREAD,
    "RESOLVED_SPREAD_UNBOUNDED": model.RESOLVED_SPREAD_UNBOUNDED,
    **{f"RESOLVED_{key}_{field.upper()}": text
       for field, way, what in model.RESOLVED_CANDIDATES
       for key, text in (("WAY", way), ("WHAT", what))},
    # the native FMU only: its eigen-solver for an order did not converge (LAPACK, in the
    # Python FMU, may still solve it)
    "RING_NOT_COMPUTED": "the native FMU could not compute the free ring's modes for these "
                         "parameters (the QR iteration of an order did not converge); the fastest "
                         "modes are %s (stiffness over mass %.3g 1/s^2): %s %s makes them "
                         "tractable, or the Python FMU (TireModal.fmu) may solve them",
    "PROBLEM_LINE": "parameter problem %d/%d: %s",
    # the clock (core.clock): a step it does not resolve, a start time it resolves no step at
    "CLOCK_RESOLUTION": clock.RESOLUTION_TEMPLATE,
    "START_UNRESOLVED": "startTime = %s s: must be at most %.4g s in magnitude: beyond it a "
                        "clock of doubles resolves no step the FMU takes (at most %g s)",
    # the running FMU
    "SHORT_STEP_CORRECTED": contact_dynamics.SHORT_STEP_TEMPLATE,
    "LONG_STEP": step_limits.LONG_STEP_TEMPLATE,
    "STIFF_CONTACT_ALLOWED": step_limits.STIFF_CONTACT_ALLOWED,
    "STIFF_CONTACT_REASON": step_limits.STIFF_CONTACT_REASON,
    "SUBSTEP_ALLOWED": contact_dynamics.SUBSTEP_ALLOWED,
    "SUBSTEP_REASON": contact_dynamics.SUBSTEP_REASON,
    "ZONE_EDGE": "t = %.9g s: the footprint reached the end of the contact zone, so road forces "
                 "beyond it are missing; raise contact_zone_length (logged once until the "
                 "footprint is back inside)",
    # the tread leaving the road and landing (status OK, category logEvents): physics
    "LIFT_OFF": "t = %.9g s: the tread left the road (in_contact = false)",
    "TOUCH_DOWN": "t = %.9g s: the tread is back on the road (in_contact = true)",
    # -- the FMI layer (both FMUs): a refused call, and why
    "REFUSED": "%s refused: %s; nothing changed",
    "PHASE": "the FMU is %s",
    "ERROR_STATE": "the FMU is in the error state; reset it or set an FMU state",
    # why the FMU is in the error state: what failed, and how
    "FAILED": "the FMU is in the error state: %s failed (%s); reset it or set an FMU state",
    "PARAMETERS_REFUSED": "the parameters were refused at fmi2ExitInitializationMode "
                          "(%d problem(s): %s); reset the FMU and set valid parameters",
    "EXIT_REFUSED": "fmi2ExitInitializationMode refused: %s",
    "STEP_FAILED": "the step from t = %s s",
    "OUTPUTS_FAILED": "computing the outputs",
    "NOT_FINITE_OUTPUTS": "its outputs are not finite",
    "OUT_OF_MEMORY": "out of memory",
    # fmi2SetupExperiment
    "START_NOT_FINITE": "startTime = %s s: must be finite",
    "STOP_TIME": "stopTime = %s s: must be finite and >= startTime = %s s",
    "TOLERANCE": "tolerance = %s: must be finite and > 0",
    # fmi2DoStep: the call as refusals name it (t, h), then why
    "STEP_CALL": "fmi2DoStep(t = %s s, h = %s s)",
    "NOT_LAST_POINT": "t = %s s: must be the last communication point t = %s s (roll back "
                      "with fmi2SetFMUstate to step from an earlier time)",
    "STEP_RANGE": "step size h = %s s: must be in (0, %g] s",
    "INPLANE_STEP_SHORT": "step size h = %s s: must be at least %g s, the in-plane tire's "
                          "shortest step",
    "INPLANE_SPIN_LIMIT": inplane_contact.SPIN_LIMIT_TEMPLATE,
    "INPLANE_SPEED_LIMIT": inplane_contact.SPEED_LIMIT_TEMPLATE,
    "INPLANE_FORCE_LIMIT": inplane_contact.FORCE_LIMIT_TEMPLATE,
    "STEP_DELAY": "step size h = %s s: must be at least %.3g s at this speed: the road "
                  "reaches the contact zone's last node %.3g s after its front, and the FMU "
                  "keeps at most %d steps of its history",
    "NO_STEP_PENDING": "no step is pending (fmi2DoStep always completes)",
    # values (a value shown as parameters.value_text shows it, an input as repr and unit)
    "INPUT_RANGE": "%s = %s %s: must be in [-%g, %g] %s",
    "REFERENCE_MISSING": "value reference %u: it does not exist (%s has %d variables)",
    "REFERENCE_TYPE": "value reference %u: %s has FMI type %s: use fmi2Get%s and fmi2Set%s",
    "OUTPUT_SET": "%s = %s: it is an output",
    "PARAMETER_FIXED": "%s = %s: parameters are fixed after initialisation (they define the "
                       "model built there); reset the FMU to change them",
    "NO_STRINGS": "%s has no String variables",
    "ROAD_FILE_ALLOWED": "an OpenCRG .crg or a two-column profile (distance m, height m) "
                         "file that can be read",
    "ROAD_EXTENT": "at t = %s s the contact zone (wheel_x = %s m) reaches beyond the road file "
                   "%s (%.6g to %.6g m along it): the road is level at its end heights there "
                   "(said again if it leaves the file's road again after coming back)",
    # FMU states (STATE_LAYOUT): the bytes, then what they mean
    "STATE_NOT_OURS": "it is not a state of this FMU (%s)",
    "STATE_TOO_SHORT": "too short",
    "STATE_NO_HEADER": "no state header",
    "STATE_SIZE": "it says it has %lu bytes, but %lu were given",
    "STATE_DAMAGED": "it is damaged: its checksum does not match",
    "STATE_VERSION": "its format version is %u, this FMU reads %d",
    "STATE_GUID": "it belongs to the FMU with GUID %s, not this one (%s)",
    "STATE_PHASE": "its phase %u is not one of this FMU's",
    "STATE_CLOCK": "its time %s s, start time %s s or flags are not valid",
    "STATE_START": "its %s",
    "STATE_BEFORE_INIT": "its time is %s s before initialisation, not its start time %s s",
    "STATE_VALUE": "its value of %s is not a valid %s",
    "STATE_INPUT": "its %s",
    "STATE_MODEL_SIZE": "its model part has the wrong size",
    "STATE_STRINGS": "its String values are not one NUL-ended UTF-8 text per String variable",
    "STATE_MODEL_PHASE": "its model part does not fit its phase",
    "STATE_NO_REASON": "its phase is error without the reason: it would refuse every call "
                       "without saying why",
    "STATE_REASON_PHASE": "it holds an error reason, but its phase is %s",
    "STATE_REASON_NUL": "its error reason holds a NUL byte",
    "STATE_PARAMETERS": "its parameters do not build a model: %s",
    "STATE_MODEL_SHORT": "its model part is %lu bytes, shorter than its header",
    "STATE_MODEL_FLAG": "flag %d of its model part is %d, not 0 or 1",
    "STATE_MODEL_CLOCK": "its time is %s s from a start at %s s, but its model is at %s s from "
                         "a start at %s s",
    "STATE_MODEL_OUTPUTS": "the outputs it shows are not its model's",
}

# -- the FMI 2.0 co-simulation state machine ------------------------------------------------
#: The phases both FMUs can be in, in the order of their numbers (a state's phase field, the
#: bit of a call mask), with what each is as a refusal says it ("the FMU is ..."). FMI 2.0's
#: stepComplete is "running": a step always completes (no stepInProgress, stepFailed or
#: stepCanceled). "error" is FMI's error state: the parameters were refused at
#: fmi2ExitInitializationMode (no model to step), or a failure left none (out of memory,
#: outputs that are not finite); reset, or set an FMU state, to leave it. A call refused for
#: its arguments or its phase changes nothing, the phase included, so a host may correct it
#: and call again (more than FMI 2.0 promises after fmi2Error, never less).
PHASES: dict[str, str] = {
    "instantiated": "instantiated (call fmi2SetupExperiment and fmi2EnterInitializationMode "
                    "first)",
    "initialisation": "in initialisation mode (call fmi2ExitInitializationMode first)",
    "running": "running (initialisation ended; fmi2Reset starts over)",
    "terminated": "terminated (fmi2Reset starts over)",
    "error": "in the error state",
}


class Phase:
    """The phases by number (plain ints: the slave compares them on its hot path)."""

    INSTANTIATED, INITIALISATION, RUNNING, TERMINATED, ERROR = range(5)
    NAMES = tuple(PHASES)


_ALL = tuple(PHASES)
_GETTERS = ("initialisation", "running", "terminated", "error")
_SETTERS = ("instantiated", "initialisation", "running")
#: Per FMI call, the phases that allow it: FMI 2.0.4, section 4.2.4 (the table of the
#: co-simulation state machine), as the Reference-FMUs' masks have it. A call its phase does
#: not allow is refused (fmi2Error) with :data:`MESSAGES` REFUSED and the phase's text.
CALLS: dict[str, tuple[str, ...]] = {
    "fmi2SetDebugLogging": _ALL,
    "fmi2SetupExperiment": ("instantiated",),
    "fmi2EnterInitializationMode": ("instantiated",),
    "fmi2ExitInitializationMode": ("initialisation",),
    "fmi2Terminate": ("running",),
    "fmi2Reset": _ALL,
    **{f"fmi2Get{kind}": _GETTERS for kind in ("Real", "Integer", "Boolean", "String")},
    **{f"fmi2Set{kind}": _SETTERS for kind in ("Real", "Integer", "Boolean", "String")},
    **{call: _ALL for call in ("fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate",
                               "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate",
                               "fmi2DeSerializeFMUstate")},
    "fmi2GetDirectionalDerivative": _GETTERS,
    "fmi2SetRealInputDerivatives": _SETTERS,
    "fmi2GetRealOutputDerivatives": ("running", "terminated", "error"),
    "fmi2DoStep": ("running",),
    # FMI allows it in stepInProgress only, which never occurs; while running it is refused
    # for that reason (no step is pending) rather than for the phase
    "fmi2CancelStep": ("running",),
    **{f"fmi2Get{kind}Status": ("running", "terminated")
       for kind in ("", "Real", "Integer", "Boolean", "String")},
}
#: The calls pythonfmu's wrapper (and the Python FMU's Linux guard in front of it) answers
#: without asking the slave: there the Python FMU follows pythonfmu, not this table (the FMU
#: state calls among them are allowed in every phase anyway).
PYTHONFMU_ANSWERS = ("fmi2SetDebugLogging", "fmi2Reset", "fmi2FreeFMUstate",
                     "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate",
                     "fmi2DeSerializeFMUstate", "fmi2GetDirectionalDerivative",
                     "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives",
                     "fmi2CancelStep", "fmi2GetStatus", "fmi2GetRealStatus",
                     "fmi2GetIntegerStatus", "fmi2GetBooleanStatus", "fmi2GetStringStatus")


def call_mask(call: str) -> int:
    """The phases that allow ``call``, one bit per phase (bit i: phase number i)."""
    return sum(1 << Phase.NAMES.index(phase) for phase in CALLS[call])


#: Each call's mask, as the slave checks it: ``CALL_MASKS[call] >> phase & 1``.
CALL_MASKS: dict[str, int] = {call: call_mask(call) for call in CALLS}


def phase_refusal(phase: int, reason: str = "") -> str:
    """Why a call the phase does not allow is refused: the phase, or in the error state
    the reason the FMU is there."""
    if phase == Phase.ERROR:
        return reason or MESSAGES["ERROR_STATE"]
    return MESSAGES["PHASE"] % PHASES[Phase.NAMES[phase]]


# -- the FMU state: one byte format for both FMUs ----------------------------------------------
#: Serialized FMU states start with these bytes, then this version.
STATE_MAGIC = "TIREFMUS"
STATE_VERSION = 4
#: The longest GUID a state holds (its field is NUL padded to STATE_GUID_BYTES).
STATE_GUID_BYTES = 48
#: The fields of a state in order: (name, struct format or a size rule, meaning). Little-
#: endian, no padding. An FMU state *is* these bytes (fmi2GetFMUstate makes them, serialize
#: copies them), in both FMUs; each puts its own GUID, and refuses a state of another.
STATE_LAYOUT = (
    ("magic", "8s", "STATE_MAGIC"),
    ("version", "<I", "STATE_VERSION"),
    ("phase", "<I", "the phase's number (PHASES)"),
    ("guid", f"{STATE_GUID_BYTES}s", "the GUID of the FMU that made it, NUL padded"),
    ("size", "<Q", "the state's size in bytes, this header and the checksum included"),
    ("time", "<d", "the last communication point (s; the start time before initialisation)"),
    ("start_time", "<d", "the start time (s)"),
    ("stale", "<I", "1 if inputs were set since the outputs were computed, else 0"),
    ("reason_size", "<I", "bytes of the error reason (0 unless the phase is error)"),
    ("strings_size", "<I", "bytes of the String variables' values"),
    ("values", "<V d", "every variable's value by value reference (Integer and Boolean exact)"),
    ("model_size", "<Q", "bytes of the model part (0 unless running or terminated)"),
    ("model", "model_size", "the model part: int32 zone warning armed, int32 in contact (the "
                            "last in_contact an event was logged for), then the step kernel's "
                            "state (kernel.c's kernel_state_write)"),
    ("strings", "strings_size", "each String variable's value by value reference, UTF-8, "
                                "each ended by a NUL"),
    ("reason", "reason_size", "the error reason, UTF-8 without NUL"),
    ("checksum", "<I", "CRC-32 (zlib's, IEEE 802.3) of every byte before it"),
)
#: Bytes before the values, and the model part's two int32 flags.
STATE_HEAD = 8 + 4 + 4 + STATE_GUID_BYTES + 8 + 8 + 8 + 4 + 4 + 4
STATE_MODEL_FLAGS = 2


def state_fixed_size(n_values: int) -> int:
    """A state's size without its model part and reason."""
    return STATE_HEAD + 8 * n_values + 8 + 4


def state_checksum(data: bytes) -> int:
    """The checksum of a state: CRC-32 of ``data`` (every byte before the checksum field).
    It finds any change of up to 32 consecutive bits for sure, any other with probability
    1 - 2^-32; anyone can recompute it, so a state is also checked for what it means."""
    return zlib.crc32(data) & 0xFFFFFFFF


def state_pack(phase: int, guid: str, time: float, start_time: float, stale: bool,
               values, model: bytes = b"", reason: str = "", strings=()) -> bytes:
    """The state bytes of these fields (both FMUs write exactly these); ``strings``: the String
    variables' values in value-reference order."""
    guid_bytes = guid.encode()
    reason_bytes = reason.encode()
    string_bytes = b"".join(str(text).encode() + b"\0" for text in strings)
    if len(guid_bytes) >= STATE_GUID_BYTES:
        raise ValueError(f"GUID {guid!r}: at most {STATE_GUID_BYTES - 1} bytes")
    size = state_fixed_size(len(values)) + len(model) + len(string_bytes) + len(reason_bytes)
    body = b"".join([
        struct.pack(f"<8sII{STATE_GUID_BYTES}sQddIII", STATE_MAGIC.encode(), STATE_VERSION,
                    phase, guid_bytes, size, time, start_time, int(stale), len(reason_bytes),
                    len(string_bytes)),
        struct.pack(f"<{len(values)}d", *(float(v) for v in values)),
        struct.pack("<Q", len(model)), model, string_bytes, reason_bytes])
    return body + struct.pack("<I", state_checksum(body))


def state_unpack(data: bytes, n_values: int) -> dict:
    """The fields of state bytes whose sizes are sound (see :data:`STATE_LAYOUT`; the checks
    of what they hold are the FMUs')."""
    (magic, version, phase, guid, size, time, start, stale, reason_size,
     strings_size) = struct.unpack_from(f"<8sII{STATE_GUID_BYTES}sQddIII", data, 0)
    values = struct.unpack_from(f"<{n_values}d", data, STATE_HEAD)
    at = STATE_HEAD + 8 * n_values
    (model_size,) = struct.unpack_from("<Q", data, at)
    model = data[at + 8:at + 8 + model_size]
    strings = data[at + 8 + model_size:at + 8 + model_size + strings_size]
    reason = data[at + 8 + model_size + strings_size:len(data) - 4]
    (checksum,) = struct.unpack_from("<I", data, len(data) - 4)
    return {"magic": magic, "version": version, "phase": phase,
            "guid": guid.rstrip(b"\0").decode(errors="replace"), "size": size, "time": time,
            "start_time": start, "stale": stale, "reason_size": reason_size, "values": values,
            "model_size": model_size, "model": model, "model_at": at + 8,
            "strings_size": strings_size, "strings": strings, "reason": reason,
            "checksum": checksum}


def state_reseal(data: bytes) -> bytes:
    """State bytes with their checksum recomputed (a tool to forge states in tests: setting
    one checks what it means)."""
    return data[:-4] + struct.pack("<I", state_checksum(data[:-4]))

#: Log categories of the native FMU (model description and C), and what each carries.
LOG_CATEGORIES = {
    "logEvents": "the tread leaving the road and coming back (status OK, information)",
    "logStatusWarning": "messages with status fmi2Warning (the footprint at the end of the "
                        "contact zone, a speed near the critical speed)",
    "logStatusError": "messages with status fmi2Error (every refused call, with its reason)",
    "logAll": "all messages, including the summary when the model is built",
}

#: Value references of the hot path (inputs, outputs and in_contact are contiguous blocks).
VALUE_REFERENCES = {"INPUTS_FIRST": INPUTS.start, "N_INPUTS": INPUTS.stop - INPUTS.start,
                    "OUTPUTS_FIRST": OUTPUTS.start, "N_OUTPUTS": OUTPUTS.stop - OUTPUTS.start,
                    "IN_CONTACT": IN_CONTACT}


def value_references(variables: tuple[FmuVariable, ...]) -> dict[str, int]:
    """The hot path's blocks of a variable table, as :data:`VALUE_REFERENCES` (the radial
    FMU's): the inputs first, then the Real outputs, then in_contact."""
    inputs = [vr for vr, v in enumerate(variables) if v.causality == "input"]
    outputs = [vr for vr, v in enumerate(variables)
               if v.causality == "output" and v.type == "Real"]
    in_contact = [v.name for v in variables].index("in_contact")
    if inputs != list(range(len(inputs))) or outputs != list(
            range(len(inputs), len(inputs) + len(outputs))) or in_contact != len(
            inputs) + len(outputs):
        raise ValueError("the variable table's inputs, Real outputs and in_contact must be "
                         "contiguous blocks, in that order, from value reference 0")
    return {"INPUTS_FIRST": 0, "N_INPUTS": len(inputs), "OUTPUTS_FIRST": len(inputs),
            "N_OUTPUTS": len(outputs), "IN_CONTACT": in_contact}


def fmu_message(text: str) -> str:
    """A core message in the FMU's names for the parameters and for "no limit"."""
    for core, fmu in FMU_WORDING:
        text = re.sub(rf"\b{core}\b", fmu, text)
    return re.sub(r"^((?:f_max|n_modes) = .*) or None\b", rf"\1 or {FMU_UNSET}", text)


# -- the C header ------------------------------------------------------------------------------

def _c_number(value: float | int) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int):
        return str(value)
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{value!r}: the spec holds finite numbers only")
    return repr(value)  # reads back to the same double


def _crc32_table() -> list[int]:
    table = []
    for n in range(256):
        c = n
        for _ in range(8):
            c = 0xEDB88320 ^ (c >> 1) if c & 1 else c >> 1
        table.append(c)
    return table


def _c_call(call: str) -> str:
    """fmi2GetFMUstate -> SPEC_CALL_GET_FMUSTATE."""
    return "SPEC_CALL_" + re.sub(r"(?<=[a-z])(?=[A-Z])", "_", call[4:]).upper()


def _c_string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"')
    return f'"{escaped}"'


_C_TYPES = {"Real": "SPEC_REAL", "Integer": "SPEC_INTEGER", "Boolean": "SPEC_BOOLEAN",
            "String": "SPEC_STRING"}
_C_CAUSALITY = {"input": "SPEC_INPUT", "output": "SPEC_OUTPUT", "parameter": "SPEC_PARAMETER"}


def _variable_row(v: FmuVariable) -> str:
    start = 0.0 if v.start is None or v.type == "String" else float(v.start)
    limit = input_limit(v) if v.causality == "input" else 0.0
    return (f"    {{{_c_string(v.name)}, {_C_TYPES[v.type]}, {_C_CAUSALITY[v.causality]}, "
            f"{_c_number(start)}, {_c_string(v.unit)}, {_c_number(float(limit))}}},")


def _field_row(f: parameters.FieldSpec, name: str) -> str:
    """A SpecField row: a FieldSpec under the FMU's name for it."""
    return (f"    {{{_c_string(name)}, {_c_string(f.unit)}, {_c_string(f.description)}, "
            f"{_c_string(f.range_text())}, {_c_number(float(f.low))}, {_c_number(float(f.high))}, "
            f"{int(f.low_inclusive)}, {int(f.integer)}}},")


def c_header(variables: tuple[FmuVariable, ...] | None = None) -> str:
    """spec.h: this module as C (constants, variable table, tire fields, messages)."""
    variables = variables or fmu_variables()
    lines = [
        "/* spec.h: what the Python FMU and this C agree on. GENERATED by",
        " * tire_fmu.fmu.spec.c_header() from the Python core: do not edit, regenerate. */",
        "#ifndef TIRE_SPEC_H",
        "#define TIRE_SPEC_H",
        "",
    ]
    for name, value in CONSTANTS.items():
        lines.append(f"#define SPEC_{name} {_c_number(value)}")
    lines.append("")
    for name, value in value_references(variables).items():
        lines.append(f"#define SPEC_BLOCK_{name} {value}")
    lines.append(f"#define SPEC_N_VARIABLES {len(variables)}")
    lines.append(f"#define SPEC_N_STRINGS {sum(v.type == 'String' for v in variables)}")
    for vr, v in enumerate(variables):
        lines.append(f"#define SPEC_VR_{v.name.upper()} {vr}")
    lines += [
        "",
        "typedef enum { SPEC_REAL, SPEC_INTEGER, SPEC_BOOLEAN, SPEC_STRING } SpecType;",
        "typedef enum { SPEC_INPUT, SPEC_OUTPUT, SPEC_PARAMETER } SpecCausality;",
        "typedef struct {",
        "    const char* name;",
        "    SpecType type;",
        "    SpecCausality causality;",
        "    double start; /* the default; an export's own start values are in export.h */",
        "    const char* unit;",
        "    double limit; /* an input's largest magnitude (interface.input_limit), else 0 */",
        "} SpecVariable;",
        "",
        "static const SpecVariable SPEC_VARIABLES[SPEC_N_VARIABLES] = {",
    ]
    lines += [_variable_row(v) for v in variables]
    lines += [
        "};",
        "",
        "/* tire data, in the order of the core's TIRE_FIELDS (the order of the problems) */",
        "typedef struct {",
        "    const char* name;",
        "    const char* unit;",
        "    const char* description;",
        "    const char* range_text;",
        "    double low, high;",
        "    int low_inclusive, integer;",
        "} SpecField;",
        "",
        f"#define SPEC_N_TIRE_FIELDS {len(parameters.TIRE_FIELDS)}",
        "static const SpecField SPEC_TIRE_FIELDS[SPEC_N_TIRE_FIELDS] = {",
    ]
    lines += [_field_row(f, f.name) for f in parameters.TIRE_FIELDS.values()]
    lines += ["};", "",
              "/* the in-plane FMU's ranges, in the order of the core's checks: the tangential "
              "data (core/inplane.py's HOST_TANGENTIAL_RANGES, inclusive), then the operating "
              "point (core/inplane_host.py's HOST_FIELDS, as the tire data's, by FMU name) */",
              "typedef struct {", "    const char *name, *unit;", "    double low, high;",
              "    int integer;", "} SpecRange;", "",
              f"#define SPEC_N_TANGENTIAL_FIELDS {len(inplane.HOST_TANGENTIAL_RANGES)}",
              "static const SpecRange SPEC_TANGENTIAL_FIELDS[SPEC_N_TANGENTIAL_FIELDS] = {"]
    for name, (low, high, unit) in inplane.HOST_TANGENTIAL_RANGES.items():
        lines.append(f"    {{{_c_string(name)}, {_c_string(unit)}, {_c_number(float(low))}, "
                     f"{_c_number(float(high))}, 0}},")
    lines += ["};", f"#define SPEC_N_INPLANE_FIELDS {len(inplane_host.HOST_FIELDS)}",
              "static const SpecField SPEC_INPLANE_FIELDS[SPEC_N_INPLANE_FIELDS] = {"]
    lines += [_field_row(f, inplane_host.FMU_NAMES[f.name])
              for f in inplane_host.HOST_FIELDS.values()]
    lines += ["};", ""]
    lines.append(f"#define SPEC_STATE_MAGIC {_c_string(STATE_MAGIC)}")
    lines.append(f"#define SPEC_STATE_VERSION {STATE_VERSION}")
    lines.append(f"#define SPEC_STATE_GUID_BYTES {STATE_GUID_BYTES}")
    lines.append(f"#define SPEC_STATE_HEAD {STATE_HEAD}")
    lines.append(f"#define SPEC_STATE_MODEL_FLAGS {STATE_MODEL_FLAGS}")
    lines += ["", "/* the FMI state machine: phases by number, and per call the phases that allow "
              "it (bit i: phase i) */", f"#define SPEC_N_PHASES {len(PHASES)}"]
    for number, name in enumerate(PHASES):
        lines.append(f"#define SPEC_PHASE_{name.upper()} {number}")
    lines.append("static const char* const SPEC_PHASE_TEXT[SPEC_N_PHASES] = {")
    lines += [f"    {_c_string(text)}," for text in PHASES.values()]
    lines += ["};", "static const char* const SPEC_PHASE_NAME[SPEC_N_PHASES] = {"]
    lines += [f"    {_c_string(name)}," for name in PHASES]
    lines += ["};", "typedef enum {"]
    lines += [f"    {_c_call(call)}," for call in CALLS]
    lines += ["    SPEC_N_CALLS", "} SpecCall;",
              "static const struct {", "    const char* name;", "    unsigned phases;",
              "} SPEC_CALLS[SPEC_N_CALLS] = {"]
    lines += [f"    {{{_c_string(call)}, {CALL_MASKS[call]}u}}," for call in CALLS]
    lines += ["};", "", "/* CRC-32 (zlib's) of a state, byte by byte: crc = table[(crc ^ b) & "
              "0xff] ^ (crc >> 8), from 0xffffffff, then inverted */",
              "static const unsigned long SPEC_CRC32_TABLE[256] = {"]
    table = _crc32_table()
    lines += ["    " + " ".join(f"{x:#010x}ul," for x in table[i:i + 6])
              for i in range(0, 256, 6)]
    lines += ["};"]
    lines.append(f"#define SPEC_N_LOG_CATEGORIES {len(LOG_CATEGORIES)}")
    lines.append("static const char* const SPEC_LOG_CATEGORIES[SPEC_N_LOG_CATEGORIES] = {")
    lines += [f"    {_c_string(name)}," for name in LOG_CATEGORIES]
    lines += ["};", ""]
    for name, template in MESSAGES.items():
        lines.append(f"#define SPEC_MSG_{name} {_c_string(template)}")
    lines += ["", "#endif", ""]
    return "\n".join(lines)
