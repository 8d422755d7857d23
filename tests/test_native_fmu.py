"""The native C FMU: its sources, its agreement with the Python FMU (the reference), its
messages and statuses, its FMU states. Other hosts and platforms: test_native_hosts.py."""

from __future__ import annotations

import math
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from contact_points_reference import zone_length_rounding_to_node
from fmpy.fmi1 import FMICallException
from native_support import (
    OUTPUTS,
    H,
    Instance,
    Opened,
    relative_errors,
    rim_lift,
    road_drop,
    run,
)

import tire_fmu
from tire_fmu.core.contact import zone_problems
from tire_fmu.core.discretisation import Grid
from tire_fmu.core.free_ring import RingTruncation
from tire_fmu.core.parameters import (
    MAX_ELEMENTS,
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    TireParameters,
)
from tire_fmu.fmu.spec import MESSAGES, c_header, fmu_message
from tire_fmu.native.builder import C_SOURCES, c_folder, write_sources

pytestmark = pytest.mark.fmu

PACKAGE = Path(tire_fmu.__file__).parent


@pytest.fixture(scope="module")
def native(native_fmu_path):
    return Opened.of(native_fmu_path)


@pytest.fixture(scope="module")
def python(python_fmu_path):
    return Opened.of(python_fmu_path)


# -- the sources -------------------------------------------------------------------------------

def test_no_c_source_is_held_in_a_python_string():
    holders = [p.relative_to(PACKAGE) for p in PACKAGE.rglob("*.py") if "#include" in p.read_text()]
    assert holders == []
    assert (c_folder() / "fmi2_layer.c").is_file()


def test_spec_header_is_the_generated_one():
    """spec.h in the package is what tire_fmu.fmu.spec generates from the core (regenerate it
    with ``python -c "from tire_fmu.fmu.spec import c_header; print(c_header(), end='')"``)."""
    assert (c_folder() / "spec.h").read_text() == c_header()


def _core_problem(make) -> str:
    with pytest.raises(ParameterError) as caught:
        make()
    return fmu_message(caught.value.problems[0])


@pytest.mark.parametrize("make, key, args", [
    (lambda: TireParameters(R=5.0), "FIELD_RANGE",
     ("R", "5 m", "(0.1, 3] m", "tread (belt) radius")),
    (lambda: TireParameters(beta=math.nan), "FIELD_NOT_FINITE",
     ("beta", "nan", "[0, 0.1] s", "stiffness-proportional damping coefficient")),
    (lambda: TireParameters(sidewall_pressure_exponent=4.0), "FIELD_RANGE",
     ("sidewall_pressure_exponent", "4", "[0, 3]",
      TIRE_FIELDS["sidewall_pressure_exponent"].description)),
    (lambda: TireParameters(inflation_pressure=0.0, sidewall_pressure_exponent=1.5),
     "PRESSURE_LAW", ("0 Pa", 1e4, 1.5)),
    (lambda: TireParameters(inflation_pressure=1e-300, sidewall_pressure_exponent=1.0),
     "PRESSURE_LAW", ("1e-300 Pa", 1e4, 1.0)),
    (lambda: OperatingPoint(n_elements=4), "ELEMENTS_RANGE", (4, 8, MAX_ELEMENTS)),
    (lambda: OperatingPoint(load_n=-2.5), "NOT_NONNEGATIVE", ("load", "-2.5 N", "N")),
    (lambda: OperatingPoint(speed_m_s=math.inf), "NOT_NONNEGATIVE", ("speed", "inf", "m/s")),
    (lambda: OperatingPoint(speed_m_s=1e-4), "MIN_ROLLING_SPEED", ("0.0001 m/s", 1e-3)),
    (lambda: RingTruncation(f_max_hz=-1.0), "F_MAX_RANGE", ("-1 Hz", 1e7)),
    (lambda: RingTruncation(n_modes=-3), "N_MODES_RANGE", (-3, 100000)),
    (lambda: (_ for _ in ()).throw(ParameterError(zone_problems(Grid(100, 0.65), 5.0))),
     "ZONE_RANGE", ("5 m", 2 * 0.65 * math.tan(math.pi / 3))),
    (lambda: (_ for _ in ()).throw(ParameterError(zone_problems(Grid(100, 0.65), 0.05))),
     "ZONE_TOO_SHORT", ("0.05 m", 2 * 0.65 * math.tan(2 * math.pi / 100), 100)),
])
def test_spec_templates_are_the_core_messages(make, key, args):
    """Each printf template of the spec, filled in as the C fills it, is the core's message in
    the FMU's words: the two runtimes cannot drift apart."""
    assert MESSAGES[key] % args == _core_problem(make)


def test_ring_truncation_refuses_what_it_cannot_use():
    """A fix in the reference: RingTruncation took any f_max and n_modes (f_max = -1 kept no
    mode at all) while the Python FMU expected it to raise ParameterError for them."""
    with pytest.raises(ParameterError) as caught:
        RingTruncation(f_max_hz=math.nan, n_modes=0)
    assert len(caught.value.problems) == 2
    assert RingTruncation(f_max_hz=150.0, n_modes=40).n_modes == 40


def test_c_compiles_without_a_warning(tmp_path):
    from tire_fmu.fmu.interface import fmu_variables

    folder = tmp_path / "sources"
    write_sources(folder, fmu_variables(), "{test}", "TireModalNative")
    command = ["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-Wpedantic", "-Wshadow",
               "-O2", "-c", *(str(folder / name) for name in C_SOURCES)]
    result = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 0, result.stderr


def test_fmpy_validate_reports_nothing(native_fmu_path):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(native_fmu_path)) == []


def test_fmu_holds_sources_and_binaries(native_fmu_path):
    from tire_fmu.native import default_platforms

    names = set(zipfile.ZipFile(native_fmu_path).namelist())
    assert {f"sources/{n}" for n in C_SOURCES} <= names
    assert {"sources/spec.h", "sources/export.h", "sources/buildDescription.xml"} <= names
    assert "binaries/linux64/TireModalNative.so" in names
    if "win64" in default_platforms():
        assert "binaries/win64/TireModalNative.dll" in names


# -- the same numbers as the Python FMU ------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("load", [15000.0, 27700.0, 45000.0])
@pytest.mark.parametrize("speed", [0.0, 10.0, 20.0])
def test_matches_the_python_fmu_through_loss_of_contact(native, python, load, speed):
    """Acceptance: one native FMU initialised at each operating point gives the Python FMU's
    outputs to 1e-9 for a 5 cm road drop and a large rim lift, both of which lift the tread
    off the road; the rim run also reads outputs between set and step (feedthrough)."""
    parameters = {"load": load, "speed": speed}
    for signal, read_first in ((road_drop, False), (rim_lift, True)):
        reference = run(python, parameters, signal, read_first=read_first)
        native_run = run(native, parameters, signal, read_first=read_first)
        assert (reference[:, 2] == 0.0).any(), "the excitation must lift the tread off"
        assert (native_run[:, 2] == 0.0).sum() == (reference[:, 2] == 0.0).sum()
        errors = relative_errors(reference, native_run)
        assert errors.max() < 1e-9, dict(zip(OUTPUTS, errors))


@pytest.mark.parametrize("parameters", [
    {"linear_contact": True, "speed": 10.0},
    {"f_max": 150.0, "speed": 10.0},
    {"f_max": 150.0, "static_correction": False},
    # no mode kept: the Python FMU's fast step refused its empty modal state (the fuzz found it)
    {"n_elements": 16, "f_max": 1e-3},
    {"n_modes": 40, "speed": 5.0},
    {"n_elements": 60, "contact_zone_length": 0.4, "sidewall_shear": 5e4, "speed": 8.0,
     "sidewall_pressure_exponent": 1.0, "inflation_pressure": 6e5, "load": 20000.0},
    # the sidewall tied to the tread above order 8 (GL073A_tied), rolling on a fine mesh
    {"n_elements": 200, "sidewall_max_order": 8.0, "speed": 20.0, "f_max": 400.0},
    # a zone whose limit/δθ rounds up to a node beyond it: the Python FMU took that node in
    # (its zone front, where road_z is read, was 4 cm ahead of the native FMU's)
    {"contact_zone_length": zone_length_rounding_to_node(100, 0.65, 7), "speed": 10.0},
])
def test_other_settings_match_the_python_fmu(native, python, parameters):
    reference = run(python, parameters, road_drop, steps=900)
    native_run = run(native, parameters, road_drop, steps=900)
    errors = relative_errors(reference, native_run)
    assert errors.max() < 1e-9, dict(zip(OUTPUTS, errors))


#: The mesh of the cleat runs: coarse, so that 41 points per node stay a fast run.
CLEAT_ELEMENTS = 40


@pytest.mark.parametrize("per_node", [1, 3, 41])
def test_over_a_cleat_at_several_points_per_node_match_the_python_fmu(native, python, per_node):
    """Issue 21: a 20 mm x 20 mm cleat at 10 m/s, rim held, crossing the whole contact zone,
    with 1 (the node model), 3 and 41 contact points per node arc: rim_Fz and contact_Fz of
    the two FMUs agree to 1e-9 of the load. The road is the cleat's profile at the zone front
    (road_z, road_vz = V dz/ds), sampled as the cleat study samples it."""
    from tire_fmu.core.contact import points_per_node
    from tire_fmu.core.contact_dynamics import build_contact_model
    from tire_fmu.core.obstacles import cleat
    from tire_fmu.core.parameters import DEFAULT_LOAD_N

    speed, tire = 10.0, TireParameters()
    arc = Grid(CLEAT_ELEMENTS, tire.R).node_arc_m
    # m points are at most arc/m apart: a spacing between arc/m and arc/(m - 2) makes m
    spacing = 1.0 if per_node == 1 else arc / (per_node - 0.5)
    assert points_per_node(arc, spacing) == per_node
    op = OperatingPoint(n_elements=CLEAT_ELEMENTS, speed_m_s=speed,
                        contact_point_spacing_m=spacing)
    front = build_contact_model(tire, op).windows.front_m
    # the cleat's first edge starts 1 cm ahead of the zone front and its last leaves the rear
    lead, obstacle = front + 0.01, cleat(0.02, 0.02)
    steps = int(math.ceil((lead + obstacle.length_m + front) / (speed * H)))
    height, slope = obstacle.road_samples(front - lead + speed * H * np.arange(steps),
                                          speed * H)
    runs = []
    for fmu in (python, native):
        instance = Instance(fmu, logging_on=False)
        assert instance.initialise(n_elements=CLEAT_ELEMENTS, speed=speed,
                                   contact_point_spacing=spacing) == 0, instance.errors()
        rows = [instance.outputs_now()]
        for k in range(steps):
            instance.slave.setReal(instance.inputs,
                                   [0.0, 0.0, float(height[k]), float(speed * slope[k])])
            instance.slave.doStep(k * H, H)
            rows.append(instance.outputs_now())
        instance.free()
        runs.append(np.array(rows))
    reference, native_run = runs
    assert reference[:, 0].max() > DEFAULT_LOAD_N + 5e3, "the cleat must load the rim"
    forces = [OUTPUTS.index("rim_Fz"), OUTPUTS.index("contact_Fz")]
    errors = np.abs(native_run[:, forces] - reference[:, forces]).max(axis=0) / DEFAULT_LOAD_N
    assert errors.max() < 1e-9, dict(zip(("rim_Fz", "contact_Fz"), errors))


def _random_parameters(seed: int) -> dict:
    """A tire, mesh and operating point drawn around GL073A (each field scaled by up to 2)."""
    rng = np.random.default_rng(seed)
    scale = lambda low, high: float(rng.uniform(low, high))  # noqa: E731
    parameters = {"n_elements": int(rng.choice([16, 30, 50, 100, 150])),
                  "load": scale(5000, 40000), "speed": scale(0, 15),
                  "R": 0.65 * scale(0.7, 1.3), "rhoA": 19.64 * scale(0.5, 2),
                  "m_s": 10 * scale(0.5, 2), "k_r1": 6.686e6 * scale(0.5, 2),
                  "k_r2": 4.431e6 * scale(0.5, 2), "EI": 25.697 * scale(0.2, 5),
                  "beta": 1.1e-4 * scale(0, 3), "alpha": 8.2e-5 * scale(0, 100),
                  "sidewall_shear": float(rng.choice([0.0, 1e4, 1e5]))}
    if rng.random() < 0.3:
        parameters["f_max"] = scale(80, 400)
    return parameters


#: A tire whose quartic at one order has a rounding floor above the first stopping rule of the
#: root finder the native FMU once used (refused until that rule was relaxed): a hard case.
_HARD_QUARTIC = {"n_elements": 150, "load": 29521.1, "R": 0.56458, "rhoA": 28.9273,
                 "m_s": 6.79093, "k_r1": 8346414.7, "k_r2": 3964972.3, "EI": 113.14986,
                 "beta": 2.857706e-4, "alpha": 6.246998e-3, "sidewall_shear": 1e5,
                 "speed": 5.633439}


@pytest.mark.parametrize("seed", [*range(12), "hard quartic"])
def test_random_tires_match_the_python_fmu(native, python, seed):
    """The per-order eigen-solver, footprint and stepping over a spread of tires and meshes:
    the same problems, or the same outputs, as the Python FMU."""
    parameters = _HARD_QUARTIC if seed == "hard quartic" else _random_parameters(seed)
    status, native_lines, _ = _problems(native, parameters)
    _, python_lines, _ = _problems(python, parameters)
    assert native_lines == python_lines
    if status == 0:
        errors = relative_errors(run(python, parameters, road_drop, steps=400),
                                 run(native, parameters, road_drop, steps=400))
        assert errors.max() < 1e-9, dict(zip(OUTPUTS, errors))


def _problems(fmu: Opened, parameters: dict) -> tuple[int, list[str], list[str]]:
    instance = Instance(fmu)
    status = instance.initialise(**parameters)
    lines = [m for s, _, m in instance.log if s >= 3 and m.startswith("parameter problem")]
    warnings = [m for s, _, m in instance.log if s == 1]
    instance.slave.freeInstance()
    return status, lines, warnings


@pytest.mark.parametrize("parameters", [
    {"R": -1.0, "b": math.nan, "k_cw": math.inf, "beta": 0.5, "n_elements": 4, "load": -1.0,
     "speed": math.nan, "f_max": -1.0, "n_modes": -3},
    {"sidewall_pressure_exponent": 1.0, "inflation_pressure": 0.0},
    {"sidewall_pressure_exponent": 1.0, "inflation_pressure": 1e-300},  # critical speed 0
    {"load": 1e7},
    {"load": 2e5, "contact_zone_length": 0.2},
    {"speed": 90.0},  # above the default (tied) tire's critical speed, 83.4 m/s at N = 100
    {"speed": 50.0, "sidewall_max_order": 0.0},  # the paper's sidewall: 42.7 m/s
    {"contact_zone_length": 5.0},
    {"contact_zone_length": 0.05},
    {"f_max": 1e8, "n_modes": 200000, "static_correction": False},
    {"f_max": -1.0, "load": 1e7},  # a refused truncation: the model still finds the load's
    {"speed": 1e-4},
    {"load": -2.0**-24},  # repr: 16 correctly rounded digits do not read back, ...063 does
    {"k_r1": 1e-3},  # conditioning: the support is too weak for k_cw
    {"EI": 1e8, "n_elements": 1000},  # conditioning: the bending is too stiff on this mesh
])
def test_parameter_problems_are_the_python_fmus(native, python, parameters):
    """Bad parameters: fmi2Error from fmi2ExitInitializationMode, every problem logged, the
    same list (texts included) as the Python FMU logs."""
    status, native_lines, _ = _problems(native, parameters)
    _, python_lines, _ = _problems(python, parameters)
    assert status == 3
    assert native_lines and native_lines == python_lines


@pytest.mark.parametrize("parameters, steps", [
    ({"n_elements": 400}, 300),
    ({"n_elements": 400, "speed": 8.0}, 300),
    ({"n_elements": 800}, 300),
    pytest.param({"n_elements": 800, "speed": 4.0}, 300, marks=pytest.mark.slow),
    pytest.param({"n_elements": 1600}, 240, marks=pytest.mark.slow),
    ({"m_s": 1e-5}, 300),
    ({"m_s": 1e-5, "speed": 20.0}, 300),
])
def test_fine_meshes_and_light_sidewalls_match_the_python_fmu(native, python, parameters, steps):
    """Meshes from N = 400 to MAX_ELEMENTS and sidewalls 1e-6 as heavy as the default, which the
    native FMU refused while it found each order's modes as the roots of a quartic: the same
    outputs as the Python FMU through the start of a road drop (at rest the tread lifts off at
    20 ms, step 200), to 1e-9. The orders themselves: tests/test_native_eig.py."""
    reference = run(python, parameters, road_drop, steps=steps)
    native_run = run(native, parameters, road_drop, steps=steps)
    assert (native_run[:, 2] == 0.0).sum() == (reference[:, 2] == 0.0).sum()
    errors = relative_errors(reference, native_run)
    assert errors.max() < 1e-9, dict(zip(OUTPUTS, errors))


def test_sidewalls_too_light_for_double_precision_are_refused_as_in_python(native, python):
    """m_s = 1e-6 kg/m (the field's lower bound) on k_r2 = 1e11 N/m^2 with beta = 0.1 s: both
    FMUs refuse it with the same problem (the model's eigenvalues span more than double
    precision resolves), naming m_s. The span each quotes is that of its own slowest
    eigenvalue, which double precision does not resolve: rounding noise, so only the rest of
    the text is compared."""
    parameters = {"m_s": 1e-6, "k_r2": 1e11, "beta": 0.1}
    status, native_lines, _ = _problems(native, parameters)
    _, python_lines, _ = _problems(python, parameters)
    assert status == 3
    span = re.compile(r"eigenvalues span [0-9.e+]+ \(")
    assert [span.sub("(", x) for x in native_lines] == [span.sub("(", x) for x in python_lines]
    [line] = native_lines
    assert "m_s = 1e-06 kg/m: must be larger" in line and span.search(line)


@pytest.mark.parametrize("parameters, field", [
    ({"rhoA": 1e-301}, "rhoA"),
    ({"m_s": 1e-301}, "m_s"),
    ({"k_cw": 5e-324}, "k_cw"),
    ({"m_s": 1e-301, "speed": 5.0, "allow_supercritical": True}, "m_s"),
    ({"k_cw": 5e-324, "speed": 5.0, "allow_supercritical": True}, "k_cw"),
    ({"inflation_pressure": 1e-300, "sidewall_pressure_exponent": 1.0}, "inflation_pressure"),
])
def test_tiny_values_are_refused_alike_naming_the_parameter(native, python, parameters, field):
    """They were refused as a critical speed of 0 m/s, a load in [0, 0] N or a singular
    matrix; now as the parameter at fault, its value and its range, by both FMUs alike."""
    status, native_lines, _ = _problems(native, parameters)
    _, python_lines, _ = _problems(python, parameters)
    assert status == 3 and native_lines == python_lines
    [line] = native_lines
    assert line.startswith(f"parameter problem 1/1: {field} = ") and ": must be " in line


@pytest.mark.parametrize("parameters, phrase", [
    ({"k_cw": 1e13, "rhoA": 1e-3}, "which would be below 1e-07 s"),  # the case
    ({"k_cw": 1e11, "rhoA": 1e-3, "n_elements": 800, "load": 100.0},
     "more than the 1000000000 a step may take"),
])
def test_a_contact_the_step_cannot_afford_is_refused_alike(native, python, parameters, phrase):
    """Issue 20: the native FMU ran k_cw = 1e13 on a 1e-3 kg/m tread for 45 s in one 1 s
    doStep (the refusal of sub-steps below 1e-7 s was the Python core's alone). Both FMUs now
    refuse such a tire at initialisation, naming k_cw, with one message; so too a contact
    whose millisecond would take more work than a step may (a fine mesh)."""
    status, native_lines, _ = _problems(native, parameters)
    _, python_lines, _ = _problems(python, parameters)
    assert status == 3 and native_lines == python_lines
    [line] = native_lines
    assert line.startswith("parameter problem 1/1: k_cw = ") and phrase in line


def test_a_contact_the_dense_count_refused_is_taken_alike(native, python):
    """k_cw = 1e10 on a 1e-3 kg/m tread, 800 nodes: a millisecond is 3163 sub-steps of 3.2e-7
    s. Counted as the points' dense solve (3 P^2 a sub-step) that was 1.2e9 units, beyond the
    former 5e8 and the present limit, and refused; counted as the node-space solve costs it,
    6.9e8, within the limit: both FMUs build it and step it to the same outputs."""
    from tire_fmu.core.contact_dynamics import build_contact_model
    from tire_fmu.core.contract import build_contract
    from tire_fmu.core.step_limits import MAX_STEP_WORK, WORK_INTERVAL_S

    contact = build_contact_model(TireParameters(k_cw=1e10, rhoA=1e-3),
                                  OperatingPoint(n_elements=800, load_n=100.0))
    c = build_contract(contact)
    per_ms = math.ceil(WORK_INTERVAL_S / contact.substep_s * (1 - 1e-12))
    dense = (1000 + c.n_modes + 2 * c.n_orders * (c.n_zone // 2 + 1) + 3 * c.n_points ** 2
             + 2 * c.n_points * c.n_support)  # the former count
    assert per_ms * c.substep_work <= MAX_STEP_WORK < per_ms * dense
    parameters = {"k_cw": 1e10, "rhoA": 1e-3, "n_elements": 800, "load": 100.0}
    for fmu in (native, python):
        status, lines, _ = _problems(fmu, parameters)
        assert status == 0 and lines == []

    def pressed(t: float) -> tuple[float, float, float, float]:
        return 1e-5, 0.0, 0.0, 0.0  # the rim 10 um down: the stiff contact rings

    reference = run(python, parameters, pressed, steps=2, h=1e-3)
    errors = relative_errors(reference, run(native, parameters, pressed, steps=2, h=1e-3))
    assert errors.max() < 1e-9, dict(zip(OUTPUTS, errors))


def test_a_step_of_more_work_than_a_step_may_take_is_refused_alike(native, python):
    """A stiff contact on a 400-node mesh: a 1 s step would take 4.4e9 units of work (about
    2 s of CPU); both FMUs refuse it with one message naming the longest step they take, and
    take that one."""
    parameters = {"n_elements": 400, "k_cw": 100 * TireParameters().k_cw}
    said = []
    for fmu in (native, python):
        instance = Instance(fmu)
        assert instance.initialise(**parameters) == 0
        with pytest.raises(FMICallException):
            instance.slave.doStep(0.0, 1.0)
        said.append([m for s, _, m in instance.log if s >= 3])
        instance.slave.freeInstance()
    assert said[0] == said[1] and len(said[0]) == 1
    assert "more than the 1000000000 a step may take (about 1 s of CPU); take steps of at " \
        "most" in said[0][0]


def test_light_heavily_damped_sidewalls_run_as_in_python(native, python):
    """Sidewall masses 2e4 times lighter than the tread and heavily damped (m_s = 1e-3 kg/m,
    beta = 0.1 s), which the native FMU's former quartic solver could not resolve: both FMUs
    run them, to the same outputs."""
    parameters = {"m_s": 1e-3, "beta": 0.1}
    reference = run(python, parameters, road_drop, steps=300)
    errors = relative_errors(reference, run(native, parameters, road_drop, steps=300))
    assert errors.max() < 1e-9, dict(zip(OUTPUTS, errors))

def test_speed_near_critical_warns_with_the_core_message(native):
    """Above 80 % of the critical speed: OK, and the core's warning. (Compared with the core,
    not the Python FMU's log, which pythonfmu 0.7 passes through printf: issue 12.)"""
    import warnings

    from tire_fmu.core.model import SupercriticalSpeedWarning, build_model

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SupercriticalSpeedWarning)
        build_model(op=OperatingPoint(speed_m_s=72.0))
    status, _, native_warnings = _problems(native, {"speed": 72.0})
    assert status == 0
    assert native_warnings == [fmu_message(str(w.message)) for w in caught]
    assert "86 % of the critical speed 83.36 m/s" in native_warnings[0]


# -- statuses ------------------------------------------------------------------------------------

def _started(native, **parameters) -> Instance:
    instance = Instance(native)
    assert instance.initialise(**{"speed": 10.0, **parameters}) == 0
    return instance


def _continue(instance: Instance, t0: float, steps: int, signal=road_drop) -> np.ndarray:
    rows = []
    for k in range(steps):
        t = t0 + k * 1e-4
        instance.slave.setReal(instance.inputs, list(signal(t)))
        assert instance.step(t) == 0
        rows.append(instance.outputs_now())
    return np.array(rows)


def test_terminated_is_the_status_after_fmi2terminate(native):
    """fmi2GetBooleanStatus(fmi2Terminated): the native FMU answers it from its phase (in the
    Python FMU pythonfmu's wrapper does, true only after a discarded step); the phases of
    every call: tests/test_fmi_behaviour.py."""
    instance = Instance(native)
    assert instance.initialise() == 0
    assert instance.slave.getBooleanStatus(3) is False
    instance.slave.terminate()
    assert instance.slave.getBooleanStatus(3) is True  # fmi2Terminated
    instance.slave.freeInstance()


def test_logged_text_is_never_read_as_a_format(native):
    instance = Instance(native, name="tire %s%s%n")
    hostile = b"%s%s%s%s%s%s%s%s%n"
    from ctypes import c_char_p

    categories = (c_char_p * 1)(hostile)
    assert instance.call("fmi2SetDebugLogging", True, 1, categories) == 3
    assert "'%s%s%s%s%s%s%s%s%n'" in instance.errors()[-1]
    instance.slave.freeInstance()


# -- FMU states ---------------------------------------------------------------------------------

def test_a_state_of_another_export_is_refused(native, tmp_path):
    from tire_fmu.native import build_native_fmu

    other = Opened.of(build_native_fmu(tmp_path / "other.fmu", {"load": 20000.0},
                                       platforms=("linux64",)))
    source = _started(Opened.of(other.path))
    data = bytes(source.slave.serializeFMUstate(source.slave.getFMUstate()))
    target = _started(native)
    with pytest.raises(FMICallException):
        target.slave.deSerializeFMUstate(data)
    assert target.errors()[-1] == MESSAGES["REFUSED"] % (
        "fmi2DeSerializeFMUstate", MESSAGES["STATE_GUID"] % (
            other.model_description.guid, native.model_description.guid))
    source.free()
    target.free()


def test_instances_are_independent_and_reset_starts_over(native):
    a, b = _started(native, load=20000.0), _started(native, load=40000.0, speed=0.0)
    rows_a, rows_b = [], []
    for k in range(300):
        t = k * 1e-4
        for instance, rows in ((a, rows_a), (b, rows_b)):
            instance.slave.setReal(instance.inputs, list(rim_lift(t)))
            instance.step(t)
            rows.append(instance.outputs_now())
    alone = _started(native, load=40000.0, speed=0.0)
    assert np.array_equal(np.array(rows_b), _continue(alone, 0.0, 300, rim_lift))
    a.slave.reset()
    a.slave.setupExperiment(startTime=0.0)
    a.slave.enterInitializationMode()
    a.set(load=40000.0, speed=0.0)
    a.slave.exitInitializationMode()
    assert np.array_equal(np.array(rows_b), _continue(a, 0.0, 300, rim_lift))
    for instance in (a, b, alone):
        instance.free()


# -- the command line ----------------------------------------------------------------------------

def _cli(*args, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "tire_fmu", *args], capture_output=True,
                          text=True, cwd=cwd, env={**__import__("os").environ,
                                                   "PYTHONPATH": str(PACKAGE.parent)})


def test_export_freezes_an_operating_point_as_start_values(native, tmp_path):
    result = _cli("export", "point.fmu", "--load", "30000", "--speed", "5", "--elements", "80",
                  "--platform", "linux64", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    exported = Opened.of(tmp_path / "point.fmu")
    starts = {v.name: v.start for v in exported.model_description.modelVariables}
    assert (float(starts["load"]), float(starts["speed"]), int(starts["n_elements"])) == (
        30000.0, 5.0, 80)
    frozen = run(exported, {}, road_drop, steps=300)
    chosen = run(native, {"load": 30000.0, "speed": 5.0, "n_elements": 80}, road_drop,
                 steps=300)
    assert np.array_equal(frozen, chosen)


def test_export_refuses_a_load_the_tire_cannot_carry(tmp_path):
    result = _cli("export", "heavy.fmu", "--load", "1e7", "--platform", "linux64", cwd=tmp_path)
    assert result.returncode != 0 and "Traceback" not in result.stderr
    assert re.search(r"must be in \[0, [0-9.e+]+\] N", result.stderr)
    assert not (tmp_path / "heavy.fmu").exists()
