"""Figures from result objects (matplotlib, imported lazily; never inside the numerics)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


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
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
