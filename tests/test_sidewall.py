"""The sidewall tied to the tread above sidewall_max_order (issue 21): what it leaves alone
(the measured orders, the static compliance), what it fixes (a standing-wave speed that
converges with the mesh) and that every representation of it is the same model (continuum
closed form, per-order FDM, assembled nodal matrices)."""

from __future__ import annotations

import csv
from dataclasses import replace

import numpy as np
import pytest

from tire_fmu.core import dispersion
from tire_fmu.core.analytic import analytic_modes
from tire_fmu.core.discretisation import Grid
from tire_fmu.core.free_ring import ring_static_gain
from tire_fmu.core.model import build_model, structural_matrices
from tire_fmu.core.parameters import OperatingPoint, ParameterError, TireParameters
from tire_fmu.core.standing_waves import critical_speed
from tire_fmu.tire_files import read_tire_file, shipped_tire_path

TOP = 8  # the highest order GL073A_modes.csv holds
PAPER = TireParameters(sidewall_max_order=0.0)
TIED = replace(PAPER, sidewall_max_order=float(TOP))


def test_the_shipped_tied_tire_is_the_paper_tire_with_the_tie():
    assert read_tire_file("GL073A_tied").tire == TIED


def test_the_measured_orders_are_the_papers_within_1_percent():
    path = shipped_tire_path("GL073A").with_name("GL073A_modes.csv")
    rows = [row for row in csv.DictReader(line for line in path.open() if line[0] != "#")]
    orders = np.array([int(r["order"]) for r in rows])
    measured = np.array([float(r["frequency_hz"]) for r in rows])
    modes = analytic_modes(TIED, orders)
    model = np.where([r["branch"] == "in" for r in rows], modes.in_phase_hz,
                     modes.out_of_phase_hz)
    assert np.max(np.abs(model / measured - 1)) < 0.01
    assert orders.max() == TOP


def test_above_the_top_order_the_sidewall_band_is_gone():
    """Lumped: the in-phase branch flattens under the sidewall band, so its phase speed
    ωR/n falls to zero. Tied: it climbs with the tread (the sidewall rides on it), and the
    tie's own branch sits far above."""
    orders = np.arange(TOP + 1, 60)
    lumped, tied = analytic_modes(PAPER, orders), analytic_modes(TIED, orders)
    assert np.all(lumped.in_phase_hz < PAPER.sidewall_band_hz)
    speed = 2 * np.pi * tied.in_phase_hz * PAPER.R / orders
    assert speed.min() > 90.0  # the tread band's, about sqrt(P/(rhoA)) and more
    assert np.all(tied.out_of_phase_hz > 10 * tied.in_phase_hz)
    # a rigid sidewall share: the in-phase mode moves the sidewall by k_r1/(k_r1 + k_r2)
    share = PAPER.k_r1 / (PAPER.k_r1 + PAPER.k_r2)
    assert tied.in_phase_ratio == pytest.approx(share, rel=0.02)


@pytest.mark.parametrize("orders", [np.arange(0, 41)])
def test_the_fdm_symbols_tend_to_the_closed_form(orders):
    """Per-order FDM frequencies converge to the continuum closed form (written apart in
    analytic.py) at second order in the node spacing, tie and all."""
    exact = analytic_modes(TIED, orders)
    errors = []
    for n in (200, 400, 800):
        low, high = dispersion.body_frequencies(TIED, orders, 0.0, n)
        errors.append(max(np.max(np.abs(low / (2 * np.pi) / exact.in_phase_hz - 1)),
                          np.max(np.abs(high / (2 * np.pi) / exact.out_of_phase_hz - 1))))
    assert errors[-1] < 1e-2
    assert 3.5 < errors[0] / errors[1] < 4.5 and 3.5 < errors[1] / errors[2] < 4.5


@pytest.mark.parametrize("speed", [0.0, 20.0])
def test_the_assembled_matrices_are_the_per_order_model(speed):
    """Eigenvalues of the dense first-order form of the nodal M, C, K against the per-order
    2x2 problems (dispersion.eigenvalues): the circulant tie blocks are the same tie."""
    n = 48
    structure = structural_matrices(TIED, Grid(n, TIED.R), speed / TIED.R)
    m, c, k = (x.toarray() for x in (structure.mass, structure.damping, structure.stiffness))
    size = 2 * n
    a = np.zeros((2 * size, 2 * size))
    a[:size, size:] = np.eye(size)
    a[size:, :size] = -np.linalg.solve(m, k)
    a[size:, size:] = -np.linalg.solve(m, c)
    nodal = np.linalg.eigvals(a)
    per_order = dispersion.eigenvalues(TIED, np.arange(-n // 2 + 1, n // 2 + 1),
                                       speed / TIED.R, n).ravel()
    distance = [np.min(np.abs(nodal - s)) / abs(s) for s in per_order]
    assert max(distance) < 1e-10
    assert nodal.size == per_order.size


def test_the_tie_leaves_the_static_compliance_alone():
    """At rest the free ring's static state has the sidewall at its share of the tread, which
    the tie does not stretch: every static gain (rim, zone nodes) is the lumped sidewall's."""
    grid = Grid(200, PAPER.R)
    zone = np.arange(-12, 13) % 200
    lumped = ring_static_gain(PAPER, grid, 0.0, zone)
    tied = ring_static_gain(TIED, grid, 0.0, zone)
    assert np.max(np.abs(tied - lumped)) < 1e-9 * np.max(np.abs(lumped))
    a = build_model(PAPER, OperatingPoint(n_elements=200))
    b = build_model(TIED, OperatingPoint(n_elements=200))
    assert b.patch.length_m == pytest.approx(a.patch.length_m, rel=1e-9)
    assert b.patch.deflection_m == pytest.approx(a.patch.deflection_m, rel=1e-9)


def test_the_standing_wave_speed_converges_with_the_mesh():
    """Lumped: the critical speed falls as 1/N. Tied: it converges (second order, the
    convective symbol sin(nδθ)/δθ at the critical order) to the in-phase mode of the top
    order travelling at its phase speed."""
    meshes = (100, 200, 400, 800, 1600)
    tied = np.array([critical_speed(TIED, n).speed_m_s for n in meshes])
    lumped = np.array([critical_speed(PAPER, n).speed_m_s for n in meshes])
    assert lumped[0] / lumped[3] == pytest.approx(8.0, rel=0.05)
    assert abs(tied[0] / tied[3] - 1) < 0.05 and tied.min() > 40.0
    steps = np.abs(np.diff(tied))
    assert np.all(3.0 < steps[:-1] / steps[1:]) and np.all(steps[:-1] / steps[1:] < 5.0)
    assert {critical_speed(TIED, n).order for n in meshes} == {TOP}
    # the continuum value, from the closed form: V with ω_in(n=8, Ω) = nΩ, spin softening
    # and the tension ρA R²Ω² included, found here by bisection on the continuum symbols
    lo, hi = 1.0, 200.0
    for _ in range(80):
        spin = 0.5 * (lo + hi)
        low, _ = dispersion.body_frequencies(TIED, np.array([TOP]), spin, None)
        lo, hi = (spin, hi) if low[0] - TOP * spin > 0 else (lo, spin)
    assert tied[-1] == pytest.approx(lo * TIED.R, rel=2e-3)


def test_the_tied_tire_runs_the_fine_mesh_at_20_m_s():
    with pytest.raises(ParameterError, match="critical"):
        build_model(PAPER, OperatingPoint(n_elements=800, speed_m_s=20.0))
    model = build_model(TIED, OperatingPoint(n_elements=800, speed_m_s=20.0))
    assert model.critical_speed_m_s > 70.0


@pytest.mark.parametrize("value", [2.5, -1.0, 1e6])
def test_a_fractional_or_out_of_range_order_is_refused_by_name(value):
    with pytest.raises(ParameterError) as error:
        replace(PAPER, sidewall_max_order=value)
    text = str(error.value)
    assert "sidewall_max_order" in text and f"{value:g}" in text and "[0, 100000]" in text


def test_above_the_top_order_the_tread_band_is_the_classical_beam_under_tension():
    """With the sidewall riding on the tread at its static share r, the in-phase branch is a
    tensioned beam on the series spring with mass rhoA + r² m_s (Clark's beam model of tire
    critical speeds): c² = (P + EI n²/R² + k R²/n²)/(rhoA + r² m_s), up to the tie's finite
    stiffness (1/SIDEWALL_TIE_FACTOR)."""
    orders = np.arange(TOP + 1, 120)
    share = PAPER.k_r1 / (PAPER.k_r1 + PAPER.k_r2)
    series = PAPER.k_r1 * PAPER.k_r2 / (PAPER.k_r1 + PAPER.k_r2)
    beam = np.sqrt((PAPER.pretension_n + PAPER.EI * orders**2 / PAPER.R**2
                    + series * PAPER.R**2 / orders**2) / (PAPER.rhoA + share**2 * PAPER.m_s))
    model = 2 * np.pi * analytic_modes(TIED, orders).in_phase_hz * PAPER.R / orders
    assert np.max(np.abs(model / beam - 1)) < 0.02
