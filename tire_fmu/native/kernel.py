"""The compiled step kernel (``native/c/kernel.c``) from Python, through ctypes.

The Python FMU and :class:`~tire_fmu.core.contact_dynamics.ContactSimulator` step the tire
with the same C as the native FMU: the contract the Python core built is handed to
``kernel_new`` once, and each communication step is one call of ``kernel_step`` with the four
inputs and five outputs in preallocated arrays. The library is compiled from the package's C
(the kernel, the road reader, the numerics) with the machine's C compiler: by the FMU builder
into the FMU (``binaries/<platform>/tire_kernel.so``), or on first use here into a cache folder
keyed by the sources' hash, so a changed source is never run stale.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ..core.contract import StepContract
from .contract import to_ctypes

#: The C files of the kernel library, and what they include.
KERNEL_SOURCES = ("kernel.c", "road.c", "road_samples.c", "numerics.c", "memory.c",
                  "inplane_step.c", "inplane_ring.c", "inplane_ritz.c", "inplane_critical.c",
                  "inplane_build.c", "inplane_static.c", "contact.c", "inplane_points.c",
                  "inplane_terms.c", "inplane_model.c")
KERNEL_HEADERS = ("kernel.h", "contract.h", "tire.h", "numerics.h", "spec.h", "road_samples.h",
                  "inplane_step.h", "inplane_ring.h", "inplane_ritz.h", "inplane_critical.h",
                  "inplane_build.h", "inplane_static.h", "inplane_points.h", "inplane_terms.h",
                  "inplane_model.h")
KERNEL_FLAGS = ("-shared", "-fPIC", "-O2", "-std=c99", "-Wl,--no-undefined")
LIBRARY_NAME = "tire_kernel"
#: The compiler, flags and file name of the kernel library per FMI platform (mingw's own
#: printf, and no DLL needed beyond the C runtime Windows ships, as the native FMU's).
PLATFORMS = {
    "linux64": (None, KERNEL_FLAGS, ("-lm",), LIBRARY_NAME + ".so"),
    "win64": ("x86_64-w64-mingw32-gcc", ("-shared", "-O2", "-std=c99",
                                         "-D__USE_MINGW_ANSI_STDIO=1", "-static-libgcc"), (),
              LIBRARY_NAME + ".dll"),
}
N_INPUTS, N_OUTPUTS = 4, 6
#: a step's report (kernel.h): the outputs, the time, whether the footprint is at a zone end
REPORT, REPORT_TIME, REPORT_ZONE_EDGE = N_OUTPUTS + 2, N_OUTPUTS, N_OUTPUTS + 1
REFUSED = -3
_WHY_SIZE = 2048  # as fmi2_layer.c's messages: the two FMUs quote a state's problems alike


class KernelUnavailable(RuntimeError):
    """No compiled kernel here (no C compiler, or the library does not load)."""


def _c_folder() -> Path:
    """The package's C (importlib.resources: the builder's c_folder, without importing it)."""
    from importlib import resources

    return Path(str(resources.files(__package__) / "c"))  # the package under any name


def sources_digest() -> str:
    """A hash of the kernel's C: the cache key, and what an FMU's library was built from."""
    digest = hashlib.sha256()
    folder = _c_folder()
    for name in KERNEL_SOURCES + KERNEL_HEADERS:
        digest.update(name.encode() + b"\0" + (folder / name).read_bytes())
    return digest.hexdigest()[:16]


def compiler() -> str | None:
    cc = os.environ.get("CC", "").split() or ["gcc"]
    return shutil.which(cc[0]) and cc[0]


def host_platform() -> str | None:
    """The FMI platform this process runs on, where the kernel library is built for it."""
    import struct
    import sys

    if struct.calcsize("P") != 8:
        return None
    return {"linux": "linux64", "win32": "win64"}.get(sys.platform)


def compile_kernel(destination: Path, platform: str = "linux64") -> Path:
    """Compile the kernel library for ``platform`` (linux64 with $CC or gcc, win64 with
    mingw-w64) to ``destination`` (a file path); KernelUnavailable when there is no such
    compiler or it fails (with its output)."""
    tool, flags, libraries, _ = PLATFORMS[platform]
    command = shutil.which(tool) and tool if tool else compiler()
    if command is None:
        raise KernelUnavailable(f"no C compiler for {platform} found ("
                                + ("install gcc, or set CC" if tool is None else
                                   f"install {tool}") + ")")
    folder = _c_folder()
    destination = Path(destination)
    destination.parent.mkdir(parents=True, exist_ok=True)
    handle, partial = tempfile.mkstemp(prefix=destination.name + ".", suffix=".partial",
                                       dir=destination.parent)
    os.close(handle)
    try:
        result = subprocess.run(
            [command, *flags, "-o", partial, *(str(folder / s) for s in KERNEL_SOURCES),
             *libraries], capture_output=True, text=True)
        if result.returncode != 0:
            raise KernelUnavailable(f"compiling the step kernel failed:\n{result.stderr}")
        os.replace(partial, destination)
    finally:
        if os.path.exists(partial):
            os.unlink(partial)
    return destination


def _cache_folder() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "tire_fmu"


_LOADED: dict[str, ctypes.CDLL] = {}


def load_library(path: str | Path | None = None) -> ctypes.CDLL:
    """The kernel library at ``path``, or the one compiled for this package's sources (made
    on first use); KernelUnavailable if neither can be had."""
    if path is None:
        path = _cache_folder() / f"{LIBRARY_NAME}-{sources_digest()}.so"
        if not path.exists():
            try:
                compile_kernel(path)
            except OSError:  # no writable cache: a private folder then
                path = Path(tempfile.mkdtemp(prefix="tire_fmu_kernel_")) / path.name
                compile_kernel(path)
    key = str(path)
    if key not in _LOADED:
        try:
            library = ctypes.CDLL(key)
        except OSError as error:
            raise KernelUnavailable(f"the step kernel {key} does not load: {error}") from error
        _declare(library)
        _LOADED[key] = library
    return _LOADED[key]


def _declare(lib: ctypes.CDLL) -> None:
    handle, double, p_double = ctypes.c_void_p, ctypes.c_double, ctypes.POINTER(ctypes.c_double)
    size, p_byte = ctypes.c_size_t, ctypes.POINTER(ctypes.c_ubyte)
    lib.kernel_new.restype = handle
    lib.kernel_new.argtypes = [ctypes.c_void_p, double, ctypes.c_char_p, size]
    lib.kernel_destroy.restype = None
    lib.kernel_destroy.argtypes = [handle]
    lib.kernel_reset.restype = None
    lib.kernel_reset.argtypes = [handle, double]
    lib.kernel_step.restype = ctypes.c_int
    lib.kernel_step.argtypes = [handle, double, p_double, p_double]
    lib.kernel_outputs_with.restype = ctypes.c_int
    lib.kernel_outputs_with.argtypes = [handle, p_double, p_double]
    lib.kernel_step_problems.restype = ctypes.c_int
    lib.kernel_step_problems.argtypes = [handle, double, p_double]
    lib.kernel_step_at.restype = ctypes.c_int
    lib.kernel_step_at.argtypes = [handle, double, p_double, p_double]
    lib.kernel_outputs_at.restype = ctypes.c_int
    lib.kernel_outputs_at.argtypes = [handle, p_double, p_double]
    lib.kernel_step_at_problems.restype = ctypes.c_int
    lib.kernel_step_at_problems.argtypes = [handle, double, p_double]
    lib.kernel_set_road.restype = ctypes.c_int
    lib.kernel_set_road.argtypes = [handle, p_double, p_double, p_double, ctypes.c_int,
                                    ctypes.c_char_p, size]
    lib.kernel_road_position.restype = double
    lib.kernel_road_position.argtypes = [handle]
    lib.kernel_outputs.restype = None
    lib.kernel_outputs.argtypes = [handle, p_double]
    for name in ("kernel_time", "kernel_start_time", "kernel_elapsed", "kernel_min_step",
                 "kernel_horizon"):
        getattr(lib, name).restype = double
        getattr(lib, name).argtypes = [handle]
    for name in ("kernel_in_contact", "kernel_at_zone_edge", "kernel_cached_steps",
                 "kernel_delay_line_on", "kernel_road_on"):
        getattr(lib, name).restype = ctypes.c_int
        getattr(lib, name).argtypes = [handle]
    lib.kernel_solver_fallbacks.restype = ctypes.c_long
    lib.kernel_solver_fallbacks.argtypes = [handle]
    lib.kernel_set_fallback_only.restype = None
    lib.kernel_set_fallback_only.argtypes = [handle, ctypes.c_int]
    lib.kernel_forces.restype = None
    lib.kernel_forces.argtypes = [handle, p_double]
    lib.kernel_state_size.restype = size
    lib.kernel_state_size.argtypes = [handle]
    lib.kernel_state_write.restype = None
    lib.kernel_state_write.argtypes = [handle, p_byte]
    lib.kernel_state_check.restype = ctypes.c_int
    lib.kernel_state_check.argtypes = [handle, p_byte, size, ctypes.c_char_p, size]
    lib.kernel_state_apply.restype = ctypes.c_int
    lib.kernel_state_apply.argtypes = [handle, p_byte]


def road_samples(road) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions, heights, running integral): the samples through which the C reads a road by
    position (road_samples.h), those the road's own ``window_reads`` reads: a
    :class:`~tire_fmu.core.obstacles.ProfileRoad`'s knots, or the samples a road that keeps
    them gives by ``state()`` (PositionRoad, HostRoad)."""
    state = getattr(road, "state", None)
    if callable(state):
        samples = np.asarray(state(), dtype=float).reshape(-1, 3)
        return tuple(np.ascontiguousarray(samples[:, i]) for i in range(3))
    knots = getattr(road, "_at_knots", None)
    if knots is None:
        raise TypeError(f"road: a {type(road).__name__} is no sampled road (a ProfileRoad, a "
                        "PositionRoad or a HostRoad)")
    return tuple(np.ascontiguousarray(a, dtype=float)
                 for a in (road.distances_m, road.heights_m, knots))


class CompiledKernel:
    """The C kernel stepping one contract: the calls of :class:`~tire_fmu.core.kernel_numpy.
    NumpyKernel`, each one call into the library."""

    def __init__(self, contract: StepContract, start_time: float = 0.0,
                 library: ctypes.CDLL | None = None, road=None):
        self.contract = contract
        self._lib = lib = library or load_library()
        why = ctypes.create_string_buffer(_WHY_SIZE)
        struct = to_ctypes(contract)
        handle = lib.kernel_new(ctypes.byref(struct), float(start_time), why, _WHY_SIZE)
        if not handle:
            raise KernelUnavailable(f"the step kernel refused the contract: "
                                    f"{why.value.decode(errors='replace')}")
        self._handle = handle
        self._in = (ctypes.c_double * N_INPUTS)()
        self._out = (ctypes.c_double * REPORT)()
        self._step = lib.kernel_step
        self.horizon_s = lib.kernel_horizon(handle)
        self.road_by_position = None
        self._road_arrays = None  # the samples the C reads in place: kept alive here
        if road is not None:
            self.set_road(road)

    def __del__(self):
        handle, self._handle = getattr(self, "_handle", None), None
        if handle:
            self._lib.kernel_destroy(handle)

    def _check(self, status: int, call: str) -> None:
        if status != 0:
            raise MemoryError(f"{call}: the step kernel ran out of memory")

    def reset(self, start_time: float = 0.0) -> None:
        self._lib.kernel_reset(self._handle, float(start_time))

    @property
    def time(self) -> float:
        return self._lib.kernel_time(self._handle)

    @property
    def start_time(self) -> float:
        return self._lib.kernel_start_time(self._handle)

    @property
    def elapsed_s(self) -> float:
        return self._lib.kernel_elapsed(self._handle)

    def step_values(self, h: float, z: float, vz: float, road_z: float, road_vz: float):
        """One communication step; the outputs at the new time as a list, or None (nothing
        changed) for a step the kernel's rules refuse."""
        inputs = self._in
        inputs[0], inputs[1], inputs[2], inputs[3] = z, vz, road_z, road_vz
        status = self._step(self._handle, h, inputs, self._out)
        if status:
            if status == REFUSED:
                return None
            self._check(status, "kernel_step")
        return self._out[0:N_OUTPUTS]

    def raw_step(self, at: bool = False):
        """(function, handle, inputs, report) of the hot path: function(handle, h, inputs,
        report) steps with the four inputs in ``inputs`` and writes the report (the outputs,
        the time, the zone-edge flag) into ``report``; 0, or -3 refused, or -1 no memory.
        ``at``: kernel_step_at's, the road by position (inputs rim_z, rim_vz, x, vx; a road
        that changes is set again, :meth:`set_road`, before the call)."""
        return (self._lib.kernel_step_at if at else self._step), self._handle, self._in, \
            self._out

    # -- the road by position ------------------------------------------------------------------
    def set_road(self, road) -> None:
        """Read the road by position from now on (kernel_set_road), through its samples
        (:func:`road_samples`); a road that keeps samples (a PositionRoad) is read again at
        each :meth:`step_on_road`, so that the C reads it as it is then. ValueError with the
        kernel's reason for bad samples or a kernel that has read the road by time."""
        self._load_road(road)
        self.road_by_position = road

    def _load_road(self, road) -> None:
        arrays = road_samples(road)
        pointer = ctypes.POINTER(ctypes.c_double)
        why = ctypes.create_string_buffer(_WHY_SIZE)
        status = self._lib.kernel_set_road(self._handle, *(a.ctypes.data_as(pointer)
                                                           for a in arrays),
                                           int(arrays[0].size), why, _WHY_SIZE)
        if status:
            raise ValueError(f"road: {why.value.decode(errors='replace')}")
        self._road_arrays = arrays

    def _refresh_road(self) -> None:
        road = self.road_by_position
        if road is not None and callable(getattr(road, "state", None)):
            self._load_road(road)

    @property
    def road_on(self) -> bool:
        return bool(self._lib.kernel_road_on(self._handle))

    @property
    def road_position(self) -> float:
        """Where along the road the road was read last (m)."""
        return self._lib.kernel_road_position(self._handle)

    def step_on_road(self, h: float, z: float, vz: float, x: float, vx: float):
        """One communication step with the road by position (kernel_step_at); the outputs at
        the new time, or None (nothing changed) for a step the kernel refuses."""
        self._refresh_road()
        inputs = self._in
        inputs[0], inputs[1], inputs[2], inputs[3] = z, vz, x, vx
        status = self._lib.kernel_step_at(self._handle, h, inputs, self._out)
        if status:
            if status == REFUSED:
                return None
            self._check(status, "kernel_step_at")
        return np.array(self._out[0:N_OUTPUTS])

    def outputs_on_road(self, z: float, vz: float, x: float, vx: float):
        """The outputs at the current time for inputs given there, the road by position
        (kernel_outputs_at), or None if refused."""
        self._refresh_road()
        self._in[:] = [float(z), float(vz), float(x), float(vx)]
        status = self._lib.kernel_outputs_at(self._handle, self._in, self._out)
        if status == REFUSED:
            return None
        self._check(status, "kernel_outputs_at")
        return np.array(self._out[0:N_OUTPUTS])

    def step_problems(self, h: float, inputs, at: bool = False) -> int:
        """kernel_step_problems (``at``: kernel_step_at_problems): why a step is refused, as
        bits (kernel.h), 0 if it is not."""
        values = (ctypes.c_double * N_INPUTS)(*(float(x) for x in inputs))
        call = self._lib.kernel_step_at_problems if at else self._lib.kernel_step_problems
        return int(call(self._handle, float(h), values))


    def outputs_with(self, inputs):
        """The outputs at the current time for inputs given there, or None if refused."""
        self._in[:] = [float(x) for x in inputs]
        status = self._lib.kernel_outputs_with(self._handle, self._in, self._out)
        if status == REFUSED:
            return None
        self._check(status, "kernel_outputs_with")
        return self._out[0:N_OUTPUTS]

    @property
    def outputs(self) -> np.ndarray:
        out = (ctypes.c_double * N_OUTPUTS)()
        self._lib.kernel_outputs(self._handle, out)
        return np.array(out[:])

    @property
    def forces(self) -> np.ndarray:
        out = np.zeros(self.contract.n_points)
        self._lib.kernel_forces(self._handle, out.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
        return out

    def at_zone_edge(self) -> bool:
        return bool(self._lib.kernel_at_zone_edge(self._handle))

    @property
    def cached_steps(self) -> int:
        """How many communication step sizes have their coefficients cached."""
        return int(self._lib.kernel_cached_steps(self._handle))

    @property
    def delay_line_on(self) -> bool:
        """Whether the road is read by road.c's delay line (a run of equal steps)."""
        return bool(self._lib.kernel_delay_line_on(self._handle))

    @property
    def solver_fallbacks(self) -> int:
        return int(self._lib.kernel_solver_fallbacks(self._handle))

    def set_fallback_only(self, on: bool) -> None:
        """Solve every contact problem by the Gauss-Seidel fallback (to test it: left to itself
        the active set settles in almost every solve)."""
        self._lib.kernel_set_fallback_only(self._handle, int(on))

    def state_bytes(self) -> bytes:
        size = self._lib.kernel_state_size(self._handle)
        buffer = (ctypes.c_ubyte * size)()
        self._lib.kernel_state_write(self._handle, buffer)
        return bytes(buffer)

    def state_problem(self, data: bytes) -> str | None:
        """Why ``data`` is not a state of this kernel, or None."""
        buffer = (ctypes.c_ubyte * len(data)).from_buffer_copy(data)
        why = ctypes.create_string_buffer(_WHY_SIZE)
        if self._lib.kernel_state_check(self._handle, buffer, len(data), why, _WHY_SIZE):
            return why.value.decode(errors="replace")
        return None

    def set_state_bytes(self, data: bytes) -> None:
        problem = self.state_problem(data)
        if problem:
            raise ValueError(problem)
        buffer = (ctypes.c_ubyte * len(data)).from_buffer_copy(data)
        self._check(self._lib.kernel_state_apply(self._handle, buffer), "kernel_state_apply")
