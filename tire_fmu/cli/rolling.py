"""Rolling-tire commands: dispersion (Fig. 18), speed-sweep (Fig. 19) and critical-speed."""

from __future__ import annotations

import argparse

import numpy as np

from ..core import critical_speed
from ..core.standing_waves import MAX_SCANNED_SPEED_M_S
from ..core.studies import dispersion_at_speed, paper_speed_m_s, speed_sweep
from .commands import command_help
from .common import (
    Output,
    add_mesh_option,
    add_output_options,
    add_tire_options,
    checked_tire,
    elements_problem,
    frequency_problem,
    patch_length_problem,
    plot_with,
    positive_problem,
    progress_bar,
    range_problem,
    table,
    write_plot,
)

#: Meshes listed by ``critical-speed`` to show that the lumped sidewall's speed falls with N.
CRITICAL_SPEED_MESHES = (50, 100, 200, 400)


def _add_rolling_options(p: argparse.ArgumentParser, patch_default: float | None) -> None:
    """Options the two rolling studies share: mesh, patch, orders, band, damping, tire."""
    add_mesh_option(p)
    default_text = "0: undeformed only" if not patch_default else f"{patch_default:g}"
    p.add_argument("--patch-length", metavar="M", type=float, default=patch_default or 0.0,
                   help=f"contact patch length in m for the loaded tire (default {default_text})")
    p.add_argument("--max-frequency", metavar="HZ", type=float, default=None,
                   help="highest loaded-mode frequency in Hz")
    p.add_argument("--damped", action="store_true",
                   help="keep the tire's damping (default: undamped, so that loaded modes and "
                   "the undamped dispersion curves compare exactly; shifts are O(zeta^2))")
    p.add_argument("--allow-supercritical", action="store_true",
                   help="build the loaded model at or above the mesh's critical speed")
    add_tire_options(p)
    add_output_options(p)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "dispersion",
        help=command_help("dispersion"),
        description="Dispersion of the rolling tire in the ground frame: frequency of each "
        "signed order n (wavenumber k = n/R; n > 0 travels against the rotation and falls "
        "with speed, n < 0 with it and rises) for the undeformed tire, and with "
        "--patch-length the complex modes of the loaded tire at their dominant order.",
    )
    p.add_argument("--speed", metavar="M_PER_S", type=float, default=None,
                   help="forward speed in m/s (default: the paper's spin 20π rad/s, i.e. "
                   "20π·R = 40.84 m/s for R = 0.65 m)")
    p.add_argument("--nmax", metavar="N", type=int, default=12,
                   help="highest |n| of the dispersion curve (default 12)")
    _add_rolling_options(p, patch_default=None)
    p.set_defaults(handler=run_dispersion, max_frequency_default=300.0)

    p = subparsers.add_parser(
        "speed-sweep",
        help=command_help("speed-sweep"),
        description="Frequencies of the rolling tire in the ground frame against speed: each "
        "undeformed pair splits into a backward (n > 0, falling) and a forward (n < 0, "
        "rising) wave; the loaded tire's complex modes are listed at each speed.",
    )
    p.add_argument("--max-speed", metavar="M_PER_S", type=float, default=None,
                   help="highest speed in m/s (default: the paper's 20π·R = 40.84 m/s, or just "
                   "below the mesh's critical speed if that is lower and there is a patch)")
    p.add_argument("--steps", metavar="K", type=int, default=21,
                   help="number of speeds from 0 to --max-speed (default 21)")
    p.add_argument("--nmax", metavar="N", type=int, default=6,
                   help="highest |n| of the undeformed curves (default 6)")
    _add_rolling_options(p, patch_default=0.204)
    p.set_defaults(handler=run_speed_sweep, max_frequency_default=200.0)

    p = subparsers.add_parser(
        "critical-speed",
        help=command_help("critical-speed"),
        description="Lowest speed at which a ground-frame frequency of the undeformed rolling "
        "tire reaches zero (a standing wave under the patch).",
    )
    add_mesh_option(p)
    add_tire_options(p)
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_critical_speed)


def _max_frequency(args: argparse.Namespace) -> float:
    if args.max_frequency is not None:
        return args.max_frequency
    return args.max_frequency_default


def _common_problems(args: argparse.Namespace, nmax_high: int) -> list[str | None]:
    f_max_hz = _max_frequency(args)
    return [
        elements_problem(args.elements),
        range_problem("--nmax", args.nmax, 1, nmax_high, integer=True),
        frequency_problem("--max-frequency", f_max_hz),
    ]


def _rolling_checks(args: argparse.Namespace, tire, top_speed: float | None) -> list:
    """Checks that need the tire: the patch length, and a loaded model below the mesh's
    critical speed (the undeformed curves need no model and may go past it)."""
    found = [patch_length_problem("--patch-length", args.patch_length, tire)]
    if (found[0] is None and args.patch_length > 0 and top_speed is not None
            and elements_problem(args.elements) is None and not args.allow_supercritical):
        critical = critical_speed(tire, args.elements).speed_m_s
        if top_speed >= critical:
            found.append(
                f"{_speed_option(args)} = {top_speed:g} m/s: must be below the critical "
                f"speed {critical:.4g} m/s of this mesh (--elements {args.elements}) for "
                "the loaded tire; use --tire-file GL073A_tied (--tire sidewall_max_order=8), "
                "fewer elements, or --allow-supercritical"
            )
    return found


def _speed_option(args: argparse.Namespace) -> str:
    if args.handler is run_dispersion:
        return "--speed" if args.speed is not None else "default --speed"
    return "--max-speed"


def run_dispersion(args: argparse.Namespace) -> Output:
    problems = _common_problems(args, nmax_high=1000)
    if args.speed is not None:
        problems.append(range_problem("--speed", args.speed, 0.0, MAX_SCANNED_SPEED_M_S, "m/s"))

    def speed(tire):  # None: a bad --speed, already reported
        if args.speed is None:
            return paper_speed_m_s(tire)
        return args.speed if problems[-1] is None else None

    tire = checked_tire(args, problems, lambda t: _rolling_checks(args, t, speed(t)))
    f_max_hz = _max_frequency(args)
    result = dispersion_at_speed(
        tire, args.elements, args.speed, args.patch_length, args.nmax, f_max_hz,
        damped=args.damped, allow_supercritical=args.allow_supercritical,
    )
    curve, rest = result.undeformed, result.at_rest
    rows = [[n, k, f_in, f_out, r_in, r_out] for n, k, f_in, f_out, r_in, r_out in zip(
        curve.orders, curve.wavenumber_per_m, curve.in_phase_hz, curve.out_of_phase_hz,
        rest.in_phase_hz, rest.out_of_phase_hz)]
    lines = [
        f"Ground-frame dispersion at V = {result.speed_m_s:.4g} m/s (Ω = {curve.spin_rad_s:.4g} "
        f"rad/s), N = {args.elements}, {'damped' if result.damped else 'undamped'}; "
        "n > 0 backward (against the rotation), n < 0 forward.",
        "",
        "undeformed",
        table(rows, ["n", "k [1/m]", "in [Hz]", "out [Hz]", "rest in [Hz]", "rest out [Hz]"]),
    ]
    if result.loaded is not None:
        shown = [m for m in result.loaded.modes if abs(m.order) <= args.nmax]
        lines += [
            "",
            f"loaded, patch {args.patch_length * 100:.3g} cm: {len(result.loaded.modes)} modes "
            f"up to {f_max_hz:g} Hz, {len(shown)} with |n| <= {args.nmax} (dominant harmonic)",
            table([[m.order, m.order / tire.R, m.frequency_hz, m.phase] for m in shown],
                  ["n", "k [1/m]", "f [Hz]", "phase"]),
        ]
    output = Output(text="\n".join(lines), data=result.to_dict())
    write_plot(args, output, plot_with("plot_dispersion", result.undeformed, result.loaded,
                                     reference=result.at_rest))
    return output


def run_speed_sweep(args: argparse.Namespace) -> Output:
    problems = _common_problems(args, nmax_high=200)
    problems.append(range_problem("--steps", args.steps, 2, 500, integer=True))
    top = None
    if args.max_speed is not None:
        problems.append(positive_problem("--max-speed", args.max_speed, "m/s",
                                         MAX_SCANNED_SPEED_M_S))
        top = args.max_speed if problems[-1] is None else None
    tire = checked_tire(args, problems, lambda t: _rolling_checks(args, t, top))
    critical = critical_speed(tire, args.elements).speed_m_s
    note = ""
    max_speed = args.max_speed
    if max_speed is None:
        max_speed = paper_speed_m_s(tire)
        if args.patch_length > 0 and max_speed >= critical and not args.allow_supercritical:
            max_speed = 0.95 * critical
            note = (f" (the paper's {paper_speed_m_s(tire):.4g} m/s is beyond this mesh's "
                    f"critical speed; stopping at 95 % of it)")
    f_max_hz = _max_frequency(args)
    speeds = np.linspace(0.0, max_speed, args.steps)
    with progress_bar("speeds") as progress:
        result = speed_sweep(
            tire, args.elements, speeds, args.patch_length, f_max_hz, args.nmax,
            damped=args.damped, allow_supercritical=args.allow_supercritical, progress=progress,
        )
    column = {int(n): j for j, n in enumerate(result.orders)}
    ks = range(1, args.nmax + 1)
    header = ["V [m/s]", *(f"n=+{k}" for k in ks), *(f"n=-{k}" for k in ks)]
    rows = [[v, *(f[column[k]] for k in ks), *(f[column[-k]] for k in ks)]
            for v, f in zip(result.speeds_m_s, result.undeformed_in_phase_hz)]
    lines = [
        f"Ground-frame in-phase frequencies [Hz] of the undeformed tire, N = {args.elements}, "
        f"speeds 0-{max_speed:.4g} m/s{note}; critical speed {critical:.4g} m/s.",
        "n = +k: backward wave (falls with speed); n = -k: forward wave (rises).",
        table(rows, header),
    ]
    if result.loaded is not None:
        counts = ", ".join(f"{len(r.modes)}" for r in result.loaded)
        lines += ["", f"loaded, patch {args.patch_length * 100:.3g} cm: modes up to "
                  f"{f_max_hz:g} Hz per speed: {counts} (all in --json)"]
    output = Output(text="\n".join(lines), data=result.to_dict())
    write_plot(args, output, plot_with("plot_speed_sweep", result))
    return output


STANDING_WAVE = (
    "The critical speed is the lowest speed at which a ground-frame frequency of the "
    "undeformed rolling tire reaches zero: a standing wave under the contact patch, which is "
    "fixed in space. "
)
LUMPED_SIDEWALL = (
    "In the paper's model the sidewall is a row of lumped masses between two "
    "radial springs with no coupling along the circumference, so its band of modes just below "
    "sqrt((k_r1 + k_r2)/m_s)/2π has no wave speed. Seen from the ground each sidewall mode of "
    "order n moves down by κ_n·Ω, and the largest discrete wavenumber κ = 1/δθ = N/2π grows "
    "with the mesh, so the critical speed, about ω_s·R·δθ, belongs to the mesh and falls as N "
    "grows. It is an artefact of the lumped sidewall, not a property of the tire. A "
    "circumferential sidewall shear stiffness (--tire sidewall_shear=G with G > 0) gives the "
    "band a wave speed of order sqrt(G/m_s) and a critical speed that converges as N grows; "
    "--tire-file GL073A_shear is the GL073A tire re-identified with it (docs/theory.md §8.8). "
    "A sidewall tied to the tread above the measured orders (--tire sidewall_max_order=8, "
    "--tire-file GL073A_tied) removes the band there and the critical speed converges "
    "(docs/theory.md §8.10)."
)
TIED_SIDEWALL = (
    "This tire's sidewall moves on its own only in the orders n <= {top}; above, it is tied to "
    "the tread at its static share, so no band without wave speed is left there. The critical "
    "speed is where the in-phase mode of order {top} stands still: it converges as N grows, to "
    "the tire's own standing-wave speed (docs/theory.md §8.10)."
)
SHEARED_SIDEWALL = (
    "This tire's sidewall masses are coupled along the circumference by a shear stiffness "
    "G = {shear:.4g} N, so its band has a wave speed c = sqrt(G/m_s) = {wave:.4g} m/s. On a "
    "mesh the critical speed lies above c by about ω_s·R·δθ/2 (ω_s the band frequency): it "
    "falls as N grows towards c, the tire's own standing-wave speed, not towards zero as with "
    "the paper's lumped sidewall (docs/theory.md §8.8)."
)


def explanation(tire) -> str:
    """Why the critical speed is what it is, for this tire's sidewall."""
    shear = tire.effective_sidewall_shear
    if tire.sidewall_max_order > 0:
        return STANDING_WAVE + TIED_SIDEWALL.format(top=int(tire.sidewall_max_order))
    if shear <= 0.0:
        return STANDING_WAVE + LUMPED_SIDEWALL
    return STANDING_WAVE + SHEARED_SIDEWALL.format(shear=shear,
                                                   wave=float(np.sqrt(shear / tire.m_s)))


def run_critical_speed(args: argparse.Namespace) -> Output:
    tire = checked_tire(args, [elements_problem(args.elements)])
    result = critical_speed(tire, args.elements)
    meshes = sorted(set(CRITICAL_SPEED_MESHES) | {args.elements})
    rows = []
    for n in meshes:
        c = critical_speed(tire, n)
        rows.append([n, c.speed_m_s, c.speed_m_s * 3.6, c.spin_rad_s, c.order, c.branch])
    data = result.to_dict()
    head = (f"critical speed at N = {args.elements}: {result.speed_m_s:.4g} m/s "
            f"({result.speed_m_s * 3.6:.4g} km/h, Ω = {result.spin_rad_s:.4g} rad/s), "
            f"order {result.order}, branch {result.branch}")
    text = "\n".join([
        head, "", explanation(tire), "",
        table(rows, ["N", "V [m/s]", "V [km/h]", "Ω [rad/s]", "order", "branch"]),
    ])
    return Output(text=text, data=data)
