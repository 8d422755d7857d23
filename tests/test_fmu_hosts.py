"""The Python FMU in hosts that cannot run it: a process without Python refuses it loudly, even
when the host drops the FMU's log and ignores its statuses (as ecos's proxyfmu does)."""

from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
import textwrap
import zipfile
from importlib import metadata
from importlib.util import find_spec
from pathlib import Path

import pytest

pytestmark = pytest.mark.fmu

TIMEOUT_S = 300

# A C host in the way ecos's proxyfmu is one: no Python in the process, a logger that prints
# nothing, and a fmi2GetReal whatever fmi2Instantiate returned.
_SILENT_HOST = r"""
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include "fmi2Functions.h"
static void silent(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                   fmi2String m, ...) {}
int main(int argc, char **argv) {  /* binary, GUID, resource URI */
    void *h = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!h) { printf("dlopen failed\n"); return 2; }
    fmi2InstantiateTYPE *instantiate = (fmi2InstantiateTYPE *)dlsym(h, "fmi2Instantiate");
    fmi2GetRealTYPE *get_real = (fmi2GetRealTYPE *)dlsym(h, "fmi2GetReal");
    fmi2CallbackFunctions cb = {silent, 0, 0, 0, 0};
    fmi2Component c = instantiate("tire", fmi2CoSimulation, argv[2], argv[3], &cb, 0, 0);
    fmi2ValueReference vr = 0;
    fmi2Real value = 0.0;
    int status = get_real(c, &vr, 1, &value);
    printf("instance %s status %d value %s\n", c ? "made" : "NULL", status,
           isnan(value) ? "nan" : "number");
    return 0;
}
"""


@pytest.fixture(scope="module")
def unpacked(python_fmu_path, tmp_path_factory):
    from fmpy import read_model_description

    folder = tmp_path_factory.mktemp("unpacked")
    zipfile.ZipFile(python_fmu_path).extractall(folder)
    return read_model_description(python_fmu_path), folder


def test_a_process_without_python_gets_the_refusal_on_stderr_and_nan_outputs(unpacked,
                                                                             tmp_path):
    """The guard refuses fmi2Instantiate there (the wrapper needs the Python C API); a host
    whose logger prints nothing still sees why on stderr, and a fmi2GetReal on the NULL
    instance returns fmi2Error with NaN, not a plausible 0.0."""
    import fmpy

    compiler = shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        pytest.skip("no C compiler for the host")
    (tmp_path / "host.c").write_text(_SILENT_HOST)
    headers = Path(fmpy.__file__).parent / "c-code"
    subprocess.run([compiler, "-O1", "-I", str(headers), "-o", str(tmp_path / "host"),
                    str(tmp_path / "host.c"), "-ldl"], check=True)
    description, folder = unpacked
    binary = Path(folder) / "binaries" / "linux64" / "TireModal.so"
    done = subprocess.run([str(tmp_path / "host"), str(binary), description.guid,
                           (Path(folder) / "resources").as_uri()],
                          capture_output=True, text=True, timeout=TIMEOUT_S)
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.strip() == "instance NULL status 3 value nan"
    assert done.stderr.count("fmi2Instantiate refused") == 1, done.stderr
    assert "_Py_" in done.stderr and "must be a Python process" in done.stderr


# -- ecos (ecospy): in process, and in its proxyfmu process -----------------------------------

_ECOS_RUN = """
    import json, sys
    from ecospy import EcosSimulation, EcosSimulationStructure
    fmu, uri, out = sys.argv[1:]
    structure = EcosSimulationStructure()
    structure.add_model("tire", uri.replace("FMU", fmu))
    structure.add_parameter_set("initial", {"tire::load": 27700.0})
    simulation = EcosSimulation(structure=structure, step_size=1e-4)
    simulation.init(parameter_set="initial")
    rows = [[simulation.get_real("tire::rim_Fz"), simulation.get_real("tire::contact_Fz")]]
    for k in range(5):
        simulation.set_real("tire::road_z", 1e-4 * k)
        simulation.step()
        rows.append([simulation.get_real("tire::rim_Fz"),
                     simulation.get_real("tire::contact_Fz")])
    simulation.terminate()
    json.dump(rows, open(out, "w"))
"""


def _ecos(fmu: Path, uri: str, tmp_path: Path) -> list:
    if find_spec("ecospy") is None:
        pytest.skip("ecospy is not installed (test extra)")
    tbb = [Path(f.locate()).parent for f in metadata.files("tbb") or ()
           if f.name.startswith("libtbb.so")]
    assert tbb, "the tbb wheel (test extra) has no libtbb.so"
    for proxy in Path(find_spec("ecospy").origin).parent.glob("binaries/proxyfmu"):
        proxy.chmod(proxy.stat().st_mode | stat.S_IXUSR)  # the wheel ships it without
    env = dict(os.environ, LD_LIBRARY_PATH=os.pathsep.join(
        [str(tbb[0]), os.environ.get("LD_LIBRARY_PATH", "")]))
    out = tmp_path / "rows.json"
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(_ECOS_RUN), str(fmu), uri,
                           str(out)], capture_output=True, text=True, timeout=TIMEOUT_S,
                          env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    return json.loads(out.read_text())


def test_in_ecos_the_tire_runs_in_process_and_reads_zero_in_its_proxy(python_fmu_path,
                                                                       native_fmu_path,
                                                                       tmp_path):
    """What docs/fmu.md tells a user to check: rim_Fz after initialisation is the load when
    the tire runs; in ecos's proxyfmu process (no Python) the Python FMU reads 0.0 with no
    error, and the native FMU runs there."""
    in_process = _ecos(python_fmu_path, "FMU", tmp_path)
    assert in_process[0] == [pytest.approx(27700.0), pytest.approx(27700.0)]
    assert abs(in_process[-1][1] - 27700.0) > 10.0  # the road moved under the tire
    proxied = _ecos(python_fmu_path, "proxyfmu://localhost?file=FMU", tmp_path)
    assert all(value == 0.0 for row in proxied for value in row)
    native = _ecos(native_fmu_path, "proxyfmu://localhost?file=FMU", tmp_path)
    assert native[0] == [pytest.approx(27700.0), pytest.approx(27700.0)]
    assert native[-1][1] == pytest.approx(in_process[-1][1], rel=1e-6)
