"""What every tire FMU declares, whatever runs inside it: variables, units, capabilities.

The Python FMU (:mod:`.slave`, pythonfmu) and the native C FMU (:mod:`tire_fmu.native`) share
this table, so their inputs, outputs, parameters, units and descriptions cannot drift apart.
It needs neither pythonfmu nor fmpy.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from xml.etree import ElementTree

from ..core.contact import DEFAULT_ZONE_LENGTH_M
from ..core.contact_dynamics import INPUT_NAMES, OUTPUT_NAMES, OUTPUT_UNITS
from ..core.free_ring import RingTruncation
from ..core.parameters import (
    DEFAULT_LOAD_N,
    DEFAULT_POINT_SPACING_M,
    MAX_ELEMENTS,
    MAX_POINT_SPACING_M,
    MIN_ELEMENTS,
    MIN_POINT_SPACING_M,
    TIRE_FIELDS,
    TireParameters,
)

#: JSON file in an FMU's resources/ with the tire data its parameters start from (written by
#: ``build_fmu(tire=...)``, e.g. from ``tire-fmu build-fmu --tire-file``); absent: GL073A.
BAKED_PARAMETERS_FILE = "tire_parameters.json"

#: Communication points closer than this (absolute s, or relative to the time) are the same.
TIME_ABS_TOLERANCE_S = 1e-12
TIME_REL_TOLERANCE = 1e-9

#: A value given to a fixed parameter is its fixed value when the two differ by at most this,
#: relative to the larger: a load computed as (2500 + 320)·9.80665 = 27654.752999999997 is
#: the 27654.753 an FMU was exported with. 1e-9 is far below any physical meaning of the
#: parameters (1e-9 of the load is 28 µN) and far above decimal round trips (~1e-16).
FIXED_PARAMETER_REL_TOLERANCE = 1e-9


def same_fixed_value(given: float, fixed: float) -> bool:
    """Whether ``given`` is the fixed parameter value ``fixed`` within
    :data:`FIXED_PARAMETER_REL_TOLERANCE` (exact for 0; never for nan)."""
    given, fixed = float(given), float(fixed)
    return abs(given - fixed) <= FIXED_PARAMETER_REL_TOLERANCE * max(abs(given), abs(fixed))

from ..core.step_limits import (  # noqa: E402, F401
    MAX_DELAY_STEPS,
    MAX_DISPLACEMENT_M,
    MAX_HISTORY_SAMPLES,
    MAX_ROAD_HEIGHT_M,
    MAX_ROAD_POSITION_M,
    MAX_STEP_S,
    MAX_TORQUE_N_M,
    MAX_VELOCITY_M_S,
)

#: The core's names for the inputs where the FMU variables differ, and the value that means
#: "no limit" (the core's None), for rendering the core's parameter problems.
FMU_NAMES = {"load_n": "load", "speed_m_s": "speed", "f_max_hz": "f_max",
             "contact_zone_length_m": "contact_zone_length",
             "contact_point_spacing_m": "contact_point_spacing"}
FMU_UNSET = "0"

CAPABILITIES = {
    "canHandleVariableCommunicationStepSize": True,  # coefficients are cached per h
    "canGetAndSetFMUstate": True,  # the full modal state, not pythonfmu's scalars only
    "canSerializeFMUstate": True,
}

#: SI base-unit exponents of the units the variables use.
BASE_UNITS = {
    "N": {"kg": 1, "m": 1, "s": -2},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "Hz": {"s": -1},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "kg/m": {"kg": 1, "m": -1},
    "N/m^2": {"kg": 1, "m": -1, "s": -2},
    "N*m^2": {"kg": 1, "m": 3, "s": -2},
    "1/s": {"s": -1},
    "s": {"s": 1},
    "kg": {"kg": 1},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "N/s": {"kg": 1, "m": 1, "s": -3},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "rad/s": {"s": -1},
    "kg*m^2": {"kg": 1, "m": 2},
}


@dataclass(frozen=True)
class FmuVariable:
    """One FMU variable; its value reference is its position in the table."""

    name: str
    type: str  # "Real", "Integer" or "Boolean"
    causality: str  # "input", "output" or "parameter"
    start: float | int | bool | None  # outputs: the value shown before initialisation
    unit: str
    description: str
    export_option: str = ""  # parameters: the CLI option of `tire-fmu export` that sets it
    #: outputs: the inputs whose values, set at a communication point, the output's next read
    #: depends on directly (ModelStructure/Outputs' dependencies); None: every input
    depends_on: tuple[str, ...] | None = None

    @property
    def variability(self) -> str:
        if self.causality == "parameter":
            return "fixed"  # they define the reduced basis
        return "discrete" if self.type == "Boolean" else "continuous"


#: TireModal's direct feed-through (docs/fmu.md, "What a step does"): inputs set at a
#: communication point reach the next read of the outputs through the contact's springs and
#: dampers on the road, the sidewall on the rim and the static correction of the dropped modes,
#: so every output may depend on every input, but the deflection, which is the rim's and the
#: road's positions (and the state) alone.
_RADIAL_FEED_THROUGH = {"deflection": ("rim_z", "road_z")}


def _signals() -> list[FmuVariable]:
    rows = _radial_signals()
    inputs = tuple(v.name for v in rows if v.causality == "input")
    return [replace(v, depends_on=_RADIAL_FEED_THROUGH.get(v.name, inputs))
            if v.causality == "output" else v for v in rows]


def _radial_signals() -> list[FmuVariable]:
    return [
        FmuVariable("rim_z", "Real", "input", 0.0, "m",
                    "rim vertical displacement from static equilibrium (z up)"),
        FmuVariable("rim_vz", "Real", "input", 0.0, "m/s",
                    "rim vertical velocity at t: the step extends the rim along it and its "
                    "last changes (docs/fmu.md, Timing)"),
        FmuVariable("road_z", "Real", "input", 0.0, "m",
                    "road height at the front of the contact zone (contact_zone_length/2 ahead "
                    "of the contact centre), from static equilibrium"),
        FmuVariable("road_vz", "Real", "input", 0.0, "m/s",
                    "road vertical velocity at the front of the contact zone at t: the step "
                    "extends the road along it and its last changes"),
        FmuVariable("rim_Fz", "Real", "output", DEFAULT_LOAD_N, OUTPUT_UNITS["rim_Fz"],
                    "vertical force of the tire on the rim, total (static load + dynamic)"),
        FmuVariable("rim_Fx", "Real", "output", 0.0, OUTPUT_UNITS["rim_Fx"],
                    "fore-aft force of the tire on the rim (x forward), total: the horizontal "
                    "projection of the ring's radial forces on the rim; the ring has no "
                    "tangential tread motion and the contact no friction, so there is no "
                    "traction, braking or tangential cleat force in it (0 at rest on a flat "
                    "road)"),
        FmuVariable("contact_Fz", "Real", "output", DEFAULT_LOAD_N, OUTPUT_UNITS["contact_Fz"],
                    "vertical force of the road on the tire (positive pushing up), total"),
        FmuVariable("deflection", "Real", "output", 0.0, OUTPUT_UNITS["deflection"],
                    "the tire's deflection: how far the rim is lowered towards the road at the "
                    "contact centre (as for the static footprint), total: the static deflection "
                    "plus the road's rise under the contact centre less rim_z; negative when "
                    "the rim is lifted clear of the road"),
        FmuVariable("contact_length", "Real", "output", 0.0, "m",
                    "length of the footprint on the road (between the interpolated edges of the "
                    "nodes that push)"),
        FmuVariable("tread_deflection", "Real", "output", 0.0, "m",
                    "radial compression of the tread at the contact centre relative to the rim, "
                    "total: the deflection less what the contact spring (k_cw) takes there"),
        FmuVariable("in_contact", "Boolean", "output", True, "",
                    "true while at least one tread node pushes on the road"),
    ]


def _parameters() -> list[FmuVariable]:
    """Parameters with their defaults; f_max and n_modes use 0 for "no limit"."""
    settings = RingTruncation()
    defaults = TireParameters()
    table = [
        FmuVariable("load", "Real", "parameter", DEFAULT_LOAD_N, "N",
                    "static vertical load the reduced basis is linearised at (the wheel's "
                    "share of the weight); rim_Fz starts at it", "--load"),
        FmuVariable("speed", "Real", "parameter", 0.0, "m/s",
                    "forward speed (spin = speed / R); below the mesh's critical speed unless "
                    "allow_supercritical", "--speed"),
        FmuVariable("n_elements", "Integer", "parameter", 100, "",
                    f"finite-difference nodes around the ring; allowed [{MIN_ELEMENTS}, "
                    f"{MAX_ELEMENTS}]", "--elements"),
        FmuVariable("f_max", "Real", "parameter", settings.f_max_hz or 0.0, "Hz",
                    "highest natural frequency of the free ring's modes the step keeps (0 = no "
                    "cut: every mode)", "--f-max"),
        FmuVariable("n_modes", "Integer", "parameter", settings.n_modes or 0, "",
                    "keep at most this many of the free ring's modes, lowest natural frequency "
                    "first (0 = no limit)", "--n-modes"),
        FmuVariable("static_correction", "Boolean", "parameter", settings.static_correction,
                    "", "add the dropped modes' static response, so static stiffness is exact",
                    "--no-static-correction"),
        FmuVariable("allow_supercritical", "Boolean", "parameter", False, "",
                    "run at or above the critical (standing-wave) speed of the mesh",
                    "--allow-supercritical"),
        FmuVariable("contact_zone_length", "Real", "parameter", DEFAULT_ZONE_LENGTH_M, "m",
                    "length of road under the tread nodes that may meet it, centred on the "
                    "contact centre (road_z is measured at its front)", "--zone-length"),
        FmuVariable("contact_point_spacing", "Real", "parameter", DEFAULT_POINT_SPACING_M, "m",
                    "spacing of the contact points along the tread, each meeting the road at "
                    "its own point (an odd number per node, interpolated between the nodes; "
                    "at or beyond the node arc, one per node); allowed "
                    f"[{MIN_POINT_SPACING_M:g}, {MAX_POINT_SPACING_M:g}]", "--point-spacing"),
        FmuVariable("linear_contact", "Boolean", "parameter", False, "",
                    "two-sided springs on the static footprint instead of the unilateral "
                    "contact (the linearised tire, for comparison with linear tools)",
                    "--linear-contact"),
    ]
    table += _tire_data_variables(defaults)
    return table


def _tire_data_variables(defaults: TireParameters, note: dict[str, str] | None = None
                         ) -> list[FmuVariable]:
    """A parameter per tire field, starting at ``defaults``, with the field's description and
    range (and ``note``'s words for a field, if any)."""
    note = note or {}
    rows = []
    for f in fields(TireParameters):
        spec = TIRE_FIELDS[f.name]
        option = ("--inflation-pressure" if f.name == "inflation_pressure"
                  else f"--tire {f.name}=VALUE")
        rows.append(FmuVariable(f.name, "Real", "parameter", getattr(defaults, f.name),
                                spec.unit, f"{spec.description}; allowed {spec.range_text()}"
                                + note.get(f.name, ""), option))
    return rows


def fmu_variables(parameter_values: dict | None = None, parameter_note: str = ""
                  ) -> tuple[FmuVariable, ...]:
    """Every variable in value-reference order: inputs, outputs (with in_contact), parameters.

    ``parameter_values`` replaces the parameters' start values (an export's fixed values) and
    ``parameter_note`` is appended to their descriptions.
    """
    parameters = _parameters()
    if parameter_values is not None or parameter_note:
        values = parameter_values or {}
        parameters = [replace(p, start=values.get(p.name, p.start),
                              description=f"{p.description}; {parameter_note}"
                              if parameter_note else p.description) for p in parameters]
    table = _signals() + parameters
    names = [v.name for v in table]
    # the runtimes read inputs and outputs as these contiguous blocks
    assert names[: len(INPUT_NAMES)] == list(INPUT_NAMES)
    assert names[len(INPUT_NAMES): len(INPUT_NAMES) + len(OUTPUT_NAMES)] == list(OUTPUT_NAMES)
    return tuple(table)


#: Value references of the hot path, fixed by the order of :func:`fmu_variables`.
INPUTS = slice(0, len(INPUT_NAMES))
OUTPUTS = slice(INPUTS.stop, INPUTS.stop + len(OUTPUT_NAMES))
IN_CONTACT = OUTPUTS.stop


def output_dependencies(table) -> dict[str, tuple[str, ...]]:
    """{output: the inputs it depends on directly} for the outputs that declare them."""
    return {v.name: v.depends_on for v in table
            if v.causality == "output" and v.depends_on is not None}


def model_structure(variables, dependencies: dict[str, tuple[str, ...]] | None = None
                    ) -> ElementTree.Element:
    """``<ModelStructure>`` of ``variables``, (name, causality, initial) in value-reference
    order: the outputs, each with the indices of the inputs it depends on directly where
    ``dependencies`` names them (without, FMI 2.0 reads every input), then the initial
    unknowns (the outputs whose initial value is calculated)."""
    variables = list(variables)
    index = {name: i for i, (name, _, _) in enumerate(variables, 1)}
    dependencies = dependencies or {}
    outputs = [i for i, (_, causality, _) in enumerate(variables, 1) if causality == "output"]
    calculated = [i for i in outputs if variables[i - 1][2] in ("calculated", "approx")]
    structure = ElementTree.Element("ModelStructure")
    for tag, indices in (("Outputs", outputs), ("InitialUnknowns", calculated)):
        if not indices:
            continue
        group = ElementTree.SubElement(structure, tag)
        for i in indices:
            unknown = ElementTree.SubElement(group, "Unknown", index=str(i))
            name = variables[i - 1][0]
            if tag == "Outputs" and name in dependencies:
                unknown.set("dependencies", " ".join(
                    str(k) for k in sorted(index[n] for n in dependencies[name])))
    return structure


def unit_definitions(units) -> ElementTree.Element:
    """<UnitDefinitions> for the units the variables use, with their SI base units."""
    definitions = ElementTree.Element("UnitDefinitions")
    for unit in sorted(set(units)):
        element = ElementTree.SubElement(definitions, "Unit", name=unit)
        if unit in BASE_UNITS:
            ElementTree.SubElement(element, "BaseUnit",
                                   {k: str(v) for k, v in BASE_UNITS[unit].items()})
    return definitions


# -- the wheel centre and the road by position (both tires' FMUs, docs/fmu.md) ----------------

#: How many heights of the host's road a step takes (road_z_i at road_x_i), spread over the
#: road the next step reaches (core/wheel_centre.road_queries): at 20 m/s and a 1 ms step one
#: every 0.6 mm, fine enough that a 20 mm cleat with 1 mm edges reaches the tire as its road
#: file does (16 left the in-plane tire's Fx 1.3-4.8 % rms off, by where the samples fell on
#: the edges; tests/test_wheel_centre.py).
ROAD_QUERIES = 32


#: wheel_z's start value in the in-plane FMUs built for the default tire (m): its loaded radius
#: at the default load on a level road, where a host that leaves wheel_z unset has the tire
#: carry its load (tests/test_inplane_fmu.py checks it against the built tire; an FMU built for
#: other data bakes its own, builder.build_inplane_fmu).
DEFAULT_INPLANE_WHEEL_Z_M = 0.6336175640756


def wheel_centre_inputs(wheel_z_m: float = 0.0) -> list[FmuVariable]:
    return [
        FmuVariable("wheel_x", "Real", "input", 0.0, "m",
                    "the wheel centre's position along the road (x forward; the road file's "
                    "u), at t"),
        FmuVariable("wheel_vx", "Real", "input", 0.0, "m/s",
                    "the wheel centre's speed along the road at t (the tire rolls at it)"),
        FmuVariable("wheel_z", "Real", "input", wheel_z_m, "m",
                    "the wheel centre's height above the road's datum (z up) at t: at "
                    "loaded_radius above the road the tire carries load"),
        FmuVariable("wheel_vz", "Real", "input", 0.0, "m/s",
                    "the wheel centre's vertical speed at t"),
    ]


def road_height_inputs() -> list[FmuVariable]:
    return [FmuVariable(f"road_z_{i}", "Real", "input", 0.0, "m",
                        f"with no road_file: the road's height at road_x_{i}, where the tire "
                        "asked for it after its last step (the host's road)")
            for i in range(1, ROAD_QUERIES + 1)]


def road_query_outputs() -> list[FmuVariable]:
    return [FmuVariable(f"road_x_{i}", "Real", "output", 0.0, "m",
                        f"with no road_file: where along the road the tire needs the host's "
                        f"road_z_{i} for its next step")
            for i in range(1, ROAD_QUERIES + 1)]


def wheel_centre_outputs() -> list[FmuVariable]:
    return [
        FmuVariable("loaded_radius", "Real", "output", 0.0, "m",
                    "the wheel centre's height above the road under it (after "
                    "initialisation: where to place the wheel to carry load)"),
        FmuVariable("effective_rolling_radius", "Real", "output", 0.0, "m",
                    "wheel_vx over the wheel's spin (R while the wheel barely turns)"),
        FmuVariable("longitudinal_slip", "Real", "output", 0.0, "",
                    "(spin R - wheel_vx) / max(|wheel_vx|, 0.1 m/s), R the tread radius: "
                    "negative braking"),
    ]


def road_parameters() -> list[FmuVariable]:
    return [
        FmuVariable("road_file", "String", "parameter", "", "",
                    "the road: an OpenCRG .crg or a two-column profile (distance m, height m) "
                    "file; empty: the host gives it (road_x_i, road_z_i)", ""),
        FmuVariable("road_lateral_offset", "Real", "parameter", 0.0, "m",
                    "where across an OpenCRG road the tire rolls (its v, left positive)", ""),
    ]


#: The largest magnitude of an input, by name where it differs from its unit's
#: (INPUT_UNIT_LIMITS): positions along the road, heights above its datum.
INPUT_NAME_LIMITS = {"wheel_x": MAX_ROAD_POSITION_M, "wheel_z": MAX_ROAD_HEIGHT_M,
                     **{f"road_z_{i}": MAX_ROAD_HEIGHT_M for i in range(1, ROAD_QUERIES + 1)}}
#: The largest magnitude of an input by its unit (beyond it a product inside a step could
#: overflow); a unit not listed: a displacement's.
INPUT_UNIT_LIMITS = {"m": MAX_DISPLACEMENT_M, "m/s": MAX_VELOCITY_M_S, "N.m": MAX_TORQUE_N_M,
                     "rad/s": MAX_VELOCITY_M_S}


def input_limit(v: FmuVariable) -> float:
    """The largest magnitude input ``v`` takes (spec INPUT_RANGE beyond it): by its name
    (INPUT_NAME_LIMITS), else by its unit. Both runtimes check this one rule: the Python FMUs
    here, the native ones on the limit spec.h's variable rows carry."""
    return INPUT_NAME_LIMITS.get(v.name) or INPUT_UNIT_LIMITS.get(v.unit, MAX_DISPLACEMENT_M)


# -- the in-plane tire's FMU (TireInPlane): the ring with tangential motion, friction, Fx, My --

def inplane_fmu_variables(parameter_values: dict | None = None) -> tuple[FmuVariable, ...]:
    """Every variable of TireInPlane.fmu in value-reference order: the radial FMU's four
    inputs first (same names, same meaning), then the rim's fore-aft motion and the torque;
    outputs; in_contact; parameters (the tire data, radial and tangential, and the operating
    point). ``parameter_values`` replaces the parameters' start values."""
    from ..core.inplane import HOST_TANGENTIAL_RANGES, TangentialParameters
    from ..core.inplane_host import (
        CRITICAL_SPEED_FRACTION,
        DEFAULT_HOST_F_MAX_HZ,
        DEFAULT_HOST_POINT_SPACING_M,
        DEFAULT_HOST_STEP_S,
        HOST_FIELDS,
    )

    def allowed(name):
        return f"allowed {HOST_FIELDS[name].range_text()}"

    radial = {v.name: v for v in _signals()}
    table = wheel_centre_inputs(DEFAULT_INPLANE_WHEEL_Z_M) + [
        FmuVariable("wheel_torque", "Real", "input", 0.0, "N.m",
                    "drive (+) or brake (-) torque on the wheel about the axle, in the sense "
                    "of its rolling; with wheel_free = false the wheel's spin is held and "
                    "this is ignored, as with wheel_driven"),
        FmuVariable("wheel_rate", "Real", "input", 0.0, "rad/s",
                    "with wheel_driven: the wheel's spin (rad/s, in the sense of rolling), "
                    "given by a host that models the wheel's body itself (a locked wheel: 0); "
                    "not read otherwise"),
        *road_height_inputs(),
        radial["rim_Fz"],
        FmuVariable("rim_Fx", "Real", "output", 0.0, "N",
                    "fore-aft force of the tire on the rim (x forward), total: braking "
                    "negative, the rolling resistance and the fore-aft cleat force in it"),
        FmuVariable("rim_My", "Real", "output", 0.0, "N.m",
                    "moment of the tire on the rim about the axle, in the sense of rolling "
                    "(a brake torque is met by a positive one as the tread drags)"),
        FmuVariable("contact_Fz", "Real", "output", DEFAULT_LOAD_N, "N",
                    "vertical force of the road on the tread (positive pushing up), summed "
                    "over the contact points"),
        FmuVariable("contact_Fx", "Real", "output", 0.0, "N",
                    "fore-aft force of the road on the tread (x forward), summed over the "
                    "contact points' tread elements"),
        FmuVariable("wheel_spin", "Real", "output", 0.0, "rad/s",
                    "the wheel's spin (speed / R at free rolling; its own with wheel_free)"),
        FmuVariable("sliding_points", "Real", "output", 0.0, "",
                    "how many contact points slide (Coulomb friction at its limit); 0 while "
                    "the whole footprint sticks"),
        *wheel_centre_outputs(),
        FmuVariable("contact_length", "Real", "output", 0.0, "m",
                    "length of road the pushing contact points cover"),
        *road_query_outputs(),
        FmuVariable("in_contact", "Boolean", "output", True, "",
                    "true while at least one contact point pushes on the road"),
        FmuVariable("load", "Real", "parameter", DEFAULT_LOAD_N, "N",
                    f"static vertical load the footprint is built for; {allowed('load_n')}",
                    "--load"),
        FmuVariable("speed", "Real", "parameter", 0.0, "m/s",
                    "forward speed the reduced step is built at (the tire then rolls at "
                    f"wheel_vx, its spin followed); allowed [0, {CRITICAL_SPEED_FRACTION:g} of "
                    "the mesh's critical speed]", "--speed"),
        FmuVariable("n_elements", "Integer", "parameter", 100, "",
                    f"nodes around the ring; {allowed('n_elements')} (with the lumped "
                    "sidewall, sidewall_max_order = 0, the critical speed falls as the mesh "
                    "is refined)",
                    "--elements"),
        FmuVariable("f_max", "Real", "parameter", DEFAULT_HOST_F_MAX_HZ, "Hz",
                    "highest natural frequency of the free ring's modes the reduced step "
                    f"keeps (with every contact-zone node's static shapes); {allowed('f_max_hz')}",
                    "--f-max"),
        FmuVariable("contact_zone_length", "Real", "parameter", DEFAULT_ZONE_LENGTH_M, "m",
                    "length of road under the contact points, centred on the contact centre; "
                    f"{allowed('zone_length_m')}", "--zone-length"),
        FmuVariable("contact_point_spacing", "Real", "parameter",
                    DEFAULT_HOST_POINT_SPACING_M, "m",
                    "spacing of the contact points, each with its tread element and "
                    f"friction; {allowed('point_spacing_m')}", "--point-spacing"),
        FmuVariable("step_size", "Real", "parameter", DEFAULT_HOST_STEP_S, "s",
                    "the tire's own step: a communication step is cut into steps of it (or "
                    f"equal shorter ones where it is no whole number of them); "
                    f"{allowed('step_s')}", "--step"),
        *road_parameters(),
        FmuVariable("wheel_free", "Boolean", "parameter", True, "",
                    "the wheel turns under wheel_torque and the tread's drag (its inertia "
                    "wheel_inertia_kg_m2); false holds its spin at speed / R", "--wheel-held"),
        FmuVariable("wheel_driven", "Boolean", "parameter", False, "",
                    "the host gives the wheel's spin (wheel_rate) and reads the tire's moment "
                    "on the rim (rim_My), as when it models the wheel's body itself; "
                    "wheel_free and wheel_torque are then not read", "--wheel-driven"),
    ]
    table += _tire_data_variables(TireParameters(),
                                  {"sidewall_shear": "; 0 for the in-plane ring (tie the "
                                                     "sidewall with sidewall_max_order)"})
    defaults = TangentialParameters()
    for name, (low, high, unit) in HOST_TANGENTIAL_RANGES.items():
        table.append(FmuVariable(name, "Real", "parameter", getattr(defaults, name),
                                 unit, f"tangential tire data ({name}); allowed [{low:g}, "
                                 f"{high:g}] {unit}".rstrip(), f"--tire {name}=VALUE"))
    # no `tire-fmu export` builds this FMU: its parameters have no export option. No output
    # feeds through: each is the last step's, whatever the inputs set since
    table = [replace(v, export_option="", depends_on=() if v.causality == "output" else None)
             for v in table]
    if parameter_values:  # the tire data and the loaded radius (wheel_z) of a built FMU
        table = [replace(v, start=parameter_values.get(v.name, v.start))
                 if v.causality == "parameter" or v.name == "wheel_z" else v for v in table]
    return tuple(table)


#: The in-plane FMU's hot-path blocks: inputs (the wheel centre's four, the torque, the spin,
#: the host road's heights), outputs (the forces, what a host reads of the tire, where the host
#: road is wanted next), in_contact.
INPLANE_INPUTS = slice(0, 6 + ROAD_QUERIES)
INPLANE_OUTPUTS = slice(INPLANE_INPUTS.stop, INPLANE_INPUTS.stop + 11 + ROAD_QUERIES)
INPLANE_IN_CONTACT = INPLANE_OUTPUTS.stop
