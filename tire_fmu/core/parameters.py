"""Tire data and operating point, with validation that reports every problem at once.

Units are SI throughout. The tire data follow the seed paper's symbols (Tables 1 and 2,
GL073A truck tire) read as the design brief says: every line quantity (masses and radial
stiffnesses) is per metre of tread circumference, and EI is in N·m². A finite-difference node
carries ``value × R·δθ`` of each line quantity.

One table (:data:`TIRE_FIELDS`) describes every tire field: symbol, unit, description and
allowed range. Validation, the CLI help, the FMU variables and the docs all read it, so the
ranges live in one place.

Every problem found is a :class:`Problem` (which input, the value given, what is allowed,
why). The CLI and the FMUs render it with :func:`render` in their own names for the inputs
(``--load``, ``load``); the message patterns are printf formats defined here once, so a C
runtime can render the same text.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

#: Default static load (N): one wheel of a heavy vehicle, 2820 kg under standard gravity, a
#: service load of the GL073A (16.00R20) truck tire. A plain number: whoever runs the tire
#: (a vehicle model, the FMU's host) sets the load its own wheel carries.
DEFAULT_LOAD_N = 27_654.753

#: The slowest speed that rolls (m/s): below it the tire is at rest to rounding, and the road
#: would reach the back of the patch after days (a time-domain run keeps that much history).
MIN_ROLLING_SPEED_M_S = 1e-3

#: Longest contact patch the linear ring model is trusted with, as a fraction of the
#: circumference. Beyond ~45° of wrap the small-deflection ring and the flat-road chord
#: geometry used to relate load and patch length both stop being credible.
MAX_PATCH_FRACTION = 1.0 / 8.0

#: The 5-point bending stencil needs distinct neighbours two nodes away on both sides, and the
#: lowest ring orders (n <= 2) need a few nodes per wavelength to be meaningful.
MIN_ELEMENTS = 8
#: The loaded rolling tire's modes and its balanced reduction are dense, O(N^3) time and
#: O(N^2) memory: at this limit seconds at rest and minutes and about 2 GB rolling on a 2-core
#: machine (20000, the former limit, needed more than 23 GB; the modal analysis of
#: benchmarks/bench_modal.py goes to it). benchmarks/bench_mesh_size.py prints what a mesh costs.
MAX_ELEMENTS = 1_600
#: The contact points' spacing along the tread (m): the default puts at least four points on a
#: 10 mm road feature. What it leaves is first order in the spacing: the rim load's peak over a
#: 20 mm cleat comes out about 2 % and over a 10 mm one about 7 % below the zero-spacing limit
#: (docs/theory.md §4.6, from docs/measured/cleat_convergence.json; tests/test_docs_claims.py
#: holds these rounded figures to the record); halving the spacing halves it at about four
#: times the run time. The range keeps the points within what a road means (0.1 mm) and at
#: most one per node (any spacing beyond the node arc puts one point on each node).
DEFAULT_POINT_SPACING_M = 2.5e-3
MIN_POINT_SPACING_M = 1e-4
MAX_POINT_SPACING_M = 1.0
POINT_SPACING_ALLOWED = "in [%g, %g] m"
POINT_SPACING_REASON = ("the spacing of the contact points along the tread; at or beyond the "
                        "node arc, one point on each node")
ELEMENTS_REASON = (f"the 5-point bending stencil needs at least {MIN_ELEMENTS} nodes around the "
                   f"ring; meshes above {MAX_ELEMENTS} cost too much time and memory to build")


#: How a problem reads. printf patterns, so that a C runtime renders the same text: the
#: input's name, its value (with unit), what is allowed; then the reason, if any.
PROBLEM_TEMPLATE = "%s = %s: must be %s"
#: appended to what is allowed when the input may also be left unset: the adapter's word for
#: unset ("None" in Python, "0" in the FMUs)
UNSET_TEMPLATE = "%s, or %s for no limit"
REASON_TEMPLATE = "%s (%s)"
#: several problems in one line
PROBLEMS_TEMPLATE = "%d parameter problems: %s"


@dataclass(frozen=True)
class Problem:
    """One thing wrong with one input: which (``field``, its core name), the value given,
    what is allowed (``allowed`` reads after "must be", e.g. ``"in (0.1, 3] m"``) and why."""

    field: str
    value: Any
    unit: str = ""
    allowed: str = ""
    reason: str = ""
    unset: bool = False  # leaving the input unset (no limit) is allowed too


def value_text(value: Any, unit: str = "") -> str:
    """A value as a message shows it: numbers in the shortest exact form, with their unit."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
        return repr(value)
    if isinstance(value, (int, np.integer)):
        text = str(int(value))
    else:
        number = float(value)
        if not math.isfinite(number):
            return repr(number)
        text = f"{number:g}"
        if float(text) != number:
            text = repr(number)
    return f"{text} {unit}" if unit else text


def render(problem: Problem, names: Mapping[str, str] | None = None, unset: str = "None"
           ) -> str:
    """``problem`` in words, naming inputs by ``names`` (core name -> the adapter's name)."""
    name = (names or {}).get(problem.field, problem.field)
    allowed = UNSET_TEMPLATE % (problem.allowed, unset) if problem.unset else problem.allowed
    text = PROBLEM_TEMPLATE % (name, value_text(problem.value, problem.unit), allowed)
    return REASON_TEMPLATE % (text, problem.reason) if problem.reason else text


class ParameterError(ValueError):
    """Invalid inputs; ``details`` lists every :class:`Problem` found, ``problems`` the same
    rendered with the core's names."""

    def __init__(self, problems: Sequence[Problem]):
        self.details = list(problems)
        self.problems = self.render()
        super().__init__(self.message())

    def render(self, names: Mapping[str, str] | None = None, unset: str = "None") -> list[str]:
        return [render(p, names, unset) for p in self.details]

    def message(self, names: Mapping[str, str] | None = None, unset: str = "None") -> str:
        """Every problem in one line."""
        rendered = self.render(names, unset)
        if len(rendered) == 1:
            return rendered[0]
        return PROBLEMS_TEMPLATE % (len(rendered), "; ".join(rendered))


@dataclass(frozen=True)
class FieldSpec:
    """What a parameter means and which values the model accepts."""

    name: str
    unit: str
    description: str
    low: float
    high: float
    low_inclusive: bool = False
    integer: bool = False

    def problem(self, value: Any) -> Problem | None:
        """What is wrong with ``value`` for this field, or None."""
        try:
            number = float(value)
        except (TypeError, ValueError):
            return Problem(self.name, value, "", f"a number in {self.range_text()}",
                           self.description)
        if not math.isfinite(number):
            return Problem(self.name, number, "", f"a finite number in {self.range_text()}",
                           self.description)
        below = number < self.low if self.low_inclusive else number <= self.low
        if below or number > self.high:
            kind = "an integer in" if self.integer else "in"
            return Problem(self.name, number, self.unit, f"{kind} {self.range_text()}",
                           self.description)
        if self.integer and number != math.floor(number):
            return Problem(self.name, number, self.unit, f"an integer in {self.range_text()}",
                           self.description)
        return None

    def range_text(self) -> str:
        left = "[" if self.low_inclusive else "("
        return f"{left}{self.low:g}, {self.high:g}] {self.unit}".rstrip()


#: Lower bounds that admit every real tire with room to spare and keep the arithmetic away
#: from underflow (a mass of 1e-300 kg/m made every frequency overflow, and the critical speed
#: read 0 m/s). The lightest tires, 23 mm road-bicycle tires, carry about 0.05 kg/m of tread
#: and less of sidewall; masses from 1e-6 kg/m leave room for the limit studies of a massless
#: sidewall (1e-5 kg/m must run, issue 20) while 1e-300 is refused. Tread rubber (E >= 1 MPa,
#: at least 2 cm wide, at most 3 cm thick) is at least 7e5 N/m^2 stiff per metre: k_cw from
#: 1e4 N/m^2. Tires run at 0.3 bar and more: the sidewall pressure law holds from 1e4 Pa
#: (0.1 bar) up, for the pressure it is referred to and the one it scales to (below, it leaves
#: the sidewall almost without stiffness: at 1e-300 Pa the critical speed read 0 m/s).
MIN_MASS_KG_M = 1e-6
MIN_CONTACT_STIFFNESS_N_M2 = 1e4
MIN_LAW_PRESSURE_PA = 1e4
#: Largest sidewall_max_order accepted: beyond every mesh (n_elements <= 1600, orders <= 800).
MAX_SIDEWALL_ORDER = 100_000.0
#: Stiffness of the tie that slaves the sidewall above sidewall_max_order to the tread's static
#: shape, as a multiple of the order's own tread and sidewall stiffness. The tie's modes then
#: sit 10x and more above the ring's own at every order (a phase speed that grows with n) while
#: the per-order solve loses at most two digits; the tie stores no energy in the free ring's
#: static state, so the static compliance at rest is that of the lumped sidewall.
SIDEWALL_TIE_FACTOR = 100.0

TIRE_FIELDS: dict[str, FieldSpec] = {
    spec.name: spec
    for spec in (
        FieldSpec("R", "m", "tread (belt) radius", 0.1, 3.0),
        FieldSpec("b", "m", "tread width", 0.01, 2.0),
        FieldSpec("inflation_pressure", "Pa", "inflation pressure p0", 0.0, 3.0e6, True),
        FieldSpec("rhoA", "kg/m", "tread mass per metre of circumference", MIN_MASS_KG_M, 1.0e4,
                  True),
        FieldSpec("m_s", "kg/m", "sidewall mass per metre of circumference", MIN_MASS_KG_M,
                  1.0e4, True),
        FieldSpec("k_r1", "N/m^2", "tread-sidewall radial stiffness per metre", 0.0, 1.0e12),
        FieldSpec("k_r2", "N/m^2", "sidewall-rim radial stiffness per metre", 0.0, 1.0e12),
        FieldSpec("EI", "N*m^2", "tread bending stiffness", 0.0, 1.0e8),
        FieldSpec("k_cw", "N/m^2", "contact-patch radial stiffness per metre",
                  MIN_CONTACT_STIFFNESS_N_M2, 1.0e13, True),
        FieldSpec("alpha", "1/s", "mass-proportional damping coefficient", 0.0, 1.0e3, True),
        FieldSpec("beta", "s", "stiffness-proportional damping coefficient", 0.0, 1.0e-1, True),
        FieldSpec(
            "sidewall_shear",
            "N",
            "circumferential shear stiffness between neighbouring sidewall masses "
            "(0 = the paper's lumped sidewall)",
            0.0,
            1.0e9,
            True,
        ),
        FieldSpec(
            "sidewall_max_order",
            "",
            "highest circumferential order n in which the sidewall moves on its own; above it "
            "the sidewall is tied to the tread's static shape (0 = every order, the paper's "
            "lumped sidewall)",
            0.0,
            MAX_SIDEWALL_ORDER,
            True,
            integer=True,
        ),
        FieldSpec(
            "sidewall_pressure_exponent",
            "",
            "exponent e of the sidewall stiffness law: k_r1, k_r2 and sidewall_shear scale with "
            "(inflation_pressure/reference_pressure)^e (0 = off, the paper's pressure-free "
            "sidewall)",
            0.0,
            3.0,
            True,
        ),
        FieldSpec(
            "reference_pressure",
            "Pa",
            "inflation pressure at which k_r1, k_r2 and sidewall_shear are given (pressure law)",
            MIN_LAW_PRESSURE_PA,
            3.0e6,
            True,
        ),
    )
}

#: The sidewall stiffnesses the pressure law scales.
PRESSURE_SCALED_FIELDS = ("k_r1", "k_r2", "sidewall_shear")


def tire_problems(values: Mapping[str, Any]) -> list[Problem]:
    """Every problem with a set of tire data, checked field by field."""
    problems = [problem for name, spec in TIRE_FIELDS.items() if name in values
                for problem in [spec.problem(values[name])] if problem]
    for name in sorted(set(values) - set(TIRE_FIELDS), key=str):
        problems.append(Problem(str(name), values[name], "",
                                f"one of the tire parameters {', '.join(TIRE_FIELDS)}",
                                "unknown tire parameter"))
    if not problems:
        problems += _pressure_law_problems(values)
    return problems


#: What the pressure-law check says (printf, so the native FMU renders the same).
PRESSURE_LAW_ALLOWED = "at least %g Pa, or sidewall_pressure_exponent = 0"
PRESSURE_LAW_REASON = ("with sidewall_pressure_exponent = %g the pressure law would leave the "
                       "sidewall almost without stiffness")


def _pressure_law_problems(values: Mapping[str, Any]) -> list[Problem]:
    defaults = {f.name: f.default for f in fields(TireParameters)}
    exponent = float(values.get("sidewall_pressure_exponent",
                                defaults["sidewall_pressure_exponent"]))
    pressure = float(values.get("inflation_pressure", defaults["inflation_pressure"]))
    if exponent > 0.0 and pressure < MIN_LAW_PRESSURE_PA:
        return [Problem("inflation_pressure", pressure, "Pa",
                        PRESSURE_LAW_ALLOWED % MIN_LAW_PRESSURE_PA,
                        PRESSURE_LAW_REASON % exponent)]
    return []


@dataclass(frozen=True)
class TireParameters:
    """In-plane ring tire data (defaults: GL073A_tied, the GL073A 16.00R20 truck tire of the
    seed paper with its sidewall tied to the tread above order 8, docs/theory.md §8.10; the
    paper's own sidewall is ``sidewall_max_order=0``, the shipped GL073A tire file).

    ``m_s``, ``k_r1``, ``k_r2`` and ``k_cw`` are per metre of tread circumference; with these
    readings eq. 12 of the paper gives the published frequencies and the total masses are
    80.2 kg (tread) and 40.8 kg (sidewall). See :data:`TIRE_FIELDS` for units and ranges.
    """

    R: float = 0.65
    b: float = 0.35
    inflation_pressure: float = 7.9e5
    rhoA: float = 19.64
    m_s: float = 10.0
    k_r1: float = 6.686e6
    k_r2: float = 4.431e6
    EI: float = 25.697
    k_cw: float = 5.93e8
    alpha: float = 8.2e-5
    beta: float = 1.1e-4
    sidewall_shear: float = 0.0
    sidewall_max_order: float = 8.0
    sidewall_pressure_exponent: float = 0.0
    reference_pressure: float = 7.9e5

    def __post_init__(self) -> None:
        problems = tire_problems(self.as_dict())
        if problems:
            raise ParameterError(problems)
        for f in fields(self):
            object.__setattr__(self, f.name, float(getattr(self, f.name)))

    def as_dict(self) -> dict[str, float]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @property
    def pretension_n(self) -> float:
        """Inflation pre-tension of the tread, P = p0·b·R (eq. 9)."""
        return self.inflation_pressure * self.b * self.R

    @property
    def circumference_m(self) -> float:
        return 2.0 * math.pi * self.R

    @property
    def max_patch_length_m(self) -> float:
        return MAX_PATCH_FRACTION * self.circumference_m

    @property
    def sidewall_stiffness_factor(self) -> float:
        """(p0/p_ref)^e, the pressure law's factor on the sidewall stiffnesses (1 when off).

        A pneumatic sidewall is a pressurised membrane: its radial and shear stiffness grow
        with inflation pressure, which the paper's constant k_r1, k_r2 leave out, so the
        vertical stiffness falls too little with pressure (see docs/theory.md, §4).
        """
        if self.sidewall_pressure_exponent == 0.0:
            return 1.0
        ratio = self.inflation_pressure / self.reference_pressure
        return ratio**self.sidewall_pressure_exponent

    @property
    def effective_k_r1(self) -> float:
        """k_r1 at the inflation pressure (N/m per metre): what the model uses."""
        return self.k_r1 * self.sidewall_stiffness_factor

    @property
    def effective_k_r2(self) -> float:
        """k_r2 at the inflation pressure (N/m per metre): what the model uses."""
        return self.k_r2 * self.sidewall_stiffness_factor

    @property
    def effective_sidewall_shear(self) -> float:
        """sidewall_shear at the inflation pressure (N): what the model uses."""
        return self.sidewall_shear * self.sidewall_stiffness_factor

    @property
    def sidewall_band_hz(self) -> float:
        """Natural frequency of a sidewall mass between fixed tread and rim, the band limit."""
        k = self.effective_k_r1 + self.effective_k_r2
        return math.sqrt(k / self.m_s) / (2.0 * math.pi)


@dataclass(frozen=True)
class OperatingPoint:
    """Where the tire is linearised: mesh, contact (load or patch length) and speed.

    Give at most one of ``load_n`` and ``patch_length_m``; with neither, the load defaults to
    :data:`DEFAULT_LOAD_N`. A load gives the footprint the model computes; a patch length is
    the paper's prescribed patch (``patch_length_m = 0``: the undeformed tire, no contact).
    ``allow_supercritical`` lets a speed at or above the critical (standing-wave) speed through.
    ``contact_zone_length_m`` is the length of road under the nodes that may meet the road,
    ``contact_point_spacing_m`` the largest distance between the contact points on the tread.
    """

    n_elements: int = 100
    load_n: float | None = None
    patch_length_m: float | None = None
    speed_m_s: float = 0.0
    allow_supercritical: bool = False
    contact_zone_length_m: float = 0.6  # contact.DEFAULT_ZONE_LENGTH_M
    contact_point_spacing_m: float = DEFAULT_POINT_SPACING_M

    def __post_init__(self) -> None:
        problems = operating_point_problems(self.as_dict())
        if problems:
            raise ParameterError(problems)
        object.__setattr__(self, "n_elements", int(self.n_elements))

    def as_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @property
    def requested_load_n(self) -> float | None:
        if self.load_n is None and self.patch_length_m is None:
            return DEFAULT_LOAD_N
        return self.load_n


_OP_UNITS = {"load_n": "N", "patch_length_m": "m", "speed_m_s": "m/s"}


def operating_point_problems(
    values: Mapping[str, Any], tire: TireParameters | None = None
) -> list[Problem]:
    """Problems with operating-point values on their own and, given ``tire``, for that tire."""
    problems = []
    known = [f.name for f in fields(OperatingPoint)]
    for name in sorted(set(values) - set(known), key=str):
        problems.append(Problem(str(name), values[name], "",
                                f"one of the operating-point settings {', '.join(known)}",
                                "unknown operating-point setting"))
    n = values.get("n_elements", 100)
    if isinstance(n, np.integer):
        n = int(n)
    integral = isinstance(n, int) or (isinstance(n, (float, np.floating))
                                      and math.isfinite(n) and float(n).is_integer())
    if isinstance(n, bool) or not integral or not MIN_ELEMENTS <= int(n) <= MAX_ELEMENTS:
        problems.append(Problem("n_elements", n, "",
                                f"an integer in [{MIN_ELEMENTS}, {MAX_ELEMENTS}]",
                                ELEMENTS_REASON))
    load, patch = values.get("load_n"), values.get("patch_length_m")
    if load is not None and patch is not None:
        problems.append(Problem("patch_length_m", patch, "m", "unset when load_n is given",
                                "the patch length is computed from the load"))
    max_patch = tire.max_patch_length_m if tire is not None else None
    for name, unit in _OP_UNITS.items():
        value = values.get(name)
        if value is None:
            continue
        try:
            number = float(value)
        except (TypeError, ValueError):
            problems.append(Problem(name, value, "", f"a finite number >= 0 {unit}"))
            continue
        if not math.isfinite(number) or number < 0:
            problems.append(Problem(name, number, unit, f"a finite number >= 0 {unit}"))
        elif name == "speed_m_s" and 0 < number < MIN_ROLLING_SPEED_M_S:
            problems.append(Problem(
                name, number, unit, f"0 or at least {MIN_ROLLING_SPEED_M_S:g} {unit}",
                "slower is at rest to rounding, and the road would take days to cross the "
                "patch"))
        elif name == "patch_length_m" and max_patch is not None and number > max_patch:
            problems.append(Problem(
                name, number, unit, f"in [0, {max_patch:.4g}] m",
                f"at most {MAX_PATCH_FRACTION:g} of the circumference, beyond which the linear "
                "ring is not credible"))
    problems += point_spacing_range_problems(
        values.get("contact_point_spacing_m", DEFAULT_POINT_SPACING_M))
    return problems


def point_spacing_range_problems(spacing_m) -> list[Problem]:
    """The contact points' spacing on its own (how many points it makes on a mesh:
    :func:`.contact.point_spacing_problems`)."""
    try:
        number = float(spacing_m)
    except (TypeError, ValueError):
        number = math.nan
    if MIN_POINT_SPACING_M <= number <= MAX_POINT_SPACING_M:  # false for nan
        return []
    return [Problem("contact_point_spacing_m", spacing_m if math.isnan(number) else number,
                    "m", POINT_SPACING_ALLOWED % (MIN_POINT_SPACING_M, MAX_POINT_SPACING_M),
                    POINT_SPACING_REASON)]


#: The stiffest local term of the tire may exceed the ring's weakest support at most this many
#: times: the static solution's relative error grows as the rounding unit times this ratio
#: (about 2e-6 at the limit), and near 1e16 the factorisation breaks down. The masses are
#: checked on the model's eigenvalues (tire_fmu.core.model.check_resolved).
MAX_STIFFNESS_RATIO = 1e10
#: What the conditioning check says (printf, so the native FMU renders the same): the reason;
#: what is allowed for the stiff term's field; or for the weaker spring.
CONDITIONING_REASON = ("the ring's support on k_r1 and k_r2 in series, %.3g N/m^2, may be at "
                       "most %g times weaker than the stiffest term, %s (%.3g N/m^2), or double "
                       "precision loses the static solution")
CONDITIONING_STIFF_ALLOWED = ("at most %.3g %s with these springs on this mesh (fewer "
                              "n_elements raise the bound)")
CONDITIONING_WEAK_ALLOWED = "at least %.3g N/m^2 with these data"
CONDITIONING_WEAK_LARGER = "larger, with the other spring above %.3g N/m^2"
#: The stiff local terms the check weighs, in its order, by the field that sets each.
STIFF_TERMS = {
    "k_cw": "the tread on k_r1 and the contact stiffness k_cw",
    "EI": "the tread's bending EI at the mesh's shortest wavelength",
    "inflation_pressure": "the tread's inflation tension at the mesh's shortest wavelength",
    "sidewall_shear": "the sidewall on k_r1 + k_r2 and its shear",
}


def conditioning_problems(tire: TireParameters, n_elements: int) -> list[Problem]:
    """Whether double precision resolves the static response of ``tire`` on this mesh.

    Local stiffnesses per metre of circumference, the FDM operators' largest symbols at the
    node spacing ds: bending 16 EI/ds^4, tension 4 P/ds^2 (likewise the sidewall shear), the
    springs as they are. The weakest support is the ring on k_r1 and k_r2 in series. The
    problem names the side that is further from the default tire's (GL073A) on this mesh: an
    upper bound for the stiff term, or a lower bound for the weaker spring.
    """
    ds = tire.R * 2.0 * math.pi / n_elements
    limit = MAX_STIFFNESS_RATIO * tire.k_r1 * tire.k_r2 / (tire.k_r1 + tire.k_r2)
    stiffest = max(_stiff_terms(tire, ds).items(), key=lambda item: item[1][0])
    (field, what), (stiffness, bound) = stiffest
    if stiffness <= limit:
        return []
    reference = TireParameters()
    support = limit / MAX_STIFFNESS_RATIO
    reference_support = reference.k_r1 * reference.k_r2 / (reference.k_r1 + reference.k_r2)
    too_stiff = stiffness / _stiff_terms(reference, ds)[(field, what)][0]
    reason = CONDITIONING_REASON % (support, MAX_STIFFNESS_RATIO, what, stiffness)
    if too_stiff >= reference_support / support:
        allowed = bound(limit)
        if allowed is not None:
            unit = TIRE_FIELDS[field].unit
            return [Problem(field, getattr(tire, field), unit,
                            CONDITIONING_STIFF_ALLOWED % (allowed, unit), reason)]
    weak, other = ("k_r2", tire.k_r1) if tire.k_r2 <= tire.k_r1 else ("k_r1", tire.k_r2)
    needed = stiffness / MAX_STIFFNESS_RATIO  # for the support in series
    allowed = (CONDITIONING_WEAK_ALLOWED % (needed * other / (other - needed)) if other > needed
               else CONDITIONING_WEAK_LARGER % needed)
    return [Problem(weak, getattr(tire, weak), TIRE_FIELDS[weak].unit, allowed, reason)]


def _stiff_terms(tire: TireParameters, ds: float) -> dict:
    """(field, what) -> (local stiffness N/m^2, the field's value at which it reaches a limit,
    or None when no value of the field alone would do)."""
    def above(value):
        return value if value > 0 else None

    what = STIFF_TERMS
    return {
        ("k_cw", what["k_cw"]):
            (tire.k_r1 + tire.k_cw, lambda limit: above(limit - tire.k_r1)),
        ("EI", what["EI"]):
            (16.0 * tire.EI / ds**4, lambda limit: limit * ds**4 / 16.0),
        ("inflation_pressure", what["inflation_pressure"]):
            (4.0 * tire.pretension_n / ds**2,
             lambda limit: limit * ds**2 / (4.0 * tire.b * tire.R)),
        ("sidewall_shear", what["sidewall_shear"]):
            (tire.k_r1 + tire.k_r2 + 4.0 * tire.sidewall_shear / ds**2,
             lambda limit: above((limit - tire.k_r1 - tire.k_r2) * ds**2 / 4.0)),
    }


def validate(
    tire_values: Mapping[str, Any] | None = None,
    op_values: Mapping[str, Any] | None = None,
) -> tuple[TireParameters, OperatingPoint]:
    """Tire data and operating point from plain values, reporting all problems at once.

    The checks that need an assembled model (a load beyond what the longest credible patch
    carries, a speed at or above the critical speed) run when the model is built, see
    :func:`tire_fmu.core.model.build_model`.
    """
    tire_values = dict(tire_values or {})
    op_values = dict(op_values or {})
    problems = tire_problems(tire_values)
    tire = None if problems else TireParameters(**tire_values)
    problems += operating_point_problems(op_values, tire)
    if problems:
        raise ParameterError(problems)
    return tire, OperatingPoint(**op_values)
