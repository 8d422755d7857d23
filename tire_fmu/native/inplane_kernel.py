"""The in-plane tire's step in C (``native/c/inplane_step.c``), through ctypes.

:class:`InPlaneKernel` steps an :class:`~tire_fmu.core.inplane_contact.InPlaneSimulator` with
the C arithmetic of its ``_step``: the simulator keeps building every matrix (at the spin it
is at), this hands their addresses to C and the state in and out. The library is the step
kernel's (:mod:`.kernel`: the same sources compiled together, cached by their hash, or the one
an FMU carries).
"""

from __future__ import annotations

import ctypes
import weakref

import numpy as np

from ..core.inplane_contact import (
    MAX_SET_PASSES,
    MIN_ENTERING_FRACTION,
    SETTLE_PASSES,
    StepState,
)
from .kernel import load_library

_P = ctypes.POINTER(ctypes.c_double)
_MATRICES = ("m", "c", "a0_inv", "yn", "yx", "wnn", "wnx", "kg", "kgn", "kgx", "gain", "carry",
             "jn", "jxw", "jl", "rim_inertia", "c1", "k1s", "k2", "kh")
_VECTORS = ("kn", "cn", "kx", "cx", "pen0", "sec", "s0")


class _Step(ctypes.Structure):
    _fields_ = ([(name, ctypes.c_int) for name in ("ny", "np", "free_spin", "max_passes",
                                                    "settle_passes")]
                + [(name, ctypes.c_double) for name in ("h", "mu", "spin", "dspin", "dshare")]
                + [(name, _P) for name in _MATRICES + _VECTORS]
                + [("carry_base", ctypes.POINTER(ctypes.c_int)), ("carry_weights", _P),
                   ("carry_shift", ctypes.c_double), ("min_entering", ctypes.c_double),
                   ("driven", ctypes.c_int), ("psi_new", ctypes.c_double), ("a0_psi", _P)])


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
    lib.host_road_window_reads.restype = None
    lib.host_road_window_reads.argtypes = [ctypes.c_void_p] * 3 + [ctypes.c_int] + [
        ctypes.c_void_p] * 2 + [ctypes.c_int, ctypes.c_double, ctypes.c_double] + [
        ctypes.c_void_p] * 2
    lib._inplane_declared = True


def _doubles(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


class InPlaneKernel:
    """The C step of one simulator (its matrices read again whenever its spin moved)."""

    def __init__(self, sim, library=None):
        self.lib = load_library() if library is None else library
        _declare(self.lib)
        # the simulator owns this kernel: a strong reference back would make the pair a
        # cycle, left with all its matrices for the cycle collector when an FMU instance
        # holding them is freed
        self._sim = weakref.ref(sim)
        ny, p = sim._ny, sim._zone.n_points
        self._work = np.zeros(self.lib.inplane_work_doubles(ny, p))
        self._iwork = np.zeros(self.lib.inplane_work_ints(p), dtype=np.int32)
        self._built_for = None
        self._keep: list = []
        self._buffers = None
        self._windows = None

    @property
    def sim(self):
        """The simulator this kernel steps."""
        return self._sim()

    def _data(self) -> _Step:
        sim = self._sim()
        # the road's speed moves s0 every step (a new array of the same length): copied into
        # a buffer C reads; the rest moves with the spin, when the step is rebuilt
        key = (id(sim._a0_inv), id(sim._kg), id(sim._carry))
        if key != self._built_for:
            arrays = {name: _doubles(getattr(sim, "_" + name)) for name in _MATRICES + _VECTORS}
            self._s0 = arrays["s0"] = np.array(sim._s0, dtype=np.float64)
            self._keep = list(arrays.values()) + [sim._a0_inv, sim._kg, sim._carry]
            base = sim._carry_base  # int32, written in place as the carry is
            self._keep += [base, sim._carry_weights]
            self._step = _Step(sim._ny, sim._zone.n_points, int(sim._free_spin), MAX_SET_PASSES,
                               SETTLE_PASSES, sim.step_length_s, sim._mu, sim._spin_now, 0.0, 0.0,
                               *(a.ctypes.data_as(_P) for a in arrays.values()),
                               base.ctypes.data_as(ctypes.POINTER(ctypes.c_int)),
                               sim._carry_weights.ctypes.data_as(_P), sim._carry_shift,
                               MIN_ENTERING_FRACTION, int(sim._driven), 0.0, None)
            if sim._driven:
                a0_psi = _doubles(sim._a0_psi)
                self._keep.append(a0_psi)
                self._step.a0_psi = a0_psi.ctypes.data_as(_P)
            self._built_for = key
        else:
            self._s0[:] = sim._s0
        return self._step

    def step(self, state, height, rate, torque, rim_old, rim):
        """The next StepState, or (status, None): 1 the sets did not settle, 2 a singular
        point solve."""
        data = self._data()
        sim = self._sim()
        # the tread's arrays follow the spin in place; its value and the ring's offset do not
        data.spin, data.dspin = sim._spin_now, sim._ring_offset(state.yd)
        data.dshare = sim._share_offset(state.yd, rim)
        data.carry_shift = sim._carry_shift
        if sim._driven:
            data.psi_new = sim._driven_psi(state.y, state.yd)
        if self._buffers is None:
            ins, outs, in_struct, out_struct, extra = self._make_buffers(data.ny, data.np)
            height_buffer, rate_buffer, rims = extra
            addresses = (height_buffer.ctypes.data, rate_buffer.ctypes.data, rims.ctypes.data,
                         rims.ctypes.data + 8 * rims.shape[1], self._work.ctypes.data,
                         self._iwork.ctypes.data)
            self._buffers = ins, outs, in_struct, out_struct, (extra, addresses)
        ins, outs, in_struct, out_struct, extra = self._buffers
        for buffer, value in zip(ins, (state.y, state.yd, state.ydd, state.e, state.slip_sign,
                                       state.f_n, state.contact, state.stick)):
            buffer[:] = value
        (height_buffer, rate_buffer, rims), addresses = extra
        height_buffer[:], rate_buffer[:] = height, rate
        rims[0, :], rims[1, :] = rim_old, rim
        at_height, at_rate, at_rim_old, at_rim, at_work, at_iwork = addresses
        status = self.lib.inplane_step(ctypes.byref(data), in_struct, out_struct, at_height,
                                       at_rate, float(torque), at_rim_old, at_rim, at_work,
                                       at_iwork)
        if status:
            return status, None
        y, yd, ydd, e, sign, f_n, contact, stick = (b.copy() for b in outs)
        return 0, StepState(y, yd, ydd, e, contact == 1, stick == 1, sign, f_n)

    def window_reads(self, road, distance_m: float, speed_m_s: float):
        """HostRoad.window_reads over the simulator's windows moved by ``distance_m``, in C
        (the same arithmetic)."""
        sim = self._sim()
        p = sim._zone.n_points
        if self._windows is None:
            self._windows = (_doubles(sim._x_lo), _doubles(sim._x_hi), np.zeros(p), np.zeros(p))
            self._window_addresses = tuple(a.ctypes.data for a in self._windows)
        lo, hi, mean, rate = self._windows
        buffer, first, n = road._buffer, road._lo, road._hi - road._lo
        rows = buffer.ctypes.data + 8 * first  # the live samples of the buffer's three rows
        stride = 8 * buffer.shape[1]
        at_lo, at_hi, at_mean, at_rate = self._window_addresses
        self.lib.host_road_window_reads(rows, rows + stride, rows + 2 * stride, n, at_lo,
                                        at_hi, p, float(distance_m), float(speed_m_s),
                                        at_mean, at_rate)
        return mean.copy(), rate.copy()

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
