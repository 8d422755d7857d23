"""Stepping a contact model in time: :class:`ContactSimulator`, over either step kernel.

A :class:`~.contact_dynamics.ContactModel` is turned into its :class:`~.contract.StepContract`
once; a kernel then steps it: the compiled C of ``native/c/kernel.c`` (the one both FMUs run)
when it can be had, or :class:`~.kernel_numpy.NumpyKernel`, its readable numpy reference. The
two are the same algorithm and agree to 1e-10; ``backend`` chooses ("auto": compiled if the
machine can build it, else numpy). This module checks what a caller gives (step sizes,
input ranges, state bytes) and keeps the API the rest of the package and its users call.

Outputs are totals: rim_Fz, rim_Fx (tire on rim), contact_Fz (road on tire, never negative
with the unilateral law), deflection (tread compression at the contact centre relative to the
rim) and contact_length (footprint length on the road, m).
"""

from __future__ import annotations

import hashlib
import math
import warnings
from dataclasses import dataclass

import numpy as np

from .contract import StepContract, build_contract
from .kernel_numpy import NumpyKernel

OUTPUT_NAMES = ("rim_Fz", "rim_Fx", "contact_Fz", "deflection", "contact_length")
INPUT_NAMES = ("rim_z", "rim_vz", "road_z", "road_vz")
#: Largest input magnitudes a step accepts (m, m/s): far beyond any tire's travel, but
#: finite enough that no product inside a step can overflow.
MAX_DISPLACEMENT_M = 10.0
MAX_VELOCITY_M_S = 1000.0
BACKENDS = ("auto", "compiled", "numpy")
_STATE_MAGIC = b"tire_fmu.kernel-state/1"


class StepError(ValueError):
    """A step the simulator refuses (bad h, non-finite input); nothing was changed."""


class StateError(ValueError):
    """Bytes that are not a state of this simulator (format, checksum, shape, values)."""


class KernelFallbackWarning(UserWarning):
    """The compiled kernel could not be had: the numpy reference steps instead (slower)."""


def make_kernel(contract: StepContract, start_time: float = 0.0, backend: str = "auto"):
    """A kernel stepping ``contract``: (kernel, the backend it is)."""
    if backend not in BACKENDS:
        from .parameters import ParameterError, Problem

        raise ParameterError([Problem("backend", backend, "", f"one of {', '.join(BACKENDS)}")])
    if backend != "numpy":
        try:  # the compiled kernel lives outside the core: ctypes and a C compiler
            from ..native.kernel import CompiledKernel, KernelUnavailable
        except ImportError as error:  # a core without the native package
            if backend == "compiled":
                raise
            warnings.warn(f"the compiled step kernel is not available ({error}); stepping "
                          "with the numpy reference", KernelFallbackWarning, stacklevel=3)
        else:
            try:
                return CompiledKernel(contract, start_time), "compiled"
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
            raise StateError(f"not a tire_fmu contact state: it starts with {data[:24]!r}")
        if not newline or hashlib.sha256(payload).hexdigest().encode() != digest:
            raise StateError("contact state damaged: its checksum does not match")
        return cls(payload)


class ContactSimulator:
    """Steps a :class:`~.contact_dynamics.ContactModel` from communication point to
    communication point (module doc)."""

    def __init__(self, contact, start_time: float = 0.0, backend: str = "auto"):
        self.contact = contact
        self.contract = build_contract(contact)
        self.kernel, self.backend = make_kernel(self.contract, start_time, backend)
        self.static_active = self.contract.f_static > 0.0

    # -- time and state -----------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.kernel.time

    @time.setter
    def time(self, value: float) -> None:
        self.kernel.time = float(value)

    def reset(self, start_time: float = 0.0) -> None:
        self.kernel.reset(start_time)

    def get_state(self) -> ContactState:
        return ContactState(self.kernel.state_bytes())

    def set_state(self, state: ContactState) -> None:
        """Restore a state; StateError (nothing changed) if it is not one of this model's."""
        problem = state_problem(self.contract, state.data)
        if problem is None and self.backend == "compiled":
            problem = self.kernel.state_problem(state.data)
        if problem:
            raise StateError(f"state of another model or damaged: {problem}")
        self.kernel.set_state_bytes(state.data)

    # -- stepping -----------------------------------------------------------------------------
    def step(self, h: float, rim_z: float, rim_vz: float, road_z: float, road_vz: float
             ) -> np.ndarray:
        return np.array(self.step_values(h, rim_z, rim_vz, road_z, road_vz))

    def step_values(self, h: float, rim_z: float, rim_vz: float, road_z: float,
                    road_vz: float) -> tuple[float, ...]:
        """Advance from ``time`` to ``time + h`` with the inputs given at ``time`` (ramped
        with their rates); the total outputs at the new time."""
        if not (h > 0.0 and math.isfinite(h)) or (rim_z + rim_vz + road_z + road_vz) * 0.0 \
                != 0.0 or abs(rim_z) > MAX_DISPLACEMENT_M or abs(road_z) > MAX_DISPLACEMENT_M \
                or abs(rim_vz) > MAX_VELOCITY_M_S or abs(road_vz) > MAX_VELOCITY_M_S:
            _check(h, (rim_z, rim_vz, road_z, road_vz))
        return tuple(self.kernel.step_values(h, rim_z, rim_vz, road_z, road_vz)) \
            if self.backend == "compiled" else tuple(
                float(x) for x in self.kernel.step(h, (rim_z, rim_vz, road_z, road_vz)))

    def outputs_with(self, rim_z: float, rim_vz: float, road_z: float, road_vz: float
                     ) -> tuple[float, ...]:
        """Total outputs at ``time`` for inputs given at ``time``; the state keeps the
        re-evaluated forces, which the next step starts from."""
        _check(1.0, (rim_z, rim_vz, road_z, road_vz))
        return tuple(float(x) for x in self.kernel.outputs_with((rim_z, rim_vz, road_z,
                                                                 road_vz)))

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


def _check(h: float, values: tuple) -> None:
    """Raise StepError naming every bad value (h, or an input outside its range)."""
    problems = []
    if not (h > 0.0 and math.isfinite(h)):
        problems.append(f"step size h = {h!r} s: must be finite and > 0")
    for name, value in zip(INPUT_NAMES, values):
        limit, unit = ((MAX_VELOCITY_M_S, "m/s") if name.endswith("vz")
                       else (MAX_DISPLACEMENT_M, "m"))
        if not (math.isfinite(value) and abs(value) <= limit):
            problems.append(f"{name} = {value!r} {unit}: must be in [-{limit:g}, "
                            f"{limit:g}] {unit}")
    if problems:
        raise StepError("; ".join(problems))


def state_problem(contract: StepContract, data: bytes) -> str | None:
    """Why ``data`` is not a kernel state of ``contract`` (the layout of kernel.c), or None."""
    import struct

    if len(data) < 16:
        return f"{len(data)} bytes, shorter than a state's header"
    modes, points, history, has_last = struct.unpack_from("<4i", data, 0)
    if (modes, points) != (contract.n_modes, contract.n_points):
        return (f"it holds {modes} modes and {points} contact points, this model "
                f"{contract.n_modes} and {contract.n_points}")
    if not 0 <= history <= (len(data) - 16) // 24 or has_last not in (0, 1):
        return "its header is impossible"
    count = 12 + 2 * modes + 5 * points + 3 * history
    if len(data) != 16 + 8 * count + points:
        return f"{len(data)} bytes, expected {16 + 8 * count + points}"
    values = np.frombuffer(data, "<f8", count, 16)
    if not np.all(np.isfinite(values)):
        return "it holds non-finite values"
    t = values[12 + 2 * modes + 5 * points:][:history]
    if np.any(np.diff(t) <= 0):
        return "its road history times do not increase"
    if has_last and not values[1] > 0:
        return f"its last step is {values[1]!r} s, not > 0"
    if np.any(np.frombuffer(data, np.uint8, points, len(data) - points) > 1):
        return "its contact flags are not 0 or 1"
    return None
