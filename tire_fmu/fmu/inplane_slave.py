"""``TireInPlane``: the in-plane tire (tangential tread motion, the wheel's rotation, friction in
the footprint) as a pythonfmu co-simulation slave.

The FMI layer is :class:`~tire_fmu.fmu.slave.TireModal`'s (the state machine, refusals,
messages and FMU-state bytes of :mod:`tire_fmu.fmu.spec`); what differs is the model: at
initialisation the parameters go through :func:`~tire_fmu.core.inplane_host.build_host_stepper`
(every problem at once), and each ``do_step`` advances its
:class:`~tire_fmu.core.inplane_contact.InPlaneStepper` with the rim's motion, the torque and
the road by position: a road file's (``road_file``) or the host's, sampled where the FMU asks
(``road_x_i`` out, ``road_z_i`` in). The outputs are those at the end of the last step (no
direct feed-through: a host reading after setting inputs gets the last step's forces); after
initialisation, the static tire's at ``load`` (``loaded_radius`` is then where to place the
wheel centre above the road to carry it).

A step the tire refuses (its contact sets did not settle, a step size that is not a whole
number of the tire's ``step_size``) leaves the FMU as it was: the stepper is checkpointed
before the step and rolled back.
"""

from __future__ import annotations

import math
import struct
import time
from dataclasses import dataclass

from pythonfmu.enums import Fmi2Status

import tire_fmu
from tire_fmu.core.blas_threads import blas_threads
from tire_fmu.core.host_inputs import MIN_STEP_S
from tire_fmu.core.inplane import TANGENTIAL_RANGES
from tire_fmu.core.inplane_contact import (
    HOST_ROAD_MARGIN_M,
    STEPPER_STATE_HEAD,
    ContactSetError,
    RunningLimitError,
    host_step_work,
)
from tire_fmu.core.inplane_host import FMU_NAMES, HostModel, HostSettings, build_host_stepper
from tire_fmu.core.obstacles import PositionRoad
from tire_fmu.core.parameters import TIRE_FIELDS, ParameterError, Problem
from tire_fmu.core.step_limits import MAX_STEP_WORK
from tire_fmu.fmu.interface import (
    INPLANE_IN_CONTACT,
    INPLANE_INPUTS,
    INPLANE_OUTPUTS,
    MAX_STEP_S,
    ROAD_QUERIES,
    TIME_ABS_TOLERANCE_S,
    TIME_REL_TOLERANCE,
    inplane_fmu_variables,
)
from tire_fmu.fmu.slave import TireModal, _cause, _input_problem
from tire_fmu.fmu.spec import MESSAGES, STATE_MODEL_FLAGS, Phase, fmu_message
from tire_fmu.road_files import RoadFile, RoadFileError, read_road_file

MODEL_IDENTIFIER = "TireInPlane"
#: Where the stepper's state holds its elapsed time (after its head and 17 scalars).
STEPPER_ELAPSED_OFFSET = struct.calcsize(STEPPER_STATE_HEAD) + 8 * 17
#: The in-plane FMU's names for the core's settings (HostSettings), for its messages.
INPLANE_FMU_NAMES = FMU_NAMES
#: Every tangential datum is a parameter (loss_factor too: it was once left out of the build,
#: so the FMU ran without the hysteretic loss whatever it was given)
_TANGENTIAL = tuple(TANGENTIAL_RANGES)


@dataclass(frozen=True)
class BuiltTire:
    """What initialisation builds: the core's stepper and the road file it reads (None: the
    host's road)."""

    model: HostModel
    road_file: RoadFile | None

    @property
    def stepper(self):
        return self.model.stepper


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
        road, road_file, problems = _road(named, settings.zone_length_m)
        library, why = self._kernel_library()
        self._kernel_note = why or "stepping with the compiled in-plane step"
        try:
            with blas_threads():  # the build's BLAS threads limited, the host's given back
                model = build_host_stepper(settings, "compiled" if library else "numpy",
                                           library, road=road)
        except ParameterError as error:  # every problem at once, the road's first
            raise ParameterError(problems + error.details) from None
        finally:
            self._say_if_blas_unlimited()
        if problems:
            raise ParameterError(problems)
        return BuiltTire(model, road_file), None, []

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
        self._show_outputs(model.stepper.outputs())
        self._contact_logged = self._values[self._IN_CONTACT]
        self._stale = False
        self._extent_warning_armed = True
        summary = model.model.summary()
        self.log(
            f"TireInPlane ready in {time.perf_counter() - started:.2f} s: N = "
            f"{summary['n_elements']}, {summary['coordinates']} coordinates, "
            f"{summary['contact_points']} contact points ({summary['points_in_contact']} on "
            f"the road), deflection {summary['deflection_m'] * 1e3:.4g} mm, critical speed "
            f"{summary['critical_speed_m_s']:.4g} m/s, loaded radius "
            f"{model.stepper.loaded_radius_m:.6g} m, {_road_words(model.road_file)}, "
            f"{self._kernel_note}; core tire_fmu "
            f"{tire_fmu.__version__} from {tire_fmu.__file__}")

    def _show_outputs(self, out, step_s: float = 1e-3) -> None:
        """The outputs after a step of ``step_s`` (or initialisation: the static tire's, the
        wheel at the loaded radius; the host road asked for under the contact zone)."""
        values, stepper = self._values, self._simulator.stepper
        if stepper._origin is None:  # the static tire, its wheel where it carries the load
            x, vx = values[self._INPUTS.start], values[self._INPUTS.start + 1]
            z = stepper.road_height(x) + stepper.loaded_radius_m
        else:
            x, vx, z = stepper.wheel_centre()
        wheel = stepper.wheel_outputs(x, vx, z)
        queries = ([0.0] * ROAD_QUERIES if self._simulator.road_file is not None else
                   stepper.road_queries(ROAD_QUERIES, x, vx, step_s).tolist())
        values[self._OUTPUTS] = [
            out.rim_fz_n, out.rim_fx_n, out.rim_my_n_m, out.contact_fz_n, out.contact_fx_n,
            out.spin_rad_s, float(out.sliding_points), wheel["loaded_radius"],
            wheel["effective_rolling_radius"], wheel["longitudinal_slip"],
            wheel["contact_length"], *queries]
        values[self._IN_CONTACT] = out.contact_fz_n > 0.0
        self._road_x = queries

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
        inputs = self._values[self._INPUTS]
        x, vx, z, vz, torque, rate = inputs[:6]
        host_road = self._simulator.road_file is None
        before = stepper.checkpoint()
        try:
            out = stepper.advance_wheel(
                step_size, x, vx, z, vz, torque, rate if sim._driven else None,
                at_time_s=current_time, road_positions=self._road_x if host_road else None,
                road_heights=inputs[6:] if host_road else None)
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
        self._show_outputs(out, step_size)
        self._now = current_time + step_size
        in_contact = self._values[self._IN_CONTACT]
        if in_contact is not self._contact_logged:
            self._contact_event(in_contact)
        if not host_road:
            self._extent_warning(stepper)
        return True

    def _extent_warning(self, stepper) -> None:
        """Said once when a contact point's road leaves the road file's (beyond it the road is
        level at its end heights), and again after it has come back."""
        road_file = self._simulator.road_file
        x = stepper.wheel_centre()[0]
        sim = stepper.sim
        beyond = road_file.leaves_extent(x + float(sim._x_lo.min()), x + float(sim._x_hi.max()))
        if beyond and self._extent_warning_armed:
            first, last = road_file.extent_m
            self.log(MESSAGES["ROAD_EXTENT"] % (repr(float(self._now)), repr(float(x)),
                                                str(road_file.path), first, last),
                     Fmi2Status.warning)
        self._extent_warning_armed = not beyond

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

    def _restored(self) -> None:
        self._road_x = self._values[self._OUTPUTS][11:11 + ROAD_QUERIES]
        self._extent_warning_armed = True

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


def _road(named: dict, zone_length_m: float) -> tuple:
    """The road the parameters give: (the road by position, the road file read or None, the
    road_file's problems)."""
    path = named["road_file"]
    if not path:
        return PositionRoad(float(zone_length_m) + HOST_ROAD_MARGIN_M), None, []
    try:
        road_file = read_road_file(path, named["road_lateral_offset"])
    except (RoadFileError, OSError) as error:
        text = str(error)
        what = text[len(path) + 2:] if text.startswith(f"{path}: ") else text
        return PositionRoad(1.0), None, [Problem(
            "road_file", path, "", "an OpenCRG .crg or a two-column profile (distance m, "
            "height m) file that can be read", what)]
    return road_file.road, road_file, []


def _road_words(road_file) -> str:
    if road_file is None:
        return f"the host's road ({ROAD_QUERIES} heights a step at road_x_i)"
    first, last = road_file.extent_m
    return (f"road {road_file.path} ({road_file.data_format}, {first:.6g} to {last:.6g} m "
            "along it)")
