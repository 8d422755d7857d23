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
   balanced truncation for the same error target (5e-3).
4. Cost per step of the stepping kernel for 20-400 states: the diagonal (element-wise)
   kernel, the dense matrix-exponential kernel and a plain dense matrix-vector product of the
   same size as the reference floor.
5. States kept for 1 % maximum relative FRF error (1-300 Hz) at 0, 10 and 20 m/s (N = 100,
   default load): the former modal selection (modes dropped while a triangle-inequality bound,
   the sum of their relative terms' magnitudes, stayed within budget; rebuilt here), modal
   truncation now and balanced truncation side by side, and why modal truncation keeps more:
   the states each input/output pair alone needs, how much the modes' terms cancel in the
   hardest pair, and what the selection would keep with a velocity-level static correction of
   the dropped modes (E += sum -c b / lambda^2) or against 1 % of each pair's peak instead of
   pointwise.
6. What the default settings give (the table of docs/theory.md section 9.5).
7. Finer meshes at speed (N = 100, 200, 400): former modal, modal and balanced for 1 %, and
   a frequency cut at 10 kHz at N = 400.

Sections 5-7 are results of the computation (the same on any machine), written with
``--record docs/measured/bench_reduction.json`` for docs/generate.py.

    python benchmarks/bench_reduction.py [--repeats 5] [--quick] [--old-max-n 400]
        [--sections 1,2,3,4,5,6,7] [--record JSON]
    python benchmarks/bench_reduction.py [--repeats 5] [--quick] [--old-max-n 400]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from functools import partial
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy: one BLAS thread
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
from record import load_average, write_record  # noqa: E402
from record import median_seconds as median_time  # noqa: E402

from tire_fmu.core import (  # noqa: E402
    OperatingPoint,
    SupercriticalSpeedWarning,
    TireParameters,
    build_model,
)
from tire_fmu.core.balanced import BalancedRealization  # noqa: E402
from tire_fmu.core.io_model import OUTPUTS, build_io_model, physical_input  # noqa: E402
from tire_fmu.core.modal_form import (  # noqa: E402
    diagonalise,
    diagonalise_proportional,
    real_block_form,
)
from tire_fmu.core.reduction import (  # noqa: E402
    ZERO_RESPONSE,
    ReducedModel,
    ReductionSettings,
    ReductionWarning,
    error_report,
    full_responses,
    modal_decomposition,
    reduce,
    relative_contributions,
    select_by_shares,
    static_correction_matrix,
)
from tire_fmu.core.stepping import DenseStepper, DiagonalStepper  # noqa: E402

PAPER_SPEED = 20 * np.pi * 0.65
BALANCED = ReductionSettings(method="balanced")




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
        trial = ReducedModel(lam_k, b_k, c_k, np.asarray(d_k, float), io.e, io.road_windows,
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
    return ReducedModel(lam_k, b_k, c_k, np.asarray(d_k, float), io.e, io.road_windows, {},
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
                                 io.road_windows, {}, BALANCED)


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
    print("\n3. The cheap reduction: states for the same error target (5e-3), N = 100, "
          "default load")
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
    print("   diagonal / dense expm: the reference steppers; plain matvec: one dense product")
    print("   (the contact FMUs' own step is measured by bench_contact.py and bench_fmu.py)")
    print(f"{'states':>7} {'diagonal':>9} {'dense expm':>11} {'plain matvec':>13}")
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

        t_diag = per_call(partial(full_step, diag, q), 2000, repeats) * 1e6
        t_dense = per_call(partial(full_step, dense, x), 2000, repeats) * 1e6
        t_mv = per_call(partial(np.dot, matrix, x), 2000, repeats) * 1e6
        print(f"{states:>7} {t_diag:>9.2f} {t_dense:>11.2f} {t_mv:>13.2f}")


def real_states(eigenvalues: np.ndarray) -> int:
    return int(np.sum(np.where(eigenvalues.imag != 0, 2, 1)))


def velocity_corrected_shares(decomp, io, settings, full) -> np.ndarray:
    """Like relative_contributions with the static correction, plus the dropped modes'
    velocity-level term (E += sum -c b / lambda^2, as the native FMU's free ring has): what
    is left of a dropped mode is then c b (i w)^2 / (lambda^2 (i w - lambda))."""
    omega = 2 * np.pi * settings.error_frequencies_hz()
    lam = decomp.eigenvalues[:, None]
    iw = 1j * omega[None, :]

    def left(value):
        return 1.0 / (iw - value) + 1.0 / value + iw / value ** 2

    rows = []
    for name, row in full:
        r = physical_input(name, io.road_windows, omega)
        c = decomp.c[row][:, None]
        rows.append(0.5 * (c * (decomp.b @ r) * left(lam)
                           + np.conj(c) * (np.conj(decomp.b) @ r) * left(np.conj(lam)))
                    / np.abs(full[(name, row)])[None, :])
    return np.array(rows)


def modal_analysis(model, target: float) -> dict:
    """Why modal truncation keeps what it keeps, from one decomposition: the former selection
    (triangle-inequality bound), the states each pair alone needs, the cancellation of the
    modes' terms, and the selection with a velocity correction or a peak-relative error."""
    settings = ReductionSettings(target_error=target)
    io = build_io_model(model)
    decomp = modal_decomposition(io)
    full = full_responses(io, settings.error_frequencies_hz(), decomp)
    lam = decomp.eigenvalues
    none = np.zeros(lam.size, dtype=bool)
    shares = relative_contributions(decomp, io, settings, full)
    magnitude = np.abs(shares)
    order = np.argsort(magnitude.max(axis=(0, 2)), kind="stable")
    bound = np.cumsum(magnitude[:, order, :], axis=1).max(axis=(0, 2))
    former = order[int(np.searchsorted(bound, target, side="right")):]
    pairs = {}
    for k, (name, row) in enumerate(full):
        alone = select_by_shares(shares[k:k + 1], none, target)
        pairs[f"{name}->{OUTPUTS[row]}"] = {
            "states_alone": real_states(lam[alone]),
            "modes_above_band_alone": int(np.count_nonzero(
                np.abs(lam[alone]) > 2 * np.pi * settings.error_band_hz[1])),
            # the magnitudes the former bound summed, against the magnitude of their sum
            "sum_of_magnitudes": float(magnitude[k].sum(axis=0).max()),
            "magnitude_of_sum": float(np.abs(shares[k].sum(axis=0)).max()),
        }
    scale = np.array([np.abs(h) / np.abs(h).max() for h in full.values()])
    return {
        "full_states": 4 * model.n_elements,
        "reachable_states": real_states(lam),  # at rest the antisymmetric class is not
        "former_modal_states": real_states(lam[former]),
        "pairs": pairs,
        "velocity_corrected_states": real_states(lam[select_by_shares(
            velocity_corrected_shares(decomp, io, settings, full), none, target)]),
        "peak_relative_states": real_states(lam[select_by_shares(
            shares * scale[:, None, :], none, target)]),
    }


def one_percent_side_by_side(speeds=(0.0, 10.0, 20.0), n_elements: int = 100) -> list[dict]:
    print(f"\n5. States for 1 % max relative FRF error, 1-300 Hz, N = {n_elements}, default load")
    print(f"{'speed':>6} {'full':>10} | {'former modal':>12} | {'modal':>6} {'error':>8} "
          f"{'exact':>8} | {'balanced':>8} {'error':>8} | {'modal/bal':>9} | "
          f"{'hardest pair alone (above)':>27} | {'sum|terms|/|sum|':>16} | {'+E corr':>7} "
          f"{'1% of peak':>10}")
    tire = TireParameters()
    target = 0.01
    rows = []
    for speed in speeds:
        model = build_model(tire, OperatingPoint(n_elements=n_elements, speed_m_s=speed))
        modal = reduce(model, ReductionSettings(target_error=target))
        balanced = reduce(model, ReductionSettings(method="balanced", target_error=target))
        analysis = modal_analysis(model, target)
        hardest = max(analysis["pairs"], key=lambda k: analysis["pairs"][k]["states_alone"])
        pair = analysis["pairs"][hardest]
        row = {
            "speed_m_s": speed, "n_elements": n_elements,
            "modal_states": modal.n_states,
            "modal_error": modal.report.max_relative_error,
            "modal_exact_error": exact_error(modal, model),
            "balanced_states": balanced.n_states,
            "balanced_error": balanced.report.max_relative_error,
            "hardest_pair": hardest, **analysis,
        }
        rows.append(row)
        full = f"{analysis['full_states']} ({analysis['reachable_states']})"
        print(f"{speed:>6g} {full:>10} | {analysis['former_modal_states']:>12} | "
              f"{modal.n_states:>6} {row['modal_error']:>8.2e} {row['modal_exact_error']:>8.2e} | "
              f"{balanced.n_states:>8} {row['balanced_error']:>8.2e} | "
              f"{modal.n_states / balanced.n_states:>9.2f} | "
              f"{hardest:>17} {pair['states_alone']:>3} ({pair['modes_above_band_alone']:>2}) | "
              f"{pair['sum_of_magnitudes'] / pair['magnitude_of_sum']:>16.1f} | "
              f"{analysis['velocity_corrected_states']:>7} "
              f"{analysis['peak_relative_states']:>10}", flush=True)
    print("   full: states (reachable from the inputs: at rest the antisymmetric class is not);")
    print("   former modal: the selection before target_error (summed magnitudes as a bound); "
          "error: against the full model's modal decomposition, exact: against sparse solves;")
    print("   hardest pair alone: the states modal truncation keeps for that input/output pair "
          "by itself (modes of them above the band); sum|terms|/|sum|: how much the modes' "
          "relative terms in that pair cancel "
          "(max over the band of the sum of their magnitudes / of the magnitude of their sum);")
    print("   +E corr: states with a velocity-level static correction of the dropped modes too; "
          "1% of peak: states for an error of 1 % of each pair's peak instead of pointwise")
    for row in rows:
        print(f"   {row['speed_m_s']:g} m/s, states each pair alone needs: "
              + ", ".join(f"{k} {v['states_alone']}" for k, v in row["pairs"].items()))
    return rows


def defaults_table() -> list[dict]:
    print("\n6. What the defaults give (N = 100, max relative FRF error over 1-300 Hz)")
    print(f"{'operating point':>34} {'full':>5} | {'modal':>14} | {'no static corr.':>15} | "
          f"{'balanced':>14} | worst pair")
    tire = TireParameters()
    cases = (
        ("rest, 27.7 kN", OperatingPoint(n_elements=100), {}),
        ("rest, 20.4 cm patch", OperatingPoint(n_elements=100, patch_length_m=0.204), {}),
        (f"{PAPER_SPEED:.2f} m/s, 20.4 cm patch",
         OperatingPoint(n_elements=100, patch_length_m=0.204, speed_m_s=PAPER_SPEED), {}),
        ("rest, 27.7 kN, f_max_hz = 300", OperatingPoint(n_elements=100), {"f_max_hz": 300.0}),
    )
    rows = []
    for label, op, extra in cases:
        model = build_model(tire, op)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ReductionWarning)  # the cut is the point here
            modal = reduce(model, ReductionSettings(**extra))
        row = {"case": label, "full_states": 4 * model.n_elements,
               "modal_states": modal.n_states, "modal_error": modal.report.max_relative_error,
               "worst_pair": max(modal.report.per_pair, key=modal.report.per_pair.get)}
        if not extra:
            plain = reduce(model, ReductionSettings(static_correction=False))
            balanced = reduce(model, BALANCED)
            row.update(plain_states=plain.n_states, plain_error=plain.report.max_relative_error,
                       balanced_states=balanced.n_states,
                       balanced_error=balanced.report.max_relative_error)
        rows.append(row)
        plain_text = (f"{row['plain_states']:>4} ({row['plain_error']:.2%})" if not extra
                      else "")
        bal_text = (f"{row['balanced_states']:>4} ({row['balanced_error']:.2%})" if not extra
                    else "")
        print(f"{label:>34} {row['full_states']:>5} | "
              f"{row['modal_states']:>4} ({row['modal_error']:>7.2%}) | {plain_text:>15} | "
              f"{bal_text:>14} | {row['worst_pair']}", flush=True)
    return rows


def finer_meshes(cases=((100, 10.0), (200, 10.0), (400, 8.0))) -> dict:
    print("\n7. Finer meshes at speed: states for 1 % max relative FRF error (default load)")
    print(f"{'N':>5} {'speed':>6} {'full':>5} | {'former modal':>12} | {'modal':>6} {'error':>8} | "
          f"{'balanced':>8} {'error':>8} | {'modal/bal':>9}")
    tire = TireParameters()
    target = 0.01
    rows = []
    for n, speed in cases:
        model = build_model(tire, OperatingPoint(n_elements=n, speed_m_s=speed))
        modal = reduce(model, ReductionSettings(target_error=target))
        balanced = reduce(model, ReductionSettings(method="balanced", target_error=target))
        settings = ReductionSettings(target_error=target)
        io = build_io_model(model)
        decomp = modal_decomposition(io)
        shares = relative_contributions(decomp, io, settings, full_responses(
            io, settings.error_frequencies_hz(), decomp))
        magnitude = np.abs(shares)
        order = np.argsort(magnitude.max(axis=(0, 2)), kind="stable")
        bound = np.cumsum(magnitude[:, order, :], axis=1).max(axis=(0, 2))
        former = real_states(decomp.eigenvalues[order[int(np.searchsorted(
            bound, target, side="right")):]])
        row = {"n_elements": n, "speed_m_s": speed, "full_states": 4 * n,
               "former_modal_states": former, "modal_states": modal.n_states,
               "modal_error": modal.report.max_relative_error,
               "balanced_states": balanced.n_states,
               "balanced_error": balanced.report.max_relative_error}
        rows.append(row)
        print(f"{n:>5} {speed:>6g} {4 * n:>5} | {former:>12} | {modal.n_states:>6} "
              f"{row['modal_error']:>8.2e} | {balanced.n_states:>8} "
              f"{row['balanced_error']:>8.2e} | {modal.n_states / balanced.n_states:>9.2f}",
              flush=True)
    n, speed = cases[-1]
    model = build_model(tire, OperatingPoint(n_elements=n, speed_m_s=speed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ReductionWarning)
        cut = reduce(model, ReductionSettings(f_max_hz=1e4))
    uncut = reduce(model)
    print(f"   N = {n}, {speed:g} m/s, default target_error {uncut.settings.target_error:g}: "
          f"no cut {uncut.n_states} states, error {uncut.report.max_relative_error:.2%}; "
          f"f_max_hz = 1e4: {cut.n_states} states, error {cut.report.max_relative_error:.2%}")
    return {"rows": rows, "cut": {
        "n_elements": n, "speed_m_s": speed, "f_max_hz": 1e4,
        "states": cut.n_states, "error": cut.report.max_relative_error,
        "uncut_states": uncut.n_states, "uncut_error": uncut.report.max_relative_error}}


SECTIONS = "1,2,3,4,5,6,7"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="N = 100 only in sections 1-2")
    parser.add_argument("--old-max-n", type=int, default=400, metavar="N",
                        help="run the former balanced path up to this mesh (default 400; it "
                        "takes minutes at N = 400 and about ten at N = 800)")
    parser.add_argument("--sections", default=SECTIONS, metavar="LIST",
                        help=f"which sections to run, comma-separated (default {SECTIONS})")
    parser.add_argument("--record", metavar="JSON",
                        help="also write the results of sections 5-7 there")
    args = parser.parse_args()
    sections = {int(x) for x in args.sections.split(",")}
    load_at_start = load_average()
    warnings.simplefilter("ignore", SupercriticalSpeedWarning)
    print("python benchmarks/bench_reduction.py", *sys.argv[1:])
    print(f"numpy {np.__version__}, BLAS threads {os.environ.get('OPENBLAS_NUM_THREADS')}, "
          f"load average {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    if 1 in sections:
        cases = [(100, 0.0), (100, 10.0), (100, 20.0)]
        if not args.quick:
            cases += [(400, 0.0), (400, 8.0), (800, 0.0)]
        balanced_table(args.repeats, cases, args.old_max_n)
    if 2 in sections:
        build_times(args.repeats, (100,) if args.quick else (100, 400))
    if 3 in sections:
        cheap_reduction(args.repeats)
    if 4 in sections:
        step_costs(args.repeats)
    results = {}
    if 5 in sections:
        results["one_percent"] = one_percent_side_by_side()
    if 6 in sections:
        results["defaults"] = defaults_table()
    if 7 in sections:
        results["finer_meshes"] = finer_meshes()
    if args.record:
        write_record(args.record, results, load_at_start)


if __name__ == "__main__":
    main()
