"""Helpers for the native FMU's tests: an fmpy runner that records statuses and log lines, the
excitations of the acceptance runs, and the comparison rule."""

from __future__ import annotations

import json
import math
import os
import shutil
import stat
import subprocess
import sys
from ctypes import byref
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    defaultCallbacks,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy

OUTPUTS = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length",
           "tread_deflection")
INPUTS = ("rim_z", "rim_vz", "road_z", "road_vz")
H = 1e-4
NATIVE_HOST = Path(__file__).parent / "native_host"
WINDOWS_TOOLS = ("x86_64-w64-mingw32-gcc", "wine")
needs_windows_tools = pytest.mark.skipif(
    not all(shutil.which(tool) for tool in WINDOWS_TOOLS),
    reason="needs x86_64-w64-mingw32-gcc and wine (.ci/run installs them: apt-get install "
           "gcc-mingw-w64-x86-64 wine64)")


def declared_dependencies(path) -> dict[str, list[str] | None]:
    """{output: the inputs its ModelStructure/Outputs entry lists}, read from the FMU's own
    modelDescription.xml (None where it has no ``dependencies``: every input, to FMI)."""
    import zipfile
    from xml.etree import ElementTree

    with zipfile.ZipFile(path) as archive:
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    names = [v.get("name") for v in root.find("ModelVariables")]
    found = {}
    for unknown in root.find("ModelStructure").find("Outputs"):
        text = unknown.get("dependencies")
        found[names[int(unknown.get("index")) - 1]] = (
            None if text is None else [names[int(i) - 1] for i in text.split()])
    return found


@dataclass
class Opened:
    """An extracted FMU, opened once per test session."""

    path: str
    model_description: object
    folder: str

    @classmethod
    def of(cls, path) -> Opened:
        return cls(str(path), read_model_description(str(path)), extract(str(path)))

    @property
    def vr(self) -> dict[str, int]:
        return {v.name: v.valueReference for v in self.model_description.modelVariables}


@dataclass
class Instance:
    """One FMU instance through fmpy with its log captured."""

    fmu: Opened
    name: str = "tire"
    logging_on: bool = True
    log: list[tuple[int, str, str]] = field(default_factory=list)

    def __post_init__(self):
        md = self.fmu.model_description
        self.slave = FMU2Slave(guid=md.guid, unzipDirectory=self.fmu.folder,
                               modelIdentifier=md.coSimulation.modelIdentifier,
                               instanceName=self.name)

        def logger(component, instance, status, category, message):
            self.log.append((status, (category or b"").decode(), (message or b"").decode()))

        self._logger = fmi2CallbackLoggerTYPE(logger)  # keep a reference while in use
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = self._logger
        callbacks.allocateMemory = defaultCallbacks.allocateMemory
        callbacks.freeMemory = defaultCallbacks.freeMemory
        addLoggerProxy(byref(callbacks))
        self._callbacks = callbacks
        self.slave.instantiate(callbacks=callbacks, loggingOn=self.logging_on)
        self.vr = self.fmu.vr
        self.inputs = [self.vr[n] for n in INPUTS]
        self.outputs = [self.vr[n] for n in OUTPUTS]

    def set(self, **values) -> None:
        for name, value in values.items():
            v = next(x for x in self.fmu.model_description.modelVariables if x.name == name)
            if v.type == "Integer":
                self.slave.setInteger([v.valueReference], [int(value)])
            elif v.type == "Boolean":
                self.slave.setBoolean([v.valueReference], [bool(value)])
            else:
                self.slave.setReal([v.valueReference], [float(value)])

    def initialise(self, start_time: float = 0.0, **parameters) -> int:
        self.slave.setupExperiment(startTime=start_time)
        self.slave.enterInitializationMode()
        self.set(**parameters)
        return self.call("fmi2ExitInitializationMode")

    def call(self, function: str, *args) -> int:
        """The status of an fmi2 function (fmpy raises for worse than warning: return it)."""
        try:
            return getattr(self.slave, function)(self.slave.component, *args)
        except FMICallException as error:
            return int(str(error).split("status ")[1].split(" ")[0])

    def step(self, t: float, h: float = H) -> int:
        return self.call("fmi2DoStep", t, h, True)

    def outputs_now(self) -> list[float]:
        return self.slave.getReal(self.outputs)

    def errors(self) -> list[str]:
        return [m for s, _, m in self.log if s >= 3]

    def free(self) -> None:
        self.slave.terminate()
        self.slave.freeInstance()


def road_drop(t: float) -> tuple[float, float, float, float]:
    """A 5 cm drop of the road for 50 ms and back: the tread leaves the road and lands."""
    return 0.0, 0.0, (-0.05 if 0.02 <= t < 0.07 else 0.0), 0.0


def rim_lift(t: float) -> tuple[float, float, float, float]:
    """The rim lifted 8 cm and lowered again as a 20 Hz cosine (ramped with its velocity)."""
    w = 2 * math.pi * 20.0
    if t < 0.05:
        return 0.04 * (1 - math.cos(w * t)), 0.04 * w * math.sin(w * t), 0.0, 0.0
    return 0.0, 0.0, 0.0, 0.0


def run(fmu: Opened, parameters: dict, signal, steps: int = 1500, h: float = H,
        read_first: bool = False) -> np.ndarray:
    """Outputs (steps + 1, 6) of the usual host loop: set the inputs, step, get the outputs;
    ``read_first`` also reads the outputs before every third step (direct feedthrough)."""
    instance = Instance(fmu, logging_on=False)
    status = instance.initialise(**parameters)
    assert status == 0, instance.errors()
    rows = [instance.outputs_now()]
    for k in range(steps):
        t = k * h
        instance.slave.setReal(instance.inputs, list(signal(t)))
        if read_first and k % 3 == 0:
            instance.outputs_now()
        instance.slave.doStep(t, h)
        rows.append(instance.outputs_now())
    instance.free()
    return np.array(rows)


def relative_errors(reference: np.ndarray, other: np.ndarray) -> np.ndarray:
    """Per output: the largest difference over the run, relative to the largest magnitude of
    its kind (forces: rim_Fz, whose static load sets the scale; lengths: their own)."""
    force_scale = np.abs(reference[:, 0]).max()
    scales = np.array([force_scale, force_scale, force_scale,
                       *np.abs(reference[:, 3:]).max(axis=0)])
    return np.abs(reference - other).max(axis=0) / scales


def _tbb_library_folder() -> str:
    for file in metadata.files("tbb") or ():
        if file.name.startswith("libtbb.so"):
            return str(Path(file.locate()).parent)
    raise AssertionError("the tbb wheel (test extra) has no libtbb.so")


def in_host(fmu, host: str, load: float, speed: float, tmp_path, inplane: bool = False
            ) -> np.ndarray:
    """400 steps of native_host/other_hosts.py's run of ``fmu`` in ``host`` (fmpy, libcosimpy,
    ecospy), in a subprocess; ``inplane``: an in-plane FMU (its outputs, its wheel braked)."""
    out = tmp_path / f"{host}.json"
    env = dict(os.environ)
    if host == "ecospy":
        env["LD_LIBRARY_PATH"] = os.pathsep.join(
            [_tbb_library_folder(), env.get("LD_LIBRARY_PATH", "")])
        from importlib.util import find_spec  # importing ecospy here would need libtbb loaded

        for proxy in Path(find_spec("ecospy").origin).parent.glob("binaries/proxyfmu"):
            proxy.chmod(proxy.stat().st_mode | stat.S_IXUSR)  # the wheel ships it without
    command = [sys.executable, str(NATIVE_HOST / "other_hosts.py"), str(fmu), host,
               repr(load), repr(speed), "400", str(out)] + (["inplane"] if inplane else [])
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, env=env)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    return np.array(json.loads(out.read_text()))


def compile_host(folder: Path, windows: bool) -> Path:
    """native_host/host.c for Linux or Windows, against the FMU unpacked in ``folder`` (its
    sources/: the FMI headers and spec.h, which says where its outputs are)."""
    out = folder / ("host.exe" if windows else "host")
    compiler = "x86_64-w64-mingw32-gcc" if windows else "gcc"
    command = [compiler, "-O2", "-Wall", "-I", str(folder / "sources"), "-o", str(out),
               str(NATIVE_HOST / "host.c")] + ([] if windows else ["-ldl"])
    subprocess.run(command, check=True, capture_output=True)
    return out


def run_host(host: Path, binary: Path, guid: str, commands: Path) -> list[str]:
    command = [str(host), str(binary), guid, str(commands)]
    env = dict(os.environ)
    if host.suffix == ".exe":
        command = ["wine", *command]
        env["WINEDEBUG"] = "-all"
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, env=env)
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout.splitlines()


def host_outputs(lines: list[str]) -> np.ndarray:
    return np.array([[float(x) for x in line.split()[1:]] for line in lines
                     if line.startswith("out ")])
