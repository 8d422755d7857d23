import os

# Before numpy loads OpenBLAS: small dense eigenproblems run ~10x slower when its threads
# fight over a couple of shared cores (the FMU builds a reduced basis in every test).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

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
