"""The unilateral contact: what it computes and what it costs, printed side by side.

1. Static footprint at 10, 27.7 and 60 kN on N = 100, 200, 400, 800: deflection, length,
   nodes, secant and tangent stiffness (the convergence with the mesh).
2. Small amplitude: 0.1 mm sines of the rim and the road, 2-300 Hz, through the contact
   simulator at h = 1e-4 s (the host sets each point's inputs before reading): largest
   magnitude error of rim_Fz and contact_Fz against the linearised loaded model's FRF, at
   rest and at 10 m/s.
3. Lift-off: a 5 cm drop and return (10 ms ramps) at rest on N = 40 against an unreduced
   integration of the assembled ring with the same contact law (scipy DOP853): lift-off and
   touch-down times, landing peak.
4. A 1 mm road step at rest: the contact force's peak, its ringing frequency and decay.
5. Cost: building the contact model (the FMU's initialisation) at N = 100 and 400, and a
   step of the simulator in contact and airborne (medians), against the same step of the
   linear contact law.

    python3 benchmarks/bench_contact.py [--quick] [--record docs/measured/bench_contact.json]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from record import load_average, write_record  # noqa: E402
from record import median_seconds as timed  # noqa: E402

from tire_fmu.core import OperatingPoint, TireParameters, build_model  # noqa: E402
from tire_fmu.core.contact_dynamics import (  # noqa: E402
    ContactSettings,
    ContactSimulator,
    build_contact_model,
)
from tire_fmu.core.frequency_response import ringing_modes, sine_response  # noqa: E402
from tire_fmu.core.io_model import build_io_model  # noqa: E402
from tire_fmu.core.parameters import DEFAULT_LOAD_N  # noqa: E402

H = 1e-4


def footprints(meshes, loads):
    rows = []
    for n in meshes:
        for load in loads:
            fp = build_model(TireParameters(), OperatingPoint(n_elements=n,
                                                              load_n=load)).patch.footprint
            rows.append({"n_elements": n, "load_n": load, "deflection_mm": fp.deflection_m * 1e3,
                         "length_cm": fp.length_m * 100, "nodes": fp.n_active,
                         "secant_mn_m": fp.secant_stiffness_n_per_m / 1e6,
                         "tangent_mn_m": fp.tangent_stiffness_n_per_m / 1e6})
    return rows


def small_amplitude(speed, freqs, amplitude=1e-4):
    contact = build_contact_model(TireParameters(), OperatingPoint(speed_m_s=speed))
    io = build_io_model(contact.model)
    transients = ringing_modes(io.a.toarray())
    worst = {("rim", "rim_Fz"): 0.0, ("rim", "contact_Fz"): 0.0,
             ("road", "rim_Fz"): 0.0, ("road", "contact_Fz"): 0.0}
    for source in ("rim", "road"):
        for f in freqs:
            w = 2 * np.pi * f
            fit_s = max(0.25, 1.0 / f)
            n = int(round((0.1 + fit_s) / H))
            sim = ContactSimulator(contact)
            ys = np.empty((n, 2))

            def inputs(t, w=w, source=source):
                z, v = amplitude * np.sin(w * t), amplitude * w * np.cos(w * t)
                return (z, v, 0.0, 0.0) if source == "rim" else (0.0, 0.0, z, v)

            for i in range(n):
                sim.step_values(H, *inputs(i * H))
                out = sim.outputs_with(*inputs((i + 1) * H))
                ys[i] = out[0], out[2]
            t = (np.arange(n) + 1) * H
            keep = t > 0.1
            measured = sine_response(t[keep], ys[keep], w, transients) / amplitude
            expected = io.frequency_response(source, [f])[[0, 2], 0]
            error = np.abs(np.abs(measured) / np.abs(expected) - 1)
            for k, name in enumerate(("rim_Fz", "contact_Fz")):
                worst[(source, name)] = max(worst[(source, name)], float(error[k]))
    return {f"{source}->{name}": value for (source, name), value in worst.items()}


def drop_against_unreduced():
    from test_contact import drop_and_return, full_model_drop, run

    tire, n_el, t_end = TireParameters(), 40, 0.08

    def road(t):
        return drop_and_return(t, down=0.005, up=0.045, depth=0.05, duration=0.01)

    _, reference = full_model_drop(tire, n_el, t_end, road)
    out = {}
    for h in (1e-4, 2.5e-5):
        sim = ContactSimulator(build_contact_model(tire, OperatingPoint(n_elements=n_el)))
        n = int(round((t_end - 1e-4) / h))
        y = run(sim, road, n, h)[:, 2]
        t = (np.arange(n) + 1) * h
        off = t[y == 0]
        out[f"h={h:g}"] = {"lift_off_s": float(off[0]), "touch_down_s": float(off[-1]),
                           "landing_peak_kn": float(y[t > 0.045].max() / 1e3)}
    fine = np.arange(1, int(round((t_end - 1e-4) / 2.5e-6)) + 1) * 2.5e-6
    ref = reference(fine)
    off = fine[ref == 0]
    out["unreduced"] = {"lift_off_s": float(off[0]), "touch_down_s": float(off[-1]),
                        "landing_peak_kn": float(ref[fine > 0.045].max() / 1e3)}
    return out


def road_step():
    sim = ContactSimulator(build_contact_model(TireParameters(), OperatingPoint()))
    n = 2000
    y = np.array([sim.step_values(H, 0.0, 0.0, 1e-3, 0.0)[2] for _ in range(n)])
    t = (np.arange(n) + 1) * H
    early = y[t < 0.01] - y[-1]
    crossings = np.flatnonzero(np.diff(np.sign(early)) != 0)
    ring_hz = (len(crossings) - 1) / (2 * (t[crossings[-1]] - t[crossings[0]])) \
        if len(crossings) > 2 else float("nan")
    envelope = [np.abs(y[(t > a) & (t < a + 0.002)] - y[-1]).max() for a in (0.0, 0.004)]
    return {"peak_kn": float(y.max() / 1e3), "min_kn": float(y.min() / 1e3),
            "final_kn": float(y[-1] / 1e3), "ringing_hz": float(ring_hz),
            "decay_per_4ms": float(envelope[1] / envelope[0])}




def costs(repeats):
    out = {}
    for n in (100, 400):
        out[f"init_s_N{n}"] = timed(lambda n=n: build_contact_model(
            TireParameters(), OperatingPoint(n_elements=n)), repeats)
    for law in ("unilateral", "linear"):
        contact = build_contact_model(TireParameters(), OperatingPoint(),
                                      settings=ContactSettings(law=law))
        for case, road in (("in contact", 1e-5), ("airborne", -0.05)):
            sim = ContactSimulator(contact)
            for _ in range(200):
                sim.step_values(H, 0.0, 0.0, road, 0.0)
            steps = 2000

            def work(sim=sim, road=road, steps=steps):
                for _ in range(steps):
                    sim.step_values(H, 0.0, 0.0, road, 0.0)

            out[f"step_us_{law}_{case}"] = timed(work, repeats) / steps * 1e6
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer frequencies and meshes")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--record", metavar="JSON", help="also write the results there")
    args = parser.parse_args(argv)
    load_at_start = load_average()
    results = {}
    meshes = (100, 200) if args.quick else (100, 200, 400, 800)
    results["footprints"] = footprints(meshes, (10e3, DEFAULT_LOAD_N, 60e3))
    print("1. Static footprint (computed by the model)")
    print("   N     load kN  deflection mm  length cm  nodes  secant MN/m  tangent MN/m")
    for r in results["footprints"]:
        print(f"   {r['n_elements']:<5d} {r['load_n'] / 1e3:7.2f} {r['deflection_mm']:14.3f} "
              f"{r['length_cm']:10.2f} {r['nodes']:6d} {r['secant_mn_m']:12.3f} "
              f"{r['tangent_mn_m']:13.3f}")
    freqs = (2.0, 57.0, 300.0) if args.quick else (2.0, 20.0, 57.0, 70.0, 120.0, 185.0, 300.0)
    results["small_amplitude"] = {f"{v:g} m/s": small_amplitude(v, freqs) for v in (0.0, 10.0)}
    print(f"2. 0.1 mm sines at {', '.join(f'{f:g}' for f in freqs)} Hz: largest |H| error "
          "against the linearised loaded model")
    for speed, errors in results["small_amplitude"].items():
        print(f"   {speed:>8s}: " + ", ".join(f"{k} {100 * e:.3f} %" for k, e in errors.items()))
    if not args.quick:
        results["drop"] = drop_against_unreduced()
        print("3. 5 cm drop and return at rest, N = 40: lift-off, touch-down, landing peak")
        for key, r in results["drop"].items():
            print(f"   {key:>11s}: {r['lift_off_s'] * 1e3:.3f} ms, "
                  f"{r['touch_down_s'] * 1e3:.3f} ms, {r['landing_peak_kn']:.2f} kN")
    results["road_step"] = road_step()
    s = results["road_step"]
    print(f"4. 1 mm road step at rest: contact force peak {s['peak_kn']:.1f} kN, min "
          f"{s['min_kn']:.1f} kN (never < 0), settles at {s['final_kn']:.1f} kN; rings at "
          f"{s['ringing_hz']:.0f} Hz, x{s['decay_per_4ms']:.2g} in 4 ms")
    results["cost"] = costs(args.repeats)
    c = results["cost"]
    print(f"5. Initialisation (build_contact_model): {c['init_s_N100'] * 1e3:.1f} ms at N = 100, "
          f"{c['init_s_N400'] * 1e3:.1f} ms at N = 400 (medians of {args.repeats})")
    for law in ("unilateral", "linear"):
        print(f"   step, {law:>10s} law: in contact {c[f'step_us_{law}_in contact']:.1f} us, "
              f"airborne {c[f'step_us_{law}_airborne']:.1f} us")
    if args.record:
        write_record(args.record, results, load_at_start)
    return 0


if __name__ == "__main__":
    sys.exit(main())
