"""The radial step kernel with the road by position (issue 37) against the road by time, on
the 20 mm x 20 mm rectangular cleat at 20 m/s (a road file's profile in 1 mm cells), the
compiled kernel, the default tire:

1. **The host's step**: rim_Fz and rim_Fx at host steps of 1 ms and 2 ms against 0.1 ms, the
   rim heaving 3 mm at 12 Hz and the wheel braking at 5 m/s² (``--held``: the rim held and
   the speed constant): the peak of the rise at the host's instants against the 0.1 ms run at
   the same instants and against its own peak (the latter includes the host's sampling of its
   outputs), the rms of the rise and the rms of the difference. By position, the wheel's x is
   given; by time, the road's height at the zone front and its rate (what a host sampling its
   road gives).
2. **The mesh**: the same cleat at N = 100, 200 and 400 against N = 400, the wheel at the
   same x at the same times (1 ms, no alignment): rms of the difference of the rise.
3. **The cost** of a 1 ms step (10 substeps) by position and by time at N = 100.

    python3 benchmarks/bench_kernel_position_road.py [--held]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from tire_fmu.core import OperatingPoint, TireParameters
from tire_fmu.core.contact_dynamics import build_contact_model
from tire_fmu.core.contract import build_contract
from tire_fmu.core.obstacles import cleat, sampled_obstacle
from tire_fmu.native.kernel import CompiledKernel

SPEED = 20.0
START_X = 0.5
DURATION = 0.1


def motion(held: bool):
    def at(t):
        if held:
            return 0.0, 0.0, START_X + SPEED * t, SPEED
        w = 2 * math.pi * 12.0
        return (3e-3 * math.sin(w * t), 3e-3 * w * math.cos(w * t),
                START_X + SPEED * t - 2.5 * t * t, SPEED - 5.0 * t)

    return at


def run(contract, road, h, at, by_position=True):
    kernel = CompiledKernel(contract, road=road if by_position else None)
    front = float(contract.window_hi_m.max())
    rows = []
    for i in range(int(round(DURATION / h))):
        z, vz, x, vx = at(i * h)
        if by_position:
            rows.append(kernel.step_on_road(h, z, vz, x, vx))
        else:
            height, slope = road.profile(x + front)
            rows.append(kernel.step_values(h, z, vz, float(height), float(vx * slope)))
    return np.array(rows)[:, :2] - contract.static_ring_out[:2]


def host_steps(contract, road, at) -> None:
    print("1. host step against 0.1 ms (%: peak at the same instants / peak against the "
          "0.1 ms run's own / rms / rms of the difference, of the rise)")
    for by_position in (True, False):
        fine = run(contract, road, 1e-4, at, by_position)
        for h in (1e-3, 2e-3):
            every = int(round(h / 1e-4))
            coarse, same = run(contract, road, h, at, by_position), fine[every - 1::every]
            cells = []
            for column, name in ((0, "rim_Fz"), (1, "rim_Fx")):
                a, b = coarse[:, column], same[:, column]
                rms = math.sqrt(np.mean(b**2))
                cells.append(f"{name} {100 * (np.abs(a).max() / np.abs(b).max() - 1):+6.2f} / "
                             f"{100 * (np.abs(a).max() / np.abs(fine[:, column]).max() - 1):+6.2f}"
                             f" / {100 * (math.sqrt(np.mean(a**2)) / rms - 1):+6.2f} / "
                             f"{100 * math.sqrt(np.mean((a - b) ** 2)) / rms:6.2f}")
            print(f"   {'by position' if by_position else 'by time    '} {h * 1e3:g} ms: "
                  + "   ".join(cells))


def meshes(road, at) -> None:
    print("2. the mesh, 1 ms, no alignment (rms of the difference from N = 400, % of its rms)")
    runs = {}
    for n in (100, 200, 400):
        model = build_contact_model(TireParameters(), OperatingPoint(n_elements=n,
                                                                     speed_m_s=SPEED))
        runs[n] = {way: run(build_contract(model), road, 1e-3, at, way) for way in (True,
                                                                                     False)}
    for n in (100, 200):
        cells = []
        for way in (True, False):
            for column, name in ((0, "rim_Fz"), (1, "rim_Fx")):
                a, b = runs[n][way][:, column], runs[400][way][:, column]
                share = math.sqrt(np.mean((a - b) ** 2) / np.mean(b**2))
                cells.append(f"{name} {100 * share:5.2f}")
            cells[-2] = ("by position " if way else "by time ") + cells[-2]
        print(f"   N = {n}: " + "   ".join(cells))


def cost(contract, road, at) -> None:
    for by_position in (True, False):
        best = math.inf
        for _ in range(3):
            start = time.perf_counter()
            run(contract, road, 1e-3, at, by_position)
            best = min(best, time.perf_counter() - start)
        print(f"3. {'by position' if by_position else 'by time'}: "
              f"{1e6 * best / round(DURATION / 1e-3):.0f} us a 1 ms step (N = 100, "
              f"{contract.n_points} points, the call from Python included)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--held", action="store_true",
                        help="the rim held and the speed constant")
    args = parser.parse_args()
    at = motion(args.held)
    road = sampled_obstacle(cleat(0.02, 0.02), 1e-3, lead_in_m=1.0, lead_out_m=2.0)
    model = build_contact_model(TireParameters(), OperatingPoint(n_elements=100,
                                                                 speed_m_s=SPEED))
    contract = build_contract(model)
    print(f"20 mm x 20 mm cleat at {SPEED:g} m/s, load {model.patch.load_n:.0f} N, "
          + ("rim held" if args.held else "rim heaving 3 mm at 12 Hz, braking at 5 m/s²"))
    host_steps(contract, road, at)
    meshes(road, at)
    cost(contract, road, at)


if __name__ == "__main__":
    main()
