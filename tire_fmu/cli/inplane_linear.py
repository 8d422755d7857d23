"""The in-plane tire's linear model at an operating point: ``tire-fmu inplane-frf`` (Bode
plots of the full model, and of its reduction) and ``inplane-reduce`` (balanced truncation,
its report, and the model written as .npz or .mat)."""

from __future__ import annotations

import argparse

from ..core.inplane_host import HOST_FIELDS
from ..core.parameters import DEFAULT_LOAD_N
from .commands import command_help
from .common import (
    LOAD_ZERO,
    MAX_FREQUENCY_HZ,
    CliError,
    Output,
    add_output_options,
    add_tire_options,
    checked_tire,
    field_problem,
    frequency_grid,
    frequency_grid_problems,
    load_default_text,
    output_file,
    output_path,
    plot_with,
    raise_problems,
    range_problem,
    response_table,
    table,
    write_plot,
    writing,
)
from .inplane import (
    DEFAULT_TIRE_FILE,
    _tangential,
    add_ring_options,
    footprint_deflection,
    load_problem,
    ring_problems,
)

INPUTS = ("torque", "rim_x", "rim_z", "road")
OUTPUTS = ("rim_Fx", "rim_Fz", "rim_My", "wheel_rate")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "inplane-frf",
        help=command_help("inplane-frf"),
        description="Frequency response of the in-plane tire linearised about its steady "
        "rolling (at rest: its static footprint; the contact and stick sets frozen, the "
        "tread elements' transport as states): from the wheel's torque, the rim's fore-aft "
        "or vertical displacement or the road's height (at the contact zone's front) to the "
        "force or moment on the rim or the wheel's spin. With --reduced the balanced "
        "reduction is overlaid with its relative error.",
    )
    p.add_argument("--input", choices=INPUTS, default="rim_z",
                   help="excitation (default rim_z): torque on the wheel [N m], rim_x / "
                   "rim_z the axle's displacement [m], road the road's height [m]")
    p.add_argument("--output", choices=OUTPUTS, default="rim_Fz",
                   help="response (default rim_Fz): the tire's force [N] or moment [N m] on "
                   "the rim, or wheel_rate the free wheel's spin [rad/s]")
    p.add_argument("--reduced", action="store_true", help="overlay the reduced model")
    p.add_argument("--min-frequency", metavar="HZ", type=float, default=0.5,
                   help="lowest frequency in Hz (default 0.5)")
    p.add_argument("--max-frequency", metavar="HZ", type=float, default=300.0,
                   help="highest frequency in Hz (default 300)")
    p.add_argument("--points", metavar="K", type=int, default=300,
                   help="frequencies, log-spaced (default 300)")
    _add_operating_options(p)
    _add_reduction_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_inplane_frf)

    p = subparsers.add_parser(
        "inplane-reduce",
        help=command_help("inplane-reduce"),
        description="Reduce the in-plane tire linearised at its operating point by balanced "
        "truncation (residualised: the static gain is kept exactly), report the states kept "
        "and the largest relative FRF error of every input/output pair over the band, and "
        "with --out write the model: .npz (arrays, JSON metadata, checksums; load with "
        "tire_fmu.model_files.load_inplane_npz) or .mat (A, B, C, D for ss(), inputs "
        "[u; du/dt; d2u/dt2]). The inputs are the torque, the rim's x and z and the road "
        "under each contact point, whose windows of road the file gives as delays behind the "
        "contact zone's front.",
    )
    p.add_argument("--out", metavar="FILE", type=output_path,
                   help="write the reduced model (.npz or .mat)")
    p.add_argument("--full", action="store_true",
                   help="with --out: write the full linear model, not the reduced one")
    _add_operating_options(p)
    _add_reduction_options(p)
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_inplane_reduce)


def _add_operating_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("operating point")
    g.add_argument("--load", metavar="N", type=float, default=DEFAULT_LOAD_N,
                   help="static load in N that sets the axle's height "
                   f"({load_default_text(DEFAULT_LOAD_N)}; {LOAD_ZERO})")
    g.add_argument("--speed", metavar="M_PER_S", type=float, default=10.0,
                   help="road speed in m/s (default 10; 0: at rest, the road a plate under "
                   "the tire)")
    g.add_argument("--torque", metavar="N_M", type=float, default=0.0,
                   help="the free wheel's steady torque in N m (+ driving, - braking; "
                   "default 0: free rolling)")
    g.add_argument("--wheel", choices=("free", "held"), default="free",
                   help="the wheel turns with its inertia under the torque (default), or is "
                   "held at the speed's spin")
    g.add_argument("--ring-f-max", metavar="HZ", type=float, default=0.0,
                   help="linearise the ring on its Ritz basis to this frequency, as the FMUs "
                   "step it (default 0: every DOF)")
    add_ring_options(p, "")
    add_tire_options(p)


def _add_reduction_options(p: argparse.ArgumentParser) -> None:
    from ..core.inplane_io import InPlaneReductionSettings

    defaults = InPlaneReductionSettings()
    g = p.add_argument_group("reduction")
    g.add_argument("--target-error", metavar="X", type=float, default=defaults.target_error,
                   help="largest relative FRF error allowed over the band: the fewest states "
                   f"that meet it are kept (default {defaults.target_error:g})")
    g.add_argument("--n-states", metavar="K", type=int, default=None,
                   help="keep exactly K states instead")
    g.add_argument("--band", metavar="LOW,HIGH", default=None,
                   help="band of the error in Hz (default "
                   f"{defaults.band_hz[0]:g},{defaults.band_hz[1]:g})")


def _settings_problems(args: argparse.Namespace) -> list[str | None]:
    """--band, --target-error and --n-states."""
    return [
        None if args.band is None or _band(args.band) is not None else
        f"--band = {args.band!r}: must be LOW,HIGH in Hz with 0 < LOW < HIGH <= "
        f"{MAX_FREQUENCY_HZ:g}, e.g. 0.5,300",
        range_problem("--target-error", args.target_error, 1e-6, 1.0),
        None if args.n_states is None else
        range_problem("--n-states", args.n_states, 1, 10_000, integer=True),
    ]


def _band(text: str) -> tuple[float, float] | None:
    try:
        band = tuple(float(x) for x in text.split(","))
    except ValueError:
        return None
    return band if len(band) == 2 and 0 < band[0] < band[1] <= MAX_FREQUENCY_HZ else None


def _settings(args: argparse.Namespace):
    """The reduction's settings (checked by :func:`_settings_problems`)."""
    from ..core.inplane_io import InPlaneReductionSettings

    band = InPlaneReductionSettings().band_hz if args.band is None else _band(args.band)
    return InPlaneReductionSettings(args.target_error, band, n_states=args.n_states)


def _operating_problems(args: argparse.Namespace) -> list[str | None]:
    """The operating point's options and the ring's."""
    return [
        *ring_problems(args),
        load_problem(args.load),
        range_problem("--speed", args.speed, 0.0, 60.0, "m/s"),
        range_problem("--torque", args.torque, -2e4, 2e4, "N m"),
        None if args.ring_f_max == 0 else field_problem(
            "--ring-f-max", args.ring_f_max, HOST_FIELDS["f_max_hz"], "0: every DOF"),
    ]


def _linear_model(args: argparse.Namespace):
    from ..core.inplane import InPlaneTire
    from ..core.inplane_contact import InPlaneSimulator
    from ..core.inplane_io import linear_model

    if args.torque != 0.0 and (args.wheel != "free" or args.speed == 0.0):
        raise CliError("--torque: only for a free wheel rolling (--speed > 0): a held wheel's "
                       "torque is what holds it, and at rest a torque has no steady state")
    if args.load == 0.0 and args.wheel == "free":
        raise CliError("--load = 0 N with --wheel free: off the road nothing holds the wheel's "
                       "spin (a pole at zero); give a load or --wheel held")
    if args.tire_file is None:
        args.tire_file = DEFAULT_TIRE_FILE
    model = InPlaneTire(checked_tire(args), _tangential(args.tangential, args.tire_file))
    deflection = 0.0 if args.load == 0.0 else footprint_deflection(
        model, args.load, args.elements, point_spacing_m=args.point_spacing)
    sim = InPlaneSimulator(model, args.elements, args.speed, deflection, wheel=args.wheel,
                           point_spacing_m=args.point_spacing, f_max_hz=args.ring_f_max or None)
    linear = linear_model(sim, args.torque)
    return linear, {**linear.operating_point, "load_n": args.load}


def _head(operating: dict, states: int) -> str:
    ring = ("every DOF" if operating["ring_f_max_hz"] is None
            else f"Ritz basis to {operating['ring_f_max_hz']:g} Hz")
    return (f"in-plane tire at {operating['load_n']:g} N (deflection "
            f"{operating['deflection_m'] * 1e3:.2f} mm), {operating['speed_m_s']:g} m/s, "
            f"{operating['torque_n_m']:g} N m, wheel {operating['wheel']}; "
            f"N = {operating['n_elements']} ({ring}), {operating['points_in_contact']} points "
            f"in contact, {operating['sliding_points']} sliding; {states} states")


def run_inplane_frf(args: argparse.Namespace) -> Output:
    import numpy as np

    from ..core.frequency_response import FrequencyResponse
    from ..core.inplane_io import INPUT_UNITS, OUTPUT_UNITS, reduce_linear_model

    raise_problems(frequency_grid_problems(args) + _settings_problems(args)
                   + _operating_problems(args))
    freqs = frequency_grid(args)
    low, high = freqs[0], freqs[-1]
    settings = _settings(args)
    linear, operating = _linear_model(args)
    if args.input not in linear.physical_inputs:
        raise CliError(f"--input = {args.input}: a held wheel takes no torque (--wheel free)")
    if args.output not in linear.output_names:
        raise CliError(f"--output = {args.output}: a held wheel has no spin of its own "
                       "(--wheel free)")
    k = linear.output_names.index(args.output)

    def response(model, label):
        return FrequencyResponse(freqs, model.frequency_response(args.input, freqs)[:, k],
                                 args.input, args.output, label,
                                 input_unit=INPUT_UNITS[args.input],
                                 output_unit=OUTPUT_UNITS[args.output])

    responses = [response(linear, f"linearised ({linear.n_states} states)")]
    data = {"operating_point": operating}
    text = _head(operating, linear.n_states)
    if args.reduced:
        reduced = reduce_linear_model(linear, settings)
        responses.append(response(reduced, f"reduced ({reduced.n_states} states)"))
        error = float(np.max(np.abs(responses[1].response - responses[0].response))
                      / np.max(responses[0].magnitude))
        data["reduction"] = reduced.report
        data["max_relative_error"] = error
        text += (f"\nreduced to {reduced.n_states} states: largest difference "
                 f"{error:.3g} of the peak over {low:g}-{high:g} Hz")
    data["responses"] = [r.to_dict() for r in responses]
    text += "\n" + response_table(responses, (1.0, 10.0, 30.0, 50.0, 100.0, 150.0, 200.0,
                                               300.0))
    output = Output(text=text, data=data)
    title = (f"{args.input} -> {args.output}: in-plane tire, {operating['load_n'] / 1e3:.3g} kN, "
             f"{operating['speed_m_s']:g} m/s, wheel {operating['wheel']}")
    write_plot(args, output, plot_with("plot_bode", responses, title=title))
    return output


def run_inplane_reduce(args: argparse.Namespace) -> Output:
    from ..core.inplane_io import reduce_linear_model
    from ..model_files import save_inplane_mat, save_inplane_npz

    problems = _settings_problems(args) + _operating_problems(args)
    out = None
    if args.out is not None:
        suffix = args.out.suffix.lower()
        try:
            out = output_file("--out", args.out, suffix if suffix == ".mat" else ".npz")
        except CliError as error:
            problems.append(str(error).replace("ending in .npz", "ending in .npz or .mat"))
    elif args.full:
        problems.append("--full: only with --out (it chooses the model written)")
    raise_problems(problems)
    settings = _settings(args)
    linear, operating = _linear_model(args)
    reduced = reduce_linear_model(linear, settings)
    report = reduced.report
    text = (_head(operating, linear.n_states)
            + f"\nbalanced truncation: {reduced.n_states} of {linear.n_states} states; largest "
            f"relative FRF error over {report['band_hz'][0]:g}-{report['band_hz'][1]:g} Hz "
            f"{report['max_relative_error']:.3g} (target {report['target_error']:g})\n"
            + table([[pair, error] for pair, error in report["per_pair"].items()],
                    ["input->output", "max rel. error"]))
    data = {**reduced.summary(), "operating_point": operating}
    output = Output(text=text, data=data)
    if out is not None:
        written = linear if args.full else reduced
        with writing("--out", out):
            path = (save_inplane_npz if out.suffix.lower() == ".npz" else save_inplane_mat)(
                written, out)
        output.data["file"] = str(path)
        output.written.append(path)
    return output
