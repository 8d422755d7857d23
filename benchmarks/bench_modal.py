"""Cost of the modal analysis at N = 100 and N = 400, side by side, with its references.

Times (median and fastest of ``--repeats`` runs, time.perf_counter) of:

- assembly, ``build_model`` at the default load (27.7 kN: the patch length is found by
  bisection on the model's own vertical stiffness), with the critical-speed scan cached as it is
  after the first build; and the cold critical-speed scan on its own;
- real modal analysis at rest, ``real_modes`` up to 300 Hz, dense (LAPACK) and sparse
  (ARPACK shift-invert), same loaded model;
- complex modal analysis of the rolling tire, ``complex_modes`` up to 300 Hz, undeformed and
  at the default load, at 20 m/s for N = 100 and 8 m/s for N = 400 (N = 400's critical speed
  is 10.8 m/s, N = 100's 42.7 m/s);
- its reference for the undeformed tire: the per-order dispersion relation
  ``tire_fmu.core.dispersion.eigenvalues`` over every order of the mesh, which gives the same
  eigenvalues from one 4x4 companion matrix per order. The largest relative gap between the
  two spectra is printed as a check that the comparison is like for like.

Run:  python3 benchmarks/bench_modal.py [--repeats K] [--blas-threads T]
"""

from __future__ import annotations

import argparse
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

MESHES = (100, 400)
#: Rolling speed per mesh: below each mesh's critical (standing-wave) speed.
ROLLING_SPEED_M_S = {100: 20.0, 400: 8.0}
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


def run(repeats: int) -> tuple[list[list[str]], list[str]]:
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
    notes: list[str] = []

    def put(label: str, n: int, text: str) -> None:
        rows.setdefault(label, {})[n] = text

    def ms(median: float, fastest: float) -> str:
        return f"{1e3 * median:9.2f} ({1e3 * fastest:.2f})"

    for n in MESHES:
        speed = ROLLING_SPEED_M_S[n]
        at_rest = OperatingPoint(n_elements=n)  # default load, 27.7 kN
        rolling_bare = OperatingPoint(n_elements=n, patch_length_m=0.0, speed_m_s=speed)
        rolling_loaded = OperatingPoint(n_elements=n, speed_m_s=speed)

        med, low, crit = timed(partial(critical_speed, tire, n), repeats,
                               before=standing_waves._critical_speed.cache_clear)
        put("critical_speed scan (cold)", n, ms(med, low))
        notes.append(f"N = {n}: critical speed {crit.speed_m_s:.2f} m/s; rolling cases at "
                     f"{speed:g} m/s")

        med, low, model = timed(partial(build_model, tire, at_rest), repeats)
        put("build_model, 27.7 kN, at rest", n, ms(med, low))
        put("  patch length found [cm]", n, f"{100 * model.patch.length_m:9.2f}")

        for method in ("dense", "sparse"):
            med, low, result = timed(partial(real_modes, model, F_MAX_HZ, method), repeats)
            put(f"real_modes {method}, <= {F_MAX_HZ:g} Hz", n, ms(med, low))
        put("  modes <= 300 Hz (real)", n, f"{len(result.modes):9d}")

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # N = 400 at 8 m/s is 74 % of critical: fine
            bare = build_model(tire, rolling_bare)
            loaded = build_model(tire, rolling_loaded)
        med, low, result = timed(partial(complex_modes, bare, F_MAX_HZ), repeats)
        put("complex_modes, undeformed, rolling", n, ms(med, low))
        # overdamped in the co-rotating frame (real body eigenvalue): listed at the Doppler
        # frequency -κΩ/2π only, which is why fine meshes list more "modes" below f_max
        overdamped = sum(1 for m in result.modes if abs(m.body_frequency_hz) < 1e-9)
        put("  modes <= 300 Hz (complex)", n, f"{len(result.modes)} ({overdamped} overdamped)")
        med, low, _ = timed(partial(complex_modes, loaded, F_MAX_HZ), repeats)
        put("complex_modes, 27.7 kN, rolling", n, ms(med, low))

        orders = all_orders(n)
        med, low, reference = timed(
            partial(dispersion_eigenvalues, tire, orders, bare.spin_rad_s, n), repeats)
        put("reference: dispersion.eigenvalues", n, ms(med, low))
        put("  max rel. gap, full vs per-order", n, f"{spectrum_gap(bare, reference):9.1e}")

    header = ["operation", *(f"N = {n} [ms]" for n in MESHES)]
    table = [[label, *(per_mesh.get(n, "") for n in MESHES)] for label, per_mesh in rows.items()]
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
    print(f"median (fastest) of {args.repeats} runs in ms; f_max = {F_MAX_HZ:g} Hz; "
          "'27.7 kN' = the default load (quarter car weight)")
    print()
    table, notes = run(args.repeats)
    print(format_table(table))
    print()
    for note in notes:
        print(note)
    print("The dispersion relation gives the undeformed spectrum (all orders, both branches, "
          "damped) that complex_modes finds by a dense 4N x 4N eigensolve; with a patch the "
          "orders couple and only the full solve applies.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
