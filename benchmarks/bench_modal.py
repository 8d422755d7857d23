"""Cost of the modal analysis from N = 100 to 1600, side by side with its references.

Times (median and fastest of ``--repeats`` runs, time.perf_counter) of:

- assembly, ``build_model`` at the default load (27.7 kN: the patch length is found by
  bisection on the model's own vertical stiffness), with the critical-speed scan cached as it is
  after the first build; and the cold critical-speed scan on its own;
- real modal analysis at rest, ``real_modes`` up to 300 Hz: "auto" (today's default: LAPACK
  on half of each symmetry class, the sidewall eliminated exactly) against the references
  "dense" (LAPACK on the whole class) and "sparse" (ARPACK shift-invert, the former default
  above 1200 DOFs per class);
- complex modal analysis of the rolling tire at half the mesh's critical speed,
  ``complex_modes`` up to 300 Hz, undeformed ("auto" = per circumferential order) and at the
  default load ("auto" = dense eigenvalues, inverse iteration for the modes up to 300 Hz),
  against "dense" (every eigenvector of the 4N state matrix, the former path; up to
  ``--dense-max-n``, it takes minutes and GBs beyond);
- the per-order dispersion relation ``tire_fmu.core.dispersion.eigenvalues`` over every order
  of the mesh, the reference an undeformed spectrum can reach, with the largest relative gap
  between the per-order and the full spectra as a like-for-like check (up to
  ``--dense-max-n``).

The last column fits the growth exponent p of time ~ N^p from the smallest to the largest
mesh.

Run:  python3 benchmarks/bench_modal.py [--repeats K] [--meshes 100 200 ...] [--dense-max-n N]
          [--blas-threads T]
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import shlex
import statistics
import sys
import time
import warnings
from collections.abc import Callable
from functools import partial
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

MESHES = (100, 200, 400, 800, 1600)
F_MAX_HZ = 300.0


def timed(function: Callable[[], object], repeats: int,
          before: Callable[[], None] | None = None) -> tuple[float, float, object]:
    """(median s, fastest s, last result) of ``repeats`` calls; ``before`` runs untimed."""
    times, result = [], None
    for _ in range(repeats):
        if before is not None:
            before()
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times), result


def all_orders(n_elements: int):
    import numpy as np

    return np.arange(-(n_elements // 2) + 1, n_elements // 2 + 1)


def spectrum_gap(model, reference) -> float:
    """Largest relative distance from each full-model eigenvalue to the nearest per-order one,
    both ways (the two spectra as sets)."""
    import numpy as np

    from tire_fmu.core.complex_modal import state_matrix

    full = np.linalg.eigvals(state_matrix(model))
    ref = reference.ravel()
    gap = np.abs(full[:, None] - ref[None, :])
    return float(max((gap.min(axis=1) / np.abs(full)).max(),
                     (gap.min(axis=0) / np.abs(ref)).max()))


def run(repeats: int, meshes, dense_max_n: int) -> tuple[list[list[str]], list[str]]:
    from tire_fmu.core import (
        OperatingPoint,
        TireParameters,
        build_model,
        complex_modes,
        critical_speed,
        real_modes,
        standing_waves,
    )
    from tire_fmu.core.dispersion import eigenvalues as dispersion_eigenvalues

    tire = TireParameters()
    rows: dict[str, dict[int, str]] = {}
    medians: dict[str, dict[int, float]] = {}
    notes: list[str] = []

    def put(label: str, n: int, text: str) -> None:
        rows.setdefault(label, {})[n] = text

    def put_time(label: str, n: int, function, reps=repeats, before=None):
        med, low, result = timed(function, reps, before=before)
        put(label, n, f"{1e3 * med:9.1f} ({1e3 * low:.1f})")
        medians.setdefault(label, {})[n] = med
        return result

    for n in meshes:
        dense_ok = n <= dense_max_n
        crit = put_time("critical_speed scan (cold)", n, partial(critical_speed, tire, n),
                        before=standing_waves._critical_speed.cache_clear)
        speed = 0.5 * crit.speed_m_s
        notes.append(f"N = {n}: critical speed {crit.speed_m_s:.2f} m/s; rolling cases at "
                     f"{speed:.2f} m/s")
        model = put_time("build_model, 27.7 kN, at rest", n,
                         partial(build_model, tire, OperatingPoint(n_elements=n)))
        result = put_time(f"real_modes auto, <= {F_MAX_HZ:g} Hz", n,
                          partial(real_modes, model, F_MAX_HZ, "auto"))
        put("  modes <= 300 Hz (real)", n, f"{len(result.modes):9d}")
        put_time("  ref: real_modes dense (whole class)", n,
                 partial(real_modes, model, F_MAX_HZ, "dense"))
        put_time("  ref: real_modes sparse (ARPACK)", n,
                 partial(real_modes, model, F_MAX_HZ, "sparse"), reps=max(1, repeats // 3))

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            bare = build_model(tire, OperatingPoint(n_elements=n, patch_length_m=0.0,
                                                    speed_m_s=speed))
            loaded = build_model(tire, OperatingPoint(n_elements=n, speed_m_s=speed))
        result = put_time("complex_modes auto, undeformed", n,
                          partial(complex_modes, bare, F_MAX_HZ, "auto"))
        overdamped = sum(1 for m in result.modes if abs(m.body_frequency_hz) < 1e-9)
        put("  modes <= 300 Hz (complex)", n, f"{len(result.modes)} ({overdamped} overdamped)")
        orders = all_orders(n)
        reference = put_time("  ref: dispersion.eigenvalues", n,
                             partial(dispersion_eigenvalues, tire, orders, bare.spin_rad_s, n))
        if dense_ok:
            put_time("  ref: complex_modes dense, undeformed", n,
                     partial(complex_modes, bare, F_MAX_HZ, "dense"), reps=max(1, repeats // 3))
            put("  max rel. gap, full vs per-order", n, f"{spectrum_gap(bare, reference):9.1e}")
        put_time("complex_modes auto, 27.7 kN", n, partial(complex_modes, loaded, F_MAX_HZ,
                                                           "auto"), reps=max(1, repeats // 3))
        if dense_ok:
            put_time("  ref: complex_modes dense, 27.7 kN", n,
                     partial(complex_modes, loaded, F_MAX_HZ, "dense"), reps=max(1, repeats // 3))

    header = ["operation", *(f"N = {n} [ms]" for n in meshes), "p"]
    table = []
    for label, per_mesh in rows.items():
        exponent = ""
        times = medians.get(label, {})
        if len(times) >= 2:
            first, last = min(times), max(times)
            exponent = f"{math.log(times[last] / times[first]) / math.log(last / first):.2f}"
        table.append([label, *(per_mesh.get(n, "") for n in meshes), exponent])
    return [header, *table], notes


def format_table(table: list[list[str]]) -> str:
    widths = [max(len(row[i]) for row in table) for i in range(len(table[0]))]
    lines = []
    for k, row in enumerate(table):
        lines.append("  ".join(cell.ljust(w) if i == 0 else cell.rjust(w)
                               for i, (cell, w) in enumerate(zip(row, widths))))
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, metavar="K",
                        help="timed runs per case; the median is reported (default 5)")
    parser.add_argument("--meshes", type=int, nargs="+", default=list(MESHES), metavar="N",
                        help=f"meshes (default {' '.join(map(str, MESHES))})")
    parser.add_argument("--dense-max-n", type=int, default=800, metavar="N",
                        help="largest mesh for the dense complex references (default 800)")
    parser.add_argument("--blas-threads", type=int, default=1, metavar="T",
                        help="BLAS/LAPACK threads (default 1: on a small shared machine "
                        "multithreaded LAPACK under load is slower and far noisier); 0 leaves "
                        "the library default")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be >= 1")
    if args.blas_threads < 0:
        parser.error("--blas-threads must be >= 0")
    if args.blas_threads:  # before numpy is imported, or it has no effect
        for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ[name] = str(args.blas_threads)
    sys.path.insert(0, str(ROOT))
    import numpy as np
    import scipy

    command = " ".join(shlex.quote(a) for a in [sys.executable, *sys.argv])
    threads = args.blas_threads or "library default"
    print(f"command: {command}")
    print(f"python {platform.python_version()}, numpy {np.__version__}, scipy "
          f"{scipy.__version__}, {os.cpu_count()} CPUs ({platform.machine()}), "
          f"BLAS threads: {threads}, load average before: "
          f"{', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"median (fastest) of {args.repeats} runs (references marked, some fewer) in ms; "
          f"fmax = {F_MAX_HZ:g} Hz; "
          "'27.7 kN' = the default load (quarter car weight)")
    print()
    table, notes = run(args.repeats, args.meshes, args.dense_max_n)
    print(format_table(table))
    print()
    for note in notes:
        print(note)
    print("p: fitted exponent of time ~ N^p between the smallest and the largest mesh. With a "
          "patch the orders couple: the rolling spectrum still needs the dense 4N eigenvalues "
          "(O(N^3)); only the eigenvectors are spared.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
