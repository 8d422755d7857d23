"""Outputs are written, then published (issue 36): a file in place is a whole one, the
previous one until the new one is complete, and a demo run's files are one run's set.

A write that fails part-way (the disk fills after some bytes) leaves the previous file as it
was, for every writer: model exports (.npz, .mat), tire files, figures, and ``tire-fmu
inplane-reduce --out F``, which rewrote F in place. A braking demo run killed with SIGKILL at
random moments while it writes leaves its folder holding the previous run's set or the new
one's, whole, never a figure cut short beside the other run's summary.
"""

from __future__ import annotations

import builtins
import errno
import json
import os
import pathlib
import random
import signal
import subprocess
import sys
import textwrap
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from tire_fmu.model_files import (
    load_inplane_npz,
    load_mat,
    save_inplane_mat,
    save_inplane_npz,
)
from tire_fmu.tire_files import TireFileError, read_tire_file, write_tire_file

ROOT = Path(__file__).resolve().parents[1]


class _FillingFile:
    """A file opened for writing that takes ``room`` bytes, then fails as a full disk does."""

    def __init__(self, raw, room: list[int]):
        self._raw, self._room = raw, room

    def write(self, data):
        size = len(data) if not isinstance(data, memoryview) else data.nbytes
        if size > self._room[0]:
            self._raw.write(data[:self._room[0]])
            self._room[0] = 0
            self._raw.flush()
            raise OSError(errno.ENOSPC, "No space left on device")
        self._room[0] -= size
        return self._raw.write(data)

    def __getattr__(self, name):
        return getattr(self._raw, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._raw.close()

    def __iter__(self):
        return iter(self._raw)


@contextmanager
def disk_fills_after(monkeypatch, room: int):
    """Every file opened for writing in the block takes ``room`` bytes in all, then fails."""
    left = [room]
    real_open, real_path_open = builtins.open, pathlib.Path.open

    def writing(mode) -> bool:
        return any(flag in str(mode) for flag in "wax+")

    def fake_open(file, mode="r", *args, **kwargs):
        raw = real_open(file, mode, *args, **kwargs)
        return _FillingFile(raw, left) if writing(mode) else raw

    def fake_path_open(self, mode="r", *args, **kwargs):
        raw = real_path_open(self, mode, *args, **kwargs)
        return _FillingFile(raw, left) if writing(mode) else raw

    with monkeypatch.context() as patch:
        patch.setattr(builtins, "open", fake_open)
        patch.setattr(pathlib.Path, "open", fake_path_open)
        yield


def _model(states: int, seed: int):
    from tire_fmu.core.inplane_io import InPlaneStateSpace

    rng = np.random.default_rng(seed)
    outputs = ("rim_Fx", "rim_Fz", "rim_My", "wheel_rate")
    return InPlaneStateSpace(
        rng.normal(size=(states, states)), rng.normal(size=(states, 4)),
        rng.normal(size=(4, states)), *(rng.normal(size=(4, 4)) for _ in range(3)),
        input_names=("torque", "rim_x", "rim_z", "road_0"), output_names=outputs,
        road_delays_s=np.array([[0.0, 0.001]]),
        operating_point={"static_outputs": dict.fromkeys(outputs, 0.0)}, report={})


def _figure(path, seed):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tire_fmu.publish import save_figure

    fig = plt.figure(figsize=(6, 4))
    fig.add_subplot().imshow(np.random.default_rng(seed).random((200, 300)))
    save_figure(fig, path, dpi=100)
    plt.close(fig)


def _tire_file(path, seed):
    from tire_fmu.core.parameters import TireParameters

    write_tire_file(path, TireParameters(R=0.5 + 0.01 * seed), name=f"tire {seed}")


WRITERS = {
    "npz": (lambda path, seed: save_inplane_npz(_model(40, seed), path),
            lambda path: load_inplane_npz(path).a),
    "mat": (lambda path, seed: save_inplane_mat(_model(40, seed), path),
            lambda path: load_mat(path)["A"]),
    "toml": (_tire_file, lambda path: read_tire_file(path).tire.R),
    "png": (_figure, lambda path: __import__("matplotlib.image").image.imread(path).shape),
}


@pytest.mark.parametrize("kind", sorted(WRITERS))
@pytest.mark.parametrize("share", [0.0, 0.01, 0.5, 0.95])
def test_a_write_that_fails_part_way_leaves_the_previous_file(tmp_path, monkeypatch, kind,
                                                              share):
    """The disk fills after ``share`` of the file's size: the previous file stays."""
    write, read = WRITERS[kind]
    path = tmp_path / f"out.{kind}"
    write(path, 1)
    before = path.read_bytes()
    room = int(share * len(before))
    with disk_fills_after(monkeypatch, room), pytest.raises((OSError, TireFileError)):
        write(path, 2)
    assert path.read_bytes() == before
    read(path)  # and it still loads
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # nothing left behind


def test_inplane_reduce_out_fails_part_way_and_keeps_the_previous_model(tmp_path, monkeypatch,
                                                                        capsys):
    from tire_fmu.cli import main

    out = tmp_path / "tire.npz"
    argv = ["inplane-reduce", "--elements", "20", "--speed", "0", "--wheel", "held", "--out",
            str(out)]
    assert main(argv) == 0
    before = out.read_bytes()
    capsys.readouterr()
    with disk_fills_after(monkeypatch, 20_000):
        assert main(argv + ["--target-error", "0.001"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--out" in err and "No space left" in err, err
    assert out.read_bytes() == before
    assert load_inplane_npz(out).n_states > 0


# -- a demo run's set ----------------------------------------------------------------------------

#: A braking demo run (vehicle_demo.braking.run_braking, its checks and its publication as
#: they are) whose physics is replaced by writing what a run writes, large enough that a kill
#: lands inside the writing: the two figures and summary.json, each marked with the run.
BRAKING_RUN = textwrap.dedent("""
    import json, sys
    from pathlib import Path

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    import vehicle_demo.braking as braking
    from tire_fmu.publish import save_figure

    out, run = Path(sys.argv[1]), sys.argv[2]

    def write_the_set(settings, work, final, started, log):
        print("writing", flush=True)
        rng = np.random.default_rng(int(run))
        figures = []
        for name in ("braking.png", "cleat_test.png"):
            fig = plt.figure(figsize=(12, 9))
            fig.add_subplot().imshow(rng.random((900, 1200)))
            figures.append(save_figure(fig, work / name, dpi=100, metadata={"Title": run}))
            plt.close(fig)
        (work / "summary.json").write_text(json.dumps({"run": run, "pad": [0.5] * 200000}))
        return braking.BrakingSummary((), 0.0, 0.0, 0.0, {}, tuple(figures), 0.0)

    braking._run_braking = write_the_set
    braking.run_braking(braking.BrakingSettings(out_dir=out, progress=False), log=print)
    print("done", flush=True)
""")


def _braking_run(out: Path, run: int) -> subprocess.Popen:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.Popen([sys.executable, "-c", BRAKING_RUN, str(out), str(run)], cwd=ROOT,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _the_set(out: Path) -> str:
    """The run whose set ``out`` holds, every file whole and of that run."""
    from PIL import Image

    assert sorted(p.name for p in out.iterdir()) == ["braking.png", "cleat_test.png",
                                                      "summary.json"]
    runs = {json.loads((out / "summary.json").read_text())["run"]}
    for name in ("braking.png", "cleat_test.png"):
        with Image.open(out / name) as image:
            image.load()  # reads every byte: a truncated PNG raises
            runs.add(image.info["Title"])
    assert len(runs) == 1, runs
    return runs.pop()


def test_a_braking_run_killed_while_it_writes_never_leaves_a_mixed_set(tmp_path):
    pytest.importorskip("PIL")
    out = tmp_path / "braking_output"
    first = _braking_run(out, 1)
    assert first.communicate(timeout=300)[0].splitlines()[-1] == "done"
    assert _the_set(out) == "1"
    chooser = random.Random(36)
    published = "1"
    for run in range(2, 8):
        process = _braking_run(out, run)
        assert process.stdout.readline().strip() == "writing"
        time.sleep(chooser.uniform(0.0, 1.5))
        process.send_signal(signal.SIGKILL)
        process.communicate(timeout=60)
        found = _the_set(out)
        assert found in (published, str(run))
        published = found
