"""TireInPlane.fmu in a host that has not imported tire_fmu: the FMU runs on the package it
carries in its resources, not on the one installed here.

Once, the slave's ``import tire_fmu`` found the host's package in ``sys.modules`` in every other
test of it, and a module the FMU's copy lacked went unseen (the C critical speed's ctypes,
needed at any speed above 0). The copy now goes by a name of its own (issue 35), and here a
fresh interpreter opens the FMU, checks that package came from its resources and that the
host's tire_fmu was never imported, and runs it rolling against the core's numbers."""

import json
import subprocess
import sys

import pytest

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from tire_fmu.core.inplane_host import HostSettings, build_host_stepper  # noqa: E402

pytestmark = pytest.mark.fmu

_HOST = r"""
import json, sys
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
assert "tire_fmu" not in sys.modules
path = sys.argv[1]
md = read_model_description(path)
vr = {v.name: v.valueReference for v in md.modelVariables}
folder = extract(path)
fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                modelIdentifier=md.coSimulation.modelIdentifier, instanceName="fresh")
fmu.instantiate()
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
fmu.setReal([vr["speed"]], [10.0])
fmu.exitInitializationMode()
radius = fmu.getReal([vr["loaded_radius"]])[0]
outputs = []
for k in range(20):  # rolling at 10 m/s at the loaded radius, braked
    fmu.setReal([vr[n] for n in ("wheel_x", "wheel_vx", "wheel_z", "wheel_torque")],
                [10.0 * k * 1e-3, 10.0, radius, -2000.0])
    fmu.doStep(k * 1e-3, 1e-3)
    outputs.append(fmu.getReal([vr["rim_Fz"], vr["rim_Fx"], vr["wheel_spin"]]))
with open(f"{folder}/resources/slavemodule.txt") as module:
    package = module.read().strip().removesuffix("_slave")
source = sys.modules[package].__file__
assert "tire_fmu" not in sys.modules
fmu.terminate()
fmu.freeInstance()
print(json.dumps({"source": str(source), "folder": str(folder), "outputs": outputs}))
"""


@pytest.fixture(scope="module")
def fmu_path(tmp_path_factory):
    from tire_fmu.fmu.builder import build_inplane_fmu

    return build_inplane_fmu(tmp_path_factory.mktemp("inplane_fresh"))


def test_a_fresh_host_runs_the_fmu_on_its_own_package_at_speed(fmu_path):
    done = subprocess.run([sys.executable, "-c", _HOST, str(fmu_path)], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    # the FMU's own copy of the package, not this checkout's
    assert report["source"].startswith(report["folder"])
    core = build_host_stepper(HostSettings(speed_m_s=10.0)).stepper
    for got in report["outputs"]:
        o = core.advance(1e-3, torque_n_m=-2000.0)
        assert got == pytest.approx([o.rim_fz_n, o.rim_fx_n, o.spin_rad_s], rel=1e-9, abs=1e-6)
    assert report["outputs"][-1][1] < -1e3  # the brake was felt
