"""A tire FMU under a quarter car on an ISO 8608 road file, in a hand-written loop.

    tire-fmu build-fmu dist --inplane --native         # dist/TireInPlaneNative.fmu
    tire-fmu road iso8608 --class C --length 60 --out road.crg
    python docs/examples/quarter_car_road_file.py dist/TireInPlaneNative.fmu road.crg

A co-simulation master as a vehicle simulator writes it: over each step t -> t + h the tire
gets the wheel centre's state at t, steps, and its force at t + h moves the car's two masses
(semi-implicit Euler). The tire is built for the corner's load: the wheel starts at the
loaded_radius the FMU reads after initialisation, the spring carries the body.
"""

import sys

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

fmu, road = sys.argv[1:3] if len(sys.argv) > 2 else ("dist/TireInPlaneNative.fmu",
                                                         "road.crg")
body_kg, wheel_kg, spring_n_m, damper_n_s_m = 2500.0, 300.0, 3.0e5, 1.5e4
load = (body_kg + wheel_kg) * 9.81                     # the corner's static load, N
speed, h = 15.0, 1e-3

md = read_model_description(fmu)
vr = {v.name: v.valueReference for v in md.modelVariables}
tire = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu),
                 modelIdentifier=md.coSimulation.modelIdentifier, instanceName="tire")
tire.instantiate()
tire.setupExperiment(startTime=0.0)
tire.enterInitializationMode()
tire.setReal([vr["load"], vr["speed"]], [load, speed])
tire.setString([vr["road_file"]], [road])
tire.exitInitializationMode()                          # builds the reduced tire here
wheel_z = tire.getReal([vr["loaded_radius"]])[0]       # where the tire carries `load`
body_z = wheel_z + 0.5                                 # the spring's length is arbitrary
wheel_vz = body_vz = 0.0
inputs = [vr[n] for n in ("wheel_x", "wheel_vx", "wheel_z", "wheel_vz")]
peak, t = 0.0, 0.0
for _ in range(3000):                                  # 3 s, 45 m of road
    tire.setReal(inputs, [speed * t, speed, wheel_z, wheel_vz])
    tire.doStep(t, h)
    rim_Fz = tire.getReal([vr["rim_Fz"]])[0]
    # the suspension's force beyond the body's weight it carries at rest: up on the wheel
    suspension = spring_n_m * (body_z - wheel_z - 0.5) + damper_n_s_m * (body_vz - wheel_vz)
    wheel_vz += h * (rim_Fz - load + suspension) / wheel_kg
    body_vz -= h * suspension / body_kg
    wheel_z += h * wheel_vz
    body_z += h * body_vz
    peak = max(peak, abs(rim_Fz - load))
    t += h
tire.terminate()
tire.freeInstance()
print(f"{fmu}: the largest dynamic tire load over 45 m of road was {peak:.0f} N "
      f"({100 * peak / load:.1f} % of {load:.0f} N)")
