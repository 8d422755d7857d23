"""Run a native FMU in another host and write its outputs as JSON (run in a subprocess: libcosim
aborts its process on an FMU error, and ecospy needs libtbb on LD_LIBRARY_PATH at start).

    python other_hosts.py FMU HOST LOAD SPEED STEPS OUT.json [inplane]
        (HOST: fmpy, libcosimpy, ecospy)

Every host runs the same loop: set the inputs, step h = 1e-4 s, read the outputs. The radial
FMU: road_z drops. ``inplane``: the in-plane FMU's outputs, its wheel centre rolling at
``speed`` along a level host road (road_z_i left at 0), lifted off the road and put back
(lift), and braked.
"""

import json
import math
import sys

RADIAL = ["rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length", "tread_deflection"]
INPLANE = ["rim_Fz", "rim_Fx", "rim_My", "contact_Fz", "contact_Fx", "wheel_spin",
           "sliding_points"]
NAMES = RADIAL
H = 1e-4


def road(k: int) -> float:
    """A 5 cm drop of the road for 15 ms: the tread leaves the road and lands."""
    return -0.05 if 100 <= k < 250 else 0.0


#: In-plane only: the wheel centre's lift (m), when it starts and ends (steps), how long its way
#: up and down takes (steps)
LIFT_M, UP, DOWN, UP_STEPS, DOWN_STEPS = 0.025, 100, 220, 100, 150


def lift(k: int) -> tuple[float, float]:
    """In-plane only: the wheel centre lifted off the road (2.5 cm, the static deflection 1.6
    cm) from 10 ms on and put back from 22 ms on, on (1 - cos) ramps: its height and its rate,
    a wheel the host moves (it lands at about 2 m/s), not a jump, which no tire's inertia
    follows."""
    def ramp(j, steps):
        u = min(max(j / steps, 0.0), 1.0)
        return (0.5 * LIFT_M * (1.0 - math.cos(math.pi * u)),
                0.5 * LIFT_M * math.pi / (steps * H) * math.sin(math.pi * u))
    up, down = ramp(k - UP, UP_STEPS), ramp(k - DOWN, DOWN_STEPS)
    return up[0] - down[0], up[1] - down[1]


def torque(k: int) -> float:
    """In-plane only: a brake torque from 5 ms on."""
    return -2500.0 if k >= 50 else 0.0


#: In-plane only: the speed and the wheel centre's height at load (its start value)
ROLLING = {"speed": 0.0, "height": 0.0}


def inputs(k: int) -> dict[str, float]:
    """The inputs each host sets before step k (their values at k H)."""
    if NAMES is not INPLANE:
        return {"road_z": road(k)}
    speed, (height, rate) = ROLLING["speed"], lift(k)
    return {"wheel_x": speed * k * H, "wheel_vx": speed, "wheel_z": ROLLING["height"] + height,
            "wheel_vz": rate, "wheel_torque": torque(k)}


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
        given = inputs(k)
        override.slave_real_values(index, [vr[n] for n in given], list(given.values()))
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
        for name, value in inputs(k).items():
            simulation.set_real("tire::" + name, value)
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
        given = inputs(k)
        slave.setReal([vr[n] for n in given], list(given.values()))
        slave.doStep(k * H, H)
        rows.append(slave.getReal([vr[n] for n in NAMES]))
    slave.terminate()
    slave.freeInstance()
    return rows


if __name__ == "__main__":
    fmu, host, load, speed, steps, out = sys.argv[1:7]
    if sys.argv[7:] == ["inplane"]:
        from fmpy import read_model_description

        NAMES = INPLANE
        ROLLING["speed"] = float(speed)
        ROLLING["height"] = float(next(v.start for v in read_model_description(fmu)
                                       .modelVariables if v.name == "wheel_z"))
    run = {"fmpy": with_fmpy, "libcosimpy": with_libcosimpy, "ecospy": with_ecospy}[host]
    rows = run(fmu, float(load), float(speed), int(steps))
    with open(out, "w") as stream:
        json.dump(rows, stream)
