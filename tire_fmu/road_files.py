"""Road files: OpenCRG (``.crg``, ASAM) and plain two-column profiles, read into the road the
tire reads by position (:class:`~tire_fmu.core.obstacles.ProfileRoad`), and written.

The physics core knows no files: this module turns a file into a ``ProfileRoad`` (heights at
distances along the road, linear between them, level at its end heights beyond them), whose
window means and slopes the in-plane simulator and the radial kernel read. The same reader in
C is ``tire_fmu/native/c/road_file.c``, for the native FMUs; tests hold the two equal and
equal to the ASAM OpenCRG C API (through pycrg).

OpenCRG
-------
A ``.crg`` file holds a grid of heights z(u, v): u along a reference line, v across it (left
positive), ``reference_line_increment`` apart in u. The tire rolls along u at a lateral offset
v (``lateral_offset_m``); the road it reads is the grid's long section at that v, interpolated
between the two long sections either side of it and linearly in u between cross sections:
the bilinear interpolation of the OpenCRG C API (``crgEvaluv2z``), which at a fixed v is
linear in u, so the profile's knots are the cross sections and the profile is the C API's
evaluation everywhere. Added to it, as the C API adds them: the reference line's height
(``reference_line_start_z``, or integrated from its slope, ``reference_line_start_s`` or a
``reference line slope`` channel, with the C API's forward or forward-backward integration when
``reference_line_end_z`` is given), the banking (``reference_line_start_b`` or a ``reference
line banking`` channel) times v, and the shift of the file's modifiers: without a
``$ROAD_CRG_MODS`` block, OpenCRG's default modifiers put the height at the start of the
reference line (u first, v = 0) to 0; ``refpoint_*`` modifiers put the height at their point to
``refpoint_z``; ``refline_offset_z`` adds its offset. That is what the ASAM tools and
``pycrg.DataSet.open`` give after loading the file and applying its modifiers.

Read: the data formats the C API and pyopencrg write, KRBI and KDBI (binary, single and
double precision) and LRFI and LDFI (text); long sections by number (``long section 3``, at
``long_section_v_right`` + (3 - 1) ``long_section_v_increment``) or by position
(``long section at v = 0.5``); the heading channel (``reference line phi``), which only moves
the road in x and y. Refused, with a message saying what is supported: other data formats,
include files (``$ROAD_CRG_FILE``), a reference line given by x/y or u channels, scaling
modifiers (``scale_*``: apply them and save the road first), a border mode in u other than
the default (2, keep the last value) or a border offset or smoothing in u, a lateral offset
outside the road's width, and a missing (NaN) height where the tire's track needs one.

The C API keeps the grid in single precision whatever the file's format; this reader keeps
what the file holds (double for KDBI and LDFI), so on those formats the two differ by up to
half a single-precision step of the height (6e-8 of it: 1.9e-9 m at 0.03 m); on KRBI and LRFI
they agree to rounding.

Beyond the extent
-----------------
Before the first cross section the road is level at the first height and after the last at
the last height: the C API's default border mode in u ("keep the last value"). A profile file
ends the same way. :attr:`RoadFile.extent_m` says where the file's road ends, so that an FMU
can say so when a wheel leaves it (never a silent zero).

Profiles
--------
Two numbers a line, distance (m) and height (m), separated by a comma and/or blanks; ``#``
starts a comment; an optional first line of two column names; distances strictly increasing.

Every refusal is a :class:`RoadFileError` (a :class:`~tire_fmu.file_checks.FileContentError`)
naming the file and what is wrong. Nothing a file holds sizes an allocation before it has been
checked against the limits below and against the file's own size. Writing goes through
:func:`tire_fmu.publish.published_file`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .core.obstacles import MAX_PROFILE_KNOTS, ProfileRoad
from .file_checks import FileContentError, read_text

SUPPORTED_CRG_FORMATS = ("KRBI", "KDBI", "LRFI", "LDFI")
#: The largest road file read (bytes).
MAX_ROAD_FILE_BYTES = 1 << 30
#: The most bytes an OpenCRG header (everything before its data) may take.
MAX_CRG_HEADER_BYTES = 1 << 20
#: The most cross sections (a profile's lines) read: the core's limit.
MAX_CROSS_SECTIONS = MAX_PROFILE_KNOTS
#: The most channels (``D:`` lines) of an OpenCRG file.
MAX_CRG_CHANNELS = 100_000
#: Heights and distances beyond these are no road (m).
MAX_ABS_HEIGHT_M = 1.0e4
MAX_ABS_DISTANCE_M = 1.0e7
#: The smallest spacing of cross sections and long sections (m): the C API's.
MIN_INCREMENT_M = 1.0e-6
#: A lateral offset this close to the road's edge is on it (m): the C API's tolerance.
V_BORDER_TOLERANCE_M = 1.0e-8
#: Header values the reader checks against each other agree within this (m).
HEADER_TOLERANCE_M = 1.0e-6
#: Characters a line of text data holds per value, and values a line, per precision.
_TEXT_FIELD = {"R": (10, 8), "D": (20, 4)}
_BINARY_TYPE = {"R": np.dtype(">f4"), "D": np.dtype(">f8")}
_RECORD_BYTES = 80


class RoadFileError(FileContentError):
    """A road file that cannot be used; the message names the file and what is wrong."""


@dataclass(frozen=True, eq=False)
class RoadFile:
    """A road file read: the road along it and what the file says about it."""

    road: ProfileRoad
    path: Path
    #: "KRBI", "KDBI", "LRFI", "LDFI" (OpenCRG) or "profile"
    data_format: str
    #: v of the long section read (m, OpenCRG; 0 for a profile)
    lateral_offset_m: float = 0.0
    #: what the OpenCRG modifiers added to every height (m)
    height_shift_m: float = 0.0
    #: the OpenCRG road's width (v of its right and left long sections, m), None for a profile
    width_m: tuple[float, float] | None = None

    @property
    def extent_m(self) -> tuple[float, float]:
        """(first, last) distance along the road the file covers (m): the road is level at the
        end heights beyond."""
        return self.road.extent_m

    def leaves_extent(self, s_lo: float, s_hi: float) -> bool:
        """Whether the stretch [s_lo, s_hi] reaches beyond the file's road."""
        first, last = self.extent_m
        return s_lo < first or s_hi > last


def read_road_file(path: str | Path, lateral_offset_m: float = 0.0) -> RoadFile:
    """The road in ``path``: an OpenCRG file (a ``.crg`` name, or a text starting with an
    OpenCRG block) read at ``lateral_offset_m``, else a two-column profile."""
    path = Path(path)
    _check_offset(path, lateral_offset_m)
    _file_size(path, max(MAX_ROAD_FILE_BYTES, MAX_PROFILE_FILE_BYTES))  # there, a file
    if path.suffix.lower() == ".crg" or _starts_like_crg(path):
        return read_crg(path, lateral_offset_m)
    if lateral_offset_m != 0.0:
        raise RoadFileError(f"{path}: a profile file has no width: the lateral offset "
                            f"{lateral_offset_m:g} m applies to OpenCRG files only (leave it 0)")
    return read_profile(path)


def _check_offset(path: Path, lateral_offset_m) -> None:
    if isinstance(lateral_offset_m, bool) or not isinstance(lateral_offset_m, (int, float)):
        raise RoadFileError(f"{path}: lateral offset {lateral_offset_m!r}: must be a finite "
                            "number (m)")
    if not math.isfinite(lateral_offset_m):
        raise RoadFileError(f"{path}: lateral offset {lateral_offset_m:g} m: must be a finite "
                            "number")


def _starts_like_crg(path: Path) -> bool:
    try:
        with path.open("rb") as stream:
            head = stream.read(256)
    except OSError:
        return False  # read_profile says why
    first = head.lstrip(b" \t\r\n")[:14].upper()
    return first.startswith((b"$CT", b"$ROAD_CRG", b"$KD_DEFINITION"))


# -- OpenCRG: the header -----------------------------------------------------------------------

_ROAD_KEYS = (
    "reference_line_start_u", "reference_line_start_x", "reference_line_start_y",
    "reference_line_start_z", "reference_line_start_phi", "reference_line_start_b",
    "reference_line_start_s", "reference_line_end_u", "reference_line_end_x",
    "reference_line_end_y", "reference_line_end_z", "reference_line_end_phi",
    "reference_line_end_b", "reference_line_end_s", "reference_line_increment",
    "long_section_v_right", "long_section_v_left", "long_section_v_increment",
    "reference_line_offset_x", "reference_line_offset_y", "reference_line_offset_z",
    "reference_line_offset_phi")
_OPTION_KEYS = (
    "border_mode_u", "border_offset_u", "border_mode_v", "border_offset_v",
    "border_smooth_ubeg", "border_smooth_uend", "refline_continuation", "refline_search_far",
    "refline_search_close", "refline_search_ufrac", "refline_search_u", "warn_msgs",
    "warn_curv_local", "warn_curv_global", "log_msgs", "log_eval_freq", "log_eval",
    "log_hist_freq", "log_hist", "log_stat_freq", "log_stat", "check_eps", "check_inc",
    "check_tol")
_MODIFIER_KEYS = (
    "scale_z_grid", "scale_slope", "scale_banking", "scale_length", "scale_width",
    "scale_curvature", "grid_nan_mode", "grid_nan_offset", "refline_rotcenter_x",
    "refline_rotcenter_y", "refline_offset_phi", "refline_offset_x", "refline_offset_y",
    "refline_offset_z", "refpoint_u_fraction", "refpoint_u_offset", "refpoint_u",
    "refpoint_v_fraction", "refpoint_v_offset", "refpoint_v", "refpoint_x", "refpoint_y",
    "refpoint_z", "refpoint_phi")
#: Modifiers that change the road's heights along u other than by a constant.
_SCALING = ("scale_z_grid", "scale_slope", "scale_banking", "scale_length", "scale_width")
_BY_REFPOINT = ("refpoint_u_fraction", "refpoint_u", "refpoint_v_fraction", "refpoint_v",
                "refpoint_x", "refpoint_y", "refpoint_z", "refpoint_phi")
_BY_OFFSET = ("refline_offset_phi", "refline_offset_x", "refline_offset_y", "refline_offset_z")
#: Block tags, tried in this order as the C API does (a longer tag before its prefix).
_TAGS = (("$ROAD_CRG_MODS", "mods"), ("$ROAD_CRG_OPTS", "opts"), ("$ROAD_CRG_FILE", "file"),
         ("$ROAD_CRG", "road"), ("$CT", "comment"), ("$KD_DEFINITION", "kd"),
         ("$$$$", "data"), ("$", None))
_NUMBER = re.compile(r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)")
_INTEGER = re.compile(r"\s*([+-]?\d+)")


@dataclass
class _Channel:
    kind: str  # "z", "slope", "bank", "phi"
    index: int  # its place in a record
    v_m: float = math.nan  # a long section's v (by position) or its number (by number)


@dataclass
class _Header:
    road: dict
    options: dict
    modifiers: dict | None  # None: no $ROAD_CRG_MODS block (OpenCRG's defaults apply)
    data_format: str
    channels: list
    data_offset: int
    by_number: bool


def _header_lines(head: bytes, complete: bool):
    """(line number, text, offset after the line) of the lines that end in ``head`` (the last
    one without a line end too when ``head`` is the whole file)."""
    start = 0
    number = 0
    while start < len(head):
        end = head.find(b"\n", start)
        if end < 0:
            if complete:
                yield number + 1, head[start:].rstrip(b"\r").decode("latin-1"), len(head)
            return
        number += 1
        yield number, head[start:end].rstrip(b"\r").decode("latin-1"), end + 1
        start = end + 1


def _value(path: Path, number: int, line: str, key: str, integer: bool = False) -> float:
    """The number after the '=' of ``line`` (C's atof/atoi: its leading number; text after it,
    a '!' comment, is not part of it)."""
    _, equals, text = line.partition("=")
    match = (_INTEGER if integer else _NUMBER).match(text) if equals else None
    if match is None:
        raise RoadFileError(f"{path}: line {number}: {key}: no number after '=' in "
                            f"{line.strip()!r}")
    value = float(match.group(1))
    if not math.isfinite(value):
        raise RoadFileError(f"{path}: line {number}: {key} = {match.group(1)}: not finite")
    return value


def _match(line: str, keys) -> str | None:
    lower = line.lstrip(" ").lower()
    return next((key for key in keys if lower.startswith(key)), None)


def _read_header(path: Path, head: bytes, complete: bool) -> _Header:
    """The header's blocks, as the OpenCRG loader reads them: a block starts with its tag in a
    line of its own and ends at the next line starting with '$'; the data follow the first
    line of '$$$$' outside a block. ``complete``: ``head`` is the whole file."""
    section = None
    road, options, modifiers = {}, {}, None
    data_format, channels, by_number = None, [], set()
    after_comment = None
    for number, line, offset in _header_lines(head, complete):
        if section == "comment":
            if line.startswith("$"):
                section = None
                if _tag(line) in ("mods", "opts", "file", "road", "comment", "kd"):
                    after_comment = (number, line.strip())
            continue
        stripped = line.lstrip(" ")
        if not stripped or stripped.startswith("*"):
            continue
        if section is None:
            tag = _tag(line)
            if tag == "data":
                return _checked_header(path, road, options, modifiers, data_format, channels,
                                       by_number, offset)
            if tag == "file":
                raise RoadFileError(f"{path}: line {number}: $ROAD_CRG_FILE (a road in "
                                    "several files) is not supported: give one file")
            if tag == "none":
                continue  # a line outside any block: the C API passes over it too
            if tag == "mods":
                modifiers = {}
            if tag == "opts":
                options = {}
            section = tag
            continue
        if stripped.startswith("$"):
            section = None
        elif section == "road":
            key = _match(line, _ROAD_KEYS)
            if key is not None:
                road[key] = _value(path, number, line, key)
        elif section == "opts":
            key = _match(line, _OPTION_KEYS)
            if key is not None:
                options[key] = _value(path, number, line, key, key.startswith("border_mode"))
        elif section == "mods":
            key = _match(line, _MODIFIER_KEYS)
            if key is not None:
                modifiers[key] = _value(path, number, line, key, key == "grid_nan_mode")
        elif section == "kd":
            if stripped.startswith("#:"):
                data_format = stripped[2:6].upper()
                if data_format not in SUPPORTED_CRG_FORMATS:
                    raise RoadFileError(
                        f"{path}: line {number}: data format {stripped[2:6]!r}: supported are "
                        "KRBI and KDBI (binary, single and double precision) and LRFI and "
                        "LDFI (text)")
            elif stripped[:2].upper() == "D:":
                if len(channels) >= MAX_CRG_CHANNELS:
                    raise RoadFileError(f"{path}: more than {MAX_CRG_CHANNELS} channels (D: "
                                        "lines)")
                channels.append(_channel(path, number, stripped[2:], len(channels), by_number))
    where = ("in the file" if complete else f"in its first {MAX_CRG_HEADER_BYTES} bytes")
    hint = (f" (line {after_comment[0]}, {after_comment[1]!r}, only ends the $CT block before "
            "it: the OpenCRG loader needs a line '$' between)" if after_comment else "")
    raise RoadFileError(f"{path}: not an OpenCRG file: no data section (a line of '$$$$' after "
                        f"the closed $ROAD_CRG and $KD_DEFINITION blocks) {where}{hint}")


def _tag(line: str) -> str | None:
    upper = line.lstrip(" ").upper()
    for tag, name in _TAGS:
        if upper.startswith(tag):
            return name
    return "none"


def _channel(path: Path, number: int, text: str, index: int, by_number: set) -> _Channel:
    definition = text.split("!", 1)[0]
    name, _, unit = definition.partition(",")
    name, unit = " ".join(name.split()).lower(), unit.strip().lower()
    if name.startswith("long section"):
        rest = name[len("long section"):].strip()
        if not unit.startswith("m"):
            raise RoadFileError(f"{path}: line {number}: long section {rest!r}: its unit "
                                f"must be m, not {unit!r}")
        if rest.startswith("at v"):
            _, equals, position = rest.partition("=")
            match = _NUMBER.match(position) if equals else None
            if match is None or not math.isfinite(float(match.group(1))):
                raise RoadFileError(f"{path}: line {number}: 'long section {rest}': no "
                                    "position after 'at v ='")
            by_number.add(False)
            return _Channel("z", index, float(match.group(1)))
        match = _NUMBER.match(rest)
        if match is None or not float(match.group(1)).is_integer():
            raise RoadFileError(f"{path}: line {number}: 'long section {rest}': a long "
                                "section is 'long section N' or 'long section at v = V'")
        by_number.add(True)
        return _Channel("z", index, float(match.group(1)))
    if name.startswith("reference line"):
        what = name[len("reference line"):].strip()
        units = {"slope": "m/m", "banking": "m/m", "phi": "rad"}
        if what in units:
            if not unit.startswith(units[what]):
                raise RoadFileError(f"{path}: line {number}: reference line {what}: its "
                                    f"unit must be {units[what]}, not {unit!r}")
            return _Channel({"banking": "bank"}.get(what, what), index)
        if what in ("x", "y", "u"):
            raise RoadFileError(f"{path}: line {number}: a reference line given by its {what} "
                                "values is not supported: u runs from reference_line_start_u "
                                "by reference_line_increment (a heading channel, 'reference "
                                "line phi', may bend it)")
    raise RoadFileError(f"{path}: line {number}: channel {definition.strip()!r}: not an "
                        "OpenCRG channel read here (long section N, long section at v = V, "
                        "reference line slope, banking or phi)")


def _checked_header(path, road, options, modifiers, data_format, channels, by_number,
                    offset) -> _Header:
    if data_format is None:
        raise RoadFileError(f"{path}: no data format in $KD_DEFINITION (a line #:KRBI, #:KDBI, "
                            "#:LRFI or #:LDFI)")
    if len(by_number) > 1:
        raise RoadFileError(f"{path}: long sections given both by number and by position "
                            "(at v =): use one way")
    if sum(c.kind == "z" for c in channels) < 2:
        raise RoadFileError(f"{path}: fewer than 2 long sections (D:long section ... lines): "
                            "no road to interpolate")
    for kind in ("slope", "bank", "phi"):
        if sum(c.kind == kind for c in channels) > 1:
            raise RoadFileError(f"{path}: more than one reference line {kind} channel")
    increment = road.get("reference_line_increment")
    if increment is None:
        raise RoadFileError(f"{path}: no reference_line_increment in $ROAD_CRG (the spacing "
                            "of the cross sections along u)")
    if not MIN_INCREMENT_M <= increment <= 1e3:
        raise RoadFileError(f"{path}: reference_line_increment = {increment:g} m: must be in "
                            f"[{MIN_INCREMENT_M:g}, 1000] m")
    mode = options.get("border_mode_u", 2)
    if mode != 2:
        raise RoadFileError(f"{path}: border_mode_u = {mode:g}: only 2 (keep the last height "
                            "beyond the road's ends, the default) is supported")
    for key in ("border_offset_u", "border_smooth_ubeg", "border_smooth_uend"):
        if options.get(key, 0.0) != 0.0:
            raise RoadFileError(f"{path}: {key} = {options[key]:g}: not supported (the road "
                                "is level at its end heights beyond its ends)")
    if modifiers is not None:
        scaling = [key for key in _SCALING if key in modifiers]
        if scaling:
            raise RoadFileError(f"{path}: modifier {', '.join(scaling)}: scaling modifiers are "
                                "not supported: apply them and save the road first (pyopencrg: "
                                "road.apply_mods(), then road.save(...))")
        if any(k in modifiers for k in _BY_REFPOINT) and any(k in modifiers for k in _BY_OFFSET):
            raise RoadFileError(f"{path}: modifiers refpoint_* and refline_offset_* together: "
                                "the OpenCRG C API refuses them, give one kind")
        for a, b in (("refpoint_u", "refpoint_u_fraction"), ("refpoint_v", "refpoint_v_fraction")):
            if a in modifiers and b in modifiers:
                raise RoadFileError(f"{path}: modifiers {a} and {b} together: give one")
    return _Header(road, options, modifiers, data_format, channels, offset, True in by_number)


# -- OpenCRG: the data -------------------------------------------------------------------------

class _Grid:
    """The data's columns (channels), read or parsed one at a time."""

    def __init__(self, path: Path, header: _Header, file_bytes: int):
        self.path, self.header = path, header
        width = len(header.channels)
        precision = header.data_format[1]
        self.binary = header.data_format[2] == "B"
        self._cache = {}
        available = file_bytes - header.data_offset
        increment = header.road["reference_line_increment"]
        start = header.road.get("reference_line_start_u", 0.0)
        if self.binary:
            end = header.road.get("reference_line_end_u")
            if end is None:
                raise RoadFileError(f"{path}: no reference_line_end_u in $ROAD_CRG: a binary "
                                    "file's cross sections are counted from it")
            count = (end - start) / increment + 0.5
            if not 1.0 <= count < MAX_CROSS_SECTIONS:
                raise RoadFileError(
                    f"{path}: reference_line_start_u = {start:g}, end_u = {end:g} by "
                    f"{increment:g} m: {count - 0.5:.6g} increments; must make 2 to "
                    f"{MAX_CROSS_SECTIONS} cross sections")
            self.rows = int(count) + 1
            dtype = _BINARY_TYPE[precision]
            record = width * dtype.itemsize
            needed = self.rows * record
            if available < needed:
                raise RoadFileError(
                    f"{path}: truncated: the header declares {self.rows} cross sections of "
                    f"{width} {header.data_format} values ({needed} bytes of data), the file "
                    f"holds {max(available, 0)} bytes ({max(available, 0) // record} cross "
                    "sections)")
            if available - needed >= _RECORD_BYTES:
                raise RoadFileError(
                    f"{path}: {available - needed} bytes of data beyond the {self.rows} cross "
                    "sections reference_line_start_u, end_u and increment declare (at most "
                    f"{_RECORD_BYTES - 1} bytes of padding): the header does not match the data")
            self._table = np.memmap(path, dtype=dtype, mode="r", offset=header.data_offset,
                                    shape=(self.rows, width))
        else:
            self._parse_text(available, width, precision)
            end = header.road.get("reference_line_end_u")
            last = start + (self.rows - 1) * increment
            if end is not None and abs(end - last) > 0.5 * increment:
                raise RoadFileError(
                    f"{path}: the data hold {self.rows} cross sections, to u = {last:g} m, "
                    f"but reference_line_end_u = {end:g} m: truncated, or the header is wrong")
        self.start_u, self.increment = start, increment
        if abs(start) > MAX_ABS_DISTANCE_M or abs(start + (self.rows - 1) * increment) \
                > MAX_ABS_DISTANCE_M:
            raise RoadFileError(f"{path}: u from {start:g} m over {self.rows} cross sections: "
                                f"beyond {MAX_ABS_DISTANCE_M:g} m")

    def _parse_text(self, available: int, width: int, precision: str) -> None:
        path = self.path
        chars, per_line = _TEXT_FIELD[precision]
        lines_per_record = -(-width // per_line)
        with path.open("rb") as stream:
            stream.seek(self.header.data_offset)
            text = stream.read(available).decode("latin-1")
        # blank lines between records are skipped, as the C API skips line ends
        lines = [line for line in (raw.rstrip("\r") for raw in text.split("\n")) if line]
        if len(lines) > MAX_CROSS_SECTIONS * lines_per_record:
            raise RoadFileError(f"{path}: more than {MAX_CROSS_SECTIONS} cross sections")
        rows, rest = divmod(len(lines), lines_per_record)
        records = ["".join(lines[k:k + lines_per_record])
                   for k in range(0, rows * lines_per_record, lines_per_record)]
        needed = width * chars
        short = next((k for k, r in enumerate(records) if len(r) < needed), None)
        if short is not None:
            raise RoadFileError(
                f"{path}: cross section {short + 1} holds {len(records[short])} characters: "
                f"{width} values of {chars} characters need {needed} (truncated or not "
                f"{self.header.data_format})")
        if rest:
            raise RoadFileError(
                f"{path}: truncated: the last cross section has {rest} of its "
                f"{lines_per_record} lines ({width} values of {chars} characters, {per_line} "
                "a line)")
        if rows < 2:
            raise RoadFileError(f"{path}: {rows} cross sections of data: a road needs 2")
        self.rows, self._records, self._chars = rows, records, chars

    def column(self, index: int) -> np.ndarray:
        """The values of channel ``index`` at every cross section (NaN where the file has
        none)."""
        if index not in self._cache:
            if self.binary:
                with np.errstate(invalid="ignore"):  # NaN placeholders stay NaN
                    values = np.array(self._table[:, index], dtype=float)
            else:
                c, w = index * self._chars, (index + 1) * self._chars
                values = np.array([_text_value(r[c:w]) for r in self._records], dtype=float)
            self._cache[index] = values
        return self._cache[index]

    def close(self) -> None:
        self._table = None


_TEXT_NUMBER = re.compile(r"[0-9+\-.eEdD ]*")


def _text_value(field: str) -> float:
    """A text field as the C API reads it: digits, signs, points, exponents and blanks are its
    number (C's atof: the leading number, 0 when none); "**unused**" is 0; anything else (a
    placeholder starting with '*') is no value (NaN)."""
    if _TEXT_NUMBER.fullmatch(field):
        try:
            return float(field)
        except ValueError:
            match = _NUMBER.match(field)
            return float(match.group(1)) if match else 0.0
    return 0.0 if field == "**unused**" else math.nan


def _v_positions(path: Path, header: _Header) -> tuple[np.ndarray, np.ndarray]:
    """(v of each long section, right to left; the channel index of each)."""
    z = [c for c in header.channels if c.kind == "z"]
    if header.by_number:
        numbers = sorted(int(c.v_m) for c in z)
        if numbers != list(range(1, len(z) + 1)):
            raise RoadFileError(f"{path}: long sections numbered other than 1 to {len(z)}, "
                                "each once")
        increment = header.road.get("long_section_v_increment")
        if increment is None:
            raise RoadFileError(f"{path}: long sections by number need "
                                "long_section_v_increment in $ROAD_CRG")
        if not MIN_INCREMENT_M <= increment <= 1e3:
            raise RoadFileError(f"{path}: long_section_v_increment = {increment:g} m: must be "
                                f"in [{MIN_INCREMENT_M:g}, 1000] m")
        right = header.road.get("long_section_v_right", 0.0)
        ordered = sorted(z, key=lambda c: c.v_m)
        v = right + increment * np.arange(len(z))
    else:
        ordered = sorted(z, key=lambda c: c.v_m)
        v = np.array([c.v_m for c in ordered])
        if np.any(np.diff(v) < MIN_INCREMENT_M):
            k = int(np.argmin(np.diff(v)))
            raise RoadFileError(f"{path}: long sections at v = {v[k]:g} and {v[k + 1]:g} m: "
                                f"closer than {MIN_INCREMENT_M:g} m")
    for key, value in (("long_section_v_right", v[0]), ("long_section_v_left", v[-1])):
        given = header.road.get(key)
        if given is not None and abs(given - value) > HEADER_TOLERANCE_M:
            raise RoadFileError(f"{path}: {key} = {given:g} m, but the long sections' "
                                f"{'right' if key.endswith('right') else 'left'} edge is at "
                                f"v = {value:g} m")
    if np.max(np.abs(v)) > MAX_ABS_DISTANCE_M:
        raise RoadFileError(f"{path}: long sections beyond {MAX_ABS_DISTANCE_M:g} m")
    return v, np.array([c.index for c in ordered])


def _bank_bounds(header: _Header, v: np.ndarray) -> tuple[float, float]:
    """The v range the C API clamps v to for the banking (its channelV first and last)."""
    road = header.road
    if header.by_number:
        first = road.get("long_section_v_right", 0.0)
    else:
        spacing = np.diff(v)
        uniform = (spacing.max() - spacing.min()) / spacing.min() < 1e-3
        first = v[0] if uniform else road.get("long_section_v_right", 0.0)
    return first, road.get("long_section_v_left", 0.0)


def _weights(header: _Header, v_positions: np.ndarray, v: float) -> tuple[int, float]:
    """(j, f): the C API reads v between long sections j and j + 1 at fraction f, the heights
    beyond the road's edges kept (f clipped to [0, 1])."""
    n = v_positions.size
    if header.by_number:
        increment = header.road["long_section_v_increment"]
        fraction = (v - v_positions[0]) / increment
        if fraction < 0.0:
            return 0, 0.0
        j = int(fraction)
        if j >= n - 1:
            return n - 2, 1.0
        return j, fraction - j
    j = int(np.clip(np.searchsorted(v_positions, v, side="right") - 1, 0, n - 2))
    fraction = (v - v_positions[j]) / (v_positions[j + 1] - v_positions[j])
    return j, min(max(fraction, 0.0), 1.0)


def _section_heights(path: Path, grid: _Grid, columns: np.ndarray, j: int, f: float,
                     v: float, what: str) -> np.ndarray:
    """The grid's heights at each cross section between long sections j and j + 1 at
    fraction f, as the C API interpolates them (z_j + f (z_j+1 - z_j)); every height the
    interpolation weighs must be there."""
    near, far = grid.column(int(columns[j])), grid.column(int(columns[j + 1]))
    needed = [(near, j)] if f == 0.0 else [(far, j + 1)] if f == 1.0 else \
        [(near, j), (far, j + 1)]
    for values, k in needed:
        bad = ~np.isfinite(values)
        if bad.any():
            row = int(np.argmax(bad))
            raise RoadFileError(
                f"{path}: no height (NaN) in long section {k + 1} at u = "
                f"{grid.start_u + row * grid.increment:g} m (cross section {row + 1}), "
                f"which {what} at v = {v:g} m reads")
        if np.max(np.abs(values)) > MAX_ABS_HEIGHT_M:
            row = int(np.argmax(np.abs(values) > MAX_ABS_HEIGHT_M))
            raise RoadFileError(
                f"{path}: height {values[row]:.6g} m in long section {k + 1} at u = "
                f"{grid.start_u + row * grid.increment:g} m (cross section {row + 1}), which "
                f"{what} at v = {v:g} m reads: beyond {MAX_ABS_HEIGHT_M:g} m, no road (a "
                "damaged file?)")
    if f == 0.0:
        return near.copy()
    if f == 1.0:
        return far.copy()
    return near + f * (far - near)


def _reference_line(path: Path, header: _Header, grid: _Grid) -> np.ndarray:
    """The reference line's height at each cross section (the C API's calcRefLineZ)."""
    road = header.road
    n, increment = grid.rows, grid.increment
    channel = next((c for c in header.channels if c.kind == "slope"), None)
    start_slope = road.get("reference_line_start_s", 0.0)
    start_z = road.get("reference_line_start_z", 0.0)
    if channel is None and start_slope == 0.0:
        return np.full(n, start_z)
    slope = grid.column(channel.index).copy() if channel else np.full(n, start_slope)
    if not np.all(np.isfinite(slope[1:])):  # the first slope is never used
        row = 1 + int(np.argmax(~np.isfinite(slope[1:])))
        raise RoadFileError(f"{path}: no reference line slope (NaN) at cross section "
                            f"{row + 1}")
    height = np.empty(n)
    if "reference_line_end_z" not in road:
        height[0] = start_z
        for k in range(n - 1):  # one step at a time, as the C API rounds
            height[k + 1] = height[k] + slope[k + 1] * increment
        return height
    # backward from the end height, then forward, each blended towards the other
    height[n - 1] = road["reference_line_end_z"]
    for k in range(n - 1, 0, -1):
        height[k - 1] = height[k] - slope[k] * increment
    height[0] = start_z
    for k in range(n - 2):
        fraction = k / (n - 1)
        height[k + 1] = ((1.0 - fraction) * (height[k] + slope[k + 1] * increment)
                         + fraction * height[k + 1])
    return height


def _banking(path: Path, header: _Header, grid: _Grid, v_positions: np.ndarray
             ) -> np.ndarray | None:
    """The banking (cross slope, m/m) at each cross section, or None without any."""
    road = header.road
    channel = next((c for c in header.channels if c.kind == "bank"), None)
    if channel is None and road.get("reference_line_start_b", 0.0) == 0.0 \
            and road.get("reference_line_end_b", 0.0) == 0.0:
        return None
    first, last = _bank_bounds(header, v_positions)
    if abs(first - v_positions[0]) > HEADER_TOLERANCE_M \
            or abs(last - v_positions[-1]) > HEADER_TOLERANCE_M:
        raise RoadFileError(
            f"{path}: a banked road needs long_section_v_right and long_section_v_left at its "
            f"outer long sections (v = {v_positions[0]:g} and {v_positions[-1]:g} m): the "
            "OpenCRG C API clamps v to them for the banking")
    if channel is None:
        return np.full(grid.rows, road.get("reference_line_start_b", 0.0))
    bank = grid.column(channel.index)
    if not np.all(np.isfinite(bank)):
        row = int(np.argmax(~np.isfinite(bank)))
        raise RoadFileError(f"{path}: no banking (NaN) at cross section {row + 1}")
    return bank


def _row_heights(path, header, grid, v_positions, columns, reference, bank, v, what):
    """The road's heights at each cross section at lateral position v."""
    j, f = _weights(header, v_positions, v)
    heights = _section_heights(path, grid, columns, j, f, v, what) + reference
    if bank is not None:
        heights = heights + bank * min(max(v, v_positions[0]), v_positions[-1])
    return heights


def _height_shift(path, header, grid, v_positions, columns, reference, bank) -> float:
    """What the file's modifiers (or OpenCRG's defaults) add to every height."""
    mods = header.modifiers
    first = grid.start_u
    last = first + (grid.rows - 1) * grid.increment
    if mods is None:  # OpenCRG's defaults: the start of the reference line to z = 0
        mods = {"refpoint_z": 0.0}
    if any(key in mods for key in _BY_REFPOINT):
        if "refpoint_u" in mods:
            u = mods["refpoint_u"]
        else:
            u = first + mods.get("refpoint_u_fraction", 0.0) * (last - first) \
                + mods.get("refpoint_u_offset", 0.0)
        if "refpoint_v" in mods:
            v = mods["refpoint_v"]
        elif "refpoint_v_fraction" in mods:
            v = v_positions[0] + mods["refpoint_v_fraction"] * (v_positions[-1] - v_positions[0]) \
                + mods.get("refpoint_v_offset", 0.0)
        else:
            v = 0.0
        heights = _row_heights(path, header, grid, v_positions, columns, reference, bank, v,
                               "the reference point (refpoint, OpenCRG's default: the start "
                               "of the reference line)")
        return mods.get("refpoint_z", 0.0) - _at_u(heights, first, grid.increment, u)
    if any(key in mods for key in _BY_OFFSET):
        return mods.get("refline_offset_z", 0.0)
    return 0.0


def _at_u(heights: np.ndarray, first: float, increment: float, u: float) -> float:
    """The C API's linear interpolation in u, the end heights kept beyond the ends."""
    n = heights.size
    fraction = (u - first) / increment
    if fraction <= 0.0:
        return float(heights[0])
    k = int(fraction)
    if k >= n - 1:
        return float(heights[-1])
    fraction -= k
    return float(heights[k] + fraction * (heights[k + 1] - heights[k]))


def read_crg(path: str | Path, lateral_offset_m: float = 0.0) -> RoadFile:
    """The road of the OpenCRG file ``path`` along its reference line at lateral offset
    ``lateral_offset_m`` (m, left positive)."""
    path = Path(path)
    _check_offset(path, lateral_offset_m)
    file_bytes = _file_size(path, MAX_ROAD_FILE_BYTES)
    with path.open("rb") as stream:
        head = stream.read(MAX_CRG_HEADER_BYTES)
    header = _read_header(path, head, complete=len(head) == file_bytes)
    v_positions, columns = _v_positions(path, header)
    if not (v_positions[0] - V_BORDER_TOLERANCE_M <= lateral_offset_m
            <= v_positions[-1] + V_BORDER_TOLERANCE_M):
        raise RoadFileError(f"{path}: lateral offset {lateral_offset_m:g} m: outside the "
                            f"road's width, v from {v_positions[0]:g} to {v_positions[-1]:g} m")
    v = min(max(float(lateral_offset_m), v_positions[0]), v_positions[-1])
    grid = _Grid(path, header, file_bytes)
    try:
        reference = _reference_line(path, header, grid)
        bank = _banking(path, header, grid, v_positions)
        heights = _row_heights(path, header, grid, v_positions, columns, reference, bank, v,
                               "the tire's track")
        shift = _height_shift(path, header, grid, v_positions, columns, reference, bank)
    finally:
        grid.close()
    heights = heights + shift
    if not np.all(np.abs(heights) <= MAX_ABS_HEIGHT_M):
        raise RoadFileError(f"{path}: heights beyond {MAX_ABS_HEIGHT_M:g} m along v = {v:g} m")
    distances = grid.start_u + grid.increment * np.arange(grid.rows)
    road = ProfileRoad(distances, heights, f"{path.name} at v = {v:g} m")
    return RoadFile(road, path, header.data_format, v, shift,
                    (float(v_positions[0]), float(v_positions[-1])))


def _file_size(path: Path, limit: int) -> int:
    """The size of the file ``path`` once it is known to be a readable file within
    ``limit``."""
    if path.is_dir():
        raise RoadFileError(f"{path}: is a folder, not a road file")
    try:
        size = path.stat().st_size
        with path.open("rb"):
            pass
    except OSError as cause:
        raise RoadFileError(f"{path}: cannot be read: {cause.strerror or cause}") from cause
    if size > limit:
        raise RoadFileError(f"{path}: {size} bytes: more than the {limit} bytes a road file "
                            "may hold")
    return size


# -- profiles ----------------------------------------------------------------------------------

#: The largest profile file read (bytes): 10 million lines of two numbers.
MAX_PROFILE_FILE_BYTES = 1 << 29
_SEPARATOR = re.compile(r"[,\s]+")


def read_profile(path: str | Path) -> RoadFile:
    """The two-column profile (distance m, height m) in ``path``."""
    path = Path(path)
    _file_size(path, MAX_PROFILE_FILE_BYTES)
    text = read_text(path, MAX_PROFILE_FILE_BYTES, "a road profile", RoadFileError)
    distances, heights, lines = [], [], []
    header_allowed = True
    for number, line in enumerate(text.splitlines(), 1):
        content = line.split("#", 1)[0].strip()
        if not content:
            continue
        fields = [f for f in _SEPARATOR.split(content) if f]
        if len(fields) != 2:
            raise RoadFileError(f"{path}: line {number}: {len(fields)} values in "
                                f"{content[:60]!r}: a profile line holds two, distance (m) and "
                                "height (m)")
        try:
            distance, height = float(fields[0]), float(fields[1])
        except ValueError:
            if header_allowed and not any(_is_number(f) for f in fields):
                header_allowed = False
                continue  # a line of column names
            raise RoadFileError(f"{path}: line {number}: {content[:60]!r}: not two numbers "
                                "(distance m, height m)") from None
        header_allowed = False
        if not (math.isfinite(distance) and math.isfinite(height)):
            raise RoadFileError(f"{path}: line {number}: {content[:60]!r}: distance and height "
                                "must be finite")
        if abs(distance) > MAX_ABS_DISTANCE_M or abs(height) > MAX_ABS_HEIGHT_M:
            raise RoadFileError(f"{path}: line {number}: {content[:60]!r}: beyond "
                                f"{MAX_ABS_DISTANCE_M:g} m along or {MAX_ABS_HEIGHT_M:g} m high")
        if distances and distance <= distances[-1]:
            raise RoadFileError(f"{path}: line {number}: distance {distance:.15g} m after "
                                f"{distances[-1]:.15g} m (line {lines[-1]}): distances must "
                                "strictly increase")
        if len(distances) >= MAX_CROSS_SECTIONS:
            raise RoadFileError(f"{path}: more than {MAX_CROSS_SECTIONS} points")
        distances.append(distance)
        heights.append(height)
        lines.append(number)
    if len(distances) < 2:
        raise RoadFileError(f"{path}: {len(distances)} points: a road profile needs at least "
                            "2 lines of distance (m) and height (m)")
    road = ProfileRoad(np.array(distances), np.array(heights), path.name)
    return RoadFile(road, path, "profile")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


# -- writing -----------------------------------------------------------------------------------

def profile_text(distances_m, heights_m, comments=()) -> str:
    """A profile file's text: ``# comments``, a line of column names, then one line per point
    with the numbers as Python writes them (``repr``: they read back to the same doubles)."""
    lines = [f"# {line}" for text in comments for line in str(text).splitlines()]
    lines.append("distance_m,height_m")
    lines += [f"{float(s)!r},{float(z)!r}" for s, z in zip(distances_m, heights_m)]
    return "\n".join(lines) + "\n"


def write_profile(path: str | Path, distances_m, heights_m, comments=()) -> Path:
    """Write a profile file (checked as the reader checks it, then published whole)."""
    from .publish import published_file  # the writers only: the FMUs ship the readers

    path = Path(path)
    ProfileRoad(np.asarray(distances_m, float), np.asarray(heights_m, float))  # refuses a bad one
    with published_file(path) as partial:
        partial.write_text(profile_text(distances_m, heights_m, comments), encoding="utf-8")
    return path


def crg_bytes(heights_m, increment_m: float, v_m, data_format: str = "KDBI",
              start_u_m: float = 0.0, comments=()) -> bytes:
    """An OpenCRG file's bytes: ``heights_m`` (cross sections x long sections) every
    ``increment_m`` along a straight reference line from ``start_u_m``, at the evenly spaced
    ``v_m`` (right to left), long sections by number, in ``data_format``."""
    z = np.asarray(heights_m, dtype=float)
    v = np.asarray(v_m, dtype=float)
    if data_format not in SUPPORTED_CRG_FORMATS:
        raise ValueError(f"data format {data_format!r}: one of {SUPPORTED_CRG_FORMATS}")
    if z.ndim != 2 or z.shape[1] != v.size or v.size < 2 or z.shape[0] < 2:
        raise ValueError(f"heights of shape {z.shape} for {v.size} long sections")
    v_increment = (v[-1] - v[0]) / (v.size - 1)
    if not np.allclose(np.diff(v), v_increment, rtol=0, atol=1e-12):
        raise ValueError("long sections must be evenly spaced")
    rows, columns = z.shape
    end_u = start_u_m + (rows - 1) * increment_m

    def key(name, value):
        return f"{name:<25}= {float(value):.17e}"

    lines = ["$CT"]
    lines += [line[:72] for text in comments for line in str(text).splitlines()]
    lines += ["$", "$ROAD_CRG",
              key("reference_line_start_u", start_u_m), key("reference_line_end_u", end_u),
              key("reference_line_increment", increment_m),
              key("long_section_v_right", v[0]), key("long_section_v_left", v[-1]),
              key("long_section_v_increment", v_increment), "$",
              # an empty block: no modifiers, so every OpenCRG reader takes the heights as
              # written (without one, OpenCRG's defaults would move the start to height 0)
              "$ROAD_CRG_MODS", "$",
              "$KD_DEFINITION", f"#:{data_format}",
              f"U:reference line u,m,{start_u_m:.17g},{increment_m:.17g}"]
    lines += [f"D:long section {k + 1},m" for k in range(columns)]
    lines += ["$", "$" * 72]
    head = ("\n".join(lines) + "\n").encode("latin-1")
    precision = data_format[1]
    if data_format[2] == "B":
        data = z.astype(_BINARY_TYPE[precision]).tobytes()
        pad = (-len(data)) % _RECORD_BYTES  # the kernel format fills its last record with NaN
        filler = np.full(pad // _BINARY_TYPE[precision].itemsize, np.nan,
                         _BINARY_TYPE[precision]).tobytes()
        return head + data + filler
    chars, per_line = _TEXT_FIELD[precision]
    out = []
    for row in z:
        fields = [_text_field(value, chars) for value in row]
        out += ["".join(fields[k:k + per_line]) for k in range(0, columns, per_line)]
    return head + ("\n".join(out) + "\n").encode("latin-1")


def _text_field(value: float, chars: int) -> str:
    """``value`` in ``chars`` characters with as many digits as fit (fixed point, or an
    exponent for large and small numbers)."""
    if not math.isfinite(value):
        return "*" * chars
    best, error = None, math.inf
    for digits in range(chars - 1, -1, -1):
        text = f"{value:.{digits}f}"
        if text.startswith(("0.", "-0.")):  # ".0123" is a number too: one digit more
            text = text.replace("0.", ".", 1)
        if len(text) <= chars:
            best, error = text.rjust(chars), abs(float(text) - value)
            break
    for digits in range(chars - 6, -1, -1):
        text = f"{value:{chars}.{digits}e}"
        if len(text) <= chars:
            if abs(float(text) - value) < error:
                best = text
            break
    return best


def write_crg(path: str | Path, heights_m, increment_m: float, v_m,
              data_format: str = "KDBI", start_u_m: float = 0.0, comments=()) -> Path:
    """Write an OpenCRG file (:func:`crg_bytes`), published whole."""
    from .publish import published_file

    path = Path(path)
    data = crg_bytes(heights_m, increment_m, v_m, data_format, start_u_m, comments)
    with published_file(path) as partial:
        partial.write_bytes(data)
    return path


#: The long sections a road written here has across its width (the same heights on each: an
#: obstacle across the whole road, a random road correlated across it).
WRITTEN_LONG_SECTIONS = 3


def write_road(path: str | Path, road: ProfileRoad, data_format: str = "KDBI",
               width_m: float = 1.0, comments=()) -> Path:
    """Write ``road`` to ``path``: an OpenCRG file in ``data_format`` for a ``.crg`` name
    (the road's knots evenly spaced, the same heights on long sections across ``width_m``),
    else a profile file."""
    path = Path(path)
    distances, heights = road.distances_m, road.heights_m
    if path.suffix.lower() != ".crg":
        return write_profile(path, distances, heights, comments)
    spacing = (distances[-1] - distances[0]) / (distances.size - 1)
    if not np.allclose(np.diff(distances), spacing, rtol=1e-9, atol=0.0):
        raise ValueError("an OpenCRG road needs evenly spaced points")
    v = np.linspace(-0.5 * width_m, 0.5 * width_m, WRITTEN_LONG_SECTIONS)
    grid = np.repeat(heights[:, None], v.size, axis=1)
    return write_crg(path, grid, spacing, v, data_format, float(distances[0]), comments)
