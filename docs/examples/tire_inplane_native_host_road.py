"""TireInPlaneNative.fmu on a road the host owns, and then on the same road as a file.

    tire-fmu build-fmu dist --inplane --native         # dist/TireInPlaneNative.fmu
    python docs/examples/tire_inplane_native_host_road.py dist/TireInPlaneNative.fmu bump.csv

A host with its own road (a terrain, a test rig) leaves road_file empty: after each step the
tire says where it needs the road next (road_x_1, road_x_2, ..., m along the road) and the
host gives the heights there (road_z_1, road_z_2, ...) with the next step's inputs. The same
road written as a profile file (distance m, height m) and given as road_file gives the same
forces.
"""

import sys

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from tire_fmu.road_files import write_profile

fmu, profile = sys.argv[1:3] if len(sys.argv) > 2 else ("dist/TireInPlaneNative.fmu",
                                                        "bump.csv")


def road(x):
    """The host's road: a 15 mm, 0.4 m long rounded bump 3 m along, m."""
    return np.where(abs(x - 3.0) < 0.2, 0.0075 * (1 + np.cos(np.pi * (x - 3.0) / 0.2)), 0.0)


distances = np.arange(0.0, 10.0, 0.001)
write_profile(profile, distances, road(distances))
speed, h = 10.0, 1e-3
md = read_model_description(fmu)
vr = {v.name: v.valueReference for v in md.modelVariables}
unzipped = extract(fmu)
peaks = []
for road_file in ("", profile):                        # the host's road, then the file
    tire = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                     modelIdentifier=md.coSimulation.modelIdentifier, instanceName="tire")
    tire.instantiate()
    tire.setupExperiment(startTime=0.0)
    tire.enterInitializationMode()
    tire.setReal([vr["speed"]], [speed])
    tire.setString([vr["road_file"]], [road_file])
    tire.exitInitializationMode()
    wheel_z = tire.getReal([vr["loaded_radius"]])[0]
    count = sum(name.startswith("road_x_") for name in vr)   # the FMU says how many
    asked = [vr[f"road_x_{k}"] for k in range(1, count + 1)]
    given = [vr[f"road_z_{k}"] for k in range(1, count + 1)]
    inputs = [vr[n] for n in ("wheel_x", "wheel_vx", "wheel_z", "wheel_vz")]
    rim_Fz, t = [], 0.0
    for _ in range(500):
        tire.setReal(inputs, [1.0 + speed * t, speed, wheel_z, 0.0])
        if not road_file:                              # heights where the tire asked
            tire.setReal(given, list(road(np.array(tire.getReal(asked)))))
        tire.doStep(t, h)
        rim_Fz.append(tire.getReal([vr["rim_Fz"]])[0])
        t += h
    tire.terminate()
    tire.freeInstance()
    peaks.append(max(rim_Fz))
print(f"{fmu}: peak rim_Fz over the bump {peaks[0]:.1f} N on the host's road, "
      f"{peaks[1]:.1f} N on the same road as a file")
