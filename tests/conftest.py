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
