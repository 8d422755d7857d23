"""Tire data and operating point validation: every problem at once, named with its range."""

import math

import pytest

from tire_fmu.core import (
    DEFAULT_LOAD_N,
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    TireParameters,
    build_model,
    validate,
)


def test_defaults_are_the_gl073a_tire_read_per_metre(tire):
    grid_mass = 2 * math.pi * tire.R
    assert tire.rhoA * grid_mass == pytest.approx(80.2, abs=0.05)  # tread mass, kg
    assert tire.m_s * grid_mass == pytest.approx(40.8, abs=0.05)  # sidewall mass, kg
    assert tire.pretension_n == pytest.approx(7.9e5 * 0.35 * 0.65)
    assert DEFAULT_LOAD_N == pytest.approx(27.7e3, rel=2e-3)


def test_node_masses_sum_to_the_line_masses(tire):
    model = build_model(tire, OperatingPoint(n_elements=64, patch_length_m=0.0))
    mass = model.mass.diagonal()
    assert mass[:64].sum() == pytest.approx(tire.rhoA * 2 * math.pi * tire.R)
    assert mass[64:].sum() == pytest.approx(tire.m_s * 2 * math.pi * tire.R)


def test_every_bad_tire_field_is_reported_at_once():
    with pytest.raises(ParameterError) as caught:
        TireParameters(k_r1=-1.0, m_s=0.0, EI=float("nan"), beta=-1e-4)
    problems = caught.value.problems
    assert len(problems) == 4
    for name in ("k_r1", "m_s", "EI", "beta"):
        [message] = [p for p in problems if p.startswith(name + " ")]
        assert TIRE_FIELDS[name].range_text() in message  # names the allowed range


def test_value_and_range_appear_in_the_message():
    with pytest.raises(ParameterError, match=r"k_r2 = -5 N/m\^2: must be in \(0, 1e\+12\]"):
        TireParameters(k_r2=-5)


def test_validate_collects_tire_and_operating_point_problems_together():
    with pytest.raises(ParameterError) as caught:
        validate({"rhoA": -1, "colour": "red"}, {"n_elements": 4, "speed_m_s": -3, "load_n": 1.0,
                                                  "patch_length_m": 0.1})
    text = " | ".join(caught.value.problems)
    assert len(caught.value.problems) == 5
    for fragment in ("rhoA = -1", "unknown tire parameter", "n_elements = 4",
                     "speed_m_s = -3", "both given"):
        assert fragment in text


def test_patch_longer_than_the_safe_fraction_is_refused(tire):
    with pytest.raises(ParameterError, match="patch_length_m = 0.9 m: must be in"):
        validate({}, {"patch_length_m": 0.9})
    validate({}, {"patch_length_m": tire.max_patch_length_m})  # the limit itself is allowed


def test_load_beyond_the_largest_credible_footprint_is_refused(tire):
    import re

    with pytest.raises(ParameterError, match=r"load_n = 2e\+06 N: must be in \[0, ") as info:
        build_model(tire, OperatingPoint(load_n=2e6))
    limit = float(re.search(r"must be in \[0, ([0-9.e+]+)\] N", str(info.value)).group(1))
    assert "end of the contact zone" in str(info.value)
    assert limit > 1e5  # a truck tire carries its rated load comfortably
    near = build_model(tire, OperatingPoint(load_n=0.99 * limit))
    assert near.patch.length_m < tire.max_patch_length_m
    # a longer zone lets the footprint grow until the 1/8-circumference rule stops it
    with pytest.raises(ParameterError, match="beyond which the linear ring is not credible"):
        build_model(tire, OperatingPoint(load_n=2e6, contact_zone_length_m=1.0))


def test_stencil_needs_eight_nodes():
    with pytest.raises(ParameterError, match="n_elements = 7"):
        OperatingPoint(n_elements=7)
    with pytest.raises(ParameterError, match="must be an integer"):
        OperatingPoint(n_elements=10.5)
    assert OperatingPoint(n_elements=8.0).n_elements == 8
