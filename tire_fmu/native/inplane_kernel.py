"""The in-plane tire's step in C (``native/c/inplane_step.c``), through ctypes.

:class:`InPlaneKernel` steps an :class:`~tire_fmu.core.inplane_contact.InPlaneSimulator` with
the C arithmetic of its ``_step``: the simulator keeps building every matrix (at the spin it
is at), this hands their addresses to C and the state in and out. The library is the step
kernel's (:mod:`.kernel`: the same sources compiled together, cached by their hash, or the one
an FMU carries).
"""

from __future__ import annotations

import ctypes

import numpy as np

from ..core.inplane_contact import MAX_SET_PASSES, SETTLE_PASSES, StepState
from .kernel import load_library

_P = ctypes.POINTER(ctypes.c_double)
_MATRICES = ("m", "c", "a0_inv", "yn", "yx", "wnn", "wnx", "kg", "kgn", "kgx", "gain", "carry",
             "jn", "jxw", "jl", "rim_inertia")
_VECTORS = ("kn", "cn", "kx", "cx", "pen0", "sec", "s0")


class _Step(ctypes.Structure):
    _fields_ = ([(name, ctypes.c_int) for name in ("ny", "np", "free_spin", "max_passes",
                                                    "settle_passes")]
                + [(name, ctypes.c_double) for name in ("h", "mu", "spin")]
                + [(name, _P) for name in _MATRICES + _VECTORS])


class _State(ctypes.Structure):
    _fields_ = ([(name, _P) for name in ("y", "yd", "ydd", "e", "slip_sign", "f_n")]
                + [(name, ctypes.POINTER(ctypes.c_int)) for name in ("contact", "stick")])


def _declare(lib) -> None:
    if getattr(lib, "_inplane_declared", False):
        return
    lib.inplane_step.restype = ctypes.c_int
    lib.inplane_step.argtypes = [ctypes.POINTER(_Step), ctypes.POINTER(_State),
                                 ctypes.POINTER(_State), ctypes.c_void_p, ctypes.c_void_p,
                                 ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p,
                                 ctypes.c_void_p, ctypes.c_void_p]
    lib.inplane_work_doubles.restype = ctypes.c_size_t
    lib.inplane_work_doubles.argtypes = [ctypes.c_int, ctypes.c_int]
    lib.inplane_work_ints.restype = ctypes.c_size_t
    lib.inplane_work_ints.argtypes = [ctypes.c_int]
    lib._inplane_declared = True


def _doubles(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


class InPlaneKernel:
    """The C step of one simulator (its matrices read again whenever its spin moved)."""

    def __init__(self, sim, library=None):
        self.lib = load_library() if library is None else library
        _declare(self.lib)
        self.sim = sim
        ny, p = sim._ny, sim._zone.n_points
        self._work = np.zeros(self.lib.inplane_work_doubles(ny, p))
        self._iwork = np.zeros(self.lib.inplane_work_ints(p), dtype=np.int32)
        self._built_for = None
        self._keep: list = []
        self._buffers = None

    def _data(self) -> _Step:
        sim = self.sim
        # the road's speed moves s0 every step (a new array of the same length): copied into
        # a buffer C reads; the rest moves with the spin, when the step is rebuilt
        key = (id(sim._a0_inv), sim._spin_now)
        if key != self._built_for:
            arrays = {name: _doubles(getattr(sim, "_" + name)) for name in _MATRICES + _VECTORS}
            self._s0 = arrays["s0"] = np.array(sim._s0, dtype=np.float64)
            self._keep = list(arrays.values()) + [sim._a0_inv]
            self._step = _Step(sim._ny, sim._zone.n_points, int(sim._free_spin), MAX_SET_PASSES,
                               SETTLE_PASSES, sim.step_s, sim._mu, sim._spin_now,
                               *(a.ctypes.data_as(_P) for a in arrays.values()))
            self._built_for = key
        else:
            self._s0[:] = sim._s0
        return self._step

    def step(self, state, height, rate, torque, rim_old, rim):
        """The next StepState, or (status, None): 1 the sets did not settle, 2 a singular
        point solve."""
        data = self._data()
        if self._buffers is None:
            self._buffers = self._make_buffers(data.ny, data.np)
        ins, outs, in_struct, out_struct, extra = self._buffers
        for buffer, value in zip(ins, (state.y, state.yd, state.ydd, state.e, state.slip_sign,
                                       state.f_n, state.contact, state.stick)):
            buffer[:] = value
        height_buffer, rate_buffer, rims = extra
        height_buffer[:], rate_buffer[:] = height, rate
        rims[0, :], rims[1, :] = rim_old, rim
        status = self.lib.inplane_step(ctypes.byref(data), in_struct, out_struct,
                                       height_buffer.ctypes.data, rate_buffer.ctypes.data,
                                       float(torque), rims[0].ctypes.data, rims[1].ctypes.data,
                                       self._work.ctypes.data, self._iwork.ctypes.data)
        if status:
            return status, None
        y, yd, ydd, e, sign, f_n, contact, stick = (b.copy() for b in outs)
        return 0, StepState(y, yd, ydd, e, contact == 1, stick == 1, sign, f_n)

    @staticmethod
    def _make_buffers(ny, p):
        """The state in and out, the road and the rim, as arrays C reads and writes (their
        addresses packed once)."""
        def arrays():
            return [np.zeros(ny), np.zeros(ny), np.zeros(ny), np.zeros(p), np.zeros(p),
                    np.zeros(p), np.zeros(p, dtype=np.int32), np.zeros(p, dtype=np.int32)]

        def pack(a):
            return ctypes.byref(_State(*(x.ctypes.data_as(_P) for x in a[:6]),
                                       *(x.ctypes.data_as(ctypes.POINTER(ctypes.c_int))
                                         for x in a[6:])))

        ins, outs = arrays(), arrays()
        return ins, outs, pack(ins), pack(outs), (np.zeros(p), np.zeros(p), np.zeros((2, 6)))
