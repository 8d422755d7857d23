"""The command line starts fast (no numpy before parsing) and limits BLAS threads."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

import tire_fmu
from tire_fmu.cli import main
from tire_fmu.cli.commands import COMMANDS

ROOT = Path(__file__).resolve().parents[1]


def _run(code: str, env_extra: dict | None = None) -> str:
    env = {**os.environ, "PYTHONPATH": str(ROOT), **(env_extra or {})}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=True, cwd=ROOT)
    return done.stdout


def test_help_imports_neither_numpy_nor_scipy():
    out = _run(
        "import sys\n"
        "from tire_fmu.cli import main\n"
        "try:\n"
        "    main(['--help'])\n"
        "except SystemExit:\n"
        "    pass\n"
        "print('LOADED', sorted(m for m in ('numpy', 'scipy') if m in sys.modules))\n"
    )
    assert "LOADED []" in out
    for name in COMMANDS:  # every command is listed
        assert name in out


def test_a_command_imports_only_its_own_module():
    out = _run(
        "import sys\n"
        "from tire_fmu.cli import build_parser\n"
        "build_parser(['analytic'])\n"
        "print(sorted(m for m in sys.modules if m.startswith('tire_fmu.cli.')))\n"
    )
    loaded = eval(out.strip())  # a list literal printed above
    assert "tire_fmu.cli.ring" in loaded
    assert not {"tire_fmu.cli.reduce", "tire_fmu.cli.rolling", "tire_fmu.cli.fmu"} & set(loaded)


def test_the_package_exports_the_core_lazily():
    assert tire_fmu.build_model is __import__("tire_fmu.core").core.build_model
    assert set(tire_fmu.__all__) == set(__import__("tire_fmu.core").core.__all__)
    with pytest.raises(AttributeError):
        tire_fmu.no_such_name  # noqa: B018


def _blas_threads_during(argv, monkeypatch, env=None):
    """The BLAS thread count a command's handler sees."""
    from threadpoolctl import threadpool_info

    import tire_fmu.cli.ring as ring

    seen = {}
    original = ring.run_analytic

    def spy(args):
        seen["threads"] = {info["num_threads"] for info in threadpool_info()
                           if info["user_api"] == "blas"}
        return original(args)

    monkeypatch.setattr(ring, "run_analytic", spy)
    if env is not None:
        monkeypatch.setenv("TIRE_FMU_BLAS_THREADS", env)
    else:
        monkeypatch.delenv("TIRE_FMU_BLAS_THREADS", raising=False)
    assert main([*argv, "analytic", "--json"]) == 0
    return seen["threads"]


def test_one_blas_thread_unless_told(monkeypatch):
    from threadpoolctl import threadpool_info, threadpool_limits

    with threadpool_limits(limits=2, user_api="blas"):
        if not any(i["num_threads"] == 2 for i in threadpool_info() if i["user_api"] == "blas"):
            pytest.skip("BLAS here cannot run two threads")  # e.g. a single-threaded build
        assert _blas_threads_during([], monkeypatch) == {1}
        assert _blas_threads_during(["--blas-threads", "2"], monkeypatch) == {2}
        assert _blas_threads_during([], monkeypatch, env="2") == {2}


def test_bad_thread_count_is_one_line(capsys):
    with pytest.raises(SystemExit) as caught:
        main(["--blas-threads", "-3", "analytic"])
    assert caught.value.code == 2
    assert "--blas-threads" in capsys.readouterr().err
