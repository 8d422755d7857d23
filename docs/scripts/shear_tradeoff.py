"""Table of docs/theory.md §8.8: GL073A re-identified for each sidewall shear G.

For each G the analytic table of tire_fmu/data/tires/GL073A_modes.csv (n = 0-6 and 8, both
branches) is fitted with m_s, k_r1, k_r2 and b free on the N = 100 mesh, minimax
(as GL073A_shear.toml was made), then the critical speed is computed on four meshes.

Run:  python3 docs/scripts/shear_tradeoff.py
"""

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tire_fmu.core import TireParameters, critical_speed  # noqa: E402
from tire_fmu.core.fit import fit_tire  # noqa: E402
from tire_fmu.measurements import read_modes  # noqa: E402
from tire_fmu.tire_files import shipped_tire_path  # noqa: E402

MESHES = (100, 200, 400, 800)
modes = read_modes(shipped_tire_path("GL073A").with_name("GL073A_modes.csv"))
print("| G [N] | max error at N = 100 [%] | c = sqrt(G/m_s) [m/s] | "
      + " | ".join(f"V_c N = {n} [m/s]" for n in MESHES) + " | V_c(100)/V_c(400) |")
print("|" + "---|" * (4 + len(MESHES)))
for shear in (0.0, 2e3, 4e3, 6e3, 8e3, 1e4, 3e4, 1e5):
    start = replace(TireParameters(), sidewall_shear=shear)
    result = fit_tire(modes, ("m_s", "k_r1", "k_r2", "b"), start, n_elements=100,
                      criterion="max")
    tire = result.tire
    speeds = [critical_speed(tire, n).speed_m_s for n in MESHES]
    worst = np.max(np.abs(result.residual_percent))
    wave = np.sqrt(tire.sidewall_shear / tire.m_s)
    print(f"| {shear:g} | {worst:.2f} | {wave:.1f} | "
          + " | ".join(f"{v:.1f}" for v in speeds) + f" | {speeds[0] / speeds[2]:.2f} |")
