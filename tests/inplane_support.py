"""Helpers for the in-plane FMUs' tests (TireInPlane, TireInPlaneNative): an fmpy instance
driven as a plain master drives it (the wheel centre's state and the host's road at t, then
fmi2DoStep(t, h)), with its log; the variables' names; the core's stepper the FMU runs."""

from ctypes import byref

import fmpy
import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy

from tire_fmu.fmu.interface import ROAD_QUERIES
from vehicle_demo.cosim import printed

#: The wheel centre's state and the wheel's coupling, at t (ISO 8855: x forward, z up).
CENTRE = ("wheel_x", "wheel_vx", "wheel_z", "wheel_vz", "wheel_torque", "wheel_rate")
ROAD_X = tuple(f"road_x_{i}" for i in range(1, ROAD_QUERIES + 1))
ROAD_Z = tuple(f"road_z_{i}" for i in range(1, ROAD_QUERIES + 1))
INPUTS = CENTRE + ROAD_Z
#: The forces and the wheel's state (the columns step() returns, in this order).
OUTPUTS = ("rim_Fz", "rim_Fx", "rim_My", "contact_Fz", "contact_Fx", "wheel_spin",
           "sliding_points")
#: What a host reads besides the forces.
WHEEL_OUTPUTS = ("loaded_radius", "effective_rolling_radius", "longitudinal_slip",
                 "contact_length")


def level(x):
    """A level road at the datum (the host's road when a test gives none)."""
    return np.zeros_like(np.asarray(x, dtype=float))


class Instance:
    """One in-plane FMU instance (TireInPlane or TireInPlaneNative) in fmpy, with its log.

    :meth:`step` gives the wheel centre at t, on the path of steady rolling at the ``speed``
    parameter at the loaded radius the FMU said after initialisation unless told otherwise
    (``wheel_x`` = ``x0`` + speed t, ``wheel_vx`` = speed, ``wheel_z`` = the loaded radius
    above the level road), and with no road file the host's road (``road``: heights by
    position, level by default) where the FMU asked for it."""

    def __init__(self, path, format_log: bool = False, x0: float = 0.0, **parameters):
        """``format_log``: the log through fmpy's printf proxy, for an FMU whose messages are
        formats with arguments (the native ones); it keeps one logger per process, so only
        the last such instance's log is its own."""
        md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
        starts = {v.name: v.start for v in md.modelVariables}
        self.speed = float(parameters.get("speed", starts.get("speed") or 0.0))
        self.road_file = parameters.get("road_file", "")
        self.x0 = float(x0)
        self.log = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(
            lambda env, name, status, category, message: self.log.append(
                (status, printed(message))))
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        if format_log:
            addLoggerProxy(byref(self.callbacks))
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path),
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName="inplane")
        self.fmu.instantiate(loggingOn=True, callbacks=self.callbacks)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in parameters.items():
            kind = self.types[name]
            setter = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
                      "Boolean": self.fmu.setBoolean, "String": self.fmu.setString}[kind]
            setter([self.vr[name]], [value])
        self.t = 0.0
        self.z0 = float(starts.get("wheel_z") or 0.0)
        self.last_road = None

    def start(self):
        # the wheel where the initialised tire carries its load, at the start of its travel
        self.fmu.setReal([self.vr["wheel_x"], self.vr["wheel_vx"]], [self.x0, self.speed])
        self.fmu.exitInitializationMode()
        self.z0 = self.read("loaded_radius")[0]
        return self

    def centre(self, t: float | None = None) -> dict:
        """The wheel centre rolling steadily at ``speed`` at the loaded radius, at ``t``."""
        t = self.t if t is None else t
        return {"wheel_x": self.x0 + self.speed * t, "wheel_vx": self.speed,
                "wheel_z": self.z0, "wheel_vz": 0.0}

    def inputs(self, road=level, **inputs) -> list[float]:
        """All the inputs at t: the named ones, the steady wheel centre's for the others, and
        the host's ``road`` at the positions the FMU asked for (recorded in ``last_road``)."""
        unknown = set(inputs) - set(CENTRE)
        if unknown:  # an old name (rim_z, road_z, ...) would otherwise be a silent zero
            raise TypeError(f"not inputs of the in-plane FMU: {sorted(unknown)}")
        values = self.centre() | inputs
        positions = np.array(self.read(*ROAD_X))
        heights = np.asarray(road(positions), dtype=float)
        self.last_road = (positions, heights)
        return [float(values.get(n, 0.0)) for n in CENTRE] + heights.tolist()

    def step(self, h, road=level, **inputs):
        self.fmu.setReal([self.vr[n] for n in INPUTS], self.inputs(road, **inputs))
        self.fmu.doStep(self.t, h)
        self.t += h
        return self.outputs()

    def read(self, *names) -> list[float]:
        return self.fmu.getReal([self.vr[n] for n in names])

    def outputs(self):
        return np.array(self.read(*OUTPUTS))

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def core_stepper(road_file: str = "", lateral_offset_m: float = 0.0, backend: str = "auto",
                 **settings):
    """The core's stepper the Python FMU runs for these settings (HostSettings' names), on the
    road it reads: the host's (a PositionRoad kept as the FMU keeps it) or a road file's."""
    from tire_fmu.core.inplane_contact import HOST_ROAD_MARGIN_M
    from tire_fmu.core.inplane_host import HostSettings, build_host_stepper
    from tire_fmu.core.obstacles import PositionRoad
    from tire_fmu.road_files import read_road_file

    host = HostSettings(**settings)
    road = (read_road_file(road_file, lateral_offset_m).road if road_file else
            PositionRoad(host.zone_length_m + HOST_ROAD_MARGIN_M))
    return build_host_stepper(host, backend, road=road).stepper
