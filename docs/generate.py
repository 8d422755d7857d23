"""Rewrite the generated sections of README.md and docs/*.md: ``python3 docs/generate.py``.

A generated section sits between two markers and is never edited by hand:

    <!-- generated: NAME -->
    ...
    <!-- end generated: NAME -->

``NAME`` picks a function below. Two kinds:

- computed from the code now, cheaply (the FMU variable table): always current;
- measured, read from the recorded results in ``docs/measured/*.json`` that the benchmarks
  write with ``--record`` (each file holds the command that produced it, the date and the
  machine's load). To refresh them, run the command quoted in the section, then this script.

``python3 docs/generate.py --check`` rewrites nothing and exits 1 naming every stale section
(``tests/test_docs.py`` runs the same check).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MEASURED = ROOT / "docs" / "measured"
FILES = ("README.md", "docs/fmu.md", "docs/native.md", "docs/vehicle_demo.md",
         "docs/theory.md")
SECTION = re.compile(r"(<!-- generated: (?P<name>[\w-]+) -->\n)(?P<body>.*?)"
                     r"(<!-- end generated: (?P=name) -->)", re.S)

GENERATORS: dict[str, Callable[[], str]] = {}


def generator(name: str):
    def register(function):
        GENERATORS[name] = function
        return function

    return register


class StaleRecord(RuntimeError):
    """A recorded result is missing or lacks what a section quotes."""


def record(name: str) -> dict:
    path = MEASURED / f"{name}.json"
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise StaleRecord(f"{path.relative_to(ROOT)} is missing: run "
                          f"python3 benchmarks/{name}.py --record "
                          f"docs/measured/{name}.json") from None
    for key in ("command", "recorded", "machine", "results"):
        if key not in data:
            raise StaleRecord(f"{path.relative_to(ROOT)} has no {key!r}")
    return data


def provenance(data: dict, timing: bool = True) -> str:
    """Where a recorded figure comes from, in one sentence; timings also say how loaded the
    shared machine was."""
    if not timing:  # results of the computation itself: the same on any machine
        return f"From the full demo run by `{data['command']}` on {data['recorded']}."
    machine = data["machine"]
    loads = [machine.get("load_average_start"), machine.get("load_average_end")]
    load = "/".join(f"{x:g}" for x in loads if x is not None) or "unknown"
    return (f"Measured with `{data['command']}` on {data['recorded']} ({machine['cores']} "
            f"cores shared with other work, load average {load} at start/end; expect "
            "±30 % between runs).")


# -- computed sections ------------------------------------------------------------------------

def _start_text(v) -> str:
    if v.causality == "output":
        return "calculated"
    if isinstance(v.start, bool):
        return str(v.start).lower()
    return f"{v.start:g}"


@generator("fmu-variables")
def fmu_variables_table() -> str:
    from tire_fmu.fmu.interface import fmu_variables

    lines = ["| name | causality | type | unit | start | meaning |", "|---|---|---|---|---|---|"]
    for v in fmu_variables():
        lines.append(f"| `{v.name}` | {v.causality} | {v.type} | {v.unit or '-'} | "
                     f"{_start_text(v)} | {v.description} |")
    return "\n".join(lines)


@generator("contact-footprint")
def contact_footprint_table() -> str:
    from tire_fmu.core import OperatingPoint, TireParameters, build_model

    lines = ["| N | load | deflection | footprint | pushing nodes | secant K_v | tangent K_v |",
             "|---|---|---|---|---|---|---|"]
    for n in (100, 200, 400):
        for load in (10e3, 27.7e3, 60e3):
            fp = build_model(TireParameters(), OperatingPoint(n_elements=n,
                                                              load_n=load)).patch.footprint
            lines.append(f"| {n} | {load / 1e3:.3g} kN | {fp.deflection_m * 1e3:.2f} mm | "
                         f"{fp.length_m * 100:.2f} cm | {fp.n_active} | "
                         f"{fp.secant_stiffness_n_per_m / 1e6:.3f} MN/m | "
                         f"{fp.tangent_stiffness_n_per_m / 1e6:.3f} MN/m |")
    lines += ["", "Computed by `docs/generate.py` from `build_model(...).patch.footprint` "
              "(the same numbers as `tire-fmu patch --load L --elements N`)."]
    return "\n".join(lines)


@generator("pressure-law")
def pressure_law_table() -> str:
    from tire_fmu.core import OperatingPoint, TireParameters, build_model

    lines = ["| sidewall_pressure_exponent | secant K_v at 7.9 bar | at 3.95 bar | ratio |",
             "|---|---|---|---|"]
    for exponent in (0.0, 0.8):
        k = [build_model(TireParameters(sidewall_pressure_exponent=exponent,
                                        inflation_pressure=p),
                         OperatingPoint(load_n=27.7e3)).patch.footprint.secant_stiffness_n_per_m
             for p in (7.9e5, 3.95e5)]
        lines.append(f"| {exponent:g} | {k[0] / 1e6:.3f} MN/m | {k[1] / 1e6:.3f} MN/m | "
                     f"{k[1] / k[0]:.3f} |")
    lines += ["", "At 27.7 kN, N = 100; computed by `docs/generate.py` (the same as `tire-fmu "
              "patch --load 27700 --inflation-pressure 3.95e5 --tire "
              "sidewall_pressure_exponent=0.8`)."]
    return "\n".join(lines)


# -- measured sections ------------------------------------------------------------------------


@generator("contact-accuracy")
def contact_accuracy() -> str:
    data = record("bench_contact")
    r = data["results"]
    small = r["small_amplitude"]
    lines = ["| 0.1 mm sines, 2-300 Hz, h = 0.1 ms | " + " | ".join(small) + " |",
             "|---|" + "---|" * len(small)]
    for pair in next(iter(small.values())):
        lines.append(f"| largest \\|H\\| error, {pair} | "
                     + " | ".join(f"{100 * v[pair]:.2f} %" for v in small.values()) + " |")
    drop = r.get("drop")
    if drop:
        lines += ["", "| 5 cm drop and return, N = 40 | lift-off | touch-down | landing peak |",
                  "|---|---|---|---|"]
        for key, d in drop.items():
            label = "unreduced ring (DOP853)" if key == "unreduced" else f"contact FMU core, {key}"
            lines.append(f"| {label} | {d['lift_off_s'] * 1e3:.2f} ms | "
                         f"{d['touch_down_s'] * 1e3:.2f} ms | {d['landing_peak_kn']:.1f} kN |")
    step = r["road_step"]
    cost = r["cost"]
    lines += ["", f"A 1 mm road step at rest (the road rises by 1 mm between two points): the "
              f"contact force peaks at {step['peak_kn']:.1f} kN, never falls below "
              f"{step['min_kn']:.1f} kN, rings at about {step['ringing_hz']:.0f} Hz (x"
              f"{step['decay_per_4ms']:.2g} in 4 ms) and settles at {step['final_kn']:.1f} kN. "
              f"Building the contact model (the FMU's initialisation) takes "
              f"{cost['init_s_N100'] * 1e3:.0f} ms at N = 100 and "
              f"{cost['init_s_N400'] * 1e3:.0f} ms at N = 400; a step of the core simulator "
              f"{cost['step_us_unilateral_in contact']:.0f} µs in contact, "
              f"{cost['step_us_unilateral_airborne']:.0f} µs airborne.", "", provenance(data)]
    return "\n".join(lines)

def _demo_summary() -> tuple[dict, dict]:
    data = record("bench_vehicle")
    return data, data["results"]["demo"]["full_summary"]


@generator("demo-contact-events")
def demo_contact_events() -> str:
    data, summary = _demo_summary()
    rows = {r["quantity"]: r["value"] for r in summary["rows"]}
    events = ("cleat 20 x 20 mm", "cleat 40 x 20 mm", "pothole 50 mm deep, 0.3 m")
    lines = ["| event | contact | contact force min / max | rim load max | in_contact false |",
             "|---|---|---|---|---|"]
    for event in events:
        for law in ("unilateral", "linear"):
            key = f"{event}, {law}"
            if f"{key}: contact force min" not in rows:
                raise StaleRecord(f"{key} is not in the recorded demo: run "
                                  f"{data['command']}")
            lines.append(f"| {event} | {law} | {rows[key + ': contact force min'] / 1e3:.1f} / "
                         f"{rows[key + ': contact force max'] / 1e3:.1f} kN | "
                         f"{rows[key + ': rim load max'] / 1e3:.1f} kN | "
                         f"{rows[key + ': airborne']:.2f} % of the run |")
    lines += ["", provenance(data, timing=False)]
    return "\n".join(lines)


@generator("demo-agreement")
def demo_agreement() -> str:
    from vehicle_demo.quarter_car import RIDE_LABELS

    data, summary = _demo_summary()
    settings = summary["settings"]
    lines = [f"Agreement of the co-simulation (N = {settings['n_elements']}, h = "
             f"{settings['step_s']:g} s, speed {settings['tf_speed_m_s']:g} m/s) with the car on "
             "the full unreduced ring model, over the lines where the coherence exceeds 0.95 "
             "and the reference exceeds 1 % of its peak:", "",
             "| transfer function | max deviation | lines compared | compared up to |",
             "|---|---|---|---|"]
    for name, a in summary["agreements"].items():
        lines.append(f"| {RIDE_LABELS[name]} | {a['max_deviation_db']:.2g} dB | "
                     f"{a['points_compared']} / {a['points_total']} | "
                     f"{a['f_max_compared_hz']:.0f} Hz |")
    lines += ["", provenance(data, timing=False)]
    return "\n".join(lines)


def _row(summary: dict, quantity: str) -> float:
    for row in summary["rows"]:
        if row["quantity"].startswith(quantity):
            return row["value"]
    raise StaleRecord(f"the recorded demo summary has no row {quantity!r}")


def _number(value, spec: str) -> str:
    return "" if value is None else format(value, spec)


@generator("demo-resonances")
def demo_resonances() -> str:
    data, summary = _demo_summary()
    stiffness = _row(summary, "tire static stiffness K_v")
    mass = _row(summary, "tire mass moving with the rim")
    lines = [f"Resonances (Hz). *Analytic*: the undamped two-mass car on a tire spring K_v = "
             f"{stiffness / 1e6:.3g} MN/m, with the tire's rim-side mass ({mass:.0f} kg, see "
             "below) added to the wheel, and without it (*massless*). *Reference*: poles of "
             "the car coupled to the full ring model (|λ|/2π and ζ). *Co-sim*: poles fitted to "
             "the co-simulated H1 (body bounce, wheel hop) or peaks of |H1| (tire modes).", "",
             "| resonance | response | analytic | massless | reference | co-sim | "
             "ζ ref / co-sim | peak gain ref / co-sim |", "|---|---|---|---|---|---|---|---|"]
    for r in summary["resonances"]:
        zeta = ("" if r["zeta_reference"] is None else
                f"{r['zeta_reference']:.3f} / {r['zeta_cosim']:.3f}")
        lines.append(
            f"| {r['resonance']} | {r['response']} | {_number(r['f_analytic_hz'], '.3f')} | "
            f"{_number(r['f_analytic_massless_hz'], '.3f')} | "
            f"{_number(r['f_reference_hz'], '.3f')} | {_number(r['f_cosim_hz'], '.3f')} | "
            f"{zeta} | {r['gain_reference']:.3g} / {r['gain_cosim']:.3g} {r['gain_unit']} |")
    lines += ["", provenance(data, timing=False)]
    return "\n".join(lines)


@generator("demo-timing")
def demo_timing() -> str:
    data = record("bench_vehicle")
    demo = data["results"]["demo"]
    return (f"The full demo takes {demo['full_s']:.0f} s with the FMUs built; `--quick` "
            f"{demo['quick_warm_s']:.0f} s ({demo['quick_cold_s']:.0f} s in a fresh folder, "
            f"building both FMUs). {provenance(data)}")


@generator("vehicle-performance")
def vehicle_performance() -> str:
    data = record("bench_vehicle")
    results = data["results"]
    h = results["step_s"]
    lines = [f"One communication step of the two-FMU co-simulation (N = 100, h = {h:g} s, "
             "Gauss-Seidel), with the Python tire and with the native C tire exported at the "
             "same load and speed:", "",
             "| case | µs per step | × faster than real time |", "|---|---|---|"]
    for case, c in results["cosim"].items():
        lines.append(f"| {case} | {c['us_per_step']:.1f} | {1 / c['rtf']:.1f} |")
    lines += ["", "Each FMU alone through the same ctypes calls (doStep, get outputs, set "
              "inputs), the floor the master cannot go below: "
              + ", ".join(f"{name} {us:.1f} µs" for name, us in results["alone_us"].items())
              + ".", "",
              f"Sweep throughput, {next(iter(results['sweep'].values()))['points']} points "
              "(load × speed, N = 60, a 6 s multisine each; median of "
              f"{results.get('sweep_rounds', 1)} alternating rounds):", "",
              "| scheduler | points per minute | wall time |", "|---|---|---|"]
    for label, r in results["sweep"].items():
        used = f" (picked: {r['scheduler']})" if label.startswith("default") else ""
        lines.append(f"| {label}{used} | {r['points_per_minute']:.1f} | {r['wall_s']:.0f} s |")
    lines += ["", provenance(data)]
    return "\n".join(lines)


@generator("fmu-init")
def fmu_init() -> str:
    data = record("bench_fmu")
    init = data["results"]["init_s"]
    times = " and ".join(f"{seconds:.2f} s at N = {n}" for n, seconds in init.items())
    return (f"Initialisation of `TireModal.fmu` (instantiate to `fmi2ExitInitializationMode`, "
            f"which builds and reduces the model; median of {data['results']['init_repeats']}) "
            f"takes {times}. {provenance(data)}")


@generator("fmu-step-cost")
def fmu_step_cost() -> str:
    data = record("bench_fmu")
    costs = data["results"]["step_us"]
    floor = costs.get("(b) minimal pythonfmu")
    lines = ["| per communication step through fmpy | µs | × (b) minimal slave |",
             "|---|---|---|"]
    for name, us in costs.items():
        ratio = f"{us / floor:.2f}" if floor else "-"
        lines.append(f"| {name} | {us:.1f} | {ratio} |")
    lines += ["", provenance(data)]
    return "\n".join(lines)


def _computed(data: dict) -> str:
    """Where a recorded result of the computation (no timing) comes from."""
    return (f"From `{data['command']}` on {data['recorded']} (results of the computation, the "
            "same on any machine).")


def _pair(name: str) -> str:
    return name.replace("->", " → ")


@generator("reduction-defaults")
def reduction_defaults() -> str:
    data = record("bench_reduction")
    lines = ["| operating point | full | modal (default) | modal, no static correction | "
             "balanced (default) |", "|---|---|---|---|---|"]
    for row in data["results"]["defaults"]:
        case = row["case"].replace("f_max_hz = 300", "`f_max_hz=300`")
        if "plain_states" in row:
            lines.append(f"| {case} | {row['full_states']} | {row['modal_states']} states, "
                         f"{100 * row['modal_error']:.2f} % | {row['plain_states']}, "
                         f"{100 * row['plain_error']:.2f} % | {row['balanced_states']}, "
                         f"{100 * row['balanced_error']:.2f} % |")
        else:
            lines.append(f"| {case} | {row['full_states']} | {row['modal_states']}, "
                         f"**{100 * row['modal_error']:.0f} %** ({_pair(row['worst_pair'])}) "
                         "| | |")
    lines += ["", _computed(data)]
    return "\n".join(lines)


@generator("reduction-one-percent")
def reduction_one_percent() -> str:
    data = record("bench_reduction")
    rows = data["results"]["one_percent"]
    lines = [f"States kept for 1 % maximum relative FRF error over 1-300 Hz, N = "
             f"{rows[0]['n_elements']}, default load:", "",
             "| speed | full (reachable) | modal, former selection | modal | balanced | "
             "modal / balanced | hardest pair alone (modes above 300 Hz) | its Σ\\|terms\\| / "
             "\\|Σ terms\\| | modal, + velocity correction | modal, 1 % of each peak |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        pair = r["pairs"][r["hardest_pair"]]
        lines.append(
            f"| {r['speed_m_s']:g} m/s | {r['full_states']} ({r['reachable_states']}) | "
            f"{r['former_modal_states']} | {r['modal_states']} ({100 * r['modal_error']:.2f} %) "
            f"| {r['balanced_states']} ({100 * r['balanced_error']:.2f} %) | "
            f"{r['modal_states'] / r['balanced_states']:.1f} | {_pair(r['hardest_pair'])}: "
            f"{pair['states_alone']} ({pair['modes_above_band_alone']}) | "
            f"{pair['sum_of_magnitudes'] / pair['magnitude_of_sum']:.1f} | "
            f"{r['velocity_corrected_states']} | {r['peak_relative_states']} |")
    lines += ["", _computed(data)]
    return "\n".join(lines)


@generator("reduction-meshes")
def reduction_meshes() -> str:
    data = record("bench_reduction")
    meshes = data["results"]["finer_meshes"]
    lines = ["| N | speed | full | modal, former selection | modal | balanced | "
             "modal / balanced |", "|---|---|---|---|---|---|---|"]
    for r in meshes["rows"]:
        lines.append(f"| {r['n_elements']} | {r['speed_m_s']:g} m/s | {r['full_states']} | "
                     f"{r['former_modal_states']} | {r['modal_states']} | "
                     f"{r['balanced_states']} | {r['modal_states'] / r['balanced_states']:.1f} |")
    cut = meshes["cut"]
    lines += ["", f"At N = {cut['n_elements']} and {cut['speed_m_s']:g} m/s with the default "
              f"target a cut at `f_max_hz={cut['f_max_hz']:g}` leaves "
              f"{100 * cut['error']:.1f} % error with {cut['states']} states; no cut meets "
              f"the target, {100 * cut['uncut_error']:.2f} % with {cut['uncut_states']}.", "",
              _computed(data)]
    return "\n".join(lines)


# -- rewriting ----------------------------------------------------------------------------------

def render(text: str) -> tuple[str, list[str]]:
    """The text with every generated section regenerated, and the names it holds."""
    names = []

    def replace(match):
        name = match.group("name")
        if name not in GENERATORS:
            raise KeyError(f"unknown generated section {name!r}; known: {sorted(GENERATORS)}")
        names.append(name)
        return f"{match.group(1)}{GENERATORS[name]().rstrip()}\n{match.group(4)}"

    return SECTION.sub(replace, text), names


def stale_sections(files=FILES) -> list[str]:
    """'file: section' for every section whose text is not what the generator gives."""
    stale = []
    for name in files:
        path = ROOT / name
        current = path.read_text()
        fresh, _ = render(current)
        for old, new in zip(SECTION.finditer(current), SECTION.finditer(fresh)):
            if old.group("body") != new.group("body"):
                stale.append(f"{name}: {old.group('name')}")
    return stale


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="rewrite nothing; exit 1 if a generated section is stale")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    try:
        if args.check:
            stale = stale_sections()
            for item in stale:
                print(f"stale: {item} (run python3 docs/generate.py)", file=sys.stderr)
            return 1 if stale else 0
        for name in FILES:
            path = ROOT / name
            text, names = render(path.read_text())
            if names:
                path.write_text(text)
                print(f"{name}: {', '.join(names)}")
    except StaleRecord as error:
        print(f"docs/generate.py: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
