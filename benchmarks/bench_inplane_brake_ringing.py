"""The rotational mode's ringing after a brake torque step (-3 kN m at t = 0.1 s), wheel free,
axle held, at rest and at 10 m/s, beside the loaded modes: `loaded_modes` at rest (a
linearisation about the static footprint) and `rolling_modes` at speed (about the steady
rolling, the tread elements' transport as states; `core/inplane_rolling_modes.py`).

Fx after the step: its periodogram, a single damped cosine fitted to it (as the first version
of this benchmark did), and at speed a sum of damped cosines seeded by the modes with the
largest part in the linear step response (`torque_step`), fitted to the run and, to show
what the fit itself recovers, to the linear response. A single damped cosine at speed fits
a mixture: the rotational mode is heavily damped and the belt's modes near 50-60 Hz ring on.

    python benchmarks/bench_inplane_brake_ringing.py                # N = 100, 10 mm, 100 µs
    python benchmarks/bench_inplane_brake_ringing.py --convergence  # and N = 200, 5 mm, 50 µs
    python benchmarks/bench_inplane_brake_ringing.py --convergence \
        --record docs/measured/bench_inplane_brake_ringing.json     # the figures docs quote
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
from scipy.optimize import curve_fit  # noqa: E402
from scipy.signal import periodogram  # noqa: E402

from benchmarks.record import load_average, write_record  # noqa: E402
from tire_fmu.core.inplane import InPlaneTire  # noqa: E402
from tire_fmu.core.inplane_contact import (  # noqa: E402
    InPlaneSimulator,
    deflection_for_load,
    loaded_modes,
    steady_rolling,
)
from tire_fmu.core.inplane_rolling_modes import (  # noqa: E402
    fit_ringing,
    rolling_modes,
    torque_step,
)
from tire_fmu.core.parameters import DEFAULT_LOAD_N  # noqa: E402

STEP_AT_S, TORQUE_N_M, SPACING_M, SPEED_M_S = 0.1, -3000.0, 0.01, 10.0
#: The ringing fitted from this long after the step (the step's first instants excite the
#: ring's high modes) to the end of the run.
FIT_FROM_S, RUN_S = 0.005, 0.5
#: The slip the run settles at is its mean over this last part of it (the ringing has decayed
#: by e^-10 before).
SETTLED_S = 0.1
#: Modes of the linear step response seeding the fit.
FIT_MODES = 4
#: The small speed at which rolling_modes must give loaded_modes' rest value.
SLOW_M_S = 0.05


def damped_cosine(t, amplitude, decay, omega, phase, offset, drift):
    return amplitude * np.exp(-decay * t) * np.cos(omega * t + phase) + offset + drift * t


def rotational(modes) -> tuple[float, float]:
    """(frequency Hz, decay 1/s) of the mode labelled rotational."""
    (k,) = [i for i, kind in enumerate(modes.kinds) if kind == "rotational"]
    return float(modes.frequencies_hz[k]), float(modes.decay_rates_1_s[k])


def brake_run(model, n, spacing, step, speed, deflection):
    """The run (the step's C where it can be had: numpy's to 1e-9, tests/test_inplane_host.py)
    and its Fx after the step."""
    sim = InPlaneSimulator(model, n, speed, deflection, point_spacing_m=spacing, wheel="free",
                           step_s=step, backend="auto")
    start = time.perf_counter()
    run = sim.run(RUN_S, torque_n_m=lambda t: TORQUE_N_M if t >= STEP_AT_S else 0.0)
    after = run.time_s > STEP_AT_S + FIT_FROM_S
    return (sim, run.time_s[after] - STEP_AT_S, run.rim_fx_n[after],
            time.perf_counter() - start, run)


def settled_slip(sim, run) -> tuple[float, float]:
    """(the run's slip over its last SETTLED_S, steady_rolling's) under the brake torque."""
    settled = run.time_s > RUN_S - SETTLED_S
    slip = run.spin_rad_s[settled].mean() * sim.model.tire.R / sim.speed_m_s - 1.0
    return float(slip), float(steady_rolling(sim, TORQUE_N_M).slip_ratio)


def single_fit(sim, t, fx) -> tuple[float, float, float]:
    freq, power = periodogram(fx - fx.mean(), fs=1 / sim.step_s, nfft=2**17)
    band = freq > 5.0
    peak_hz = float(freq[band][np.argmax(power[band])])
    fit, _ = curve_fit(damped_cosine, t, fx, maxfev=20000,
                       p0=[fx.max() - fx.mean(), 10.0, 2 * np.pi * peak_hz, 0.0, fx[-1], 0.0])
    return peak_hz, fit[2] / (2 * np.pi), fit[1]


def modes_text(modes) -> str:
    return ", ".join(f"{f:.2f} Hz/{d:.1f} 1/s" for f, d, *_ in modes)


def at_speed(model, n, spacing, step, deflection, run_too=True) -> dict:
    sim = InPlaneSimulator(model, n, SPEED_M_S, deflection, point_spacing_m=spacing,
                           wheel="free", step_s=step)
    start = time.perf_counter()
    modes = rolling_modes(sim, TORQUE_N_M)
    linear = torque_step(sim, 0.0, TORQUE_N_M)
    took = time.perf_counter() - start
    f_rot, d_rot = rotational(modes)
    seeds = linear.dominant(FIT_MODES)
    label = f"N = {n}, {spacing * 1e3:g} mm, {step * 1e6:g} µs"
    out = {"n_elements": n, "spacing_m": spacing, "step_s": step,
           "points_in_contact": modes.points_in_contact, "sliding_points": modes.sliding_points,
           "rotational_hz": f_rot, "rotational_decay_1_s": d_rot,
           "step_modes": [{"frequency_hz": f, "decay_1_s": d, "fx_amplitude_n": a}
                          for f, d, a in seeds]}
    print(f"[{label}] rolling_modes at {SPEED_M_S:g} m/s under {TORQUE_N_M:g} N m "
          f"({modes.points_in_contact} points in contact, {modes.sliding_points} sliding; "
          f"{took:.1f} s): rotational {f_rot:.2f} Hz decaying at {d_rot:.1f} 1/s "
          f"(zeta {d_rot / np.hypot(d_rot, 2 * np.pi * f_rot):.3f})")
    print("    linear step response, modes by their part in Fx: "
          + ", ".join(f"{f:.2f} Hz/{d:.1f} 1/s ({a / 1e3:.2f} kN)" for f, d, a in seeds))
    if not run_too:
        return out
    sim, t, fx, took, run = brake_run(model, n, spacing, step, SPEED_M_S, deflection)
    peak_hz, single_hz, single_decay = single_fit(sim, t, fx)
    slip, steady_slip = settled_slip(sim, run)
    print(f"    settled slip {slip * 100:.3f} % against steady_rolling's {steady_slip * 100:.3f} % "
          f"({(slip / steady_slip - 1) * 100:+.2f} %)")
    print(f"    run ({took:.0f} s): Fx rings at {peak_hz:.2f} Hz (periodogram), "
          f"{single_hz:.2f} Hz decaying at {single_decay:.1f} 1/s (single damped cosine)")
    fitted, rms = fit_ringing(t, fx, seeds)
    print(f"    run, {FIT_MODES} damped cosines seeded by those modes: {modes_text(fitted)} "
          f"(rms {rms:.0f} N of Fx's {fx.std():.0f} N)")
    own, own_rms = fit_ringing(t, linear.fx(t), seeds)
    print(f"    linear response, same fit:             {modes_text(own)} (rms {own_rms:.0f} N)")
    apart = float(np.sqrt(np.mean((linear.fx(t) - fx) ** 2)))
    print(f"    rotational: run {fitted[0][0]:.2f} Hz against rolling_modes' {f_rot:.2f} Hz "
          f"({(fitted[0][0] / f_rot - 1) * 100:+.1f} %), decay {fitted[0][1]:.1f} against "
          f"{d_rot:.1f} 1/s; the linear response against the run: rms {apart:.0f} N")
    out |= {"settled_slip": slip, "steady_slip": steady_slip,
            "periodogram_hz": peak_hz, "single_fit_hz": single_hz,
            "single_fit_decay_1_s": single_decay,
            "run_fit": [{"frequency_hz": f, "decay_1_s": d} for f, d in fitted],
            "run_fit_rms_n": rms, "run_fx_std_n": float(fx.std()),
            "linear_fit": [{"frequency_hz": f, "decay_1_s": d} for f, d in own],
            "linear_against_run_rms_n": apart}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--convergence", action="store_true",
                        help="also N = 200, 5 mm points and a 50 µs step")
    parser.add_argument("--record", metavar="JSON",
                        help="write the figures to this file (docs/measured/...)")
    args = parser.parse_args()
    load_at_start = load_average()
    model = InPlaneTire()
    deflection = deflection_for_load(model, DEFAULT_LOAD_N, 100, point_spacing_m=SPACING_M)
    rest_sim = InPlaneSimulator(model, 100, 0.0, deflection, point_spacing_m=SPACING_M,
                                wheel="free")
    at_rest = loaded_modes(rest_sim)
    (f_rest,) = [f for f, kind in zip(at_rest.frequencies_hz, at_rest.kinds)
                 if kind == "rotational"]
    slow = rolling_modes(InPlaneSimulator(model, 100, SLOW_M_S, deflection,
                                          point_spacing_m=SPACING_M, wheel="free"))
    print(f"loaded rotational mode at rest (loaded_modes): {f_rest:.2f} Hz; rolling_modes at "
          f"{SLOW_M_S:g} m/s: {rotational(slow)[0]:.2f} Hz")
    sim, t, fx, *_ = brake_run(model, 100, SPACING_M, 1e-4, 0.0, deflection)
    peak_hz, single_hz, single_decay = single_fit(sim, t, fx)
    print(f" 0.0 m/s: Fx rings at {peak_hz:.2f} Hz (periodogram), {single_hz:.2f} Hz decaying "
          f"at {single_decay:.1f} 1/s (damped fit)")
    results = {"speed_m_s": SPEED_M_S, "torque_n_m": TORQUE_N_M, "load_n": DEFAULT_LOAD_N,
               "step_at_s": STEP_AT_S, "run_s": RUN_S, "fit_from_s": FIT_FROM_S,
               "rest": {"loaded_modes_hz": float(f_rest), "slow_speed_m_s": SLOW_M_S,
                        "rolling_modes_slow_hz": rotational(slow)[0],
                        "periodogram_hz": peak_hz, "single_fit_hz": single_hz,
                        "single_fit_decay_1_s": single_decay},
               "cases": []}
    cases = [(100, SPACING_M, 1e-4)]
    if args.convergence:
        cases += [(100, SPACING_M, 5e-5), (200, SPACING_M, 1e-4), (100, 0.005, 1e-4),
                  (200, 0.005, 1e-4), (200, SPACING_M, 5e-5)]
    for n, spacing, step in cases:
        # each discretisation pressed to the same load
        d = deflection_for_load(model, DEFAULT_LOAD_N, n, point_spacing_m=spacing)
        results["cases"].append(at_speed(model, n, spacing, step, d))
    if args.convergence:  # the linearisation alone (it holds no step), finer still
        d = deflection_for_load(model, DEFAULT_LOAD_N, 100, point_spacing_m=0.0025)
        results["cases"].append(at_speed(model, 100, 0.0025, 1e-4, d, run_too=False))
    if args.record:
        write_record(args.record, results, load_at_start)


if __name__ == "__main__":
    main()
