"""The in-plane ring's commands: ``tire-fmu inplane-modes`` (radial, tangential and rotational
modes of the tire with its rim held or free; ground-frame frequencies per order at speed),
``inplane-speed-sweep`` (those frequencies against the speed) and ``inplane-cleat``."""

from __future__ import annotations

import argparse
from dataclasses import replace

from ..core.inplane_host import HOST_FIELDS
from ..core.parameters import DEFAULT_LOAD_N
from .commands import command_help
from .common import (
    LOAD_ZERO,
    CliError,
    Output,
    add_output_options,
    add_tire_options,
    checked_tire,
    elements_problem,
    field_problem,
    frequency_problem,
    load_default_text,
    order_problem,
    plot_with,
    raise_problems,
    range_problem,
    table,
    write_plot,
)

#: The in-plane ring's default tire file: GL073A (the paper's lumped radial sidewall) with
#: the tangential data and their provenance.
DEFAULT_TIRE_FILE = "GL073A_inplane"


def register(subparsers) -> None:
    register_modes(subparsers)
    register_speed_sweep(subparsers)
    register_cleat(subparsers)


def add_ring_options(parser, points_when: str) -> None:
    """--elements, --point-spacing and --tangential, as both in-plane commands take them."""
    from ..core.inplane import TANGENTIAL_RANGES

    names = ", ".join(f"{name} [{unit or '1'}]"
                      for name, (_, _, unit) in TANGENTIAL_RANGES.items())
    parser.add_argument("--elements", metavar="N", type=int, default=100,
                        help="number of nodes around the ring (default 100)")
    when = f" {points_when}" if points_when else ""
    parser.add_argument("--point-spacing", metavar="M", type=float, default=0.005,
                        help=f"contact point spacing in m{when} (default 0.005)")
    parser.add_argument("--tangential", metavar="NAME=VALUE", action="append", default=[],
                        help="override a tangential parameter of the tire file (repeatable). "
                        f"Names: {names}")


def ring_problems(args: argparse.Namespace) -> list[str | None]:
    """--elements and --point-spacing of add_ring_options."""
    return [elements_problem(args.elements),
            range_problem("--point-spacing", args.point_spacing, 1e-3, 0.05, "m")]


def load_problem(load_n) -> str | None:
    """--load of an in-plane command: the in-plane FMU's load, or 0 for the undeformed tire."""
    return field_problem("--load", load_n, replace(HOST_FIELDS["load_n"], low_inclusive=True),
                         "0 N: the undeformed tire")


def footprint_deflection(model, load_n: float, n_elements: int, **options) -> float:
    """The deflection for the load (deflection_for_load); a footprint it cannot find is the
    load's problem in the in-plane FMU's words."""
    from ..core.inplane_contact import ContactSetError, deflection_for_load
    from ..core.inplane_host import footprint_problem
    from ..core.parameters import ParameterError

    try:
        return deflection_for_load(model, load_n, n_elements, **options)
    except ContactSetError as error:
        raise ParameterError([footprint_problem(load_n, model.tire.k_cw, n_elements)]
                             ) from error


def register_modes(subparsers) -> None:
    p = subparsers.add_parser(
        "inplane-modes",
        help=command_help("inplane-modes"),
        description="Modes of the full in-plane ring (radial and tangential motion of tread and "
        "sidewall), undeformed, with the rim held or (--rim-free) free to translate and turn "
        "with the wheel's mass and inertia. Each mode is labelled with its dominant order and "
        "kind (radial, tangential, rotational: the tangential order 0). With --speed, the "
        "ground-frame frequencies of each order (rim held) instead, and --plot draws them "
        "against the signed order (the dispersion, with the ring at rest in grey). The tire "
        "data default to "
        f"{DEFAULT_TIRE_FILE} (GL073A, its lumped radial sidewall, with tangential data); a "
        "tire file's [tangential] table gives the tangential data, --tangential overrides "
        "them.",
    )
    add_ring_options(p, "with --load")
    p.add_argument("--rim-free", action="store_true",
                   help="let the rim translate and turn (wheel mass and inertia from --tangential)")
    p.add_argument("--load", metavar="N", type=float,
                   help="press the tire on a flat road with this load in N (at rest): the "
                   "modes of the linearised footprint (points in contact, tread elements "
                   "sticking), the axle held; with --rim-free the wheel turns freely; with "
                   "--speed the modes of the tire rolling steadily (no "
                   f"default: the undeformed tire; {LOAD_ZERO})")
    p.add_argument("--speed", metavar="M_PER_S", type=float, default=0.0,
                   help="forward speed in m/s: list each order's ground-frame frequencies; "
                   "with --load, the modes of the tire rolling steadily at it (linearised "
                   "about the steady rolling, the tread elements' transport as states)")
    p.add_argument("--torque", metavar="N_M", type=float, default=0.0,
                   help="with --load, --speed and --rim-free: the torque on the wheel in N m "
                   "(+ driving, - braking) it rolls under (default 0)")
    p.add_argument("--nmax", metavar="N", type=int, default=8,
                   help="highest order listed with --speed (default 8)")
    p.add_argument("--max-frequency", metavar="HZ", type=float, default=200.0,
                   help="highest frequency listed in Hz (default 200)")
    p.add_argument("--sidewall-tangential", choices=("tied", "lumped"), default="tied",
                   help="the sidewall's tangential motion: tied to the tread at its static "
                   "share (default) or lumped masses of its own")
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_inplane_modes)


def register_speed_sweep(subparsers) -> None:
    p = subparsers.add_parser(
        "inplane-speed-sweep",
        help=command_help("inplane-speed-sweep"),
        description="Ground-frame frequencies of the undeformed in-plane ring (rim held) order "
        "by order against the speed: each order's pair splits into a wave against the rotation "
        "and one with it, by about 2nΩ(n²-1)/(n²+1) (the inextensible ring's), and order 1 "
        "hardly at all. The radial ring's speed-sweep (Fig. 19) with the tangential motion; "
        f"the tire data default to {DEFAULT_TIRE_FILE}.",
    )
    add_ring_options(p, "")
    p.add_argument("--max-speed", metavar="M_PER_S", type=float,
                   help="highest speed in m/s (default: 0.9 of the mesh's critical speed, at "
                   "most 60)")
    p.add_argument("--speeds", metavar="COUNT", type=int, default=25,
                   help="number of speeds from 0 (default 25)")
    p.add_argument("--nmax", metavar="N", type=int, default=6,
                   help="highest order (default 6)")
    p.add_argument("--max-frequency", metavar="HZ", type=float, default=200.0,
                   help="highest frequency listed and plotted in Hz (default 200)")
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_inplane_speed_sweep)


def run_inplane_speed_sweep(args: argparse.Namespace) -> Output:
    import numpy as np

    from ..core.inplane import InPlaneTire
    from ..core.inplane_modes import critical_speed as inplane_critical_speed
    from ..core.inplane_modes import speed_sweep

    raise_problems([*ring_problems(args),
                    frequency_problem("--max-frequency", args.max_frequency),
                    None if args.max_speed is None else
                    range_problem("--max-speed", args.max_speed, 0.1,
                                  HOST_FIELDS["speed_m_s"].high, "m/s"),
                    range_problem("--speeds", args.speeds, 2, 400, integer=True),
                    order_problem("--nmax", args.nmax, args.elements)])
    if args.tire_file is None:
        args.tire_file = DEFAULT_TIRE_FILE
    model = InPlaneTire(checked_tire(args), _tangential(args.tangential, args.tire_file))
    critical = inplane_critical_speed(model, args.elements)
    top = args.max_speed if args.max_speed is not None else min(0.9 * critical.speed_m_s, 60.0)
    sweep = speed_sweep(model, args.elements, np.linspace(0.0, top, args.speeds),
                        range(args.nmax + 1))
    rows = []
    for j, n in enumerate(sweep.orders):
        rest = sweep.against_hz[0, j, 0]
        split = sweep.split_hz(int(n))[-1]
        inextensible = 2 * n * (n * n - 1) / (n * n + 1) * top / model.tire.R / (2 * np.pi)
        rows.append([int(n), rest, sweep.against_hz[-1, j, 0], sweep.with_hz[-1, j, 0], split,
                     inextensible])
    head = (f"the lowest pair of each order from rest to {top:.4g} m/s ({args.speeds} speeds), "
            f"rim held, N = {args.elements}")
    foot = (f"critical (standing-wave) speed of this mesh, undamped: {critical.speed_m_s:.4g} "
            f"m/s (order {critical.order}, {critical.branch})")
    text = table(rows, ["n", "at rest [Hz]", "against rotation [Hz]", "with rotation [Hz]",
                        "split [Hz]", "2nΩ(n²-1)/(n²+1) [Hz]"])
    output = Output(text=head + "\n" + text + "\n" + foot,
                    data=sweep.to_dict() | {"critical_speed": critical.to_dict()})
    write_plot(args, output, plot_with("plot_inplane_speed_sweep", sweep,
                                       max_frequency_hz=args.max_frequency,
                                       critical_speed_m_s=critical.speed_m_s))
    return output


def register_cleat(subparsers) -> None:
    from ..core.obstacles import MAX_OBSTACLE_LENGTH_M, MAX_OBSTACLE_SIZE_M

    p = subparsers.add_parser(
        "inplane-cleat",
        help=command_help("inplane-cleat"),
        description="The classic cleat test with the in-plane tire (SAE J2730-like): the "
        "axle held at the deflection of --load, the wheel free to turn, the road carrying a "
        "cleat at --speed; Fx, Fz and My at the axle against time, and the spectra of Fx and "
        "Fz with the frequencies that dominate them.",
    )
    p.add_argument("--speed", metavar="M_PER_S", type=float, default=10.0,
                   help="road speed in m/s (default 10)")
    p.add_argument("--load", metavar="N", type=float, default=DEFAULT_LOAD_N,
                   help="static load in N that sets the axle's height "
                   f"({load_default_text(DEFAULT_LOAD_N)}; {LOAD_ZERO})")
    p.add_argument("--height", metavar="M", type=float, default=0.02,
                   help="cleat height in m (default 0.02)")
    p.add_argument("--length", metavar="M", type=float, default=0.02,
                   help="cleat length along the road in m (default 0.02)")
    p.add_argument("--shape", choices=("rectangular", "rounded"), default="rectangular",
                   help="rectangular (steps) or rounded (1 - cos)")
    add_ring_options(p, "")
    p.add_argument("--f-max", metavar="HZ", type=float, default=300.0,
                   help="reduce the ring to its modes up to this frequency with the zone's "
                   "static shapes (default 300; 0 steps every DOF)")
    p.add_argument("--step", metavar="S", type=float, default=1e-4,
                   help="time step in s (default 1e-4)")
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_inplane_cleat, max_obstacle=(MAX_OBSTACLE_SIZE_M,
                                                             MAX_OBSTACLE_LENGTH_M))


def run_inplane_cleat(args: argparse.Namespace) -> Output:
    import numpy as np
    from scipy.signal import periodogram

    from ..core.inplane import InPlaneTire
    from ..core.inplane_contact import InPlaneSimulator
    from ..core.obstacles import cleat

    size, length = args.max_obstacle
    raise_problems([
        *ring_problems(args),
        range_problem("--speed", args.speed, 0.5, 60.0, "m/s"),
        load_problem(args.load),
        range_problem("--height", args.height, 1e-4, size, "m"),
        range_problem("--length", args.length, 1e-4, length, "m"),
        None if args.f_max == 0 else field_problem("--f-max", args.f_max,
                                                   HOST_FIELDS["f_max_hz"], "0: every DOF"),
        field_problem("--step", args.step, HOST_FIELDS["step_s"]),
    ])
    if args.tire_file is None:
        args.tire_file = DEFAULT_TIRE_FILE
    model = InPlaneTire(checked_tire(args), _tangential(args.tangential, args.tire_file))
    deflection = 0.0 if args.load == 0 else footprint_deflection(
        model, args.load, args.elements, point_spacing_m=args.point_spacing)
    ahead = 0.4  # m of road before the cleat: past the zone's front, rolling settled
    sim = InPlaneSimulator(model, args.elements, args.speed, deflection, step_s=args.step,
                           point_spacing_m=args.point_spacing,
                           obstacle=cleat(args.height, args.length, args.shape),
                           obstacle_ahead_m=ahead, f_max_hz=args.f_max or None)
    duration = (ahead + 0.3 + args.length) / args.speed + 0.1
    run = sim.run(duration)
    on = run.time_s > 0.5 * ahead / args.speed

    def dominant(signal):
        freq, power = periodogram(signal - signal.mean(), fs=1 / args.step, nfft=2**16)
        band = freq >= 5.0
        return float(freq[band][np.argmax(power[band])])

    fx, fz = run.rim_fx_n[on], run.rim_fz_n[on]
    summary = {"deflection_m": deflection, "peak_fz_n": float(fz.max()),
               "fx_min_n": float(fx.min()), "fx_max_n": float(fx.max()),
               "fx_dominant_hz": dominant(fx), "fz_dominant_hz": dominant(fz),
               "basis_size": sim._ny}
    text = (f"{cleat(args.height, args.length, args.shape).label} at {args.speed:g} m/s, "
            f"axle held at {deflection * 1e3:.2f} mm ({args.load:g} N), wheel free, "
            f"N = {args.elements}, {args.point_spacing * 1e3:g} mm points, "
            f"{'every DOF' if not args.f_max else f'modes to {args.f_max:g} Hz'}\n"
            + table([["peak Fz [kN]", summary["peak_fz_n"] / 1e3],
                     ["Fx min / max [kN]", f"{summary['fx_min_n'] / 1e3:.3g} / "
                      f"{summary['fx_max_n'] / 1e3:.3g}"],
                     ["Fx dominant [Hz]", summary["fx_dominant_hz"]],
                     ["Fz dominant [Hz]", summary["fz_dominant_hz"]]], ["", "value"]))
    output = Output(text=text, data={"load_n": args.load, "summary": summary,
                                     "run": run.to_dict()})
    write_plot(args, output, plot_with("plot_inplane_cleat", run, args.load, on))
    return output


def _tangential(items: list[str], tire_file: str | None = None):
    """The tangential data: the tire file's [tangential] table, then --tangential."""
    from dataclasses import asdict

    from ..core.inplane import TANGENTIAL_RANGES, TangentialParameters
    from ..tire_files import TireFileError, read_tire_file

    values = {}
    if tire_file is not None:
        try:
            table = read_tire_file(tire_file, warn=False).tangential
        except TireFileError as error:
            raise CliError(f"--tire-file: {error}") from error
        values = {} if table is None else asdict(table)
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or name not in TANGENTIAL_RANGES:
            raise CliError(f"--tangential {item!r}: expected NAME=VALUE with NAME one of "
                           f"{', '.join(TANGENTIAL_RANGES)}")
        try:
            values[name] = float(text)
        except ValueError:
            raise CliError(f"--tangential {item!r}: {text!r} is not a number") from None
    return TangentialParameters(**values)


def run_inplane_modes(args: argparse.Namespace) -> Output:
    import numpy as np

    from ..core.inplane import InPlaneRing, InPlaneTire
    from ..core.inplane_modes import critical_speed as inplane_critical_speed
    from ..core.inplane_modes import speed_sweep, tire_modes

    raise_problems([*ring_problems(args),
                    frequency_problem("--max-frequency", args.max_frequency),
                    field_problem("--speed", args.speed, HOST_FIELDS["speed_m_s"]),
                    None if args.load is None else load_problem(args.load),
                    range_problem("--torque", args.torque, -2e4, 2e4, "N m"),
                    # the orders are listed at --speed only: the mesh bounds them there
                    order_problem("--nmax", args.nmax,
                                  args.elements if args.speed > 0 else None)])
    if args.tire_file is None:
        args.tire_file = DEFAULT_TIRE_FILE
    model = InPlaneTire(checked_tire(args), _tangential(args.tangential, args.tire_file),
                        sidewall_tangential=args.sidewall_tangential)
    if args.load is not None and not args.load == 0.0:  # 0 N: the undeformed tire
        return _loaded(args, model)
    if args.speed > 0:
        if args.rim_free:
            raise CliError("--speed with --rim-free: the per-order frequencies are the ring's "
                           "with the rim held (the free rim couples orders 0 and 1)")
        # at rest too: the dispersion plot shows the asymmetry against it
        sweep = speed_sweep(model, args.elements, [0.0, args.speed], range(args.nmax + 1))
        rows, data = [], []
        for j, n in enumerate(sweep.orders):
            backward, forward = (f[np.isfinite(f) & (f <= args.max_frequency)]
                                 for f in (sweep.against_hz[-1, j], sweep.with_hz[-1, j]))
            rows.append([int(n), ", ".join(f"{x:.2f}" for x in backward),
                         ", ".join(f"{x:.2f}" for x in forward)])
            data.append({"order": int(n), "against_rotation_hz": backward.tolist(),
                         "with_rotation_hz": forward.tolist()})
        critical = inplane_critical_speed(model, args.elements)
        head = (f"ground-frame frequencies per order at {args.speed:g} m/s, rim held, "
                f"N = {args.elements}")
        foot = (f"critical (standing-wave) speed of this mesh, undamped: "
                f"{critical.speed_m_s:.4g} m/s (order {critical.order}, {critical.branch})"
                + (": this speed is above it" if args.speed >= critical.speed_m_s else ""))
        output = Output(text=head + "\n" + table(rows, ["n", "waves against θ [Hz]",
                                                         "waves with θ [Hz]"]) + "\n" + foot,
                        data={"speed_m_s": args.speed, "orders": data,
                              "critical_speed": critical.to_dict()})
        write_plot(args, output, plot_with("plot_inplane_dispersion", sweep,
                                           max_frequency_hz=args.max_frequency))
        return output
    ring = InPlaneRing(model, args.elements, rim_free=args.rim_free)
    result = tire_modes(ring, f_max_hz=args.max_frequency)
    rows = [[i + 1, m.frequency_hz, m.order, m.kind, m.phase, m.tangential_share]
            for i, m in enumerate(result.modes)]
    rim = "rim free" if args.rim_free else "rim held"
    head = (f"{len(result.modes)} in-plane modes up to {args.max_frequency:g} Hz; "
            f"N = {args.elements}, {rim}, undeformed, at rest")
    output = Output(text=head + "\n" + table(rows, ["#", "f [Hz]", "order", "kind", "phase",
                                                    "tangential share"]),
                    data=result.to_dict() | {"tangential": model.tangential.as_dict()})
    write_plot(args, output, plot_with("plot_inplane_modes", result))
    return output


def _loaded(args: argparse.Namespace, model) -> Output:
    from ..core.inplane_contact import InPlaneSimulator, loaded_modes

    wheel = "free" if args.rim_free else "held"
    if args.torque != 0.0 and not (args.speed > 0 and args.rim_free):
        raise CliError("--torque: only with --load, --speed and --rim-free (a held wheel's "
                       "torque is what holds it)")
    if args.speed > 0:
        return _rolling(args, model, wheel)
    deflection = footprint_deflection(model, args.load, args.elements,
                                      point_spacing_m=args.point_spacing)
    sim = InPlaneSimulator(model, args.elements, 0.0, deflection, wheel=wheel,
                           point_spacing_m=args.point_spacing)
    result = loaded_modes(sim, f_max_hz=args.max_frequency)
    rows = [[i + 1, f, z, k] for i, (f, z, k) in
            enumerate(zip(result.frequencies_hz, result.damping_ratios, result.kinds))]
    head = (f"{len(rows)} modes of the tire pressed with {args.load:g} N (deflection "
            f"{deflection * 1e3:.2f} mm, {result.points_in_contact} points in contact) up to "
            f"{args.max_frequency:g} Hz; N = {args.elements}, axle held, wheel {wheel}")
    data = {"load_n": args.load, "deflection_m": deflection, "wheel": wheel,
            "points_in_contact": result.points_in_contact,
            "modes": [{"frequency_hz": f, "damping_ratio": z, "kind": k}
                      for _, f, z, k in rows]}
    return Output(text=head + "\n" + table(rows, ["#", "f [Hz]", "zeta", "kind"]), data=data)


def _rolling(args: argparse.Namespace, model, wheel: str) -> Output:
    from ..core.inplane_contact import InPlaneSimulator, steady_rolling
    from ..core.inplane_rolling_modes import rolling_modes

    deflection = footprint_deflection(model, args.load, args.elements,
                                      point_spacing_m=args.point_spacing)
    sim = InPlaneSimulator(model, args.elements, args.speed, deflection, wheel=wheel,
                           point_spacing_m=args.point_spacing)
    steady = steady_rolling(sim, args.torque)
    result = rolling_modes(sim, args.torque, f_max_hz=args.max_frequency)
    tire = [i for i, kind in enumerate(result.kinds) if kind != "transport"]
    rows = [[n + 1, result.frequencies_hz[i], result.decay_rates_1_s[i],
             result.damping_ratios[i], result.kinds[i]] for n, i in enumerate(tire)]
    head = (f"{len(rows)} modes of the tire pressed with {args.load:g} N (deflection "
            f"{deflection * 1e3:.2f} mm) rolling at {args.speed:g} m/s under {args.torque:g} N m "
            f"(slip {steady.slip_ratio * 100:.3f} %, {result.points_in_contact} points in "
            f"contact, {result.sliding_points} sliding), natural frequency up to "
            f"{args.max_frequency:g} Hz; N = {args.elements}, axle held, wheel {wheel}; "
            "linearised about the steady rolling, f the damped frequency "
            f"({len(result.kinds) - len(tire)} eigenvalues of the elements' transport left out)")
    data = {"load_n": args.load, "deflection_m": deflection, "wheel": wheel,
            "speed_m_s": args.speed, "torque_n_m": args.torque,
            "slip_ratio": steady.slip_ratio, "points_in_contact": result.points_in_contact,
            "sliding_points": result.sliding_points,
            "modes": [{"frequency_hz": f, "decay_rate_1_s": d, "damping_ratio": z, "kind": k}
                      for _, f, d, z, k in rows]}
    return Output(text=head + "\n" + table(rows, ["#", "f [Hz]", "decay [1/s]", "zeta",
                                                    "kind"]), data=data)
