"""Rewrite the generated parts of README.md and docs/*.md: ``python3 docs/generate.py``.

A generated section sits between two markers and is never edited by hand:

    <!-- generated: NAME -->
    ...
    <!-- end generated: NAME -->

and so does a generated value inside a line of prose (a number, with its unit, or a message
quoted from a run):

    ... the largest stable step is <!-- value: NAME -->7.76 ms<!-- /value --> for ...

``NAME`` picks a function below (``spec:CONSTANT`` is the shared constant of
``tire_fmu/fmu/spec.py``, ``spec:CONSTANT:percent`` the same fraction in per cent). Two kinds:

- computed from the code now, cheaply (the FMU variable table, defaults, limits, messages of
  the Python FMU run in plain Python): always current;
- measured, read from the recorded results in ``docs/measured/*.json`` that the benchmarks
  write with ``--record`` (each file holds the command that produced it, the date and the
  machine's load). To refresh them, run the command quoted in the section, then this script.

``python3 docs/generate.py --check`` rewrites nothing and exits 1 naming every stale section
or value (``tests/test_docs.py`` runs the same check). The same test finds numbers typed into
the prose of :data:`PROSE_CHECKED` (see :func:`typed_numbers`): a number with a unit, or after
"≈", outside generated parts and code, that is not one of the file's :data:`DEFINITIONS`.
"""

from __future__ import annotations

import argparse
import functools
import json
import re
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MEASURED = ROOT / "docs" / "measured"
FILES = ("README.md", "docs/fmu.md", "docs/native.md", "docs/vehicle_demo.md",
         "docs/theory.md", "docs/roads.md")
SECTION = re.compile(r"(<!-- generated: (?P<name>[\w-]+) -->\n)(?P<body>.*?)"
                     r"(<!-- end generated: (?P=name) -->)", re.S)
VALUE = re.compile(r"(<!-- value: (?P<name>[\w:-]+) -->)(?P<body>[^\n]*?)(<!-- /value -->)")

GENERATORS: dict[str, Callable[[], str]] = {}
VALUES: dict[str, Callable[[], str]] = {}


def generator(name: str):
    def register(function):
        GENERATORS[name] = function
        return function

    return register


def value(name: str):
    def register(function):
        VALUES[name] = function
        return function

    return register


def value_text(name: str) -> str:
    """The text of the generated value ``name``."""
    if name.startswith("spec:"):
        from tire_fmu.fmu.spec import CONSTANTS

        _, constant, *style = name.split(":")
        if constant not in CONSTANTS:
            raise KeyError(f"unknown constant {constant!r} in value {name!r}")
        number = CONSTANTS[constant]
        return f"{100 * number:g} %" if style == ["percent"] else f"{number:g}"
    if name not in VALUES:
        raise KeyError(f"unknown generated value {name!r}; known: {sorted(VALUES)}")
    return VALUES[name]()


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
    if isinstance(v.start, str):
        return f'"{v.start}"'
    return f"{v.start:g}"


def _variables_table(variables) -> str:
    lines = ["| name | causality | type | unit | start | meaning |", "|---|---|---|---|---|---|"]
    for v in variables:
        lines.append(f"| `{v.name}` | {v.causality} | {v.type} | {v.unit or '-'} | "
                     f"{_start_text(v)} | {v.description} |")
    return "\n".join(lines)


@generator("fmu-variables")
def fmu_variables_table() -> str:
    from tire_fmu.fmu.interface import fmu_variables

    return _variables_table(fmu_variables())


@generator("inplane-fmu-variables")
def inplane_fmu_variables_table() -> str:
    from tire_fmu.fmu.interface import inplane_fmu_variables

    return _variables_table(inplane_fmu_variables())


#: The user's examples of docs/fmu.md, each a script run by
#: tests/test_docs_examples.py and shown whole.
EXAMPLES = {"example-cleat": "cleat_road_file.py",
            "example-quarter-car": "quarter_car_road_file.py",
            "example-tire-inplane": "tire_inplane_braking.py",
            "example-tire-inplane-native": "tire_inplane_native_host_road.py"}


def _example(file: str) -> str:
    text = (ROOT / "docs" / "examples" / file).read_text().rstrip("\n")
    return f"`docs/examples/{file}`:\n\n```python\n{text}\n```"


for _name, _file in EXAMPLES.items():
    generator(_name)(functools.partial(_example, _file))


@generator("truck-real-time")
def truck_real_time_table() -> str:
    data = record("bench_truck")
    r = data["results"]
    lines = ["| tires | host | real-time factor (wall / simulated time) | body heave "
             "acceleration, rms |", "|---|---|---|---|"]
    for row in r["rows"]:
        lines.append(f"| four {row['fmu']} | {row['host']} | {row['real_time_factor']:.3g} | "
                     f"{row['body_az_rms_m_s2']:.3g} m/s² |")
    return ("\n".join(lines) + f"\n\n{r['duration_s']:g} s of the truck at "
            f"{r['speed_m_s']:g} m/s on an ISO 8608 class C road, host step "
            f"{r['step_s'] * 1e3:g} ms, the median of {r['repeats']} runs; CPU: "
            f"{data['machine']['cpu']}. " + provenance(data))


@value("road-queries")
def _road_queries() -> str:
    from tire_fmu.fmu.interface import ROAD_QUERIES

    return f"{ROAD_QUERIES}"


@value("road-query-gap-20-1")
def _road_query_gap() -> str:
    from tire_fmu.fmu.interface import ROAD_QUERIES

    return f"one every {20.0 * 1e-3 / ROAD_QUERIES * 1e3:.2g} mm at 20 m/s and a 1 ms step"


@value("inplane-critical-fraction")
def _inplane_critical_fraction() -> str:
    from tire_fmu.core.inplane_host import CRITICAL_SPEED_FRACTION

    return f"{CRITICAL_SPEED_FRACTION:g}"


@value("inplane-default-step")
def _inplane_default_step() -> str:
    from tire_fmu.core.inplane_host import DEFAULT_HOST_STEP_S

    return f"{DEFAULT_HOST_STEP_S * 1e3:g} ms"


@generator("inplane-fmu-cost")
def inplane_fmu_cost_table() -> str:
    data = record("bench_inplane_fmu")
    costs, inits = data["results"]["step_us"], data["results"]["init_s"]
    names = list(next(iter(costs.values())))
    # the ratios of the names the record has: (a)/(d), and with the native in-plane FMU
    # (f) what the Python layer costs, (a)/(f)
    label = {key: next((n for n in names if n.startswith(key)), None)
             for key in ("(a) ", "(d) ", "(f) ")}
    ratios = [(f"{a.strip()}/{b.strip()}", label[a], label[b])
              for a, b in (("(a) ", "(d) "), ("(a) ", "(f) ")) if label[a] and label[b]]
    lines = ["| per communication step through fmpy, h = 0.1 ms, µs | " + " | ".join(names)
             + "".join(f" | {title}" for title, _, _ in ratios) + " |",
             "|---" * (len(names) + 1 + len(ratios)) + "|"]
    for regime, row in costs.items():
        lines.append(f"| {regime} | " + " | ".join(f"{row[n]:.1f}" for n in names)
                     + "".join(f" | {row[a] / row[b]:.2g}" for _, a, b in ratios) + " |")
    labels = list(next(iter(inits.values())))
    lines += ["", "| initialisation, warm process, s | " + " | ".join(labels) + " |",
              "|---" * (len(labels) + 1) + "|"]
    for name, row in inits.items():
        lines.append(f"| {name} | " + " | ".join(f"{row[k]:.2f}" for k in labels) + " |")
    lines += ["", provenance(data)]
    return "\n".join(lines)


@generator("host-timing")
def host_timing_table() -> str:
    data = record("bench_host_timing")
    results = data["results"]
    lines = ["| extending the inputs over a 1 ms step (the in-plane core) | rim_Fz | rim_Fx |",
             "|---|---|---|"]
    for scheme, errors in results["schemes"].items():
        chosen = " (the FMUs')" if scheme == "rate and its changes" else ""
        lines.append(f"| {scheme}{chosen} | {100 * errors['rim_Fz']:.2f} % | "
                     f"{100 * errors['rim_Fx']:.2f} % |")
    lines += ["", "| FMU (plain master) | h | rim_Fz | rim_Fx |", "|---|---|---|---|"]
    for name, steps in results["fmus"].items():
        for h, errors in steps.items():
            lines.append(f"| {name} | {float(h) * 1e3:g} ms | {100 * errors['rim_Fz']:.2f} % "
                         f"| {100 * errors['rim_Fx']:.2f} % |")
    return ("\n".join(lines) + f"\n\nComputed by `{data['command']}` on {data['recorded']} "
            "(the same numbers on any machine).\n")


@generator("contact-footprint")
def contact_footprint_table() -> str:
    from tire_fmu.core import OperatingPoint, TireParameters, build_model

    lines = ["| N | load | deflection | footprint | pushing points (per node) | secant K_v | "
             "tangent K_v | footprint, one point per node |",
             "|---|---|---|---|---|---|---|---|"]
    for n in (100, 200, 400, 800):
        for load in (10e3, 27.7e3, 60e3):
            fp = build_model(TireParameters(), OperatingPoint(n_elements=n,
                                                              load_n=load)).patch.footprint
            nodes = build_model(TireParameters(), OperatingPoint(
                n_elements=n, load_n=load, contact_point_spacing_m=1.0)).patch.footprint
            lines.append(f"| {n} | {load / 1e3:.3g} kN | {fp.deflection_m * 1e3:.2f} mm | "
                         f"{fp.length_m * 100:.2f} cm | {fp.n_active} "
                         f"({fp.zone.points_per_node}) | "
                         f"{fp.secant_stiffness_n_per_m / 1e6:.3f} MN/m | "
                         f"{fp.tangent_stiffness_n_per_m / 1e6:.3f} MN/m | "
                         f"{nodes.length_m * 100:.2f} cm |")
    lines += ["", "Computed by `docs/generate.py` from `build_model(...).patch.footprint` "
              "(the same numbers as `tire-fmu patch --load L --elements N`; the last column "
              "with `--point-spacing 1`, one contact point per node)."]
    return "\n".join(lines)


@generator("k-cw-effect")
def k_cw_effect_table() -> str:
    from dataclasses import replace

    from tire_fmu.core import OperatingPoint, TireParameters, build_model

    base = TireParameters()
    lines = ["| k_cw [N/m²] | footprint at 27.7 kN | deflection | secant K_v | tangent K_v |",
             "|---|---|---|---|---|"]
    for factor in (0.1, 0.3, 1.0, 3.0, 10.0):
        tire = replace(base, k_cw=base.k_cw * factor)
        fp = build_model(tire, OperatingPoint(n_elements=200, load_n=27.7e3)).patch.footprint
        lines.append(f"| {tire.k_cw:.3g} ({factor:g} x) | {fp.length_m * 100:.2f} cm | "
                     f"{fp.deflection_m * 1e3:.2f} mm | "
                     f"{fp.secant_stiffness_n_per_m / 1e6:.3f} MN/m | "
                     f"{fp.tangent_stiffness_n_per_m / 1e6:.3f} MN/m |")
    lines += ["", "N = 200, default point spacing; computed by `docs/generate.py` (the same as "
              "`tire-fmu patch --load 27700 --elements 200 --tire k_cw=VALUE`)."]
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


@generator("inplane-closed-form")
def inplane_closed_form_table() -> str:
    import numpy as np

    from tire_fmu.core.inplane import InPlaneRing, InPlaneTire
    from tire_fmu.core.inplane_analytic import inplane_analytic_modes
    from tire_fmu.core.inplane_modes import order_frequencies_at_rest_hz

    model = InPlaneTire()
    orders = range(11)
    exact = inplane_analytic_modes(model, orders).frequencies_hz
    rings = {n: InPlaneRing(model, n) for n in (100, 400)}
    lines = ["| n | closed form [Hz] | FDM N = 100 [Hz] | FDM N = 400 [Hz] | largest error, "
             "N = 100 / 400 |", "|---|---|---|---|---|"]
    for n in orders:
        fdm = {m: order_frequencies_at_rest_hz(r, n) for m, r in rings.items()}
        err = [f"{np.max(np.abs(fdm[m] / exact[n] - 1)) * 100:.3f} %" for m in rings]
        lines.append(f"| {n} | " + " | ".join(
            ", ".join(f"{x:.2f}" for x in row) for row in (exact[n], fdm[100], fdm[400]))
            + f" | {err[0]} / {err[1]} |")
    lines += ["", "Every branch of each order (tread radial and tangential, sidewall radial) of "
              "the "
              "default in-plane tire (GL073A with the default tangential data), undeformed, rim "
              "held; computed by `docs/generate.py` (the same as `tire-fmu inplane-modes "
              "--elements N`; closed form: core/inplane_analytic.py)."]
    return "\n".join(lines)


@generator("inplane-rolling")
def inplane_rolling_table() -> str:
    import numpy as np

    from tire_fmu.core.inplane import InPlaneRing, InPlaneTire
    from tire_fmu.core.inplane_analytic import inextensible_split_factor
    from tire_fmu.core.inplane_modes import order_frequencies_hz

    model = InPlaneTire()
    lines = ["| V [m/s] | n | pair [Hz] | split [Hz] | 2nΩ(n²−1)/(n²+1) [Hz] | radial-only "
             "ring 2nΩ [Hz] |", "|---|---|---|---|---|---|"]
    for speed in (10.0, 40.8):
        spin = speed / model.tire.R
        ring = InPlaneRing(model, 200, spin_rad_s=spin)
        for n in range(1, 7 if speed < 20 else 5):
            pair = np.sort(np.abs(order_frequencies_hz(ring, n)))[:2]
            lines.append(f"| {speed:g} | {n} | {pair[0]:.2f} / {pair[1]:.2f} | "
                         f"{pair[1] - pair[0]:.2f} | "
                         f"{2 * spin * inextensible_split_factor(n) / (2 * np.pi):.2f} | "
                         f"{2 * n * spin / (2 * np.pi):.2f} |")
    lines += ["", "The lowest pair of each order seen from the ground (N = 200, rim held, the "
              "default in-plane tire with its damping); at 40.8 m/s the slow wave of orders "
              "above 4 "
              "meets the sidewall's radial branch, so the lowest two are no longer one pair; "
              "computed by `docs/generate.py` (the "
              "same as `tire-fmu inplane-modes --speed V --elements 200`)."]
    return "\n".join(lines)


@generator("inplane-rotational")
def inplane_rotational_table() -> str:
    from tire_fmu.core.inplane import InPlaneRing, InPlaneTire
    from tire_fmu.core.inplane_modes import tire_modes

    model = InPlaneTire()
    tang = model.tangential
    lines = ["| rim | rotational mode [Hz] | first modes [Hz] (kind, order) |", "|---|---|---|"]
    for free in (False, True):
        result = tire_modes(InPlaneRing(model, 100, rim_free=free), f_max_hz=80)
        (rot,) = result.select(kind="rotational")
        first = [m for m in result.modes if m.kind != "rigid"][:6]
        lines.append(f"| {'free' if free else 'held'} | {rot.frequency_hz:.2f} | "
                     + ", ".join(f"{m.frequency_hz:.1f} ({m.kind}, {m.order})" for m in first)
                     + " |")
    lines += ["", f"N = 100, undeformed, at rest; wheel {tang.wheel_mass_kg:g} kg and "
              f"{tang.wheel_inertia_kg_m2:g} kg m² when free; computed by `docs/generate.py` "
              "(the same as `tire-fmu inplane-modes [--rim-free]`)."]
    return "\n".join(lines)


@generator("inplane-cleat")
def inplane_cleat_table() -> str:
    data = record("bench_inplane_cleat")
    res = data["results"]
    lines = ["| obstacle | point spacing | peak Fz | Fx min / max | Fx rms | Fx dominant | "
             "run time |", "|---|---|---|---|---|---|---|"]
    for row in res["cleat"]:
        lines.append(f"| {row['obstacle']} | {row['spacing_m'] * 1e3:g} mm | "
                     f"{row['peak_fz_n'] / 1e3:.2f} kN | {row['fx_min_n'] / 1e3:.2f} / "
                     f"{row['fx_max_n'] / 1e3:.2f} kN | {row['fx_rms_n'] / 1e3:.2f} kN | "
                     f"{row['fx_dominant_hz']:.1f} Hz | {row['seconds']:.0f} s |")
    lines += ["", f"Axle held, wheel free, {res['speed_m_s']:g} m/s, N = 100, h = "
              f"{res['step_s'] * 1e6:g} µs, 27.7 kN; the rim forces after the start of rolling "
              "has settled. " + provenance(data)]
    return "\n".join(lines)


def _brake_ringing_gaps(key: str, fitted: str) -> list[float]:
    """The run's fitted rotational mode against rolling_modes', relative, every case run."""
    cases = record("bench_inplane_brake_ringing")["results"]["cases"]
    return [case["run_fit"][0][fitted] / case[key] - 1 for case in cases if "run_fit" in case]


@generator("inplane-friction")
def inplane_friction_table() -> str:
    data = record("bench_inplane_friction")
    res = data["results"]
    lines = ["| k_tx | footprint half length | slip stiffness dFx/dκ | brush model 2 k_tx a² | "
             + " / ".join(f"{t / 1e3:g}" for t in res["brakes_n_m"]) + " kN m brake: slip | "
             "sliding points |", "|---|---|---|---|---|---|"]
    for r in res["rows"]:
        lines.append(f"| {r['k_tx_factor']:g} × default ({r['k_tx_n_m2']:.3g} N/m²) | "
                     f"{r['half_footprint_m'] * 1e3:.1f} mm | {r['slip_stiffness_n'] / 1e3:.0f} kN "
                     f"| {r['brush_slip_stiffness_n'] / 1e3:.0f} kN | "
                     + " / ".join(f"{100 * x:.2f} %" for x in r["brake_slip"]) + " | "
                     + " / ".join(str(n) for n in r["brake_sliding_points"])
                     + f" of {r['points_in_contact']} |")
    lines += ["", f"`steady_rolling` at {res['speed_m_s']:g} m/s, {res['load_n'] / 1e3:.1f} kN, "
              f"N = {res['n_elements']}, {res['spacing_m'] * 1e3:g} mm points, μ = "
              f"{res['friction_coefficient']:g}; the slip stiffness from free rolling and a "
              f"{res['small_torque_n_m']:g} N m brake (where only the rearmost point, at the "
              "footprint's vanishing pressure, slides, as a brush's does under any slip). "
              "Results of the "
              f"computation, from `{data['command']}` on {data['recorded']}."]
    return "\n".join(lines)


@generator("inplane-reference")
def inplane_reference_table() -> str:
    data = record("bench_inplane_reference")
    res = data["results"]
    lines = ["| wheel | step | Fx: rms difference | Fz: rms difference |", "|---|---|---|---|"]
    lines += [f"| {r['wheel']} | {r['step_s'] * 1e6:g} µs | {100 * r['fx_rms_difference']:.2f} % "
              f"| {100 * r['fz_rms_difference']:.2f} % |" for r in res["rows"]]
    fx = ", ".join(f"{s['fx_dominant_hz']:.1f} Hz with the wheel {s['wheel']}"
                   for s in res["spectra"])
    lines += ["", f"The {res['speed_m_s']:g} m/s cleat, N = {res['n_elements']}, "
              f"{res['spacing_m'] * 1e3:g} mm points, {res['duration_s']:g} s, against the "
              "reference integrated once with scipy's adaptive Runge-Kutta; Fx's and Fz's rms "
              "difference relative to Fx's rms and to Fz's rms about the load. The reference's "
              f"Fx is dominated by {fx}; its Fz by the passage itself (the run's lowest "
              f"frequency, {res['spectra'][0]['fz_dominant_hz']:.1f} Hz, about its inverse "
              "length): no mode rings through Fz in so short a run. Results of the computation "
              f"(the same on any machine), from `{data['command']}` on {data['recorded']}."]
    return "\n".join(lines)


@generator("inplane-reduction")
def inplane_reduction_table() -> str:
    data = record("bench_inplane_reduction")
    res = data["results"]
    lines = ["| N | operating point | full model | 1 %: states (error) | 0.1 %: states (error) "
             "| linearise / reduce | a step: reduced model / simulator |",
             "|---|---|---|---|---|---|---|"]
    for r in res["rows"]:
        torque = f", {r['torque_n_m']:g} N m" if r["torque_n_m"] else ""
        lines.append(
            f"| {r['n_elements']} | {r['speed_m_s']:g} m/s, wheel {r['wheel']}{torque} | "
            f"{r['full_states']} states | {r['states_1pc']} ({100 * r['error_1pc']:.2f} %) | "
            f"{r['states_01pc']} ({100 * r['error_01pc']:.3f} %) | {r['build_s']:.2f} / "
            f"{r['reduce_s']:.1f} s | {r['step_reduced_s'] * 1e6:.1f} / "
            f"{r['step_simulator_s'] * 1e6:.0f} µs |")
    lines += ["", f"{res['load_n'] / 1e3:.1f} kN, {res['spacing_m'] * 1e3:g} mm points, the "
              "ring unreduced; the error is the largest over every input/output pair and 0.5-300 "
              "Hz; a step of the reduced model (1 %) is its exact discretisation at "
              f"{res['step_s'] * 1e6:g} µs, a step of the simulator the FMUs' (Ritz basis to 300 "
              "Hz), medians. " + provenance(data)]
    return "\n".join(lines)


@value("brake-slip-gap")
def brake_slip_gap() -> str:
    """The slip the brake run settles at against steady_rolling's, the largest of the cases."""
    cases = record("bench_inplane_brake_ringing")["results"]["cases"]
    gaps = [c["settled_slip"] / c["steady_slip"] - 1 for c in cases if "settled_slip" in c]
    return f"{100 * max(abs(g) for g in gaps):.1f} %"


@value("brake-ringing-frequency-gap")
def brake_ringing_frequency_gap() -> str:
    gaps = _brake_ringing_gaps("rotational_hz", "frequency_hz")
    return f"{100 * max(abs(g) for g in gaps):.1f} %"


@value("brake-ringing-decay-gap")
def brake_ringing_decay_gap() -> str:
    gaps = _brake_ringing_gaps("rotational_decay_1_s", "decay_1_s")
    return f"{100 * min(gaps):.0f}–{100 * max(gaps):.0f} %"


@generator("inplane-brake-ringing")
def inplane_brake_ringing_table() -> str:
    data = record("bench_inplane_brake_ringing")
    res = data["results"]
    lines = ["| N | points | step | `rolling_modes`: rotational | run, fit: rotational | "
             "next modes: `rolling_modes` / run | single damped cosine | periodogram | "
             "settled slip: run / `steady_rolling` |",
             "|---|---|---|---|---|---|---|---|---|"]
    for case in res["cases"]:
        eig = case["step_modes"]
        head = (f"| {case['n_elements']} | {case['spacing_m'] * 1e3:g} mm | "
                f"{case['step_s'] * 1e6:g} µs | {case['rotational_hz']:.2f} Hz, "
                f"{case['rotational_decay_1_s']:.1f} 1/s | ")
        if "run_fit" not in case:
            lines.append(head + "(linearisation only) | "
                         + ", ".join(f"{m['frequency_hz']:.2f}" for m in eig[1:3])
                         + " Hz | | | |")
            continue
        fit = case["run_fit"]
        error = (fit[0]["frequency_hz"] / case["rotational_hz"] - 1) * 100
        lines.append(head + f"{fit[0]['frequency_hz']:.2f} Hz ({error:+.1f} %), "
                     f"{fit[0]['decay_1_s']:.1f} 1/s | "
                     + ", ".join(f"{e['frequency_hz']:.2f} / {r['frequency_hz']:.2f}"
                                 for e, r in zip(eig[1:3], fit[1:3]))
                     + f" Hz | {case['single_fit_hz']:.2f} Hz, "
                     f"{case['single_fit_decay_1_s']:.1f} 1/s | {case['periodogram_hz']:.2f} Hz | "
                     f"{case['settled_slip'] * 100:.3f} / {case['steady_slip'] * 100:.3f} % |")
    rest = res["rest"]
    lines += ["", f"A {res['torque_n_m']:g} N m brake step at {res['speed_m_s']:g} m/s, wheel "
              f"free, axle held, {res['load_n'] / 1e3:.1f} kN. The run's Fx from "
              f"{res['fit_from_s'] * 1e3:g} ms after the step to the end is fitted with "
              f"{len(res['cases'][0]['step_modes'])} damped cosines seeded by the modes with the "
              "largest part in the linear step response (`torque_step`). At rest the same step "
              f"rings at {rest['single_fit_hz']:.2f} Hz against `loaded_modes`' "
              f"{rest['loaded_modes_hz']:.2f} Hz; `rolling_modes` at "
              f"{rest['slow_speed_m_s']:g} m/s gives {rest['rolling_modes_slow_hz']:.2f} Hz. "
              f"Measured with `{data['command']}` on {data['recorded']}."]
    return "\n".join(lines)


@generator("inplane-rolling-resistance")
def inplane_rolling_resistance_table() -> str:
    data = record("bench_inplane_cleat")
    rows = data["results"]["rolling_resistance"]
    speeds = sorted({r["speed_m_s"] for r in rows})
    cases = sorted({(r["tire"], r["load_n"]) for r in rows})
    lines = ["| tire file | load | " + " | ".join(f"{v:g} m/s" for v in speeds) + " |",
             "|---|---|" + "---|" * len(speeds)]
    for tire, load in cases:
        cells = [next(r for r in rows if (r["tire"], r["load_n"]) == (tire, load)
                      and r["speed_m_s"] == v) for v in speeds]
        lines.append(f"| {tire} | {load / 1e3:.2f} kN | "
                     + " | ".join(f"{c['coefficient']:.5f}" for c in cells) + " |")
    lines += ["", "Rolling resistance coefficient -Fx/Fz of the free wheel on a flat road "
              "(N = 100, 10 mm points, the mean over 0.15-0.3 s of a run from the static "
              "footprint). " + provenance(data)]
    return "\n".join(lines)


@generator("inplane-convergence")
def inplane_convergence_table() -> str:
    data = record("bench_inplane_convergence")
    results = data["results"]
    lines = ["| N | points | rotational, wheel held | rotational, wheel free "
             "| rolling resistance, viscous | rolling resistance, hysteretic |",
             "|---|---|---|---|---|---|"]
    for r in results["rows"]:
        lines.append(f"| {r['n_elements']} | {r['points']} at {r['point_spacing_m'] * 1e3:g} mm "
                     f"| {r['rotational_held_hz']:.2f} Hz | {r['rotational_free_hz']:.2f} Hz "
                     f"| {r['rolling_resistance']:.5f} "
                     f"| {r['rolling_resistance_hysteretic']:.5f} |")
    lines += ["", f"The loaded tire at {results['load_n'] / 1e3:.2f} kN: its rotational mode at "
              f"rest (`loaded_modes`) and the free-rolling resistance coefficient -Fx/Fz at "
              f"{results['speed_m_s']:g} m/s (`steady_rolling`), by mesh and contact-point "
              "spacing, with the paper's viscous damping (the default tire) and with the "
              f"hysteretic loss of `{results['hysteretic_tire']}`. " + provenance(data)]
    return "\n".join(lines)


def _convergence_rows(key: str) -> dict:
    rows = record("bench_inplane_convergence")["results"]["rows"]
    return {(r["n_elements"], r["point_spacing_m"]): r[key] for r in rows}


@value("hysteretic-rr-convergence")
def hysteretic_rr_convergence() -> str:
    """How far the hysteretic coefficient moves with the mesh: N = 100 and 200 against N = 400
    at the same point spacing, the largest over the spacings."""
    rr = _convergence_rows("rolling_resistance_hysteretic")
    finest = max(n for n, _ in rr)
    spacings = sorted({s for _, s in rr})

    def worst(n):
        return max(abs(rr[n, s] / rr[finest, s] - 1) for s in spacings if (n, s) in rr)

    coarse = sorted({n for n, _ in rr if n < finest})
    return " and ".join(f"{100 * worst(n):.1f} % at N = {n}" for n in coarse) + (
        f" of N = {finest}")


@value("viscous-rr-convergence")
def viscous_rr_convergence() -> str:
    """The viscous coefficient's change from N = 100 to N = 400, the largest over spacings."""
    rr = _convergence_rows("rolling_resistance")
    finest, coarsest = max(n for n, _ in rr), min(n for n, _ in rr)
    change = max(abs(rr[coarsest, s] / rr[finest, s] - 1) for _, s in rr if (finest, s) in rr)
    return f"{100 * change:.0f} %"


@generator("inplane-footprint")
def inplane_footprint_table() -> str:
    from tire_fmu.core.inplane import InPlaneTire
    from tire_fmu.core.inplane_contact import (
        InPlaneSimulator,
        deflection_for_load,
        loaded_modes,
        steady_rolling,
    )

    model = InPlaneTire()
    spacing = 0.005
    deflection = deflection_for_load(model, 27.7e3, 100, point_spacing_m=spacing)
    lines = ["| wheel | loaded rotational mode | points in contact |", "|---|---|---|"]
    for wheel in ("held", "free"):
        modes = loaded_modes(InPlaneSimulator(model, 100, 0.0, deflection, wheel=wheel,
                                              point_spacing_m=spacing), f_max_hz=100)
        (f,) = [f for f, k in zip(modes.frequencies_hz, modes.kinds) if k == "rotational"]
        lines.append(f"| {wheel} | {f:.2f} Hz | {modes.points_in_contact} |")
    lines += ["", "| brake torque | slip ratio | Fx | sliding points |", "|---|---|---|---|"]
    sim = InPlaneSimulator(model, 100, 10.0, deflection, point_spacing_m=spacing)
    for torque in (0.0, -1000.0, -3000.0, -6000.0):
        st = steady_rolling(sim, torque)
        lines.append(f"| {torque:g} N m | {st.slip_ratio * 100:.3f} % | "
                     f"{st.rim_fx_n / 1e3:.3f} kN | {st.sliding_points} |")
    lines += ["", f"27.7 kN (deflection {deflection * 1e3:.2f} mm), N = 100, 5 mm points; the "
              "loaded modes at rest, the steady rolling at 10 m/s; computed by "
              "`docs/generate.py` (`tire-fmu inplane-modes --load 27700 [--rim-free]`, "
              "`core.inplane_contact.steady_rolling`)."]
    return "\n".join(lines)


@generator("inplane-rolling-modes")
def inplane_rolling_modes_table() -> str:
    from tire_fmu.core.inplane import InPlaneTire
    from tire_fmu.core.inplane_contact import (
        InPlaneSimulator,
        deflection_for_load,
        loaded_modes,
    )
    from tire_fmu.core.inplane_rolling_modes import rolling_modes

    model = InPlaneTire()
    spacing = 0.01
    deflection = deflection_for_load(model, 27.7e3, 100, point_spacing_m=spacing)

    def rotational(modes):
        (k,) = [i for i, kind in enumerate(modes.kinds) if kind == "rotational"]
        return modes.frequencies_hz[k], modes.damping_ratios[k]

    rest = loaded_modes(InPlaneSimulator(model, 100, 0.0, deflection, point_spacing_m=spacing,
                                         wheel="free"), f_max_hz=100)
    f, z = rotational(rest)
    lines = ["| speed | rotational mode, free rolling | rotational mode, -3000 N m | "
             "sliding points at -3000 N m |", "|---|---|---|---|",
             f"| at rest (`loaded_modes`) | {f:.2f} Hz, ζ {z:.4f} | | |"]
    for speed in (0.05, 1.0, 2.0, 5.0, 10.0, 20.0):
        sim = InPlaneSimulator(model, 100, speed, deflection, point_spacing_m=spacing,
                               wheel="free")
        free = rotational(rolling_modes(sim, 0.0, f_max_hz=100))
        braked_modes = rolling_modes(sim, -3000.0, f_max_hz=100)
        braked = rotational(braked_modes)
        lines.append(f"| {speed:g} m/s | {free[0]:.2f} Hz, ζ {free[1]:.4f} | {braked[0]:.2f} Hz, "
                     f"ζ {braked[1]:.4f} | {braked_modes.sliding_points} |")
    lines += ["", "Wheel free, axle held, 27.7 kN (deflection "
              f"{deflection * 1e3:.2f} mm), N = 100, 10 mm points; f the damped frequency, ζ "
              "= -Re λ/|λ|; computed by `docs/generate.py` (`tire-fmu inplane-modes --load "
              "27700 --speed V --rim-free [--torque -3000] --point-spacing 0.01`)."]
    return "\n".join(lines)


@generator("inplane-rolling-entry")
def inplane_rolling_entry_table() -> str:
    import numpy as np

    from tire_fmu.core.inplane import InPlaneTire
    from tire_fmu.core.inplane_contact import (
        InPlaneSimulator,
        deflection_for_load,
        steady_rolling,
    )
    from tire_fmu.core.inplane_rolling_modes import rolling_modes, steady_sets

    model = InPlaneTire()
    spacing, torque = 0.01, -3000.0
    deflection = deflection_for_load(model, 27.7e3, 100, point_spacing_m=spacing)
    sim = InPlaneSimulator(model, 100, 10.0, deflection, point_spacing_m=spacing, wheel="free")
    steady = steady_rolling(sim, torque)
    contact, stick, sign = steady_sets(sim, steady)
    first = int(np.flatnonzero(contact)[0])
    nr = sim._n_ring_coords
    pressed = float(sim._pen0[first] + sim._jn[first, :nr] @ steady.state[:nr])
    sliding, off, slide_sign = stick.copy(), contact.copy(), sign.copy()
    sliding[first] = False
    off[first] = False
    # sliding the way its element is deflected, as the run's first point does
    slide_sign[first] = np.sign(steady.element_deflection_m[first])
    lines = ["| first point in contact | rotational mode | decay |", "|---|---|---|"]
    for label, sets in (("sticking (steady_rolling's sets)", None),
                        ("sliding", (contact, sliding, slide_sign)),
                        ("off the road", (off, stick, sign))):
        modes = rolling_modes(sim, torque, 100.0, sets)
        (k,) = [i for i, kind in enumerate(modes.kinds) if kind == "rotational"]
        lines.append(f"| {label} | {modes.frequencies_hz[k]:.2f} Hz | "
                     f"{modes.decay_rates_1_s[k]:.1f} 1/s |")
    lines += ["", f"{torque:g} N m at 10 m/s, wheel free, 27.7 kN, N = 100, 10 mm points; the "
              f"first point in contact pressed by {pressed * 1e6:.1f} µm in the steady rolling; "
              "the other points frozen as in the steady rolling; computed by "
              "`docs/generate.py` (`rolling_modes(..., sets=...)`)."]
    return "\n".join(lines)


@generator("tied-sidewall")
def tied_sidewall_table() -> str:
    import numpy as np

    from tire_fmu.core.analytic import analytic_modes
    from tire_fmu.core.dispersion import body_frequencies
    from tire_fmu.core.standing_waves import critical_speed
    from tire_fmu.tire_files import read_tire_file

    paper, tied = read_tire_file("GL073A").tire, read_tire_file("GL073A_tied").tire
    top = int(tied.sidewall_max_order)
    meshes = (100, 200, 400, 800, 1600)
    lines = ["| tire | " + " | ".join(f"N = {n}" for n in meshes) + " | continuum |",
             "|---|" + "---|" * (len(meshes) + 1)]
    lo, hi = 1.0, 400.0  # the continuum: ω_in(top, Ω) = top·Ω, by bisection on the symbols
    for _ in range(80):
        spin = 0.5 * (lo + hi)
        low, _ = body_frequencies(tied, np.array([top]), spin, None)
        lo, hi = (spin, hi) if low[0] - top * spin > 0 else (lo, spin)
    for name, tire, limit in (("GL073A (lumped)", paper, "0"),
                              ("GL073A_tied", tied, f"{lo * tied.R:.2f}")):
        speeds = [critical_speed(tire, n) for n in meshes]
        lines.append(f"| {name} | " + " | ".join(f"{c.speed_m_s:.2f} (n = {c.order})"
                                                 for c in speeds) + f" | {limit} |")
    orders = np.arange(top - 1, top + 5)
    lumped, tied_modes = analytic_modes(paper, orders), analytic_modes(tied, orders)
    lines += ["", "Critical speed [m/s] and the order that stands still first; computed by "
              "`docs/generate.py` (the same as `tire-fmu critical-speed --tire-file GL073A_tied "
              "--elements N`).", "",
              "| order n | " + " | ".join(str(n) for n in orders) + " |",
              "|---|" + "---|" * orders.size,
              "| lumped: in-phase [Hz] | " + " | ".join(f"{f:.1f}" for f in lumped.in_phase_hz)
              + " |",
              "| tied: in-phase [Hz] | " + " | ".join(f"{f:.1f}" for f in tied_modes.in_phase_hz)
              + " |",
              "| lumped: out-of-phase [Hz] | "
              + " | ".join(f"{f:.1f}" for f in lumped.out_of_phase_hz) + " |",
              "| tied: out-of-phase (the tie) [Hz] | "
              + " | ".join(f"{f:.0f}" for f in tied_modes.out_of_phase_hz) + " |",
              "| tied: in-phase phase speed ωR/n [m/s] | "
              + " | ".join(f"{2 * np.pi * f * tied.R / n:.1f}" if n else "-"
                           for f, n in zip(tied_modes.in_phase_hz, orders)) + " |",
              "", "The continuum frequencies (analytic.py, eq. 12 with the tie); orders up to "
              f"{top} are the paper's exactly."]
    return "\n".join(lines)


def _tied_speeds():
    import numpy as np

    from tire_fmu.core.analytic import analytic_modes
    from tire_fmu.tire_files import read_tire_file

    tied = read_tire_file("GL073A_tied").tire
    top = int(tied.sidewall_max_order)
    top_hz = float(analytic_modes(tied, [top]).in_phase_hz[0])
    share = tied.k_r1 / (tied.k_r1 + tied.k_r2)
    k = tied.k_r1 * tied.k_r2 / (tied.k_r1 + tied.k_r2)
    n = np.arange(top + 1, 200)
    band = np.sqrt((tied.pretension_n + tied.EI * n**2 / tied.R**2 + k * tied.R**2 / n**2)
                   / (tied.rhoA + share**2 * tied.m_s)).min()
    return top, top_hz, 2 * np.pi * top_hz * tied.R / top, float(band)


@value("tied-top-mode")
def _tied_top_mode() -> str:
    top, hz, _, _ = _tied_speeds()
    return f"{hz:.1f} Hz at $n = {top}$"


@value("tied-top-speed")
def _tied_top_speed() -> str:
    return f"{_tied_speeds()[2]:.1f} m/s"


@value("tied-band-speed")
def _tied_band_speed() -> str:
    return f"{_tied_speeds()[3]:.1f} m/s"


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

def _cleat_record() -> tuple[dict, dict]:
    data = record("cleat_convergence")
    return data, data["results"]


def _cleat_provenance(data: dict) -> str:
    return (f"From `{data['command']}` on {data['recorded']} (results of the computation; "
            "the run times vary with the machine).")


@generator("cleat-convergence")
def cleat_convergence_tables() -> str:
    from tire_fmu.core.studies import CLEAT_TABLE_HEADER, cleat_table

    data, results = _cleat_record()
    header = "| " + " | ".join(CLEAT_TABLE_HEADER) + " |"
    rule = "|" + "---|" * len(CLEAT_TABLE_HEADER)
    lines = []
    for case in results["cases"]:
        rows, note = cleat_table(case["study"])
        lines += [f"**{case['name']}** (rim held at {case['study']['load_n'] / 1e3:.3g} kN, "
                  f"step {case['study']['step_s'] * 1e6:g} µs, {case['seconds']:.1f} s)", "",
                  header, rule]
        lines += ["| " + " | ".join(row) + " |" for row in rows]
        notes = [note[0].upper() + note[1:] + "."]
        if case["refused"]:
            notes.append("Not run: " + "; ".join(
                f"N = {r['n_elements']} (critical speed {r['critical_speed_m_s']:.3g} m/s)"
                for r in case["refused"]) + ".")
        if case["near_critical"]:
            notes.append("Within 20 % of the critical speed: " + ", ".join(
                f"N = {r['n_elements']} ({r['critical_speed_m_s']:.3g} m/s)"
                for r in case["near_critical"]) + ".")
        lines += ["", " ".join(notes), ""]
    lines.append(_cleat_provenance(data))
    return "\n".join(lines)


@generator("cleat-spacing")
def cleat_spacing_table() -> str:
    from tire_fmu.core.studies import richardson

    data, results = _cleat_record()
    spacing = results["spacing"]
    cleats = sorted({row["cleat_m"] for row in spacing["rows"]})
    spacings = sorted({row["point_spacing_m"] for row in spacing["rows"]}, reverse=True)
    by = {(row["cleat_m"], row["point_spacing_m"]): row for row in spacing["rows"]}
    lines = ["| point spacing asked (points per node, arc) | "
             + " | ".join(f"{c * 1e3:g} x {c * 1e3:g} mm cleat" for c in cleats)
             + f" | run time ({cleats[-1] * 1e3:g} mm) |",
             "|---|" + "---|" * (len(cleats) + 1)]
    for h in spacings:
        first = by[(cleats[0], h)]
        cells = [f"{by[(c, h)]['peak_rise_kn']:.2f} kN" for c in cleats]
        lines.append(f"| {h * 1e3:g} mm ({first['points_per_node']}, "
                     f"{first['point_arc_m'] * 1e3:.3g} mm) | " + " | ".join(cells)
                     + f" | {by[(cleats[-1], h)]['run_s']:.1f} s |")
    cells = []
    for c in cleats:
        arcs = [by[(c, h)]["point_arc_m"] for h in spacings]
        value, order = richardson(arcs, [by[(c, h)]["peak_rise_kn"] for h in spacings])
        cells.append(f"{value:.2f} kN (order {order:.2f})")
    lines.append("| extrapolated to zero spacing (Richardson, last three) | "
                 + " | ".join(cells) + " | |")
    lines += ["", f"rim_Fz peak rise at N = {spacing['n_elements']}, 10 m/s, rim held. "
              + _cleat_provenance(data)]
    return "\n".join(lines)


@generator("cleat-step")
def cleat_step_table() -> str:
    data, results = _cleat_record()
    step = results["step"]
    lines = ["| step | rim_Fz peak rise | mean rim_Fz under the tire | mean contact_Fz under the "
             "tire | min contact_Fz |", "|---|---|---|---|---|"]
    for row in step["rows"]:
        lines.append(f"| {row['step_s'] * 1e6:g} µs | {row['peak_rise_kn']:.2f} kN | "
                     f"{row['mean_rim_fz_kn']:.2f} kN | {row['mean_contact_fz_kn']:.2f} kN | "
                     f"{row['min_contact_fz_kn']:.1f} kN |")
    lines += ["", f"20 x 20 mm cleat at 10 m/s, N = {step['n_elements']}, contact points at "
              "the default spacing. " + _cleat_provenance(data)]
    return "\n".join(lines)


def _spacing_deficit(cleat_m: float) -> str:
    from tire_fmu.core.studies import CLEAT_POINT_SPACING_M, richardson

    _, results = _cleat_record()
    rows = sorted((r for r in results["spacing"]["rows"] if r["cleat_m"] == cleat_m),
                  key=lambda r: -r["point_spacing_m"])
    value, _ = richardson([r["point_arc_m"] for r in rows], [r["peak_rise_kn"] for r in rows])
    (default,) = [r for r in rows if r["point_spacing_m"] == CLEAT_POINT_SPACING_M]
    return f"{100 * (1 - default['peak_rise_kn'] / value):.1f} %"


@value("cleat-spacing-deficit-10mm")
def _cleat_spacing_deficit_10() -> str:
    return _spacing_deficit(0.01)


@value("cleat-spacing-deficit-20mm")
def _cleat_spacing_deficit_20() -> str:
    return _spacing_deficit(0.02)


@generator("cleat-acceptance")
def cleat_acceptance_table() -> str:
    """Issue 21's criteria on the default tire, case by case, from the record."""
    data, results = _cleat_record()
    lines = ["| case | N = 100 vs converged | N = 400 vs N = 800 | rim_Fz history rms, N = 100 "
             "vs finest | min contact_Fz under the tire |", "|---|---|---|---|---|"]
    for case in results["cases"]:
        if case["refused"] or "GL073A_shear" in case["name"]:
            continue
        rows = {r["n_elements"]: r for r in case["study"]["meshes"]}
        if not {100, 400, 800} <= set(rows):
            continue
        converged = case["study"]["extrapolated_rise_kn"] or rows[max(rows)]["peak_rise_kn"]
        low = min(r["min_contact_fz_kn"] for r in rows.values())
        lines.append(
            f"| {case['name']} | {100 * (rows[100]['peak_rise_kn'] / converged - 1):+.1f} % | "
            f"{100 * (rows[400]['peak_rise_kn'] / rows[800]['peak_rise_kn'] - 1):+.1f} % | "
            f"{100 * rows[100]['history_rms_difference']:.1f} % | {low:.1f} kN |")
    lines += ["", f"Rim held at its static height, tire {results['tire']}. "
              + _cleat_provenance(data)]
    return "\n".join(lines)


@value("cleat-shear-meshes")
def _cleat_shear_meshes() -> str:
    """How close N = 400 and 800, and N = 100 and 800, are on the GL073A_shear cases."""
    _, results = _cleat_record()
    parts = []
    for case in results["cases"]:
        if "GL073A_shear" not in case["name"]:
            continue
        rise = {row["n_elements"]: row["peak_rise_kn"] for row in case["study"]["meshes"]}
        speed = case["study"]["speed_m_s"]
        parts.append(f"at {speed:g} m/s N = 400 is {100 * abs(rise[400] / rise[800] - 1):.1f} % "
                     f"and N = 100 {100 * abs(rise[100] / rise[800] - 1):.1f} % from N = 800")
    return "; ".join(parts)


def _step_rows() -> list[dict]:
    _, results = _cleat_record()
    return sorted(results["step"]["rows"], key=lambda r: -r["step_s"])


@value("cleat-fmu-step-peak-low")
def _cleat_fmu_step_peak_low() -> str:
    rows = _step_rows()
    return f"{100 * (1 - rows[0]['peak_rise_kn'] / rows[-1]['peak_rise_kn']):.1f} %"


@value("cleat-fmu-step-contact-bias")
def _cleat_fmu_step_contact_bias() -> str:
    row = _step_rows()[0]
    return f"{100 * (row['mean_contact_fz_kn'] / row['mean_rim_fz_kn'] - 1):.0f} %"


@value("cleat-finest-step-contact-bias")
def _cleat_finest_step_contact_bias() -> str:
    row = _step_rows()[-1]
    return f"{100 * (row['mean_contact_fz_kn'] / row['mean_rim_fz_kn'] - 1):.1f} %"


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
    from vehicle_demo.transfer import COHERENCE_MIN, GAIN_FLOOR

    data, summary = _demo_summary()
    settings = summary["settings"]
    lines = [f"Agreement of the co-simulation (N = {settings['n_elements']}, h = "
             f"{settings['step_s']:g} s, speed {settings['tf_speed_m_s']:g} m/s) with the car on "
             f"the full unreduced ring model, over the lines where the coherence exceeds "
             f"{COHERENCE_MIN:g} and the reference exceeds {100 * GAIN_FLOOR:g} % of its peak:",
             "",
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
    results = data["results"]
    warm, first = results["warm_init_s"], results["first_init_s"]
    sizes = list(next(iter(next(iter(warm.values())).values())))
    lines = ["| initialisation, instantiate to `fmi2ExitInitializationMode`, s | "
             + " | ".join(f"warm, N = {n}" for n in sizes) + " | "
             + " | ".join(f"first, N = {n}" for n in sizes) + " |",
             "|---" * (1 + 2 * len(sizes)) + "|"]
    for name, by_spacing in warm.items():
        for label, by_n in by_spacing.items():
            firsts = first[name][label]
            lines.append(f"| {name}, {label} | "
                         + " | ".join(f"{by_n[n]:.3f}" for n in sizes) + " | "
                         + " | ".join(f"{firsts[n]['total_s']:.3f}" for n in sizes) + " |")
    lines += ["", "Warm: in a process that has initialised the FMU before (its modules "
              f"imported; median of {results['init_repeats']}). First: each sample in a fresh "
              "process on a fresh extraction of the FMU, as a host's first run meets it "
              f"(median of {results['init_samples']}; for the Python FMU it includes importing "
              "the slave, which bench_fmu_init.py splits out above). The build itself, "
              "`fmi2ExitInitializationMode`, takes "
              + ", ".join(f"{first[name][label][n]['exit_s']:.3f} s ({name[:3]} {label}, "
                          f"N = {n})" for name in first for label in first[name]
                          for n in sizes[-1:])
              + " of the first one at the finest mesh. " + provenance(data)]
    return "\n".join(lines)


#: The rows of the fresh-process table: (label, key in each case of bench_fmu_init's record).
FRESH_INIT_ROWS = (
    ("total", "total_s"),
    ("Python start-up", "python_s"),
    ("`import fmpy.fmi2` (the host's)", "host_import_s"),
    ("`fmi2Instantiate` (imports and constructs the slave)", "instantiate_s"),
    ("setup, enter and exit initialisation (builds the model)", "initialise_s"),
    ("of instantiate and initialisation, under `-X importtime`: pythonfmu's import",
     "pythonfmu_import_s"),
    ("the slave's imports (its module and all it imports)", "slave_imports_s"),
    ("the rest (compute)", "compute_s"),
    ("total for a host that keeps one extraction (bytecode cached)", "cached_total_s"),
)


@generator("fmu-init-fresh")
def fmu_init_fresh() -> str:
    data = record("bench_fmu_init")
    results = data["results"]
    tire, floor = results["cases"]["TireModal"], results["cases"]["minimal pythonfmu"]
    lines = ["| a fresh process, to the end of `fmi2ExitInitializationMode` | TireModal "
             f"(N = {results['n_elements']}) | minimal pythonfmu slave |", "|---|---|---|"]
    for label, key in FRESH_INIT_ROWS:
        lines.append(f"| {label} | {tire[key]:.3f} s | {floor[key]:.3f} s |")
    lines += ["", f"Medians of {results['rounds']} processes each, every one but the last "
              "row's on a fresh extraction of the FMU, as fmpy's `simulate_fmu` gives each run "
              "(only the bytecode each FMU ships beside its sources, no cache of earlier "
              "runs): TireModal takes "
              f"{tire['total_s'] - floor['total_s']:.3f} s more than the minimal slave, whose "
              "time is that of Python, fmpy and pythonfmu starting. " + provenance(data)]
    return "\n".join(lines)


@generator("fmu-init-threads")
def fmu_init_threads() -> str:
    data = record("bench_fmu_init_threads")
    results = data["results"]
    environments = list(results["environments"])
    names = {"default": "BLAS's default threads", "one thread": "one thread",
             "BLAS as the host has it": "the FMU leaving BLAS alone"}
    lines = [f"| `fmi2ExitInitializationMode`, N = {results['n_elements']} | "
             + " | ".join(names.get(e, e) for e in environments) + " | default / one |",
             "|---" * (len(environments) + 2) + "|"]
    left_alone = []
    for label, cases in results["cases"].items():
        for key, what in (("wall_s", "wall"), ("cpu_s", "CPU")):
            ratio = cases["default"][key] / cases["one thread"][key]
            left_alone.append(cases["BLAS as the host has it"][key] / cases["one thread"][key])
            lines.append(f"| {label}, {what} | " + " | ".join(
                f"{cases[e][key]:.3f} s" for e in environments) + f" | {ratio:.2f} |")
    worst = max(results["ratios"].values())
    machine = data["machine"]
    lines += ["", f"Medians of {results['rounds']} fresh processes per cell (CPU: every "
              "thread of the process), on one extraction of each FMU, the three "
              "environments alternating round by round so that load hits them alike. With "
              "BLAS's default threads (a thread per core, "
              "OPENBLAS_NUM_THREADS unset) the FMUs build within "
              f"{worst:.2f} times their one-thread cost (the aim: {results['aim_ratio']:g}); "
              "left to those threads (`TIRE_FMU_BLAS_THREADS=0`), up to "
              f"{max(left_alone):.1f} times. CPU: {machine.get('cpu', 'not recorded')}. "
              + provenance(data)]
    return "\n".join(lines)


@generator("fmu-step-cost")
def fmu_step_cost() -> str:
    data = record("bench_fmu")
    costs, ratios = data["results"]["step_us"], data["results"]["ratios"]
    names = list(next(iter(costs.values())))
    lines = ["| per communication step through fmpy, µs | " + " | ".join(names)
             + " | (a)/(b) | (c)/(d) |", "|---" * (len(names) + 3) + "|"]
    for regime, row in costs.items():
        lines.append(f"| {regime} | " + " | ".join(f"{row[n]:.1f}" for n in names)
                     + f" | {ratios[regime]['python_over_minimal']:.2f} | "
                     f"{ratios[regime]['native_over_trivial']:.2f} |")
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
# -- README: a fit that recovers a known tire ----------------------------------------------

#: The README's example: GL073A's table fitted from a start far from GL073A.
README_FIT = ("fit", "tire_fmu/data/tires/GL073A_modes.csv", "--free", "m_s,k_r1,k_r2,EI",
              "--tire", "m_s=7", "--tire", "k_r1=9e6", "--tire", "k_r2=3e6", "--tire",
              "EI=40")


@generator("readme-fit")
def readme_fit() -> str:
    import contextlib
    import io
    import os

    from tire_fmu.cli import main
    from tire_fmu.core import TireParameters, analytic_modes
    from tire_fmu.measurements import read_modes

    start = os.getcwd()
    buffer = io.StringIO()
    try:
        os.chdir(ROOT)
        with contextlib.redirect_stdout(buffer):
            code = main([*README_FIT, "--json"])
        modes = read_modes(README_FIT[1])
    finally:
        os.chdir(start)
    if code != 0:
        raise StaleRecord(f"tire-fmu {' '.join(README_FIT)} failed")
    fit = json.loads(buffer.getvalue())
    truth = TireParameters()
    starting = TireParameters(**{p["name"]: p["start"] for p in fit["parameters"]})
    paper = [analytic_modes(starting, [m.order]) for m in modes]
    first = max(abs((a.in_phase_hz[0] if m.branch == "in" else a.out_of_phase_hz[0])
                    / m.frequency_hz - 1) for a, m in zip(paper, modes))
    command = " ".join(README_FIT[:4]) + " \\\n    " + " ".join(README_FIT[4:])
    lines = ["```bash", f"tire-fmu {command}", "```", "",
             "| parameter | start | fitted | GL073A |", "|---|---|---|---|"]
    for p in fit["parameters"]:
        lines.append(f"| {p['name']} [{p['unit']}] | {p['start']:.4g} | {p['value']:.6g} | "
                     f"{getattr(truth, p['name']):.6g} |")
    # a residual at rounding level differs in its digits from one BLAS to the next: say so,
    # rather than print a number the next machine does not reproduce
    residual = fit["max_abs_residual_percent"]
    residual_text = (f"{residual:.1g} %" if residual >= 1e-9 else
                     "below 1e-9 % (rounding: the data came from these parameters)")
    lines += ["", f"The start's frequencies are up to {100 * first:.0f} % off the table's; the "
              f"fit ends at a largest residual {residual_text} "
              f"({fit['evaluations']} evaluations, rank {fit['rank']} of "
              f"{len(fit['parameters'])}). Computed by `docs/generate.py` running that command "
              "(`--json`)."]
    return "\n".join(lines)


# -- values in the prose --------------------------------------------------------------------


def _format_time(seconds: float) -> str:
    return f"{seconds * 1e3:.3g} ms" if seconds < 0.1 else f"{seconds:.3g} s"


@functools.cache
def _demo_model():
    """The demo's tire model (N = 100, the car's load, at rest), as the demo builds it."""
    from tire_fmu.core import OperatingPoint, TireParameters, build_model
    from vehicle_demo.quarter_car import QuarterCarParameters

    return build_model(TireParameters(), OperatingPoint(
        n_elements=100, load_n=QuarterCarParameters().static_tire_load_n))


def _settings():
    from vehicle_demo.demo import DemoSettings

    return DemoSettings()


def _resonance(summary: dict, name: str) -> dict:
    for r in summary["resonances"]:
        if r["resonance"] == name:
            return r
    raise StaleRecord(f"the recorded demo has no resonance {name!r}")


@value("demo-f-max")
def _demo_f_max() -> str:
    return f"{_settings().excitation.f_max_hz:g} Hz"


@value("demo-deviation-band")
def _demo_deviation_band() -> str:
    from vehicle_demo.plots import DEVIATION_BAND_DB

    return f"±{DEVIATION_BAND_DB:g} dB"


@value("demo-coherence-drawn")
def _demo_coherence_drawn() -> str:
    from vehicle_demo.plots import COHERENCE_SHOWN_BELOW

    return (f"only if a line's coherence is below {COHERENCE_SHOWN_BELOW:g} (otherwise the "
            "note under the figure gives its lowest value, \"(not drawn)\")")


@value("demo-road-run")
def _demo_road_run() -> str:
    s = _settings()
    return f"a class-{s.road_class} road at {s.road_speed_m_s:g} m/s"


def _braking_settings():
    from vehicle_demo.braking import BrakingSettings

    return BrakingSettings()


@value("braking-runs")
def _braking_runs() -> str:
    from vehicle_demo.braking import BrakingSettings

    s, quick = BrakingSettings(), BrakingSettings.quick()
    return (f"N = {s.n_elements}, {s.duration_s:g} s per run; `--quick`: N = "
            f"{quick.n_elements}, {quick.duration_s:g} s")


@value("braking-setup")
def _braking_setup() -> str:
    s = _braking_settings()
    return (f"Three runs from `--speed` (default {s.speed_m_s:g} m/s), the brake torque "
            f"(`--torque`, default {s.brake_torque_n_m / 1e3:g} kN m) ramped in over "
            f"{s.brake_ramp_s:g} s after {s.brake_at_s:g} s of rolling: on a level road, on an "
            f"ISO 8608 road (`--road-class`, default {s.road_class}, a profile in space so "
            f"that the slowing vehicle reads it at its own speed, level for its first "
            f"{s.road_fade_in_m:g} m) and over a {s.cleat_height_m * 1e3:g} × "
            f"{s.cleat_length_m * 1e3:g} mm cleat. Then the classic cleat test of a drum: the "
            f"axle held, the wheel free, a constant {s.cleat_test_speed_m_s:g} m/s")


@value("demo-cleat")
def _demo_cleat() -> str:
    s = _settings()
    return (f"a {s.cleat_shape} {s.cleat_height_m * 1e3:g} mm × {s.cleat_length_m * 1e3:g} mm "
            f"cleat at {s.cleat_speed_m_s:g} m/s")


@value("demo-events-speed")
def _demo_events_speed() -> str:
    return f"{_settings().events_speed_m_s:g} m/s"


@value("demo-step")
def _demo_step() -> str:
    return f"{_settings().step_s:g} s"


@value("demo-multisine-rms")
def _demo_multisine_rms() -> str:
    return f"{_settings().excitation.rms_velocity_m_s:g} m/s"


@value("demo-lines")
def _demo_lines() -> str:
    from vehicle_demo.demo import DemoSettings

    full, quick = DemoSettings().excitation, DemoSettings.quick().excitation
    return (f"from {full.f_min_hz:g} to {full.f_max_hz:g} Hz (T = {full.period_s:g} s, "
            f"{1 / full.period_s:g} Hz lines; quick mode {quick.period_s:g} s)")


@value("demo-averages")
def _demo_averages() -> str:
    from vehicle_demo.demo import DemoSettings

    return (f"{DemoSettings().excitation.average_periods} averages; quick "
            f"{DemoSettings.quick().excitation.average_periods}")


@value("demo-fade-in")
def _demo_fade_in() -> str:
    return f"{_settings().road_fade_in_s:g} s"


@value("sweep-multisine")
def _sweep_multisine() -> str:
    from vehicle_demo.sweep import SweepSettings

    ex = SweepSettings().excitation
    seconds = ex.period_s * (ex.settle_periods + ex.average_periods)
    return f"a {seconds:g} s multisine ({1 / ex.period_s:g} Hz lines)"


@value("tire-mode-min")
def _tire_mode_min() -> str:
    from vehicle_demo.transfer import TIRE_MODE_MIN_HZ

    return f"{TIRE_MODE_MIN_HZ:g} Hz"


@value("identification-rule")
def _identification_rule() -> str:
    from vehicle_demo import transfer as t

    low, high = t.IDENTIFICATION_BAND_HZ
    hop_low, hop_high = t.WHEEL_HOP_BAND_HZ
    return (f"over {low:g}–{high:g} Hz; body bounce is the pole below "
            f"{t.BODY_BOUNCE_MAX_HZ:g} Hz with ζ < {t.BODY_BOUNCE_MAX_ZETA:g}, wheel hop the "
            f"pole of {hop_low:g}–{hop_high:g} Hz with ζ < {t.WHEEL_HOP_MAX_ZETA:g}")


@value("iso-band")
def _iso_band() -> str:
    from vehicle_demo.road import ISO_N_MAX_CYCLES_PER_M, ISO_N_MIN_CYCLES_PER_M

    return f"{ISO_N_MIN_CYCLES_PER_M:g}–{ISO_N_MAX_CYCLES_PER_M:g} cycles/m"


@value("iso-slope")
def _iso_slope() -> str:
    from vehicle_demo.road import N0_CYCLES_PER_M, WAVINESS

    return f"n0 = {N0_CYCLES_PER_M:g} cycles/m and w = {WAVINESS:g}"


@value("iso-class-a")
def _iso_class_a() -> str:
    from vehicle_demo.road import ISO_8608_GD_N0_M3

    ratio = ISO_8608_GD_N0_M3["B"] / ISO_8608_GD_N0_M3["A"]
    return f"{ISO_8608_GD_N0_M3['A']:g} m³ for A, ×{ratio:g} per class"


@value("quarter-car")
def _quarter_car() -> str:
    from vehicle_demo.quarter_car import QuarterCarParameters

    car = QuarterCarParameters()
    return (f"body {car.body_mass_kg:g} kg, wheel + axle {car.wheel_mass_kg:g} kg (without the "
            f"tire), suspension {car.suspension_stiffness_n_per_m / 1e3:g} kN/m and "
            f"{car.suspension_damping_n_s_per_m / 1e3:g} kN·s/m")


@value("quarter-car-load")
def _quarter_car_load() -> str:
    from vehicle_demo.quarter_car import QuarterCarParameters

    return f"{QuarterCarParameters().static_tire_load_n:.0f} N"


@value("sidewall-band")
def _sidewall_band() -> str:
    from tire_fmu.core import TireParameters

    return f"{TireParameters().sidewall_band_hz:.0f} Hz"


@value("node-arc-n100")
def _node_arc() -> str:
    return f"{_demo_model().grid.node_arc_m * 100:.3g} cm at N = 100"


@value("rim-feedthrough")
def _rim_feedthrough() -> str:
    from tire_fmu.core.io_model import build_io_model

    io = build_io_model(_demo_model())
    return f"{-io.d_disp[0, 0] / 1e6:.3g} MN/m and {-io.e[0, 0] / 1e3:.3g} kN·s/m"


@value("contact-feedthrough")
def _contact_feedthrough() -> str:
    from tire_fmu.core.io_model import build_io_model

    io = build_io_model(_demo_model())
    return (f"{io.d_disp[2, 1:].sum():.3g} N/m on height and {io.e[2, 1:].sum():.3g} N·s/m on "
            "velocity, the pushing nodes' springs and dampers at the default load, N = 100")


@value("patch-filter")
def _patch_filter() -> str:
    """First null of the road filter of the footprint's points (weighted by their springs) at
    1 m/s; it scales with V, so L = V / f_null."""
    import numpy as np

    from tire_fmu.core.contact import road_windows

    model = _demo_model()
    patch = model.patch
    windows = road_windows(patch.zone, patch.deflection_m, 1.0)
    weights = patch.point_stiffness_n_per_m  # contact force per unit road under each point
    freqs = np.linspace(0.01, 50.0, 50001)
    gain = np.abs(weights @ windows.frequency_response(2 * np.pi * freqs)) / weights.sum()
    first = np.flatnonzero((gain[1:-1] < gain[:-2]) & (gain[1:-1] <= gain[2:]))[0] + 1
    length = 1.0 / freqs[first]
    data, summary = _demo_summary()
    hop = _resonance(summary, "wheel hop")["f_reference_hz"]
    return (f"L = {length * 100:.2g} cm at the default load, N = 100: the null falls to wheel "
            f"hop, {hop:.3g} Hz, at {hop * length:.2g} m/s")


@value("demo-spring-wheel-hop")
def _demo_spring_wheel_hop() -> str:
    _, summary = _demo_summary()
    r = _resonance(summary, "wheel hop")
    excess = r["f_analytic_massless_hz"] / r["f_reference_hz"] - 1
    return f"{100 * excess:.2g} % above the reference's"


@value("demo-first-tire-mode")
def _demo_first_tire_mode() -> str:
    _, summary = _demo_summary()
    return f"{_resonance(summary, 'tire mode 1')['f_reference_hz']:.3g} Hz in the rim load"


@value("demo-body-fall")
def _demo_body_fall() -> str:
    _, summary = _demo_summary()
    fall = _row(summary, "road -> body acceleration (full model): fall from its peak")
    return f"{fall:.0f} dB from its peak to {summary['settings']['excitation']['f_max_hz']:g} Hz"


@value("demo-damping")
def _demo_damping() -> str:
    _, summary = _demo_summary()
    damping = _row(summary, "tire equivalent damping (low-frequency")
    change = _row(summary, "tire equivalent damping: largest change")
    return (f"{damping:.1f} N·s/m at N = {summary['settings']['n_elements']}; the model's "
            f"damping is stiffness-proportional, so Im K_dyn/ω stays within {change:.2g} % of "
            "it up to wheel hop")


@value("demo-rim-side-mass")
def _demo_rim_side_mass() -> str:
    import math

    from tire_fmu.core import TireParameters

    _, summary = _demo_summary()
    tire = TireParameters()
    total = (tire.rhoA + tire.m_s) * 2 * math.pi * tire.R
    return (f"m = {_row(summary, 'tire mass moving with the rim'):.2f} kg: part of its "
            f"{total:.1f} kg")


@value("demo-wheel-hop-shift")
def _demo_wheel_hop_shift() -> str:
    _, summary = _demo_summary()
    r = _resonance(summary, "wheel hop")
    return (f"{r['f_analytic_massless_hz']:.2f} Hz (massless tire) to "
            f"{r['f_analytic_hz']:.2f} Hz")


@value("demo-zetas")
def _demo_zetas() -> str:
    _, summary = _demo_summary()
    body, wheel = (_resonance(summary, n)["zeta_reference"] for n in ("body bounce",
                                                                       "wheel hop"))
    return f"ζ = {body:.3f} and {wheel:.3f} on the reference"


@value("demo-radius")
def _demo_radius() -> str:
    import math

    _, summary = _demo_summary()
    h = summary["settings"]["step_s"]
    radius = _row(summary, "coupling: spectral radius at h (Gauss-Seidel)")
    body = _resonance(summary, "body bounce")
    decay = math.exp(-body["zeta_reference"] * 2 * math.pi * body["f_reference_hz"] * h)
    return (f"At h = {h:g} s it equals e^{{−ζωh}} of body bounce to "
            f"{abs(radius - decay):.0e}: the coupling adds no growth")


@value("demo-stable-steps")
def _demo_stable_steps() -> str:
    _, summary = _demo_summary()
    gs = _row(summary, "coupling: largest stable step (Gauss-Seidel)")
    jacobi = _row(summary, "coupling: largest stable step (Jacobi)")
    return f"**{_format_time(gs)}** for Gauss-Seidel and **{_format_time(jacobi)}** for Jacobi"


# -- the coupling's accuracy (benchmarks/bench_coupling.py) ---------------------------------

_RESPONSES = ("body_acc", "wheel_acc", "rim_load", "contact_force")


def _coupling_cases(**match) -> list[dict]:
    data = record("bench_coupling")
    cases = [c for c in data["results"]["cases"]
             if all(c[k] == v for k, v in match.items())]
    if not cases:
        raise StaleRecord(f"docs/measured/bench_coupling.json has no case {match}: run "
                          f"{data['command']}")
    return cases


def _worst(case: dict, name: str) -> tuple[float, float]:
    a = case["agreements"][name]
    return a["max_deviation_db"], a["worst_frequency_hz"]


@generator("coupling-accuracy")
def coupling_accuracy() -> str:
    from vehicle_demo.plots import DEVIATION_BAND_DB
    from vehicle_demo.quarter_car import RIDE_LABELS
    from vehicle_demo.transfer import GAIN_FLOOR

    data = record("bench_coupling")
    rest = _coupling_cases(speed_m_s=0.0, read_after_inputs=True)
    n, lines = rest[0]["n_elements"], rest[0]["line_spacing_hz"]
    steps = sorted({c["step_s"] for c in rest})
    names = [RIDE_LABELS[r].replace("road → ", "") for r in _RESPONSES]
    out = [f"Largest deviation from the full model (N = {n}, {lines:g} Hz lines, speed 0), dB:",
           "", "| h | scheme | " + " | ".join(names) + " |", "|---|---|" + "---|" * len(names)]
    for h in steps:
        for case in (c for c in rest if c["step_s"] == h):
            out.append(f"| {h:g} s | {case['scheme']} | "
                       + " | ".join(f"{_worst(case, r)[0]:.2g}" for r in _RESPONSES) + " |")
    gauss = [c for c in rest if c["scheme"] == "gauss-seidel"]
    within = [c["step_s"] for c in gauss
              if all(_worst(c, r)[0] <= DEVIATION_BAND_DB for r in _RESPONSES)]
    default = next(c for c in gauss if c["step_s"] == _settings().step_s)
    ride = [r for r in _RESPONSES if r != "body_acc"]
    body_db, body_hz = _worst(default, "body_acc")
    body_top = default["agreements"]["body_acc"]["f_max_compared_hz"]
    where = ", where it has fallen to that floor" if body_hz >= 0.9 * body_top else ""
    out += ["", f"So h = {default['step_s']:g} s keeps wheel acceleration, rim load and "
            f"contact force within {max(_worst(default, r)[0] for r in ride):.2g} dB to "
            f"{rest[0]['agreements']['wheel_acc']['f_max_compared_hz']:g} Hz, and "
            f"{max(within):g} s is the largest step of the table that keeps every ride "
            f"transfer function within the {DEVIATION_BAND_DB:g} dB band. Body acceleration "
            f"is compared only where it exceeds {100 * GAIN_FLOOR:g} % of its peak (up to "
            f"{body_top:g} Hz); its "
            f"largest deviation is {body_db:.2g} dB at {body_hz:g} Hz{where}.", "",
            f"Measured with `{data['command']}` on {data['recorded']} (results of the "
            "computation, the same on any machine)."]
    return "\n".join(out)


@generator("coupling-read-order")
def coupling_read_order() -> str:
    data = record("bench_coupling")
    out = ["| case | h | contact force, tire read after the new inputs | read before them |",
           "|---|---|---|---|"]
    for speed in (0.0, max(c["speed_m_s"] for c in data["results"]["cases"])):
        (before,) = _coupling_cases(speed_m_s=speed, read_after_inputs=False)
        h = before["step_s"]
        (after,) = _coupling_cases(speed_m_s=speed, read_after_inputs=True, step_s=h,
                                   scheme=before["scheme"])
        cells = [f"{db:.2g} dB (at {hz:g} Hz)" for db, hz in
                 (_worst(after, "contact_force"), _worst(before, "contact_force"))]
        out.append(f"| {speed:g} m/s, N = {before['n_elements']} | {h:g} s | {cells[0]} | "
                   f"{cells[1]} |")
    out += ["", f"Largest deviation of road → contact force from the full model. Measured with "
            f"`{data['command']}` on {data['recorded']}."]
    return "\n".join(out)


@value("coupling-at-speed")
def _coupling_at_speed() -> str:
    cases = sorted(_coupling_cases(read_after_inputs=True, speed_m_s=20.0),
                   key=lambda c: -c["step_s"])
    contact = " and ".join(
        f"{_worst(c, 'contact_force')[0]:.2g} dB near {_worst(c, 'contact_force')[1]:g} Hz at "
        f"h = {c['step_s']:g} s" for c in cases)
    others = max(_worst(c, r)[0] for c in cases for r in _RESPONSES if r != "contact_force")
    return (f"at {cases[0]['speed_m_s']:g} m/s, N = {cases[0]['n_elements']}, road → contact "
            f"force deviates from the full model by up to {contact}; body acceleration, wheel "
            f"acceleration and rim load stay within {others:.2g} dB at either step")


# -- theory ----------------------------------------------------------------------------------

@value("io-windows-example")
def _io_windows_example() -> str:
    import warnings

    from tire_fmu.core import OperatingPoint, TireParameters, build_model
    from tire_fmu.core.io_model import build_io_model

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # 96 % of the critical speed: the paper's Fig. 18
        io = build_io_model(build_model(TireParameters(), OperatingPoint(
            patch_length_m=0.204, speed_m_s=40.84)))
    w = io.road_windows
    spans = ", ".join(f"{a * 1e3:.2f}–{b * 1e3:.2f}" for a, b in zip(w.early_s, w.late_s))
    return (f"{io.n_inputs} with the 20.4 cm patch at 40.84 m/s: windows {spans} ms after "
            "the front")


@value("rim-fx-rolling")
def _rim_fx_rolling() -> str:
    from tire_fmu.core import OperatingPoint, TireParameters, build_model

    model = build_model(TireParameters(), OperatingPoint(speed_m_s=20.0))
    statics = model.patch.static_outputs()
    return (f"{statics['rim_Fx']:.1f} N at 20 m/s and the default load, "
            f"{100 * -statics['rim_Fx'] / statics['rim_Fz']:.2f} % of it")


# -- docs/fmu.md: what the Python FMU logs, from a run of its slave ---------------------------

MESSAGE_ELEMENTS = 40  # the mesh of the runs: every message is the same on any mesh but N


@functools.cache
def _fmu_messages() -> dict[str, list[str]]:
    """What the Python FMU's slave logs in each case of the failure table, as a host prints it
    ("[status] text"), driven in plain Python the way pythonfmu's wrapper drives it."""
    import warnings

    from tire_fmu.core.contact_dynamics import INPUT_NAMES
    from tire_fmu.fmu.slave import TireModal
    from tire_fmu.fmu.spec import CONSTANTS

    def new():
        return TireModal(instance_name="tire", resources=".", visible=False)

    def said(slave, status_at_least=1):
        out = [f"[{int(m.status)}] " + m.msg.replace("%%", "%").replace("##", "#")
               for m in slave.log_queue if int(m.status) >= status_at_least]
        slave.log_queue.clear()
        return out

    def vr(slave, name):
        return slave._index[name]

    def initialised(**parameters):
        slave = new()
        slave.setup_experiment(0.0)
        slave.enter_initialization_mode()
        parameters.setdefault("n_elements", MESSAGE_ELEMENTS)
        for name, value in parameters.items():
            setter = {int: slave.set_integer, bool: slave.set_boolean}.get(type(value),
                                                                            slave.set_real)
            setter([vr(slave, name)], [value])
        slave.exit_initialization_mode()
        return slave

    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for case, parameters in (("parameters", {"R": -1.0}), ("load", {"load": 1e7}),
                                 ("speed", {"speed": 500.0}),
                                 ("m_s", {"m_s": 1e-6, "k_r2": 1e11, "beta": 0.1}),
                                 ("k_r2", {"k_r2": 0.01}), ("speed-warning", {"speed": 90.0})):
            out[case] = said(initialised(**parameters))
        slave = new()
        slave.setup_experiment(float("nan"))
        out["setup"] = said(slave)
        slave.setup_experiment(1e16)
        out["setup-clock"] = said(slave)
        slave = initialised()
        said(slave)
        slave.exit_initialization_mode()
        out["order"] = said(slave)
        slave.terminate()
        slave.do_step(0.0, 1e-3)
        out["order"] += said(slave)
        slave = initialised(speed=CONSTANTS["MIN_ROLLING_SPEED_M_S"])
        said(slave)
        slave.do_step(0.0, 1e-4)
        out["delay"] = said(slave)
        slave = initialised()
        said(slave)
        slave.set_real([vr(slave, n) for n in INPUT_NAMES], [float("nan"), 0.0, 0.0, 0.0])
        out["input"] = said(slave)
        state = slave._get_fmu_state()
        slave._set_fmu_state(state[:-1] + bytes([state[-1] ^ 1]))
        out["state-damaged"] = said(slave)
        slave._set_fmu_state(_forged_mode(state, len(slave._table)))
        out["state-meaning"] = said(slave)
        fresh = new()
        fresh.get_real([vr(fresh, "rim_Fz")])
        out["instantiated"] = said(fresh)
        slave = initialised()
        said(slave)
        slave.do_step(0.0, 1e-3)
        slave.do_step(1e-3, 0.0)
        out["step-size"] = said(slave)
        slave.do_step(0.5, 1e-3)
        out["time"] = said(slave)
        slave.set_real([vr(slave, "load")], [1.0])
        out["fixed"] = said(slave)
        slave = new()
        slave.setup_experiment(1e12)
        slave.enter_initialization_mode()
        slave.set_integer([vr(slave, "n_elements")], [MESSAGE_ELEMENTS])
        slave.exit_initialization_mode()
        said(slave)
        slave.do_step(1e12, 1e-4)
        out["clock"] = said(slave)
        slave = initialised(f_max=150.0)
        said(slave)
        slave.do_step(0.0, 1e-6)
        out["short-step"] = said(slave)
        slave.get_real([999])
        out["reference"] = said(slave)
    return out


def _forged_mode(state: bytes, n_values: int) -> bytes:
    """``state`` with its first mode set to 1e300 and the checksum recomputed."""
    from tire_fmu.core import kernel_numpy
    from tire_fmu.fmu.spec import STATE_MODEL_FLAGS, state_pack, state_unpack

    f = state_unpack(state, n_values)
    flags, kernel = f["model"][:4 * STATE_MODEL_FLAGS], f["model"][4 * STATE_MODEL_FLAGS:]
    fields = kernel_numpy.state_fields(kernel)
    fields["q"][0] = 1e300
    return state_pack(f["phase"], f["guid"], f["time"], f["start_time"], f["stale"],
                      f["values"], flags + kernel_numpy.state_data(fields))


@generator("fmi-state-machine")
def fmi_state_machine() -> str:
    """The FMI 2.0 co-simulation state machine both FMUs follow (spec.CALLS)."""
    from tire_fmu.fmu.spec import CALLS, PHASES, PYTHONFMU_ANSWERS

    shared = [c for c in CALLS if c not in PYTHONFMU_ANSWERS or "FMUstate" in c
              or c == "fmi2Reset"]
    own = [c for c in CALLS if c not in shared]
    lines = ["| call | " + " | ".join(PHASES) + " |", "|---" * (len(PHASES) + 1) + "|"]
    for call in shared + own:
        marks = " | ".join("yes" if phase in CALLS[call] else "refused" for phase in PHASES)
        lines.append(f"| `{call}`{' †' if call in own else ''} | {marks} |")
    lines += ["", "† answered in the Python FMU by pythonfmu's wrapper (and the Linux guard in "
              "front of it) without asking the slave; in the native FMU by this table. "
              "fmi2CancelStep is FMI's in stepInProgress only, which never occurs (a step "
              "always completes): while running it is refused for that reason.", "",
              "A refused call: `" + _spec_message("REFUSED") + "`, with `" +
              _spec_message("PHASE") + "` and the phase's text: " +
              "; ".join(f"{name}: \"{text}\"" for name, text in PHASES.items()) +
              " (in the error state, why the FMU is there, e.g. `" +
              _spec_message("PARAMETERS_REFUSED") + "`, or `" + _spec_message("FAILED") +
              "`)."]
    return "\n".join(lines)


@generator("fmu-state-layout")
def fmu_state_layout() -> str:
    """The one FMU-state byte format (spec.STATE_LAYOUT)."""
    from tire_fmu.fmu.spec import STATE_LAYOUT

    lines = ["| field | bytes | what |", "|---|---|---|"]
    for name, form, meaning in STATE_LAYOUT:
        if form == "<V d":
            size = "8 each"
        elif form.startswith("<") or form[0].isdigit():
            import struct

            size = str(struct.calcsize(form))
        else:
            size = f"`{form}`"
        lines.append(f"| `{name}` | {size} | {meaning} |")
    return "\n".join(lines)


def _spec_message(key: str) -> str:
    from tire_fmu.fmu.spec import MESSAGES

    return MESSAGES[key]


def _message(case: str, index: int = 0, strip: str = "", clip: str = "") -> str:
    """One logged message as inline code; ``strip`` drops a prefix, ``clip`` cuts the text
    after that phrase (the rest is "...)")."""
    messages = _fmu_messages()[case]
    if len(messages) <= index:
        raise StaleRecord(f"the slave logged {messages} in case {case!r}")
    text = messages[index]
    if strip and text.startswith(strip):
        text = text[len(strip):]
    if clip:
        text = text[:text.index(clip) + len(clip)] + "...)"
    return f"`{text}`"


@value("fmu-msg-setup-clock")
def _msg_setup_clock() -> str:
    return _message("setup-clock")


@value("fmu-msg-short-step")
def _msg_short_step() -> str:
    return _message("short-step")


@value("fmu-msg-clock")
def _msg_clock() -> str:
    return _message("clock")


@value("deflection-at-rest")
def _deflection_at_rest() -> str:
    """The static deflection and tread compression at the defaults, as the FMU starts."""
    from tire_fmu.core.contact_dynamics import build_contact_model

    statics = build_contact_model().static_outputs
    return (f"{statics['deflection'] * 1e3:.2f} mm at the defaults at rest, against "
            f"{statics['tread_deflection'] * 1e3:.2f} mm of tread compression")


@value("fmu-msg-parameters")
def _msg_parameters() -> str:
    first = _message("parameters")
    echo = re.sub(r"\(1 problem\(s\): .*\); reset", "(1 problem(s): ...); reset",
                  _message("parameters", 1))
    return f"{first}, then {echo}"


@value("fmu-msg-load-speed")
def _msg_load_speed() -> str:
    strip = "[3] parameter problem 1/1: "
    return f"{_message('load', strip=strip)}, {_message('speed', strip=strip)}"


@value("fmu-msg-precision")
def _msg_precision() -> str:
    strip = "[3] parameter problem 1/1: "
    return (f"{_message('m_s', strip=strip, clip='may span at most 1e+10 (')}; "
            f"{_message('k_r2', strip=strip, clip='weaker than the stiffest term, ')}")


for _case in ("speed-warning", "setup", "delay", "input", "step-size", "time", "fixed",
              "reference", "state-damaged", "state-meaning", "instantiated"):
    value(f"fmu-msg-{_case}")(functools.partial(_message, _case))


@value("fmu-msg-order")
def _msg_order() -> str:
    return f"{_message('order')}; {_message('order', 1)}"


@value("mesh-size-cost")
def _mesh_size_cost() -> str:
    data = record("bench_mesh_size")
    results = data["results"]
    largest = [c for c in results["cases"] if c["n_elements"] == results["max_elements"]]
    if not largest:
        raise StaleRecord(f"{data['command']} did not measure N = {results['max_elements']}")
    parts = [f"{_format_time(c['fmu_init_s'])} at "
             + ("rest" if c["speed_m_s"] == 0 else f"{c['speed_m_s']:g} m/s") for c in largest]
    peak = max(c["fmu_init_peak_mb"] for c in largest)
    machine = data["machine"]
    return (f"at that mesh the FMU's initialisation took {' and '.join(parts)}, with a peak "
            f"of {peak / 1024:.2g} GB, measured with `{data['command']}` on {data['recorded']} "
            f"({machine['cores']} cores shared with other work, load average "
            f"{machine['load_average_start']:g}/{machine['load_average_end']:g} at start/end)")


@value("road-reach")
def _road_reach() -> str:
    from tire_fmu.core import OperatingPoint, TireParameters, build_model

    model = build_model(TireParameters(), OperatingPoint(n_elements=100, speed_m_s=20.0))
    return f"{model.patch.road.horizon_s * 1e3:.3g} ms at N = 100 and 20 m/s"


# -- rewriting ----------------------------------------------------------------------------------

# Each generator's text depends on the code and the recorded results only, so one process
# makes it once (the checks render every file more than once)
@functools.cache
def _section_text(name: str) -> str:
    return GENERATORS[name]().rstrip()


@functools.cache
def _value_text(name: str) -> str:
    return value_text(name)


def render(text: str) -> tuple[str, list[str]]:
    """The text with every generated section and value regenerated, and the names it holds."""
    names = []

    def replace(match):
        name = match.group("name")
        if name not in GENERATORS:
            raise KeyError(f"unknown generated section {name!r}; known: {sorted(GENERATORS)}")
        names.append(name)
        return f"{match.group(1)}{_section_text(name)}\n{match.group(4)}"

    def replace_value(match):
        name = match.group("name")
        names.append(name)
        return f"{match.group(1)}{_value_text(name)}{match.group(4)}"

    text = SECTION.sub(replace, text)
    return VALUE.sub(replace_value, text), names


def stale_sections(files=FILES) -> list[str]:
    """'file: name' for every section or value whose text is not what its generator gives."""
    stale = []
    for name in files:
        path = ROOT / name
        current = path.read_text()
        fresh, _ = render(current)
        for pattern in (SECTION, VALUE):
            for old, new in zip(pattern.finditer(current), pattern.finditer(fresh)):
                if old.group("body") != new.group("body"):
                    stale.append(f"{name}: {old.group('name')}")
    return stale


# -- road files (docs/roads.md) -----------------------------------------------------------------

def _road_command(argv: list[str]) -> tuple[dict, str]:
    """``tire-fmu ARGV --json`` run in a scratch folder: its JSON, and the command as shown."""
    import contextlib
    import io
    import os
    import tempfile

    from tire_fmu.cli import main

    start = os.getcwd()
    buffer = io.StringIO()
    with tempfile.TemporaryDirectory() as folder:
        try:
            os.chdir(folder)
            with contextlib.redirect_stdout(buffer), contextlib.redirect_stderr(io.StringIO()):
                code = main([*argv, "--json"])
        finally:
            os.chdir(start)
    if code != 0:
        raise StaleRecord(f"tire-fmu {' '.join(argv)} failed")
    return json.loads(buffer.getvalue()), "tire-fmu " + " ".join(argv)


def _road_summary(data: dict) -> str:
    first, last = data["extent_m"]
    return (f"{data['points']} points every {data['spacing_m']:g} m from {first:g} to "
            f"{last:g} m, heights {1e3 * data['height_min_m']:.4g} to "
            f"{1e3 * data['height_max_m']:.4g} mm, written as {data['format']}")


@generator("road-examples")
def road_examples() -> str:
    runs = [["road", "cleat", "--height", "0.02", "--length", "0.02", "--out", "cleat.crg"],
            ["road", "triangle", "--height", "0.05", "--half-angle", "60", "--out",
             "triangle.crg"],
            ["road", "step", "--height", "0.05", "--out", "step.csv"],
            ["road", "pothole", "--depth", "0.05", "--length", "0.3", "--out", "pothole.crg"],
            ["road", "iso8608", "--class", "C", "--length", "200", "--seed", "1", "--out",
             "road_C.crg"]]
    lines = ["| command | the file |", "|---|---|"]
    for argv in runs:
        data, command = _road_command(argv)
        extra = (f"; rms height {1e3 * data['rms_height_m']:.3g} mm, Gd(n0) "
                 f"{data['gd_n0_m3']:g} m³" if "rms_height_m" in data else "")
        lines.append(f"| `{command}` | {_road_summary(data)}{extra} |")
    lines += ["", "Computed by `docs/generate.py` running these commands (`--json`)."]
    return "\n".join(lines)


@generator("road-agreement")
def road_agreement() -> str:
    """The readers against the ASAM C API (pycrg) on a file of each format."""
    import tempfile

    import numpy as np
    import pycrg

    from tire_fmu.core.iso8608 import iso8608_profile
    from tire_fmu.road_files import SUPPORTED_CRG_FORMATS, read_road_file, write_crg

    pycrg.set_message_level(0)
    profile = iso8608_profile("C", 4000, 0.005, seed=2, fade_in_m=1.0)
    grid = np.column_stack([profile.heights_m, 0.5 * profile.heights_m, -profile.heights_m])
    rng = np.random.default_rng(0)
    lines = ["| format | largest difference from the C API (m) | the C API's single-precision "
             "step at the largest height (m) |", "|---|---|---|"]
    with tempfile.TemporaryDirectory() as folder:
        for data_format in SUPPORTED_CRG_FORMATS:
            path = Path(folder) / f"road_{data_format}.crg"
            write_crg(path, grid, 0.005, [-0.5, 0.0, 0.5], data_format)
            u = np.r_[rng.uniform(-1.0, 21.0, 400)]
            worst = 0.0
            for v in (0.0, 0.2, -0.37):
                road = read_road_file(path, v).road
                with pycrg.DataSet.open(str(path)) as dataset:
                    point = dataset.create_contact_point()
                    theirs = np.array([point.uv_to_z(float(x), v) for x in u])
                worst = max(worst, float(np.max(np.abs(road.profile(u)[0] - theirs))))
            step = float(np.spacing(np.float32(np.max(np.abs(grid)))))
            lines.append(f"| {data_format} | {worst:.2g} | {step:.2g} |")
    lines += ["", "An ISO 8608 class C road (20 m) written in each format, read at v = 0, 0.2 "
              "and -0.37 m and compared at 400 random u (some beyond its ends) with pycrg's "
              "`uv_to_z`; computed by `docs/generate.py`."]
    return "\n".join(lines)


@value("road-max-cross-sections")
def road_max_cross_sections() -> str:
    from tire_fmu.road_files import MAX_CROSS_SECTIONS

    return f"{MAX_CROSS_SECTIONS:,}".replace(",", " ")


@value("road-max-bytes")
def road_max_bytes() -> str:
    from tire_fmu.road_files import MAX_ROAD_FILE_BYTES

    return f"{MAX_ROAD_FILE_BYTES / 2**30:g} GiB"


# -- numbers typed into prose -------------------------------------------------------------------

#: Files whose prose may not hold a measured-looking number that is not generated.
PROSE_CHECKED = ("docs/vehicle_demo.md", "docs/fmu.md", "docs/roads.md")
#: Numbers these files state as definitions (of a standard, a method, a test), not as
#: results: exact phrases, each with where it is defined.
DEFINITIONS: dict[str, tuple[str, ...]] = {
    "docs/vehicle_demo.md": (
        "95 %",  # the confidence of Welch's band in road_psd.png (demo.py: chi2 0.025/0.975)
    ),
    "docs/roads.md": (
        "1.5 to 3.0 mm",  # SAE J2705's crown radius
        "45, 60, 75, 80 or 85°",  # SAE J2705's apex half-angles
        "0.1 cycles/m",  # ISO 8608's n0
        "16e-6 m³",  # ISO 8608's class A
        "0.011-2.83 cycles/m",  # ISO 8608's band
        "1e-8 m",  # the C API's border tolerance in v
    ),
    "docs/fmu.md": (
        "FMI 2.0",  # the standard
        "core to 1e-12",  # the tolerance of tests/test_tire_files.py's comparison
    ),
}
_NUMBER = r"[-−±]?\d+(?:[ ,]\d{3})*(?:\.\d+)?(?:e[-+]?\d+)?"
_UNIT = (r"(?:[kMG]?Hz|[mµu]?s|min|kg|[kMG]?N(?:·s|\*m)?(?:/m(?:\^2|²)?)?|dB|%|[mk]?m/s²?|"
         r"km/h|[mck]?m³?|[kMG]B|bar|[kM]?Pa|rad/s|cycles/m|variables)")
#: A number with a unit, a number after "≈" or "~", or a bare number that looks computed:
#: three or more digits, a decimal point or an exponent (not a mesh "N = 100" or an order
#: "n = 4", not ISO 8608, not a version such as 0.7.0).
MEASURED_LOOKING = re.compile(
    rf"(?<![\w.]){_NUMBER}(?:\s?[-–]\s?{_NUMBER})?\s?{_UNIT}(?![\w/²³^])"
    rf"|[≈~]\s?{_NUMBER}"
    r"|(?<![\w.,-])(?<!N = )(?<!n = )(?<!ISO )(?<!§)(?:\d+\.\d+(?:e[-+]?\d+)?|\d+e[-+]?\d+|\d{3,})"
    r"(?!\w|\.\d)")
_NOT_PROSE = (
    re.compile(r"^```.*?^```", re.S | re.M),  # code blocks
    SECTION,
    VALUE,
    re.compile(r"<!--.*?-->", re.S),  # comments
    re.compile(r"`[^`\n]*`"),  # inline code: names, commands, quoted messages
)


def typed_numbers(name: str, text: str | None = None) -> list[str]:
    """Measured-looking numbers typed into the prose of file ``name``: a number followed by a
    unit (Hz, s, N, kg, dB, %, m/s, ...) or after "≈"/"~", outside code, generated sections
    and values, that is not one of the file's :data:`DEFINITIONS`. Each is 'file:line: text'.
    """
    text = (ROOT / name).read_text() if text is None else text
    for pattern in _NOT_PROSE:  # blank out, keeping the line breaks for the line numbers
        text = pattern.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)
    allowed = DEFINITIONS.get(name, ())
    found = []
    for number, line in enumerate(text.splitlines(), 1):
        defined = [(m.start(), m.end()) for phrase in allowed
                   for m in re.finditer(re.escape(phrase), line)]
        for match in MEASURED_LOOKING.finditer(line):
            if not any(a <= match.start() and match.end() <= b for a, b in defined):
                found.append(f"{name}:{number}: {match.group(0).strip()}")
    return found


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
            typed = [x for name in PROSE_CHECKED for x in typed_numbers(name)]
            for item in typed:
                print(f"typed number: {item} (generate it: see docs/generate.py)",
                      file=sys.stderr)
            return 1 if stale or typed else 0
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
