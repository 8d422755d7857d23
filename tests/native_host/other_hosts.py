"""Run a native FMU in another host and write its outputs as JSON (run in a subprocess: libcosim
aborts its process on an FMU error, and ecospy needs libtbb on LD_LIBRARY_PATH at start).

    python other_hosts.py FMU HOST LOAD SPEED STEPS OUT.json     (HOST: fmpy, libcosimpy, ecospy)

Every host runs the same loop: set road_z, step h = 1e-4 s, read the outputs.
"""

import json
import sys

NAMES = ["rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length", "tread_deflection"]
H = 1e-4


def road(k: int) -> float:
    """A 5 cm drop of the road for 15 ms: the tread leaves the road and lands."""
    return -0.05 if 100 <= k < 250 else 0.0


def with_libcosimpy(fmu, load, speed, steps):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_step_size(step_size=int(round(H * 1e9)))
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=fmu, instance_name="tire"))
    vr = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    execution.real_initial_value(index, vr["load"], load)
    execution.real_initial_value(index, vr["speed"], speed)
    override = CosimManipulator.create_override()
    execution.add_manipulator(override)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    rows = []
    for k in range(steps):
        override.slave_real_values(index, [vr["road_z"]], [road(k)])
        execution.step()
        rows.append(observer.last_real_values(index, [vr[n] for n in NAMES]))
    return rows


def with_ecospy(fmu, load, speed, steps):
    from ecospy import EcosSimulation, EcosSimulationStructure

    structure = EcosSimulationStructure()
    structure.add_model("tire", fmu)
    structure.add_parameter_set("initial", {"tire::load": load, "tire::speed": speed})
    simulation = EcosSimulation(structure=structure, step_size=H)
    simulation.init(parameter_set="initial")
    rows = []
    for k in range(steps):
        simulation.set_real("tire::road_z", road(k))
        simulation.step()
        rows.append([simulation.get_real("tire::" + n) for n in NAMES])
    simulation.terminate()
    return rows


def with_fmpy(fmu, load, speed, steps):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="tire")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr["load"], vr["speed"]], [load, speed])
    slave.exitInitializationMode()
    rows = []
    for k in range(steps):
        slave.setReal([vr["road_z"]], [road(k)])
        slave.doStep(k * H, H)
        rows.append(slave.getReal([vr[n] for n in NAMES]))
    slave.terminate()
    slave.freeInstance()
    return rows


if __name__ == "__main__":
    fmu, host, load, speed, steps, out = sys.argv[1:]
    run = {"fmpy": with_fmpy, "libcosimpy": with_libcosimpy, "ecospy": with_ecospy}[host]
    rows = run(fmu, float(load), float(speed), int(steps))
    with open(out, "w") as stream:
        json.dump(rows, stream)
