"""Figures from result objects (matplotlib, imported lazily; never inside the numerics)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .publish import save_figure


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")  # files only: no display on servers and CI
    import matplotlib.pyplot as plt

    return plt


def plot_mode_shapes(result, path: Path, max_modes: int = 12, scale: float = 0.25) -> Path:
    """Polar mode shapes as the paper's Figs. 12-16: tread outside, sidewall inside.

    Radii are drawn relative to the undeformed tread (1) and sidewall (0.6) circles; each shape
    is scaled so its largest displacement is ``scale``. Complex (rolling) shapes show the real
    part. θ = 0 (contact centre) is at the bottom.
    """
    plt = _pyplot()
    count = min(max_modes, len(result.modes))
    cols = min(4, max(count, 1))
    rows = max(1, int(np.ceil(count / cols)))
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.4 * rows),
                             subplot_kw={"projection": "polar"}, squeeze=False)
    n_el = result.grid.n_elements
    order = np.argsort(result.grid.theta)
    th = np.r_[result.grid.theta[order], result.grid.theta[order][0]]  # closed curve
    for ax in axes.ravel()[count:]:
        ax.set_visible(False)
    for i, ax in zip(range(count), axes.ravel()):
        shape = np.real(result.shapes[:, i])
        peak = np.max(np.abs(shape)) or 1.0
        tread = shape[:n_el] / peak * scale
        side = shape[n_el:] / peak * scale
        tr = np.r_[tread[order], tread[order][0]]
        sw = np.r_[side[order], side[order][0]]
        ax.plot(th, np.ones_like(th), color="0.8", lw=0.8)
        ax.plot(th, 0.6 * np.ones_like(th), color="0.8", lw=0.8)
        ax.plot(th, 1.0 + tr, color="C0", lw=1.5, label="tread")
        ax.plot(th, 0.6 + sw, color="C3", lw=1.2, label="sidewall")
        ax.set_theta_zero_location("S")
        ax.set_ylim(0, 1.0 + 1.4 * scale)
        ax.set_xticks([])
        ax.set_yticks([])
        m = result.modes[i]
        label = m.symmetry or m.direction or ""
        ax.set_title(f"{m.frequency_hz:.1f} Hz  n={m.order} {m.phase} {label}".strip(),
                     fontsize=9)
    axes.ravel()[0].legend(loc="upper left", fontsize=7, bbox_to_anchor=(-0.15, 1.15))
    summary = result.model_summary or {}
    fig.suptitle(
        f"Mode shapes (radial, real part; contact centre θ = 0 at the bottom): "
        f"N = {result.grid.n_elements}, patch length "
        f"{summary.get('patch_length_m', 0.0) * 100:.3g} cm, "
        f"speed {summary.get('speed_m_s', 0.0):g} m/s",
        fontsize=11,
    )
    fig.tight_layout()
    return _save(fig, plt, path, dpi=120)


# --------------------------------------------------------------------------------------------
# Study figures. Each takes a result object from :mod:`tire_fmu.core.studies` (or the core's
# dispersion and modal results) and writes one file; colours follow the order |n| throughout.


def _order_colours(plt, orders):
    top = max(int(np.max(np.abs(orders))), 1)
    cmap = plt.get_cmap("viridis")
    return lambda n: cmap(0.9 * abs(int(n)) / top)


def _order_colourbar(plt, fig, ax, top: int) -> None:
    from matplotlib.colors import Normalize

    # Same mapping as _order_colours: |n| -> viridis(0.9 |n| / top).
    mappable = plt.cm.ScalarMappable(norm=Normalize(0.0, top / 0.9), cmap="viridis")
    bar = fig.colorbar(mappable, ax=ax, pad=0.01, fraction=0.04)
    bar.set_ticks(range(0, top + 1))
    bar.ax.set_ylim(0, top)
    bar.set_label("order |n|")


def _save(fig, plt, path, dpi: int = 130) -> Path:
    """Write the figure (its format from the extension), published whole: a figure that fails
    part-way leaves the previous file."""
    path = Path(path)
    save_figure(fig, path, dpi=dpi)
    plt.close(fig)
    return path


def _span(values) -> str:
    values = np.asarray(values)
    low, high = values.min(), values.max()
    return f"{low:g}" if low == high else f"{low:g}-{high:g}"


def plot_convergence(result, path: Path) -> Path:
    """The paper's Fig. 14: FDM frequencies against N with the exact roots as horizontal lines
    (in-phase, out-of-phase), and the relative error on log-log axes with a δθ² guide."""
    plt = _pyplot()
    colour = _order_colours(plt, result.orders)
    counts = result.element_counts
    fig, axes = plt.subplots(1, 3, figsize=(15, 5))
    for ax, phase, name in zip(axes[:2], ("in", "out"), ("in-phase", "out-of-phase")):
        fdm, exact = result.frequencies_hz(phase), result.exact_hz(phase)
        for j, n in enumerate(result.orders):
            ax.axhline(exact[j], color=colour(n), lw=0.8, ls=":")
            ax.plot(counts, fdm[:, j], "o-", color=colour(n), ms=3.5, lw=1.2, label=f"n = {n}")
        ax.set_xscale("log")
        ax.set_xticks(counts, [str(c) for c in counts], fontsize=8)
        ax.minorticks_off()
        ax.set_xlabel("number of elements N")
        ax.set_ylabel("natural frequency [Hz]")
        ax.set_title(f"{name}: FDM (o) and exact eq. 12 (dotted)", fontsize=10)
        ax.grid(alpha=0.3)
    # the orders' legend goes below the panels: inside, it hid the lowest orders' curves
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 13), fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, 0.0))
    ax = axes[2]
    for phase, style in (("in", "o-"), ("out", "s--")):
        error = np.abs(result.relative_error(phase)) * 100.0
        for j, n in enumerate(result.orders):
            shown = np.isfinite(error[:, j]) & (error[:, j] > 1e-9)
            if shown.any():
                ax.loglog(counts[shown], error[shown, j], style, color=colour(n), ms=3, lw=1)
    # δθ² guide drawn above every curve, anchored at the finest mesh's largest error.
    finest = np.nanmax(np.abs(np.r_[result.relative_error("in")[-1],
                                    result.relative_error("out")[-1]])) * 100.0
    if np.isfinite(finest) and finest > 0:
        guide = 3.0 * finest * (counts[-1] / counts.astype(float)) ** 2
        ax.loglog(counts, guide, "k-", lw=2.2, alpha=0.6, label="slope 2 in δθ (∝ N⁻²)")
    ax.plot([], [], "o-", color="0.4", label="in-phase")
    ax.plot([], [], "s--", color="0.4", label="out-of-phase")
    slopes = [s for p in ("in", "out") for s in result.convergence_order(p) if np.isfinite(s)]
    if slopes:
        ax.text(0.03, 0.03, f"observed order {min(slopes):.2f}-{max(slopes):.2f}",
                transform=ax.transAxes, fontsize=9)
    ax.set_xticks(counts, [str(c) for c in counts], fontsize=8)
    ax.minorticks_off()
    ax.set_xlabel("number of elements N")
    ax.set_ylabel("|FDM - exact| / exact [%]")
    ax.set_title("relative error", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    fig.suptitle(
        f"FDM convergence, undeformed tire at rest (N = {_span(counts)}, "
        f"patch length 0 cm, speed 0 m/s, orders n = {_span(result.orders)})"
    )
    rows = -(-len(labels) // 13)
    fig.tight_layout(rect=(0, 0.05 * rows, 1, 1))
    return _save(fig, plt, path)


def plot_patch_sweep(result, path: Path) -> Path:
    """The paper's Fig. 17: rise of each split member over the undeformed tire against patch
    length; symmetric (antinode at the patch centre) solid, antisymmetric (node there) dashed."""
    plt = _pyplot()
    colour = _order_colours(plt, result.orders)
    phases = result.phases
    fig, axes = plt.subplots(1, len(phases), figsize=(7.5 * len(phases), 6.4), squeeze=False)
    length_cm = result.lengths_m * 100.0
    for ax, phase in zip(axes[0], phases):
        sym = result.shift_percent("symmetric", phase)
        anti = result.shift_percent("antisymmetric", phase)
        for j, n in enumerate(result.orders):
            f0 = result.undeformed_hz[phase][j]
            ax.plot(length_cm, sym[:, j], "-", color=colour(n), lw=1.6,
                    label=f"n = {n} ({f0:.1f} Hz)")
            ax.plot(length_cm, anti[:, j], "--", color=colour(n), lw=1.3)
        ax.plot([], [], "-", color="0.3",
                label="symmetric member: antinode at the patch centre, stiffened")
        ax.plot([], [], "--", color="0.3",
                label="antisymmetric member: node at the patch centre, barely moves")
        if length_cm.min() <= 20.4 <= length_cm.max():
            ax.axvline(20.4, color="0.5", lw=0.8, ls=":")
            ax.text(20.9, ax.get_ylim()[1] * 0.97, "20.4 cm (paper)", fontsize=8, va="top",
                    color="0.4")
        ax.set_xlabel("contact patch length [cm]")
        ax.set_ylabel("frequency shift over the undeformed tire [%]")
        branch = "in-phase" if phase == "in" else "out-of-phase"
        ax.set_title(f"{branch} modes", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2,
                  frameon=False)  # below the axes, off the curves
    fig.suptitle(
        f"Split of the mode pairs by the contact patch\nN = {result.n_elements}, patch length "
        f"{_span(np.round(length_cm, 2))} cm, speed 0 m/s", fontsize=11,
    )
    fig.tight_layout()
    return _save(fig, plt, path)


def _modes_by_order(modes, n_limit):
    """(k-index order, frequency, phase) of the complex modes with |order| <= n_limit."""
    rows = [(m.order, m.frequency_hz, m.phase) for m in modes.modes if abs(m.order) <= n_limit]
    return rows, len(modes.modes) - len(rows)


def plot_dispersion(dispersion, loaded=None, path: Path = Path("dispersion.png"),
                    reference=None) -> Path:
    """The paper's Fig. 18: ground-frame frequency against signed wavenumber k = n/R.

    ``dispersion`` is the undeformed tire at the spin (lines); ``loaded`` (a ModalResult of the
    loaded rolling model, or None) is drawn as markers at each mode's dominant signed order;
    ``reference`` (optional, the same at rest) is drawn in grey to show the asymmetry.
    n > 0 travels against the rotation (backward), n < 0 with it (forward).
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 5.8))
    k = dispersion.wavenumber_per_m
    nonzero = dispersion.orders != 0
    radius = float(np.median(dispersion.orders[nonzero] / k[nonzero])) if nonzero.any() else 1.0
    if reference is not None:
        for values in (reference.in_phase_hz, reference.out_of_phase_hz):
            ax.plot(reference.wavenumber_per_m, values, "-", color="0.75", lw=1.0)
        ax.plot([], [], "-", color="0.75", label="undeformed, at rest")
    ax.plot(k, dispersion.in_phase_hz, ".-", color="C0", lw=1.4, label="undeformed, in-phase")
    ax.plot(k, dispersion.out_of_phase_hz, ".-", color="C1", lw=1.4,
            label="undeformed, out-of-phase")
    title_patch = "patch length 0 cm (undeformed)"
    if loaded is not None:
        n_limit = int(np.max(np.abs(dispersion.orders)))
        rows, outside = _modes_by_order(loaded, n_limit)
        for phase, marker, colour, name in (("in", "o", "C0", "in-phase"),
                                            ("out", "s", "C1", "out-of-phase")):
            picked = [(n, f) for n, f, p in rows if p == phase]
            if picked:
                n, f = np.array(picked).T
                ax.plot(n / radius, f, marker, mfc="none", mec=colour, mew=1.3, ms=7,
                        label=f"loaded, {name} (dominant order)")
        patch = loaded.model_summary.get("patch_length_m", 0.0)
        title_patch = f"patch length {patch * 100:.3g} cm (markers) and 0 cm (lines)"
        if outside:
            ax.text(0.99, 0.01, f"{outside} loaded modes with |n| > {n_limit} not shown",
                    transform=ax.transAxes, ha="right", fontsize=8, color="0.4")
    ax.axvline(0.0, color="0.6", lw=0.6)
    ax.set_ylim(bottom=min(0.0, float(np.nanmin(dispersion.in_phase_hz))))
    spin = dispersion.spin_rad_s
    ax.set_xlabel("signed wavenumber k = n/R [1/m]  (k > 0: backward wave, k < 0: forward)")
    ax.set_ylabel("ground-frame frequency [Hz]")
    mesh = "continuum" if dispersion.n_elements is None else f"N = {dispersion.n_elements}"
    ax.set_title(
        f"Dispersion of the rolling tire: {mesh}, {title_patch}, speed {spin * radius:.4g} m/s "
        f"(Ω = {spin:.4g} rad/s)", fontsize=10,
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper center", ncol=2)
    fig.tight_layout()
    return _save(fig, plt, path)


def plot_speed_sweep(result, path: Path) -> Path:
    """The paper's Fig. 19: ground-frame frequencies against speed.

    Undeformed orders as lines (backward n > 0 solid, falling; forward n < 0 dashed, rising;
    out-of-phase branch faint), loaded in-phase modes as markers coloured by their dominant
    order, the rest of the loaded spectrum in grey, and the mesh's critical (standing-wave)
    speed as a vertical line.
    """
    plt = _pyplot()
    colour = _order_colours(plt, result.orders)
    fig, ax = plt.subplots(figsize=(9.5, 6.2))
    v = result.speeds_m_s
    for j, n in enumerate(result.orders):
        style = "-" if n >= 0 else "--"
        ax.plot(v, result.undeformed_in_phase_hz[:, j], style, color=colour(n), lw=1.3)
        ax.plot(v, result.undeformed_out_of_phase_hz[:, j], style, color=colour(n), lw=0.6,
                alpha=0.35)
    n_limit = int(np.max(np.abs(result.orders)))
    if result.loaded is not None:
        picked, band = [], []
        for speed, modes in zip(v, result.loaded):
            # the rest is dozens of modes a speed, mostly the lumped sidewall's band (with high
            # orders that fall towards zero near the critical speed): drawn as their span
            rest = []
            for m in modes.modes:
                if abs(m.order) <= n_limit and m.phase == "in":
                    picked.append((speed, m.frequency_hz, colour(m.order)))
                else:
                    rest.append(m.frequency_hz)
            if rest:
                band.append((speed, min(rest), max(rest)))
        if band:
            speeds, low, high = (np.array(x) for x in zip(*band))
            ax.fill_between(speeds, low, high, color="0.9", lw=0, zorder=1,
                            label=f"loaded, out-of-phase or |n| > {n_limit} (mostly the "
                            "sidewall band): the span of their frequencies")
        if picked:
            speeds, freqs, cols = zip(*picked)
            ax.scatter(speeds, freqs, s=16, c=list(cols), edgecolors="k", linewidths=0.3,
                       zorder=3, label=f"loaded in-phase, |n| <= {n_limit} (colour = |n|)")
    ax.plot([], [], "-", color="0.3", label="undeformed, n > 0 (backward)")
    ax.plot([], [], "--", color="0.3", label="undeformed, n < 0 (forward)")
    critical = result.critical_speed_m_s
    right = v.max()
    if np.isfinite(critical) and critical <= 1.15 * v.max():
        right = max(right, critical) * 1.02
        # named in the legend, not written over the data
        ax.axvline(critical, color="C3", lw=1.4, ls="-.",
                   label=f"critical (standing-wave) speed {critical:.3g} m/s")
    else:
        ax.plot([], [], color="C3", lw=1.4, ls="-.",
                label=f"critical (standing-wave) speed {critical:.3g} m/s (off scale)")
    ax.set_xlim(v.min(), right)
    ax.set_ylim(0.0, result.f_max_hz)
    ax.set_xlabel("speed V [m/s]")
    ax.set_ylabel("ground-frame frequency [Hz]")
    radius = result.radius_m
    secondary = ax.secondary_xaxis("top", functions=(lambda x: x / radius, lambda w: w * radius))
    secondary.set_xlabel("spin Ω [rad/s]")
    patch = (f"patch {result.patch_length_m * 100:.3g} cm (markers) and undeformed (lines)"
             if result.loaded is not None else "undeformed")
    damping = "damped" if result.damped else "undamped"
    ax.set_title(
        f"Ground-frame frequencies vs speed ({damping}): N = {result.n_elements}, {patch}, "
        f"speed {_span(np.round(v, 2))} m/s", fontsize=10,
    )
    ax.grid(alpha=0.3)
    # below the axes: inside, any corner hides curves at some speed
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.11), ncol=2,
              frameon=False)
    _order_colourbar(plt, fig, ax, n_limit)
    fig.tight_layout()
    return _save(fig, plt, path)


def plot_bode(responses, path: Path, title: str = "") -> Path:
    """Bode plot (magnitude, log-log, and phase) of frequency responses of one input/output
    pair, overlaid; with a reference first and others after, a third panel shows their
    relative error to it."""
    plt = _pyplot()
    reference = responses[0]
    panels = 3 if len(responses) > 1 else 2
    fig, axes = plt.subplots(panels, 1, figsize=(8, 2.6 * panels + 0.6), sharex=True)
    for k, frf in enumerate(responses):
        style = {"lw": 2.2, "color": "0.2"} if k == 0 else {"lw": 1.2, "ls": "--"}
        axes[0].loglog(frf.frequencies_hz, frf.magnitude, label=frf.label, **style)
        axes[1].semilogx(frf.frequencies_hz, frf.phase_deg, **style)
        if k > 0:
            axes[2].loglog(frf.frequencies_hz, frf.relative_error_to(reference),
                           label=frf.label, lw=1.2)
    axes[0].set_ylabel(f"|{reference.output} / {reference.input}| [{reference.unit}]")
    axes[1].set_ylabel("phase [deg]")
    if panels == 3:
        axes[2].set_ylabel("relative error [-]")
        axes[2].axhline(0.01, color="0.5", lw=0.8, ls=":")
        axes[2].text(reference.frequencies_hz[0], 0.0105, " 1 %", fontsize=8, color="0.4")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("frequency [Hz]")
    fig.suptitle(title or f"{reference.input} -> {reference.output}", fontsize=10)
    fig.tight_layout()
    return _save(fig, plt, path, dpi=120)


def plot_fit(result, path: Path) -> Path:
    """Measured against fitted natural frequencies per order (a :class:`FitResult`), with the
    relative residual of every mode below."""
    plt = _pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True,
                                      gridspec_kw={"height_ratios": [3, 1.4]})
    orders = np.array([m.order for m in result.modes])
    branches = np.array([m.branch for m in result.modes])
    residual = result.residual_percent
    for branch, colour, label in (("in", "C0", "in-phase"), ("out", "C3", "out-of-phase")):
        pick = branches == branch
        if not pick.any():
            continue
        order = np.argsort(orders[pick])
        n = orders[pick][order]
        top.plot(n, result.measured_hz[pick][order], "o", color=colour, mfc="none",
                 label=f"{label}, measured")
        top.plot(n, result.fitted_hz[pick][order], "-", marker=".", color=colour,
                 label=f"{label}, fitted")
        bottom.plot(n, residual[pick][order], "o-", color=colour, ms=4, label=label)
    bottom.axhline(0.0, color="0.5", lw=0.8)
    top.set_ylabel("natural frequency [Hz]")
    bottom.set_ylabel("fitted / measured - 1 [%]")
    bottom.set_xlabel("circumferential order n")
    top.legend(fontsize=8)
    top.grid(alpha=0.3)
    bottom.grid(alpha=0.3)
    model = "analytic ring" if result.n_elements is None else f"FDM N = {result.n_elements}"
    top.set_title(f"Fit of {', '.join(result.free)} ({model}, {result.criterion}); "
                  f"rms residual {100 * result.residual_rms:.2g} %", fontsize=10)
    fig.tight_layout()
    return _save(fig, plt, path, dpi=120)


def plot_footprint(model, patch, path: Path) -> Path:
    """The static contact: line pressure at each contact point, and the tread near the
    contact (rim frame, radial scale in mm) on the flat road, both against the x of the static
    tread, so a point's pressure stands above it (a pushing point lies on the road, where its
    ray meets it; the others sit above the road). The ring's nodes are marked on the tread."""
    plt = _pyplot()
    zone = patch.zone
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True,
                                      gridspec_kw={"height_ratios": [1, 1.3]})
    radius, height = zone.grid.radius_m, zone.grid.radius_m - patch.deflection_m
    w = (patch.footprint.tread_displacement_m if patch.footprint is not None
         else np.zeros(zone.n_points))
    r = radius + w
    x = -r * np.sin(zone.point_theta) * 1e3
    pressure = patch.forces_n / zone.point_arc_m / 1e3
    pushing = pressure > 0
    top.vlines(x[pushing], 0, pressure[pushing], color="tab:blue", lw=3)
    top.plot(x, pressure, "o", color="tab:blue", ms=4 if zone.points_per_node == 1 else 2)
    if patch.footprint is not None:
        for edge in (patch.footprint.front_edge_m, patch.footprint.rear_edge_m):
            top.axvline(edge * 1e3, color="0.5", ls=":", lw=1)
    top.set_ylabel("line pressure [kN/m]")
    kind = "prescribed patch" if patch.prescribed else "computed footprint"
    top.set_title(f"{kind}: {patch.load_n / 1e3:.3g} kN, deflection "
                  f"{patch.deflection_m * 1e3:.3g} mm, length {patch.length_m * 100:.3g} cm "
                  f"(N = {model.n_elements}, V = {model.speed_m_s:g} m/s)", fontsize=9)
    # tread on its ray at R + w from the rim centre, R - δ above the road
    theta = np.linspace(zone.theta[0], zone.theta[-1], 200)
    bottom.plot(-radius * np.sin(theta) * 1e3, (height - radius * np.cos(theta)) * 1e3,
                "--", color="0.6", label="undeformed tread")
    bottom.plot(x, (height - r * np.cos(zone.point_theta)) * 1e3, "-", color="tab:blue",
                lw=1, label=f"tread at the contact points ({zone.points_per_node} per node)")
    # the points that sit on a node (every m-th: m is odd, so one at each node's centre)
    on_node = np.isclose(np.mod(zone.point_theta / zone.grid.dtheta + 0.5, 1.0), 0.5,
                         atol=1e-9)
    bottom.plot(x[on_node], (height - r[on_node] * np.cos(zone.point_theta[on_node])) * 1e3,
                "o", color="tab:blue", ms=4, label="ring nodes (static)")
    bottom.axhline(0.0, color="k", lw=1.5, label="road")
    bottom.set_xlabel("x along the road [mm] (forward)")
    bottom.set_ylabel("height above road [mm]")
    bottom.set_ylim(-0.5 * patch.deflection_m * 1e3 - 1, 3 * patch.deflection_m * 1e3 + 5)
    bottom.legend(loc="upper center", fontsize=8, ncol=3)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    return _save(fig, plt, path)


def plot_cleat_convergence(result, path: Path) -> Path:
    """The rim load over an obstacle on each mesh (rim held at its static height) with the
    time the obstacle is under the tire shaded, the road's push below it, and the
    convergence table."""
    from .core.studies import CLEAT_TABLE_HEADER, cleat_table

    plt = _pyplot()
    counts = result.element_counts
    cmap = plt.get_cmap("viridis")
    colours = [cmap(0.85 * i / max(counts.size - 1, 1)) for i in range(counts.size)]
    fig = plt.figure(figsize=(13, 9.5))
    grid = fig.add_gridspec(3, 1, height_ratios=(2.2, 1.6, 1.1))
    rim_ax = fig.add_subplot(grid[0])
    contact_ax = fig.add_subplot(grid[1], sharex=rim_ax)
    t_ms = 1e3 * result.time_s
    start, end = 1e3 * result.under_tire_s[-1]
    for ax in (rim_ax, contact_ax):
        ax.axvspan(start, end, color="0.92", zorder=0)
        ax.grid(alpha=0.3)
    for i, n in enumerate(counts):
        label = (f"N = {n}, {result.points_per_node[i]} points per node "
                 f"({1e3 * result.point_arc_m[i]:.2g} mm)")
        width = 1.8 if i == counts.size - 1 else 1.1
        rim_ax.plot(t_ms, result.rim_fz_n[i] / 1e3, color=colours[i], lw=width, label=label)
        contact_ax.plot(t_ms, result.contact_fz_n[i] / 1e3, color=colours[i], lw=0.7)
    rim_ax.axhline(result.static_rim_fz_n[-1] / 1e3, color="0.5", lw=0.8, ls=":")
    rim_ax.set_ylabel("rim_Fz [kN]")
    rim_ax.legend(fontsize=8, loc="upper right")
    rim_ax.set_title(f"{result.obstacle.label} at {result.speed_m_s:g} m/s, rim held at its "
                     f"static height for {result.load_n / 1e3:.3g} kN (shaded: the obstacle "
                     f"under the tire; step {result.step_s * 1e6:g} µs)", fontsize=10)
    contact_ax.set_ylabel("contact_Fz [kN]")
    contact_ax.set_xlabel("time since the obstacle's first edge passed the contact centre [ms]")
    plt.setp(rim_ax.get_xticklabels(), visible=False)
    table_ax = fig.add_subplot(grid[2])
    table_ax.axis("off")
    rows, note = cleat_table(result.to_dict(histories=False))
    table = table_ax.table(cellText=rows, colLabels=list(CLEAT_TABLE_HEADER), loc="upper center",
                           cellLoc="center")
    table.auto_set_font_size(False)
    table.set_fontsize(8)
    table.scale(1.0, 1.25)
    table_ax.text(0.5, 0.0, note, transform=table_ax.transAxes, ha="center", fontsize=9)
    fig.tight_layout()
    return _save(fig, plt, path)


def plot_inplane_speed_sweep(sweep, path: Path, max_frequency_hz: float = 200.0,
                             critical_speed_m_s: float | None = None) -> Path:
    """The in-plane ring's ground-frame frequencies against speed, order by order: waves
    against the rotation solid, with it dashed (a pair splits as the tire rolls); the
    inextensible ring's split 2nΩ(n²-1)/(n²+1) about each order's lowest pair at rest dotted;
    the mesh's critical speed as a vertical line."""
    plt = _pyplot()
    colour = _order_colours(plt, sweep.orders)
    fig, ax = plt.subplots(figsize=(9.5, 6.2))
    v = sweep.speeds_m_s
    for j, n in enumerate(sweep.orders):
        for branch in range(sweep.against_hz.shape[2]):
            label = f"n = {n}" if branch == 0 else None
            ax.plot(v, sweep.against_hz[:, j, branch], "-", color=colour(n), lw=1.3,
                    label=label)
            ax.plot(v, sweep.with_hz[:, j, branch], "--", color=colour(n), lw=1.0)
        if n >= 2:
            rest = 0.5 * (sweep.against_hz[0, j, 0] + sweep.with_hz[0, j, 0])
            half = n * (n * n - 1) / (n * n + 1) * (v / sweep.radius_m) / (2 * np.pi)
            for sign in (1, -1):
                ax.plot(v, rest + sign * half, ":", color=colour(n), lw=0.8)
    if critical_speed_m_s is not None and critical_speed_m_s <= v.max():
        ax.axvline(critical_speed_m_s, color="k", lw=0.8, ls="-.")
        ax.text(critical_speed_m_s, 0.97 * max_frequency_hz, " critical speed", fontsize=8,
                va="top")
    ax.set_ylim(0.0, max_frequency_hz)
    ax.set_xlim(v.min(), v.max())
    ax.set_xlabel("speed [m/s]")
    ax.set_ylabel("ground-frame frequency [Hz]")
    ax.set_title(f"In-plane ring, rim held, N = {sweep.n_elements}: solid against the "
                 "rotation, dashed with it; dotted: the inextensible ring's split", fontsize=10)
    ax.legend(fontsize=8, ncol=sweep.orders.size, loc="upper center",
              bbox_to_anchor=(0.5, -0.09))
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return _save(fig, plt, path)


def plot_inplane_dispersion(sweep, path: Path, max_frequency_hz: float = 200.0) -> Path:
    """The in-plane ring's dispersion at the sweep's last speed: ground-frame frequency against
    the signed order n (n > 0 travels against the rotation, n < 0 with it; §8.6), every
    branch; the same at the sweep's first speed (rest) in grey, for the asymmetry."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 5.8))
    n = sweep.orders

    def signed(i):  # (signed orders, branches): against the rotation at +n, with it at -n
        return (np.concatenate([-n[::-1], n]),
                np.concatenate([sweep.with_hz[i, ::-1], sweep.against_hz[i]]))

    for i, style in ((0, dict(color="0.7", lw=1.0)), (-1, dict(lw=1.4))):
        orders, values = signed(i)
        for branch in range(values.shape[1]):
            colour = style.get("color", f"C{branch}")
            label = ("at rest" if i == 0 and branch == 0 else
                     f"branch {branch + 1}" if i != 0 else None)
            ax.plot(orders, values[:, branch], ".-", color=colour, lw=style["lw"], ms=4,
                    label=label)
    ax.axvline(0.0, color="0.6", lw=0.6)
    ax.xaxis.get_major_locator().set_params(integer=True)
    ax.set_ylim(0.0, max_frequency_hz)
    ax.set_xlabel("signed order n  (n > 0: wave against the rotation, n < 0: with it)")
    ax.set_ylabel("ground-frame frequency [Hz]")
    ax.set_title(f"In-plane ring, rim held, N = {sweep.n_elements}: dispersion at "
                 f"{sweep.speeds_m_s[-1]:.4g} m/s, at rest in grey", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper center", ncol=4)
    fig.tight_layout()
    return _save(fig, plt, path)


def plot_inplane_modes(result, path: Path, max_modes: int = 12, scale: float = 0.15) -> Path:
    """Deformed shapes of the in-plane ring: the tread line displaced radially and
    tangentially (x forward, z up, contact centre at the bottom), with ticks on material
    points so the tangential motion shows; the rim drawn where it is free."""
    plt = _pyplot()
    ring = result.ring
    count = min(max_modes, len(result.modes))
    cols = min(4, max(count, 1))
    rows = max(1, int(np.ceil(count / cols)))
    fig, axes = plt.subplots(rows, cols, figsize=(3.0 * cols, 3.1 * rows), squeeze=False)
    th = ring.theta
    radial = np.stack([-np.sin(th), -np.cos(th)])
    tangential = np.stack([-np.cos(th), np.sin(th)])
    for ax in axes.ravel()[count:]:
        ax.set_visible(False)
    for i, ax in zip(range(count), axes.ravel()):
        shape = result.shapes[:, i]
        w, v = shape[ring.field_slice("w")], shape[ring.field_slice("v")]
        peak = max(np.max(np.abs(w)), np.max(np.abs(v))) or 1.0
        xy = radial * (1.0 + w / peak * scale) + tangential * (v / peak * scale)
        ax.plot(*np.c_[radial, radial[:, :1]], color="0.8", lw=0.8)
        ax.plot(*np.c_[xy, xy[:, :1]], color="C0", lw=1.5)
        ticks = slice(None, None, max(1, ring.n_elements // 16))
        ax.plot(xy[0, ticks], xy[1, ticks], "o", color="C3", ms=2.5)
        ax.plot(radial[0, ticks], radial[1, ticks], "o", color="0.6", ms=2.0)
        ax.set_aspect("equal")
        ax.axis("off")
        m = result.modes[i]
        ax.set_title(f"{m.frequency_hz:.1f} Hz  n={m.order} {m.kind} {m.phase}".strip(),
                     fontsize=9)
    rim = "free rim" if ring.rim_free else "rim held"
    fig.suptitle(f"In-plane modes ({rim}, N = {ring.n_elements}; red: material points)",
                 fontsize=10)
    fig.tight_layout()
    return _save(fig, plt, path, dpi=120)


def plot_inplane_cleat(run, load_n: float, window, path: Path) -> Path:
    """The cleat test: Fx, Fz - load and My at the axle against time, and the spectra of Fx
    and Fz (Welch's estimate of the part after the start of rolling)."""
    from scipy.signal import welch

    plt = _pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6.5))
    t = run.time_s
    top.plot(t, run.rim_fx_n / 1e3, label="Fx")
    top.plot(t, (run.rim_fz_n - load_n) / 1e3, label="Fz - static load")
    top.set_xlabel("time [s]")
    top.set_ylabel("force at the axle [kN]")
    twin = top.twinx()
    twin.plot(t, run.rim_my_n_m / 1e3, color="C2", lw=0.8, label="My")
    twin.set_ylabel("My [kN m]", color="C2")
    top.legend(loc="upper left")
    top.grid(alpha=0.3)
    fs = 1.0 / (t[1] - t[0])
    for name, signal in (("Fx", run.rim_fx_n[window]), ("Fz", run.rim_fz_n[window])):
        freq, power = welch(signal - signal.mean(), fs=fs, nperseg=min(signal.size, 4096))
        bottom.semilogy(freq, power, label=name)
    bottom.set_xlim(0, 300)
    bottom.set_xlabel("frequency [Hz]")
    bottom.set_ylabel("PSD [N²/Hz]")
    bottom.legend()
    bottom.grid(alpha=0.3)
    fig.tight_layout()
    return _save(fig, plt, path, dpi=120)


def plot_road_profile(road, title: str, path: Path) -> Path:
    """A road profile as the tire reads it (a :class:`~tire_fmu.core.obstacles.ProfileRoad`):
    height against distance, the file's extent marked, the level road beyond it dashed."""
    plt = _pyplot()
    first, last = road.extent_m
    span = last - first
    margin = 0.05 * span
    fig, ax = plt.subplots(figsize=(8, 3.6))
    ax.plot(road.distances_m, road.heights_m * 1e3, lw=1.0, color="C0", label="road file")
    for edge, beyond in ((first, first - margin), (last, last + margin)):
        height = float(road.profile(edge)[0]) * 1e3
        ax.plot([edge, beyond], [height, height], ls="--", lw=1.0, color="C0",
                label="beyond: level at the end height" if edge == first else None)
        ax.axvline(edge, color="0.6", lw=0.8)
    low, high = road.heights_m.min() * 1e3, road.heights_m.max() * 1e3
    pad = 0.08 * (high - low) or 1.0
    ax.set_xlim(first - margin, last + margin)
    ax.set_ylim(low - pad, high + pad)
    ax.set_xlabel("distance along the road [m]")
    ax.set_ylabel("height [mm]")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    return _save(fig, plt, path)
