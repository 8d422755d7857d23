"""Stepping a contact model in time: :class:`ContactSimulator`, over either step kernel.

A :class:`~.contact_dynamics.ContactModel` is turned into its :class:`~.contract.StepContract`
once; a kernel then steps it: the compiled C of ``native/c/kernel.c`` (the one both FMUs run)
when it can be had, or :class:`~.kernel_numpy.NumpyKernel`, its readable numpy reference. The
two are the same algorithm and agree to 1e-10; ``backend`` chooses ("auto": compiled if the
machine can build it, else numpy, with a :class:`KernelFallbackWarning`). This module checks
what a caller gives (step sizes, input ranges, state bytes) and keeps the API the rest of the
package and its users call; the arithmetic is the kernel's.

Outputs are totals: rim_Fz, rim_Fx (tire on rim), contact_Fz (road on tire, never negative
with the unilateral law), deflection (the rim's lowering towards the road at the contact
centre), contact_length (footprint length on the road, m) and tread_deflection (the tread's
compression at the contact centre relative to the rim).

The clock is the time since the start (:mod:`.clock`): a step the clock cannot resolve at
the absolute time is refused, and the road history is indexed by the time since the start, so
the outputs do not depend on when a run starts.
"""

from __future__ import annotations

import hashlib
import math
import warnings
from dataclasses import dataclass

import numpy as np

from . import clock
from .contract import StepContract, build_contract
from .kernel_numpy import SUBSTEP_SLACK, NumpyKernel, state_data, state_fields
from .step_limits import (
    LONG_STEP_TEMPLATE,
    MAX_DISPLACEMENT_M,
    MAX_STEP_WORK,
    MAX_VELOCITY_M_S,
    SHORT_STEP_TEMPLATE,
)

OUTPUT_NAMES = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length",
                "tread_deflection")
OUTPUT_UNITS = {"rim_Fz": "N", "rim_Fx": "N", "contact_Fz": "N", "deflection": "m",
                "contact_length": "m", "tread_deflection": "m"}
INPUT_NAMES = ("rim_z", "rim_vz", "road_z", "road_vz")
BACKENDS = ("auto", "compiled", "numpy")
_STATE_MAGIC = b"tire_fmu.kernel-state/2"


class StepError(ValueError):
    """A step the simulator refuses (bad h, non-finite input); nothing was changed."""


class StateError(ValueError):
    """Bytes that are not a state of this simulator (format, checksum, shape, values)."""


class KernelFallbackWarning(UserWarning):
    """The compiled kernel could not be had: the numpy reference steps instead (slower)."""


def make_kernel(contract: StepContract, start_time: float = 0.0, backend: str = "auto",
                library=None):
    """A kernel stepping ``contract``: (kernel, the backend it is). ``library``: a loaded
    compiled kernel library to use (the Python FMU's own), else the package's."""
    if backend not in BACKENDS:
        from .parameters import ParameterError, Problem

        raise ParameterError([Problem("backend", backend, "", f"one of {', '.join(BACKENDS)}")])
    if backend != "numpy":
        # the compiled kernel lives outside the core (ctypes and a C compiler): imported only
        # when asked for, so the core itself needs numpy and scipy alone
        try:
            from ..native.kernel import CompiledKernel, KernelUnavailable
        except ImportError as error:
            if backend == "compiled":
                raise
            warnings.warn(f"the compiled step kernel is not available ({error}); stepping "
                          "with the numpy reference kernel", KernelFallbackWarning, stacklevel=3)
        else:
            try:
                return CompiledKernel(contract, start_time, library), "compiled"
            except KernelUnavailable as error:
                if backend == "compiled":
                    raise
                warnings.warn(f"{error}; stepping with the numpy reference kernel",
                              KernelFallbackWarning, stacklevel=3)
    return NumpyKernel(contract, start_time), "numpy"


@dataclass(frozen=True, eq=False)
class ContactState:
    """A :class:`ContactSimulator`'s state: the kernel's bytes (one layout for both kernels
    and both FMUs, ``native/c/kernel.c``), checked by a SHA-256 when read back."""

    data: bytes

    def to_bytes(self) -> bytes:
        digest = hashlib.sha256(self.data).hexdigest().encode()
        return _STATE_MAGIC + b" " + digest + b"\n" + self.data

    @classmethod
    def from_bytes(cls, data: bytes) -> ContactState:
        data = bytes(data)
        head, newline, payload = data.partition(b"\n")
        magic, _, digest = head.partition(b" ")
        if magic != _STATE_MAGIC:
            raise StateError(f"not a tire_fmu contact state of this version: it starts with "
                             f"{data[:len(_STATE_MAGIC)]!r}")
        if not newline or hashlib.sha256(payload).hexdigest().encode() != digest:
            raise StateError("contact state damaged: its checksum does not match")
        if len(payload) < 16 + 8 * 15:
            raise StateError(f"contact state of {len(payload)} bytes: shorter than its header")
        return cls(payload)

    def fields(self) -> dict:
        """What the state holds, by name (the layout of kernel.c; kernel_numpy.state_fields):
        start_time, elapsed_s, carry_s, last_step_s (nan: no step yet), seen_z, seen_vz,
        ring_out, outputs, given_vz, change, h_change, seen_x, seen_vx, given_vx, change_vx,
        q, df, penetration, rate, seen_heights, seen_slopes, history_t, history_z, history_v,
        active."""
        return state_fields(self.data)

    def replaced(self, **changes) -> ContactState:
        """The same state with some fields changed (a tool to build states, forged ones
        included: setting one checks what it means)."""
        fields = self.fields()
        unknown = set(changes) - set(fields)
        if unknown:
            raise TypeError(f"no state fields {sorted(unknown)}; they are {list(fields)}")
        return ContactState(state_data({**fields, **changes}))

    def __getattr__(self, name: str):
        if name != "data" and name in _FIELD_NAMES:
            return self.fields()[name]
        raise AttributeError(name)

    @property
    def time(self) -> float:
        fields = self.fields()
        return fields["start_time"] + fields["elapsed_s"]


_FIELD_NAMES = frozenset(("start_time", "elapsed_s", "carry_s", "last_step_s", "seen_z",
                          "seen_vz", "ring_out", "outputs", "given_vz", "change", "h_change",
                          "seen_x", "seen_vx", "given_vx", "change_vx", "q", "df",
                          "penetration", "rate",
                          "seen_heights", "seen_slopes", "history_t", "history_z", "history_v",
                          "active"))


class ContactSimulator:
    """Steps a :class:`~.contact_dynamics.ContactModel` from communication point to
    communication point (module doc)."""

    def __init__(self, contact, start_time: float = 0.0, backend: str = "auto", library=None):
        self.contact = contact
        self.contract = build_contract(contact)
        self.kernel, self.backend = make_kernel(self.contract, start_time, backend, library)
        self.static_active = self.contract.f_static > 0.0
        self.n_zone = self.contract.n_points
        self.min_step_s = self.contract.min_step_s

    # -- time and state -----------------------------------------------------------------------
    @property
    def time(self) -> float:
        """The clock: the start time plus the time since it."""
        return self.kernel.time

    @property
    def start_time(self) -> float:
        return self.kernel.start_time

    @property
    def elapsed_s(self) -> float:
        """The time since the start: what the road history is indexed by."""
        return self.kernel.elapsed_s

    def reset(self, start_time: float = 0.0) -> None:
        self.kernel.reset(start_time)

    def get_state(self) -> ContactState:
        return ContactState(self.kernel.state_bytes())

    def state_problems(self, state: ContactState) -> list[str]:
        """Everything that makes ``state`` no state of this simulator (empty when it is
        one): its layout and what it means, checked by the kernel (kernel_state_check)."""
        problem = self.kernel.state_problem(state.data)
        return problem.split("; ") if problem else []

    def set_state(self, state: ContactState) -> None:
        """Continue from ``state`` exactly as the run it was taken from; StateError listing
        every problem changes nothing."""
        problems = self.state_problems(state)
        if problems:
            raise StateError("; ".join(problems))
        self.kernel.set_state_bytes(state.data)

    # -- stepping -----------------------------------------------------------------------------
    def step(self, h: float, rim_z: float, rim_vz: float, road_z: float, road_vz: float
             ) -> np.ndarray:
        return np.array(self.step_values(h, rim_z, rim_vz, road_z, road_vz))

    def step_values(self, h: float, rim_z: float, rim_vz: float, road_z: float,
                    road_vz: float) -> tuple[float, ...]:
        """Advance from ``time`` to ``time + h`` with the inputs given at ``time`` (ramped
        with their rates); the total outputs at the new time. The kernel checks the step
        (kernel_step_problems); a refused one raises StepError naming every problem, and
        changes nothing."""
        out = self.kernel.step_values(h, rim_z, rim_vz, road_z, road_vz)
        if out is None:
            self._check(h, (rim_z, rim_vz, road_z, road_vz))
            raise AssertionError("the kernel refused a step the core finds no fault with")
        return tuple(out)

    def outputs_with(self, rim_z: float, rim_vz: float, road_z: float, road_vz: float
                     ) -> tuple[float, ...]:
        """Total outputs at ``time`` for inputs given at ``time``; the state keeps the
        re-evaluated forces, which the next step starts from."""
        out = self.kernel.outputs_with((rim_z, rim_vz, road_z, road_vz))
        if out is None:
            self._check(None, (rim_z, rim_vz, road_z, road_vz))
            raise AssertionError("the kernel refused inputs the core finds no fault with")
        return tuple(float(x) for x in out)

    def _check(self, h: float | None, values: tuple) -> None:
        """Raise StepError naming every bad value (h, an input outside its range, or a step
        the clock does not resolve at the current time; None: no step, the inputs only)."""
        problems = []
        if h is None:
            pass
        elif not (h > 0.0 and math.isfinite(h)):
            problems.append(f"step size h = {h!r} s: must be finite and > 0")
        elif h < self.min_step_s:
            problems.append(SHORT_STEP_TEMPLATE % (repr(h), self.min_step_s))
        elif not clock.resolves(self.time, h):
            problems.append(clock.resolution_problem(self.time, h))
        else:
            c = self.contract
            n_sub = math.ceil(h / c.substep_s * (1 - SUBSTEP_SLACK))
            if n_sub * c.substep_work > MAX_STEP_WORK:
                longest = (MAX_STEP_WORK // c.substep_work) * c.substep_s
                problems.append(LONG_STEP_TEMPLATE % (repr(h), n_sub, c.substep_s,
                                                      c.substep_work, MAX_STEP_WORK, longest))
        for name, value in zip(INPUT_NAMES, values):
            limit, unit = ((MAX_VELOCITY_M_S, "m/s") if name.endswith("vz")
                           else (MAX_DISPLACEMENT_M, "m"))
            if not (math.isfinite(value) and abs(value) <= limit):
                problems.append(f"{name} = {value!r} {unit}: must be in [-{limit:g}, "
                                f"{limit:g}] {unit}")
        if problems:
            raise StepError("; ".join(problems))

    # -- what it shows ------------------------------------------------------------------------
    @property
    def outputs(self) -> np.ndarray:
        return np.array(self.kernel.outputs)

    def output_dict(self) -> dict[str, float]:
        return dict(zip(OUTPUT_NAMES, (float(x) for x in self.kernel.outputs)))

    @property
    def forces(self) -> np.ndarray:
        """The road's push on each contact point at ``time`` (N)."""
        return np.array(self.kernel.forces)

    @property
    def in_contact(self) -> bool:
        return bool(self.kernel.outputs[2] > 0.0)

    def at_zone_edge(self) -> bool:
        """Whether a zone end point pushes: the footprint may reach beyond the zone."""
        return bool(self.kernel.at_zone_edge())

    @property
    def solver_fallbacks(self) -> int:
        return int(self.kernel.solver_fallbacks)
