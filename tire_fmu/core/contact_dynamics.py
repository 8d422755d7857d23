"""Time stepping of the tire with the unilateral contact: a linear ring, a nonlinear interface.

The ring is linear, so it is stepped exactly in its free modal basis (:mod:`.free_ring`, built
at initialisation for the speed), with the rim motion and the road's push f_j on each
contact-zone node as inputs, each ramped over the step. Only the contact is nonlinear: over a
step t -> t + h the forces ramp from their values at t to unknown values at t + h, and those
are solved so that the law of :mod:`.contact` holds at t + h,

    f_j = max(0, k_j p_j + c_j ṗ_j) where p_j > 0, else 0,
    p(t + h) = a + W_p Δf,  ṗ(t + h) = a' + W_r Δf,

where a, a' are the end-of-step penetrations and rates with the forces held at their deviation
from the static footprint (Δf = f - f_static = 0 at t + h) and W_p, W_r the step's own
interface flexibility (exact, from the modal step coefficients, cached per h). The solve is a
primal-dual active set iteration on the few zone nodes, warm-started from the last step's set;
no node ever pulls. An explicit contact at this stiffness would be unstable at h = 1e-4 s.

The ramp makes the interface second order; like any such scheme it is stable only while
ω_c·h stays small for the contact frequency ω_c = sqrt(k_cw/ρA) (about 5.5e3 rad/s with the
paper's data), so a communication step longer than ``max_substep_s`` is divided into equal
substeps, with the inputs ramped through them.

At the start of each communication step the forces are re-evaluated from the ring's state and
the inputs the host gave for that point (an algebraic evaluation: with every mode kept the
zone displacements do not depend on the forces at an instant), so outputs read after new
inputs, and the step that follows, use them.

The model can also run ``law="linear"``: two-sided springs on the static footprint's nodes,
f = f_static + k Δp + c Δṗ, which is exactly the linearised loaded model (a reference for the
unilateral contact at small amplitude, and what a linear frequency-domain tool assumes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .blas_threads import blas_threads
from .contact import ContactPatch, RoadWindows
from .free_ring import FreeRingModel, RingModes, RingTruncation, ring_modes
from .model import TireModel, build_model, check_resolved
from .parameters import OperatingPoint, TireParameters
from .step_limits import (  # noqa: F401  (the limits a step checks, for the FMUs' spec)
    MAX_DISPLACEMENT_M,
    MAX_STATE_DISPLACEMENT_M,
    MAX_STATE_VELOCITY_M_S,
    MAX_STEP_WORK,
    MAX_VELOCITY_M_S,
    MIN_CORRECTED_STEP_S,
    SHORT_STEP_TEMPLATE,
    STIFF_CONTACT_ALLOWED,
    STIFF_CONTACT_REASON,
    WORK_INTERVAL_S,
    substep_work,
)

LAWS = ("unilateral", "linear")
#: Longest internal step (s); shorter still if the contact frequency asks for it.
MAX_SUBSTEP_S = 1e-4
#: The shortest contact sub-step a tire may need (s): GL073A needs 1.8e-4 s (so 0.1 ms), and
#: 1e-7 s is 1000 sub-steps per 0.1 ms communication step. Stiffer contacts on lighter treads
#: are refused rather than run for hours (a property test over the ranges found one).
MIN_SUBSTEP_S = 1e-7
#: How a tire that would need shorter sub-steps is refused (the k_cw problem's texts): the
#: largest k_cw and rhoA; then the shortest sub-step.
SUBSTEP_ALLOWED = "at most %.3g N/m^2 with rhoA = %g kg/m"
SUBSTEP_REASON = ("the contact is sub-stepped at 1/sqrt(k_cw/rhoA), which would be below %g s: "
                  "more than 10^4 sub-steps per millisecond")


class ContactZoneWarning(UserWarning):
    """The footprint reached the end of the contact zone: forces beyond it are missing."""


@dataclass(frozen=True)
class ContactSettings:
    law: str = "unilateral"
    max_substep_s: float = MAX_SUBSTEP_S

    def __post_init__(self) -> None:
        from .parameters import ParameterError, Problem

        problems = []
        if self.law not in LAWS:
            problems.append(Problem("law", self.law, "", f"one of {', '.join(LAWS)}"))
        if not (isinstance(self.max_substep_s, (int, float)) and 0 < self.max_substep_s <= 1.0):
            problems.append(Problem("max_substep_s", self.max_substep_s, "s", "in (0, 1] s"))
        if problems:
            raise ParameterError(problems)


@dataclass(frozen=True, eq=False)
class ContactModel:
    """Everything a contact simulation needs, built once for an operating point."""

    model: TireModel  # the linearised loaded model (its patch is the static footprint)
    modes: RingModes  # the free ring's modes for the speed, by order
    settings: ContactSettings
    substep_s: float  # the longest internal step used

    @cached_property
    def ring(self) -> FreeRingModel:
        """The free ring's modes as a dense modal form (frequency responses, checks)."""
        return self.modes.modal_form(self.model.grid)

    @property
    def patch(self) -> ContactPatch:
        return self.model.patch

    @property
    def windows(self) -> RoadWindows:
        return self.patch.road

    @property
    def static_outputs(self) -> dict[str, float]:
        """The simulator's outputs (OUTPUT_NAMES) at the static footprint."""
        statics = self.patch.static_outputs()  # the linear model's: "deflection" is the tread's
        return {"rim_Fz": statics["rim_Fz"], "rim_Fx": statics["rim_Fx"],
                "contact_Fz": statics["contact_Fz"], "deflection": self.patch.deflection_m,
                "contact_length": self.patch.length_m,
                "tread_deflection": statics["deflection"]}

    def summary(self) -> dict:
        return {**self.model.summary(), "law": self.settings.law,
                "ring_modes": self.modes.n_modes, "ring_states": 2 * self.modes.n_modes,
                "ring_modes_total": self.modes.total_modes,
                "zone_nodes": int(self.modes.zone_nodes.size),
                "substep_s": self.substep_s}


@blas_threads()  # small dense problems: see core.blas_threads
def build_contact_model(tire: TireParameters | None = None, op: OperatingPoint | None = None,
                        truncation: RingTruncation | None = None,
                        settings: ContactSettings | None = None) -> ContactModel:
    """The static footprint for the load, the free ring for the speed, the interface."""
    tire = tire or TireParameters()
    op = op or OperatingPoint()
    settings = settings or ContactSettings()
    model = build_model(tire, op)
    modes = ring_modes(tire, model.grid, model.spin_rad_s, model.patch.zone.nodes, truncation)
    # the free ring's rigid rotation (eigenvalue 0 exactly) is no mode to resolve
    check_resolved(modes.eigenvalues[modes.eigenvalues != 0], model)
    contact_rad_s = math.sqrt(tire.k_cw / tire.rhoA)
    if 1.0 / contact_rad_s < MIN_SUBSTEP_S:
        from .parameters import TIRE_FIELDS, ParameterError, Problem

        raise ParameterError([Problem(
            "k_cw", tire.k_cw, TIRE_FIELDS["k_cw"].unit,
            SUBSTEP_ALLOWED % (tire.rhoA / MIN_SUBSTEP_S**2, tire.rhoA),
            SUBSTEP_REASON % MIN_SUBSTEP_S)])
    substep = min(settings.max_substep_s, 1.0 / contact_rad_s)
    zone = model.patch.zone
    # a ring truncated with static correction reads the held forces through its rate term
    # every sub-step (contract.build_contract's truncated, ring.c's)
    truncated = bool(np.any(modes.d[:, 1:]) or np.any(modes.e[:, 1:]))
    work = substep_work(modes.n_modes, model.grid.n_elements // 2 + 1, zone.n_nodes,
                        zone.n_points, int(zone.point_support.shape[1]), truncated)
    per_interval = math.ceil(WORK_INTERVAL_S / substep * (1 - 1e-12))
    if per_interval * work > MAX_STEP_WORK:
        from .parameters import TIRE_FIELDS, ParameterError, Problem

        most = tire.rhoA * (MAX_STEP_WORK / work / WORK_INTERVAL_S) ** 2
        raise ParameterError([Problem(
            "k_cw", tire.k_cw, TIRE_FIELDS["k_cw"].unit,
            STIFF_CONTACT_ALLOWED % (most, tire.rhoA, model.grid.n_elements),
            STIFF_CONTACT_REASON % (per_interval, work, MAX_STEP_WORK))])
    return ContactModel(model=model, modes=modes, settings=settings, substep_s=substep)


# The stepping: one kernel (C, or its numpy reference) over the contract of a ContactModel.
from .simulator import (  # noqa: E402, F401  (the API this module has always offered)
    INPUT_NAMES,
    OUTPUT_NAMES,
    OUTPUT_UNITS,
    ContactSimulator,
    ContactState,
    KernelFallbackWarning,
    StateError,
    StepError,
)
