"""What the footprint's regularisation of Coulomb friction does: the tread elements' stiffness
`k_tx` (a brush model's bristles: stick is elastic with the tread's shear compliance) scaled
from a quarter to four times the default, at 10 m/s and the default load, by
`steady_rolling` (a direct solve, no stepping).

Per stiffness: the footprint's length, the longitudinal slip stiffness C = dFx/dκ at a small
brake torque beside the brush model's 2 k_tx a² (a the footprint's half length, whatever the
pressure along it; its bristles stand on a rigid carcass, where this ring's own compliance
takes a share of the slip), and the slip and sliding points under a -3 and a -6 kN m brake.
Coulomb's law itself (μ f_n once an element slides) is not regularised: only the stick is
elastic.

    python benchmarks/bench_inplane_friction.py
    python benchmarks/bench_inplane_friction.py --record docs/measured/bench_inplane_friction.json
"""

from __future__ import annotations

import argparse
import os
import sys
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from benchmarks.record import load_average, write_record  # noqa: E402
from tire_fmu.core.inplane import InPlaneTire  # noqa: E402
from tire_fmu.core.inplane_contact import (  # noqa: E402
    InPlaneSimulator,
    deflection_for_load,
    steady_rolling,
)
from tire_fmu.core.parameters import DEFAULT_LOAD_N  # noqa: E402

SPEED_M_S, N, SPACING_M = 10.0, 100, 0.005
FACTORS = (0.25, 0.5, 1.0, 2.0, 4.0)
#: A torque small enough that no element slides (the slip stiffness's linear range).
SMALL_TORQUE_N_M = -300.0
BRAKES_N_M = (-3000.0, -6000.0)


def footprint_half_length_m(sim, y) -> float:
    """Half the footprint's length: between the edges where the penetration, linear between
    the outermost points pushing and their neighbours off the road, crosses zero."""
    pen = sim._pen0 + sim._jn @ y
    x = (sim.model.tire.R - sim.deflection_m) * np.tan(sim._zone.point_theta)
    on = np.flatnonzero(pen > 0)
    edges = []
    for inside, outside in ((on[0], on[0] - 1), (on[-1], on[-1] + 1)):
        share = pen[inside] / (pen[inside] - pen[outside])
        edges.append(x[inside] + share * (x[outside] - x[inside]))
    return 0.5 * abs(edges[1] - edges[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--record", metavar="JSON",
                        help="write the figures to this file (docs/measured/...)")
    args = parser.parse_args()
    load_at_start = load_average()
    base = InPlaneTire()
    rows = []
    print("| k_tx | half footprint | C = dFx/dκ | brush 2 k a² | slip at -3 / -6 kN m | "
          "sliding points |\n|---|---|---|---|---|---|")
    for factor in FACTORS:
        model = replace(base, tangential=replace(base.tangential,
                                                 k_tx=factor * base.tangential.k_tx))
        deflection = deflection_for_load(model, DEFAULT_LOAD_N, N, point_spacing_m=SPACING_M)
        sim = InPlaneSimulator(model, N, SPEED_M_S, deflection, point_spacing_m=SPACING_M)
        small = steady_rolling(sim, SMALL_TORQUE_N_M)
        free = steady_rolling(sim, 0.0)
        stiffness = (small.rim_fx_n - free.rim_fx_n) / (small.slip_ratio - free.slip_ratio)
        half = footprint_half_length_m(sim, sim.static_state())
        brush = 2.0 * model.tangential.k_tx * half**2
        brakes = [steady_rolling(sim, torque) for torque in BRAKES_N_M]
        row = {"k_tx_factor": factor, "k_tx_n_m2": model.tangential.k_tx,
               "half_footprint_m": half, "slip_stiffness_n": stiffness,
               "brush_slip_stiffness_n": brush, "small_torque_sliding": small.sliding_points,
               "brake_slip": [b.slip_ratio for b in brakes],
               "brake_sliding_points": [b.sliding_points for b in brakes],
               "points_in_contact": int(np.sum(sim._pen0 + sim._jn @ sim.static_state() > 0))}
        rows.append(row)
        print(f"| {factor:g} x {base.tangential.k_tx:.3g} N/m² | {half * 1e3:.1f} mm | "
              f"{stiffness / 1e3:.0f} kN | {brush / 1e3:.0f} kN | "
              + " / ".join(f"{100 * b.slip_ratio:.3f} %" for b in brakes) + " | "
              + " / ".join(f"{b.sliding_points}" for b in brakes)
              + f" of {row['points_in_contact']} |")
    if args.record:
        write_record(args.record, {"speed_m_s": SPEED_M_S, "n_elements": N,
                                   "spacing_m": SPACING_M, "load_n": DEFAULT_LOAD_N,
                                   "small_torque_n_m": SMALL_TORQUE_N_M,
                                   "brakes_n_m": list(BRAKES_N_M),
                                   "friction_coefficient": base.tangential.friction_coefficient,
                                   "rows": rows}, load_at_start)


if __name__ == "__main__":
    main()
