"""Helpers for the in-plane FMUs' tests (TireInPlane, TireInPlaneNative): an fmpy instance
with its log, the variables' names."""

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

from vehicle_demo.cosim import printed

INPUTS = ("rim_z", "rim_vz", "road_z", "road_vz", "rim_x", "rim_vx", "wheel_torque", "wheel_rate")
OUTPUTS = ("rim_Fz", "rim_Fx", "rim_My", "contact_Fz", "contact_Fx", "wheel_spin",
           "sliding_points")


class Instance:
    """One in-plane FMU instance (TireInPlane or TireInPlaneNative) in fmpy, with its log."""

    def __init__(self, path, format_log: bool = False, **parameters):
        """``format_log``: the log through fmpy's printf proxy, for an FMU whose messages are
        formats with arguments (the native ones); it keeps one logger per process, so only
        the last such instance's log is its own."""
        md = read_model_description(path)
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
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
                      "Boolean": self.fmu.setBoolean}[kind]
            setter([self.vr[name]], [value])
        self.t = 0.0

    def start(self):
        self.fmu.exitInitializationMode()
        return self

    def step(self, h, **inputs):
        self.fmu.setReal([self.vr[n] for n in INPUTS], [inputs.get(n, 0.0) for n in INPUTS])
        self.fmu.doStep(self.t, h)
        self.t += h
        return self.outputs()

    def outputs(self):
        return np.array(self.fmu.getReal([self.vr[n] for n in OUTPUTS]))

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
