"""The C road-file reader (``tire_fmu/native/c/road_file.c``) through ctypes, for the tests:
compiled on its own with the project's warning flags (any warning fails), opened, read back."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np

from tire_fmu.native.builder import c_folder

FLAGS = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-Wpedantic", "-Wshadow", "-O2")
SOURCES = ("road_file.c", "memory.c")
_DOUBLE_P = ctypes.POINTER(ctypes.c_double)
_WHY_SIZE = 2048


class RoadFileStruct(ctypes.Structure):
    """road_file.h's RoadFile."""

    _fields_ = [("n", ctypes.c_size_t), ("s", _DOUBLE_P), ("z", _DOUBLE_P),
                ("area", _DOUBLE_P), ("lateral_offset_m", ctypes.c_double),
                ("height_shift_m", ctypes.c_double), ("format", ctypes.c_char * 8),
                ("mem", ctypes.c_void_p)]


class CRoadFileError(ValueError):
    """The C refused the file: ``status`` its code, the message its sentence."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


def compile_library(folder: Path) -> Path:
    """road_file.c and memory.c as a shared library in ``folder``."""
    compiler = shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        raise RuntimeError("no C compiler (gcc)")
    source = Path(str(c_folder()))
    library = folder / "road_file.so"
    result = subprocess.run([compiler, *FLAGS, "-shared", "-fPIC", "-I", str(source), "-o",
                             str(library), *(str(source / name) for name in SOURCES), "-lm"],
                            capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"road_file.c does not compile cleanly:\n{result.stderr}")
    return library


class CRoadFiles:
    """The library's functions."""

    def __init__(self, library: Path):
        lib = self.lib = ctypes.CDLL(str(library))
        lib.road_file_open.restype = ctypes.c_int
        lib.road_file_open.argtypes = [ctypes.c_char_p, ctypes.c_double, ctypes.c_void_p,
                                       ctypes.POINTER(RoadFileStruct), ctypes.c_char_p,
                                       ctypes.c_size_t]
        for name in ("road_file_height", "road_file_slope", "road_file_integral"):
            getattr(lib, name).restype = ctypes.c_double
            getattr(lib, name).argtypes = [ctypes.POINTER(RoadFileStruct), ctypes.c_double]
        lib.road_file_mean.restype = ctypes.c_double
        lib.road_file_mean.argtypes = [ctypes.POINTER(RoadFileStruct), ctypes.c_double,
                                       ctypes.c_double]
        lib.road_file_extent.restype = None
        lib.road_file_extent.argtypes = [ctypes.POINTER(RoadFileStruct),
                                         _DOUBLE_P, _DOUBLE_P]
        lib.road_file_free.restype = None
        lib.road_file_free.argtypes = [ctypes.POINTER(RoadFileStruct)]

    def open(self, path, lateral_offset_m: float = 0.0) -> CRoad:
        road = RoadFileStruct()
        why = ctypes.create_string_buffer(_WHY_SIZE)
        status = self.lib.road_file_open(str(path).encode(), lateral_offset_m, None,
                                         ctypes.byref(road), why, _WHY_SIZE)
        if status != 0:
            self.lib.road_file_free(ctypes.byref(road))
            raise CRoadFileError(status, why.value.decode("utf-8", "replace"))
        return CRoad(self.lib, road)


class CRoad:
    """An open road: its knots and the C's reads of it (freed by :meth:`close`)."""

    def __init__(self, lib, road: RoadFileStruct):
        self.lib, self.road = lib, road

    @property
    def distances_m(self) -> np.ndarray:
        return np.ctypeslib.as_array(self.road.s, (self.road.n,)).copy()

    @property
    def heights_m(self) -> np.ndarray:
        return np.ctypeslib.as_array(self.road.z, (self.road.n,)).copy()

    @property
    def data_format(self) -> str:
        return self.road.format.decode()

    @property
    def height_shift_m(self) -> float:
        return self.road.height_shift_m

    @property
    def extent_m(self) -> tuple[float, float]:
        first, last = ctypes.c_double(), ctypes.c_double()
        self.lib.road_file_extent(ctypes.byref(self.road), ctypes.byref(first),
                                  ctypes.byref(last))
        return first.value, last.value

    def _each(self, name, s) -> np.ndarray:
        function = getattr(self.lib, name)
        return np.array([function(ctypes.byref(self.road), float(x)) for x in np.ravel(s)])

    def height(self, s) -> np.ndarray:
        return self._each("road_file_height", s)

    def slope(self, s) -> np.ndarray:
        return self._each("road_file_slope", s)

    def mean(self, s_lo, s_hi) -> np.ndarray:
        return np.array([self.lib.road_file_mean(ctypes.byref(self.road), float(a), float(b))
                         for a, b in zip(np.ravel(s_lo), np.ravel(s_hi))])

    def close(self) -> None:
        self.lib.road_file_free(ctypes.byref(self.road))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
