"""What the Python FMU imports to start: only what building and stepping the contact simulator
need. Each check runs in a fresh interpreter and looks at ``sys.modules`` after
fmi2ExitInitializationMode (the time it takes is benchmarks/bench_fmu_init.py's business)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Modules the FMU's start-up path must not load: the sparse assembly, the modal analysis and
#: reduction, scipy's optimisers, plotting and the command line.
NOT_NEEDED = (
    "scipy.sparse", "scipy.optimize", "scipy.spatial", "scipy.stats", "scipy.integrate",
    "scipy.interpolate", "matplotlib", "tire_fmu.core.complex_modal", "tire_fmu.core.modal",
    "tire_fmu.core.balanced", "tire_fmu.core.rotation", "tire_fmu.core.studies",
    "tire_fmu.core.fit", "tire_fmu.core.frequency_response", "tire_fmu.cli", "tire_fmu.plots",
)

#: After the check, prints what of NOT_NEEDED is loaded, and what the FMU said it built.
REPORT = """
import json, sys
print(json.dumps({"loaded": sorted(set(NOT_NEEDED) & set(sys.modules)), "fz": fz}))
"""


def _run(code: str) -> dict:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def _with_report(body: str) -> str:
    return (f"NOT_NEEDED = {NOT_NEEDED!r}\n" + textwrap.dedent(body) + REPORT)


def test_the_slave_initialises_without_what_it_does_not_need():
    """The slave module and an initialisation at the defaults (N = 100), in plain Python."""
    found = _run(_with_report("""
        from tire_fmu.fmu.slave import Phase, TireModal
        slave = TireModal(instance_name="tire", resources=".", visible=False)
        slave.setup_experiment(0.0)
        slave.enter_initialization_mode()
        slave.exit_initialization_mode()
        assert slave._phase == Phase.RUNNING, [m.msg for m in slave.log_queue]
        fz = slave.get_real([slave._index["rim_Fz"]])[0]
    """))
    assert found["loaded"] == []
    from tire_fmu.core import DEFAULT_LOAD_N

    assert found["fz"] == pytest.approx(DEFAULT_LOAD_N, rel=1e-9)  # it did build the model


def test_the_core_build_path_leaves_the_sparse_model_unassembled():
    """build_contact_model and a step: the patch, critical speed and free ring only."""
    found = _run(_with_report("""
        from tire_fmu.core.contact_dynamics import ContactSimulator, build_contact_model
        contact = build_contact_model()
        assert "structure" not in vars(contact.model)  # never asked for
        fz = ContactSimulator(contact).step_values(1e-4, 0.0, 0.0, 0.0, 0.0)[0]
    """))
    assert found["loaded"] == []
    assert found["fz"] > 0


def test_importing_the_core_package_imports_none_of_it():
    found = _run("""
import json, sys
import tire_fmu.core
print(json.dumps({"loaded": sorted(m for m in sys.modules
                                   if m.startswith(("numpy", "scipy", "tire_fmu.core.")))}))
""")
    assert found["loaded"] == []


def test_the_core_names_are_their_modules_definitions():
    import importlib

    import tire_fmu.core as core

    for name in core.__all__:
        module = importlib.import_module(f"tire_fmu.core.{core._SOURCES[name]}")
        assert getattr(core, name) is getattr(module, name), name
    assert set(core.__all__) <= set(dir(core))
    with pytest.raises(AttributeError, match="no_such_name"):
        core.no_such_name  # noqa: B018
    from tire_fmu.core import clock  # a submodule, not one of the names

    assert clock.__name__ == "tire_fmu.core.clock"


def test_the_assembled_matrices_follow_from_the_model_on_first_use():
    """The lazy structure and contact springs equal the assembly from the same fields."""
    import numpy as np

    from tire_fmu.core import OperatingPoint, build_model, undeformed
    from tire_fmu.core.model import structural_matrices

    model = build_model(op=OperatingPoint(n_elements=40, speed_m_s=10.0))
    assert "structure" not in vars(model) and "contact_stiffness" not in vars(model)
    expected = structural_matrices(model.tire, model.grid, 10.0 / model.tire.R)
    assert abs(model.structure.stiffness - expected.stiffness).max() == 0
    assert abs(model.structure.damping - expected.damping).max() == 0
    springs = model.contact_stiffness.toarray()
    patch, zone = model.patch, model.patch.zone
    interp = zone.interpolation
    block = interp.T @ np.diag(patch.point_stiffness_n_per_m) @ interp  # Iᵀ diag(k) I
    np.testing.assert_allclose(springs[np.ix_(zone.nodes, zone.nodes)], block, rtol=1e-14,
                               atol=0)
    springs[np.ix_(zone.nodes, zone.nodes)] = 0.0
    assert not springs.any() and patch.contact_points.size > 0
    assert undeformed(model).contact_stiffness.nnz == 0


@pytest.mark.fmu
def test_the_built_fmu_initialises_through_fmpy_without_what_it_does_not_need(
        python_fmu_path, tmp_path):
    """The FMU as a host loads it: fmpy, the shipped resources, the defaults (N = 100)."""
    from fmpy import extract, read_model_description

    description = read_model_description(str(python_fmu_path))
    rim_fz = next(v.valueReference for v in description.modelVariables if v.name == "rim_Fz")
    folder = str(extract(str(python_fmu_path), unzipdir=str(tmp_path / "unzipped")))
    found = _run(_with_report(f"""
        import sys
        from fmpy.fmi2 import FMU2Slave
        slave = FMU2Slave(guid={description.guid!r}, unzipDirectory={folder!r},
                          modelIdentifier={description.coSimulation.modelIdentifier!r},
                          instanceName="tire")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        with open({folder!r} + "/resources/slavemodule.txt") as module:
            package = module.read().strip().removesuffix("_slave")
        # the FMU's copy, under its own name: what it must not load is named so there
        assert sys.modules[package].__file__.startswith({folder!r})
        assert "tire_fmu" not in sys.modules
        NOT_NEEDED = tuple(n.replace("tire_fmu.", package + ".", 1) for n in NOT_NEEDED)
        fz = slave.getReal([{rim_fz}])[0]
        slave.terminate()
        slave.freeInstance()
    """))
    assert found["loaded"] == []
    assert found["fz"] > 0


@pytest.mark.fmu
def test_a_fresh_extraction_imports_the_shipped_bytecode(python_fmu_path, tmp_path):
    """Every Python file in the FMU has its bytecode beside it, checked by the source's hash:
    from a fresh extraction (time stamps not kept) with bytecode writing off, as hosts run,
    the slave and everything it imports from the FMU load without compiling a line."""
    import zipfile

    with zipfile.ZipFile(python_fmu_path) as archive:
        names = set(archive.namelist())
        archive.extractall(tmp_path)
    sources = sorted(n for n in names if n.startswith("resources/") and n.endswith(".py"))
    tag = sys.implementation.cache_tag
    missing = [n for n in sources if "{0}/__pycache__/{2}.{1}.pyc".format(
        *n.rsplit("/", 1)[0:1], tag, n.rsplit("/", 1)[1][:-3]) not in names]
    assert len(sources) > 30 and missing == []
    resources = tmp_path / "resources"
    slave = (resources / "slavemodule.txt").read_text().strip()
    code = textwrap.dedent(f"""
        import importlib.machinery, json, sys
        compiled = []
        original = importlib.machinery.SourceFileLoader.source_to_code
        def counted(self, data, path, *args, **kwargs):
            compiled.append(path)
            return original(self, data, path, *args, **kwargs)
        importlib.machinery.SourceFileLoader.source_to_code = counted
        sys.path.insert(0, {str(resources)!r})
        import {slave}
        ours = [m.__file__ for m in list(sys.modules.values())
                if getattr(m, "__file__", None) and m.__file__.startswith({str(resources)!r})]
        print(json.dumps({{"compiled": compiled, "ours": len(ours)}}))
    """)
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    env.pop("PYTHONPATH", None)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, cwd=tmp_path, timeout=120)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["ours"] > 15 and found["compiled"] == []
