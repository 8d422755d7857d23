"""tire_fmu: an open in-plane modal ring tire model (0-300 Hz) for FMI co-simulation.

The physics lives in :mod:`tire_fmu.core` (numpy + scipy only); the CLI, plots and the FMU
slave are thin adapters over it. The core's names are re-exported here lazily, so importing
the package (as the ``tire-fmu`` command does) loads neither numpy nor scipy by itself.
"""

__version__ = "0.1.0"

#: the names of :mod:`tire_fmu.core` (its ``__all__``), listed here so that a star import
#: and tab completion see them without importing the core
__all__ = [
    "AnalyticModes", "CriticalSpeed", "DEFAULT_LOAD_N", "Dispersion", "ModalResult", "Mode",
    "OperatingPoint", "ParameterError", "Problem", "SupercriticalSpeedWarning", "TIRE_FIELDS",
    "TireModel", "TireParameters", "analytic_modes", "build_model", "complex_modes",
    "critical_speed", "dispersion_relation", "modal_analysis", "real_modes", "render",
    "undeformed",
    "validate",
]


def __getattr__(name: str):
    if name in __all__:
        from . import core

        return getattr(core, name)
    raise AttributeError(f"module 'tire_fmu' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
