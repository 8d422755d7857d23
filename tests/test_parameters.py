"""Tire data and operating point validation: every problem at once, named with its range."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tire_fmu.core import (
    DEFAULT_LOAD_N,
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    Problem,
    TireParameters,
    build_model,
    render,
    validate,
)
from tire_fmu.core.parameters import (
    MAX_ELEMENTS,
    PROBLEM_TEMPLATE,
    REASON_TEMPLATE,
    UNSET_TEMPLATE,
    value_text,
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
                     "speed_m_s = -3", "unset when load_n is given"):
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


@pytest.mark.parametrize("speed", [5e-324, 1e-9, 0.00099])
def test_a_crawl_slower_than_rolling_is_refused(speed):
    with pytest.raises(ParameterError, match="must be 0 or at least 0.001 m/s"):
        OperatingPoint(speed_m_s=speed)
    OperatingPoint(speed_m_s=0.0)
    OperatingPoint(speed_m_s=1e-3)


def test_stencil_needs_eight_nodes():
    with pytest.raises(ParameterError, match="n_elements = 7"):
        OperatingPoint(n_elements=7)
    with pytest.raises(ParameterError, match="must be an integer"):
        OperatingPoint(n_elements=10.5)
    assert OperatingPoint(n_elements=8.0).n_elements == 8


# -- problems: one structure, rendered in each adapter's names ------------------------------

def test_a_problem_renders_in_the_names_of_whoever_reports_it():
    load = Problem("load_n", 1e7, "N", "in [0, 52345.6] N", "for this tire")
    assert render(load) == "load_n = 1e+07 N: must be in [0, 52345.6] N (for this tire)"
    assert render(load, {"load_n": "load"}) == ("load = 1e+07 N: must be in [0, 52345.6] N "
                                                "(for this tire)")
    cut = Problem("f_max_hz", -1.0, "Hz", "in (0, 1e7] Hz", unset=True)
    assert render(cut, {"f_max_hz": "f_max"}, unset="0") == (
        "f_max = -1 Hz: must be in (0, 1e7] Hz, or 0 for no limit")
    assert render(cut) == "f_max_hz = -1 Hz: must be in (0, 1e7] Hz, or None for no limit"


@pytest.mark.parametrize("value, text", [(3.0000001, "3.0000001 m"), (2e6, "2e+06 m"),
                                         (-1, "-1 m"), (math.nan, "nan"), ("x", "'x'"),
                                         (True, "True"), (27654.752999998633,
                                                          "27654.752999998633 m")])
def test_values_read_exactly_as_given(value, text):
    # shortest form that is the value itself: 3.0000001 must not read "3" next to "(0.1, 3]"
    assert value_text(value, "m") == text


def test_the_templates_render_the_same_text_from_c(tmp_path):
    """The native runtime will render problems with snprintf and these patterns."""
    import shutil
    import subprocess

    compiler = shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        pytest.skip("no C compiler")
    problem = Problem("f_max_hz", -1.0, "Hz", "in (0, 1e7] Hz", "the highest kept", unset=True)
    source = tmp_path / "render.c"
    source.write_text(f'''#include <stdio.h>
int main(void) {{
    char allowed[256], text[512], out[1024];
    snprintf(allowed, sizeof allowed, "{UNSET_TEMPLATE}", "in (0, 1e7] Hz", "0");
    snprintf(text, sizeof text, "{PROBLEM_TEMPLATE}", "f_max", "-1 Hz", allowed);
    snprintf(out, sizeof out, "{REASON_TEMPLATE}", text, "the highest kept");
    puts(out);
    return 0;
}}
''')
    subprocess.run([compiler, "-o", str(tmp_path / "render"), str(source)], check=True)
    printed = subprocess.run([str(tmp_path / "render")], capture_output=True, text=True,
                             check=True).stdout.strip()
    assert printed == render(problem, {"f_max_hz": "f_max"}, unset="0")


def test_parameter_error_keeps_the_problems_and_their_text():
    with pytest.raises(ParameterError) as caught:
        validate({"R": -1.0}, {"load_n": math.inf})
    error = caught.value
    assert [p.field for p in error.details] == ["R", "load_n"]
    assert error.problems == [render(p) for p in error.details]
    assert error.message({"load_n": "--load"}).startswith("2 parameter problems: R = -1 m")
    assert "--load = inf" in error.message({"load_n": "--load"})


# -- ranges that run ---------------------------------------------------------------------------

TINY = [("rhoA", 1e-301), ("m_s", 1e-301), ("k_cw", 5e-324)]


@pytest.mark.parametrize("field, value", TINY)
@pytest.mark.parametrize("op", [{}, {"patch_length_m": 0.0},
                                {"speed_m_s": 5.0, "allow_supercritical": True}])
def test_tiny_masses_and_contact_stiffness_are_refused_naming_them(field, value, op):
    # they were refused as "speed = 0 m/s must be below the critical speed 0 m/s",
    # "load must be in [0, 0] N" and, allowed supercritical, "LinAlgError: Singular matrix"
    with pytest.raises(ParameterError) as caught:
        build_model(*validate({field: value}, {"n_elements": 40, **op}))
    [problem] = caught.value.details
    assert problem.field == field and problem.value == value
    spec = TIRE_FIELDS[field]
    assert problem.allowed == f"in {spec.range_text()}" and spec.low_inclusive
    assert value < spec.low and TireParameters(**{field: spec.low})  # the bound itself is taken


@pytest.mark.parametrize("field, low, runs", [
    ("rhoA", 1e-6, {"n_elements": 40, "load_n": DEFAULT_LOAD_N}),
    ("m_s", 1e-6, {"n_elements": 40, "load_n": DEFAULT_LOAD_N, "speed_m_s": 20.0}),
    ("k_cw", 1e4, {"n_elements": 40, "load_n": 50.0}),  # soft tread: a light load
])
def test_the_lower_bounds_build_a_model(field, low, runs):
    assert TIRE_FIELDS[field].low == low
    model = build_model(*validate({field: low}, runs))
    assert model.patch.load_n == pytest.approx(runs["load_n"], rel=1e-9)
    assert np.isfinite(model.critical_speed_m_s) and model.critical_speed_m_s > 20.0

def test_the_mesh_limit_is_one_that_runs():
    OperatingPoint(n_elements=MAX_ELEMENTS)  # benchmarks/bench_mesh_size.py builds it
    with pytest.raises(ParameterError, match=f"n_elements = {MAX_ELEMENTS + 1}"):
        OperatingPoint(n_elements=MAX_ELEMENTS + 1)


@pytest.mark.parametrize("tire, n, field", [
    ({"m_s": 1e-3, "k_r2": 1e11, "beta": 0.1}, 100, "m_s = 0.001 kg/m"),
    ({"rhoA": 1e-3, "k_cw": 1e11, "beta": 0.1}, 100, "rhoA = 0.001 kg/m")])
def test_masses_the_arithmetic_cannot_resolve_name_the_parameter_to_change(tire, n, field):
    from tire_fmu.core.reduction import reduce

    model = build_model(*validate(tire, {"n_elements": n}))
    with pytest.raises(ParameterError, match="eigenvalues span") as caught:
        reduce(model, report=False)
    assert caught.value.problems[0].startswith(field)


@pytest.mark.parametrize("tire, n, expected", [
    ({"k_r2": 1e-5, "k_r1": 1e12}, 100, "k_r2 = 1e-05 N/m^2: must be at least"),
    ({"EI": 1e8}, 400, "EI = 1e+08 N*m^2: must be at most"),
    ({"k_r2": 1e-2}, 100, "k_r2 = 0.01 N/m^2: must be at least"),
    ({"k_cw": 1e13, "k_r2": 1e3}, 100, "k_cw = 1e+13 N/m^2: must be at most")])
def test_stiffnesses_the_arithmetic_cannot_resolve_name_the_parameter_to_change(tire, n,
                                                                               expected):
    with pytest.raises(ParameterError, match="double precision loses") as caught:
        build_model(*validate(tire, {"n_elements": n}))
    assert caught.value.problems[0].startswith(expected)
    [problem] = caught.value.details
    bound = float(problem.allowed.split()[2])  # "at most X ..." / "at least X ..."
    fixed = {**tire, problem.field: bound * (0.5 if "most" in problem.allowed else 2.0)}
    # the bound it names is one that runs (undeformed: a stiffer tire carries less load)
    build_model(*validate(fixed, {"n_elements": n, "patch_length_m": 0.0}))


def _in_range(spec):
    low = spec.low if spec.low_inclusive and spec.low > 0 else max(spec.low, 1e-20)
    if spec.low_inclusive and spec.low == 0.0:
        return st.one_of(st.just(0.0), st.floats(-20, math.log10(spec.high)).map(
            lambda e: 10.0 ** e))
    return st.floats(math.log10(low), math.log10(spec.high)).map(
        lambda e: min(max(10.0 ** e, math.nextafter(spec.low, math.inf)), spec.high))


@settings(max_examples=25, deadline=None)
@given(tire=st.fixed_dictionaries({name: _in_range(spec) for name, spec in TIRE_FIELDS.items()
                                   if name != "R"}),
       radius=st.floats(0.2, 3.0), n=st.integers(8, 60), load_fraction=st.floats(0.0, 1.0))
def test_tire_data_inside_the_ranges_run_or_are_refused_with_a_reason(tire, radius, n,
                                                                     load_fraction):
    """A documented range must be one that runs: anything inside it either builds a model
    whose steps are finite, or is refused as a ParameterError naming what to change."""
    from tire_fmu.core.contact_dynamics import ContactSimulator, build_contact_model

    tire = {**tire, "R": radius}
    try:
        parameters = TireParameters(**tire)
        contact = build_contact_model(parameters, OperatingPoint(
            n, load_n=load_fraction * 2 * DEFAULT_LOAD_N))
        simulator = ContactSimulator(contact)
    except ParameterError as error:
        assert all(p.field in TIRE_FIELDS or p.field in ("load_n", "speed_m_s",
                                                         "contact_zone_length_m")
                   for p in error.details), error
        return
    steps = [simulator.step(1e-4, 1e-3, 0.0, 1e-3 * math.sin(k), 0.0) for k in range(50)]
    assert np.all(np.isfinite(steps))
