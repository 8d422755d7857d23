"""The step of the tire in plain numpy: the readable reference of ``native/c/kernel.c``.

Both step a :class:`~.contract.StepContract` with the same algorithm; this one writes it with
dense matrices and no caching, the C with the order structure and caches, and a test holds
them to 1e-10 of each other. Over a communication step h, split into n equal substeps of at
most the contract's ``substep_s``:

1. the road under each contact point is read at the current time: the mean height over its
   window of road and that mean's rate, by time (the host's road height at the zone front,
   its history read through each point's window delays, :mod:`.road`) or by position (a road
   along which the wheel centre is at x moving at vx, read over each point's window
   [x + window_lo_m, x + window_hi_m] of the contract, :meth:`NumpyKernel.set_road`);
2. the contact forces at the current time are solved again for the inputs given now (the last
   substep's end re-solved: the penetrations move with the inputs' change and with the end
   forces through that substep's own interface flexibility), or, after a reset, taken from the
   law at the instant;
3. each substep advances the modal state exactly with the rim and the force deviations ramped
   from their values at its start to their values at its end, those end forces solving the
   law at the end with the road at the substep's end (by time: ramped on at its rate from the
   communication point; by position: read again where the wheel centre's path along the road
   is then, at the path's rate, so that a cleat is resolved at a substep's travel whatever the
   host's step):

       q(t+h) = e^{λh} q + hφ₁ b_rim z + h²φ₂ b_rim ż + h(φ₁-φ₂) B Δf(t) + hφ₂ B Δf(t+h),
       [σ; p; ṗ](t+h) = base + M f(t+h),  f = max(0, σ) where p > 0 and σ > 0, else 0,

   with σ = k p + c ṗ, a primal-dual active-set iteration warm-started from the last set (and
   projected Gauss-Seidel should it cycle).

The ring's modes act on the zone nodes (B, C from the order structure written out); the
contact points read the nodes through the interpolation matrix I (P x Z) and load them through
Iᵀ, the virtual work of the interpolation.
"""

from __future__ import annotations

import math
import struct

import numpy as np

from . import clock
from .contract import StepContract
from .host_inputs import input_path, on_grid, rate_changes
from .road import SAME_POINT_EPS, RoadReader, RoadWindows
from .stepping import phi_functions

#: Active-set iterations per solve: this many per contact point, plus ACTIVE_SET_EXTRA; then PGS.
ACTIVE_SET_PER_NODE = 2
ACTIVE_SET_EXTRA = 4
#: Projected Gauss-Seidel fallback: sweeps, and the relative change that ends it.
PGS_SWEEPS = 1000
PGS_TOLERANCE = 1e-13
#: A step within this relative distance of a multiple of the substep needs no extra substep.
SUBSTEP_SLACK = 1e-12
#: Communication step sizes whose coefficients are kept (a host varying h evicts the oldest).
KERNEL_CACHE_SIZE = 32
#: With the road by position, the index of x among a step's inputs (rim_z, rim_vz, x, vx).
INPUT_X = 2
#: step_problems' bit of a kernel reading the road the other way (kernel.h's
#: KERNEL_OTHER_ROAD): a step by time with a road by position set, or one by position without.
OTHER_ROAD = 256


class _Interface:
    """One substep length h: the modal step coefficients and the contact interface
    [σ; p; ṗ] = base + M f on the total end forces f (M = [S; W_p; W_r]).

    The points' flexibilities are the zone nodes' read through the interpolation I (P x Z),
    W_p = I W_w Iᵀ, W_r = I W_r Iᵀ, S = diag(k) W_p + diag(c) W_r, so the kernel keeps the
    Z x Z node blocks and applies M in node space, O(P S + Z²) a product for O(P²); only S's
    diagonal is formed at the points (for the projected Gauss-Seidel). ``m`` writes M out."""

    def __init__(self, kernel: NumpyKernel, h: float, instant: bool = False):
        self.h = h
        k = kernel
        if instant:  # a truncated ring couples the forces at an instant: its direct terms only
            w_nodes, r_nodes, out_nodes = k.d_f[k.w_rows], k.d_f[k.r_rows], k.d_f[:3]
            self.decay = self.g_start = self.g_end = self.g_z = self.g_vz = None
        else:
            lam = k.contract.lam
            phi1, phi2 = phi_functions(lam * h)
            self.decay = np.exp(lam * h)
            self.g_start = (h * (phi1 - phi2))[:, None] * k.b_f  # on Δf at the start (nodes)
            self.g_end = (h * phi2)[:, None] * k.b_f  # on Δf at the end
            self.g_z = h * phi1 * k.b_rim
            self.g_vz = h * h * phi2 * k.b_rim
            per_force = np.real(k.c_ring @ self.g_end) + k.d_f + k.e_f / h  # rows x Z
            w_nodes, r_nodes, out_nodes = per_force[k.w_rows], per_force[k.r_rows], per_force[:3]
        interp = k.interp
        self.interp, self.k, self.c = interp, k.k, k.c
        self.w_nodes, self.r_nodes = np.array(w_nodes), np.array(r_nodes)
        self.s_diag = (k.k * np.einsum("pa,ab,pb->p", interp, w_nodes, interp)
                       + k.c * np.einsum("pa,ab,pb->p", interp, r_nodes, interp))
        self.out_f = out_nodes @ interp.T  # ring outputs per unit end force at the points
        g = interp.T @ k.f_static
        self.pen_const = k.contract.pen_static - interp @ (self.w_nodes @ g)
        self.rate_const = -(interp @ (self.r_nodes @ g))

    @property
    def m(self) -> np.ndarray:
        """M = [S; W_p; W_r] (3P x P) written out at the points (the step never forms it)."""
        w_p = self.interp @ self.w_nodes @ self.interp.T
        w_r = self.interp @ self.r_nodes @ self.interp.T
        return np.vstack([self.k[:, None] * w_p + self.c[:, None] * w_r, w_p, w_r])

    def combine(self, base: np.ndarray, f: np.ndarray) -> np.ndarray:
        """base + M f, through the zone nodes."""
        g = self.interp.T @ f
        wp, wr = self.interp @ (self.w_nodes @ g), self.interp @ (self.r_nodes @ g)
        return base + np.concatenate([self.k * wp + self.c * wr, wp, wr])

    def active_forces(self, active: np.ndarray, sigma0: np.ndarray) -> np.ndarray:
        """f_A = (I - S_AA)⁻¹ σ0_A, zeros elsewhere. S_AA = U_A I_Aᵀ with U = diag(k) I W_w
        + diag(c) I W_r has rank at most Z: (I - U_A I_Aᵀ)⁻¹ = I + U_A (I_Z - I_Aᵀ U_A)⁻¹ I_Aᵀ
        (Woodbury; the same nonzero spectrum), a Z x Z solve for an a x a one."""
        f = np.zeros(sigma0.size)
        if active.any():
            i_a, k_a, c_a = self.interp[active], self.k[active], self.c[active]
            u_a = k_a[:, None] * (i_a @ self.w_nodes) + c_a[:, None] * (i_a @ self.r_nodes)
            sigma_a = sigma0[active]
            y = np.linalg.solve(np.eye(self.w_nodes.shape[0]) - i_a.T @ u_a, i_a.T @ sigma_a)
            f[active] = (sigma_a + k_a * (i_a @ (self.w_nodes @ y))
                         + c_a * (i_a @ (self.r_nodes @ y)))
        return f


class NumpyKernel:
    """Steps a contract: the same calls and state as the C kernel (``kernel.h``)."""

    def __init__(self, contract: StepContract, start_time: float = 0.0, road=None):
        """A kernel for ``contract`` whose clock starts at ``start_time``; ``road``: the road by
        position (:meth:`set_road`), else it reads the road by time (:meth:`step`)."""
        self.contract = c = contract
        n_orders = np.repeat(np.arange(c.n_orders), np.diff(c.order_start))
        theta = c.zone_offset * (2 * np.pi / c.n_elements)
        phase = np.exp(1j * np.outer(n_orders, theta))  # (K, Z)
        self.b_f = c.beta[:, None] * np.conj(phase)  # a node force into each mode
        z = c.n_zone
        # ring rows: rim_Fz, rim_Fx, deflection, w (Z), ẇ (Z) on the modal state
        self.c_ring = np.vstack([c.c_rim, -c.gamma[None, :], (c.gamma[:, None] * phase).T,
                                 (c.eta[:, None] * phase).T])
        self.b_rim = c.b_rim
        self.w_rows, self.r_rows = slice(3, 3 + z), slice(3 + z, 3 + 2 * z)
        self.d_rim, self.e_rim = c.d[:, 0], c.e[:, 0]
        self.d_f, self.e_f = c.d[:, 1:], c.e[:, 1:]
        self.truncated = bool(np.any(self.d_f) or np.any(self.e_f))
        self.interp = np.zeros((c.n_points, z))
        np.add.at(self.interp, (np.repeat(np.arange(c.n_points), c.n_support),
                                c.point_support.ravel()), c.point_weight.ravel())
        self.k, self.c = c.point_stiffness, c.point_damping
        self.sec = c.point_sec
        self.f_static = c.f_static
        self.static_active = c.f_static > 0
        self.linear = bool(c.linear)
        # how the rim's own motion moves each point's penetration and rate at an instant
        self.pen_rim = self.interp @ self.d_rim[self.w_rows] - self.sec
        self.rate_rim = self.interp @ self.e_rim[self.r_rows] - self.sec
        windows = RoadWindows(c.window_early_s, c.window_late_s, 0.0)
        self.road = RoadReader(windows)
        self.horizon_s = windows.horizon_s
        self.window_lo, self.window_hi = c.window_lo_m, c.window_hi_m
        self.road_by_position = None
        self._interfaces: dict[float, tuple[int, _Interface]] = {}
        self._instant = _Interface(self, 0.0, instant=True) if self.truncated else None
        self.solver_fallbacks = 0
        self.fallback_only = False  # tests: every solve by the Gauss-Seidel fallback
        self.reset(start_time)
        if road is not None:
            self.set_road(road)

    # -- state ---------------------------------------------------------------------------
    def reset(self, start_time: float = 0.0) -> None:
        c = self.contract
        p = c.n_points
        self.start_time = float(start_time)
        self.elapsed_s, self.carry_s = 0.0, 0.0
        self.q = np.zeros(c.n_modes, dtype=complex)
        self.df = np.zeros(p)
        self.active = self.static_active.copy()
        self.penetration = c.pen_static.copy()
        self.rate = np.zeros(p)
        self.seen = (0.0, 0.0, np.zeros(p), np.zeros(p))  # z, ż, heights, slopes
        # the rim's rate given at the last communication point, its last change over the step
        # it was made in and that step's length (0: none yet): the extension's history
        self.given_vz, self.change, self.h_change = 0.0, 0.0, 0.0
        # the road by position: where along the road (and at what rate) the road was read
        # last, the position's rate given at the last communication point and its last change
        # (its step is the rim's h_change): all 0 with the road by time
        self.seen_x, self.seen_vx, self.given_vx, self.change_vx = 0.0, 0.0, 0.0, 0.0
        self.ring_out = np.zeros(3)
        self.last: _Interface | None = None
        self.last_step = math.nan
        self.road.reset(self.start_time)
        self.outputs = self._outputs()

    @property
    def time(self) -> float:
        """The clock: the start time plus the time since it (core/clock.py)."""
        return self.start_time + self.elapsed_s

    # -- stepping ------------------------------------------------------------------------
    def interface(self, h: float) -> tuple[int, _Interface]:
        """The communication step h: (substeps, the substep's interface), cached by h itself:
        a host's h jittered by its clock's rounding (far from t = 0 a few distinct values)
        gets coefficients of its own, so the tire integrates exactly the time the host's clock
        moved and a run reads the same from any start time."""
        entry = self._interfaces.get(h)
        if entry is not None:
            return entry
        n_sub = max(1, math.ceil(h / self.contract.substep_s * (1 - SUBSTEP_SLACK)))
        entry = (n_sub, _Interface(self, h / n_sub))
        if len(self._interfaces) >= KERNEL_CACHE_SIZE:
            self._interfaces.pop(next(iter(self._interfaces)))
        self._interfaces[h] = entry
        return entry

    @property
    def cached_steps(self) -> int:
        """How many communication step sizes have their coefficients cached."""
        return len(self._interfaces)

    def _road(self, h: float) -> tuple[np.ndarray, np.ndarray]:
        p = self.contract.n_points
        out = np.empty(2 * p)
        self.road.read(self.elapsed_s, self._road_z, self._road_vz, h, out)
        return out[:p].copy(), out[p:].copy()

    # -- the road by position --------------------------------------------------------------
    def set_road(self, road) -> None:
        """Read the road by position from now on: ``road`` has ``window_reads(s_lo, s_hi,
        speed_m_s) -> (means, rates)``, the mean height over each window [s_lo, s_hi] of road
        and its rate as the road passes at the speed (core/obstacles.py's ProfileRoad,
        PositionRoad; the C reads the same samples with the same arithmetic). It is read
        where it is at each read, so a road that changes (a host's samples) is read as it is
        then. The kernel then steps with :meth:`step_on_road` only (:meth:`reset` keeps the
        road); ValueError for a kernel that has read the road by time."""
        if self.road_by_position is None and self.last is not None:
            raise ValueError("this kernel has read the road by time: a road by position is "
                             "set before its first step or after a reset")
        if not callable(getattr(road, "window_reads", None)):
            raise TypeError(f"road: {type(road).__name__} has no window_reads(s_lo, s_hi, "
                            "speed_m_s)")
        self.road_by_position = road

    @property
    def road_position(self) -> float:
        """Where along the road the road was read last (m): the last step's end, or the x of
        :meth:`outputs_on_road`."""
        return self.seen_x

    def _read_road_at(self, x: float, vx: float) -> tuple[np.ndarray, np.ndarray]:
        """(means, rates) under the points with the wheel centre at x moving at vx."""
        means, rates = self.road_by_position.window_reads(self.window_lo + x,
                                                          self.window_hi + x, vx)
        self.seen_x, self.seen_vx = x, vx
        return np.array(means, dtype=float), np.array(rates, dtype=float)

    def step_problems(self, h: float, inputs, at: bool = False) -> int:
        """Why a step is refused, as the bits of kernel.h's kernel_step_problems (0: it is
        not): h not finite and > 0 (1), shorter than the contract's shortest step (2), not
        resolved by the clock (4); input i not finite or beyond its limit (8 << i; with the
        road by position, ``at``, input 2 is x, limited to MAX_ROAD_POSITION_M); the kernel
        reading the road the other way (256)."""
        from .step_limits import (
            MAX_DISPLACEMENT_M,
            MAX_ROAD_POSITION_M,
            MAX_STEP_WORK,
            MAX_VELOCITY_M_S,
        )

        problems = 0
        c = self.contract
        if not 0.0 < h < math.inf:
            problems |= 1
        elif h < c.min_step_s:
            problems |= 2
        elif not clock.resolves(self.time, h):
            problems |= 4
        elif math.ceil(h / c.substep_s * (1 - SUBSTEP_SLACK)) * c.substep_work > MAX_STEP_WORK:
            problems |= 128
        for i, value in enumerate(inputs):
            limit = (MAX_VELOCITY_M_S if i % 2 else
                     MAX_ROAD_POSITION_M if at and i == INPUT_X else MAX_DISPLACEMENT_M)
            if not abs(value) <= limit:
                problems |= 8 << i
        if bool(at) != (self.road_by_position is not None):
            problems |= OTHER_ROAD
        return problems

    def step(self, h: float, inputs) -> np.ndarray | None:
        """One communication step from ``time`` with the inputs (rim_z, rim_vz, road_z,
        road_vz) given at ``time``, the road by time; the outputs at the new time, or None
        (nothing changed) for a step step_problems finds fault with."""
        return self._advance(h, inputs, False)

    def step_on_road(self, h: float, z: float, vz: float, x: float, vx: float
                     ) -> np.ndarray | None:
        """One communication step from ``time`` with the road by position: the rim at z
        moving at vz, the wheel centre at x along the road moving at vx, given at ``time``
        (x extended over the step as z is); the outputs at the new time, or None (nothing
        changed) for a step step_problems(h, inputs, at=True) finds fault with."""
        return self._advance(h, (z, vz, x, vx), True)

    def _advance(self, h: float, inputs, at: bool) -> np.ndarray | None:
        inputs = tuple(float(x) for x in inputs)
        if self.step_problems(h, inputs, at):
            return None
        # a host's h that is a whole number of substeps to its clock's resolution is that
        # number: the tire's clock stays on its grid from any start time (host_inputs.on_grid)
        h = on_grid(h, self.contract.substep_s, self.time)
        z, vz, third, fourth = inputs
        n_sub, interface = self.interface(h)
        # the inputs extended over the step (host_inputs), each substep on its chord
        h_before = self.last_step if self.last is not None else 0.0
        (accel,), (jerk,) = rate_changes([vz], [self.given_vz], h_before, [self.change],
                                         self.h_change)
        path = input_path(z, vz, accel, jerk)
        ends = [path(i * interface.h) for i in range(n_sub + 1)]
        if at:
            (accel_x,), (jerk_x,) = rate_changes([fourth], [self.given_vx], h_before,
                                                 [self.change_vx], self.h_change)
            path_x = input_path(third, fourth, accel_x, jerk_x)
            heights, slopes = self._read_road_at(third, fourth)
        else:
            self._road_z, self._road_vz = third, fourth
            heights, slopes = self._road(h)
        self._start(z, vz, heights, slopes)
        position = z
        for i in range(n_sub):
            if at:
                # the road at the substep's end, the wheel centre there on its path along the
                # road moving at the path's rate: the road resolved at each substep's travel
                x_end, vx_end, _ = path_x((i + 1) * interface.h)
                heights, slopes = self._read_road_at(x_end, vx_end)
            else:
                heights = heights + interface.h * slopes  # ramped on at its rate
            # the ring integrated on the chord; the rate at the substep's end in the direct
            # terms and the penetrations' rates
            chord = (ends[i + 1][0] - position) / interface.h
            self._substep(interface, position, chord, heights, slopes, ends[i + 1][1])
            position = ends[i + 1][0]
        self.change = (vz - self.given_vz) / h_before if h_before > 0.0 else 0.0
        self.given_vz = vz
        if at:
            self.change_vx = (fourth - self.given_vx) / h_before if h_before > 0.0 else 0.0
            self.given_vx = fourth
        self.h_change = h_before
        self.elapsed_s, self.carry_s = clock.advance(self.elapsed_s, self.carry_s, h)
        self.last_step = h
        self.outputs = self._outputs()
        return self.outputs.copy()

    def step_values(self, h: float, z: float, vz: float, road_z: float, road_vz: float):
        out = self.step(h, (z, vz, road_z, road_vz))
        return None if out is None else [float(x) for x in out]

    def raw_step(self, at: bool = False):
        """(function, handle, inputs, report): the compiled kernel's hot-path calling
        convention (native/kernel.py) over this kernel, for callers written against it; ``at``:
        kernel_step_at's (inputs rim_z, rim_vz, x, vx) rather than kernel_step's."""
        inputs, report = [0.0] * 4, [0.0] * 8  # plain floats, as the ctypes arrays read

        def step(handle, h, inputs, report):
            out = self._advance(h, inputs, at)
            if out is None:
                return -3
            report[:6] = [float(x) for x in out]
            report[6] = self.time
            report[7] = float(self.at_zone_edge())
            return 0

        return step, None, inputs, report

    def outputs_with(self, inputs) -> np.ndarray | None:
        """The outputs at ``time`` for inputs given there (the forces stay re-solved), or
        None if an input is refused. The road by time."""
        return self._outputs_for(inputs, False)

    def outputs_on_road(self, z: float, vz: float, x: float, vx: float) -> np.ndarray | None:
        """:meth:`outputs_with` with the road by position: the road read at x (rate at vx)."""
        return self._outputs_for((z, vz, x, vx), True)

    def _outputs_for(self, inputs, at: bool) -> np.ndarray | None:
        inputs = tuple(float(x) for x in inputs)
        # only the inputs are judged here: no step is taken, however long it would be
        if self.step_problems(1.0, inputs, at) & ~(2 | 4 | 128):
            return None
        z, vz, third, fourth = inputs
        if at:
            heights, slopes = self._read_road_at(third, fourth)
        else:
            self._road_z, self._road_vz = third, fourth
            heights, slopes = self._road(self.last_step)
        self._start(z, vz, heights, slopes)
        self.outputs = self._outputs()
        return self.outputs.copy()

    def _start(self, z, vz, heights, slopes) -> None:
        z_seen, vz_seen, heights_seen, slopes_seen = self.seen
        dz, dvz = z - z_seen, vz - vz_seen
        pen = self.penetration + self.pen_rim * dz + self.sec * (heights - heights_seen)
        rate = self.rate + self.rate_rim * dvz + self.sec * (slopes - slopes_seen)
        self.ring_out = self.ring_out + self.d_rim[:3] * dz + self.e_rim[:3] * dvz
        interface = self.last if self.last is not None else (
            self._instant if not self.linear else None)
        if interface is not None:
            f_old = self.f_static + self.df
            base = interface.combine(np.concatenate([self.k * pen + self.c * rate, pen, rate]),
                                     -f_old)
            f, combined = self._solve(interface, base)
            change = f - f_old
            if self.last is not None:
                self.q = self.q + interface.g_end @ (self.interp.T @ change)
            self.ring_out = self.ring_out + interface.out_f @ change
            p = self.contract.n_points
            pen, rate = combined[p:2 * p], combined[2 * p:]
        elif self.linear:
            f = np.where(self.static_active, self.f_static + self.k * (
                pen - self.contract.pen_static) + self.c * rate, 0.0)
        else:
            push = self.k * pen + self.c * rate
            f = np.where(pen > 0.0, np.maximum(push, 0.0), 0.0)
            self.active = f > 0.0
        self.df = f - self.f_static
        self.penetration, self.rate = pen, rate
        self.seen = (z, vz, heights.copy(), slopes.copy())

    def _substep(self, k: _Interface, z, vz, heights, slopes, vz_end=None) -> None:
        """One substep with the rim at z moving at vz (its chord) and at vz_end at its end;
        ``heights`` and ``slopes``: the road under the points at its end and their rates."""
        h = k.h
        vz_end = vz if vz_end is None else vz_end
        p = self.contract.n_points
        df_nodes = self.interp.T @ self.df
        self.q = k.decay * self.q + k.g_start @ df_nodes + k.g_z * z + k.g_vz * vz
        y = np.real(self.c_ring @ self.q) + self.d_rim * (z + h * vz) + self.e_rim * vz_end \
            - self.e_f @ df_nodes / h
        w_pt, r_pt = self.interp @ y[self.w_rows], self.interp @ y[self.r_rows]
        pen0 = w_pt - self.sec * (z + h * vz) + self.sec * heights + k.pen_const
        rate0 = r_pt - self.sec * vz_end + self.sec * slopes + k.rate_const
        base = np.concatenate([self.k * pen0 + self.c * rate0, pen0, rate0])
        f, combined = self._solve(k, base)
        df_end = f - self.f_static
        self.q = self.q + k.g_end @ (self.interp.T @ df_end)
        self.ring_out = y[:3] + k.out_f @ df_end
        self.df = df_end
        self.penetration, self.rate = combined[p:2 * p], combined[2 * p:]
        self.seen = (z + h * vz, vz_end, heights.copy(), slopes.copy())
        self.last = k

    def _solve(self, k: _Interface, base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Total end forces with [σ; p; ṗ] = base + M f and the law (two-sided springs on the
        static footprint's points for the linear law), and base + M f."""
        p = self.contract.n_points
        if self.linear:
            f = k.active_forces(self.static_active, base[:p])
            return f, k.combine(base, f)
        active = self.active
        passes = 0 if self.fallback_only else ACTIVE_SET_PER_NODE * p + ACTIVE_SET_EXTRA
        for _ in range(passes):
            f = k.active_forces(active, base[:p])
            combined = k.combine(base, f)
            new = (combined[p:2 * p] > 0.0) & (combined[:p] > 0.0)
            if np.array_equal(new, active):
                self.active = active
                return np.maximum(f, 0.0), combined
            active = new
        f = self._fallback(k, base)
        return f, k.combine(base, f)

    def set_fallback_only(self, on: bool) -> None:
        """Solve every contact problem by the Gauss-Seidel fallback (to test it: left to itself
        the active set settles in almost every solve), as the compiled kernel's switch does."""
        self.fallback_only = bool(on)

    def _fallback(self, k: _Interface, base: np.ndarray) -> np.ndarray:
        """Projected Gauss-Seidel on the same law, for an active set that cycles; the rows of
        point j read in node space (g = Iᵀ f kept current as each f_j changes)."""
        self.solver_fallbacks += 1
        p = self.contract.n_points
        read_w, read_r = self.interp @ k.w_nodes, self.interp @ k.r_nodes  # I W (P x Z)
        f = np.maximum(self.f_static + self.df, 0.0)
        g = self.interp.T @ f
        for _ in range(PGS_SWEEPS):
            previous = f.copy()
            for j in range(p):
                wp, wr = read_w[j] @ g, read_r[j] @ g
                pen_j = base[p + j] + wp
                rest = base[j] + self.k[j] * wp + self.c[j] * wr - k.s_diag[j] * f[j]
                now = max(0.0, rest / (1.0 - k.s_diag[j])) if pen_j > 0.0 else 0.0
                g = g + self.interp[j] * (now - f[j])
                f[j] = now
            if np.max(np.abs(f - previous)) <= PGS_TOLERANCE * max(1.0, float(np.max(np.abs(f)))):
                break
        self.active = f > 0.0
        return f

    # -- outputs -------------------------------------------------------------------------
    def _outputs(self) -> np.ndarray:
        c = self.contract
        forces = self.f_static + self.df
        ring = c.static_ring_out + self.ring_out
        # deflection: the rim's lowering at the contact centre (the static one, the road's
        # rise under the centre point, less the rim's); tread_deflection: the ring's own
        deflection = c.static_deflection_m + self.seen[2][c.centre_point] - self.seen[0]
        return np.array([ring[0], ring[1], float(c.point_cos @ forces), deflection,
                         self.contact_length(), ring[2]])

    def contact_length(self) -> float:
        """Footprint length on the road (m): between the edges where the penetration,
        interpolated between the outermost pushing point and its neighbour, crosses zero."""
        from .contact import _edges

        front, rear = _edges(self.contract.point_x_road, self.penetration,
                             (self.f_static + self.df) > 0.0)
        return front - rear

    @property
    def forces(self) -> np.ndarray:
        return self.f_static + self.df

    def at_zone_edge(self) -> bool:
        forces = self.forces
        return bool(forces[0] > 0.0 or forces[-1] > 0.0)

    # -- the state as bytes: the layout of kernel.c ------------------------------------------
    def state_bytes(self) -> bytes:
        t, z, v = self.road.history()
        return state_data({
            "start_time": self.start_time, "elapsed_s": self.elapsed_s, "carry_s": self.carry_s,
            "last_step_s": self.last_step if self.last is not None else math.nan,
            "seen_z": self.seen[0], "seen_vz": self.seen[1], "ring_out": self.ring_out,
            "outputs": self.outputs, "given_vz": self.given_vz, "change": self.change,
            "h_change": self.h_change, "seen_x": self.seen_x, "seen_vx": self.seen_vx,
            "given_vx": self.given_vx, "change_vx": self.change_vx, "q": self.q, "df": self.df,
            "penetration": self.penetration, "rate": self.rate, "seen_heights": self.seen[2],
            "seen_slopes": self.seen[3], "history_t": t, "history_z": z, "history_v": v,
            "active": self.active})

    def state_problem(self, data: bytes) -> str | None:
        """Why ``data`` is no state of this kernel (kernel.c's kernel_state_check), or None."""
        problems = state_problems(self, data)
        return "; ".join(problems) if problems else None

    def set_state_bytes(self, data: bytes) -> None:
        """Restore bytes of :meth:`state_bytes` (or of the C kernel) that state_problem
        accepted."""
        fields = _StateFields(self.contract, data)
        self.start_time, self.elapsed_s, self.carry_s = fields.start, fields.elapsed, fields.carry
        self.last_step = fields.last if fields.has_last else math.nan
        self.ring_out = fields.ring_out.copy()
        self.outputs = fields.outputs.copy()
        self.q = fields.q.copy()
        self.df, self.penetration, self.rate = (x.copy() for x in (
            fields.df, fields.penetration, fields.rate))
        self.seen = (fields.seen_z, fields.seen_vz, fields.heights.copy(), fields.slopes.copy())
        self.given_vz, self.change, self.h_change = fields.given_vz, fields.change, fields.h_change
        self.seen_x, self.seen_vx = fields.seen_x, fields.seen_vx
        self.given_vx, self.change_vx = fields.given_vx, fields.change_vx
        self.road.reset(self.start_time)
        self.road.history_t, self.road.history_z, self.road.history_v = (
            x.copy() for x in (fields.t, fields.z, fields.v))
        self.active = fields.active.copy()
        self.last = self.interface(self.last_step)[1] if fields.has_last else None


#: The state layout (kernel.c's kernel_state_write): four int32 (modes, points, road samples,
#: whether a step was taken), the head's doubles, the arrays of doubles, then one byte per
#: contact point (pushing or not). Names as ContactState.fields gives them. The road by
#: position's four (seen_x .. change_vx) are 0 with the road by time, whose history is empty
#: with the road by position.
_STATE_INTS = 4
STATE_HEAD = ("start_time", "elapsed_s", "carry_s", "last_step_s", "seen_z", "seen_vz",
              "ring_out", "ring_out", "ring_out", *("outputs",) * 6, "given_vz", "change",
              "h_change", "seen_x", "seen_vx", "given_vx", "change_vx")
_STATE_HEAD = len(STATE_HEAD)
STATE_ARRAYS = ("q", "df", "penetration", "rate", "seen_heights", "seen_slopes", "history_t",
                "history_z", "history_v")


def state_fields(data: bytes) -> dict:
    """The named fields of state bytes whose layout is sound (sizes from their header)."""
    modes, points, history, has_last = struct.unpack_from("<4i", data, 0)
    values = np.frombuffer(data, "<f8", _STATE_HEAD + 2 * modes + 5 * points + 3 * history,
                           4 * _STATE_INTS)
    head = values[:_STATE_HEAD]
    out = {"start_time": float(head[0]), "elapsed_s": float(head[1]),
           "carry_s": float(head[2]),
           "last_step_s": float(head[3]) if has_last else math.nan,
           "seen_z": float(head[4]), "seen_vz": float(head[5]),
           "ring_out": head[6:9].copy(), "outputs": head[9:15].copy(),
           "given_vz": float(head[15]), "change": float(head[16]), "h_change": float(head[17]),
           "seen_x": float(head[18]), "seen_vx": float(head[19]), "given_vx": float(head[20]),
           "change_vx": float(head[21])}
    rest = values[_STATE_HEAD:]
    out["q"] = rest[:2 * modes].copy().view(complex)
    sizes = (points,) * 5 + (history,) * 3
    offset = 2 * modes
    for name, size in zip(STATE_ARRAYS[1:], sizes):
        out[name] = rest[offset:offset + size].copy()
        offset += size
    out["active"] = np.frombuffer(data, np.uint8, points, len(data) - points).astype(bool)
    return out


def state_data(fields: dict) -> bytes:
    """State bytes from named fields (the inverse of :func:`state_fields`)."""
    q = np.ascontiguousarray(fields["q"], dtype=complex)
    history = np.asarray(fields["history_t"]).size
    last = fields["last_step_s"]
    has_last = not math.isnan(last)
    head = [fields["start_time"], fields["elapsed_s"], fields["carry_s"],
            last if has_last else 0.0, fields["seen_z"], fields["seen_vz"],
            *fields["ring_out"], *fields["outputs"], fields.get("given_vz", 0.0),
            fields.get("change", 0.0), fields.get("h_change", 0.0),
            *(fields.get(name, 0.0) for name in ("seen_x", "seen_vx", "given_vx", "change_vx"))]
    active = np.asarray(fields["active"])
    return b"".join([
        struct.pack("<4i", q.size, active.size, history, int(has_last)),
        struct.pack(f"<{len(head)}d", *head), q.view("<f8").tobytes(),
        *(np.asarray(fields[name], "<f8").tobytes() for name in STATE_ARRAYS[1:]),
        active.astype(np.uint8).tobytes()])


class _StateFields:
    """State bytes read into named fields (the layout of kernel.c's kernel_state_write)."""

    def __init__(self, contract: StepContract, data: bytes):
        f = state_fields(data)
        self.history = f["history_t"].size
        self.has_last = not math.isnan(f["last_step_s"])
        self.values = np.frombuffer(data, "<f8", (len(data) - contract.n_points - 16) // 8, 16)
        self.start, self.elapsed, self.carry = f["start_time"], f["elapsed_s"], f["carry_s"]
        self.last = f["last_step_s"] if self.has_last else 0.0
        self.seen_z, self.seen_vz = f["seen_z"], f["seen_vz"]
        self.given_vz, self.change, self.h_change = f["given_vz"], f["change"], f["h_change"]
        self.seen_x, self.seen_vx = f["seen_x"], f["seen_vx"]
        self.given_vx, self.change_vx = f["given_vx"], f["change_vx"]
        self.ring_out, self.outputs, self.q = f["ring_out"], f["outputs"], f["q"]
        self.df, self.penetration, self.rate = f["df"], f["penetration"], f["rate"]
        self.heights, self.slopes = f["seen_heights"], f["seen_slopes"]
        self.t, self.z, self.v = f["history_t"], f["history_z"], f["history_v"]
        self.active = f["active"]


def state_problems(kernel: NumpyKernel, data: bytes) -> list[str]:
    """Everything that makes ``data`` no state of this kernel: its layout (sizes, finite
    values, flags), then what it means (the same rules as kernel.c's kernel_state_check): a
    clock a run reaches, a road history as the reader keeps it, contact forces that do not
    pull, displacements and rates within MAX_STATE_DISPLACEMENT_M and MAX_STATE_VELOCITY_M_S,
    and outputs that are the ones its own values give."""
    from .step_limits import (
        MAX_DELAY_STEPS,
        MAX_DISPLACEMENT_M,
        MAX_HISTORY_SAMPLES,
        MAX_STATE_DISPLACEMENT_M,
        MAX_STATE_VELOCITY_M_S,
        MAX_STEP_S,
        MAX_VELOCITY_M_S,
    )

    c = kernel.contract
    k, p = c.n_modes, c.n_points
    if len(data) < 4 * _STATE_INTS:
        return [f"its model part is {len(data)} bytes, shorter than its header"]
    modes, points, history, has_last = struct.unpack_from("<4i", data, 0)
    if (modes, points) != (k, p):
        return [f"state of another model (build both with the same parameters): it holds "
                f"{modes} modes and {points} contact points, this model {k} and {p}"]
    if not 0 <= history <= (len(data) - 4 * _STATE_INTS) // 24:
        return [f"its road history length {history} is impossible"]
    expected = 4 * _STATE_INTS + 8 * (_STATE_HEAD + 2 * k + 5 * p + 3 * history) + p
    if len(data) != expected:
        return [f"its model part is {len(data)} bytes, expected {expected}"]
    if has_last not in (0, 1):
        return [f"its has-last flag is {has_last}, not 0 or 1"]
    s = _StateFields(c, data)
    bad = np.flatnonzero(~np.isfinite(s.values))
    if bad.size:
        return [f"value {int(bad[0])} of its model part is not finite"]
    if has_last and not s.last > 0.0:
        return [f"its last step is {s.last:g} s, not > 0"]
    if np.any(np.frombuffer(data, np.uint8, p, len(data) - p) > 1):
        return ["its contact flags are not 0 or 1"]
    problems = []
    time = s.start + s.elapsed
    if not (s.elapsed >= 0.0 and abs(s.carry) <= math.nextafter(s.elapsed, math.inf)
            - s.elapsed):
        problems.append(f"its clock reads {s.elapsed!r} s since the start with a carry of "
                        f"{s.carry!r} s: a run's clock is >= 0, and its carry below one "
                        "rounding of it")
    last = s.last if has_last else math.nan
    if bool(has_last) != (s.elapsed != 0.0):
        problems.append(f"its clock reads {s.elapsed!r} s since the start and its last step "
                        f"is {last!r} s: only steps advance the clock")
    elif has_last and not s.last <= MAX_STEP_S:
        problems.append(f"its last step is {s.last!r} s; the FMU takes at most {MAX_STEP_S:g} s")
    elif has_last and not clock.resolves(time - s.last, s.last):
        problems.append(f"its last step of {s.last!r} s ends at t = {time!r} s, where the "
                        "clock does not resolve it")
    problems += _history_problems(kernel, s, MAX_HISTORY_SAMPLES, MAX_DELAY_STEPS,
                                  MAX_DISPLACEMENT_M, MAX_VELOCITY_M_S)
    problems += _position_problems(kernel, s)
    length, rate = MAX_STATE_DISPLACEMENT_M, MAX_STATE_VELOCITY_M_S
    forces = kernel.f_static + s.df
    bound = kernel.f_static + kernel.k * (length + np.abs(c.pen_static)) + kernel.c * rate
    if not kernel.linear and np.any(forces < 0.0):
        problems.append("its contact forces pull on the tread (the unilateral contact only "
                        "pushes)")
    if not np.all(np.abs(forces) <= bound):
        problems.append(f"its contact forces exceed what the zone springs give at "
                        f"{length:g} m and {rate:g} m/s")
    size = np.abs(s.q)
    for what, found, limit, unit in (
            ("the tread's excursion at the zone nodes from a mode",
             np.max(size * np.abs(c.gamma), initial=0.0), length, "m"),
            ("the tread's rate at the zone nodes from a mode",
             np.max(size * np.abs(c.eta), initial=0.0), rate, "m/s"),
            ("its penetrations", np.max(np.abs(s.penetration)), length, "m"),
            ("its penetration rates", np.max(np.abs(s.rate)), rate, "m/s"),
            ("the rim and road positions it saw",
             max(abs(s.seen_z), float(np.max(np.abs(s.heights)))), length, "m"),
            ("the road rates it saw", np.max(np.abs(s.slopes)), rate, "m/s"),
            ("the tread deflection it holds", abs(s.ring_out[2]), length, "m")):
        if not found <= limit:
            problems.append(f"{what} reach {float(found):.3g} {unit}, beyond the {limit:g} "
                            f"{unit} a state may hold")
    if not abs(s.seen_vz) <= MAX_VELOCITY_M_S:
        problems.append(f"the rim velocity it saw, {s.seen_vz!r} m/s, is beyond the input "
                        f"limit {MAX_VELOCITY_M_S:g} m/s")
    if not (abs(s.given_vz) <= MAX_VELOCITY_M_S and 0.0 <= s.h_change <= MAX_STEP_S):
        problems.append(f"the rim velocity given last, {s.given_vz!r} m/s, or the step of its "
                        f"last change, {s.h_change!r} s, is beyond what a host gives")
    if not (abs(s.ring_out[0]) <= bound.sum() and abs(s.ring_out[1]) <= bound.sum()):
        problems.append(f"its rim forces exceed what the zone springs give at {length:g} m "
                        f"and {rate:g} m/s")
    if problems:
        return problems
    from .contact import _edges

    front, rear = _edges(c.point_x_road, s.penetration, forces > 0.0)
    scale = float(np.abs(forces).sum() + np.abs(kernel.f_static).sum())
    expected_out = (c.static_ring_out[0] + s.ring_out[0], c.static_ring_out[1] + s.ring_out[1],
                    float(c.point_cos @ forces),
                    c.static_deflection_m + s.heights[c.centre_point] - s.seen_z, front - rear,
                    c.static_ring_out[2] + s.ring_out[2])
    tolerance = (0.0, 0.0, 1e-9 * scale, 0.0,
                 1e-9 * float(c.point_x_road[0] - c.point_x_road[-1]), 0.0)
    from .simulator import OUTPUT_NAMES

    wrong = [f"{name} = {float(g)!r}, but the state gives {float(e)!r}"
             for name, g, e, tol in zip(OUTPUT_NAMES, s.outputs, expected_out, tolerance)
             if not abs(g - e) <= tol]
    if wrong:
        problems.append("its outputs are not the ones it gives: " + "; ".join(wrong))
    return problems


def _history_problems(kernel: NumpyKernel, s: _StateFields, max_samples: int,
                      max_steps: int, max_height: float, max_rate: float) -> list[str]:
    """The road history as the reader keeps it: none at rest; then at most max_samples,
    times increasing, the newest at the last step's start, none before the start, all but
    the oldest within the windows' reach, samples within the inputs' limits."""
    horizon = kernel.horizon_s
    history = s.history
    if kernel.road_by_position is not None:
        return [f"its road history holds {history} samples, but this kernel reads the road by "
                "position and keeps none"] if history else []
    if not kernel.road.delayed:
        return [f"its road history holds {history} samples, but at rest the whole zone reads "
                "the road at the instant and keeps none"] if history else []
    if history > max_samples:
        return [f"its road history holds {history} samples; the FMU keeps at most "
                f"{max_samples} (one a step, over at most {max_steps} steps)"]
    problems = []
    now, last = s.elapsed, s.last if s.has_last else 0.0
    slack = SAME_POINT_EPS * (abs(now) + horizon + 1.0)
    t = s.t
    if not np.all(np.diff(t) > 0.0):
        problems.append("its road history times do not increase")
    if history:
        newest = float(t[-1])
        if not (now - last - slack <= newest <= now + slack):
            problems.append(f"its newest road sample is at {newest!r} s, but the state is at "
                            f"{now!r} s after a step of {s.last if s.has_last else math.nan!r}"
                            " s: the road is sampled at each step's start")
        if t[0] < -slack:
            problems.append(f"its road history starts at {float(t[0])!r} s, before the start")
        if history > 1 and t[1] < newest - horizon - slack:
            problems.append(f"its road history reaches back {newest - float(t[1]):.6g} s from "
                            f"its newest sample, beyond the {horizon:.6g} s the contact zone "
                            "reads (older samples are dropped)")
    elif s.has_last:
        problems.append("its road history is empty, but a step was taken (each step samples "
                        "the road at its start)")
    if not (np.all(np.abs(s.z) <= max_height) and np.all(np.abs(s.v) <= max_rate)):
        problems.append(f"its road samples go beyond the inputs' limits ({max_height:g} m, "
                        f"{max_rate:g} m/s)")
    return problems


def _position_problems(kernel: NumpyKernel, s: _StateFields) -> list[str]:
    """The road by position's part of the head: where the road was read, within what a host
    gives; none with the road by time (kernel.c's position_problems)."""
    from .step_limits import MAX_ROAD_POSITION_M, MAX_VELOCITY_M_S

    where = f"{s.seen_x!r} m"
    if kernel.road_by_position is not None:
        if not (abs(s.seen_x) <= MAX_ROAD_POSITION_M and abs(s.seen_vx) <= MAX_VELOCITY_M_S
                and abs(s.given_vx) <= MAX_VELOCITY_M_S):
            return [f"the position along the road it read the road at, {where}, its rate "
                    f"there, {s.seen_vx!r} m/s, or the rate given last, {s.given_vx!r} m/s, is "
                    f"beyond what a host gives ({MAX_ROAD_POSITION_M:g} m, "
                    f"{MAX_VELOCITY_M_S:g} m/s)"]
        return []
    if s.seen_x != 0.0 or s.seen_vx != 0.0 or s.given_vx != 0.0 or s.change_vx != 0.0:
        return [f"it holds a position along the road ({where}) or its rates ({s.seen_vx!r} "
                f"m/s, given {s.given_vx!r} m/s), but this kernel reads the road by time"]
    return []
