"""The in-plane tire over a cleat with the axle held (SAE J2730-like), and free rolling: the
fore-aft and vertical rim forces against the contact-point spacing, the frequencies that
dominate them, and the rolling resistance against speed and load.

Unreduced ring (core/inplane_contact.py), N = 100, 10 m/s, free wheel, h = 50 µs:

    python benchmarks/bench_inplane_cleat.py [--spacings 0.01 0.005 0.0025] [--record JSON]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402
from scipy.signal import periodogram  # noqa: E402

from benchmarks.record import load_average, write_record  # noqa: E402
from tire_fmu.core.inplane import InPlaneTire  # noqa: E402
from tire_fmu.core.inplane_contact import InPlaneSimulator, deflection_for_load  # noqa: E402
from tire_fmu.core.obstacles import cleat  # noqa: E402
from tire_fmu.core.parameters import DEFAULT_LOAD_N  # noqa: E402
from tire_fmu.tire_files import read_tire_file  # noqa: E402

STEP_S = 5e-5
SPEED_M_S = 10.0


def dominant_hz(signal: np.ndarray, step_s: float, low_hz: float = 5.0) -> float:
    freq, power = periodogram(signal - signal.mean(), fs=1 / step_s, nfft=2**17)
    band = freq >= low_hz
    return float(freq[band][np.argmax(power[band])])


def cleat_case(model, deflection, spacing, n_elements, obstacle):
    sim = InPlaneSimulator(model, n_elements, SPEED_M_S, deflection, step_s=STEP_S,
                           point_spacing_m=spacing, obstacle=obstacle, obstacle_ahead_m=0.6)
    start = time.perf_counter()
    run = sim.run(0.16)
    seconds = time.perf_counter() - start
    on = run.time_s > 0.03  # the start of rolling has settled
    fz, fx = run.rim_fz_n[on], run.rim_fx_n[on]
    return {"spacing_m": spacing, "n_elements": n_elements, "obstacle": obstacle.label,
            "peak_fz_n": float(fz.max()), "fx_min_n": float(fx.min()),
            "fx_max_n": float(fx.max()), "fx_rms_n": float(np.sqrt(np.mean(fx**2))),
            "fz_rise_rms_n": float(np.sqrt(np.mean((fz - DEFAULT_LOAD_N) ** 2))),
            "fx_dominant_hz": dominant_hz(fx, STEP_S), "fz_dominant_hz": dominant_hz(fz, STEP_S),
            "seconds": seconds, "steps": int(run.time_s.size),
            "fx": fx[::20].tolist(), "fz": fz[::20].tolist()}


#: The tire files whose rolling resistance is reported, and the speeds (m/s).
RESISTANCE_TIRES = ("GL073A_inplane", "GL073A_inplane_hysteretic")
RESISTANCE_SPEEDS_M_S = (1.0, 5.0, 10.0, 20.0)


def rolling_resistance(model, load_n, speed, spacing):
    deflection = deflection_for_load(model, load_n, 100, point_spacing_m=spacing)
    sim = InPlaneSimulator(model, 100, speed, deflection, step_s=1e-4, point_spacing_m=spacing)
    run = sim.run(0.3, record_every=10)
    settled = run.time_s > 0.15
    return {"load_n": load_n, "speed_m_s": speed,
            "coefficient": float(-run.rim_fx_n[settled].mean() / load_n),
            "axle_moment_n_m": float(run.rim_my_n_m[settled].mean())}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spacings", type=float, nargs="+", default=[0.01, 0.005, 0.0025])
    parser.add_argument("--record", metavar="JSON")
    args = parser.parse_args(argv)
    load_start = load_average()
    model = InPlaneTire()
    deflection = deflection_for_load(model, DEFAULT_LOAD_N, 100, point_spacing_m=0.005)
    rows = []
    print(f"{'obstacle':<26} {'spacing':>8} {'N':>4} {'peak Fz':>9} {'Fx min':>8} {'Fx max':>8} "
          f"{'Fx rms':>7} {'f(Fx)':>6} {'f(Fz)':>6} {'s':>6}")
    for obstacle in (cleat(0.02, 0.02), cleat(0.02, 0.05, "rounded")):
        for spacing in args.spacings:
            row = cleat_case(model, deflection, spacing, 100, obstacle)
            rows.append(row)
            print(f"{row['obstacle']:<26} {spacing * 1e3:6.2f}mm {100:>4} "
                  f"{row['peak_fz_n'] / 1e3:7.2f}kN {row['fx_min_n'] / 1e3:6.2f}kN "
                  f"{row['fx_max_n'] / 1e3:6.2f}kN {row['fx_rms_n'] / 1e3:5.2f}kN "
                  f"{row['fx_dominant_hz']:6.1f} {row['fz_dominant_hz']:6.1f} "
                  f"{row['seconds']:6.1f}", flush=True)
    resistance = []
    for name in RESISTANCE_TIRES:  # the paper's viscous damping, and with a hysteretic loss
        tire = read_tire_file(name)
        tire_model = InPlaneTire(tire.tire, tire.tangential)
        resistance += [{"tire": name, **rolling_resistance(tire_model, load, speed, 0.01)}
                       for load in (0.5 * DEFAULT_LOAD_N, DEFAULT_LOAD_N)
                       for speed in RESISTANCE_SPEEDS_M_S]
    print("rolling resistance coefficient (free wheel, flat road):")
    for r in resistance:
        print(f"  {r['tire']:<26} {r['load_n'] / 1e3:6.2f} kN {r['speed_m_s']:5.1f} m/s  "
              f"{r['coefficient']:.5f}  (axle moment {r['axle_moment_n_m']:+.2f} N m)")
    if args.record:
        write_record(args.record, {"step_s": STEP_S, "speed_m_s": SPEED_M_S,
                                   "deflection_m": deflection, "cleat": rows,
                                   "rolling_resistance": resistance}, load_start)
    return 0


if __name__ == "__main__":
    sys.exit(main())
