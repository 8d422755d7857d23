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
