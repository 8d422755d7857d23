"""Tables of measured natural frequencies (CSV) for ``tire-fmu fit``.

One mode per row, a header naming the columns (any order, case-insensitive)::

    # GL073A, analytic table of the paper (Hz)
    order,branch,frequency_hz,weight,damping_ratio
    0,in,53.41,,
    0,out,184.20,2,0.021

``order`` (circumferential order n >= 0), ``branch`` (``in`` / ``out``, also ``in-phase`` /
``out-of-phase``) and ``frequency_hz`` are required; ``weight`` (default 1) and
``damping_ratio`` (empty = not measured) are optional. Lines starting with ``#`` and blank lines
are skipped. Every problem is reported at once, naming the row (data rows counted from 1), the
file line and the column.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from .core.fit import MeasuredMode
from .core.parameters import MAX_ELEMENTS
from .file_checks import FileContentError, read_text

REQUIRED_COLUMNS = ("order", "branch", "frequency_hz")
OPTIONAL_COLUMNS = ("weight", "damping_ratio")
BRANCH_NAMES = {"in": "in", "in-phase": "in", "in_phase": "in",
                "out": "out", "out-of-phase": "out", "out_of_phase": "out"}
#: The largest table read (bytes): one line per mode, a few hundred modes at most.
MAX_TABLE_BYTES = 1 << 20
#: The highest order a table may give: the highest any mesh resolves (N / 2 at the finest N).
MAX_ORDER = MAX_ELEMENTS // 2


class MeasurementError(FileContentError):
    """A table of measured modes that cannot be used; ``problems`` lists every one."""

    def __init__(self, source: str, problems: list[str]):
        self.problems = list(problems)
        count = "" if len(problems) == 1 else f"{len(problems)} problems: "
        super().__init__(f"{source}: {count}" + "; ".join(problems))


def read_modes(path: str | Path) -> list[MeasuredMode]:
    """The measured modes of a CSV file (see the module docstring for the format)."""
    path = Path(path)
    try:
        text = read_text(path, MAX_TABLE_BYTES, "a table of measured modes")
    except FileContentError as error:  # the message names the file already
        raise MeasurementError(str(path), [str(error).removeprefix(f"{path}: ")]) from error
    return parse_modes(text, str(path))


def parse_modes(text: str, source: str = "table") -> list[MeasuredMode]:
    lines = [(number, line) for number, line in enumerate(text.splitlines(), 1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise MeasurementError(source, ["no header and no rows (expected columns "
                                        f"{', '.join(REQUIRED_COLUMNS + OPTIONAL_COLUMNS)})"])
    try:
        rows = list(csv.reader(io.StringIO("\n".join(line for _, line in lines))))
    except csv.Error as error:  # a field beyond csv's limit, a NUL byte
        raise MeasurementError(source, [f"not a CSV table ({error})"]) from error
    header = [cell.strip().lower() for cell in rows[0]]
    problems = []
    known = REQUIRED_COLUMNS + OPTIONAL_COLUMNS
    for column in header:
        if column not in known:
            problems.append(f"header (line {lines[0][0]}): unknown column {column!r}; "
                            f"known: {', '.join(known)}")
    for column in REQUIRED_COLUMNS:
        if column not in header:
            problems.append(f"header (line {lines[0][0]}): required column {column!r} missing")
    if len(set(header)) != len(header):
        problems.append(f"header (line {lines[0][0]}): a column is named twice")
    if problems:
        raise MeasurementError(source, problems)
    modes = []
    for index, (cells, (line, _)) in enumerate(zip(rows[1:], lines[1:]), 1):
        where = f"row {index} (line {line})"
        if len(cells) != len(header):
            problems.append(f"{where}: {len(cells)} values for {len(header)} columns")
            continue
        cell = {name: value.strip() for name, value in zip(header, cells)}
        found = []
        order = _integer(cell["order"], f"{where}, column 'order'", found)
        branch = BRANCH_NAMES.get(cell["branch"].lower())
        if branch is None:
            found.append(f"{where}, column 'branch': {cell['branch']!r} must be in or out "
                         "(in-phase / out-of-phase)")
        frequency = _number(cell["frequency_hz"], f"{where}, column 'frequency_hz'", found,
                            "a frequency in Hz > 0", positive=True)
        weight = 1.0
        if cell.get("weight"):
            weight = _number(cell["weight"], f"{where}, column 'weight'", found,
                             "a weight > 0", positive=True)
        damping = None
        if cell.get("damping_ratio"):
            damping = _number(cell["damping_ratio"], f"{where}, column 'damping_ratio'", found,
                              "a damping ratio in (0, 1)", positive=True)
            if damping is not None and not damping < 1.0:
                found.append(f"{where}, column 'damping_ratio': {cell['damping_ratio']!r} "
                             "must be a damping ratio in (0, 1)")
        problems += found
        if not found:
            modes.append(MeasuredMode(order, branch, frequency, weight, damping, label=where))
    if not rows[1:]:
        problems.append("no data rows under the header")
    seen: dict[tuple[int, str], str] = {}
    for mode in modes:
        key = (mode.order, mode.branch)
        if key in seen:
            problems.append(f"{mode.label}: order {mode.order} {mode.branch}-phase is already "
                            f"given in {seen[key]}")
        seen.setdefault(key, mode.label)
    if problems:
        raise MeasurementError(source, problems)
    return modes


def _number(text: str, where: str, problems: list[str], meaning: str,
            positive: bool = False) -> float | None:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or (positive and value <= 0.0):
        problems.append(f"{where}: {text!r} must be {meaning}")
        return None
    return value


def _integer(text: str, where: str, problems: list[str]) -> int | None:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value.is_integer() and 0 <= value <= MAX_ORDER):
        problems.append(f"{where}: {text!r} must be an integer order n in [0, {MAX_ORDER}] "
                        "(the highest any mesh resolves)")
        return None
    return int(value)


def modes_text(modes) -> str:
    """A CSV table of modes (the format :func:`parse_modes` reads)."""
    lines = ["order,branch,frequency_hz,weight,damping_ratio"]
    for m in modes:
        damping = "" if m.damping_ratio is None else repr(float(m.damping_ratio))
        lines.append(f"{m.order},{m.branch},{float(m.frequency_hz)!r},{float(m.weight)!r},"
                     f"{damping}")
    return "\n".join(lines) + "\n"
