"""The quarter car's parameters and equations of motion, numpy only.

The one definition of the car: :class:`QuarterCarParameters` (fields, defaults, units, the FMU
variable each field becomes, validation) and gravity. The frequency-domain references
(``quarter_car.py``), the master (``cosim.py``) and the QuarterCar FMU's slave all read it; the
slave ships this module in its ``resources/`` (hence the distinctive name: pythonfmu FMUs in
one process share ``sys.modules``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

#: Standard gravity (m/s²), the one value every part of the demo uses.
GRAVITY_M_S2 = 9.80665


def _parameter(default: float, fmu_name: str, unit: str, description: str):
    return field(default=default, metadata={"fmu_name": fmu_name, "unit": unit,
                                            "description": description})


class QuarterCarError(ValueError):
    """Invalid quarter-car parameters; ``problems`` lists every one."""

    def __init__(self, problems: list[str]):
        self.problems = list(problems)
        super().__init__("; ".join(self.problems))


@dataclass(frozen=True)
class QuarterCarParameters:
    """One corner of a heavy vehicle (design-brief defaults); each field's metadata names the
    QuarterCar FMU parameter it becomes, with its unit and description."""

    body_mass_kg: float = _parameter(2500.0, "body_mass", "kg",
                                     "sprung (body) mass of the corner")
    wheel_mass_kg: float = _parameter(320.0, "wheel_mass", "kg",
                                      "unsprung mass: wheel and axle share, without the tire")
    suspension_stiffness_n_per_m: float = _parameter(
        80e3, "suspension_stiffness", "N/m", "suspension spring between body and wheel")
    suspension_damping_n_s_per_m: float = _parameter(
        8.5e3, "suspension_damping", "N.s/m", "suspension damper between body and wheel")
    gravity_m_s2: float = _parameter(GRAVITY_M_S2, "gravity", "m/s2",
                                     "gravitational acceleration")

    def __post_init__(self) -> None:
        problems = []
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                problems.append(f"{f.name} = {value!r}: must be a finite number > 0")
        if problems:
            raise QuarterCarError(problems)

    @property
    def static_tire_load_n(self) -> float:
        """The load the tire carries at rest: the tire FMU's ``load`` must equal it."""
        return (self.body_mass_kg + self.wheel_mass_kg) * self.gravity_m_s2

    def with_static_load(self, load_n: float) -> QuarterCarParameters:
        """The same car with the body mass that puts ``load_n`` on the tire (the wheel mass is
        a property of the axle, the payload is what changes)."""
        body = load_n / self.gravity_m_s2 - self.wheel_mass_kg
        if body <= 0:
            raise QuarterCarError([f"load = {load_n:g} N: must exceed the wheel's weight "
                                   f"{self.wheel_mass_kg * self.gravity_m_s2:.6g} N"])
        return replace(self, body_mass_kg=body)

    def as_dict(self) -> dict[str, float]:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def fmu_values(self) -> dict[str, float]:
        """The parameters under the QuarterCar FMU's names."""
        return {f.metadata["fmu_name"]: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_fmu_values(cls, values: dict) -> QuarterCarParameters:
        """The car from FMU parameter values (raises QuarterCarError naming every bad one)."""
        return cls(**{f.name: values[f.metadata["fmu_name"]] for f in fields(cls)})


def two_mass_state_space(body_mass_kg: float, wheel_mass_kg: float,
                         suspension_stiffness_n_per_m: float,
                         suspension_damping_n_s_per_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of x = [z_b, ż_b, z_w, ż_w] with input ΔF_rim (N) on the wheel."""
    m_b, m_w = body_mass_kg, wheel_mass_kg
    k, c = suspension_stiffness_n_per_m, suspension_damping_n_s_per_m
    a = np.array([
        [0.0, 1.0, 0.0, 0.0],
        [-k / m_b, -c / m_b, k / m_b, c / m_b],
        [0.0, 0.0, 0.0, 1.0],
        [k / m_w, c / m_w, -k / m_w, -c / m_w],
    ])
    b = np.array([0.0, 0.0, 0.0, 1.0 / m_w])
    return a, b
