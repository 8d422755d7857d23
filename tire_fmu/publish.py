"""Publishing files and folders whole: written under a private name, then put in place at once.

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
from collections.abc import Iterator
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
