"""The rotational mode's ringing after a brake torque step (-3 kN m at t = 0.1 s), wheel free,
axle held, at rest and at 10 m/s, beside the loaded rotational mode `loaded_modes` reports
(a linearisation at rest): the frequency of Fx after the step by its periodogram and by a
damped-cosine fit, and the fit's decay rate.

    python benchmarks/inplane_brake_ringing.py
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy.optimize import curve_fit  # noqa: E402
from scipy.signal import periodogram  # noqa: E402

from tire_fmu.core.inplane import InPlaneTire  # noqa: E402
from tire_fmu.core.inplane_contact import (  # noqa: E402
    InPlaneSimulator,
    deflection_for_load,
    loaded_modes,
)
from tire_fmu.core.parameters import DEFAULT_LOAD_N  # noqa: E402

STEP_AT_S, TORQUE_N_M, SPACING_M = 0.1, -3000.0, 0.01


def damped_cosine(t, amplitude, decay, omega, phase, offset, drift):
    return amplitude * np.exp(-decay * t) * np.cos(omega * t + phase) + offset + drift * t


def main() -> None:
    model = InPlaneTire()
    deflection = deflection_for_load(model, DEFAULT_LOAD_N, 100, point_spacing_m=SPACING_M)
    at_rest = loaded_modes(InPlaneSimulator(model, 100, 0.0, deflection,
                                            point_spacing_m=SPACING_M, wheel="free"))
    rotational = [f for f, kind in zip(at_rest.frequencies_hz, at_rest.kinds)
                  if kind == "rotational"]
    print(f"loaded rotational mode at rest (loaded_modes): {rotational[0]:.2f} Hz")
    for speed in (0.0, 10.0):
        sim = InPlaneSimulator(model, 100, speed, deflection, point_spacing_m=SPACING_M,
                               wheel="free")
        run = sim.run(0.5, torque_n_m=lambda t: TORQUE_N_M if t >= STEP_AT_S else 0.0)
        after = run.time_s > STEP_AT_S + 0.005
        t, fx = run.time_s[after] - STEP_AT_S, run.rim_fx_n[after]
        freq, power = periodogram(fx - fx.mean(), fs=1 / sim.step_s, nfft=2**17)
        band = freq > 5.0
        peak_hz = float(freq[band][np.argmax(power[band])])
        fit, _ = curve_fit(damped_cosine, t, fx, maxfev=20000,
                           p0=[fx.max() - fx.mean(), 10.0, 2 * np.pi * peak_hz, 0.0, fx[-1], 0.0])
        print(f"{speed:4.1f} m/s: Fx rings at {peak_hz:.2f} Hz (periodogram), "
              f"{fit[2] / (2 * np.pi):.2f} Hz decaying at {fit[1]:.1f} 1/s (damped fit)")


if __name__ == "__main__":
    main()
