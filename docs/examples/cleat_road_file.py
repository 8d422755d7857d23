"""A tire FMU over a cleat in a road file, through fmpy's simulate_fmu.

    tire-fmu build-fmu dist --inplane                  # dist/TireInPlane.fmu
    tire-fmu road cleat --out cleat.crg --lead-in 2 --lead-out 3  # 20 x 20 mm, 2 m along
    python docs/examples/cleat_road_file.py dist/TireInPlane.fmu cleat.crg

The cleat test of SAE J2730: the wheel centre held at the tire's loaded radius, rolling at
10 m/s. wheel_z is left at its start value, the default tire's loaded radius at the default
load, so the axle is where the tire carries that load.
"""

import sys

import numpy as np
from fmpy import read_model_description, simulate_fmu

fmu, road = sys.argv[1:3] if len(sys.argv) > 2 else ("dist/TireInPlane.fmu", "cleat.crg")
speed, h = 10.0, 1e-3                                  # m/s; the host's step, s
t = np.arange(0.0, 0.4, h)
# every input at its start value (simulate_fmu wants them all), the wheel's travel given
inputs = [v for v in read_model_description(fmu).modelVariables if v.causality == "input"]
signals = np.zeros(t.size, dtype=[("time", float)] + [(v.name, float) for v in inputs])
for v in inputs:
    signals[v.name] = float(v.start)
signals["time"] = t
signals["wheel_x"] = 0.5 + speed * t                   # the wheel centre along the road, m
signals["wheel_vx"] = speed
result = simulate_fmu(fmu, start_values={"speed": speed, "road_file": road},
                      input=signals, output=["rim_Fz", "rim_Fx", "loaded_radius", "in_contact"],
                      output_interval=h, stop_time=t[-1])
print(f"{fmu}: rim_Fz from {result['rim_Fz'][0]:.0f} N to a peak of "
      f"{result['rim_Fz'].max():.0f} N over the cleat, rim_Fx from "
      f"{result['rim_Fx'].min():.0f} to {result['rim_Fx'].max():.0f} N, loaded radius "
      f"{result['loaded_radius'][0]:.4f} m")
