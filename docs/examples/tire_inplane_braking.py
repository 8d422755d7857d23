"""TireInPlane.fmu braking a car's corner on a road file, in a hand-written loop.

    tire-fmu build-fmu dist --inplane                  # dist/TireInPlane.fmu
    tire-fmu road iso8608 --class B --length 60 --out road.crg
    python docs/examples/tire_inplane_braking.py dist/TireInPlane.fmu road.crg

The in-plane tire turns its wheel under wheel_torque and returns the fore-aft force: the car
(its corner's mass, the axle at the loaded radius) slows under the tire's own rim_Fx, read
with the slip and the effective rolling radius the tire reports.
"""

import sys

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

fmu, road = sys.argv[1:3] if len(sys.argv) > 2 else ("dist/TireInPlane.fmu", "road.crg")
corner_kg, speed, h = 2800.0, 20.0, 1e-3               # kg, m/s, s
brake_n_m = -2000.0                                    # against the rolling

md = read_model_description(fmu)
vr = {v.name: v.valueReference for v in md.modelVariables}
tire = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu),
                 modelIdentifier=md.coSimulation.modelIdentifier, instanceName="tire")
tire.instantiate()
tire.setupExperiment(startTime=0.0)
tire.enterInitializationMode()
tire.setReal([vr["load"], vr["speed"]], [corner_kg * 9.81, speed])
tire.setString([vr["road_file"]], [road])
tire.exitInitializationMode()
wheel_z = tire.getReal([vr["loaded_radius"]])[0]       # the axle held at the loaded radius
inputs = [vr[n] for n in ("wheel_x", "wheel_vx", "wheel_z", "wheel_vz", "wheel_torque")]
outputs = [vr[n] for n in ("rim_Fx", "longitudinal_slip", "effective_rolling_radius")]
x, v, t = 1.0, speed, 0.0                              # 1 m into the road
for k in range(1000):                                  # 1 s: rolling 0.2 s, then the brake
    torque = brake_n_m if t >= 0.2 else 0.0
    tire.setReal(inputs, [x, v, wheel_z, 0.0, torque])
    tire.doStep(t, h)
    rim_Fx, slip, rolling_radius = tire.getReal(outputs)
    if k == 199:
        free_radius = rolling_radius
    v += h * rim_Fx / corner_kg                        # the tire's force slows the corner
    x += h * v
    t += h
tire.terminate()
tire.freeInstance()
print(f"{fmu}: free rolling at an effective radius of {free_radius:.4f} m; braking with "
      f"{-brake_n_m:.0f} N m: rim_Fx {rim_Fx:.0f} N, slip {100 * slip:.2f} %, "
      f"{speed:.0f} -> {v:.2f} m/s")
