"""The braking quarter car with the in-plane tire: ``python -m vehicle_demo braking``.

The ride demo's corner (body, wheel and suspension; :class:`QuarterCarParameters`) rolling
and braking on the in-plane tire, run as an FMU host runs a tire: every communication step
the host integrates the body and the wheel under the tire's last vertical force and the
vehicle's speed under its last fore-aft force (m dV/dt = Fx, m = load/g), then advances the
tire (:class:`tire_fmu.core.inplane_contact.InPlaneStepper`) with the wheel's height and the
axle's fore-aft motion at the step's end and the brake torque. The wheel's rotation is the
tire's (the wheel's inertia, the tire's moment and the torque); its spin comes back.

Three braking runs from the same speed, the brake torque ramped in after rolling settles:
on a level road (the slip it settles at beside :func:`.steady_rolling`'s solve for the same
torque and speed), on an ISO 8608 road of a class, and over a cleat. Then the classic cleat
test of a drum: axle held, wheel free, constant road speed, Fx and Fz at the axle against
time and their spectra. Figures and ``summary.json`` go to ``--out``.

The tire is the core's stepper in process by default; with ``fmu`` (``--fmu``) the braking
runs and the cleat test step TireInPlane.fmu through fmpy instead (built into ``--out``): the
wheel centre's state at each step's start and the road as a host that owns it gives it, its
heights where the FMU asks (``road_x_i``, at most the contact points' spacing apart), which
the in-process tire reads as window means of the exact profile.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from tire_fmu.core.parameters import DEFAULT_LOAD_N
from tire_fmu.fmu.interface import ROAD_QUERIES

from .outputs import check_output_folder, run_folder

#: Standard gravity (m/s²): the vehicle's mass from the load its wheel carries.
GRAVITY_M_S2 = 9.80665
#: Road before the rough profile begins and before the cleat (m ahead of the contact centre):
#: past the front of the contact zone, so that the tire starts on a level road.
ROAD_AHEAD_M = 0.5


class BrakingError(ValueError):
    """A setting the braking demo cannot run with (the message names it and its range)."""


@dataclass(frozen=True)
class BrakingSettings:
    out_dir: Path = Path("braking_output")
    speed_m_s: float = 20.0
    load_n: float = DEFAULT_LOAD_N
    #: the vehicle's share on this wheel; None: load / g
    vehicle_mass_kg: float | None = None
    brake_torque_n_m: float = -6000.0  # negative brakes
    brake_at_s: float = 0.15
    brake_ramp_s: float = 0.1
    duration_s: float = 1.2
    road_class: str = "C"
    road_seed: int = 0
    road_fade_in_m: float = 2.0
    cleat_height_m: float = 0.02
    cleat_length_m: float = 0.02
    cleat_at_s: float = 0.7  # when the cleat meets the contact centre, about
    cleat_test_speed_m_s: float = 10.0
    #: the host's communication step with the tire
    communication_step_s: float = 1e-3
    n_elements: int = 100
    point_spacing_m: float = 0.01
    step_s: float = 1e-4
    f_max_hz: float = 300.0
    progress: bool = True
    tire: object = field(default=None, repr=False)  # an InPlaneTire; None: the default
    #: step TireInPlane.fmu through fmpy (built into out_dir) instead of the core in process
    fmu: bool = False

    @classmethod
    def quick(cls, **overrides) -> BrakingSettings:
        """A short look: a coarser mesh and half the time."""
        values = dict(n_elements=60, duration_s=0.6, cleat_at_s=0.4, road_fade_in_m=1.0)
        values.update(overrides)
        return cls(**values)

    @property
    def quarter_car(self):
        """The ride demo's corner (vehicle_demo's QuarterCarParameters) carrying load_n."""
        from .vehicle_demo_quarter_car_dynamics import QuarterCarParameters

        return QuarterCarParameters().with_static_load(self.load_n)

    @property
    def mass_kg(self) -> float:
        return self.load_n / GRAVITY_M_S2 if self.vehicle_mass_kg is None else (
            self.vehicle_mass_kg)

    def problems(self, names: dict[str, str] | None = None) -> list[str]:
        """Every setting outside its range, all at once (``names``: the options' names)."""
        from tire_fmu.core.parameters import MAX_ELEMENTS, MIN_ELEMENTS

        names = names or {}
        found = []

        def check(name, ok, unit, allowed):
            if not ok:
                found.append(f"{names.get(name, name)} = {getattr(self, name)!r}"
                             f"{' ' + unit if unit else ''}: must be {allowed}")

        def within(name, lo, hi, unit, open_low=False):
            value = getattr(self, name)
            ok = isinstance(value, (int, float)) and math.isfinite(value) and (
                lo < value if open_low else lo <= value) and value <= hi
            check(name, ok, unit, f"in {'(' if open_low else '['}{lo:g}, {hi:g}] {unit}")

        within("speed_m_s", 0.5, 60.0, "m/s")
        within("load_n", 1000.0, 1e5, "N")
        if self.vehicle_mass_kg is not None:
            within("vehicle_mass_kg", 10.0, 1e5, "kg")
        within("brake_torque_n_m", -5e4, 5e4, "N m")
        within("brake_at_s", 0.0, 10.0, "s")
        within("brake_ramp_s", 0.0, 10.0, "s")
        within("duration_s", 0.05, 60.0, "s")
        within("road_fade_in_m", 0.0, 100.0, "m")
        within("cleat_height_m", 0.0, 0.1, "m", open_low=True)
        within("cleat_length_m", 0.0, 1.0, "m", open_low=True)
        within("cleat_at_s", 0.0, 60.0, "s")
        within("cleat_test_speed_m_s", 0.5, 60.0, "m/s")
        within("point_spacing_m", 1e-3, 0.05, "m")
        within("step_s", 1e-6, 1e-3, "s")
        within("communication_step_s", 1e-5, 1e-2, "s")
        if not found:  # a communication step a whole number of the tire's steps
            ratio = self.communication_step_s / self.step_s
            check("communication_step_s", abs(ratio - round(ratio)) < 1e-9 * ratio, "s",
                  f"a whole multiple of step_s = {self.step_s:g} s")
        within("f_max_hz", 50.0, 1e5, "Hz")
        from vehicle_demo.road import ISO_8608_GD_N0_M3

        check("road_class", self.road_class in ISO_8608_GD_N0_M3, "",
              f"one of {', '.join(ISO_8608_GD_N0_M3)}")
        n = self.n_elements
        check("n_elements", isinstance(n, int) and MIN_ELEMENTS <= n <= MAX_ELEMENTS, "",
              f"an integer in [{MIN_ELEMENTS}, {MAX_ELEMENTS}]")
        return found


@dataclass(frozen=True, eq=False)
class BrakingRun:
    """One run's histories (SI) and the road it ran on."""

    name: str
    road: str
    time_s: np.ndarray
    fx_n: np.ndarray  # at the axle, + forward (a brake pulls it back: negative)
    fz_n: np.ndarray
    my_n_m: np.ndarray
    slip_ratio: np.ndarray  # (spin R - V)/V, R the tread radius
    wheel_speed_m_s: np.ndarray  # spin R
    vehicle_speed_m_s: np.ndarray
    torque_n_m: np.ndarray
    sliding_points: np.ndarray

    def summary(self, after_s: float) -> dict:
        on = self.time_s >= after_s
        return {"name": self.name, "road": self.road,
                "mean_slip_ratio": float(self.slip_ratio[on].mean()),
                "mean_fx_n": float(self.fx_n[on].mean()),
                "fz_min_n": float(self.fz_n[on].min()), "fz_max_n": float(self.fz_n[on].max()),
                "vehicle_speed_end_m_s": float(self.vehicle_speed_m_s[-1]),
                "most_sliding_points": int(self.sliding_points.max())}


@dataclass(frozen=True, eq=False)
class BrakingSummary:
    runs: tuple
    steady_slip_ratio: float  # steady_rolling's, at the brake torque and the start speed
    steady_fx_n: float
    settled_after_s: float
    cleat_test: dict
    figures: tuple
    wall_s: float

    def to_dict(self) -> dict:
        return {"runs": [run.summary(self.settled_after_s) for run in self.runs],
                "steady_slip_ratio": self.steady_slip_ratio, "steady_fx_n": self.steady_fx_n,
                "settled_after_s": self.settled_after_s, "cleat_test": self.cleat_test,
                "figures": [str(p) for p in self.figures], "wall_s": self.wall_s}


def brake_torque(settings: BrakingSettings):
    """The brake torque against time: 0, then a linear ramp to the full torque."""
    start, ramp, full = settings.brake_at_s, settings.brake_ramp_s, settings.brake_torque_n_m

    def torque(t):
        if t < start:
            return 0.0
        return full if ramp == 0 or t >= start + ramp else full * (t - start) / ramp

    return torque


def _simulator(settings, model, deflection, speed, obstacle=None, ahead_m=ROAD_AHEAD_M):
    from tire_fmu.core.inplane_contact import InPlaneSimulator

    return InPlaneSimulator(model, settings.n_elements, speed, deflection,
                            step_s=settings.step_s, wheel="free",
                            point_spacing_m=settings.point_spacing_m, obstacle=obstacle,
                            obstacle_ahead_m=ahead_m, f_max_hz=settings.f_max_hz)


def _deflection_at(settings, model, speed) -> float:
    """The rim's deflection (m) whose footprint carries the load at ``speed`` on the reduced
    tire the runs step, as TireInPlane.fmu built at that speed finds it (rim_Fz starts at the
    load, and the FMU and the core run the same tire)."""
    from tire_fmu.core.inplane_contact import deflection_carrying

    return deflection_carrying(_simulator(settings, model, 0.0, speed), settings.load_n)


def rough_road(settings: BrakingSettings):
    """The ISO 8608 profile under the braking run, level for its first ``road_fade_in_m``
    (a half-cosine rise), long enough for the run at the start speed."""
    from tire_fmu.core.iso8608 import iso8608_profile
    from tire_fmu.core.obstacles import SampledRoad

    spacing = 0.25 * settings.point_spacing_m
    length = settings.speed_m_s * settings.duration_s + 1.0
    samples = int(round(length / spacing))
    profile = iso8608_profile(settings.road_class, samples, spacing, settings.road_seed,
                              fade_in_m=min(settings.road_fade_in_m, samples * spacing))
    return SampledRoad(spacing, profile.heights_m,
                       f"ISO 8608 class {settings.road_class} (seed {settings.road_seed})")


class FmuTire:
    """TireInPlane.fmu through fmpy, advanced as :class:`InPlaneStepper` is (the rim's
    deviation from rolling steadily at ``sim.speed_m_s`` at the static load, the torque), as a
    master drives it: the wheel centre's state at each communication step's start (the values
    at t: along the road from 0, at the FMU's ``loaded_radius`` plus the rim's lift) and the
    host's road (``sim``'s obstacle, its start ``sim.obstacle_ahead_m`` ahead of the wheel
    centre's start) given by position where the FMU asks for it (``road_x_i`` out,
    ``road_z_i`` in). ``sim`` is the same tire in process."""

    CENTRE = ("wheel_x", "wheel_vx", "wheel_z", "wheel_vz", "wheel_torque")
    OUTPUTS = ("rim_Fz", "rim_Fx", "rim_My", "contact_Fz", "contact_Fx", "wheel_spin",
               "sliding_points")

    def __init__(self, path, sim, settings, wheel_free: bool = True):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        md = read_model_description(str(path))
        self._vr = {v.name: v.valueReference for v in md.modelVariables}
        self._folder = extract(str(path))
        self.slave = FMU2Slave(guid=md.guid, unzipDirectory=self._folder,
                               modelIdentifier=md.coSimulation.modelIdentifier,
                               instanceName="braking tire")
        self.slave.instantiate()
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        reals = {"load": settings.load_n, "speed": sim.speed_m_s, "f_max": settings.f_max_hz,
                 "contact_zone_length": sim.zone_length_m,
                 "contact_point_spacing": settings.point_spacing_m, "step_size": settings.step_s,
                 "wheel_x": 0.0, "wheel_vx": sim.speed_m_s}
        self.slave.setReal([self._vr[k] for k in reals], list(reals.values()))
        self.slave.setInteger([self._vr["n_elements"]], [settings.n_elements])
        self.slave.setBoolean([self._vr["wheel_free"]], [wheel_free])
        self.slave.exitInitializationMode()
        self.sim, self.time_s = sim, 0.0
        # where the wheel centre carries the load: the rim's lift is from there
        self.loaded_radius_m = self.slave.getReal([self._vr["loaded_radius"]])[0]
        self._centre = [self._vr[n] for n in self.CENTRE]
        self._asked = [self._vr[f"road_x_{i}"] for i in range(1, ROAD_QUERIES + 1)]
        self._heights = [self._vr[f"road_z_{i}"] for i in range(1, ROAD_QUERIES + 1)]
        self._outputs = [self._vr[n] for n in self.OUTPUTS]

    def road_m(self, x_m: np.ndarray) -> np.ndarray:
        """The road's height (m) at ``x_m`` along it (the wheel centre starts at 0)."""
        sim = self.sim
        if sim.obstacle is None:
            return np.zeros_like(x_m)
        return sim.obstacle.profile(x_m - sim.obstacle_ahead_m)[0]

    def advance(self, step_s, x_m=0.0, vx_m_s=0.0, z_m=0.0, vz_m_s=0.0, torque_n_m=0.0):
        from tire_fmu.core.inplane_contact import InPlaneOutputs

        sim, end = self.sim, self.time_s + step_s
        self.slave.setReal(self._centre, [sim.speed_m_s * self.time_s + x_m,
                                          sim.speed_m_s + vx_m_s, self.loaded_radius_m + z_m,
                                          vz_m_s, torque_n_m])
        asked = np.array(self.slave.getReal(self._asked))
        self.slave.setReal(self._heights, self.road_m(asked).tolist())
        self.slave.doStep(self.time_s, step_s)
        self.time_s = end
        fz, fx, my, cfz, cfx, spin, sliding = self.slave.getReal(self._outputs)
        return InPlaneOutputs(fx, fz, my, cfz, cfx, spin, int(sliding))

    def close(self) -> None:
        import shutil

        self.slave.terminate()
        self.slave.freeInstance()
        shutil.rmtree(self._folder, ignore_errors=True)


def _tire_host(sim, settings, torque_n_m, fmu_path):
    """The tire a run advances: the core's stepper, or the FMU."""
    from tire_fmu.core.inplane_contact import InPlaneStepper

    if fmu_path is None:
        return InPlaneStepper(sim, torque_n_m)
    return FmuTire(fmu_path, sim, settings)


def _braking_run(name, sim, settings, torque, bar, fmu_path=None) -> BrakingRun:
    """The quarter car as a co-simulation master runs a tire: each communication step from t
    the tire advances from the wheel's height and the axle's fore-aft motion at t and the
    brake torque (:class:`tire_fmu.core.inplane_contact.InPlaneStepper`), while the body and
    wheel advance on their exact discrete map over the step and the vehicle's speed on its
    trapezoid, the tire's forces at t held; then the two exchange what they have at t + h."""
    from scipy.linalg import expm

    from .vehicle_demo_quarter_car_dynamics import two_mass_state_space

    car, dt = settings.quarter_car, settings.communication_step_s
    a, b = two_mass_state_space(car.body_mass_kg, car.wheel_mass_kg,
                                car.suspension_stiffness_n_per_m,
                                car.suspension_damping_n_s_per_m)
    block = np.zeros((5, 5))
    block[:4, :4], block[:4, 4] = a, b
    exact = expm(block * dt)  # x(t + dt) = Φ x + Γ ΔF for ΔF held over the step
    phi, gamma = exact[:4, :4], exact[:4, 4]
    host = _tire_host(sim, settings, torque(0.0), fmu_path)
    steps = int(round(settings.duration_s / dt))
    radius = sim.model.tire.R
    x = np.zeros(4)  # body and wheel: z_b, ż_b, z_w, ż_w from the static equilibrium
    v0 = speed = settings.speed_m_s
    ahead = 0.0  # the axle's travel beyond v0 t
    fz, fx = settings.load_n, 0.0
    rows = []
    for k in range(1, steps + 1):
        out = host.advance(dt, ahead, speed - v0, x[2], x[3], torque((k - 1) * dt))
        x = phi @ x + gamma * (fz - settings.load_n)
        new_speed = speed + dt * fx / settings.mass_kg
        ahead += dt * (0.5 * (speed + new_speed) - v0)
        speed = new_speed
        fz, fx = out.rim_fz_n, out.rim_fx_n
        if speed < 0.5:
            break  # the vehicle has (nearly) stopped: slip is undefined from here
        rows.append((k * dt, fx, fz, out.rim_my_n_m, out.spin_rad_s * radius, speed,
                     torque(k * dt), out.sliding_points))
        bar(k, steps)
    if fmu_path is not None:
        host.close()
    t, fx_, fz_, my, wheel, vehicle, applied, sliding = (np.array(c) for c in zip(*rows))
    road = "level road" if sim.obstacle is None else sim.obstacle.label
    return BrakingRun(name, road, t, fx_, fz_, my, wheel / vehicle - 1.0, wheel, vehicle,
                      applied, sliding.astype(int))


def _fmu_cleat_test(fmu_path, sim, settings, duration_s, bar):
    """The cleat test (axle held, wheel free) through the FMU, one step of the tire's at a
    time, recorded as :meth:`InPlaneSimulator.run` records it."""
    from tire_fmu.core.inplane_contact import InPlaneRun

    tire = FmuTire(fmu_path, sim, settings)
    steps = int(round(duration_s / settings.step_s))
    rows = []
    for k in range(1, steps + 1):
        o = tire.advance(settings.step_s)
        rows.append((k * settings.step_s, o.rim_fx_n, o.rim_fz_n, o.rim_my_n_m, o.contact_fz_n,
                     o.contact_fx_n, o.spin_rad_s, o.sliding_points, sim.speed_m_s))
        bar(k, steps)
    tire.close()
    return InPlaneRun(*(np.array(column) for column in zip(*rows)))


def run_braking(settings: BrakingSettings | None = None, log=print,
                names: dict[str, str] | None = None) -> BrakingSummary:
    """The braking runs and the cleat test; figures and ``summary.json`` into ``out_dir``, one
    run's set replacing the previous one's whole (:mod:`vehicle_demo.outputs`)."""
    settings = settings or BrakingSettings()
    found = settings.problems(names)
    if found:
        raise BrakingError("; ".join(found))
    started = time.perf_counter()
    out = Path(settings.out_dir)
    option = (names or {}).get("out_dir", "out_dir")
    check_output_folder(out, option, OUTPUTS, BrakingError)
    with run_folder(out, option, BrakingError) as work:
        return _run_braking(settings, work, out, started,
                            lambda text: log(str(text).replace(str(work), str(out))))


#: What a run writes into OUT (a run replaces OUT whole: vehicle_demo.outputs)
OUTPUTS = ("braking.png", "cleat_test.png", "summary.json", "fmus")


def _run_braking(settings: BrakingSettings, out: Path, final: Path, started: float,
                 log) -> BrakingSummary:
    """The runs, every file written into ``out`` (which becomes ``final``)."""
    from scipy.signal import periodogram

    from tire_fmu.core.inplane import InPlaneTire
    from tire_fmu.core.inplane_contact import steady_rolling
    from tire_fmu.core.obstacles import cleat
    from tire_fmu.plots import plot_inplane_cleat

    from .plots import plot_braking
    from .progress import advance, step_bar

    model = settings.tire or InPlaneTire()
    # on the reduced tire the runs step, as TireInPlane.fmu solves it: rim_Fz starts at the load
    deflection = _deflection_at(settings, model, settings.speed_m_s)
    fmu_path = None
    if settings.fmu:
        from tire_fmu.fmu.builder import build_inplane_fmu

        fmu_path = build_inplane_fmu(out / "fmus", tire=model)
        log(f"stepping {fmu_path} through fmpy")
    log(f"in-plane tire at {settings.load_n:g} N: axle {deflection * 1e3:.2f} mm down, "
        f"N = {settings.n_elements}, {settings.point_spacing_m * 1e3:g} mm points, modes to "
        f"{settings.f_max_hz:g} Hz; vehicle {settings.mass_kg:.0f} kg from "
        f"{settings.speed_m_s:g} m/s, brake {settings.brake_torque_n_m:g} N m")
    torque = brake_torque(settings)
    steady = steady_rolling(_simulator(settings, model, deflection, settings.speed_m_s),
                            settings.brake_torque_n_m)
    # the cleat meets the contact centre at about cleat_at_s (the vehicle slows a little)
    cleat_ahead = settings.speed_m_s * settings.cleat_at_s
    cases = [("level road", None, ROAD_AHEAD_M),
             (f"ISO 8608 class {settings.road_class}", rough_road(settings), ROAD_AHEAD_M),
             ("cleat", cleat(settings.cleat_height_m, settings.cleat_length_m), cleat_ahead)]
    steps = int(round(settings.duration_s / settings.communication_step_s))
    runs = []
    for name, road, ahead in cases:
        sim = _simulator(settings, model, deflection, settings.speed_m_s, road, ahead)
        with step_bar(steps, settings.progress, f"braking, {name}") as bar:
            runs.append(_braking_run(name, sim, settings, torque, advance(bar), fmu_path))
    # the classic cleat test: the axle held, the wheel free, the road's speed constant
    speed = settings.cleat_test_speed_m_s
    ahead = 0.4
    sim = _simulator(settings, model, _deflection_at(settings, model, speed), speed,
                     cleat(settings.cleat_height_m, settings.cleat_length_m), ahead)
    duration = (ahead + 0.3 + settings.cleat_length_m) / speed + 0.1
    with step_bar(int(round(duration / settings.step_s)), settings.progress, "cleat test") as bar:
        test = (sim.run(duration, progress=advance(bar)) if fmu_path is None
                else _fmu_cleat_test(fmu_path, sim, settings, duration, advance(bar)))
    on = test.time_s > 0.5 * ahead / speed

    def dominant_hz(signal):
        freq, power = periodogram(signal - signal.mean(), fs=1 / settings.step_s, nfft=2**16)
        band = freq >= 5.0
        return float(freq[band][np.argmax(power[band])])

    cleat_test = {"speed_m_s": speed, "fx_min_n": float(test.rim_fx_n[on].min()),
                  "fx_max_n": float(test.rim_fx_n[on].max()),
                  "fz_max_n": float(test.rim_fz_n[on].max()),
                  "fx_dominant_hz": dominant_hz(test.rim_fx_n[on]),
                  "fz_dominant_hz": dominant_hz(test.rim_fz_n[on])}
    out.mkdir(parents=True, exist_ok=True)
    settled = settings.brake_at_s + settings.brake_ramp_s + 0.2 * settings.duration_s
    figures = (plot_braking(runs, steady.slip_ratio, out / "braking.png"),
               plot_inplane_cleat(test, settings.load_n, on, out / "cleat_test.png"))
    summary = BrakingSummary(tuple(runs), steady.slip_ratio, steady.rim_fx_n, settled,
                             cleat_test, tuple(final / path.name for path in figures),
                             time.perf_counter() - started)
    data = {"settings": {k: (str(v) if isinstance(v, Path) else v)
                         for k, v in asdict(settings).items() if k != "tire"},
            **summary.to_dict()}
    (out / "summary.json").write_text(json.dumps(data, indent=2))
    return summary


def format_braking(summary: BrakingSummary) -> str:
    """The summary as text: each run's settled slip and force, the steady solve, the cleat
    test's extremes and dominant frequencies."""
    lines = [f"steady rolling solve at the brake torque: slip {summary.steady_slip_ratio:.4%}, "
             f"Fx {summary.steady_fx_n / 1e3:.3f} kN",
             f"{'run':<22}{'slip (mean)':>12}{'Fx mean kN':>12}{'Fz min kN':>11}"
             f"{'Fz max kN':>11}{'V end m/s':>11}{'sliding':>9}"]
    for run in summary.runs:
        s = run.summary(summary.settled_after_s)
        lines.append(f"{s['name']:<22}{s['mean_slip_ratio']:>12.4%}{s['mean_fx_n'] / 1e3:>12.3f}"
                     f"{s['fz_min_n'] / 1e3:>11.2f}{s['fz_max_n'] / 1e3:>11.2f}"
                     f"{s['vehicle_speed_end_m_s']:>11.3f}{s['most_sliding_points']:>9d}")
    c = summary.cleat_test
    lines.append(f"cleat test at {c['speed_m_s']:g} m/s: Fx {c['fx_min_n'] / 1e3:.2f} to "
                 f"{c['fx_max_n'] / 1e3:.2f} kN, peak Fz {c['fz_max_n'] / 1e3:.2f} kN; "
                 f"Fx dominated by {c['fx_dominant_hz']:.1f} Hz, Fz by "
                 f"{c['fz_dominant_hz']:.1f} Hz")
    lines += [f"wrote {p}" for p in summary.figures]
    lines.append(f"({summary.wall_s:.1f} s)")
    return "\n".join(lines)
