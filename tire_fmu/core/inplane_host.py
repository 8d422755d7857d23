"""The in-plane tire as an FMU builds it: every setting checked at once, the footprint for the
load, the reduced step for the speed, a stepper the host advances.

:class:`HostSettings` holds what an FMU's parameters give (the tire data, radial and
tangential, and the operating point); :func:`build_host_stepper` validates them all, reporting
every problem in one :class:`~.parameters.ParameterError`, and returns the
:class:`~.inplane_contact.InPlaneStepper` with the host's road
(:class:`~.obstacles.HostRoad`) and a summary for the log. The speed must stay below the
mesh's critical speed (:func:`.inplane_modes.critical_speed`), above which the rolling ring's
standing waves grow without bound. The default tire ties the radial sidewall to the tread above
order 8, as the radial FMU's does, so that the critical speed converges as the mesh is refined;
with the paper's lumped sidewall (``sidewall_max_order`` = 0) it falls as 1/N.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

from .contact import DEFAULT_ZONE_LENGTH_M, zone_problems
from .discretisation import Grid
from .host_inputs import substeps
from .inplane import (
    HOST_TANGENTIAL_RANGES,
    InPlaneTire,
    TangentialParameters,
    tangential_problems,
)
from .inplane_contact import (
    MAX_FORCE_LOADS,
    ContactSetError,
    InPlaneSimulator,
    InPlaneStepper,
    deflection_carrying,
    rebuild_work,
    step_work,
)
from .parameters import (
    DEFAULT_LOAD_N,
    MIN_ELEMENTS,
    FieldSpec,
    ParameterError,
    Problem,
    TireParameters,
    tire_problems,
    value_text,
)
from .step_limits import MAX_STEP_WORK, WORK_INTERVAL_S

#: The simulator's step the host's steps are whole multiples of (s).
DEFAULT_HOST_STEP_S = 1e-4
#: The highest natural frequency of the free ring's modes the reduced step keeps (Hz).
DEFAULT_HOST_F_MAX_HZ = 300.0
#: The in-plane tire's default contact points (m): 10 mm, where its cleat forces converge
#: within a few per cent (docs/theory.md section 13).
DEFAULT_HOST_POINT_SPACING_M = 0.01
#: Loads the in-plane FMU takes (N): above, the static deflection leaves the linear ring.
MAX_HOST_LOAD_N = 1.0e5
#: The speed may be at most this fraction of the mesh's critical speed.
CRITICAL_SPEED_FRACTION = 0.95
#: The static deflection must stay below this fraction of the tread radius.
MAX_DEFLECTION_FRACTION = 0.2
#: The operating point's ranges by HostSettings field, as the tire data's are
#: (:class:`~.parameters.FieldSpec`: the range, whether its low end is allowed, integer or not,
#: the reason a problem gives): both FMUs read them (spec.h's SPEC_INPLANE_FIELDS), and so does
#: the command line where it takes the same settings. The load's low end is open: the tire is
#: built pressed onto the road.
#: The finest mesh the in-plane FMUs build (its initialisation, dense in the ring's DOFs,
#: grows as N³: benchmarks/bench_mesh_size.py --inplane measures it).
MAX_HOST_ELEMENTS = 800
HOST_ELEMENTS_REASON = (f"the 5-point bending stencil needs at least {MIN_ELEMENTS} nodes "
                        f"around the ring; the in-plane tire's initialisation grows as N³, and "
                        f"above {MAX_HOST_ELEMENTS} costs minutes and gigabytes")
#: How a tire whose millisecond would take more work than a step may is refused (its words in
#: both runtimes): the work, coordinates, contact points, steps of step_size, the limit.
WORK_ALLOWED = ("a tire whose millisecond takes at most the %.4g units of work a step may "
                "(this one: %.4g, for %d coordinates, %d contact points and %d steps of "
                "step_size)")
WORK_REASON = "fewer elements, a lower f_max, a wider contact_point_spacing or a longer step_size"

HOST_FIELDS: dict[str, FieldSpec] = {
    spec.name: spec
    for spec in (
        FieldSpec("load_n", "N", "static vertical load the footprint is built for", 0.0,
                  MAX_HOST_LOAD_N),
        FieldSpec("speed_m_s", "m/s", "forward speed the reduced step is built at", 0.0, 150.0,
                  True),
        FieldSpec("n_elements", "", HOST_ELEMENTS_REASON, MIN_ELEMENTS, MAX_HOST_ELEMENTS,
                  True, True),
        FieldSpec("f_max_hz", "Hz", "highest natural frequency of the ring's modes kept", 1.0,
                  1e5, True),
        FieldSpec("zone_length_m", "m", "length of road under the contact points", 0.01, 2.0,
                  True),
        FieldSpec("point_spacing_m", "m", "spacing of the contact points", 1e-4, 0.1, True),
        FieldSpec("step_s", "s", "the tire's own step", 1e-6, 1e-3, True),
    )
}


#: The FMUs' names for HostSettings' fields (their parameters and messages).
FMU_NAMES = {"load_n": "load", "speed_m_s": "speed", "n_elements": "n_elements",
             "f_max_hz": "f_max", "zone_length_m": "contact_zone_length",
             "point_spacing_m": "contact_point_spacing", "step_s": "step_size"}


@dataclass(frozen=True)
class HostSettings:
    """What the in-plane FMU's parameters give (SI). ``tire`` and ``tangential`` are plain
    values by field name (the radial ones of :class:`~.parameters.TireParameters`, the
    tangential ones of :class:`~.inplane.TangentialParameters`); missing ones take the
    FMUs' defaults (GL073A_tied: the paper's data, the radial sidewall tied above order 8)."""

    tire: dict = field(default_factory=dict)
    tangential: dict = field(default_factory=dict)
    load_n: float = DEFAULT_LOAD_N
    speed_m_s: float = 0.0
    n_elements: int = 100
    f_max_hz: float = DEFAULT_HOST_F_MAX_HZ
    zone_length_m: float = DEFAULT_ZONE_LENGTH_M
    point_spacing_m: float = DEFAULT_HOST_POINT_SPACING_M
    step_s: float = DEFAULT_HOST_STEP_S
    wheel_free: bool = True
    #: the host gives the wheel's spin (InPlaneStepper.advance's wheel_rate_rad_s):
    #: wheel_free is then not read
    wheel_driven: bool = False


@dataclass(frozen=True)
class HostModel:
    """The stepper an FMU advances and what its log says about it."""

    stepper: InPlaneStepper
    deflection_m: float
    critical_speed_m_s: float  # nan at rest (not computed)
    points_in_contact: int

    def summary(self) -> dict:
        sim = self.stepper.sim
        return {"n_elements": sim.n_elements, "coordinates": sim._ny,
                "stepping_with": sim.stepping_with,
                "contact_points": sim._zone.n_points,
                "points_in_contact": self.points_in_contact,
                "deflection_m": self.deflection_m,
                "critical_speed_m_s": self.critical_speed_m_s}


#: What a load whose static footprint is not found must be, and why (printf, so that the
#: native FMU, whose footprint solve refuses in the same cases, says the same: the load as a
#: value, k_cw as a value with its unit, n_elements).
FOOTPRINT_ALLOWED = "a load whose static footprint the model finds"
FOOTPRINT_REASON = ("with k_cw = %s and n_elements = %d its contact set did not settle, or "
                    "the load is too small for the footprint to resolve; another load, k_cw or "
                    "n_elements may")


def millisecond_work(stepper: InPlaneStepper) -> float:
    """The work of a millisecond's step (WORK_INTERVAL_S) of this tire: a host must be able to
    take one (host_step_work)."""
    sim = stepper.sim
    count = substeps(WORK_INTERVAL_S, sim.step_s)[0]
    return count * step_work(sim._ny, sim._zone.n_points) + 2.0 * rebuild_work(
        sim._ny, sim._zone.n_points)


def footprint_problem(load_n: float, k_cw: float, n_elements: int) -> Problem:
    """The load's problem when the static footprint is not found (both FMUs' words)."""
    return Problem("load_n", load_n, "N", FOOTPRINT_ALLOWED,
                   FOOTPRINT_REASON % (value_text(k_cw, "N/m^2"), n_elements))


def _number(value):
    """A setting as FieldSpec.problem reads it: True is no number here (it is 1.0 to float)."""
    return repr(value) if isinstance(value, bool) else value


def settings_problems(settings: HostSettings) -> tuple[list[Problem], InPlaneTire | None]:
    """Every problem with the settings on their own, and the tire if its data are sound."""
    problems = []
    tire_values = dict(settings.tire)
    problems += tire_problems(tire_values)
    known = {f.name for f in fields(TangentialParameters)}
    for name in sorted(set(settings.tangential) - known):
        problems.append(Problem(name, settings.tangential[name], "",
                                f"one of the tangential parameters {', '.join(sorted(known))}",
                                "unknown tangential parameter"))
    tangential = TangentialParameters(**{k: v for k, v in settings.tangential.items()
                                         if k in known})
    radius = tire_values.get("R", TireParameters().R)
    problems += tangential_problems(tangential, radius if isinstance(radius, (int, float))
                                    else TireParameters().R, HOST_TANGENTIAL_RANGES)
    ranges = [HOST_FIELDS[name].problem(_number(getattr(settings, name)))
              for name in HOST_FIELDS]
    problems += [problem for problem in ranges if problem]
    if not any(problems) and isinstance(radius, (int, float)):
        # the contact zone on this mesh (its nodes, the points it makes), as the radial tire's
        grid = Grid(int(settings.n_elements), float(radius))
        problems += [replace(problem, field={"contact_zone_length_m": "zone_length_m",
                                             "contact_point_spacing_m": "point_spacing_m"}
                             .get(problem.field, problem.field))
                     for problem in zone_problems(grid, settings.zone_length_m,
                                                  settings.point_spacing_m)]
    tire = None
    if not problems:
        try:
            tire = InPlaneTire(TireParameters(**tire_values), tangential)
        except ParameterError as error:
            problems += error.details
    return problems, tire


def _critical_speed(tire, n: int, backend: str, library) -> float:
    """The mesh's critical speed (m/s): by the C (``native/c/inplane_critical.c``, the same
    to 1e-10, a hundred times faster at N = 400) where the step's C can be had, else by
    :func:`.inplane_modes.critical_speed`."""
    from .inplane_modes import critical_speed

    if backend != "numpy":
        try:  # outside the core (ctypes and a compiler): only when asked for
            from ..native.inplane_critical import c_critical_speed
            from ..native.kernel import KernelUnavailable
        except ImportError:
            if backend == "compiled":
                raise
        else:
            try:
                return c_critical_speed(tire, n, library).speed_m_s
            except KernelUnavailable:
                if backend == "compiled":
                    raise
            except ValueError:  # a tire the core takes and the C's ranges do not: the core's
                pass
    return critical_speed(tire, n).speed_m_s


def build_host_stepper(settings: HostSettings, backend: str = "auto",
                       library=None, road=None) -> HostModel:
    """The stepper for these settings, or a ParameterError naming every problem. ``backend``
    is the step's arithmetic (:data:`~.inplane_contact.BACKENDS`: "auto" steps with the C of
    ``native/c/inplane_step.c`` when it can be had, ``library`` being a loaded kernel library
    to use, else numpy). ``road``: the road by position the FMUs' wheel-centre mode reads
    (:meth:`~.inplane_contact.InPlaneStepper.advance_wheel`: a road file's profile or the
    host's :class:`~.obstacles.PositionRoad`); without, the deviation mode with the host's
    height at the zone's front (:meth:`~.inplane_contact.InPlaneStepper.advance`)."""
    problems, tire = settings_problems(settings)
    if problems:
        raise ParameterError(problems)
    n = int(settings.n_elements)
    # at rest too: the running tire's spin and road speed are held below it at every step
    critical = _critical_speed(tire, n, backend, library)
    if settings.speed_m_s > 0:
        if settings.speed_m_s > CRITICAL_SPEED_FRACTION * critical:
            raise ParameterError([Problem(
                "speed_m_s", settings.speed_m_s, "m/s",
                f"at most {CRITICAL_SPEED_FRACTION:g} of the mesh's critical speed "
                f"{critical:.4g} m/s (n_elements = {n})",
                "with the paper's lumped sidewall (sidewall_max_order = 0) a finer mesh lowers "
                "it: use fewer elements, or tie the sidewall (sidewall_max_order = 8)"
                if tire.tire.sidewall_max_order == 0 else
                "the sidewall's highest free order sets it: lower sidewall_max_order")])
    options = {"zone_length_m": settings.zone_length_m,
               "point_spacing_m": settings.point_spacing_m}
    try:
        sim = InPlaneSimulator(tire, n, settings.speed_m_s, 0.0, step_s=settings.step_s,
                               wheel="driven" if settings.wheel_driven
                               else "free" if settings.wheel_free else "held",
                               f_max_hz=settings.f_max_hz, backend=backend, library=library,
                               **options)
        # the footprint of the reduced tire the step runs (its static shapes make it the full
        # tire's to a fraction of a per cent) at the speed it rolls at, so that rim_Fz is the
        # load when it rolls steadily there (found at rest it was 0.06 % low at 20 m/s)
        deflection = deflection_carrying(sim, settings.load_n)
        most = MAX_DEFLECTION_FRACTION * tire.tire.R
        if not 0.0 < deflection < most:
            raise ParameterError([Problem("load_n", settings.load_n, "N",
                                          f"a load the tire carries below {most:g} m of "
                                          "deflection")])
        sim.set_deflection(deflection)
        stepper = (InPlaneStepper(sim, host_road=True) if road is None
                   else InPlaneStepper(sim, position_road=road))
    except ContactSetError as error:  # the static footprint, at rest or at the speed
        raise ParameterError([footprint_problem(settings.load_n, tire.tire.k_cw, n)]) from error
    contact = stepper.state.contact
    if contact.size and (contact[0] or contact[-1]):
        raise ParameterError([Problem(
            "zone_length_m", settings.zone_length_m, "m",
            f"longer than the footprint at {settings.load_n:g} N",
            "the static footprint reaches the end of the contact zone")])
    millisecond = millisecond_work(stepper)
    if millisecond > MAX_STEP_WORK:
        sim = stepper.sim
        count = substeps(WORK_INTERVAL_S, sim.step_s)[0]
        raise ParameterError([Problem("n_elements", n, "", WORK_ALLOWED % (
            MAX_STEP_WORK, millisecond, sim._ny, sim._zone.n_points, count), WORK_REASON)])
    stepper.critical_speed_m_s, stepper.load_n = critical, settings.load_n
    stepper.speed_limit_m_s = CRITICAL_SPEED_FRACTION * critical
    stepper.spin_limit_rad_s = stepper.speed_limit_m_s / tire.tire.R
    stepper.force_limit_n = MAX_FORCE_LOADS * settings.load_n
    return HostModel(stepper, deflection, critical, int(contact.sum()))
