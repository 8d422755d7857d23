"""tire_fmu: an open in-plane modal ring tire model (0-300 Hz) for FMI co-simulation.

The physics lives in :mod:`tire_fmu.core` (numpy + scipy only); the CLI, plots and the FMU
slave are thin adapters over it.
"""

from .core import *  # noqa: F403
from .core import __all__ as _core_all

__version__ = "0.1.0"
__all__ = list(_core_all)
