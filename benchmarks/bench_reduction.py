"""Reduced-order model benchmarks, printed side by side with their references in one run.

1. Balanced truncation (default settings: fewest states with max relative FRF error <= 5e-3
   over 1-300 Hz), ``reduce(model, method="balanced", report=False)``, against
   (a) the former code path, rebuilt here from the same library pieces: the complete modal
       decomposition (no symmetry split), exact full-model responses, Gramians by scipy's
       Bartels-Stewart solver and eigenvalue factors, and an error report (with its static
       solve) per bisection step; it is slow, so it runs once per case and only up to
       ``--old-max-n``;
   (b) python-control's ``balanced_reduction(sys, order, method="matchdc")`` (slycot ab09nd)
       on the full first-order model (4N states) with the same output weights, asked for the
       order the new path found (skipped, and said so, without slycot).
   States and the exact max relative FRF error of each result are printed with the times.
2. Reduction build at N = 100 and 400 (the FMU-independent part of initialisation): the
   eigendecomposition alone, ``reduce(report=False)`` and ``reduce()`` for both methods,
   against the full-model responses the former code computed on every build (two sparse
   assemblies and factorisations per frequency, 400 frequencies), and the gap between the
   modal-decomposition responses now used and those exact ones.
3. The cheap reduction at 0, 10 and 20 m/s (N = 100): states and build time of modal and
   balanced truncation for the same error budget (5e-3).
4. Cost per step of the stepping kernel for 20-400 states: the diagonal (element-wise)
   kernel, the dense matrix-exponential kernel and a plain dense matrix-vector product of the
   same size as the reference floor.
5. States needed for 1 % maximum relative FRF error (1-300 Hz) per method, at rest and at the
   paper's speed with a 20.4 cm patch.

    python benchmarks/bench_reduction.py [--repeats 5] [--quick] [--old-max-n 400]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
import warnings
from functools import partial
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy: one BLAS thread
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402
from tire_fmu.core.simulation import OUTPUT_NAMES, TireSimulator  # noqa: E402

from tire_fmu.core import (  # noqa: E402
    OperatingPoint,
    SupercriticalSpeedWarning,
    TireParameters,
    build_model,
)
from tire_fmu.core.balanced import BalancedRealization  # noqa: E402
from tire_fmu.core.io_model import OUTPUTS, build_io_model  # noqa: E402
from tire_fmu.core.modal_form import (  # noqa: E402
    diagonalise,
    diagonalise_proportional,
    real_block_form,
)
from tire_fmu.core.reduction import (  # noqa: E402
    ZERO_RESPONSE,
    ReducedModel,
    ReductionSettings,
    error_report,
    full_responses,
    modal_decomposition,
    reduce,
    static_correction_matrix,
)
from tire_fmu.core.stepping import DenseStepper, DiagonalStepper  # noqa: E402

PAPER_SPEED = 20 * np.pi * 0.65
BALANCED = ReductionSettings(method="balanced")


def median_time(function, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def timed_once(function):
    start = time.perf_counter()
    result = function()
    return time.perf_counter() - start, result


def per_call(function, calls: int, repeats: int) -> float:
    def batch():
        for _ in range(calls):
            function()

    return median_time(batch, repeats) / calls


def _complete_decomposition(io):
    """The former decomposition: every mode, one eigenproblem on all DOFs."""
    model = io.model
    if model.speed_m_s == 0.0:
        return diagonalise_proportional(model.stiffness, model.mass.diagonal(),
                                        model.tire.alpha, model.tire.beta, io.b_disp,
                                        io.b_vel, io.out_disp, io.out_vel)
    return diagonalise(io.a.toarray(), io.b, io.c)


def _weights(full):
    peak = np.zeros(len(OUTPUTS))
    for (_, row), response in full.items():
        peak[row] = max(peak[row], np.abs(response).max())
    return np.divide(1.0, peak, out=np.zeros_like(peak), where=peak > 0)


def former_balanced(model, settings=BALANCED):
    """The former balanced path (see the module docstring), n_states of the result."""
    io = build_io_model(model)
    freqs = settings.error_frequencies_hz()
    full = {}
    for name in ("rim", "road"):  # one assembly and factorisation per input and frequency
        h = io.frequency_response(name, freqs)
        full.update({(name, row): h[row] for row in range(len(OUTPUTS))})
    floor = ZERO_RESPONSE * max(np.abs(h).max() for (_, row), h in full.items()
                                if OUTPUTS[row] != "deflection")
    full = {key: h for key, h in full.items()
            if OUTPUTS[key[1]] == "deflection" or np.abs(h).max() > floor}
    decomp = _complete_decomposition(io)
    lam, b, c = decomp.eigenvalues, decomp.b, decomp.c
    d = io.d + static_correction_matrix(io, lam, b, c)
    realization = BalancedRealization(lam, b, c, d, _weights(full), True, gramians="dense")

    def error(k):
        lam_k, b_k, c_k, d_k = realization.truncate(k)
        trial = ReducedModel(lam_k, b_k, c_k, np.asarray(d_k, float), io.e, io.input_delays_s,
                             {}, settings)
        return error_report(trial, io, full).max_relative_error

    low, high = 1, realization.order
    if error(high) > settings.target_error:
        return realization.truncate(high)
    while low < high:
        middle = (low + high) // 2
        if error(middle) <= settings.target_error:
            high = middle
        else:
            low = middle + 1
    lam_k, b_k, c_k, d_k = realization.truncate(high)
    return ReducedModel(lam_k, b_k, c_k, np.asarray(d_k, float), io.e, io.input_delays_s, {},
                        settings)


def control_balanced(model, order: int):
    """python-control's balanced_reduction (slycot, matchdc) of the full first-order model
    with the same output weights, asked for ``order`` states: (seconds, ReducedModel), or
    None without slycot."""
    try:
        import control
        import slycot  # noqa: F401
    except ImportError:
        return None
    io = build_io_model(model)
    freqs = BALANCED.error_frequencies_hz()
    weight = _weights(full_responses(io, freqs, modal_decomposition(io)))
    keep = weight > 0  # the weighted outputs that carry a response
    system = control.ss(io.a.toarray(), io.b, io.c[keep] * weight[keep, None],
                        io.d[keep] * weight[keep, None])
    seconds, reduced = timed_once(partial(control.balanced_reduction, system, order,
                                          method="matchdc"))
    # the unweighted outputs of the same reduced state (the unweighted ones are not needed)
    a_k, b_k = np.asarray(reduced.A), np.asarray(reduced.B)
    c_k = np.zeros((len(OUTPUTS), a_k.shape[0]))
    d_k = io.d.copy()
    c_k[keep] = np.asarray(reduced.C) / weight[keep, None]
    d_k[keep] = np.asarray(reduced.D) / weight[keep, None]
    form = diagonalise(a_k, b_k, c_k)
    return seconds, ReducedModel(form.eigenvalues, form.b, form.c, d_k, io.e,
                                 io.input_delays_s, {}, BALANCED)


def exact_error(reduced, model) -> float:
    return error_report(reduced, build_io_model(model)).max_relative_error


def balanced_table(repeats: int, cases, old_max_n: int) -> None:
    print("\n1. Balanced truncation to max rel. FRF error 5e-3, 1-300 Hz (median s; states, "
          "exact error)")
    print(f"{'N':>5} {'speed':>6} | {'new [s]':>8} {'states':>6} {'error':>8} | "
          f"{'former [s]':>10} {'states':>6} {'error':>8} {'x':>6} | "
          f"{'control [s]':>11} {'error':>8} {'x':>6}")
    tire = TireParameters()
    for n, speed in cases:
        model = build_model(tire, OperatingPoint(n_elements=n, speed_m_s=speed))
        new_time = median_time(partial(reduce, model, BALANCED, report=False), repeats)
        new = reduce(model, BALANCED, report=False)
        new_err = exact_error(new, model)
        row = f"{n:>5} {speed:>6g} | {new_time:>8.3f} {new.n_states:>6} {new_err:>8.2e} | "
        if n <= old_max_n:
            old_time, old = timed_once(partial(former_balanced, model))
            row += (f"{old_time:>10.2f} {old.n_states:>6} {exact_error(old, model):>8.2e} "
                    f"{old_time / new_time:>6.0f} | ")
        else:
            row += f"{'(skipped)':>10} {'':>6} {'':>8} {'':>6} | "
        ref = control_balanced(model, new.n_states)
        if ref is None:
            row += "slycot not installed"
        else:
            row += (f"{ref[0]:>11.2f} {exact_error(ref[1], model):>8.2e} "
                    f"{ref[0] / new_time:>6.1f}")
        print(row, flush=True)
    print("   x: reference time / new time, same run. The former path runs once per case "
          f"(--old-max-n {old_max_n}); control is one call of balanced_reduction alone, "
          "given the order that the new path found.")


def build_times(repeats: int, meshes) -> None:
    print("\n2. Reduction build, the FMU-independent part of initialisation (median s)")
    print(f"{'N':>5} {'speed':>6} {'eig only':>9} {'modal':>7} {'+report':>8} "
          f"{'balanced':>9} {'+report':>8} | {'former responses':>16} {'x modal':>8} | "
          f"{'modal vs exact responses':>24}")
    tire = TireParameters()
    freqs = ReductionSettings().error_frequencies_hz()
    for n in meshes:
        for speed in (0.0, 8.0 if n > 200 else 10.0):
            model = build_model(tire, OperatingPoint(n_elements=n, speed_m_s=speed))
            io = build_io_model(model)
            eig = median_time(partial(modal_decomposition, io), repeats)
            modal = median_time(partial(reduce, model, report=False), repeats)
            modal_rep = median_time(partial(reduce, model), repeats)
            bal = median_time(partial(reduce, model, BALANCED, report=False), repeats)
            bal_rep = median_time(partial(reduce, model, BALANCED), repeats)

            def former_responses(io=io):
                for name in ("rim", "road"):
                    io.frequency_response(name, freqs)

            old = median_time(former_responses, max(1, repeats // 3))
            exact = full_responses(io, freqs)
            approx = full_responses(io, freqs, modal_decomposition(io))
            gap = max(float(np.max(np.abs(approx[k] - h) / np.abs(h))) for k, h in exact.items())
            print(f"{n:>5} {speed:>6g} {eig:>9.3f} {modal:>7.3f} {modal_rep:>8.3f} {bal:>9.3f} "
                  f"{bal_rep:>8.3f} | {old:>16.3f} {(old + modal) / modal:>8.1f} | "
                  f"{gap:>24.1e}", flush=True)
    print("   former responses: what every build computed before (2 x 400 sparse solves), "
          "even with report=False; 'x modal' = (former responses + modal) / modal, a lower "
          "bound of the former build's cost over today's")


def cheap_reduction(repeats: int) -> None:
    print("\n3. The cheap reduction: states for the same budget (5e-3), N = 100, default load")
    print(f"{'speed':>6} {'modal states':>13} {'balanced states':>16} {'ratio':>6} "
          f"{'modal [s]':>10} {'balanced [s]':>13} {'time ratio':>11}")
    tire = TireParameters()
    for speed in (0.0, 10.0, 20.0):
        model = build_model(tire, OperatingPoint(n_elements=100, speed_m_s=speed))
        modal, balanced = reduce(model, report=False), reduce(model, BALANCED, report=False)
        t_modal = median_time(partial(reduce, model, report=False), repeats)
        t_bal = median_time(partial(reduce, model, BALANCED, report=False), repeats)
        print(f"{speed:>6g} {modal.n_states:>13} {balanced.n_states:>16} "
              f"{modal.n_states / balanced.n_states:>6.2f} {t_modal:>10.3f} {t_bal:>13.3f} "
              f"{t_bal / t_modal:>11.2f}", flush=True)
    print("   balanced truncation now costs what modal truncation costs (both are the modal "
          "decomposition plus a little), so it is the cheap reduction at speed")


def step_costs(repeats: int) -> None:
    print("\n4. Cost per step of the stepping kernel, h = 1e-4 s (median µs)")
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
    print("\n5. States for 1 % max relative FRF error, 1-300 Hz, N = 100, patch 20.4 cm")
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
    parser.add_argument("--old-max-n", type=int, default=400, metavar="N",
                        help="run the former balanced path up to this mesh (default 400; it "
                        "takes minutes at N = 400 and about ten at N = 800)")
    args = parser.parse_args()
    warnings.simplefilter("ignore", SupercriticalSpeedWarning)
    print("python benchmarks/bench_reduction.py", f"--repeats {args.repeats}",
          f"--old-max-n {args.old_max_n}", "--quick" if args.quick else "")
    print(f"numpy {np.__version__}, BLAS threads {os.environ.get('OPENBLAS_NUM_THREADS')}, "
          f"load average {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    cases = [(100, 0.0), (100, 10.0), (100, 20.0)]
    if not args.quick:
        cases += [(400, 0.0), (400, 8.0), (800, 0.0)]
    balanced_table(args.repeats, cases, args.old_max_n)
    build_times(args.repeats, (100,) if args.quick else (100, 400))
    cheap_reduction(args.repeats)
    step_costs(args.repeats)
    states_for_one_percent()


if __name__ == "__main__":
    main()
