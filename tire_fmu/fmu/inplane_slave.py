"""``TireInPlane``: the in-plane tire (tangential tread motion, the wheel's rotation, friction in
the footprint) as a pythonfmu co-simulation slave.

The FMI layer is :class:`~tire_fmu.fmu.slave.TireModal`'s (the state machine, refusals,
messages and FMU-state bytes of :mod:`tire_fmu.fmu.spec`); what differs is the model: at
initialisation the parameters go through :func:`~tire_fmu.core.inplane_host.build_host_stepper`
(every problem at once), and each ``do_step`` advances its
:class:`~tire_fmu.core.inplane_contact.InPlaneStepper` with the rim's motion, the torque and
the road at the contact zone's front. The outputs are those at the end of the last step (no
direct feed-through: a host reading after setting inputs gets the last step's forces).

A step the tire refuses (its contact sets did not settle, a step size that is not a whole
number of the tire's ``step_size``) leaves the FMU as it was: the stepper is checkpointed
before the step and rolled back.
"""

from __future__ import annotations

import math
import struct
import time

import tire_fmu
from tire_fmu.core.blas_threads import blas_threads
from tire_fmu.core.host_inputs import MIN_STEP_S
from tire_fmu.core.inplane import TANGENTIAL_RANGES
from tire_fmu.core.inplane_contact import (
    STEPPER_STATE_HEAD,
    ContactSetError,
    RunningLimitError,
    host_step_work,
)
from tire_fmu.core.inplane_host import FMU_NAMES, HostSettings, build_host_stepper
from tire_fmu.core.parameters import TIRE_FIELDS, ParameterError
from tire_fmu.core.step_limits import MAX_STEP_WORK
from tire_fmu.fmu.interface import (
    INPLANE_IN_CONTACT,
    INPLANE_INPUTS,
    INPLANE_OUTPUTS,
    MAX_STEP_S,
    TIME_ABS_TOLERANCE_S,
    TIME_REL_TOLERANCE,
    inplane_fmu_variables,
)
from tire_fmu.fmu.slave import TireModal, _cause, _input_problem
from tire_fmu.fmu.spec import MESSAGES, STATE_MODEL_FLAGS, Phase, fmu_message

MODEL_IDENTIFIER = "TireInPlane"
#: Where the stepper's state holds its elapsed time (after its head and 17 scalars).
STEPPER_ELAPSED_OFFSET = struct.calcsize(STEPPER_STATE_HEAD) + 8 * 17
#: The in-plane FMU's names for the core's settings (HostSettings), for its messages.
INPLANE_FMU_NAMES = FMU_NAMES
#: Every tangential datum is a parameter (loss_factor too: it was once left out of the build,
#: so the FMU ran without the hysteretic loss whatever it was given)
_TANGENTIAL = tuple(TANGENTIAL_RANGES)


class TireInPlane(TireModal):
    """In-plane ring tire with tangential motion and friction: rim motion, torque and road
    in; Fx, Fz and the axle moment out."""

    description = ("Open in-plane ring tire with tangential tread motion, the wheel's "
                   "rotation and Coulomb friction in the footprint (0-300 Hz): Fx, Fz and the "
                   "axle moment My from the rim's motion, the wheel torque and the road; "
                   "reduced step built at initialisation for the load and speed. Needs Python "
                   "with numpy and scipy.")
    model_identifier = MODEL_IDENTIFIER
    _INPUTS, _OUTPUTS, _IN_CONTACT = INPLANE_INPUTS, INPLANE_OUTPUTS, INPLANE_IN_CONTACT

    @staticmethod
    def _variables(parameter_values):
        return inplane_fmu_variables(parameter_values)

    # -- building the model ------------------------------------------------------------------
    def _build(self, parameters: tuple) -> tuple:
        named = {self._table[vr].name: value for vr, value in zip(self._parameter_vrs,
                                                                   parameters)}
        settings = HostSettings(
            tire={name: named[name] for name in TIRE_FIELDS},
            tangential={name: named[name] for name in _TANGENTIAL},
            load_n=named["load"], speed_m_s=named["speed"],
            n_elements=int(named["n_elements"]), f_max_hz=named["f_max"],
            zone_length_m=named["contact_zone_length"],
            point_spacing_m=named["contact_point_spacing"], step_s=named["step_size"],
            wheel_free=bool(named["wheel_free"]), wheel_driven=bool(named["wheel_driven"]))
        library, why = self._kernel_library()
        self._kernel_note = why or "stepping with the compiled in-plane step"
        with blas_threads():  # the build's BLAS threads limited, the host's given back after
            stepper = build_host_stepper(settings, "compiled" if library else "numpy", library)
        self._say_if_blas_unlimited()
        return stepper, None, []

    def _set_simulator(self, simulator, built_for) -> None:
        self._simulator, self._built_for = simulator, built_for

    def _initialise(self) -> None:
        started = time.perf_counter()
        parameters = self._parameter_values()
        try:
            model = self._build(parameters)[0]
        except ParameterError as error:
            self._refuse_parameters([fmu_message(text)
                                     for text in error.render(INPLANE_FMU_NAMES)])
            return
        self._set_simulator(model, parameters)
        self._checked_h = math.nan
        self._phase = Phase.RUNNING
        self._contact_warning_armed = True
        outputs = model.stepper.outputs()
        self._show_outputs(outputs)
        self._contact_logged = self._values[self._IN_CONTACT]
        self._stale = False
        summary = model.summary()
        self.log(
            f"TireInPlane ready in {time.perf_counter() - started:.2f} s: N = "
            f"{summary['n_elements']}, {summary['coordinates']} coordinates, "
            f"{summary['contact_points']} contact points ({summary['points_in_contact']} on "
            f"the road), deflection {summary['deflection_m'] * 1e3:.4g} mm, critical speed "
            f"{summary['critical_speed_m_s']:.4g} m/s, {self._kernel_note}; core tire_fmu "
            f"{tire_fmu.__version__} from {tire_fmu.__file__}")

    def _show_outputs(self, out) -> None:
        values = self._values
        values[self._OUTPUTS] = [out.rim_fz_n, out.rim_fx_n, out.rim_my_n_m, out.contact_fz_n,
                                 out.contact_fx_n, out.spin_rad_s, float(out.sliding_points)]
        values[self._IN_CONTACT] = out.contact_fz_n > 0.0

    # -- stepping ----------------------------------------------------------------------------
    def do_step(self, current_time: float, step_size: float) -> bool:
        if self._phase != Phase.RUNNING:
            return self._allowed("fmi2DoStep")
        now = self._now
        if current_time != now and not abs(current_time - now) <= max(
                TIME_ABS_TOLERANCE_S, TIME_REL_TOLERANCE * abs(now)):
            return self._refuse_step(current_time, step_size, MESSAGES["NOT_LAST_POINT"] % (
                repr(float(current_time)), repr(now)))
        if not 0.0 < step_size <= MAX_STEP_S:  # false for nan too
            return self._refuse_step(current_time, step_size, MESSAGES["STEP_RANGE"] % (
                repr(float(step_size)), MAX_STEP_S))
        if not step_size >= MIN_STEP_S:
            return self._refuse_step(current_time, step_size, MESSAGES["INPLANE_STEP_SHORT"] % (
                repr(float(step_size)), MIN_STEP_S))
        stepper = self._simulator.stepper
        sim = stepper.sim
        count, length, per, longest, too_much = host_step_work(
            step_size, sim.step_s, sim._ny, sim._zone.n_points, current_time)
        if too_much:
            return self._refuse_step(current_time, step_size, MESSAGES["LONG_STEP"] % (
                repr(float(step_size)), count, length, per, MAX_STEP_WORK, longest))
        z, vz, road_z, road_vz, x, vx, torque, rate = self._values[self._INPUTS]
        before = stepper.checkpoint()
        try:
            out = stepper.advance(step_size, x, vx, z, vz, torque, road_z, road_vz, rate,
                                  at_time_s=current_time)
        except ContactSetError as error:
            stepper.rollback(before)
            return self._refuse_step(current_time, step_size, f"{error}; nothing changed "
                                     "(a shorter step_size settles the sets sooner)")
        except RunningLimitError as error:
            stepper.rollback(before)
            return self._refuse_step(current_time, step_size, str(error))
        except Exception as error:  # an escaping exception would be fmi2Fatal
            stepper.rollback(before)
            self._fail(MESSAGES["STEP_FAILED"] % repr(float(current_time)), _cause(error))
            return False
        if not math.isfinite(out.rim_fz_n + out.rim_fx_n + out.rim_my_n_m + out.spin_rad_s):
            self._fail(MESSAGES["STEP_FAILED"] % repr(float(current_time)),
                       MESSAGES["NOT_FINITE_OUTPUTS"])
            return False
        self._show_outputs(out)
        self._now = current_time + step_size
        in_contact = self._values[self._IN_CONTACT]
        if in_contact is not self._contact_logged:
            self._contact_event(in_contact)
        return True

    def _refresh(self) -> bool:
        # no feed-through: the outputs are the last step's whatever the inputs now are
        self._stale = False
        return True

    def get_real(self, vrs):
        if vrs == self._output_vrs and self._phase == Phase.RUNNING:
            return self._values[self._OUTPUTS]
        return self._get("fmi2GetReal", vrs, "Real", float, 0.0)

    def get_boolean(self, vrs):
        return self._get("fmi2GetBoolean", vrs, "Boolean", bool, False)

    def set_real(self, vrs, values):
        if vrs == self._input_vrs and self._phase == Phase.RUNNING:
            table = self._table
            if not any(_input_problem(table[vr], value) for vr, value in zip(vrs, values)):
                self._values[self._INPUTS] = values
                return
        self._set("fmi2SetReal", vrs, values, "Real")

    # -- the model's part of an FMU state: the stepper's bytes ---------------------------------
    def _model_state_bytes(self) -> bytes:
        return self._simulator.stepper.state_bytes()

    @staticmethod
    def _model_part_problem(simulator, model: bytes, values: list, time_s: float,
                            start: float) -> str | None:
        flags_size = 4 * STATE_MODEL_FLAGS
        if len(model) < flags_size:
            return MESSAGES["STATE_MODEL_SHORT"] % len(model)
        for i, flag in enumerate(struct.unpack_from(f"<{STATE_MODEL_FLAGS}i", model)):
            if flag not in (0, 1):
                return MESSAGES["STATE_MODEL_FLAG"] % (i, flag)
        stepper = simulator.stepper
        part = model[flags_size:]
        problem = stepper.state_problem(part)
        if problem:
            return problem
        elapsed = struct.unpack_from("<d", part, STEPPER_ELAPSED_OFFSET)[0]
        if not abs(start + elapsed - time_s) <= max(TIME_ABS_TOLERANCE_S,
                                                     TIME_REL_TOLERANCE * abs(time_s)) + 1e-9:
            return MESSAGES["STATE_MODEL_CLOCK"] % (repr(time_s), repr(start),
                                                    repr(start + elapsed), repr(start))
        return None

    @staticmethod
    def _set_model_state(simulator, data: bytes) -> None:
        simulator.stepper.set_state_bytes(data)
