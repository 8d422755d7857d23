"""BLAS's threads while a tire is built (tire_fmu.core.blas_threads): one thread unless
TIRE_FMU_BLAS_THREADS says otherwise, the caller's own limits given back, the outermost limit
deciding. The FMUs' builds are tests/test_fmu_host_process.py's."""

import numpy as np
import pytest

from tire_fmu.core.blas_threads import BLAS_THREADS_ENV, blas_threads

pytest.importorskip("threadpoolctl")


def _blas_thread_counts():
    from threadpoolctl import threadpool_info

    return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}


def test_the_readmes_library_calls_build_on_one_blas_thread_and_give_the_callers_back(
        monkeypatch):
    """The README's snippet (build_model, reduce, build_contact_model) ran on BLAS's default
    threads: 76-125 s against 7.6 s on one thread (issue 35)."""
    import scipy.linalg
    from threadpoolctl import threadpool_limits

    from tire_fmu.core import OperatingPoint, TireParameters, build_model
    from tire_fmu.core.contact_dynamics import build_contact_model
    from tire_fmu.core.reduction import ReductionSettings, reduce

    monkeypatch.delenv(BLAS_THREADS_ENV, raising=False)
    seen = []
    for module, names in ((np.linalg, ("inv", "solve", "eig")),
                          (scipy.linalg, ("eig", "lu_factor", "lu_solve", "svd"))):
        for name in names:
            original = getattr(module, name)
            monkeypatch.setattr(module, name, lambda *a, _f=original, **k: (
                seen.append(_blas_thread_counts()), _f(*a, **k))[1])
    op = OperatingPoint(load_n=27_700, speed_m_s=10.0, n_elements=40)
    with threadpool_limits(limits=2, user_api="blas"):
        if _blas_thread_counts() != {2}:
            pytest.skip("BLAS here cannot run two threads")
        for call in (lambda: build_model(TireParameters(), op),
                     lambda: reduce(build_model(TireParameters(), op),
                                    ReductionSettings(method="balanced")),
                     lambda: build_contact_model(TireParameters(), op)):
            seen.clear()
            call()
            assert seen and all(counts == {1} for counts in seen)
            assert _blas_thread_counts() == {2}  # the caller's, given back


def test_the_outermost_limit_decides_and_the_environment_sets_the_default(monkeypatch):
    import scipy.linalg  # noqa: F401
    from threadpoolctl import threadpool_limits

    monkeypatch.delenv(BLAS_THREADS_ENV, raising=False)
    with threadpool_limits(limits=2, user_api="blas"):
        if _blas_thread_counts() != {2}:
            pytest.skip("BLAS here cannot run two threads")
        with blas_threads():
            assert _blas_thread_counts() == {1}
        with blas_threads(2):  # as `tire-fmu --blas-threads 2` runs a command
            with blas_threads():  # a library call inside keeps it
                assert _blas_thread_counts() == {2}
        with blas_threads(0), blas_threads():  # 0: BLAS as the caller has it
            assert _blas_thread_counts() == {2}
        monkeypatch.setenv(BLAS_THREADS_ENV, "0")
        with blas_threads():
            assert _blas_thread_counts() == {2}
        monkeypatch.setenv(BLAS_THREADS_ENV, "two")
        with pytest.raises(ValueError, match=f"{BLAS_THREADS_ENV} = 'two': must be an "
                                             "integer >= 0"):
            with blas_threads():
                pass
        assert _blas_thread_counts() == {2}
