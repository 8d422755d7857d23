"""The step contract: its generated C header, its ctypes mirror, and the two builders (the
Python core and the native FMU's C) compared field by field over random tires, so that a
divergence names the array and the index."""

import ctypes
import math
import shutil
import subprocess
from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

from tire_fmu.core.contact_dynamics import ContactSettings, build_contact_model
from tire_fmu.core.contract import CONTRACT_VERSION, StepContract, build_contract
from tire_fmu.core.free_ring import RingTruncation
from tire_fmu.core.parameters import (
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    TireParameters,
)
from tire_fmu.core.standing_waves import critical_speed
from tire_fmu.fmu.interface import fmu_variables
from tire_fmu.native.builder import C_SOURCES, c_folder
from tire_fmu.native.contract import TireContractStruct, c_header, from_ctypes, to_ctypes

#: Relative to each array's largest entry: the two builders do the same arithmetic in the same
#: order except in the eigen-decompositions (LAPACK's and the C's QR of the same matrices).
CONTRACT_RTOL = 1e-12
#: The arrays scaled by eigenvectors: two eigen-solvers agree on a vector to the rounding unit
#: times its condition, which rolling orders near a veering raise (1.1e-11 measured at N = 800
#: and 27.5 m/s, where the eigenvalues still agree to 3e-14).
EIGENVECTOR_RTOL = 2e-11
EIGENVECTOR_FIELDS = ("beta", "gamma", "eta", "b_rim", "c_rim")
SHIM = Path(__file__).parent / "native_host" / "contract_shim.c"


def test_contract_header_is_the_generated_one():
    """contract.h is what tire_fmu.native.contract generates from StepContract (regenerate it
    with ``python -c "from tire_fmu.native.contract import c_header; print(c_header(),
    end='')" > tire_fmu/native/c/contract.h``)."""
    assert (Path(str(c_folder())) / "contract.h").read_text() == c_header()
    assert f"#define TIRE_CONTRACT_VERSION {CONTRACT_VERSION}u" in c_header()


def test_a_contract_survives_the_ctypes_mirror(contract_at_rest):
    back = from_ctypes(to_ctypes(contract_at_rest))
    for spec in fields(StepContract):
        assert np.array_equal(getattr(back, spec.name), getattr(contract_at_rest, spec.name)), \
            spec.name


def test_an_inconsistent_contract_is_refused(contract_at_rest):
    values = {spec.name: getattr(contract_at_rest, spec.name) for spec in fields(StepContract)}
    with pytest.raises(ValueError, match="lam must be"):
        StepContract(**{**values, "lam": values["lam"][:-1]})
    with pytest.raises(ValueError, match="order_start must rise"):
        StepContract(**{**values, "order_start": values["order_start"][::-1].copy()})


@pytest.fixture(scope="module")
def contract_at_rest():
    return build_contract(build_contact_model())


# -- the C builder against the Python builder ---------------------------------------------------

class CBuilder:
    """The native FMU's builder (every C file but the FMI layer) in a small library."""

    def __init__(self, folder: Path):
        if shutil.which("gcc") is None:
            pytest.fail("comparing the builders needs gcc")
        c = Path(str(c_folder()))
        target = folder / "contract_shim.so"
        subprocess.run(["gcc", "-std=c99", "-O2", "-shared", "-fPIC", "-I", str(c), "-o",
                        str(target), str(SHIM), *(str(c / s) for s in C_SOURCES
                                                  if s != "fmi2_layer.c"), "-lm"],
                       check=True, capture_output=True)
        self.lib = ctypes.CDLL(str(target))
        self.lib.shim_build.restype = ctypes.c_void_p
        self.lib.shim_build.argtypes = [ctypes.POINTER(ctypes.c_double),
                                        ctypes.POINTER(TireContractStruct), ctypes.c_char_p,
                                        ctypes.c_size_t]
        self.lib.shim_free.argtypes = [ctypes.c_void_p]
        self.table = fmu_variables()

    def build(self, values: dict) -> tuple[StepContract | None, str]:
        """The C's contract for FMU parameter values, or None and its problems."""
        unknown = set(values) - {v.name for v in self.table}
        assert not unknown, unknown
        array = (ctypes.c_double * len(self.table))(*[
            float(values.get(v.name, v.start or 0.0)) for v in self.table])
        out, text = TireContractStruct(), ctypes.create_string_buffer(16384)
        handle = self.lib.shim_build(array, ctypes.byref(out), text, len(text))
        if not handle:
            return None, text.value.decode()
        try:
            return from_ctypes(out), ""
        finally:
            self.lib.shim_free(handle)


@pytest.fixture(scope="module")
def c_builder(tmp_path_factory):
    return CBuilder(tmp_path_factory.mktemp("contract"))


def random_case(rng: np.random.Generator) -> dict:
    """A tire and operating point in range: each tire field within x2 of GL073A's (the
    sidewall laws on or off), a mesh from 8 to 1600 nodes, a load up to 1.3 x the default,
    a speed up to 90 % of the mesh's critical speed, and the truncation and law at random."""
    base = TireParameters()
    tire = {}
    for name, spec in TIRE_FIELDS.items():
        value = getattr(base, name)
        if name == "sidewall_shear":
            value = 0.0 if rng.random() < 0.5 else float(10 ** rng.uniform(3, 5.5))
        elif name == "sidewall_pressure_exponent":
            value = 0.0 if rng.random() < 0.7 else float(rng.uniform(0.2, 1.5))
        elif value > 0:
            value = float(value * 2.0 ** rng.uniform(-1, 1))
        tire[name] = min(max(value, spec.low if spec.low_inclusive else
                             math.nextafter(spec.low, math.inf)), spec.high)
    n = int(rng.choice([8, 12, 16, 30, 50, 64, 100, 101, 150, 200, 256, 400, 800, 1600],
                       p=[.04, .04, .06, .08, .1, .08, .2, .06, .08, .08, .06, .06, .04, .02]))
    params = TireParameters(**tire)
    critical = critical_speed(params, n).speed_m_s
    speed = 0.0 if rng.random() < 0.4 else float(rng.uniform(0.01, 0.9) * min(critical, 60.0))
    case = {"tire": tire, "n_elements": n, "speed": speed,
            "load": float(rng.uniform(0.0, 1.3) * 27_654.753),
            "f_max": 0.0 if rng.random() < 0.6 else float(10 ** rng.uniform(2, 4)),
            "n_modes": 0 if rng.random() < 0.85 else int(rng.integers(1, 400)),
            "static_correction": bool(rng.random() < 0.8),
            "linear_contact": bool(rng.random() < 0.2)}
    return case


def python_contract(case: dict) -> StepContract:
    tire = TireParameters(**case["tire"])
    op = OperatingPoint(n_elements=case["n_elements"], load_n=case["load"],
                        speed_m_s=case["speed"])
    truncation = RingTruncation(f_max_hz=case["f_max"] or None,
                                n_modes=case["n_modes"] or None,
                                static_correction=case["static_correction"])
    settings = ContactSettings(law="linear" if case["linear_contact"] else "unilateral")
    return build_contract(build_contact_model(tire, op, truncation, settings))


def c_values(case: dict) -> dict:
    return {**case["tire"], "n_elements": case["n_elements"], "load": case["load"],
            "speed": case["speed"], "f_max": case["f_max"], "n_modes": case["n_modes"],
            "static_correction": float(case["static_correction"]),
            "linear_contact": float(case["linear_contact"]),
            "contact_point_spacing": case.get("spacing", 1.0)}


def differences(python: StepContract, native: StepContract) -> list[str]:
    """Every field where the two contracts differ: integers exactly, numbers and arrays beyond
    CONTRACT_RTOL of their largest entry, naming the worst index."""
    found = []
    for spec in fields(StepContract):
        a, b = getattr(python, spec.name), getattr(native, spec.name)
        if not isinstance(a, np.ndarray):
            exact = spec.metadata["kind"] == "int"
            if a != b if exact else not abs(a - b) <= CONTRACT_RTOL * abs(a):
                found.append(f"{spec.name}: {a!r} (Python) != {b!r} (C)")
            continue
        if a.shape != b.shape:
            found.append(f"{spec.name}: shape {a.shape} (Python) != {b.shape} (C)")
            continue
        if not a.size:
            continue
        error = np.abs(a - b)
        scale = float(np.abs(a).max())
        worst = np.unravel_index(int(np.argmax(error)), a.shape)
        rtol = EIGENVECTOR_RTOL if spec.name in EIGENVECTOR_FIELDS else CONTRACT_RTOL
        if spec.metadata["kind"] == "int" and error.max() > 0 or \
                error.max() > rtol * max(scale, 1e-300):
            found.append(f"{spec.name}{list(worst)}: {a[worst]!r} (Python) != {b[worst]!r} "
                         f"(C), {error.max() / max(scale, 1e-300):.2e} of the largest")
    return found


@pytest.mark.parametrize("speed, n_elements", [(0.0, 100), (20.0, 100), (0.0, 400),
                                               (8.0, 400), (0.0, 1600)])
def test_the_builders_agree_on_the_default_tire(c_builder, speed, n_elements):
    case = {"tire": TireParameters().as_dict(), "n_elements": n_elements, "speed": speed,
            "load": 27_654.753, "f_max": 0.0, "n_modes": 0, "static_correction": True,
            "linear_contact": False}
    native, problems = c_builder.build(c_values(case))
    assert native is not None, problems
    assert differences(python_contract(case), native) == []


@pytest.mark.slow
def test_the_builders_agree_on_random_tires(c_builder):
    """60 random tires in range (seeded): each either refused by both builders or built to
    the same contract by both; at least 50 of them built, rolling and at rest."""
    rng = np.random.default_rng(20)
    built, rolling, mismatched = 0, 0, []
    for index in range(60):
        case = random_case(rng)
        try:
            python = python_contract(case)
        except ParameterError as error:
            native, _ = c_builder.build(c_values(case))
            if native is not None:
                mismatched.append(f"case {index}: refused by Python only ({error})")
            continue
        native, problems = c_builder.build(c_values(case))
        if native is None:
            mismatched.append(f"case {index}: refused by C only ({problems.strip()})")
            continue
        built += 1
        rolling += case["speed"] > 0
        mismatched += [f"case {index} (N = {case['n_elements']}, {case['speed']:.3g} m/s): "
                       f"{text}" for text in differences(python, native)]
    assert mismatched == []
    assert built >= 50 and rolling >= 20
