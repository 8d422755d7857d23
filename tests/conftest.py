import os

# Before numpy loads OpenBLAS: small dense eigenproblems run ~10x slower when its threads
# fight over a couple of shared cores (the FMU builds a reduced basis in every test).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import functools
import warnings

import pytest

from tire_fmu.core import TireParameters


@pytest.fixture(scope="session")
def tire():
    return TireParameters()


@pytest.fixture(autouse=True)
def _no_supercritical_noise():
    # Tests near the critical speed check the warning explicitly where it matters.
    from tire_fmu.core import SupercriticalSpeedWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SupercriticalSpeedWarning)
        yield


# -- the `fmu` marker: every test that builds an FMU carries it ------------------------------
# so that `pytest -m "not fmu"` is a fast physics-only run. Building one outside such a test
# fails it, whichever fixture or helper did the building.

_BUILDING_ALLOWED = [True]


def _only_in_fmu_tests(function):
    @functools.wraps(function)
    def guarded(*args, **kwargs):
        if not _BUILDING_ALLOWED[0]:
            pytest.fail(f"this test builds an FMU ({function.__module__}.{function.__name__}) "
                        "but is not marked fmu", pytrace=False)
        return function(*args, **kwargs)

    return guarded


def pytest_configure(config):
    import tire_fmu.fmu.builder as python_builder
    import tire_fmu.native.builder as native_builder

    # the two steps every build goes through: pythonfmu's packaging and the C compiler
    python_builder.build_pythonfmu = _only_in_fmu_tests(python_builder.build_pythonfmu)
    native_builder.compile_binary = _only_in_fmu_tests(native_builder.compile_binary)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    # before the item's fixtures, module- and session-scoped ones included, are set up
    _BUILDING_ALLOWED[0] = item.get_closest_marker("fmu") is not None


@pytest.fixture(scope="session")
def native_fmu_path(tmp_path_factory):
    """The native FMU with its default start values, linux64 and (when the cross compiler is
    installed, as .ci/run does) win64, built once per session."""
    from tire_fmu.native import build_native_fmu

    return build_native_fmu(tmp_path_factory.mktemp("native") / "TireModalNative.fmu")


@pytest.fixture(scope="session")
def python_fmu_path(tmp_path_factory):
    """TireModal.fmu (pythonfmu), built once per session."""
    from tire_fmu.fmu.builder import build_fmu

    return build_fmu(tmp_path_factory.mktemp("python_fmu"))
