"""Publishing files and folders whole: written under a private name, then put in place at once.

Every file the package writes goes through :func:`published_file` (figures through
:func:`save_figure`); a set of files that belong together (a demo run's figures, tables and
summary) is written into a private folder that :func:`published_folder` puts in place of the
previous run's folder in one step (files written into a private folder, there or in a build's
staging folder, are published with it). A folder, not a manifest: a reader of the folder needs no
protocol to see one run's set (with a manifest written last, a reader would have to check it
and the files it names), and on Linux the exchange of the two folders is atomic.

A reader of the published path sees the previous content or the finished new one, never a
half-written file, and two writers of one path never share a temporary name (each gets its
own folder from :func:`tempfile.mkdtemp`, beside the destination so that the final rename
stays on one file system and is atomic). A writer that fails, or is interrupted, removes what
it wrote and leaves the destination as it was; one that is killed outright leaves only its
hidden ``.NAME.*`` folder behind.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import errno
import os
import shutil
import sys
import tempfile
from collections.abc import Collection, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

#: prefix of the private folders, after the destination's name: ``.TireModal.fmu.part-...``
PART = "part-"


def private_folder(dest: Path) -> Path:
    """A new folder only this writer uses, beside ``dest`` (whose parent must exist)."""
    return Path(tempfile.mkdtemp(prefix=f".{dest.name}.{PART}", dir=dest.parent))


@contextmanager
def published_file(dest: str | Path) -> Iterator[Path]:
    """A path to write ``dest``'s new content to; when the block ends without an exception
    the file replaces ``dest`` in one step. Whatever the block raises (an error, a failed
    check, KeyboardInterrupt), ``dest`` keeps its previous content and the partial file is
    removed. The file is created with the process's default permissions (umask)."""
    dest = Path(dest)
    folder = private_folder(dest)
    try:
        partial = folder / dest.name
        yield partial
        os.replace(partial, dest)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def save_figure(fig, path: str | Path, **options) -> Path:
    """A matplotlib figure written to ``path`` (its format from the extension) through
    :func:`published_file`; ``options`` go to ``savefig``."""
    path = Path(path)
    with published_file(path) as partial:
        fig.savefig(partial, **options)
    return path


@contextmanager
def published_folder(dest: str | Path, carry: Sequence[str] = ()) -> Iterator[Path]:
    """A new private folder to write a set of files that belong together into (a run's
    figures and its summary); when the block ends without an exception the folder replaces
    ``dest`` whole (:func:`publish_folder`), so that ``dest`` holds one run's set or the
    previous one, never a mix. Whatever the block raises, ``dest`` stays as it was. The
    entries of ``dest`` named in ``carry`` (files, or folders of files: FMUs to reuse) are
    linked into the new folder first (copied where the file system has no hard links)."""
    dest = Path(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)
    work = private_folder(dest)
    try:
        for name in carry:
            _link_tree(dest / name, work / name)
        yield work
        publish_folder(work, dest)
    finally:
        shutil.rmtree(work, ignore_errors=True)  # gone already once published


def _link_tree(source: Path, target: Path) -> None:
    if source.name.startswith("."):  # a writer's private folder, left by a kill
        return
    if source.is_dir():
        target.mkdir()
        for item in source.iterdir():
            _link_tree(item, target / item.name)
    elif source.is_file():
        try:
            os.link(source, target)
        except OSError:
            shutil.copy2(source, target)  # keeps the times an up-to-date check reads


def foreign_entries(dest: str | Path, outputs: Collection[str]) -> list[str]:
    """The entries of the folder ``dest`` a run that writes ``outputs`` did not write (a
    folder replaced whole would lose them), sorted; none when ``dest`` does not exist."""
    dest = Path(dest)
    if not dest.is_dir():
        return []
    return sorted(item.name for item in dest.iterdir() if item.name not in outputs)


def publish_folder(finished: Path, dest: Path) -> None:
    """Put the complete folder ``finished`` (a :func:`private_folder` of ``dest``) in place
    of ``dest`` and delete what ``dest`` held.

    Where the system can exchange two paths in one step (Linux ``renameat2`` with
    ``RENAME_EXCHANGE``), ``dest`` is never missing nor mixed; elsewhere the old folder is
    first renamed aside, so an interruption between the two renames leaves ``dest`` missing,
    the previous content in a hidden ``.NAME.part-*`` folder beside it, never a mix.
    """
    finished, dest = Path(finished), Path(dest)
    # mkdtemp made it private (0700): published, it gets what mkdir would have given it
    os.chmod(finished, 0o777 & ~_umask())
    if not dest.exists():
        os.rename(finished, dest)
        return
    try:
        exchange(finished, dest)
        old = finished
    except OSError:
        old = private_folder(dest)
        os.rename(dest, old / dest.name)
        os.rename(finished, dest)
    shutil.rmtree(old, ignore_errors=True)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def exchange(a: Path, b: Path) -> None:
    """Swap the paths ``a`` and ``b`` atomically; OSError where the system cannot."""
    if not sys.platform.startswith("linux"):
        raise OSError(errno.ENOSYS, "no atomic exchange on this system")
    libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
    renameat2 = getattr(libc, "renameat2", None)
    if renameat2 is None:  # glibc before 2.28, or another C library
        raise OSError(errno.ENOSYS, "renameat2 is not available")
    renameat2.argtypes = (ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint)
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code), str(a), None, str(b))
