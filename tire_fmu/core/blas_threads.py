"""How many threads BLAS and LAPACK (numpy's and scipy's) may run while the tire is built.

The dense problems here (eigenproblems, inverses, Gramians of a few hundred rows) are small:
on a few shared cores BLAS's worker threads mostly wait on each other, and the library's
default of one thread per core costs several times the CPU and the wall time of one thread
(benchmarks/bench_cli.py, benchmarks/bench_fmu_init_threads.py). So the calls that build a
tire (``build_model``, ``build_contact_model``, ``reduce``, the FMUs' initialisation and the
model an FMU state rebuilds) run inside :func:`blas_threads`: at most
``TIRE_FMU_BLAS_THREADS`` threads (default 1; 0 leaves BLAS as the caller has it), and the
caller's own limits back when they return. The outermost :func:`blas_threads` decides: the
calls inside it (``reduce`` builds a model, the CLI runs a command) keep its limit.

threadpoolctl sets the limits, on the BLAS libraries loaded when the outermost
:func:`blas_threads` starts: numpy's, and scipy's, which it loads first (scipy imports
scipy.linalg lazily, and a BLAS loaded inside would run on its default threads) unless told
that the work needs none (TireModal's build, whose fresh start never loads scipy). It is a
dependency of the package, not of the physics: without it (an FMU in a host Python that lacks
it) everything runs on BLAS's default threads and :func:`unavailable` says why.
"""

from __future__ import annotations

import os
import sys
import threading
from contextlib import contextmanager

#: The environment variable with the thread count (0: the BLAS library's default).
BLAS_THREADS_ENV = "TIRE_FMU_BLAS_THREADS"
DEFAULT_BLAS_THREADS = 1

_lock = threading.Lock()
_depth = 0  # how many blas_threads are open in this process (any thread)
_limiter = None  # the outermost one's threadpoolctl limiter, or None if it changed nothing
_controller = None  # threadpoolctl's view of the loaded BLAS libraries
_scanned = -1  # len(sys.modules) when it was made: scanning again costs ~1 ms
_missing: str | None = None


def parse_blas_threads(text: str) -> int:
    """A thread count as the CLI and TIRE_FMU_BLAS_THREADS give it: an integer >= 0."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise ValueError(f"{text!r}: must be an integer >= 0 (0: the BLAS library's default)")
    return value


def configured_blas_threads() -> int:
    """``TIRE_FMU_BLAS_THREADS``, or 1 when it is not set; ValueError naming the variable when
    it is not an integer >= 0."""
    text = os.environ.get(BLAS_THREADS_ENV, str(DEFAULT_BLAS_THREADS))
    try:
        return parse_blas_threads(text)
    except ValueError as error:
        raise ValueError(f"{BLAS_THREADS_ENV} = {error}") from None


def unavailable() -> str | None:
    """Why :func:`blas_threads` could not limit the threads (threadpoolctl missing), or None."""
    return _missing


@contextmanager
def blas_threads(limit: int | None = None, *, load_scipy: bool = True):
    """BLAS limited to ``limit`` threads inside (None: :func:`configured_blas_threads`; 0: as
    the caller has it), the caller's limits given back on leaving. Inside another
    :func:`blas_threads` it changes nothing. ``load_scipy=False``: the work inside needs
    only numpy, so scipy is not loaded for it. Also a decorator (``@blas_threads()``)."""
    global _depth, _limiter
    with _lock:
        if _depth == 0:
            threads = configured_blas_threads() if limit is None else limit
            _limiter = _limit(threads, load_scipy) if threads else None
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0 and _limiter is not None:
                limiter, _limiter = _limiter, None
                limiter.restore_original_limits()


def _limit(threads: int, load_scipy: bool):
    """threadpoolctl's limiter of the loaded BLAS libraries to ``threads``, set; None without
    threadpoolctl."""
    global _controller, _scanned, _missing
    if load_scipy:
        import scipy.linalg  # noqa: F401  (its BLAS loaded now, so that it is limited)
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError as error:
        _missing = (f"threadpoolctl is not installed in this Python ({error}): BLAS runs on "
                    "its default threads, which on a few shared cores can make the build "
                    "several times slower (pip install threadpoolctl)")
        return None
    if len(sys.modules) != _scanned:  # something was imported since: perhaps a BLAS
        _controller, _scanned = ThreadpoolController(), len(sys.modules)
    return _controller.limit(limits=threads, user_api="blas")
