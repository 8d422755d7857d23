"""Reduced-order model benchmarks, printed side by side in one run.

1. Build time of the reduced model (assembly + modal decomposition + selection + report) at
   N = 100 and N = 400, modal and balanced, against the bare dense eigensolver it relies on.
2. Cost per step of the stepping kernel for 20-400 states: the diagonal (element-wise)
   kernel, the dense matrix-exponential kernel and a plain dense matrix-vector product of the
   same size as the reference floor.
3. States needed for 1 % maximum relative FRF error (1-300 Hz) per method, at rest and at the
   paper's speed with a 20.4 cm patch.

    python benchmarks/bench_reduction.py [--repeats 5] [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings
from functools import partial

import numpy as np

from tire_fmu.core import OperatingPoint, SupercriticalSpeedWarning, TireParameters, build_model
from tire_fmu.core.io_model import build_io_model
from tire_fmu.core.modal_form import real_block_form
from tire_fmu.core.reduction import (
    ReducedModel,
    ReductionSettings,
    modal_decomposition,
    reduce,
)
from tire_fmu.core.simulation import OUTPUT_NAMES, TireSimulator
from tire_fmu.core.stepping import DenseStepper, DiagonalStepper

PAPER_SPEED = 20 * np.pi * 0.65


def median_time(function, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def per_call(function, calls: int, repeats: int) -> float:
    def batch():
        for _ in range(calls):
            function()

    return median_time(batch, repeats) / calls


def build_times(repeats: int, meshes) -> None:
    print("\n1. Build time of the reduced model (median s)")
    print(f"{'N':>5} {'speed':>7} {'eig only':>9} {'modal':>8} {'balanced':>9}  states m/b")
    tire = TireParameters()
    for n in meshes:
        for speed in (0.0, 8.0 if n > 200 else 20.0):
            model = build_model(tire, OperatingPoint(n_elements=n, speed_m_s=speed))
            io = build_io_model(model)
            eig = median_time(partial(modal_decomposition, io), repeats)
            modal = median_time(partial(reduce, model, report=False), repeats)
            balanced = ReductionSettings(method="balanced")
            bal = median_time(partial(reduce, model, balanced, report=False),
                              max(1, repeats // 3))
            m = reduce(model, report=False).n_states
            b = reduce(model, ReductionSettings(method="balanced"), report=False).n_states
            print(f"{n:>5} {speed:>7g} {eig:>9.3f} {modal:>8.3f} {bal:>9.3f}  {m}/{b}")


def step_costs(repeats: int) -> None:
    print("\n2. Cost per step of the stepping kernel, h = 1e-4 s (median µs)")
    print("   fused: TireSimulator.step_values, the FMU's hot path (BLAS on one buffer);")
    print("   diagonal / dense expm: the reference steppers; plain matvec: one dense product")
    print(f"{'states':>7} {'fused':>7} {'diagonal':>9} {'dense expm':>11} {'plain matvec':>13}")
    rng = np.random.default_rng(0)
    inputs = 2
    for states in (20, 50, 100, 200, 400):
        modes = states // 2
        lam = -rng.uniform(5, 50, modes) + 1j * rng.uniform(100, 2000, modes)
        b = rng.normal(size=(modes, inputs)) + 1j * rng.normal(size=(modes, inputs))
        c = rng.normal(size=(4, modes)) + 1j * rng.normal(size=(4, modes))
        d, e = rng.normal(size=(4, inputs)), rng.normal(size=(4, inputs))
        diag = DiagonalStepper(lam, b, c, d, e)
        dense = DenseStepper(*real_block_form(lam, b, c, d, e))
        u = rng.normal(size=2 * inputs)
        q = np.zeros(modes, complex)
        x = np.zeros(states)
        diag.coefficients(1e-4)
        dense.coefficients(1e-4)
        matrix = rng.normal(size=(states, states))

        def full_step(stepper, state, inputs=u):
            stepper.output(stepper.step(state, inputs, 1e-4), inputs)

        reduced = ReducedModel(lam, b, c, d, e, np.zeros(inputs),
                               dict.fromkeys(OUTPUT_NAMES, 0.0), ReductionSettings())
        simulator = TireSimulator(reduced)
        simulator.step_values(1e-4, 0.0, 0.0, 0.0, 0.0)
        t_fused = per_call(partial(simulator.step_values, 1e-4, 1e-3, 0.0, 2e-3, 0.0), 2000,
                           repeats) * 1e6
        t_diag = per_call(partial(full_step, diag, q), 2000, repeats) * 1e6
        t_dense = per_call(partial(full_step, dense, x), 2000, repeats) * 1e6
        t_mv = per_call(partial(np.dot, matrix, x), 2000, repeats) * 1e6
        print(f"{states:>7} {t_fused:>7.2f} {t_diag:>9.2f} {t_dense:>11.2f} {t_mv:>13.2f}")


def states_for_one_percent() -> None:
    print("\n3. States for 1 % max relative FRF error, 1-300 Hz, N = 100, patch 20.4 cm")
    print(f"{'speed':>7} {'full':>5} {'modal default':>14} {'modal (err)':>12} "
          f"{'modal @1%':>10} {'balanced @1%':>13}")
    tire = TireParameters()
    for speed in (0.0, PAPER_SPEED):
        model = build_model(tire, OperatingPoint(n_elements=100, patch_length_m=0.204,
                                                 speed_m_s=speed))
        default = reduce(model)
        modal = reduce(model, ReductionSettings(contribution_threshold=0.01))
        balanced = reduce(model, ReductionSettings(method="balanced", target_error=0.01))
        print(f"{speed:>7.2f} {4 * model.n_elements:>5} {default.n_states:>14} "
              f"{default.report.max_relative_error:>12.2e} "
              f"{modal.n_states:>4} ({modal.report.max_relative_error:.1e}) "
              f"{balanced.n_states:>4} ({balanced.report.max_relative_error:.1e})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="N = 100 only")
    args = parser.parse_args()
    warnings.simplefilter("ignore", SupercriticalSpeedWarning)
    print("python benchmarks/bench_reduction.py", f"--repeats {args.repeats}",
          "--quick" if args.quick else "")
    build_times(args.repeats, (100,) if args.quick else (100, 400))
    step_costs(args.repeats)
    states_for_one_percent()


if __name__ == "__main__":
    main()
