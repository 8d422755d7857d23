"""Physics core of tire_fmu: numpy and scipy only, no files, FMI or command line.

Modules, in the order they build on each other:

- :mod:`.parameters`: tire data, operating point, validation that lists every problem
- :mod:`.discretisation`: periodic FDM grid, stencils and their symbols
- :mod:`.analytic`: closed-form frequencies of the undeformed ring (eq. 12)
- :mod:`.contact`: patch weights, load-patch geometry, road delays
- :mod:`.rotation`: ground-frame rolling terms
- :mod:`.model`: assembly at an operating point, static vertical stiffness
- :mod:`.dispersion`, :mod:`.standing_waves`: undeformed rolling ring per order
- :mod:`.modal`, :mod:`.complex_modal`: modal analysis and mode labels
- :mod:`.blas_threads`: the BLAS threads the builds run on (one; threadpoolctl sets it where
  it is installed, and without it nothing changes: the physics needs numpy and scipy only)

The names below are imported from their modules on first use (PEP 562), not here: a user of
one module (the FMU imports the contact simulator and what it builds on) does not pay for the
modal analysis, scipy.sparse.linalg and the rest of the core at start-up.
"""

from importlib import import_module

#: Each public name and the module of the core that defines it.
_SOURCES = {
    "AnalyticModes": "analytic",
    "CriticalSpeed": "standing_waves",
    "DEFAULT_LOAD_N": "parameters",
    "Dispersion": "dispersion",
    "ModalResult": "modal",
    "Mode": "modal",
    "OperatingPoint": "parameters",
    "ParameterError": "parameters",
    "Problem": "parameters",
    "SupercriticalSpeedWarning": "model",
    "TIRE_FIELDS": "parameters",
    "TireModel": "model",
    "TireParameters": "parameters",
    "analytic_modes": "analytic",
    "build_model": "model",
    "complex_modes": "complex_modal",
    "critical_speed": "standing_waves",
    "dispersion_relation": "dispersion",
    "modal_analysis": "complex_modal",
    "real_modes": "modal",
    "render": "parameters",
    "undeformed": "model",
    "validate": "parameters",
}

__all__ = list(_SOURCES)


def __getattr__(name: str):
    if name not in _SOURCES:
        # an AttributeError also lets ``from tire_fmu.core import model`` find the submodule
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(f".{_SOURCES[name]}", __name__), name)
    globals()[name] = value  # found once: later look-ups do not come here
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
