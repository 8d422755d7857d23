"""A two-axle truck on four tire FMUs over an OpenCRG road: the vehicle example to copy.

The truck is a rigid body (heave, pitch, roll) on four suspension corners, each an unsprung
mass on a spring and damper, each on its own tire FMU (either in-plane FMU: they take the
wheel centre, docs/fmu.md). Every FMU reads the same OpenCRG road file at its own
lateral offset (left wheels at ``+track/2``, right at ``-track/2``, ISO 8855: x forward, y
left, z up), so the two tracks differ and the body rolls.

The master is the quarter car's (:mod:`vehicle_demo.cosim`), generalised: over each
communication step t -> t + h

1. each tire gets its wheel centre's state at t (``wheel_x``, ``wheel_vx``: the truck's
   position and speed along the road plus the axle's offset; ``wheel_z``, ``wheel_vz``: the
   unsprung mass's height above the road's datum and its rate) and steps;
2. the truck's linear equations are integrated exactly over the step with the tires' forces
   ``rim_Fz`` linear between their values at t and t + h (a first-order hold, through one
   matrix exponential of the augmented system: scipy.linalg.expm).

The same loop runs in fmpy (:class:`~vehicle_demo.cosim.FmuInstance`) and in libcosim, a C++
master (libcosimpy: the four tires as its slaves, their inputs set through its override
manipulator, their outputs read through its last-value observer): the same FMUs give the same
outputs in both (tests/test_truck.py).

Everything starts in static equilibrium: each tire's ``load`` is its corner's weight, the
wheel centres start at the tires' ``loaded_radius`` above the road, the suspension springs
carry the body. The road file starts level (its ISO 8608 roads fade in from 0).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from tire_fmu.core.parameters import FieldSpec, ParameterError

G_M_S2 = 9.81
#: The corners in order: front left, front right, rear left, rear right.
CORNERS = ("front_left", "front_right", "rear_left", "rear_right")
#: The hosts the truck runs in.
HOSTS = ("fmpy", "libcosim")


@dataclass(frozen=True)
class TruckParameters:
    """A two-axle truck (SI). Its default corners carry 27-31 kN each, the range the default
    tire (GL073A, a truck tire) is built for."""

    sprung_mass_kg: float = 10000.0
    pitch_inertia_kg_m2: float = 3.0e4
    roll_inertia_kg_m2: float = 6.0e3
    wheelbase_m: float = 4.0
    #: the centre of gravity behind the front axle (m)
    cg_to_front_axle_m: float = 1.8
    track_m: float = 2.0
    unsprung_mass_front_kg: float = 400.0
    unsprung_mass_rear_kg: float = 500.0
    spring_front_n_m: float = 3.0e5
    spring_rear_n_m: float = 3.5e5
    damper_front_n_s_m: float = 1.5e4
    damper_rear_n_s_m: float = 1.8e4

    def problems(self) -> list:
        specs = [FieldSpec(f.name, "", f.name.replace("_", " "), 0.0, math.inf)
                 for f in fields(self)]
        found = [spec.problem(getattr(self, spec.name)) for spec in specs]
        found = [p for p in found if p]
        if not found and not self.cg_to_front_axle_m < self.wheelbase_m:
            found.append(FieldSpec("cg_to_front_axle_m", "m", "between the axles", 0.0,
                                   self.wheelbase_m).problem(self.cg_to_front_axle_m))
        return found

    @property
    def corner_x_m(self) -> np.ndarray:
        """Each corner's x from the centre of gravity (m, forward)."""
        a, b = self.cg_to_front_axle_m, self.wheelbase_m - self.cg_to_front_axle_m
        return np.array([a, a, -b, -b])

    @property
    def corner_y_m(self) -> np.ndarray:
        """Each corner's y from the centre of gravity (m, left)."""
        half = 0.5 * self.track_m
        return np.array([half, -half, half, -half])

    @property
    def unsprung_kg(self) -> np.ndarray:
        return np.array([self.unsprung_mass_front_kg] * 2 + [self.unsprung_mass_rear_kg] * 2)

    @property
    def spring_n_m(self) -> np.ndarray:
        return np.array([self.spring_front_n_m] * 2 + [self.spring_rear_n_m] * 2)

    @property
    def damper_n_s_m(self) -> np.ndarray:
        return np.array([self.damper_front_n_s_m] * 2 + [self.damper_rear_n_s_m] * 2)

    @property
    def spring_loads_n(self) -> np.ndarray:
        """What each suspension spring carries at rest (N): the sprung weight by the lever
        rule, shared equally left and right."""
        b_share = (self.wheelbase_m - self.cg_to_front_axle_m) / self.wheelbase_m
        axle = self.sprung_mass_kg * G_M_S2 * np.array([b_share, 1.0 - b_share])
        return np.repeat(axle / 2.0, 2)

    @property
    def tire_loads_n(self) -> np.ndarray:
        """Each tire's static load (N): its corner's sprung share and its unsprung mass."""
        return self.spring_loads_n + self.unsprung_kg * G_M_S2


def truck_matrices(truck: TruckParameters) -> tuple[np.ndarray, np.ndarray]:
    """The truck's linear equations s' = A s + B u in deviations from rest, s = (body heave z,
    pitch θ (nose down positive), roll φ (left side up positive), the four wheel centres'
    heights, then their rates), u = the four tires' forces beyond their static loads (N, up
    on the wheels). A body corner is at z + y φ - x θ."""
    x, y = truck.corner_x_m, truck.corner_y_m
    # each corner's displacement from the body's three coordinates
    corner = np.column_stack([np.ones(4), -x, y])  # d(corner z)/d(z, θ, φ)
    k, c = truck.spring_n_m, truck.damper_n_s_m
    mass = np.diag([truck.sprung_mass_kg, truck.pitch_inertia_kg_m2, truck.roll_inertia_kg_m2,
                    *truck.unsprung_kg])
    # the suspension's stiffness and damping on (body, wheels): springs between each body
    # corner and its wheel
    link = np.hstack([corner, -np.eye(4)])  # spring compression rate = link @ q
    stiffness = link.T @ np.diag(k) @ link
    damping = link.T @ np.diag(c) @ link
    inverse = np.linalg.inv(mass)
    n = 7
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -inverse @ stiffness
    a[n:, n:] = -inverse @ damping
    b = np.zeros((2 * n, 4))
    b[n + 3:, :] = inverse[3:, 3:]  # the tires push on the wheels
    return a, b


def first_order_hold(a: np.ndarray, b: np.ndarray, step_s: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Φ, Γ0, Γ1): over a step h the exact s(h) = Φ s(0) + Γ0 u(0) + Γ1 u'(0) for an input
    linear over the step, from one matrix exponential of the augmented system."""
    from scipy.linalg import expm

    n, m = b.shape
    block = np.zeros((n + 2 * m, n + 2 * m))
    block[:n, :n] = a
    block[:n, n:n + m] = b
    block[n:n + m, n + m:] = np.eye(m)
    e = expm(block * step_s)
    return e[:n, :n], e[:n, n:n + m], e[:n, n + m:]


@dataclass(frozen=True)
class TruckRun:
    """What a run gave at the communication points (SI; the body's motion from rest)."""

    host: str
    fmu: str
    time_s: np.ndarray
    body_z_m: np.ndarray
    pitch_rad: np.ndarray
    roll_rad: np.ndarray
    body_az_m_s2: np.ndarray
    #: the wheel centres' heights above the road's datum (m), by corner
    wheel_z_m: np.ndarray
    #: the tires' rim_Fz (N), by corner
    rim_fz_n: np.ndarray
    tire_loads_n: np.ndarray
    speed_m_s: float
    step_s: float
    wall_s: float
    road_file: str
    log: tuple = field(default=())

    @property
    def real_time_factor(self) -> float:
        """Wall time over simulated time (< 1: faster than real time)."""
        simulated = self.time_s[-1] - self.time_s[0]
        return self.wall_s / simulated if simulated > 0 else math.nan

    def summary(self) -> dict:
        dynamic = self.rim_fz_n - self.tire_loads_n
        return {
            "host": self.host, "fmu": self.fmu, "speed_m_s": self.speed_m_s,
            "step_s": self.step_s, "duration_s": float(self.time_s[-1] - self.time_s[0]),
            "body_az_rms_m_s2": float(np.sqrt(np.mean(self.body_az_m_s2 ** 2))),
            "pitch_rms_deg": float(np.degrees(np.sqrt(np.mean(self.pitch_rad ** 2)))),
            "roll_rms_deg": float(np.degrees(np.sqrt(np.mean(self.roll_rad ** 2)))),
            "dynamic_load_rms_n": [float(v) for v in np.sqrt(np.mean(dynamic ** 2, axis=0))],
            "smallest_rim_fz_n": float(self.rim_fz_n.min()),
            "real_time_factor": self.real_time_factor,
        }


#: The truck's road is level this far (m), where the truck starts at rest on its tires, then
#: rises into the random road over FADE_IN_M: a truck rolling onto a slope from a level start
#: meets it as it would, not as a jump of the road's rate under a tire whose wheel has none.
LEVEL_START_M = 6.0
FADE_IN_M = 10.0


def truck_road(path: str | Path, length_m: float = 100.0, road_class: str = "C",
               track_m: float = 2.0, seed: int = 1, spacing_m: float = 0.01) -> Path:
    """An OpenCRG road for the truck: level for LEVEL_START_M, then two independent ISO 8608
    tracks of the class at ``y = ±track/2`` (the left one at v = +track/2) rising from 0 over
    FADE_IN_M, their mean on the centre line, written as KDBI."""
    from tire_fmu.core.iso8608 import iso8608_profile
    from tire_fmu.road_files import write_crg

    level = int(round(LEVEL_START_M / spacing_m))
    samples = int(round(length_m / spacing_m)) - level
    left, right = (np.concatenate([np.zeros(level), iso8608_profile(
        road_class, samples, spacing_m, seed=seed + k, fade_in_m=FADE_IN_M).heights_m])
        for k in range(2))
    heights = np.column_stack([right, 0.5 * (left + right), left])
    return write_crg(path, heights, spacing_m, [-0.5 * track_m, 0.0, 0.5 * track_m],
                     comments=[f"truck road: ISO 8608 class {road_class}, independent left "
                               f"and right tracks {track_m:g} m apart, seed {seed}"])


class _Tires:
    """The four tire FMUs in one host: set the wheel centres, step, read rim_Fz."""

    names = ("wheel_x", "wheel_vx", "wheel_z", "wheel_vz")

    def start(self, parameters: list[dict]) -> np.ndarray:
        """Initialise with each corner's parameters; their loaded radii (m)."""
        raise NotImplementedError

    def step(self, t: float, h: float, inputs: np.ndarray) -> np.ndarray:
        """Inputs (4 corners x wheel_x, wheel_vx, wheel_z, wheel_vz) at t; rim_Fz at t + h."""
        raise NotImplementedError

    def close(self) -> None:
        pass


class _FmpyTires(_Tires):
    def __init__(self, fmu: Path):
        from .cosim import FmuInstance

        self.instances = [FmuInstance(fmu, corner) for corner in CORNERS]
        first = self.instances[0]
        self.inputs = [first.vr(n) for n in self.names]
        self.outputs = [first.vr("rim_Fz"), first.vr("loaded_radius")]

    def start(self, parameters):
        radii = []
        for instance, values in zip(self.instances, parameters):
            instance.start(values)
            radii.append(instance.fmu.getReal(self.outputs)[1])
        return np.array(radii)

    def step(self, t, h, inputs):
        forces = []
        for instance, given in zip(self.instances, inputs):
            fmu = instance.fmu
            fmu.setReal(self.inputs, list(given))
            try:
                fmu.doStep(t, h)
            except Exception as error:
                raise instance.fail(f"the step at t = {t:.6g} s", error) from error
            forces.append(fmu.getReal(self.outputs[:1])[0])
        return np.array(forces)

    def close(self):
        for instance in self.instances:
            instance.close()


class _LibcosimTires(_Tires):
    """libcosim (C++) stepping the four FMUs: an execution with a fixed step, the inputs set
    through an override manipulator before each step, the outputs read after it."""

    def __init__(self, fmu: Path, step_s: float):
        from libcosimpy.CosimExecution import CosimExecution
        from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
        from libcosimpy.CosimManipulator import CosimManipulator
        from libcosimpy.CosimObserver import CosimObserver
        from libcosimpy.CosimSlave import CosimLocalSlave

        log_output_level(CosimLogLevel.ERROR)
        self.step_ns = int(round(step_s * 1e9))
        if abs(self.step_ns * 1e-9 - step_s) > 1e-15:
            raise ValueError(f"step_s = {step_s!r}: libcosim steps in whole nanoseconds")
        self.execution = CosimExecution.from_step_size(step_size=self.step_ns)
        self.slaves = [self.execution.add_local_slave(
            CosimLocalSlave(fmu_path=str(fmu), instance_name=corner)) for corner in CORNERS]
        self.vr = {v.name.decode(): v.reference
                   for v in self.execution.slave_variables(self.slaves[0])}
        self.override = CosimManipulator.create_override()
        self.execution.add_manipulator(self.override)
        self.observer = CosimObserver.create_last_value()
        self.execution.add_observer(self.observer)

    def start(self, parameters):
        for slave, values in zip(self.slaves, parameters):
            for name, value in values.items():
                if isinstance(value, str):
                    self.execution.string_initial_value(slave, self.vr[name], value)
                elif isinstance(value, bool):
                    self.execution.boolean_initial_value(slave, self.vr[name], value)
                elif isinstance(value, int):
                    self.execution.integer_initial_value(slave, self.vr[name], value)
                else:
                    self.execution.real_initial_value(slave, self.vr[name], float(value))
        # libcosim initialises at its first step: the loaded radii come from the tire data
        return None

    def step(self, t, h, inputs):
        refs = [self.vr[n] for n in self.names]
        for slave, given in zip(self.slaves, inputs):
            self.override.slave_real_values(slave, refs, [float(v) for v in given])
        if not self.execution.step():
            raise RuntimeError(f"libcosim refused the step at t = {t:.6g} s (the FMUs' log "
                               "is above)")
        return np.array([self.observer.last_real_values(slave, [self.vr["rim_Fz"]])[0]
                         for slave in self.slaves])


def run_truck(fmu: str | Path, road_file: str | Path, truck: TruckParameters | None = None,
              speed_m_s: float = 15.0, duration_s: float = 3.0, step_s: float = 1e-3,
              host: str = "fmpy", tire_parameters: dict | None = None, start_x_m: float = 5.0,
              loaded_radii_m=None,
              progress: Callable[[int], None] | None = None) -> TruckRun:
    """The truck at ``speed_m_s`` over ``road_file`` for ``duration_s`` with host step
    ``step_s``, its four tires ``fmu`` stepped by ``host`` (fmpy or libcosim), the front
    axle starting ``start_x_m`` along the road. ``loaded_radii_m``: where the four wheel
    centres start above the road (libcosim initialises the FMUs only at its first step, so the
    truck cannot read their ``loaded_radius`` first: give fmpy's, TruckRun.wheel_z_m[0])."""
    truck = truck or TruckParameters()
    problems = truck.problems()
    if host not in HOSTS:
        raise ValueError(f"host = {host!r}: must be one of {HOSTS}")
    if problems:
        raise ParameterError(problems)
    steps = int(round(duration_s / step_s))
    if steps < 1:
        raise ValueError(f"duration_s = {duration_s!r}: must be at least one step_s")
    loads = truck.tire_loads_n
    parameters = [{"load": float(load), "speed": float(speed_m_s), "road_file": str(road_file),
                   "road_lateral_offset": float(y), **(tire_parameters or {})}
                  for load, y in zip(loads, truck.corner_y_m)]
    tires = _FmpyTires(Path(fmu)) if host == "fmpy" else _LibcosimTires(Path(fmu), step_s)
    try:
        radii = tires.start(parameters)
        if loaded_radii_m is not None:
            radii = np.asarray(loaded_radii_m, dtype=float).reshape(4)
        elif radii is None:
            raise ValueError("libcosim: give loaded_radii_m (fmpy's loaded_radius)")
        return _loop(tires, truck, host, Path(fmu).stem, radii, loads, speed_m_s, step_s,
                     steps, start_x_m, str(road_file), progress)
    finally:
        tires.close()


def _loop(tires, truck, host, fmu_name, radii, loads, speed, h, steps, start_x, road_file,
          progress) -> TruckRun:
    a, b = truck_matrices(truck)
    phi, gamma0, gamma1 = first_order_hold(a, b, h)
    x_axle = np.array([0.0, 0.0, -truck.wheelbase_m, -truck.wheelbase_m]) + start_x
    state = np.zeros(14)  # deviations from rest: the road starts level
    forces = np.zeros(4)  # beyond the static loads, at rest
    rows = np.zeros((steps + 1, 14))
    rim = np.zeros((steps + 1, 4))
    rim[0] = loads
    accel = np.zeros(steps + 1)
    started = time.perf_counter()
    for k in range(steps):
        t = k * h
        inputs = np.column_stack([x_axle + speed * t, np.full(4, speed),
                                  radii + state[3:7], state[10:14]])
        total = tires.step(t, h, inputs)
        new = total - loads
        state = phi @ state + gamma0 @ forces + gamma1 @ ((new - forces) / h)
        forces = new
        rows[k + 1], rim[k + 1] = state, total
        accel[k + 1] = (a @ state + b @ forces)[7]
        if progress is not None and (k + 1) % 100 == 0:
            progress(100)
    wall = time.perf_counter() - started
    return TruckRun(host=host, fmu=fmu_name, time_s=np.arange(steps + 1) * h,
                    body_z_m=rows[:, 0], pitch_rad=rows[:, 1], roll_rad=rows[:, 2],
                    body_az_m_s2=accel, wheel_z_m=radii + rows[:, 3:7], rim_fz_n=rim,
                    tire_loads_n=loads, speed_m_s=float(speed), step_s=h, wall_s=wall,
                    road_file=road_file)


def plot_truck(run: TruckRun, path: str | Path) -> Path:
    """The body's heave acceleration, pitch and roll and the four tires' loads over time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    t = run.time_s
    axes[0].plot(t, run.body_az_m_s2, lw=0.8)
    axes[0].set_ylabel("body heave\nacceleration (m/s²)")
    axes[1].plot(t, np.degrees(run.pitch_rad), lw=0.9, label="pitch (nose down +)")
    axes[1].plot(t, np.degrees(run.roll_rad), lw=0.9, label="roll (left up +)")
    axes[1].set_ylabel("angle (°)")
    axes[1].legend(loc="upper right")
    for corner, series in zip(CORNERS, run.rim_fz_n.T):
        axes[2].plot(t, series / 1e3, lw=0.7, label=corner.replace("_", " "))
    axes[2].set_ylabel("rim_Fz (kN)")
    axes[2].set_xlabel("time (s)")
    axes[2].legend(loc="upper right", ncol=2, fontsize=8)
    axes[2].set_xlim(t[0], t[-1])
    fig.suptitle(f"Truck at {run.speed_m_s:g} m/s on {Path(run.road_file).name}: four "
                 f"{run.fmu} in {run.host}, h = {run.step_s * 1e3:g} ms "
                 f"(real-time factor {run.real_time_factor:.2g})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


class TruckError(ValueError):
    """A truck demo setting that cannot be run; the message names the option."""


#: The tire FMUs on the wheel-centre interface the truck drives: the native one first (the
#: faster). The radial FMUs join when they take the wheel centre too.
TIRE_FMUS = ("TireInPlaneNative", "TireInPlane")
#: What the demo writes into OUT.
TRUCK_OUTPUTS = ("fmus", "truck_road.crg", "truck.png", "summary.json")


def build_tire_fmu(identifier: str, folder: Path) -> Path:
    """``identifier``'s FMU with its default tire, built into ``folder``."""
    if identifier == "TireModal":
        from tire_fmu.fmu.builder import build_fmu

        return build_fmu(folder)
    if identifier == "TireInPlane":
        from tire_fmu.fmu.builder import build_inplane_fmu

        return build_inplane_fmu(folder)
    from tire_fmu.native.builder import build_native_fmu

    kind = {"TireModalNative": "radial", "TireInPlaneNative": "inplane"}[identifier]
    return build_native_fmu(folder, kind=kind)


def run_truck_demo(out: Path, tire: str = TIRE_FMUS[0], host: str = "fmpy",
                   speed_m_s: float = 15.0, duration_s: float = 3.0, step_s: float = 1e-3,
                   road: Path | None = None, road_class: str = "C", progress: bool = True,
                   log=print) -> dict:
    """The demo: build the FMU, write the road, run the truck in the host(s), write its figure
    and summary into ``out`` (replaced whole when the run completes)."""
    import json

    from .outputs import check_output_folder, run_folder
    from .progress import step_bar

    problems = [text for ok, text in (
        (tire in TIRE_FMUS, f"--tire {tire!r}: one of {', '.join(TIRE_FMUS)}"),
        (host in (*HOSTS, "both"), f"--host {host!r}: fmpy, libcosim or both"),
        (math.isfinite(speed_m_s) and 0.0 <= speed_m_s <= 40.0,
         f"--speed {speed_m_s!r}: must be in [0, 40] m/s"),
        (math.isfinite(step_s) and 1e-5 <= step_s <= 1e-2,
         f"--step {step_s!r}: must be in [1e-05, 0.01] s"),
        (math.isfinite(duration_s) and step_s <= duration_s <= 600.0,
         f"--duration {duration_s!r}: must be in [--step, 600] s"),
        (road is None or Path(road).is_file(), f"--road {str(road)!r}: no such file"),
    ) if not ok]
    if problems:
        raise TruckError("; ".join(problems))
    check_output_folder(out, "--out", TRUCK_OUTPUTS, TruckError)
    truck = TruckParameters()
    with run_folder(out, "--out", TruckError) as work:
        fmu = build_tire_fmu(tire, work / "fmus")
        log(f"built {out / 'fmus' / fmu.name}")
        if road is None:
            length = LEVEL_START_M + FADE_IN_M + speed_m_s * duration_s + 2 * truck.wheelbase_m
            road_path = truck_road(work / "truck_road.crg", length_m=max(length, 30.0),
                                   road_class=road_class, track_m=truck.track_m)
            shown_road = out / road_path.name
        else:
            road_path = shown_road = Path(road).resolve()
        runs = []
        for name in (HOSTS if host == "both" else (host,)):
            steps = int(round(duration_s / step_s))
            with step_bar(steps, progress, f"truck in {name}") as bar:
                runs.append(run_truck(
                    fmu, road_path, truck, speed_m_s, duration_s, step_s, name,
                    loaded_radii_m=runs[0].wheel_z_m[0] if runs else None,
                    progress=bar.update))
        first = runs[0]
        plot_truck(first, work / "truck.png")
        summary = {"tire": tire, "road_file": str(shown_road), "runs": [r.summary() for r in
                                                                         runs]}
        if len(runs) == 2:
            summary["largest_rim_fz_difference_n"] = float(
                np.abs(runs[0].rim_fz_n - runs[1].rim_fz_n).max())
        (work / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    summary["figure"] = str(out / "truck.png")
    return summary


def format_truck(summary: dict) -> str:
    lines = [f"truck on {summary['road_file']} with four {summary['tire']}:"]
    for run in summary["runs"]:
        loads = ", ".join(f"{v / 1e3:.3g}" for v in run["dynamic_load_rms_n"])
        lines.append(
            f"  {run['host']}: {run['duration_s']:g} s at {run['speed_m_s']:g} m/s, step "
            f"{run['step_s'] * 1e3:g} ms: body heave acceleration "
            f"{run['body_az_rms_m_s2']:.3g} m/s² rms, pitch {run['pitch_rms_deg']:.3g}° rms, "
            f"roll {run['roll_rms_deg']:.3g}° rms, dynamic tire loads {loads} kN rms (FL, FR, "
            f"RL, RR), real-time factor {run['real_time_factor']:.3g} (wall time / simulated "
            "time)")
    if "largest_rim_fz_difference_n" in summary:
        lines.append(f"  fmpy and libcosim: rim_Fz differs by at most "
                     f"{summary['largest_rim_fz_difference_n']:.3g} N")
    lines.append(f"wrote {summary['figure']}")
    return "\n".join(lines)
