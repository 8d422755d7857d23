"""The in-plane ring's ground-frame frequencies against speed (``speed_sweep``, ``tire-fmu
inplane-speed-sweep``) and at one speed against the signed order (``inplane-modes --speed``'s
dispersion): checked against the assembled rolling ring's spectrum solved whole, the ring at
rest, and Huang & Soedel's split of the inextensible ring."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg

from tire_fmu.cli import main
from tire_fmu.core.inplane import InPlaneRing, InPlaneTire, TangentialParameters
from tire_fmu.core.inplane_analytic import inextensible_split_factor
from tire_fmu.core.inplane_modes import order_frequencies_at_rest_hz, speed_sweep
from tire_fmu.core.parameters import TireParameters
from tire_fmu.tire_files import read_tire_file

PAPER = TireParameters(sidewall_max_order=0.0)


def assembled_frequencies_hz(model: InPlaneTire, n_elements: int, speed_m_s: float):
    """|Im s|/2π of every root of the whole rolling ring (rim held), from its dense M, C, K:
    no Fourier blocks, no orders."""
    ring = InPlaneRing(model, n_elements, spin_rad_s=speed_m_s / model.tire.R)
    size = ring.mass.shape[0]
    m_inv = np.linalg.inv(ring.mass)
    companion = np.block([[np.zeros((size, size)), np.eye(size)],
                          [-m_inv @ ring.stiffness, -m_inv @ ring.damping]])
    return np.sort(np.abs(scipy.linalg.eigvals(companion).imag)) / (2 * np.pi)


@pytest.mark.parametrize("speed", [0.0, 15.0])
def test_every_order_together_is_the_assembled_rolling_ring(speed):
    """All orders 0..N/2 both ways are the whole ring's spectrum (N = 24, damped)."""
    model, n = InPlaneTire(), 24
    sweep = speed_sweep(model, n, [speed], range(n // 2 + 1))
    parts = []
    for j, order in enumerate(sweep.orders):
        # order 0 and N/2 are their own conjugates: each root once
        both = order in (0, n // 2)
        parts += [sweep.against_hz[0, j]] + ([] if both else [sweep.with_hz[0, j]])
    ours = np.concatenate(parts)
    ours = np.sort(ours[np.isfinite(ours)])
    whole = assembled_frequencies_hz(model, n, speed)
    # the whole ring's roots come in conjugates s, s̄: one |Im s| per pair
    whole = whole[::2]
    np.testing.assert_allclose(ours, whole, rtol=1e-8, atol=1e-8 * whole.max())


def test_at_rest_both_directions_are_the_rest_frequencies():
    """The first speed 0: against and with the rotation equal, and (undamped) the order's
    frequencies at rest from its Hermitian pencil."""
    model = InPlaneTire(replace(TireParameters(), alpha=0.0, beta=0.0))
    sweep = speed_sweep(model, 60, [0.0, 10.0], range(7))
    np.testing.assert_allclose(sweep.against_hz[0], sweep.with_hz[0], rtol=1e-9)
    ring = InPlaneRing(model, 60)
    for j, n in enumerate(sweep.orders):
        rest = order_frequencies_at_rest_hz(ring, int(n))
        got = sweep.against_hz[0, j]
        np.testing.assert_allclose(got[np.isfinite(got)], rest[: np.isfinite(got).sum()],
                                   rtol=1e-9)
        assert sweep.split_hz(int(n))[0] < 1e-9


@pytest.mark.parametrize("order", [2, 4, 6])
def test_the_split_grows_with_speed_as_the_inextensible_rings(order):
    """Stiff membrane, no damping: the split at each speed within 3 % of 2nΩ(n²-1)/(n²+1)."""
    model = InPlaneTire(replace(PAPER, alpha=0.0, beta=0.0), TangentialParameters(EA=1e11),
                        sidewall_mass=False)
    speeds = np.array([1.0, 2.0, 4.0])
    sweep = speed_sweep(model, 400, speeds, [order])
    expected = 2 * speeds / model.tire.R * inextensible_split_factor(order) / (2 * np.pi)
    np.testing.assert_allclose(sweep.split_hz(order), expected, rtol=0.03)


def test_speed_sweep_command_gives_the_study_and_its_plot(capsys, tmp_path):
    plot = tmp_path / "sweep.png"
    assert main(["inplane-speed-sweep", "--elements", "40", "--speeds", "3", "--max-speed", "20",
                 "--nmax", "3", "--json", "--plot", str(plot)]) == 0
    data = json.loads(capsys.readouterr().out)
    shipped = read_tire_file("GL073A_inplane", warn=False)  # the command's default tire
    study = speed_sweep(InPlaneTire(shipped.tire, shipped.tangential), 40, [0.0, 10.0, 20.0],
                        range(4))
    assert data["speeds_m_s"] == [0.0, 10.0, 20.0] and data["orders"] == [0, 1, 2, 3]
    for key, values in (("against_rotation_hz", study.against_hz),
                        ("with_rotation_hz", study.with_hz)):
        np.testing.assert_array_equal(np.array(data[key], dtype=float), values)
    # n >= 2: the wave against the rotation falls with speed, the one with it rises
    assert np.all(np.diff(study.against_hz[:, 2:, 0], axis=0) < 0)
    assert np.all(np.diff(study.with_hz[:, 2:, 0], axis=0) > 0)
    assert data["critical_speed"]["critical_speed_m_s"] > 20
    assert plot.stat().st_size > 10_000


def test_dispersion_plot_at_a_speed(capsys, tmp_path):
    plot = tmp_path / "dispersion.png"
    assert main(["inplane-modes", "--elements", "40", "--speed", "20", "--nmax", "4",
                 "--json", "--plot", str(plot)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [row["order"] for row in data["orders"]] == [0, 1, 2, 3, 4]
    assert plot.stat().st_size > 10_000


@pytest.mark.parametrize("args, named", [
    (["--speeds", "1"], "--speeds"), (["--max-speed", "-3"], "--max-speed"),
    (["--nmax", "30", "--elements", "40"], "--nmax")])
def test_bad_options_are_named(capsys, args, named):
    assert main(["inplane-speed-sweep", *args]) != 0
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err
