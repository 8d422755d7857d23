"""The in-plane simulator over the 20 mm cleat at 10 m/s against the unreduced integration
written apart in tests/test_inplane_reference.py: the relative rms difference of Fx and Fz
at three time steps, with the wheel held and free, and the frequencies dominating the
reference's Fx and Fz (a periodogram of the run after the cleat reaches the footprint).

    python benchmarks/bench_inplane_reference.py
    python benchmarks/bench_inplane_reference.py --record docs/measured/bench_inplane_reference.json
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))

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

from benchmarks.record import load_average, write_record  # noqa: E402
from tire_fmu.core.inplane_contact import InPlaneSimulator, deflection_for_load  # noqa: E402
from tire_fmu.core.parameters import DEFAULT_LOAD_N  # noqa: E402

STEPS_S = (1e-4, 5e-5, 2.5e-5)


def dominant_hz(signal: np.ndarray, sample_hz: float) -> float:
    freq, power = periodogram(signal - signal.mean(), fs=sample_hz, nfft=2**16)
    band = freq >= 5.0
    return float(freq[band][np.argmax(power[band])])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--record", metavar="JSON",
                        help="write the figures to this file (docs/measured/...)")
    args = parser.parse_args()
    load_at_start = load_average()
    deflection = deflection_for_load(MODEL, DEFAULT_LOAD_N, N, point_spacing_m=SPACING)
    print("| wheel | step | Fx rms difference | Fz rms difference |\n|---|---|---|---|")
    rows, spectra = [], []
    for wheel in ("held", "free"):
        reference = UnreducedCleatRun(deflection, wheel)
        for step_s in STEPS_S:
            run = InPlaneSimulator(MODEL, N, SPEED, deflection, point_spacing_m=SPACING,
                                   obstacle=CLEAT, obstacle_ahead_m=AHEAD, wheel=wheel,
                                   step_s=step_s).run(
                DURATION, record_every=int(round(STEPS_S[0] / step_s)))
            if step_s == STEPS_S[0]:
                fx, fz, _ = reference.run(run.time_s)
            row = {"wheel": wheel, "step_s": step_s,
                   "fx_rms_difference": rms(run.rim_fx_n - fx) / rms(fx),
                   "fz_rms_difference": rms(run.rim_fz_n - fz) / rms(fz - DEFAULT_LOAD_N)}
            rows.append(row)
            print(f"| {wheel} | {step_s * 1e6:g} µs | {row['fx_rms_difference']:.2%} | "
                  f"{row['fz_rms_difference']:.2%} |")
        on = run.time_s > 0.5 * AHEAD / SPEED
        spectra.append({"wheel": wheel, "fx_dominant_hz": dominant_hz(fx[on], 1 / STEPS_S[0]),
                        "fz_dominant_hz": dominant_hz(fz[on], 1 / STEPS_S[0])})
    for s in spectra:
        print(f"reference, wheel {s['wheel']}: Fx dominant {s['fx_dominant_hz']:.1f} Hz, "
              f"Fz dominant {s['fz_dominant_hz']:.1f} Hz")
    if args.record:
        write_record(args.record, {"n_elements": N, "spacing_m": SPACING, "speed_m_s": SPEED,
                                   "duration_s": DURATION, "rows": rows, "spectra": spectra},
                     load_at_start)


if __name__ == "__main__":
    main()
