"""``QuarterCar``: body and wheel as a pythonfmu co-simulation slave, and its builder.

The slave needs only numpy, scipy and pythonfmu: the builder ships this file alone, under a
distinctive module name (pythonfmu FMUs in one process share ``sys.modules``).

Input ``rim_Fz`` is the tire's TOTAL vertical force on the rim (what ``TireModal.fmu``
outputs); the slave subtracts the static load (m_b + m_w)·g itself, so gravity, suspension
preload and static tire load never appear and the states are deviations from equilibrium.
Over a step the force ramps from ``rim_Fz`` with slope ``rim_Fz_rate`` (0: held), and the
step is exact for that ramp: the matrix exponential of the augmented system

    d/dt [x, u, u̇] = [[A, B, 0], [0, 0, 1], [0, 0, 0]] [x, u, u̇],

cached per step size. A host that knows the force at both ends of the step (the Gauss-Seidel
master in :mod:`vehicle_demo.cosim`) passes the slope between them: first-order hold.

Outputs are the state at the end of the step and the accelerations there, computed with the
force at the end of the ramp. Bad parameters, non-finite inputs or h <= 0 refuse the step
(fmi2Discard) with a logged message; nothing raises into the host.
"""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status
from scipy.linalg import expm

try:  # inside the FMU the dynamics module sits next to the slave, in resources/
    from vehicle_demo_quarter_car_dynamics import (
        QuarterCarError,
        QuarterCarParameters,
        two_mass_state_space,
    )
except ImportError:  # in the package
    from vehicle_demo.vehicle_demo_quarter_car_dynamics import (
        QuarterCarError,
        QuarterCarParameters,
        two_mass_state_space,
    )

DYNAMICS_MODULE = "vehicle_demo_quarter_car_dynamics"

#: (name, start, unit, description) of the parameters (from QuarterCarParameters), inputs and
#: outputs.
PARAMETERS = tuple((f.metadata["fmu_name"], f.default, f.metadata["unit"],
                    f.metadata["description"]) for f in fields(QuarterCarParameters))
INPUTS = (
    ("rim_Fz", QuarterCarParameters().static_tire_load_n, "N",
     "vertical force of the tire on the rim, TOTAL (static load included), z up"),
    ("rim_Fz_rate", 0.0, "N/s", "slope of rim_Fz over the step (0 = held)"),
)
OUTPUTS = (
    ("wheel_z", "m", "wheel vertical displacement from static equilibrium (z up)"),
    ("wheel_vz", "m/s", "wheel vertical velocity"),
    ("wheel_az", "m/s2", "wheel vertical acceleration"),
    ("body_z", "m", "body vertical displacement from static equilibrium"),
    ("body_vz", "m/s", "body vertical velocity"),
    ("body_az", "m/s2", "body vertical acceleration"),
    ("suspension_travel", "m", "body minus wheel displacement (extension positive)"),
)


class QuarterCar(Fmi2Slave):
    """Two-mass quarter car: rim force in, wheel and body motion out (exact linear step)."""

    author = "tire_fmu contributors"
    description = ("Quarter car (body, suspension, wheel) for TireModal.fmu: input the tire's "
                   "total rim force, outputs deviations from static equilibrium. Exact step "
                   "for a force ramped over the step.")
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=1.0, step_size=1e-4)

    def __init__(self, **kwargs):
        # Cheap on purpose: pythonfmu instantiates the slave at build time.
        super().__init__(**kwargs)
        # Every variable's value by value reference (the registration order below): the host's
        # get/set calls index this list directly, which costs a few hundred ns where
        # pythonfmu's per-variable getters and type checks cost microseconds a step.
        self._values: list[float] = ([start for _, start, _, _ in PARAMETERS + INPUTS]
                                     + [0.0] * len(OUTPUTS))
        self._x = (0.0, 0.0, 0.0, 0.0)  # [z_b, ż_b, z_w, ż_w]
        self._cache: dict[float, tuple] = {}
        self._system = None
        self._problem = "the FMU is not initialised (call fmi2ExitInitializationMode)"
        for name, _, _, text in PARAMETERS:  # units: written at build time
            self._register(Real(name, causality=Fmi2Causality.parameter,
                                variability=Fmi2Variability.fixed,
                                initial=Fmi2Initial.exact, description=text))
        for name, _, _, text in INPUTS:
            self._register(Real(name, causality=Fmi2Causality.input,
                                variability=Fmi2Variability.continuous, description=text))
        for name, _, text in OUTPUTS:
            # the experiment starts in static equilibrium: every deviation is exactly 0
            self._register(Real(name, causality=Fmi2Causality.output,
                                variability=Fmi2Variability.continuous,
                                initial=Fmi2Initial.exact, description=text))

    def _register(self, variable: Real) -> None:
        vr = len(self.vars)
        variable.getter = lambda: self._values[vr]
        if variable.causality != Fmi2Causality.output:
            def setter(value):
                self._values[vr] = value
            variable.setter = setter
        self.register_variable(variable)

    def get_real(self, vrs):
        values = self._values
        try:
            return [values[vr] for vr in vrs]
        except (IndexError, TypeError):
            return super().get_real(vrs)  # raises with pythonfmu's message

    def set_real(self, vrs, values):
        if vrs == _INPUT_VRS:  # the master's call: both inputs, in order
            self._values[_INPUTS] = values
        else:
            super().set_real(vrs, values)

    def exit_initialization_mode(self):
        try:
            car = QuarterCarParameters.from_fmu_values(
                {name: value for (name, *_), value in zip(PARAMETERS, self._values)})
        except QuarterCarError as error:
            self._problem = f"parameters rejected: {error}"
            self.log(f"QuarterCar rejected its parameters: {error}", Fmi2Status.error)
            self._system = None
            return
        a, b = two_mass_state_space(car.body_mass_kg, car.wheel_mass_kg,
                                    car.suspension_stiffness_n_per_m,
                                    car.suspension_damping_n_s_per_m)
        self._system = (a, b, car.static_tire_load_n)
        self._cache.clear()
        self._problem = ""

    def _coefficients(self, h: float) -> tuple:
        """Rows of [Φ | Γ0 | Γ1] for the state and [A | B] for the accelerations, as tuples
        of floats: a 4-state step in plain Python costs less than the numpy calls would."""
        cached = self._cache.get(h)
        if cached is None:
            a, b, _ = self._system
            aug = np.zeros((6, 6))
            aug[:4, :4] = a
            aug[:4, 4] = b
            aug[4, 5] = 1.0  # u' = u̇, u̇' = 0: the force ramp
            e = expm(aug * h)
            step_rows = tuple(tuple(float(v) for v in row) for row in e[:4, :6])
            acc_rows = tuple(tuple(float(v) for v in np.r_[a[i], b[i]]) for i in (1, 3))
            cached = (step_rows, acc_rows)
            if len(self._cache) > 32:
                self._cache.clear()
            self._cache[h] = cached
        return cached

    def do_step(self, current_time: float, step_size: float) -> bool:
        if self._system is None:
            self.log(f"doStep at t = {current_time!r} s refused: {self._problem}",
                     Fmi2Status.discard)
            return False
        values = self._values
        force, rate = values[_FORCE], values[_RATE]
        if not (step_size > 0 and math.isfinite(step_size)) or not (
                math.isfinite(force) and math.isfinite(rate)):
            self.log(f"doStep at t = {current_time!r} s refused: h = {step_size!r} s, "
                     f"rim_Fz = {force!r} N, rim_Fz_rate = {rate!r} N/s (h must be > 0 and "
                     "inputs finite); state unchanged", Fmi2Status.discard)
            return False
        step_rows, (body_row, wheel_row) = self._coefficients(step_size)
        x0, x1, x2, x3 = self._x
        u = force - self._system[2]
        r0, r1, r2, r3 = step_rows
        x0, x1, x2, x3 = (
            r0[0] * x0 + r0[1] * x1 + r0[2] * x2 + r0[3] * x3 + r0[4] * u + r0[5] * rate,
            r1[0] * x0 + r1[1] * x1 + r1[2] * x2 + r1[3] * x3 + r1[4] * u + r1[5] * rate,
            r2[0] * x0 + r2[1] * x1 + r2[2] * x2 + r2[3] * x3 + r2[4] * u + r2[5] * rate,
            r3[0] * x0 + r3[1] * x1 + r3[2] * x2 + r3[3] * x3 + r3[4] * u + r3[5] * rate,
        )
        self._x = (x0, x1, x2, x3)
        u_end = u + rate * step_size
        r, w = body_row, wheel_row
        # outputs in OUTPUTS order: wheel z, vz, az, body z, vz, az, suspension travel
        values[_OUTPUTS] = (
            x2, x3, w[0] * x0 + w[1] * x1 + w[2] * x2 + w[3] * x3 + w[4] * u_end,
            x0, x1, r[0] * x0 + r[1] * x1 + r[2] * x2 + r[3] * x3 + r[4] * u_end,
            x0 - x2,
        )
        return True


#: Value references, fixed by the registration order (parameters, inputs, outputs).
_INPUTS = slice(len(PARAMETERS), len(PARAMETERS) + len(INPUTS))
_INPUT_VRS = list(range(_INPUTS.start, _INPUTS.stop))
_FORCE, _RATE = _INPUT_VRS
_OUTPUTS = slice(_INPUTS.stop, _INPUTS.stop + len(OUTPUTS))
assert [name for name, *_ in OUTPUTS] == ["wheel_z", "wheel_vz", "wheel_az", "body_z",
                                          "body_vz", "body_az", "suspension_travel"]


# -- builder (host side only) ----------------------------------------------------------------

MODEL_IDENTIFIER = "QuarterCar"
SLAVE_MODULE = "vehicle_demo_quarter_car_slave_1"
CAPABILITIES = {
    "canHandleVariableCommunicationStepSize": True,  # coefficients cached per h
    "canGetAndSetFMUstate": False,
    "canSerializeFMUstate": False,
}


def build_quarter_car_fmu(out_dir=".", validate: bool = True):
    """Write ``QuarterCar.fmu`` into ``out_dir`` and return its path.

    Built like ``TireModal.fmu`` (``tire_fmu.fmu.builder.build_pythonfmu``): units written
    into the model description, and fmpy's validation must report no problem. The slave ships
    with the numpy-only dynamics module it shares with the frequency-domain references.
    """
    from pathlib import Path

    from tire_fmu.fmu.builder import build_pythonfmu

    here = Path(__file__).parent
    units = {name: unit for name, _, unit, _ in PARAMETERS + INPUTS}
    units.update({name: unit for name, unit, _ in OUTPUTS})
    return build_pythonfmu(Path(__file__), Path(out_dir) / f"{MODEL_IDENTIFIER}.fmu",
                           SLAVE_MODULE, project_files=[here / f"{DYNAMICS_MODULE}.py"],
                           capabilities=CAPABILITIES, units=units, validate=validate)
