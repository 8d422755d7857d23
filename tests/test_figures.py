"""Figures say what they show: panels that share an axis share their data's extent, legends
leave the curves visible, shading is explained, and no output is drawn where it cannot be
(a footprint shorter than nothing). Checked on the figure objects (Agg backend)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from tire_fmu.core import OperatingPoint, TireParameters, build_model  # noqa: E402


def _captured(module, monkeypatch):
    """The figures a plot function of ``module`` makes, instead of saving them."""
    figures = []

    def keep(fig, *args):
        figures.append(fig)
        return args[-1]

    monkeypatch.setattr(module, "_save", keep)
    return figures


def _overlaps(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_the_convergence_legend_covers_no_panel(monkeypatch):
    """The orders' legend sat inside the in-phase panel, over its lowest curves (n = 0-2)."""
    from tire_fmu import plots
    from tire_fmu.core.studies import convergence_study

    figures = _captured(plots, monkeypatch)
    plots.plot_convergence(convergence_study(element_counts=(20, 40, 80), orders=range(6)),
                           "unused.png")
    (fig,) = figures
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    order_legends = [legend for legend in fig.legends + [ax.get_legend() for ax in fig.axes]
                     if legend is not None
                     and any(t.get_text() == "n = 0" for t in legend.get_texts())]
    assert len(order_legends) == 1
    box = order_legends[0].get_window_extent(renderer)
    for ax in fig.axes:
        assert not _overlaps(box, ax.get_window_extent(renderer)), ax.get_title()


def test_the_footprint_panels_draw_the_same_nodes_at_the_same_x(monkeypatch):
    """The pressure was drawn at the road points of the nodes' rays (out to ±250 mm), the
    tread at the nodes themselves (±237 mm): the same node at two x on one shared axis."""
    from tire_fmu import plots

    model = build_model(TireParameters(), OperatingPoint(load_n=27_700.0))
    figures = _captured(plots, monkeypatch)
    plots.plot_footprint(model, model.patch, "unused.png")
    (fig,) = figures
    top, bottom = fig.axes
    pressure = [line for line in top.get_lines() if line.get_marker() == "o"]
    tread = [line for line in bottom.get_lines()
             if line.get_label().startswith("tread at the contact points")]
    nodes = [line for line in bottom.get_lines() if line.get_label() == "ring nodes (static)"]
    assert len(pressure) == len(tread) == len(nodes) == 1
    assert np.array_equal(pressure[0].get_xdata(), tread[0].get_xdata())
    # every ring node is drawn on the tread, at one of the points' x
    assert set(nodes[0].get_xdata()) <= set(tread[0].get_xdata())
    assert len(nodes[0].get_xdata()) == np.count_nonzero(model.patch.zone.point_weight.max(
        axis=1) == 1.0)
    assert top.get_xlim() == bottom.get_xlim()


def _run(time, length, in_contact):
    from types import SimpleNamespace

    return SimpleNamespace(time_s=time, rim_Fz_n=np.full(time.size, 27e3),
                           contact_Fz_n=np.full(time.size, 27e3), contact_length_m=length,
                           in_contact=in_contact)


def test_contact_events_explain_their_shading(monkeypatch):
    from types import SimpleNamespace

    from vehicle_demo import plots

    time = np.linspace(0.0, 0.1, 101)
    lifted = time < 0.05
    events = {"pothole": SimpleNamespace(time_s=time, height_m=np.zeros(time.size))}
    runs = {("pothole", "unilateral"): _run(time, np.full(time.size, 0.1), ~lifted),
            ("pothole", "linear"): _run(time, np.full(time.size, 0.1), np.ones(time.size, bool))}
    figures = _captured(plots, monkeypatch)
    plots.plot_contact_events(events, runs, "unused.png")
    (fig,) = figures
    (legend,) = fig.legends
    labels = [t.get_text() for t in legend.get_texts()]
    shading = [handle for handle, label in zip(legend.legend_handles, labels)
               if "in_contact = false" in label]
    assert len(shading) == 1
    spans = [p for ax in fig.axes for p in ax.patches]
    assert spans and all(np.allclose(p.get_facecolor(), shading[0].get_facecolor())
                         for p in spans)


@pytest.mark.parametrize("depth_m", [0.05, 0.1])
def test_the_linear_contacts_footprint_is_never_negative(depth_m):
    """A two-sided spring can push from above the road (its damper), where the interpolated
    edges used to cross: contact_events.png drew the linear contact's footprint at -15 cm."""
    from tire_fmu.core import validate
    from tire_fmu.core.contact_dynamics import (
        ContactSettings,
        ContactSimulator,
        build_contact_model,
    )
    from vehicle_demo.road import pothole

    tire, op = validate({}, {"n_elements": 100, "speed_m_s": 10.0})
    lengths = {}
    for law in ("linear", "unilateral"):
        sim = ContactSimulator(build_contact_model(tire, op, settings=ContactSettings(law=law)))
        # 0.6 m: longer than the tread can bridge (a 0.3 m pothole carries it on its edges)
        profile = pothole(depth_m, 0.6, 10.0, 0.2, 1e-4, "rectangular", 0.5)
        lengths[law] = np.array([sim.step(1e-4, 0.0, 0.0, z, v)[4] for z, v in
                                 zip(profile.height_m[1:], profile.velocity_m_s[1:])])
    assert lengths["linear"].min() >= 0.0
    assert lengths["unilateral"].min() == 0.0  # it lifts off: a length of 0, as it should
    assert lengths["linear"].max() > 0.05


def test_the_ride_figure_draws_coherence_only_as_the_docs_say(monkeypatch):
    from vehicle_demo import plots
    from vehicle_demo.quarter_car import RIDE_OUTPUTS, RideResponse
    from vehicle_demo.transfer import FrfEstimate, agreement

    freqs = np.linspace(0.5, 300.0, 600)
    h = {name: 1.0 / (1.0 + 1j * freqs / 10.0) for name in RIDE_OUTPUTS}
    reference = RideResponse("reference", freqs, h)
    for lowest, panels in ((1.0, 3), (0.9, 4)):
        coherence = {name: np.r_[lowest, np.ones(freqs.size - 1)] for name in RIDE_OUTPUTS}
        estimate = FrfEstimate(freqs, h, coherence, 3)
        figures = _captured(plots, monkeypatch)
        plots.plot_bode(estimate, reference, reference, agreement(estimate, reference),
                        "unused.png")
        (fig,) = figures
        assert len(fig.axes) == 4 * panels
        noted = "(not drawn)" in " ".join(t.get_text() for t in fig.texts)
        assert noted == (lowest >= plots.COHERENCE_SHOWN_BELOW)
