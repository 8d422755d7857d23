"""Issue 19 through fmpy on both FMUs (the Python FMU and the native C FMU): outputs that do
not depend on the start time, long runs that keep time, and one meaning of "deflection".
(Steps and start times the clock cannot resolve, and forged states refused for what they
mean: tests/test_fmi_behaviour.py.)"""

from __future__ import annotations

import math

import numpy as np
import pytest
from native_support import OUTPUTS, Instance, Opened, relative_errors

from tire_fmu.core import OperatingPoint, TireParameters, build_model

pytestmark = pytest.mark.fmu

LAST_SUCCESSFUL_TIME = 2  # fmi2LastSuccessfulTime


@pytest.fixture(scope="module", params=["python", "native"])
def fmu(request, python_fmu_path, native_fmu_path):
    return Opened.of(python_fmu_path if request.param == "python" else native_fmu_path)


@pytest.fixture(scope="module")
def both(python_fmu_path, native_fmu_path):
    return Opened.of(python_fmu_path), Opened.of(native_fmu_path)


def _road(t):
    """A 15 Hz road of 5 mm and a 1 cm step up at 20 ms."""
    w = 2 * math.pi * 15
    return (0.0, 0.0, 0.005 * math.sin(w * t) + (0.01 if t >= 0.02 else 0.0),
            0.005 * w * math.cos(w * t))


def _run(fmu, start, steps, h, accumulate=False, speed=20.0):
    """Outputs after each step of a host that passes start + k·h (or adds h to its t)."""
    instance = Instance(fmu, logging_on=False)
    assert instance.initialise(start_time=start, speed=speed) == 0, instance.errors()
    rows, t = [], start
    for k in range(steps):
        if not accumulate:
            t = start + k * h
        instance.slave.setReal(instance.inputs, list(_road(k * h)))
        assert instance.step(t, h) == 0, instance.errors()
        rows.append(instance.outputs_now())
        t += h
    last = instance.slave.getRealStatus(LAST_SUCCESSFUL_TIME)
    instance.free()
    return np.array(rows), last


# -- the start time ------------------------------------------------------------------------------

def test_outputs_at_any_start_time_are_those_from_zero_on_both_fmus(both):
    """Issue 19: at 20 m/s the outputs depended on the start time (0.76 N apart at 1e6 s,
    1.3-4 kN at 1.7e9 s, 13 kN at 1e12 s), in both FMUs. They now agree to the tolerance the
    two FMUs agree to at t = 0 (in fact bit for bit)."""
    h = 2.5e-4  # resolved up to 2.2e12 s; 1e-4 s is not at 1e12 s (refused: below)
    python, native = both
    runs = {(fmu.path, start): _run(fmu, start, 300, h)[0]
            for fmu in (python, native) for start in (0.0, 1e6, 1.7e9, 1e12)}
    across = relative_errors(runs[python.path, 0.0], runs[native.path, 0.0]).max()
    assert across < 1e-9
    for (path, start), rows in runs.items():
        errors = relative_errors(runs[path, 0.0], rows)
        assert errors.max() <= max(across, 1e-12), (path, start, dict(zip(OUTPUTS, errors)))


@pytest.mark.parametrize("steps", [20_000])
def test_a_long_run_from_an_epoch_start_keeps_time_and_gives_the_outputs_from_zero(fmu,
                                                                                  steps):
    """A host that adds h to its t at an epoch clock drifts (each sum rounds to 2.4e-7 s);
    the FMU sums its steps itself, so it stays at start + k·h and its outputs after 2 s are
    those of the same run from 0 (the FMU took the host's t as its clock before)."""
    h, start = 1e-4, 1.7e9
    late, late_time = _run(fmu, start, steps, h, accumulate=True)
    early, _ = _run(fmu, 0.0, steps, h)
    assert relative_errors(early, late).max() <= 1e-12
    if "Native" in fmu.path:  # pythonfmu's wrapper reports the host's t + h itself
        assert abs(late_time - (start + steps * h)) <= math.ulp(start)


# -- deflection ----------------------------------------------------------------------------------

def test_deflection_is_the_rims_lowering_and_tread_deflection_the_treads_in_both_fmus(fmu):
    """Issue 19: "deflection" was the rim's lowering in `patch` (18.66 mm) and the tread's
    compression in the FMU (18.17 mm). The FMU's deflection is now the rim's lowering at the
    contact centre (the footprint's, plus the road's rise there, less rim_z); the tread's
    compression relative to the rim is tread_deflection."""
    patch = build_model(TireParameters(), OperatingPoint()).patch
    instance = Instance(fmu)
    assert instance.initialise() == 0
    vr = instance.vr
    deflection, tread = instance.slave.getReal([vr["deflection"], vr["tread_deflection"]])
    assert deflection == patch.deflection_m and 0.0186 < deflection < 0.0188
    assert tread == pytest.approx(patch.centre_compression_m, rel=1e-12) and \
        0.0181 < tread < 0.0182
    rim_z, road_z, road_vz, h = -1e-3, 2e-3, 0.05, 1e-4
    instance.slave.setReal(instance.inputs, [rim_z, 0.0, road_z, road_vz])
    assert instance.step(0.0, h) == 0  # at rest the whole zone reads the road at once
    deflection, tread = instance.slave.getReal([vr["deflection"], vr["tread_deflection"]])
    assert deflection == pytest.approx(patch.deflection_m + road_z + h * road_vz - rim_z,
                                       abs=1e-15)
    assert tread > patch.centre_compression_m + 1e-4  # pressed further: the tread gives too
    instance.slave.setReal(instance.inputs, [0.1, 0.0, 0.0, 0.0])  # lifted clear
    assert instance.step(h, h) == 0
    deflection, contact = instance.slave.getReal([vr["deflection"], vr["contact_Fz"]])
    assert deflection == pytest.approx(patch.deflection_m - 0.1, abs=1e-15) and contact == 0.0
    instance.free()
