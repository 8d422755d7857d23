"""Figures from result objects (matplotlib, imported here only; the Agg backend, no display).

- :func:`plot_bode`: co-simulated H1 against the full-model and spring-damper references, with
  phase and coherence, one column per ride transfer function;
- :func:`plot_road_run`: road, rim load and contact force over time, loss of contact shaded;
- :func:`plot_road_psd`: a generated ISO 8608 road against its target and Welch's band;
- :func:`plot_sweep`: how body bounce, wheel hop and the lowest tire mode move in a sweep.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .quarter_car import RIDE_LABELS, RIDE_OUTPUTS, RIDE_UNITS

FACTOR_UNITS = {"load": "N", "speed": "m/s", "inflation_pressure": "Pa", "n_elements": "-",
                "body_mass_kg": "kg", "wheel_mass_kg": "kg"}
COLOURS = {"cosim": "#1f77b4", "full": "#111111", "spring": "#d62728", "band": "#bbbbbb"}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path) -> Path:
    """Write the figure, published whole (tire_fmu.publish.save_figure)."""
    from tire_fmu.publish import save_figure

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path, dpi=110, bbox_inches="tight")
    _pyplot().close(fig)
    return path


def _phase_deg(h):
    """Wrapped phase with a gap where it wraps, so no vertical line joins -180 and 180."""
    phase = np.degrees(np.angle(h))
    jumps = np.flatnonzero(np.abs(np.diff(phase)) > 180)
    return np.insert(phase.astype(float), jumps + 1, np.nan), jumps + 1


def _with_gaps(x, positions):
    return np.insert(np.asarray(x, dtype=float), positions, np.nan)


#: Coherence panels are drawn only where some line falls below this: a noise-free periodic
#: multisine gives coherence 1 to within 1e-3, and four flat panels say nothing (the note
#: under the figure gives the lowest value instead).
COHERENCE_SHOWN_BELOW = 0.99
#: Half-width of the shaded band of the deviation panels: the acceptance limit, dB.
DEVIATION_BAND_DB = 1.0


def plot_bode(estimate, full, spring, agreements, path, title: str = "") -> Path:
    """Panels for each of :data:`RIDE_OUTPUTS`: |H| (dB), phase, the co-simulation's
    deviation from the full-model reference (dB) and, if any line's coherence is below
    :data:`COHERENCE_SHOWN_BELOW`, the coherence; one legend for the whole figure.

    ``full`` and ``spring`` are :class:`~vehicle_demo.quarter_car.RideResponse` on any grid
    (a fine log grid draws smooth curves; the deviation panel interpolates ``full``'s
    log-magnitude to the lines); ``agreements`` from :func:`~vehicle_demo.transfer.agreement`
    give the numbers in the titles.
    """
    plt = _pyplot()
    lowest = min(float(np.min(estimate.coherence[name])) for name in RIDE_OUTPUTS)
    with_coherence = lowest < COHERENCE_SHOWN_BELOW
    ratios = [3, 1.8, 1.2, 1.0] if with_coherence else [3, 1.8, 1.2]
    fig, axes = plt.subplots(len(ratios), 4, figsize=(18, 3.1 * sum(ratios) / 1.7 + 1.2),
                             sharex=True, gridspec_kw={"height_ratios": ratios})
    f_lo, f_hi = estimate.freqs_hz.min(), estimate.freqs_hz.max()
    for col, name in enumerate(RIDE_OUTPUTS):
        mag, phase, dev = axes[:3, col]
        coh = axes[3, col] if with_coherence else None
        h1 = estimate.h1[name]
        mag.semilogx(estimate.freqs_hz, 20 * np.log10(np.abs(h1)), "o", color=COLOURS["cosim"],
                     ms=3, alpha=0.35, mew=0, label="co-simulation H1 (two FMUs)", zorder=1)
        wrapped, gaps = _phase_deg(h1)
        phase.semilogx(_with_gaps(estimate.freqs_hz, gaps), wrapped, "o",
                       color=COLOURS["cosim"], ms=2.5, alpha=0.35, mew=0, zorder=1)
        for response, colour, style, label in (
            (spring, COLOURS["spring"], "--", "spring-damper tire (reference)"),
            (full, COLOURS["full"], "-", "full ring tire (reference)"),
        ):
            mag.semilogx(response.freqs_hz, 20 * np.log10(np.abs(response[name])), style,
                         color=colour, lw=1.0, label=label, zorder=2)
            wrapped, gaps = _phase_deg(response[name])
            phase.semilogx(_with_gaps(response.freqs_hz, gaps), wrapped, style, color=colour,
                           lw=0.9, zorder=2)
        reference_db = np.interp(np.log(estimate.freqs_hz), np.log(full.freqs_hz),
                                 20 * np.log10(np.abs(full[name])))
        a = agreements[name]
        deviation = 20 * np.log10(np.abs(h1)) - reference_db
        # the acceptance's points: coherent, and above 1 % (-40 dB) of the reference's peak
        compared = (estimate.coherence[name] > 0.95) & (reference_db > reference_db.max() - 40)
        dev.semilogx(estimate.freqs_hz[~compared], deviation[~compared], ".", color="0.7",
                     ms=2, label="not compared")
        dev.semilogx(estimate.freqs_hz[compared], deviation[compared], ".",
                     color=COLOURS["cosim"], ms=2, label="compared")
        dev.axhspan(-DEVIATION_BAND_DB, DEVIATION_BAND_DB, color="#2ca02c", alpha=0.08, lw=0)
        dev.set_ylim(-1.5 * DEVIATION_BAND_DB, 1.5 * DEVIATION_BAND_DB)
        if coh is not None:
            coh.semilogx(estimate.freqs_hz, estimate.coherence[name], ".",
                         color=COLOURS["cosim"], ms=2)
            coh.axhline(0.95, color="0.4", ls=":", lw=1)
            coh.set_ylabel("coherence")
            coh.set_ylim(0.9, 1.005)
        mag.set_title(f"{RIDE_LABELS[name]}\nmax |ΔH| = {a.max_deviation_db:.2f} dB over "
                      f"{a.points_compared}/{a.points_total} lines", fontsize=10)
        mag.set_ylabel(f"|H| [dB re 1 {RIDE_UNITS[name]}]")
        phase.set_ylabel("phase [deg]")
        phase.set_yticks([-180, -90, 0, 90, 180])
        phase.set_ylim(-190, 190)
        dev.set_ylabel("co-sim − full [dB]")
        axes[-1, col].set_xlabel("frequency [Hz]")
        for ax in axes[:, col]:
            ax.grid(True, which="both", alpha=0.3)
            ax.set_xlim(f_lo, f_hi)
    # one legend for all panels, in a row above them: the curves are the same in every column
    handles, labels = axes[0, 0].get_legend_handles_labels()
    more_handles, more_labels = axes[2, 0].get_legend_handles_labels()
    fig.legend(handles + more_handles, labels + [f"deviation, {x} line" for x in more_labels],
               loc="upper center", ncol=len(labels) + len(more_labels), fontsize=11,
               markerscale=2.5, frameon=False, bbox_to_anchor=(0.5, 0.955))
    if title:
        fig.suptitle(title, fontsize=12, y=0.995)
    fig.tight_layout(rect=(0, 0.025, 1, 0.93))
    note = ("compared: lines with coherence > 0.95 and |H| above 1 % of the reference's peak; "
            f"shaded band ±{DEVIATION_BAND_DB:g} dB (the acceptance limit)")
    if not with_coherence:
        note += f"; coherence ≥ {np.floor(lowest * 1e4) / 1e4:.4f} at every line (not drawn)"
    fig.text(0.5, 0.004, note, ha="center", fontsize=10, color="0.3")
    return _save(fig, path)


#: Colour of the intervals in which the tire FMU reports in_contact = false.
LOST_CONTACT_COLOUR = "#ffb3b3"


def _shade_lost_contact(ax, time, in_contact):
    lost = ~np.asarray(in_contact, dtype=bool)
    if not lost.any():
        return False
    edges = np.flatnonzero(np.diff(np.r_[0, lost.astype(int), 0]))
    for start, stop in zip(edges[::2], edges[1::2]):
        ax.axvspan(time[start], time[min(stop, len(time) - 1)], color=LOST_CONTACT_COLOUR,
                   lw=0)
    return True


def plot_road_run(result, path, title: str = "") -> Path:
    """Road and wheel motion, rim load and contact force (totals), body acceleration."""
    plt = _pyplot()
    t = result.time_s
    fig, (road, force, acc) = plt.subplots(3, 1, figsize=(12, 9), sharex=True,
                                           gridspec_kw={"height_ratios": [1, 1.6, 1]})
    lost = False
    for ax in (road, force, acc):
        lost = _shade_lost_contact(ax, t, result.in_contact) or lost
    road.plot(t, 1e3 * result.road_z_m, color="0.5", lw=1,
              label="road height (contact zone front)")
    road.plot(t, 1e3 * result.wheel_z_m, color=COLOURS["cosim"], lw=1, label="wheel")
    road.plot(t, 1e3 * result.body_z_m, color="#2ca02c", lw=1.4, label="body")
    road.set_ylabel("displacement [mm]")
    road.legend(loc="upper right", fontsize=8, ncol=3)
    force.plot(t, 1e-3 * result.rim_Fz_n, color="#ff7f0e", lw=1, label="rim load (tire on rim)")
    force.plot(t, 1e-3 * result.contact_Fz_n, color=COLOURS["full"], lw=0.7, alpha=0.8,
               label="contact force (road on tire)")
    force.axhline(1e-3 * result.static_load_n, color="0.3", ls="--", lw=1,
                  label=f"static load {result.static_load_n / 1e3:.1f} kN")
    force.axhline(0.0, color="#d62728", ls=":", lw=1)
    force.set_ylabel("vertical force [kN]")
    note = ("shaded: tire FMU reports in_contact = false "
            f"({100 * result.contact_lost_fraction:.2f} % of the time)" if lost
            else "in contact throughout (in_contact = true)")
    force.legend(loc="upper right", fontsize=8, title=note, title_fontsize=8)
    acc.plot(t, result.body_az_m_s2, color="#2ca02c", lw=1, label="body")
    acc.set_ylabel("body acceleration [m/s²]")
    acc.set_xlabel("time [s]")
    for ax in (road, force, acc):
        ax.grid(True, alpha=0.3)
        ax.set_xlim(t[0], t[-1])
    if title:
        fig.suptitle(title, fontsize=12)
    fig.tight_layout()
    return _save(fig, path)


def plot_road_psd(n_cycles_per_m, psd_m3, spectrum, band, path, title: str = "") -> Path:
    """Welch estimate of a generated road against the ISO 8608 target and the chi-square band
    (``band`` = (low, high) factors on the target)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 5))
    target = spectrum.psd_m3(n_cycles_per_m)
    inside = target > 0
    ax.fill_between(n_cycles_per_m[inside], band[0] * target[inside], band[1] * target[inside],
                    color=COLOURS["band"], alpha=0.6, label="95 % band of Welch's estimate")
    ax.loglog(n_cycles_per_m[inside], psd_m3[inside], color=COLOURS["cosim"], lw=1,
              label="generated road (Welch)")
    ax.loglog(n_cycles_per_m[inside], target[inside], color=COLOURS["full"], lw=1.5,
              label=f"ISO 8608 class {spectrum.road_class}, w = {spectrum.waviness:g}")
    ax.set_xlabel("spatial frequency n [cycles/m]")
    ax.set_ylabel("G_d(n) [m³]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=9)
    ax.set_title(title or "road displacement PSD")
    fig.tight_layout()
    return _save(fig, path)


def plot_sweep(table, factor: str, path, title: str = "") -> Path:
    """Body bounce, wheel hop and the lowest tire mode against one factor: co-simulation
    (markers) and full-model reference (lines), one series per combination of the others."""
    plt = _pyplot()
    ok = table[table["status"] == "ok"]
    others = [c for c in table.columns[: list(table.columns).index("status")] if c != factor]
    groups = list(ok.groupby(others)) if others else [((), ok)]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    for ax, (column, ref, label) in zip(axes, (
        ("body_bounce_hz", "ref_body_bounce_hz", "body bounce"),
        ("wheel_hop_hz", "ref_wheel_hop_hz", "wheel hop"),
        ("tire_mode_hz", "ref_tire_mode_hz", "lowest tire mode (first rim-load peak above 25 Hz)"),
    )):
        for key, group in groups:
            group = group.sort_values(factor)
            key = key if isinstance(key, tuple) else (key,)
            name = ", ".join(f"{o}={v:g}" for o, v in zip(others, key)) or "co-simulation"
            line, = ax.plot(group[factor], group[column], "o", ms=6, label=name)
            ax.plot(group[factor], group[ref], "-", color=line.get_color(), lw=1, alpha=0.7)
        ax.set_title(label, fontsize=10)
        ax.set_xlabel(f"{factor} [{FACTOR_UNITS[factor]}]" if factor in FACTOR_UNITS
                      else factor)
        ax.set_ylabel("frequency [Hz]")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.text(0.99, -0.02, "markers: co-simulation (two FMUs); lines: the car on the full "
             "ring model", ha="right", fontsize=9, color="0.3")
    failed = table[table["status"] != "ok"]
    if len(failed):
        fig.text(0.01, -0.02, f"{len(failed)} failed point(s), see the table's 'error' column",
                 color="#d62728", fontsize=9)
    if title:
        fig.suptitle(title, fontsize=12)
    fig.tight_layout()
    return _save(fig, path)


def plot_contact_events(events, runs, path, title: str = "") -> Path:
    """One column per event (road profile at the zone front): rim load, contact force and
    footprint length against time, unilateral contact solid, linear contact dashed."""
    plt = _pyplot()
    names = list(events)
    fig, axes = plt.subplots(4, len(names), figsize=(5 * len(names), 10), sharex="col",
                             gridspec_kw={"height_ratios": [0.7, 1.2, 1.2, 0.8]},
                             squeeze=False)
    from matplotlib.patches import Patch

    styles = {"unilateral": dict(color=COLOURS["cosim"], lw=1.2, ls="-"),
              "linear": dict(color="#d62728", lw=1.0, ls="--")}
    shaded = False
    for col, name in enumerate(names):
        profile = events[name]
        road, rim, contact, length = axes[:, col]
        road.plot(profile.time_s, 1e3 * profile.height_m, color="0.4", lw=1)
        road.set_title(name, fontsize=10)
        for law, style in styles.items():
            run = runs[(name, law)]
            rim.plot(run.time_s, 1e-3 * run.rim_Fz_n, label=f"{law} contact", **style)
            contact.plot(run.time_s, 1e-3 * run.contact_Fz_n, **style)
            length.plot(run.time_s, 100 * run.contact_length_m, **style)
            if law == "unilateral":
                shaded = _shade_lost_contact(contact, run.time_s, run.in_contact) or shaded
        contact.axhline(0.0, color="k", lw=0.8)
        for ax in axes[:, col]:
            ax.grid(True, alpha=0.3)
        length.set_xlabel("time [s]")
    axes[0, 0].set_ylabel("road at zone front [mm]")
    axes[1, 0].set_ylabel("rim load [kN]")
    axes[2, 0].set_ylabel("contact force [kN]")
    axes[3, 0].set_ylabel("footprint length [cm]")
    handles, labels = axes[1, 0].get_legend_handles_labels()
    if shaded:
        handles.append(Patch(color=LOST_CONTACT_COLOUR, lw=0))
        labels.append("shaded: the unilateral contact's tread is off the road "
                      "(in_contact = false)")
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=10,
               bbox_to_anchor=(0.5, -0.01))
    if title:
        fig.suptitle(title, fontsize=12)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    return _save(fig, path)


def plot_braking(runs, steady_slip_ratio: float, path) -> Path:
    """The braking runs: Fx and Fz at the axle, the slip beside the steady solve's, and the
    wheel's and the vehicle's speed, against time, one colour per road."""
    plt = _pyplot()
    fig, axes = plt.subplots(4, 1, figsize=(8.5, 10), sharex=True)
    fx, fz, slip, speed = axes
    for i, run in enumerate(runs):
        colour = f"C{i}"
        fx.plot(run.time_s, run.fx_n / 1e3, color=colour, lw=0.9, label=run.name)
        fz.plot(run.time_s, run.fz_n / 1e3, color=colour, lw=0.9)
        slip.plot(run.time_s, 100 * run.slip_ratio, color=colour, lw=0.9)
        speed.plot(run.time_s, run.wheel_speed_m_s, color=colour, lw=0.9)
        speed.plot(run.time_s, run.vehicle_speed_m_s, color=colour, lw=1.6, ls="--")
    slip.axhline(100 * steady_slip_ratio, color="k", lw=0.8, ls=":",
                 label="steady rolling solve")
    fx.set_ylabel("Fx at the axle [kN]")
    fz.set_ylabel("Fz at the axle [kN]")
    slip.set_ylabel("slip ratio [%]")
    speed.set_ylabel("speed [m/s]\n(wheel spin·R solid, vehicle dashed)")
    speed.set_xlabel("time [s]")
    fx.legend(loc="lower left", fontsize=8)
    slip.legend(loc="lower left", fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    fx.set_title("Braking quarter car, in-plane tire")
    return _save(fig, path)
