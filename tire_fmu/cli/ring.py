"""Ring-model commands: modes, analytic, patch."""

from __future__ import annotations

import argparse

import numpy as np

from ..core import analytic_modes, modal_analysis
from .common import (
    Output,
    add_contact_options,
    add_mesh_option,
    add_output_options,
    add_speed_options,
    add_tire_options,
    model_from_args,
    table,
    tire_from_args,
    write_plot,
)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "modes",
        help="natural frequencies, damping and labelled mode shapes",
        description="Modal analysis of the ring tire. At rest: real modes labelled by order, "
        "in/out-of-phase and (with a patch) symmetric/antisymmetric about the patch centre. "
        "Rolling (--speed > 0): complex ground-frame modes with signed order and direction.",
    )
    add_mesh_option(p)
    add_contact_options(p, "default 0: the undeformed tire")
    add_speed_options(p)
    p.add_argument("--fmax", metavar="HZ", type=float, default=300.0,
                   help="highest frequency listed in Hz (default 300)")
    add_tire_options(p)
    add_output_options(p)
    p.set_defaults(handler=run_modes)

    p = subparsers.add_parser(
        "analytic",
        help="closed-form frequencies of the undeformed ring (eq. 12)",
        description="Exact roots of eq. 12 per order n: in-phase and out-of-phase frequencies.",
    )
    p.add_argument("--nmax", metavar="N", type=int, default=12,
                   help="highest circumferential order n (default 12)")
    add_tire_options(p)
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_analytic)

    p = subparsers.add_parser(
        "patch",
        help="patch length, deflection and vertical stiffness for a load",
        description="Static contact: the patch length whose secant load K_v(L)·δ(L) equals the "
        "given load, with δ(L) the flat-road chord deflection and K_v the model's own static "
        "vertical stiffness.",
    )
    p.add_argument("--load", metavar="N", type=float, required=True,
                   help="static vertical load in N")
    add_mesh_option(p)
    add_speed_options(p)
    add_tire_options(p)
    add_output_options(p, plot=False)
    p.set_defaults(handler=run_patch)


def run_modes(args: argparse.Namespace) -> Output:
    if args.fmax is not None and not args.fmax > 0:
        from .common import CliError

        raise CliError(f"--fmax = {args.fmax:g} Hz: must be > 0")
    model = model_from_args(args, undeformed_default=True)
    result = modal_analysis(model, fmax_hz=args.fmax)
    rolling = model.speed_m_s > 0
    header = ["#", "f [Hz]", "order", "phase", "symmetry" if not rolling else "direction",
              "zeta"]
    rows = []
    for i, m in enumerate(result.modes):
        label = m.direction if rolling else m.symmetry
        rows.append([i + 1, m.frequency_hz, m.order, m.phase, label, m.damping_ratio])
    summary = model.summary()
    head = (
        f"{len(result.modes)} modes up to {args.fmax:g} Hz; N = {model.n_elements}, "
        f"patch {summary['patch_length_m'] * 100:.3g} cm, load {summary['load_n']:.4g} N, "
        f"speed {model.speed_m_s:g} m/s"
    )
    output = Output(text=head + "\n" + table(rows, header), data=result.to_dict())

    def draw(path):
        from ..plots import plot_mode_shapes

        return plot_mode_shapes(result, path)

    write_plot(args, output, draw)
    return output


def run_analytic(args: argparse.Namespace) -> Output:
    from .common import CliError

    if args.nmax < 0 or args.nmax > 10_000:
        raise CliError(f"--nmax = {args.nmax}: must be in [0, 10000]")
    tire = tire_from_args(args)
    result = analytic_modes(tire, np.arange(args.nmax + 1))
    rows = [[n, f_in, f_out] for n, f_in, f_out in
            zip(result.orders, result.in_phase_hz, result.out_of_phase_hz)]
    text = table(rows, ["n", "in-phase [Hz]", "out-of-phase [Hz]"])
    return Output(text=text, data=result.to_dict())


def run_patch(args: argparse.Namespace) -> Output:
    model = model_from_args(args, undeformed_default=False)
    data = model.summary()
    text = "\n".join([
        f"load                {data['load_n']:.6g} N",
        f"patch length        {data['patch_length_m'] * 100:.4g} cm "
        f"({data['patch_nodes']} nodes at N = {model.n_elements})",
        f"deflection          {data['deflection_m'] * 1000:.4g} mm",
        f"vertical stiffness  {data['vertical_stiffness_n_per_m'] / 1e6:.4g} MN/m",
    ])
    return Output(text=text, data=data)
