"""Files that look valid are valid: FMUs and the demo's outputs appear whole or not at all.

Each FMU build writes under a name of its own and puts the finished, validated FMU in place in
one step (tire_fmu.publish), so concurrent builds of one path, builds that fail validation and
builds cut short by Ctrl-C or a kill never leave a broken or half-built FMU where a host or
the demo's up-to-date check would take it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest

from tire_fmu.publish import PART, publish_folder, published_file

ROOT = Path(__file__).resolve().parents[1]

#: Run in a fresh process: hold at the first zip opened for writing until ``count`` processes
#: are there, so that concurrent builds surely write their FMUs at the same time; then run the
#: command (``tire-fmu ...`` or ``build_fmu.py ...``).
TOGETHER = textwrap.dedent("""
    import os, runpy, sys, time, zipfile
    from pathlib import Path

    barrier, count, argv = Path(sys.argv[1]), int(sys.argv[2]), sys.argv[3:]
    opened = zipfile.ZipFile.__init__
    held = []

    def hold_once(self, file, mode="r", *args, **kwargs):
        opened(self, file, mode, *args, **kwargs)
        if mode == "w" and not held:
            held.append(file)
            (barrier / str(os.getpid())).touch()
            deadline = time.monotonic() + 300
            while len(list(barrier.iterdir())) < count and time.monotonic() < deadline:
                time.sleep(0.01)

    zipfile.ZipFile.__init__ = hold_once
    if argv[0] == "build_fmu.py":
        sys.argv = argv
        runpy.run_path(argv[0], run_name="__main__")
    else:
        from tire_fmu.cli import main
        sys.exit(main(argv[1:]))
""")


def _whole_and_valid(fmu: Path) -> None:
    from fmpy.validation import validate_fmu

    with zipfile.ZipFile(fmu) as archive:
        assert archive.testzip() is None  # every entry's CRC checks
    assert validate_fmu(str(fmu)) == []


def _run_together(tmp_path: Path, commands: list[list[str]]) -> list[subprocess.CompletedProcess]:
    barrier = tmp_path / "barrier"
    barrier.mkdir()
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    started = [subprocess.Popen([sys.executable, "-c", TOGETHER, str(barrier),
                                 str(len(commands)), *command], cwd=ROOT, env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
               for command in commands]
    done = []
    for process, command in zip(started, commands):
        out, err = process.communicate(timeout=600)
        done.append(subprocess.CompletedProcess(command, process.returncode, out, err))
    assert len(list(barrier.iterdir())) == len(commands)  # all were writing at once
    return done


@pytest.mark.fmu
@pytest.mark.slow
def test_concurrent_native_exports_to_one_path_each_publish_a_whole_fmu(tmp_path):
    target = tmp_path / "out" / "same.fmu"
    target.parent.mkdir()
    command = ["tire-fmu", "export", "--format", "fmu", str(target), "--platform", "linux64"]
    for done in _run_together(tmp_path, [command, command]):
        assert done.returncode == 0, done.stderr
    _whole_and_valid(target)
    assert sorted(p.name for p in target.parent.iterdir()) == ["same.fmu"]  # nothing left


@pytest.mark.fmu
@pytest.mark.slow
def test_concurrent_python_fmu_builds_to_one_folder_each_publish_a_whole_fmu(tmp_path):
    from tire_fmu.fmu.builder import build_record

    out = tmp_path / "SAME"
    command = ["build_fmu.py", "-o", str(out)]
    for done in _run_together(tmp_path, [command, command]):
        assert done.returncode == 0, done.stderr
        assert Path(done.stdout.strip()) == out / "TireModal.fmu"
    _whole_and_valid(out / "TireModal.fmu")
    record = build_record(out / "TireModal.fmu")
    assert record["built_by"] == "tire_fmu 0.1.0" and record["guard"] is True
    assert "linux64" in record["kernel"]
    assert sorted(p.name for p in out.iterdir()) == ["TireModal.fmu"]


def _interrupt(*_, **__):
    raise KeyboardInterrupt


@pytest.mark.fmu
def test_a_build_interrupted_before_the_guard_publishes_nothing(tmp_path, monkeypatch):
    # between pythonfmu's write and the guard's compile: pythonfmu's zip on its own is a valid
    # FMU whose binary cannot return fmi2Error (R = -1 would pass initialisation)
    import tire_fmu.fmu.builder as builder

    monkeypatch.setattr(builder, "compile_guard", _interrupt)
    with pytest.raises(KeyboardInterrupt):
        builder.build_fmu(tmp_path / "dist")
    assert list((tmp_path / "dist").iterdir()) == []  # no FMU, no partial file


@pytest.mark.fmu
@pytest.mark.parametrize("where", ["compile_guard", "validation_problems"])
def test_a_build_killed_midway_publishes_nothing(tmp_path, where):
    # os._exit: no exception handler, no clean-up runs, as under SIGKILL
    script = textwrap.dedent(f"""
        import os, sys
        import tire_fmu.fmu.builder as builder
        builder.{where} = lambda *_, **__: os._exit(9)
        builder.build_fmu(sys.argv[1])
    """)
    private_tmp = tmp_path / "tmp"  # where the killed build's staging folders stay behind
    private_tmp.mkdir()
    out = tmp_path / "dist"
    done = subprocess.run([sys.executable, "-c", script, str(out)], cwd=ROOT, timeout=300,
                          env={**os.environ, "TMPDIR": str(private_tmp)},
                          capture_output=True, text=True)
    assert done.returncode == 9, done.stderr
    assert not (out / "TireModal.fmu").exists()
    assert all(p.name.startswith(f".TireModal.fmu.{PART}") for p in out.iterdir())


@pytest.mark.fmu
def test_a_build_that_fails_validation_leaves_the_previous_fmu_alone(tmp_path, monkeypatch,
                                                                       python_fmu_path):
    import tire_fmu.fmu.builder as builder

    dest = tmp_path / "TireModal.fmu"
    monkeypatch.setattr(builder, "validation_problems", lambda fmu: ["a problem"])
    with pytest.raises(builder.FmuBuildError, match="does not validate: a problem"):
        builder.build_fmu(dest)
    assert list(tmp_path.iterdir()) == []  # none published
    previous = python_fmu_path.read_bytes()
    dest.write_bytes(previous)
    with pytest.raises(builder.FmuBuildError, match="does not validate: a problem"):
        builder.build_fmu(dest, tire=builder_tire())
    assert dest.read_bytes() == previous and list(tmp_path.iterdir()) == [dest]


def builder_tire():
    from tire_fmu.core import TireParameters

    return TireParameters(k_r1=7e6)  # a build that would differ from the previous FMU


@pytest.mark.fmu
def test_a_native_build_that_fails_validation_publishes_nothing(tmp_path, monkeypatch):
    import tire_fmu.native.builder as native

    dest = tmp_path / "TireModalNative.fmu"
    native.build_native_fmu(dest, platforms=())  # sources only: no compiler needed
    previous = dest.read_bytes()
    monkeypatch.setattr(native, "validation_problems", lambda fmu: ["a problem"])
    with pytest.raises(native.NativeBuildError, match="does not validate: a problem"):
        native.build_native_fmu(dest, {"load": 20_000.0}, platforms=())
    assert dest.read_bytes() == previous and list(tmp_path.iterdir()) == [dest]


# -- the helpers themselves ---------------------------------------------------------------------

def test_a_published_file_appears_whole_or_not_at_all(tmp_path):
    dest = tmp_path / "f.txt"
    dest.write_text("old")
    with pytest.raises(RuntimeError):
        with published_file(dest) as partial:
            partial.write_text("half")
            assert dest.read_text() == "old"  # not yet
            raise RuntimeError
    assert dest.read_text() == "old" and list(tmp_path.iterdir()) == [dest]
    with published_file(dest) as partial, published_file(dest) as other:
        assert partial != other  # two writers, two names
        partial.write_text("new")
        other.write_text("newer")
    assert dest.read_text() == "new" and list(tmp_path.iterdir()) == [dest]
    mask = os.umask(0)
    os.umask(mask)
    assert dest.stat().st_mode & 0o777 == 0o666 & ~mask  # not mkstemp's 0600


@pytest.mark.parametrize("atomic_exchange", [True, False])
def test_a_published_folder_replaces_the_old_one_whole(tmp_path, monkeypatch, atomic_exchange):
    import tire_fmu.publish as publish

    if not atomic_exchange:
        def unsupported(a, b):
            raise OSError(38, "not here")

        monkeypatch.setattr(publish, "exchange", unsupported)
    dest = tmp_path / "out"
    dest.mkdir()
    (dest / "old.txt").write_text("old")
    finished = publish.private_folder(dest)
    (finished / "new.txt").write_text("new")
    publish_folder(finished, dest)
    assert [p.name for p in dest.iterdir()] == ["new.txt"]
    mask = os.umask(0)
    os.umask(mask)
    assert dest.stat().st_mode & 0o777 == 0o777 & ~mask  # as mkdir makes it, not 0700
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # the old folder is gone
    again = publish.private_folder(tmp_path / "fresh")
    publish_folder(again, tmp_path / "fresh")  # no previous folder
    assert (tmp_path / "fresh").is_dir() and not again.exists()
