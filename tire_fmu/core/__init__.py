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
"""

from .analytic import AnalyticModes, analytic_modes
from .complex_modal import complex_modes, modal_analysis
from .dispersion import Dispersion, dispersion_relation
from .modal import ModalResult, Mode, real_modes
from .model import SupercriticalSpeedWarning, TireModel, build_model, undeformed
from .parameters import (
    DEFAULT_LOAD_N,
    TIRE_FIELDS,
    OperatingPoint,
    ParameterError,
    Problem,
    TireParameters,
    render,
    validate,
)
from .standing_waves import CriticalSpeed, critical_speed

__all__ = [
    "AnalyticModes",
    "CriticalSpeed",
    "DEFAULT_LOAD_N",
    "Dispersion",
    "ModalResult",
    "Mode",
    "OperatingPoint",
    "ParameterError",
    "Problem",
    "SupercriticalSpeedWarning",
    "TIRE_FIELDS",
    "TireModel",
    "TireParameters",
    "analytic_modes",
    "build_model",
    "complex_modes",
    "critical_speed",
    "dispersion_relation",
    "modal_analysis",
    "real_modes",
    "render",
    "undeformed",
    "validate",
]
