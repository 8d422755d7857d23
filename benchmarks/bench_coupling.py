"""Accuracy of vehicle_demo's coupling scheme against the communication step (not a timing).

The quarter car and TireModal.fmu co-simulated through fmpy on a multisine road (0.5 Hz lines
to 300 Hz, as a sweep point runs it), and each ride transfer function compared with the car on
the full unreduced ring model over the coherent lines (vehicle_demo.transfer.agreement): the
largest deviation in dB and the line where it is. Cases:

1. at rest, N = 60: Gauss-Seidel and Jacobi at h = 5e-5, 1e-4, 2e-4 and 5e-4 s;
2. rolling at 20 m/s, N = 50: Gauss-Seidel at h = 1e-4 and 5e-5 s;
3. the tire read before its inputs of the new communication point are set (its direct
   feedthrough then uses the road velocity the step ramped with): Gauss-Seidel, h = 1e-4 s,
   at rest (N = 60) and at 20 m/s (N = 50).

docs/vehicle_demo.md quotes docs/measured/bench_coupling.json.

    python3 benchmarks/bench_coupling.py [--record docs/measured/bench_coupling.json]
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # before numpy: see vehicle_demo/__main__.py

import argparse  # noqa: E402
import tempfile  # noqa: E402
from dataclasses import asdict  # noqa: E402
from pathlib import Path  # noqa: E402

from record import load_average, write_record  # noqa: E402

from vehicle_demo.cosim import cosimulate  # noqa: E402
from vehicle_demo.demo import ensure_fmus  # noqa: E402
from vehicle_demo.quarter_car import QuarterCarParameters  # noqa: E402
from vehicle_demo.sweep import SweepSettings  # noqa: E402
from vehicle_demo.transfer import agreement, estimate_frf, ride_outputs  # noqa: E402

STEPS_AT_REST_S = (5e-5, 1e-4, 2e-4, 5e-4)
STEPS_ROLLING_S = (1e-4, 5e-5)
REST_ELEMENTS, ROLLING_ELEMENTS, ROLLING_SPEED_M_S = 60, 50, 20.0


def accuracy(fmus, n_elements: int, speed_m_s: float, step_s: float, scheme: str,
             read_after_inputs: bool = True) -> dict:
    """Largest deviation (dB) of each ride transfer function from the full model, and where."""
    from tire_fmu.core import OperatingPoint, TireParameters, build_model
    from vehicle_demo.quarter_car import full_tire_two_port, ride_response

    car = QuarterCarParameters()
    excitation = SweepSettings().excitation
    _, height, velocity = excitation.road(step_s)
    run = cosimulate(fmus, height, velocity, car, {"n_elements": n_elements,
                                                   "speed": speed_m_s}, step_s, scheme,
                     read_after_inputs=read_after_inputs)
    estimate = estimate_frf(height, ride_outputs(run), excitation, step_s)
    model = build_model(TireParameters(), OperatingPoint(
        n_elements=n_elements, load_n=car.static_tire_load_n, speed_m_s=speed_m_s))
    reference = ride_response(car, full_tire_two_port(model, estimate.freqs_hz))
    found = agreement(estimate, reference)
    return {"n_elements": n_elements, "speed_m_s": speed_m_s, "step_s": step_s,
            "scheme": scheme, "read_after_inputs": read_after_inputs,
            "line_spacing_hz": 1.0 / excitation.period_s,
            "agreements": {name: asdict(a) for name, a in found.items()}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", metavar="JSON", help="also write the results there (the "
                        "docs quote docs/measured/bench_coupling.json)")
    args = parser.parse_args()
    load_at_start = load_average()
    cases = []
    with tempfile.TemporaryDirectory(prefix="bench_coupling_") as tmp:
        fmus = ensure_fmus(Path(tmp) / "fmus", log=lambda *_: None)
        plan = [(REST_ELEMENTS, 0.0, h, scheme, True)
                for scheme in ("gauss-seidel", "jacobi") for h in STEPS_AT_REST_S]
        plan += [(ROLLING_ELEMENTS, ROLLING_SPEED_M_S, h, "gauss-seidel", True)
                 for h in STEPS_ROLLING_S]
        plan += [(REST_ELEMENTS, 0.0, 1e-4, "gauss-seidel", False),
                 (ROLLING_ELEMENTS, ROLLING_SPEED_M_S, 1e-4, "gauss-seidel", False)]
        print(f"{'N':>4} {'V m/s':>6} {'h s':>8} {'scheme':>13} {'read':>7}  "
              "max |dB| body / wheel / rim load / contact force (worst line, Hz)")
        for n, speed, h, scheme, after in plan:
            case = accuracy(fmus, n, speed, h, scheme, after)
            cases.append(case)
            a = case["agreements"]
            print(f"{n:>4} {speed:>6g} {h:>8g} {scheme:>13} {'after' if after else 'before':>7}  "
                  + " / ".join(f"{a[k]['max_deviation_db']:.3g} ({a[k]['worst_frequency_hz']:g})"
                               for k in ("body_acc", "wheel_acc", "rim_load", "contact_force")),
                  flush=True)
    if args.record:
        write_record(args.record, {"cases": cases}, load_at_start)


if __name__ == "__main__":
    main()
