"""Issue 37's acceptance for TireInPlane (the Python in-plane FMU): the wheel centre in, the
road by position, driven through fmpy's FMU2Slave as a plain master drives it (the inputs set
before fmi2DoStep(t, h) are the values at t; inplane_support.Instance).

- a 20 mm x 20 mm cleat in a road file at 20 m/s, the wheel centre held at the loaded radius:
  the peak and rms of rim_Fz and rim_Fx at host steps of 1 and 2 ms against 0.1 ms;
- the same cleat as the host's road (road_x_i out, road_z_i in) at 1 ms;
- a road file that is missing or malformed refused at initialisation, naming road_file, the
  path and what is wrong;
- the warning when the contact zone leaves the road file's road.

benchmarks/bench_road_by_position.py prints the same figures side by side (and at 0.5 ms).
"""

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from inplane_support import Instance

from tire_fmu.core.obstacles import cleat, sampled_obstacle
from tire_fmu.road_files import write_road

pytestmark = pytest.mark.fmu

SPEED_M_S = 20.0
#: The wheel centre's start and the cleat's first edge (m along the road): the zone's front
#: meets the cleat after about 40 ms, when the start of rolling has settled.
START_M, CLEAT_AT_M = 2.0, 3.0
#: Long enough for the zone (about 0.3 m) to pass the cleat and the tire to ring down.
DURATION_S = 0.2
FINE_S = 1e-4


@pytest.fixture(scope="module")
def fmu_path(tmp_path_factory):
    from tire_fmu.fmu.builder import build_inplane_fmu

    return build_inplane_fmu(tmp_path_factory.mktemp("wheel_centre"))


def cleat_road():
    """The 20 mm x 20 mm cleat after CLEAT_AT_M of level road, sampled every mm (cell means:
    an edge is a 1 mm ramp, the cleat's area exact)."""
    return sampled_obstacle(cleat(0.02, 0.02), 1e-3, lead_in_m=CLEAT_AT_M, lead_out_m=4.0)


@pytest.fixture(scope="module")
def cleat_file(tmp_path_factory):
    return write_road(tmp_path_factory.mktemp("roads") / "cleat.crg", cleat_road())


def cleat_run(path, h, road_file="", road=None, start=START_M) -> np.ndarray:
    """rim_Fz and rim_Fx after each host step of ``h``: the wheel centre at the loaded radius
    moving at SPEED_M_S from START_M; the road the file's, or with ``road`` the host's."""
    fmu = Instance(str(path), x0=start, speed=SPEED_M_S, road_file=road_file).start()
    heights = (lambda x: road.profile(x)[0]) if road is not None else None
    rows = [fmu.step(h, **({"road": heights} if heights else {}))[:2]
            for _ in range(int(round(DURATION_S / h)))]
    fmu.close()
    return np.array(rows)


def differences(run: np.ndarray, reference: np.ndarray) -> dict:
    """For rim_Fz and rim_Fx: the peak's error and the histories' rms difference, over the
    reference's departure from its value before the cleat (both at the same times)."""
    out = {}
    for i, name in enumerate(("rim_Fz", "rim_Fx")):
        before = reference[0, i]
        peak = np.abs(reference[:, i] - before).max()
        out[name] = (abs(np.abs(run[:, i] - before).max() - peak) / peak,
                     np.sqrt(np.mean((run[:, i] - reference[:, i]) ** 2))
                     / np.sqrt(np.mean((reference[:, i] - before) ** 2)))
    return out


@pytest.fixture(scope="module")
def fine(fmu_path, cleat_file):
    return cleat_run(fmu_path, FINE_S, str(cleat_file))


def at(h, fine_run):
    every = int(round(h / FINE_S))
    return fine_run[every - 1::every]


@pytest.mark.parametrize("h, within", [(1e-3, 0.02), (2e-3, 0.03)])
def test_a_cleat_in_a_road_file_does_not_depend_on_the_host_step(fmu_path, cleat_file, fine,
                                                                 h, within):
    """The road is read by position at the tire's own step: at 1 ms (20 mm of road a step,
    the cleat's length) and 2 ms the peaks and the histories are the 0.1 ms run's (before
    issue 37 the peak of Fz was 15 % low at 1 ms, the road arriving at the host's step)."""
    assert np.ptp(fine[:, 0]) > 0.2 * fine[0, 0] and np.ptp(fine[:, 1]) > 2e3  # a real hit
    found = differences(cleat_run(fmu_path, h, str(cleat_file)), at(h, fine))
    for name, (peak, rms) in found.items():
        assert peak < within and rms < within, (name, peak, rms)


@pytest.mark.parametrize("offset_mm", [0.0, 1.0, 2.5, 4.0])
def test_the_hosts_road_at_1_ms_is_the_road_files(fmu_path, cleat_file, offset_mm):
    """The same cleat owned by the host, its heights given where the FMU asks (road_x_i):
    within 3 % of the road file's run at 0.1 ms, wherever the samples fall on the cleat (the
    wheel's start moved by a part of the contact points' 10 mm spacing; at 0 measured
    earlier with a cleat of 0.1 mm edges: 2.1 % and 2.5 % rms)."""
    start = START_M + 1e-3 * offset_mm
    fine = cleat_run(fmu_path, FINE_S, str(cleat_file), start=start)
    found = differences(cleat_run(fmu_path, 1e-3, road=cleat_road(), start=start),
                        at(1e-3, fine))
    for name, (peak, rms) in found.items():
        assert peak < 0.03 and rms < 0.03, (name, peak, rms)


def refused_at_initialisation(path, road_file) -> str:
    fmu = Instance(str(path), road_file=str(road_file))
    with pytest.raises(FMICallException):
        fmu.start()
    said = " ".join(m for _, m in fmu.log)
    # and it stays refused: no step on a road it could not read
    with pytest.raises(FMICallException):
        fmu.fmu.doStep(0.0, 1e-3)
    fmu.fmu.freeInstance()
    return said


@pytest.mark.parametrize("case", ["missing", "not a road", "a number missing"])
def test_a_road_file_it_cannot_read_is_refused_at_initialisation(fmu_path, tmp_path, case):
    path = tmp_path / {"missing": "nowhere.crg", "not a road": "notes.txt",
                       "a number missing": "short.txt"}[case]
    if case == "not a road":
        path.write_text("these are no heights\n")
    elif case == "a number missing":
        path.write_text("0 0\n1 0.01\n2\n")
    said = refused_at_initialisation(fmu_path, path)
    assert "road_file" in said and str(path) in said, said
    what = {"missing": ("no such file", "not found", "does not exist", "cannot be opened"),
            "not a road": ("line 1",), "a number missing": ("line 3",)}[case]
    assert any(words in said.lower() for words in what), said


def test_a_zone_that_leaves_the_road_files_road_is_warned_of_once(fmu_path, tmp_path):
    """A road 2.3 m long, the wheel from 1.9 m at 10 m/s: the zone's front leaves it after
    about 25 ms; warned once (fmi2Warning) naming the file, the road level beyond it."""
    path = write_road(tmp_path / "short.txt", sampled_obstacle(
        cleat(0.01, 0.05), 1e-3, lead_in_m=1.0, lead_out_m=1.25))
    fmu = Instance(str(fmu_path), x0=1.9, speed=10.0, road_file=str(path)).start()
    first = len(fmu.log)
    for _ in range(60):
        fmu.step(1e-3)
    fmu.close()
    warned = [(status, m) for status, m in fmu.log[first:] if "beyond the road file" in m]
    assert len(warned) == 1 and warned[0][0] == 1, fmu.log[first:]
    assert str(path) in warned[0][1] and "level at its end heights" in warned[0][1]
    assert "np.float64" not in warned[0][1]  # the position as a number (it once showed numpy's)
