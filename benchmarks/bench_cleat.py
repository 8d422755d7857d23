"""The rim load over cleats and a pothole against the mesh, rim held at its static height: the
matrix of issue 21 (tire_fmu.core.studies.cleat_convergence on each case).

Cases: a 20 mm x 20 mm cleat at 10 and 20 m/s, 10 x 10 mm and 50 x 50 mm cleats and a 50 mm
deep, 0.3 m long pothole at 10 m/s, all with the contact points at their default spacing; the
20 mm cleat at 10 m/s with one point per node (the node contact, for comparison); and the
20 mm cleat at 10 and 20 m/s on the shipped GL073A_shear tire, whose sidewall shear let the
finest meshes run at these speeds before the default tire's sidewall was tied (kept for
comparison; with --tire-file, the tire of every case but these). Meshes
at or above their critical (standing-wave) speed for a case are not run: the record names them
with that speed. Prints each case's convergence table (the one ``tire-fmu cleat`` prints).
Then, at N = 200, the 10 mm and 20 mm cleats at finer point spacings (the spacing's own
convergence), and at N = 100 the 20 mm cleat at halved steps from the FMU's 1e-4 s down (the
step's: the rim load's peak, and the mean rim and contact force while the cleat is under the
tire, which agree once the step resolves the points' entry at the cleat's edges).

Run:  python3 benchmarks/bench_cleat.py [--meshes 100 200 400 800] [--step 2.5e-5]
      [--tire-file GL073A_tied] [--record docs/measured/cleat_convergence.json]
(docs/theory.md, "Contact points: convergence over cleats", renders the record).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

#: (name, obstacle as (height m, length m; negative: a pothole), speed m/s, point spacing m
#: or None for the default, one point per node when 1.0)
CASES = (
    ("cleat 20 x 20 mm, 10 m/s", (0.02, 0.02), 10.0, None),
    ("cleat 20 x 20 mm, 20 m/s", (0.02, 0.02), 20.0, None),
    ("cleat 10 x 10 mm, 10 m/s", (0.01, 0.01), 10.0, None),
    ("cleat 50 x 50 mm, 10 m/s", (0.05, 0.05), 10.0, None),
    ("pothole 50 mm deep, 0.3 m, 10 m/s", (-0.05, 0.3), 10.0, None),
    ("cleat 20 x 20 mm, 10 m/s, one point per node", (0.02, 0.02), 10.0, 1.0),
)
#: The same cleat on a tire whose sidewall shear keeps the critical speed of the finest
#: meshes above the speed (the shipped GL073A_shear), so that N = 800 runs.
SHEAR_TIRE = "GL073A_shear"
SHEAR_CASES = (
    (f"cleat 20 x 20 mm, 10 m/s, {SHEAR_TIRE}", (0.02, 0.02), 10.0, None),
    (f"cleat 20 x 20 mm, 20 m/s, {SHEAR_TIRE}", (0.02, 0.02), 20.0, None),
)
#: The point spacing's own convergence: mesh, cleats (height = length, m), spacings (m).
SPACING_MESH = 200
SPACING_CLEATS = (0.01, 0.02)
SPACINGS_M = (5e-3, 2.5e-3, 1.25e-3, 6.25e-4)
#: The step's: mesh and steps (s).
STEP_MESH = 100
STEPS_S = (1e-4, 5e-5, 2.5e-5, 1.25e-5)


def _under_tire_means(study) -> tuple[float, float]:
    """Mean rim_Fz and contact_Fz (N) while the obstacle is under the tire, first mesh."""
    start, end = study.under_tire_s[0]
    inside = (study.time_s >= start) & (study.time_s <= end)
    return (float(study.rim_fz_n[0, inside].mean()),
            float(study.contact_fz_n[0, inside].mean()))


def _bar(total: int):
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None
    return tqdm(total=total, desc="meshes", unit="mesh", file=sys.stderr,
                disable=not sys.stderr.isatty())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", type=int, nargs="+", default=[100, 200, 400, 800],
                        help="element counts, coarse to fine")
    parser.add_argument("--step", type=float, default=None,
                        help="communication step in s (default the study's)")
    parser.add_argument("--tire-file", default=None,
                        help="a tire file, or a shipped tire by name (default GL073A_tied, "
                             "the default tire)")
    parser.add_argument("--record", metavar="JSON",
                        help="also write the results there (docs/theory.md quotes "
                        "docs/measured/cleat_convergence.json)")
    args = parser.parse_args()

    from record import load_average, write_record

    from tire_fmu.cli.common import table
    from tire_fmu.core import SupercriticalSpeedWarning, TireParameters, critical_speed
    from tire_fmu.core.obstacles import Obstacle
    from tire_fmu.core.studies import (
        CLEAT_STEP_S,
        CLEAT_TABLE_HEADER,
        cleat_convergence,
        cleat_table,
    )
    from tire_fmu.tire_files import read_tire_file

    load_at_start = load_average()
    tire = read_tire_file(args.tire_file).tire if args.tire_file else TireParameters()
    step = args.step or CLEAT_STEP_S
    meshes = sorted(set(args.meshes))
    shear_tire = read_tire_file(SHEAR_TIRE).tire
    critical = {id(t): {n: critical_speed(t, n).speed_m_s for n in meshes}
                for t in (tire, shear_tire)}
    cases = [(case, tire) for case in CASES] + [(case, shear_tire) for case in SHEAR_CASES]
    bar = _bar(len(cases) * len(meshes))
    done_before = 0
    results = []
    for (name, (height, length), speed, spacing), case_tire in cases:
        speeds = critical[id(case_tire)]
        runnable = [n for n in meshes if speed < speeds[n]]
        refused = [{"n_elements": n, "critical_speed_m_s": speeds[n]}
                   for n in meshes if n not in runnable]

        def progress(done: int, total: int, base: int = done_before) -> None:
            if bar is not None:
                bar.update(base + done - bar.n)

        started = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SupercriticalSpeedWarning)  # noted per case below
            options = {} if spacing is None else {"point_spacing_m": spacing}
            study = cleat_convergence(case_tire, Obstacle(height, length), speed, runnable,
                                      step_s=step, progress=progress, **options)
        elapsed = time.perf_counter() - started
        done_before += len(meshes)
        if bar is not None:
            bar.update(done_before - bar.n)
        data = study.to_dict(histories=False)
        near = [n for n in runnable if speed >= 0.8 * speeds[n]]
        results.append({"name": name, "refused": refused, "near_critical": [
            {"n_elements": n, "critical_speed_m_s": speeds[n]} for n in near],
            "seconds": elapsed, "study": data})
        rows, note = cleat_table(data)
        print(f"\n{name} ({elapsed:.1f} s)")
        print(table(rows, list(CLEAT_TABLE_HEADER)))
        print(note + ".")
        for item in refused:
            print(f"N = {item['n_elements']} not run: {speed:g} m/s is at or above its "
                  f"critical speed {item['critical_speed_m_s']:.4g} m/s")
        sys.stdout.flush()
    if bar is not None:
        bar.close()

    spacing_rows = []
    print(f"\npoint spacing, N = {SPACING_MESH}, 10 m/s: rim_Fz peak rise")
    for size in SPACING_CLEATS:
        for spacing in SPACINGS_M:
            study = cleat_convergence(tire, Obstacle(size, size), 10.0, (SPACING_MESH,),
                                      point_spacing_m=spacing, step_s=step)
            spacing_rows.append({"cleat_m": size, "point_spacing_m": spacing,
                                 "points_per_node": int(study.points_per_node[0]),
                                 "point_arc_m": float(study.point_arc_m[0]),
                                 "peak_rise_kn": float(study.peak_rise_n[0]) / 1e3,
                                 "run_s": float(study.run_s[0])})
            print(f"  {size * 1e3:g} mm cleat, spacing {spacing * 1e3:g} mm "
                  f"({study.points_per_node[0]} per node): {study.peak_rise_n[0] / 1e3:.2f} kN "
                  f"({study.run_s[0]:.1f} s)", flush=True)

    step_rows = []
    print(f"\nstep, N = {STEP_MESH}, 20 mm cleat at 10 m/s")
    for h in STEPS_S:
        study = cleat_convergence(tire, Obstacle(0.02, 0.02), 10.0, (STEP_MESH,), step_s=h)
        rim_mean, contact_mean = _under_tire_means(study)
        step_rows.append({"step_s": h, "peak_rise_kn": float(study.peak_rise_n[0]) / 1e3,
                          "mean_rim_fz_kn": rim_mean / 1e3,
                          "mean_contact_fz_kn": contact_mean / 1e3,
                          "min_contact_fz_kn": float(study.min_contact_fz_n[0]) / 1e3})
        print(f"  h = {h:g} s: peak rise {study.peak_rise_n[0] / 1e3:.2f} kN; under the tire "
              f"mean rim_Fz {rim_mean / 1e3:.2f} kN, mean contact_Fz {contact_mean / 1e3:.2f} "
              "kN", flush=True)
    if args.record:
        write_record(args.record, {"tire": args.tire_file or "GL073A_tied", "step_s": step,
                                   "meshes": meshes, "cases": results,
                                   "spacing": {"n_elements": SPACING_MESH, "rows": spacing_rows},
                                   "step": {"n_elements": STEP_MESH, "rows": step_rows}},
                     load_at_start)


if __name__ == "__main__":
    main()
