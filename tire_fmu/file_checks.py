"""What every reader of a file here checks before it trusts the file, and the one error it raises.

A file is input like any other: whatever it holds, a reader either returns what it means or
raises :class:`FileContentError` (or a subclass: ``ModelFileError``, ``TireFileError``,
``MeasurementError``) whose message names the file, what is wrong and what is expected. The
command lines turn that error into one line. Nothing a file holds decides how much memory a
reader takes before the reader has checked it against a stated limit: text is read only up to
its reader's limit, JSON is measured (length, nesting) before it is parsed.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np

#: JSON nests no deeper than this in any file here (a model file's metadata nests 4 levels);
#: json.loads recurses once per level, so a file nested thousands deep would end it with
#: RecursionError instead of a message
MAX_JSON_DEPTH = 64

#: A JSON string token: what lies between its quotes is no structure (it may hold brackets).
_JSON_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.DOTALL)


class FileContentError(ValueError):
    """A file that cannot be used as it is: the message names the file, what is wrong with it
    and what is expected instead."""


def read_text(path: str | Path, max_bytes: int, what: str,
              error: type[FileContentError] = FileContentError) -> str:
    """The UTF-8 text of ``path`` (a byte-order mark dropped), refused beyond ``max_bytes``
    before it is read: ``what`` names the kind of file in the message."""
    path = Path(path)
    try:
        with path.open("rb") as stream:
            data = stream.read(max_bytes + 1)
    except OSError as cause:
        raise error(f"{path}: cannot be read: {cause.strerror or cause}") from cause
    if len(data) > max_bytes:
        raise error(f"{path}: more than {max_bytes} bytes: not {what} (at most {max_bytes} "
                    "bytes)")
    try:
        # utf-8-sig: a byte-order mark, as some Windows editors write, is not part of the text
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as cause:
        raise error(f"{path}: not UTF-8 text ({cause}): not {what}") from cause


def json_problem(text: str, max_chars: int, max_depth: int = MAX_JSON_DEPTH) -> str | None:
    """Why ``text`` is too long or nested too deeply to parse, or None: measured without
    parsing (strings stripped, then the brackets counted)."""
    if len(text) > max_chars:
        return f"{len(text)} characters of JSON, more than the {max_chars} allowed"
    structure = np.frombuffer(_JSON_STRING.sub("", text).encode("utf-8"), np.uint8)
    steps = (np.isin(structure, (ord("["), ord("{"))).astype(np.int64)
             - np.isin(structure, (ord("]"), ord("}"))))
    depth = int(np.cumsum(steps).max(initial=0))
    if depth > max_depth:
        return f"JSON nested {depth} levels deep, more than the {max_depth} allowed"
    return None


def load_json(text: str, source: str, what: str, max_chars: int,
              error: type[FileContentError] = FileContentError,
              max_depth: int = MAX_JSON_DEPTH) -> Any:
    """``text`` parsed as JSON once :func:`json_problem` finds it within the limits;
    ``source`` and ``what`` (e.g. "its metadata") name it in the message."""
    problem = json_problem(text, max_chars, max_depth)
    if problem:
        raise error(f"{source}: {what} is {problem}")
    try:
        return json.loads(text)
    except (ValueError, RecursionError) as cause:  # ValueError: JSONDecodeError, huge integers
        raise error(f"{source}: {what} is not valid JSON ({cause})") from cause
