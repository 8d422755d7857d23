"""The tangential fit: its predictions against the assembled ring's modes (a different
path: the whole tire's eigenproblem, labelled), round trips from a known tire, what the report
says when the data cannot see a direction, and the command line with a tire file."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from tire_fmu.core.fit import FitError
from tire_fmu.core.fit_inplane import (
    InPlaneTarget,
    fit_inplane,
    predictions,
    rotational_free_hz,
    tangential_frequency_hz,
)
from tire_fmu.core.inplane import InPlaneRing, InPlaneTire
from tire_fmu.core.inplane_modes import tire_modes

N = 60
MODEL = InPlaneTire()


def scaled(**factors) -> InPlaneTire:
    t = MODEL.tangential
    return replace(MODEL, tangential=replace(
        t, **{name: getattr(t, name) * f for name, f in factors.items()}))


def test_the_tangential_branches_are_the_assembled_tires_modes():
    ring = InPlaneRing(MODEL, N)
    modes = tire_modes(ring)
    rotational = modes.select(kind="rotational")
    assert tangential_frequency_hz(ring, 0) == pytest.approx(rotational[0].frequency_hz,
                                                             rel=1e-9)
    for order in (1, 2, 3):
        f = tangential_frequency_hz(ring, order)
        # the assembled tire has the order's branch twice (cos and sin), mostly tangential
        # (order 1's is the tread's translation on the sidewall, half radial: its share
        # is 1/2 to within the pressure's small coupling)
        same = [m for m in modes.modes if m.order == order and abs(m.frequency_hz / f - 1)
                < 1e-9]
        assert len(same) == 2, order
        assert all(m.tangential_share > (0.49 if order == 1 else 0.5) for m in same), order
    free = tire_modes(InPlaneRing(MODEL, N, rim_free=True)).select(kind="rotational")
    assert rotational_free_hz(MODEL, N) == pytest.approx(free[0].frequency_hz, rel=1e-12)
    # the wheel's inertia stiffens the pair: the rim-free mode lies above the held one
    assert free[0].frequency_hz > rotational[0].frequency_hz


def test_a_fit_to_the_modes_of_a_known_tire_recovers_it():
    truth = scaled(k_t1=1.3, k_t2=0.8, EA=2.0)
    kinds = [InPlaneTarget("tangential", 1.0, order=n) for n in (0, 1, 2)] + [
        InPlaneTarget("rotational_free", 1.0)]
    values = predictions(truth, kinds, N)
    targets = [replace(t, value=float(v)) for t, v in zip(kinds, values)]
    result = fit_inplane(targets, ["k_t1", "k_t2", "EA"], MODEL, n_elements=N)
    assert result.success and result.rank == 3
    for row in result.parameter_rows():
        assert row["value"] == pytest.approx(getattr(truth.tangential, row["name"]),
                                             rel=1e-7), row
    assert np.max(np.abs(result.residual_percent)) < 1e-7
    assert result.degrees_of_freedom == 1


def test_a_slip_stiffness_pins_the_tread_elements_stiffness():
    truth = scaled(k_tx=0.6)
    target = InPlaneTarget("slip_stiffness", 1.0, speed_m_s=10.0)
    measured = float(predictions(truth, [target], 48)[0])
    at_start = float(predictions(MODEL, [target], 48)[0])
    assert measured < at_start  # a softer tread slips more for the same force
    result = fit_inplane([replace(target, value=measured)], ["k_tx"], MODEL, n_elements=48)
    assert result.model.tangential.k_tx == pytest.approx(truth.tangential.k_tx, rel=1e-6)
    # the fitted C_κ is of the size truck tires have: 10-25 times the load
    assert 5 < measured / target.load_n < 30


def test_a_direction_the_data_cannot_see_is_named():
    # the rotational mode with the rim held alone cannot tell the two sidewall springs apart
    target = InPlaneTarget("tangential", 33.0, order=0)
    result = fit_inplane([target], ["k_t1", "k_t2"], MODEL, n_elements=N)
    assert result.fitted[0] == pytest.approx(33.0, rel=1e-8)
    assert result.rank == 1 and len(result.null_directions) == 1
    assert set(result.null_directions[0]) == {"k_t1", "k_t2"}


def test_every_problem_of_a_fit_is_reported_at_once():
    with pytest.raises(FitError) as caught:
        fit_inplane([InPlaneTarget("tangential", -3.0, order=99),
                     InPlaneTarget("slip_stiffness", 1e5, load_n=0.0),
                     InPlaneTarget("torsion", 30.0)], ["k_t1", "friction_coefficient"],
                    n_elements=N)
    text = str(caught.value)
    for part in ("= -3.0 Hz", "order = 99", "load_n = 0.0 N", "kind 'torsion'",
                 "'friction_coefficient'"):
        assert part in text, part


def test_fit_command_writes_a_tire_file_the_in_plane_commands_read(tmp_path, capsys):
    from tire_fmu.cli import main

    out = tmp_path / "fitted.toml"
    assert main(["fit", "--tangential-mode", "0=33", "--rotational-free", "70",
                 "--inplane-elements", str(N), "--out", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [p["name"] for p in data["inplane"]["parameters"]] == ["k_t1", "k_t2"]
    from tire_fmu.tire_files import read_tire_file

    written = read_tire_file(out)
    model = InPlaneTire(written.tire, written.tangential)
    assert tangential_frequency_hz(InPlaneRing(model, N), 0) == pytest.approx(33.0, rel=1e-7)
    assert rotational_free_hz(model, N) == pytest.approx(70.0, rel=1e-7)
    assert main(["fit", "--tangential-mode", "x=3", "--free-tangential", "EA,foo"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'x=3'" in err and "'foo'" in err
