"""The native FMU in other hosts and on other platforms: the win64 binary under wine against the
linux64 one (a small C host for each), a strict C host through a lift-off, the sources built
again with fmpy's build, libcosimpy and ecospy against fmpy."""

from __future__ import annotations

import shutil
import zipfile
from pathlib import Path

import pytest
from native_support import (
    OUTPUTS,
    Opened,
    compile_host,
    host_outputs,
    in_host,
    needs_windows_tools,
    relative_errors,
    road_drop,
    run,
    run_host,
)

from tire_fmu.fmu.interface import fmu_variables

pytestmark = pytest.mark.fmu

@pytest.fixture(scope="module")
def unpacked(native_fmu_path, tmp_path_factory):
    folder = tmp_path_factory.mktemp("unpacked")
    zipfile.ZipFile(native_fmu_path).extractall(folder)
    return folder, Opened.of(native_fmu_path).model_description.guid


def _command_file(path: Path, parameters: dict, steps: int = 1200) -> Path:
    vr = {v.name: i for i, v in enumerate(fmu_variables())}
    lines = [f"real {vr[name]} {value!r}" for name, value in parameters.items()] + ["init"]
    for k in range(steps):
        t = k * 1e-4
        rim_z, rim_vz, road_z, road_vz = road_drop(t)
        lines += [f"real {vr['road_z']} {road_z!r}", f"real {vr['rim_z']} {rim_z!r}",
                  f"step {t!r} 0.0001"]
    path.write_text("\n".join(lines) + "\n")
    return path


@needs_windows_tools
def test_win64_under_wine_gives_the_linux64_outputs(unpacked, tmp_path):
    """The same C host, compiled for Windows (LoadLibrary/GetProcAddress) and for Linux, runs
    the same commands: outputs to 1e-12, the same statuses and the same log lines (the
    messages are printf'd by mingw's C library on one side and glibc on the other)."""
    folder, guid = unpacked
    linux = compile_host(folder, windows=False)
    windows = compile_host(folder, windows=True)
    for parameters in ({"load": 27700.0, "speed": 10.0},
                       {"load": 45000.0, "speed": 20.0, "n_elements": 120}):
        commands = _command_file(tmp_path / "run.txt", parameters)
        a = run_host(linux, folder / "binaries/linux64/TireModalNative.so", guid, commands)
        b = run_host(windows, folder / "binaries/win64/TireModalNative.dll", guid, commands)
        assert relative_errors(host_outputs(a), host_outputs(b)).max() < 1e-12
        assert [x for x in a if not x.startswith(("out ", "log "))] == [
            x for x in b if not x.startswith(("out ", "log "))]
        ready = "ready in"  # its CPU time differs
        assert [x for x in a if x.startswith("log ") and ready not in x] == [
            x for x in b if x.startswith("log ") and ready not in x]
    bad = _command_file(tmp_path / "bad.txt", {"R": -1.0, "beta": 0.5, "load": 1e9}, steps=0)
    a = run_host(linux, folder / "binaries/linux64/TireModalNative.so", guid, bad)
    b = run_host(windows, folder / "binaries/win64/TireModalNative.dll", guid, bad)
    assert a == b and sum("parameter problem" in line for line in a) == 2


def test_a_strict_c_host_runs_through_a_lift_off(unpacked, tmp_path):
    """Every doStep through a 5 cm road drop that lifts the tread off returns fmi2OK (a host
    that stops on fmi2Warning, as the C fmusim does, runs through)."""
    folder, guid = unpacked
    host = compile_host(folder, windows=False)
    lines = run_host(host, folder / "binaries/linux64/TireModalNative.so", guid,
                      _command_file(tmp_path / "run.txt", {"speed": 10.0}))
    statuses = [line for line in lines if line.startswith("status step")]
    assert len(statuses) == 1200 and set(statuses) == {"status step 0"}
    assert (host_outputs(lines)[:, 2] == 0.0).any()
    assert not [line for line in lines if line.startswith("log ") and line.split()[2] != "0"]


def test_sources_build_elsewhere_with_fmpy(native_fmu_path, tmp_path):
    """sources/ and its buildDescription.xml build on their own: fmpy's build (CMake) makes a
    linux64 binary that gives the shipped binary's outputs."""
    from fmpy.build import build_platform_binary

    folder = tmp_path / "rebuilt"
    zipfile.ZipFile(native_fmu_path).extractall(folder)
    shutil.rmtree(folder / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(folder, build_dir=tmp_path / "build")
    rebuilt = tmp_path / "rebuilt.fmu"
    with zipfile.ZipFile(rebuilt, "w") as archive:
        for path in sorted(folder.rglob("*")):
            if path.is_file():
                archive.write(path, path.relative_to(folder).as_posix())
    parameters = {"speed": 10.0}
    shipped = run(Opened.of(native_fmu_path), parameters, road_drop, steps=600)
    again = run(Opened.of(rebuilt), parameters, road_drop, steps=600)
    assert relative_errors(shipped, again).max() < 1e-12


@pytest.mark.parametrize("host", ["libcosimpy", "ecospy"])
@pytest.mark.parametrize("load, speed", [(27700.0, 0.0), (40000.0, 15.0)])
def test_other_hosts_give_fmpys_outputs(native_fmu_path, host, load, speed, tmp_path):
    reference = in_host(native_fmu_path, "fmpy", load, speed, tmp_path)
    other = in_host(native_fmu_path, host, load, speed, tmp_path)
    assert reference.shape == other.shape == (400, len(OUTPUTS))
    if speed == 0.0:
        assert (reference[:, 2] == 0.0).any()  # through a lift-off
    else:  # rolling, the 22 cm of dropped road is bridged by the tread on its edges
        assert reference[:, 2].min() < 0.6 * load  # but it loses much of its load
    assert relative_errors(reference, other).max() < 1e-9
