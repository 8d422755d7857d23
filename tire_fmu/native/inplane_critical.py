"""The in-plane ring's critical speed computed in C (``native/c/inplane_critical.c``), through
ctypes.

:func:`c_critical_speed` gives what :func:`~tire_fmu.core.inplane_modes.critical_speed` gives:
the lowest spin at which the undamped held ring's K_n(Ω) of an order n turns singular (a
standing wave), its speed, the order and the wave's kind, from the C a native in-plane FMU can
check its speed with at initialisation; tests/test_inplane_critical_c.py holds the two to
1e-10. The library is the step kernel's (:mod:`.kernel`).
"""

from __future__ import annotations

import ctypes
import math

import numpy as np

from ..core.inplane import InPlaneTire
from ..core.standing_waves import CriticalSpeed
from .inplane_ring import InPlaneRingData, n_fields, ring_data
from .kernel import load_library

#: inplane_critical.h's kinds of the standing wave
BRANCHES = {1: "radial", 2: "tangential"}
_WHY_SIZE = 512


def _declare(lib) -> None:
    if getattr(lib, "_inplane_critical_declared", False):
        return
    lib.inplane_critical_work_doubles.restype = ctypes.c_size_t
    lib.inplane_critical_work_doubles.argtypes = [ctypes.c_int] * 2
    lib.inplane_critical_speed.restype = ctypes.c_int
    lib.inplane_critical_speed.argtypes = [
        ctypes.POINTER(InPlaneRingData), ctypes.c_int, ctypes.c_int,
        ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double),
        ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_int), ctypes.c_void_p,
        ctypes.c_char_p, ctypes.c_size_t]
    lib._inplane_critical_declared = True


def c_critical_speed(model: InPlaneTire, n_elements: int, library=None) -> CriticalSpeed:
    """``inplane_modes.critical_speed(model, n_elements)`` computed by the C; ValueError with
    the C's sentence (parameter, value, allowed) when it refuses the input."""
    lib = load_library() if library is None else library
    _declare(lib)
    fields = n_fields(model)
    work = np.empty(max(lib.inplane_critical_work_doubles(int(n_elements), fields), 1))
    spin, speed = ctypes.c_double(math.nan), ctypes.c_double(math.nan)
    order, branch = ctypes.c_int(-1), ctypes.c_int(0)
    why = ctypes.create_string_buffer(_WHY_SIZE)
    status = lib.inplane_critical_speed(
        ctypes.byref(ring_data(model)), int(n_elements), fields, ctypes.byref(spin),
        ctypes.byref(speed), ctypes.byref(order), ctypes.byref(branch), work.ctypes.data,
        why, _WHY_SIZE)
    if status:
        raise ValueError(f"inplane_critical_speed refused the ring (status {status}): "
                         f"{why.value.decode(errors='replace')}")
    found = order.value >= 0
    return CriticalSpeed(speed.value, spin.value, order.value if found else None,
                         BRANCHES[branch.value] if found else None, int(n_elements))
