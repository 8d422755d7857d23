"""Tire data and operating point, with validation that reports every problem at once.

Units are SI throughout. The tire data follow the seed paper's symbols (Tables 1 and 2,
GL073A truck tire) read as the design brief says: every line quantity (masses and radial
stiffnesses) is per metre of tread circumference, and EI is in N·m². A finite-difference node
carries ``value × R·δθ`` of each line quantity.

One table (:data:`TIRE_FIELDS`) describes every tire field: symbol, unit, description and
allowed range. Validation, the CLI help, the FMU variables and the docs all read it, so the
ranges live in one place.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

#: Default static load (N): one wheel of a heavy vehicle, 2820 kg under standard gravity, a
#: service load of the GL073A (16.00R20) truck tire. A plain number: whoever runs the tire
#: (a vehicle model, the FMU's host) sets the load its own wheel carries.
DEFAULT_LOAD_N = 27_654.753

#: Longest contact patch the linear ring model is trusted with, as a fraction of the
#: circumference. Beyond ~45° of wrap the small-deflection ring and the flat-road chord
#: geometry used to relate load and patch length both stop being credible.
MAX_PATCH_FRACTION = 1.0 / 8.0

#: The 5-point bending stencil needs distinct neighbours two nodes away on both sides, and the
#: lowest ring orders (n <= 2) need a few nodes per wavelength to be meaningful.
MIN_ELEMENTS = 8
MAX_ELEMENTS = 20_000


class ParameterError(ValueError):
    """Invalid tire data or operating point; ``problems`` lists every one found."""

    def __init__(self, problems: list[str]):
        self.problems = list(problems)
        if len(self.problems) == 1:
            message = self.problems[0]
        else:
            message = f"{len(self.problems)} parameter problems: " + "; ".join(self.problems)
        super().__init__(message)


@dataclass(frozen=True)
class FieldSpec:
    """What a parameter means and which values the model accepts."""

    name: str
    unit: str
    description: str
    low: float
    high: float
    low_inclusive: bool = False

    def problem(self, value: Any) -> str | None:
        """Return a message naming the field, its value and the allowed range, or None."""
        try:
            number = float(value)
        except (TypeError, ValueError):
            return f"{self.name} = {value!r}: must be a number in {self.range_text()}"
        if not math.isfinite(number):
            return f"{self.name} = {value!r}: must be finite, in {self.range_text()}"
        below = number < self.low if self.low_inclusive else number <= self.low
        if below or number > self.high:
            return f"{self.name} = {number:g} {self.unit}: must be in {self.range_text()}"
        return None

    def range_text(self) -> str:
        left = "[" if self.low_inclusive else "("
        return f"{left}{self.low:g}, {self.high:g}] {self.unit}".rstrip()


TIRE_FIELDS: dict[str, FieldSpec] = {
    spec.name: spec
    for spec in (
        FieldSpec("R", "m", "tread (belt) radius", 0.1, 3.0),
        FieldSpec("b", "m", "tread width", 0.01, 2.0),
        FieldSpec("inflation_pressure", "Pa", "inflation pressure p0", 0.0, 3.0e6, True),
        FieldSpec("rhoA", "kg/m", "tread mass per metre of circumference", 0.0, 1.0e4),
        FieldSpec("m_s", "kg/m", "sidewall mass per metre of circumference", 0.0, 1.0e4),
        FieldSpec("k_r1", "N/m^2", "tread-sidewall radial stiffness per metre", 0.0, 1.0e12),
        FieldSpec("k_r2", "N/m^2", "sidewall-rim radial stiffness per metre", 0.0, 1.0e12),
        FieldSpec("EI", "N*m^2", "tread bending stiffness", 0.0, 1.0e8),
        FieldSpec("k_cw", "N/m^2", "contact-patch radial stiffness per metre", 0.0, 1.0e13),
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
            0.0,
            3.0e6,
        ),
    )
}

#: The sidewall stiffnesses the pressure law scales.
PRESSURE_SCALED_FIELDS = ("k_r1", "k_r2", "sidewall_shear")


def tire_problems(values: Mapping[str, Any]) -> list[str]:
    """Every problem with a set of tire data, checked field by field."""
    problems = []
    for name, spec in TIRE_FIELDS.items():
        if name in values:
            problem = spec.problem(values[name])
            if problem:
                problems.append(f"{problem} ({spec.description})")
    unknown = sorted(set(values) - set(TIRE_FIELDS))
    if unknown:
        problems.append(f"unknown tire parameter(s) {unknown}; known: {sorted(TIRE_FIELDS)}")
    if not problems:
        problems += _pressure_law_problems(values)
    return problems


def _pressure_law_problems(values: Mapping[str, Any]) -> list[str]:
    defaults = {f.name: f.default for f in fields(TireParameters)}
    exponent = float(values.get("sidewall_pressure_exponent",
                                defaults["sidewall_pressure_exponent"]))
    pressure = float(values.get("inflation_pressure", defaults["inflation_pressure"]))
    if exponent > 0.0 and pressure == 0.0:
        return [f"inflation_pressure = 0 Pa with sidewall_pressure_exponent = {exponent:g}: the "
                "pressure law would leave the sidewall without stiffness; give a pressure > 0 "
                "or set the exponent to 0"]
    return []


@dataclass(frozen=True)
class TireParameters:
    """In-plane ring tire data (defaults: GL073A 16.00R20 truck tire of the seed paper).

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
    ``contact_zone_length_m`` is the length of road under the nodes that may meet the road.
    """

    n_elements: int = 100
    load_n: float | None = None
    patch_length_m: float | None = None
    speed_m_s: float = 0.0
    allow_supercritical: bool = False
    contact_zone_length_m: float = 0.6  # contact.DEFAULT_ZONE_LENGTH_M

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
) -> list[str]:
    """Problems with operating-point values on their own and, given ``tire``, for that tire."""
    problems = []
    known = {f.name for f in fields(OperatingPoint)}
    unknown = sorted(set(values) - known)
    if unknown:
        problems.append(f"unknown operating-point setting(s) {unknown}; known: {sorted(known)}")
    n = values.get("n_elements", 100)
    if isinstance(n, np.integer):
        n = int(n)
    integral = isinstance(n, int) or (isinstance(n, (float, np.floating)) and float(n).is_integer())
    if isinstance(n, bool) or not integral:
        problems.append(
            f"n_elements = {n!r}: must be an integer in [{MIN_ELEMENTS}, {MAX_ELEMENTS}]"
        )
    elif not MIN_ELEMENTS <= int(n) <= MAX_ELEMENTS:
        problems.append(
            f"n_elements = {n}: must be in [{MIN_ELEMENTS}, {MAX_ELEMENTS}] "
            "(the 5-point bending stencil needs at least 8 nodes around the ring)"
        )
    load, patch = values.get("load_n"), values.get("patch_length_m")
    if load is not None and patch is not None:
        problems.append(
            f"load_n = {load!r} N and patch_length_m = {patch!r} m both given: "
            "give one, the other is computed from it"
        )
    max_patch = tire.max_patch_length_m if tire is not None else None
    for name, unit in _OP_UNITS.items():
        value = values.get(name)
        if value is None:
            continue
        try:
            number = float(value)
        except (TypeError, ValueError):
            number = math.nan
        if not math.isfinite(number) or number < 0:
            problems.append(f"{name} = {value!r}: must be a finite number >= 0 {unit}")
        elif name == "patch_length_m" and max_patch is not None and number > max_patch:
            problems.append(
                f"patch_length_m = {number:g} m: must be in [0, {max_patch:.4g}] m, at most "
                f"{MAX_PATCH_FRACTION:g} of the circumference, beyond which the linear ring "
                "is not credible"
            )
    return problems


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
