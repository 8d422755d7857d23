"""The road by position (issue 37): TireInPlane (the Python in-plane FMU) through fmpy over a
20 mm x 20 mm cleat, the axle held at the loaded radius and moved along the road at a constant
speed, printed side by side in one run with the CPU it ran on.

1. **The host step.** The cleat in a road file (a profile and an OpenCRG file of the same
   road), the FMU stepped at host steps of 1 and 2 ms against 0.1 ms; and the same cleat as the
   host's road (the FMU's ``road_x_i`` out, the host's heights at them in as ``road_z_i``) at
   1 ms against the road file at 0.1 ms. For rim_Fz and rim_Fx: the peak's error (the largest
   departure from the value before the cleat, relative to the reference's) and the rms of the
   difference of the histories over the rms of the reference's departure.
2. **The mesh.** The same road file at N = 100, 200, 400 and 800, at 10 and 20 m/s, the host
   giving the same wheel positions at the same times (no alignment): the rms difference of
   rim_Fz and rim_Fx from N = 800 over the rms of N = 800's departure, and the lag of the best
   cross-correlation of each history with N = 800's (a mesh-dependent place where the road is
   read shows as a lag; the host step is 0.1 ms here, so the lag is resolved to 0.1 ms).

    python3 benchmarks/bench_road_by_position.py [--meshes 100 200 400 800] [--speeds 10 20]
        [--record JSON]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tire_fmu.fmu.interface import ROAD_QUERIES

sys.path.insert(0, str(Path(__file__).resolve().parent))
from record import cpu_model, load_average, write_record  # noqa: E402

#: Where the wheel centre starts along the road, and the cleat (m): the contact zone starts on
#: level road and meets the cleat after about 40 ms at 20 m/s.
START_M, CLEAT_AT_M = 2.0, 3.0
DURATION_S = 0.2
FINE_S = 1e-4
#: The host steps compared with FINE_S (s).
HOST_STEPS_S = (5e-4, 1e-3, 2e-3)
#: Where the wheel starts beyond START_M (m): the host's samples fall elsewhere on the cleat.
PHASES_M = (0.0, 1e-3, 2.5e-3, 4e-3)


def cleat_road():
    """The 20 mm x 20 mm cleat after CLEAT_AT_M of level road, sampled every mm (its cell
    means: an edge is a 1 mm ramp, its area exact)."""
    from tire_fmu.core.obstacles import cleat, sampled_obstacle

    return sampled_obstacle(cleat(0.02, 0.02), 1e-3, lead_in_m=CLEAT_AT_M, lead_out_m=4.0)


def write_roads(folder: Path) -> dict[str, Path]:
    from tire_fmu.road_files import write_road

    road = cleat_road()
    return {"profile": write_road(folder / "cleat.txt", road),
            "OpenCRG": write_road(folder / "cleat.crg", road)}


class Host:
    """One FMU instance as a plain master drives it: the inputs at t, then fmi2DoStep(t, h)."""

    def __init__(self, path, **parameters):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        types = {v.name: v.type for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName="bench")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in parameters.items():
            setter = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
                      "Boolean": self.fmu.setBoolean, "String": self.fmu.setString}[types[name]]
            setter([self.vr[name]], [value])
        self.fmu.exitInitializationMode()

    def read(self, names) -> list[float]:
        return self.fmu.getReal([self.vr[n] for n in names])

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def cleat_run(fmu_path, h: float, speed: float, road_file: str = "", road=None,
              n_elements: int = 100, start_m: float = START_M) -> np.ndarray:
    """rim_Fz and rim_Fx after each host step of ``h``: the wheel centre at the loaded radius,
    moving at ``speed`` from START_M; the road a file's, or with ``road`` (a ProfileRoad) the
    host's, given where the FMU asks."""
    host = Host(fmu_path, speed=speed, n_elements=n_elements, road_file=road_file)
    height = host.read(["loaded_radius"])[0]
    centre = [host.vr[n] for n in ("wheel_x", "wheel_vx", "wheel_z")]
    asked = [host.vr[f"road_x_{i}"] for i in range(1, ROAD_QUERIES + 1)]
    heights = [host.vr[f"road_z_{i}"] for i in range(1, ROAD_QUERIES + 1)]
    forces = [host.vr["rim_Fz"], host.vr["rim_Fx"]]
    rows = []
    for k in range(int(round(DURATION_S / h))):
        t = k * h
        host.fmu.setReal(centre, [start_m + speed * t, speed, height])
        if road is not None:
            host.fmu.setReal(heights, list(road.profile(np.array(host.fmu.getReal(asked)))[0]))
        host.fmu.doStep(t, h)
        rows.append(host.fmu.getReal(forces))
    host.close()
    return np.array(rows)


def differences(run: np.ndarray, reference: np.ndarray) -> dict[str, dict[str, float]]:
    """For rim_Fz and rim_Fx: the peak's error and the histories' rms difference, each over
    the reference's departure from its value before the cleat (``run`` at every host step,
    ``reference`` at the same times)."""
    out = {}
    for i, name in enumerate(("rim_Fz", "rim_Fx")):
        before = reference[0, i]
        peak = np.abs(reference[:, i] - before).max()
        out[name] = {
            "peak": float((np.abs(run[:, i] - before).max() - peak) / peak),
            "rms": float(np.sqrt(np.mean((run[:, i] - reference[:, i]) ** 2))
                         / np.sqrt(np.mean((reference[:, i] - before) ** 2)))}
    return out


def best_lag_s(run: np.ndarray, reference: np.ndarray, h: float) -> float:
    """The shift of ``run`` that best matches ``reference`` (s; positive: ``run`` late)."""
    a, b = run - run[0], reference - reference[0]
    correlation = np.correlate(a, b, mode="full")
    return float((np.argmax(correlation) - (b.size - 1)) * h)


def on(h: float, fine: np.ndarray) -> np.ndarray:
    """The fine run at the coarse run's communication points (the end of each step)."""
    every = int(round(h / FINE_S))
    return fine[every - 1::every]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", type=int, nargs="+", default=[100, 200, 400, 800])
    parser.add_argument("--speeds", type=float, nargs="+", default=[10.0, 20.0])
    parser.add_argument("--record", help="write the results to this JSON file")
    args = parser.parse_args(argv)
    from tire_fmu.fmu.builder import build_inplane_fmu

    load_start = load_average()
    print(f"CPU: {cpu_model()}; load average {load_start}")
    started = time.perf_counter()
    results: dict = {"host_step": {}, "mesh": {}}
    with tempfile.TemporaryDirectory(prefix="bench_road_by_position_") as folder:
        folder = Path(folder)
        fmu = build_inplane_fmu(folder / "fmu")
        roads = write_roads(folder)
        speed = 20.0
        print(f"\n1. host step: the cleat at {speed:g} m/s, N = 100, against the road file at "
              f"{FINE_S * 1e3:g} ms (peak error, rms of the difference; % of the departure)")
        print(f"   {'road':28s} {'h':>6s} {'Fz peak':>8s} {'Fz rms':>8s} {'Fx peak':>8s} "
              f"{'Fx rms':>8s}")
        for kind, path in roads.items():
            fine = cleat_run(fmu, FINE_S, speed, str(path))
            cases = [(f"road file ({kind})", h, str(path), None) for h in HOST_STEPS_S]
            if kind == "profile":
                cases += [("host's road (road_x, road_z)", h, "", cleat_road())
                          for h in (FINE_S,) + HOST_STEPS_S]
            for label, h, road_file, road in cases:
                found = differences(cleat_run(fmu, h, speed, road_file, road), on(h, fine))
                results["host_step"][f"{label}, {h * 1e3:g} ms"] = found
                fz, fx = found["rim_Fz"], found["rim_Fx"]
                print(f"   {label:28s} {h * 1e3:4.1f}ms {100 * fz['peak']:7.2f}% "
                      f"{100 * fz['rms']:7.2f}% {100 * fx['peak']:7.2f}% {100 * fx['rms']:7.2f}%",
                      flush=True)
        print(f"\n   the host's road at 1 ms, the wheel's start moved (the samples fall elsewhere "
              f"on the cleat), against the road file at {FINE_S * 1e3:g} ms from there")
        for phase in PHASES_M:
            fine = cleat_run(fmu, FINE_S, speed, str(roads["profile"]), start_m=START_M + phase)
            found = differences(cleat_run(fmu, 1e-3, speed, "", cleat_road(),
                                          start_m=START_M + phase), on(1e-3, fine))
            results["host_step"][f"host's road, 1 ms, start + {phase * 1e3:g} mm"] = found
            fz, fx = found["rim_Fz"], found["rim_Fx"]
            print(f"   {'start + %g mm' % (phase * 1e3):28s} {1:4.1f}ms {100 * fz['peak']:7.2f}% "
                  f"{100 * fz['rms']:7.2f}% {100 * fx['peak']:7.2f}% {100 * fx['rms']:7.2f}%",
                  flush=True)
        finest = max(args.meshes)
        print(f"\n2. mesh: the same road file (profile), host step {FINE_S * 1e3:g} ms, no "
              f"alignment; against N = {finest} (rms of the difference, % of the departure; "
              f"lag of the best cross-correlation)")
        print(f"   {'speed':>6s} {'N':>5s} {'build s':>8s} {'Fz rms':>8s} {'Fx rms':>8s} "
              f"{'Fz lag ms':>10s} {'Fx lag ms':>10s}")
        for speed in args.speeds:
            runs, builds = {}, {}
            for n in sorted(args.meshes, reverse=True):
                began = time.perf_counter()
                runs[n] = cleat_run(fmu, FINE_S, speed, str(roads["profile"]), n_elements=n)
                builds[n] = time.perf_counter() - began
            for n in sorted(args.meshes):
                found = differences(runs[n], runs[finest])
                lags = [best_lag_s(runs[n][:, i], runs[finest][:, i], FINE_S) for i in (0, 1)]
                results["mesh"][f"{speed:g} m/s, N = {n}"] = {
                    "rim_Fz_rms": found["rim_Fz"]["rms"], "rim_Fx_rms": found["rim_Fx"]["rms"],
                    "rim_Fz_lag_s": lags[0], "rim_Fx_lag_s": lags[1],
                    "build_and_run_s": builds[n]}
                print(f"   {speed:6g} {n:5d} {builds[n]:8.1f} "
                      f"{100 * found['rim_Fz']['rms']:7.2f}% {100 * found['rim_Fx']['rms']:7.2f}% "
                      f"{lags[0] * 1e3:10.1f} {lags[1] * 1e3:10.1f}", flush=True)
    print(f"\n{time.perf_counter() - started:.0f} s")
    if args.record:
        write_record(args.record, results, load_start)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
