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
  against the core), and that the C fills in with the same values.
"""

from __future__ import annotations

import math

from ..core import (
    clock,
    contact,
    contact_dynamics,
    free_ring,
    kernel_numpy,
    modal_form,
    model,
    parameters,
    road,
    standing_waves,
    step_limits,
    stepping,
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
    TIME_ABS_TOLERANCE_S,
    TIME_REL_TOLERANCE,
    FmuVariable,
    fmu_variables,
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
    "MAX_STEP_WORK": step_limits.MAX_STEP_WORK,
    "WORK_INTERVAL_S": step_limits.WORK_INTERVAL_S,
    "SUBSTEP_SLACK": kernel_numpy.SUBSTEP_SLACK,
    "SERIES_LIMIT": stepping.SERIES_LIMIT,
    "KERNEL_CACHE_SIZE": kernel_numpy.KERNEL_CACHE_SIZE,
    # the inputs a step accepts (beyond them a product inside the step could overflow)
    "MAX_DISPLACEMENT_M": contact_dynamics.MAX_DISPLACEMENT_M,
    "MAX_VELOCITY_M_S": contact_dynamics.MAX_VELOCITY_M_S,
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
                     "of this mesh (n_elements = %d); a finer mesh lowers it, sidewall_shear > "
                     "0 raises it, allow_supercritical runs anyway",
    "NEAR_CRITICAL": "speed %g m/s is %.0f %% of the critical speed %.4g m/s (n_elements = %d): "
                     "sidewall modes near zero frequency dominate the response",
    "ZONE_RANGE": "contact_zone_length = %s: must be in (0, %.4g] m (at most 60 degrees of "
                  "the ring either side of the contact centre)",
    "ZONE_TOO_SHORT": "contact_zone_length = %s: must be at least %.4g m (one node either "
                      "side), or refine the mesh (it holds only the centre node of a mesh of %d "
                      "elements)",
    "LOAD_RANGE": "load = %s: must be in [0, %.6g] N for this tire and mesh; at %.6g N "
                  "(deflection %.3g mm) %s",
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
}

#: Serialized FMU states of the native FMU start with these bytes, then this version.
STATE_MAGIC = "TIREFMUS"
STATE_VERSION = 2
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


def fmu_message(text: str) -> str:
    """A core message in the FMU's names for the parameters and for "no limit"."""
    import re

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


def _c_string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"')
    return f'"{escaped}"'


_C_TYPES = {"Real": "SPEC_REAL", "Integer": "SPEC_INTEGER", "Boolean": "SPEC_BOOLEAN"}
_C_CAUSALITY = {"input": "SPEC_INPUT", "output": "SPEC_OUTPUT", "parameter": "SPEC_PARAMETER"}


def _variable_row(v: FmuVariable) -> str:
    start = 0.0 if v.start is None else float(v.start)
    return (f"    {{{_c_string(v.name)}, {_C_TYPES[v.type]}, {_C_CAUSALITY[v.causality]}, "
            f"{_c_number(start)}, {_c_string(v.unit)}}},")


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
    for name, value in VALUE_REFERENCES.items():
        lines.append(f"#define SPEC_BLOCK_{name} {value}")
    lines.append(f"#define SPEC_N_VARIABLES {len(variables)}")
    for vr, v in enumerate(variables):
        lines.append(f"#define SPEC_VR_{v.name.upper()} {vr}")
    lines += [
        "",
        "typedef enum { SPEC_REAL, SPEC_INTEGER, SPEC_BOOLEAN } SpecType;",
        "typedef enum { SPEC_INPUT, SPEC_OUTPUT, SPEC_PARAMETER } SpecCausality;",
        "typedef struct {",
        "    const char* name;",
        "    SpecType type;",
        "    SpecCausality causality;",
        "    double start; /* the default; an export's own start values are in export.h */",
        "    const char* unit;",
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
        "    int low_inclusive;",
        "} SpecField;",
        "",
        f"#define SPEC_N_TIRE_FIELDS {len(parameters.TIRE_FIELDS)}",
        "static const SpecField SPEC_TIRE_FIELDS[SPEC_N_TIRE_FIELDS] = {",
    ]
    for f in parameters.TIRE_FIELDS.values():
        lines.append(f"    {{{_c_string(f.name)}, {_c_string(f.unit)}, "
                     f"{_c_string(f.description)}, {_c_string(f.range_text())}, "
                     f"{_c_number(f.low)}, {_c_number(f.high)}, {int(f.low_inclusive)}}},")
    lines += ["};", ""]
    lines.append(f"#define SPEC_STATE_MAGIC {_c_string(STATE_MAGIC)}")
    lines.append(f"#define SPEC_STATE_VERSION {STATE_VERSION}")
    lines.append(f"#define SPEC_N_LOG_CATEGORIES {len(LOG_CATEGORIES)}")
    lines.append("static const char* const SPEC_LOG_CATEGORIES[SPEC_N_LOG_CATEGORIES] = {")
    lines += [f"    {_c_string(name)}," for name in LOG_CATEGORIES]
    lines += ["};", ""]
    for name, template in MESSAGES.items():
        lines.append(f"#define SPEC_MSG_{name} {_c_string(template)}")
    lines += ["", "#endif", ""]
    return "\n".join(lines)
