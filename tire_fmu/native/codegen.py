"""C sources of a native FMU from a reduced model.

:func:`native_model` fixes everything an export is: the reduced model, the FMU variables with
their export values, a GUID derived from both, and a description. :func:`generate_sources`
turns it into C: ``tire_model_data.h`` (the model as ``static const double`` tables, written
with Python's ``repr`` so every number reads back to the same double, and the variable table)
and ``tire_native.c`` (the FMI 2.0 runtime, the same for every export; see :mod:`.runtime`).
The builder writes the model description from the same :class:`NativeModel`, so the C tables
and the XML cannot disagree.

The variables mirror the Python FMU's (``tire_fmu.fmu.slave``): the same names, types, units
and value references, so a host can swap one FMU for the other. Parameters are ``fixed`` at
the values the model was reduced for; the C code refuses any other value.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import textwrap
import uuid
from dataclasses import asdict, dataclass, fields

import numpy as np

import tire_fmu

from ..core.contact_dynamics import INPUT_NAMES, OUTPUT_NAMES
from ..core.parameters import OperatingPoint, TireParameters
from ..core.reduction import ReducedModel
from ..core.road import SAME_POINT_EPS as SAME_STEP_EPS
from ..core.stepping import SERIES_LIMIT
from ..fmu.interface import (
    TIME_ABS_TOLERANCE_S,
    TIME_REL_TOLERANCE,
    FmuVariable,
    fmu_variables,
)
from .runtime import DATA_FILE, RUNTIME_C, RUNTIME_FILE

DEFAULT_MODEL_IDENTIFIER = "TireModalNative"

_GUID_NAMESPACE = uuid.UUID("6f1c3a52-5d1e-4f57-9a53-2b1e0c7d9e41")


@dataclass(frozen=True, eq=False)
class NativeModel:
    """A reduced model and what its native FMU declares about it."""

    reduced: ReducedModel
    variables: tuple[FmuVariable, ...]
    model_identifier: str
    guid: str
    description: str

    @property
    def parameters(self) -> dict[str, float | int | bool]:
        return {v.name: v.start for v in self.variables if v.causality == "parameter"}

    def index(self, name: str) -> int:
        """Value reference of a variable."""
        return next(i for i, v in enumerate(self.variables) if v.name == name)

    @property
    def road_delayed(self) -> bool:
        return bool(np.any(self.reduced.input_delays_s[1:] > 0))


# -- what the FMU declares ------------------------------------------------------------------

def export_parameters(reduced: ReducedModel, operating_point: OperatingPoint | None = None
                      ) -> dict[str, float | int | bool]:
    """Parameter values of the export, under the Python FMU's names and conventions (f_max and
    n_modes 0 for no limit).

    The load is the one asked for (``operating_point.requested_load_n``): the model's own
    patch load comes out of a bisection and differs in the last digits. Without an operating
    point, or when the patch length was given instead, it is the patch's load.
    """
    op = reduced.metadata.operating_point
    settings = reduced.settings
    load = op.load_n
    if operating_point is not None and operating_point.requested_load_n is not None:
        load = operating_point.requested_load_n
    if operating_point is not None:
        allow_supercritical = operating_point.allow_supercritical
    else:  # only a supercritical export needed it
        allow_supercritical = op.speed_m_s >= op.critical_speed_m_s
    values = {
        "load": float(load),
        "speed": float(op.speed_m_s),
        "n_elements": int(op.n_elements),
        "f_max": float(settings.f_max_hz or 0.0),
        "n_modes": int(settings.n_modes or 0),
        "static_correction": bool(settings.static_correction),
        "allow_supercritical": bool(allow_supercritical),
    }
    tire = reduced.metadata.tire
    values.update({f.name: float(getattr(tire, f.name)) for f in fields(TireParameters)})
    return values


def export_variables(parameters: dict[str, float | int | bool]) -> tuple[FmuVariable, ...]:
    """The Python FMU's variables with the export's values as fixed parameters."""
    return fmu_variables(parameters, "fixed at export: the reduced model is compiled in")


def native_model(reduced: ReducedModel, operating_point: OperatingPoint | None = None,
                 model_identifier: str = DEFAULT_MODEL_IDENTIFIER) -> NativeModel:
    """Everything one export declares. ``operating_point``, when given, supplies the requested
    load and ``allow_supercritical`` (see :func:`export_parameters`)."""
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,63}", model_identifier):
        raise ValueError(f"model_identifier = {model_identifier!r}: must be a C identifier "
                         "(letters, digits, underscores; at most 64 characters)")
    arrays = _model_arrays(reduced)
    bad = [name for name, array in arrays.items() if not np.all(np.isfinite(array))]
    if bad:
        raise ValueError(f"the reduced model has non-finite entries in {', '.join(bad)}; "
                         "it cannot be exported")
    parameters = export_parameters(reduced, operating_point)
    variables = export_variables(parameters)
    return NativeModel(reduced, variables, model_identifier,
                       _guid(arrays, reduced, parameters, model_identifier),
                       describe(reduced, parameters))


def _model_arrays(reduced: ReducedModel) -> dict[str, np.ndarray]:
    return {
        "eigenvalues": np.asarray(reduced.eigenvalues, dtype=complex),
        "b": np.asarray(reduced.b, dtype=complex),
        "c": np.asarray(reduced.c, dtype=complex),
        "d": np.asarray(reduced.d, dtype=float),
        "e": np.asarray(reduced.e, dtype=float),
        "input_delays_s": np.asarray(reduced.input_delays_s, dtype=float),
        "static_outputs": np.array([reduced.static_outputs[n] for n in OUTPUT_NAMES]),
    }


def _guid(arrays, reduced, parameters, model_identifier) -> str:
    """Derived from the model and its declaration: the same export gives the same GUID, and
    any change to the model gives another (the binary checks it when instantiated)."""
    digest = hashlib.sha256()
    digest.update(f"tire_fmu {tire_fmu.__version__} {model_identifier}".encode())
    for name, array in arrays.items():
        digest.update(f"{name}{array.dtype.str}{array.shape}".encode())
        digest.update(np.ascontiguousarray(array).tobytes())
    digest.update(json.dumps(parameters, sort_keys=True).encode())
    digest.update(json.dumps(asdict(reduced.settings), sort_keys=True, default=str).encode())
    digest.update(RUNTIME_C.encode())
    return "{" + str(uuid.uuid5(_GUID_NAMESPACE, digest.hexdigest())) + "}"


def describe(reduced: ReducedModel, parameters: dict) -> str:
    """One paragraph: what the FMU is and the operating point and settings it was built for."""
    op = reduced.metadata.operating_point
    s = reduced.settings
    groups = reduced.n_inputs - 1
    if s.method == "modal":
        how = (f"modal truncation (contribution threshold {s.contribution_threshold:g}, f_max "
               f"{'none' if s.f_max_hz is None else f'{s.f_max_hz:g} Hz'}, n_modes "
               f"{'no limit' if s.n_modes is None else s.n_modes})")
    else:
        how = (f"balanced truncation (n_states "
               f"{'from target error' if s.n_states is None else s.n_states}, target error "
               f"{s.target_error:g})")
    error = (f"; max relative FRF error {reduced.report.max_relative_error:.3g} over "
             f"{s.error_band_hz[0]:g}-{s.error_band_hz[1]:g} Hz" if reduced.report else "")
    return (
        f"Open in-plane modal ring tire (tire_fmu {tire_fmu.__version__}), the reduced model "
        f"compiled to C: no Python needed on the host. Exported for load {parameters['load']:.8g} "
        f"N, speed {parameters['speed']:g} m/s, N = {op.n_elements} elements, patch "
        f"{op.patch_length_m * 100:.4g} cm ({op.patch_nodes} nodes), inflation pressure "
        f"{parameters['inflation_pressure']:g} Pa; {how}, static correction "
        f"{'on' if s.static_correction else 'off'}: {reduced.n_modes} modes "
        f"({reduced.n_states} states), {groups} road delay group{'s' * (groups != 1)}{error}. "
        "Inputs are deviations from static equilibrium, forces are totals. Parameters are "
        "fixed at these values; re-export to change them."
    )


# -- C text ---------------------------------------------------------------------------------

def c_double(value: float) -> str:
    """A C literal that reads back to exactly this double (Python's shortest repr)."""
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{value!r} has no C literal")
    return repr(value)


def c_string(text: str) -> str:
    """A C string literal; anything outside printable ASCII as octal escapes (which, unlike
    hex escapes, cannot swallow the characters after them)."""
    out = []
    for byte in text.encode("utf-8"):
        char = chr(byte)
        if char in '"\\':
            out.append("\\" + char)
        elif 32 <= byte < 127:
            out.append(char)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


#: The C runtime's mode loops run in groups of this many (its LANES).
LANES = 4


def padded_modes(n_modes: int) -> int:
    """Modes rounded up to whole groups of :data:`LANES` (at least one group: C has no empty
    arrays); the padding modes are zero."""
    return max(LANES, -(-n_modes // LANES) * LANES)


def _fill(numbers: list[str], width: int) -> list[str]:
    """Comma-separated numbers packed into lines of at most ``width`` characters."""
    lines, line = [], ""
    for number in numbers:
        if line and len(line) + 2 + len(number) > width:
            lines.append(line)
            line = number
        else:
            line = f"{line}, {number}" if line else number
    return lines + [line]


def c_string_lines(text: str, indent: str, width: int = 88) -> str:
    """A long C string as adjacent literals on several lines (C joins them)."""
    pieces = textwrap.wrap(text, width, drop_whitespace=False) or [""]
    return f"\n{indent}".join(c_string(piece) for piece in pieces)


def _table(name: str, bounds: str, values: np.ndarray, comment: str) -> str:
    """``static const double NAME[bounds] = {...};``, zero-padded to the mode padding and to
    at least one element per axis (C has no empty arrays). ``bounds`` names the size macros,
    so the C reads as the model does."""
    values = np.asarray(values, dtype=float)
    shape = [padded_modes(n) if bound == "N_MODES_PAD" else max(n, 1)
             for n, bound in zip(values.shape, bounds.split())]
    padded = np.zeros(shape)
    padded[tuple(slice(0, n) for n in values.shape)] = values
    dims = "".join(f"[{bound}]" for bound in bounds.split())
    lines = [f"/* {comment} */", f"static const double {name}{dims} = {{"]
    rows = padded.reshape(-1, shape[-1]) if padded.ndim > 1 else padded[None, :]
    for row in rows:
        chunks = _fill([c_double(v) for v in row], width=90)
        if padded.ndim > 1:
            lines.append("    {" + (",\n     ".join(chunks)) + "},")
        else:
            lines += ["    " + chunk + "," for chunk in chunks]
    lines.append("};")
    return "\n".join(lines)


def _variable_rows(native: NativeModel) -> str:
    types = {"Real": "TYPE_REAL", "Integer": "TYPE_INTEGER", "Boolean": "TYPE_BOOLEAN"}
    causalities = {"parameter": "CAUSALITY_PARAMETER", "input": "CAUSALITY_INPUT",
                   "output": "CAUSALITY_OUTPUT"}
    rows = []
    for vr, v in enumerate(native.variables):
        value = c_double(float(v.start)) if v.causality == "parameter" else "0.0"
        head = (f"    /* {vr:2d} */ {{{c_string(v.name)}, {types[v.type]}, "
                f"{causalities[v.causality]},")
        tail = f"{value}, {c_string(v.unit)}, {c_string(v.export_option)}}},"
        rows.append(f"{head} {tail}" if len(head) + len(tail) < 100 else
                    f"{head}\n             {tail}")
    return "\n".join(rows)


def model_summary(native: NativeModel) -> str:
    """The line the FMU logs when it starts."""
    r, p = native.reduced, native.parameters
    op = r.metadata.operating_point
    return (f"exported reduced model, N = {p['n_elements']}, {r.n_modes} modes "
            f"({r.n_states} states), patch {op.patch_length_m * 100:.3g} cm, static load "
            f"{r.static_outputs['rim_Fz']:.6g} N, speed {p['speed']:g} m/s, "
            f"{r.n_inputs - 1} road delay group(s); tire_fmu {tire_fmu.__version__}")


def model_data_header(native: NativeModel) -> str:
    """``tire_model_data.h``: sizes, constants, model tables and the variable table."""
    r = native.reduced
    lam = np.asarray(r.eigenvalues, dtype=complex)
    b = np.asarray(r.b, dtype=complex)
    c = np.asarray(r.c, dtype=complex)
    delays = np.asarray(r.input_delays_s, dtype=float)
    static = np.array([r.static_outputs[n] for n in OUTPUT_NAMES])
    first_input = native.index(INPUT_NAMES[0])
    first_output = native.index(OUTPUT_NAMES[0])
    about = "\n".join(" * " + line for line in textwrap.wrap(native.description, 92))
    return f"""/* {DATA_FILE}: the reduced tire model of {native.model_identifier}.
 *
 * Generated by tire_fmu {tire_fmu.__version__} (tire_fmu.native.codegen); do not edit, re-export.
 * Included once, by {RUNTIME_FILE}, which defines VariableInfo.
 *
{about}
 *
 * Diagonal modal form, one complex mode per conjugate pair (C carries the pair's factor 2):
 *     q' = diag(EIGEN) q + B r,    y = STATIC_OUTPUT + Re(C q) + D r + E v,
 * r = [rim_z, road_z delayed by INPUT_DELAY[j] for road group j], v their velocities,
 * y = [rim_Fz, rim_Fx, contact_Fz, deflection]. Numbers are Python's repr of the doubles,
 * which reads back to the same bits.
 */

#define MODEL_IDENTIFIER {c_string(native.model_identifier)}
#define MODEL_GUID {c_string(native.guid)}
static const char MODEL_SUMMARY[] =
    {c_string_lines(model_summary(native), "    ")};

#define N_MODES {r.n_modes}
#define N_MODES_PAD {padded_modes(r.n_modes)}  /* whole groups of 4, zero modes after N_MODES */
#define N_INPUTS {r.n_inputs}
#define ROAD_DELAYED {int(native.road_delayed)}  /* 0: the whole patch sees the road at once */
#define ROAD_HORIZON {c_double(delays.max())}  /* s, the longest road delay */

/* As the Python reference (tire_fmu.core.stepping, .simulation and the Python FMU) */
#define PHI_SERIES_LIMIT {c_double(SERIES_LIMIT)}
#define SAME_STEP_EPS {c_double(SAME_STEP_EPS)}
#define TIME_ABS_TOLERANCE {c_double(TIME_ABS_TOLERANCE_S)}
#define TIME_REL_TOLERANCE {c_double(TIME_REL_TOLERANCE)}

#define N_VARIABLES {len(native.variables)}
#define VR_FIRST_INPUT {first_input}
#define VR_FIRST_OUTPUT {first_output}
#define VR_IN_CONTACT {native.index("in_contact")}

{_table("EIGEN_RE", "N_MODES_PAD", lam.real, "eigenvalues, real part (1/s)")}

{_table("EIGEN_IM", "N_MODES_PAD", lam.imag, "eigenvalues, imaginary part (rad/s)")}

{_table("B_RE", "N_MODES_PAD N_INPUTS", b.real, "input matrix, real part, [mode][input]")}

{_table("B_IM", "N_MODES_PAD N_INPUTS", b.imag, "input matrix, imaginary part")}

{_table("C_RE", "N_REAL_OUTPUTS N_MODES_PAD", c.real,
        "output matrix, real part, [output][mode]")}

{_table("C_IM", "N_REAL_OUTPUTS N_MODES_PAD", c.imag, "output matrix, imaginary part")}

{_table("D", "N_REAL_OUTPUTS N_INPUTS", r.d, "feedthrough of the inputs, [output][input]")}

{_table("E", "N_REAL_OUTPUTS N_INPUTS", r.e, "feedthrough of the input velocities")}

{_table("INPUT_DELAY", "N_INPUTS", delays,
        "delay of each internal input after the leading edge, s")}

{_table("STATIC_OUTPUT", "N_REAL_OUTPUTS", static,
        "outputs at static equilibrium: N, N, N, m")}

/* name, type, causality, export value (parameters), unit, export option (parameters) */
static const VariableInfo VARIABLES[N_VARIABLES] = {{
{_variable_rows(native)}
}};
"""


def generate_sources(native: NativeModel) -> dict[str, str]:
    """File name -> text of the C sources (the FMI headers are copied by the builder)."""
    return {DATA_FILE: model_data_header(native), RUNTIME_FILE: RUNTIME_C}
