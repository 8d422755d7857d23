"""The in-plane simulator over the 20 mm cleat at 10 m/s against the unreduced integration
written apart in tests/test_inplane_reference.py: the relative rms difference of Fx and Fz
at three time steps, with the wheel held and free, and the frequencies dominating the
reference's Fx and Fz (a periodogram of the run after the cleat reaches the footprint).

    python benchmarks/inplane_reference.py
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402
from scipy.signal import periodogram  # noqa: E402
from test_inplane_reference import (  # noqa: E402
    AHEAD,
    CLEAT,
    DURATION,
    MODEL,
    SPACING,
    SPEED,
    N,
    UnreducedCleatRun,
    rms,
)

from tire_fmu.core.inplane_contact import InPlaneSimulator, deflection_for_load  # noqa: E402
from tire_fmu.core.parameters import DEFAULT_LOAD_N  # noqa: E402

STEPS_S = (1e-4, 5e-5, 2.5e-5)


def dominant_hz(signal: np.ndarray, sample_hz: float) -> float:
    freq, power = periodogram(signal - signal.mean(), fs=sample_hz, nfft=2**16)
    band = freq >= 5.0
    return float(freq[band][np.argmax(power[band])])


def main() -> None:
    deflection = deflection_for_load(MODEL, DEFAULT_LOAD_N, N, point_spacing_m=SPACING)
    print("| wheel | step | Fx rms difference | Fz rms difference |\n|---|---|---|---|")
    spectra = []
    for wheel in ("held", "free"):
        reference = UnreducedCleatRun(deflection, wheel)
        for step_s in STEPS_S:
            run = InPlaneSimulator(MODEL, N, SPEED, deflection, point_spacing_m=SPACING,
                                   obstacle=CLEAT, obstacle_ahead_m=AHEAD, wheel=wheel,
                                   step_s=step_s).run(
                DURATION, record_every=int(round(STEPS_S[0] / step_s)))
            if step_s == STEPS_S[0]:
                fx, fz, _ = reference.run(run.time_s)
            print(f"| {wheel} | {step_s * 1e6:g} µs | "
                  f"{rms(run.rim_fx_n - fx) / rms(fx):.2%} | "
                  f"{rms(run.rim_fz_n - fz) / rms(fz - DEFAULT_LOAD_N):.2%} |")
        on = run.time_s > 0.5 * AHEAD / SPEED
        spectra.append((wheel, dominant_hz(fx[on], 1 / STEPS_S[0]),
                        dominant_hz(fz[on], 1 / STEPS_S[0])))
    for wheel, fx_hz, fz_hz in spectra:
        print(f"reference, wheel {wheel}: Fx dominant {fx_hz:.1f} Hz, Fz dominant {fz_hz:.1f} Hz")


if __name__ == "__main__":
    main()
