"""Tire data files: TOML with a ``[parameters]`` table and a ``[units]`` table naming the unit
of every value, read by every CLI command (``--tire-file``), written by ``tire-fmu fit`` and
baked into FMUs as parameter start values.

::

    format = "tire_fmu-tire/1"
    name = "GL073A"
    description = "..."
    source = "..."

    [parameters]
    R = 0.65
    k_r1 = 6686000.0

    [units]
    R = "m"
    k_r1 = "N/m^2"

Units are checked, not converted: each must be the SI unit of
:data:`~tire_fmu.core.parameters.TIRE_FIELDS` (``""`` or ``"1"`` for a pure number), so a value
in mm or kPa is refused with its name instead of silently misread. Parameters a file leaves out
take the GL073A defaults, with a warning naming them. Optional tables (``[fit]`` from
``tire-fmu fit``) are kept as metadata. Floats are written with ``repr``, which reads back to
the same double, so a file reproduces its tire exactly.
"""

from __future__ import annotations

import math
import sys
import warnings
from dataclasses import asdict, dataclass, field, fields
from importlib import resources
from pathlib import Path
from typing import Any

from .core.inplane import TANGENTIAL_RANGES, TangentialParameters, tangential_problems
from .core.parameters import TIRE_FIELDS, TireParameters, render, tire_problems
from .file_checks import FileContentError, read_text
from .publish import published_file

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on 3.10 only
    import tomli as tomllib

FORMAT = "tire_fmu-tire/1"
#: Top-level keys a tire file may hold; tables beyond [parameters] and [units] are metadata.
TEXT_KEYS = ("format", "name", "description", "source")
METADATA_TABLES = ("fit",)
#: The in-plane ring's own tables: its tangential data and their units.
TANGENTIAL_TABLES = ("tangential", "tangential_units")
DIMENSIONLESS = ("", "1")
_SHIPPED = ("data", "tires")
#: The largest tire file read (bytes): a tire file is a few kilobytes of TOML.
MAX_TIRE_FILE_BYTES = 1 << 20


class TireFileError(FileContentError):
    """A tire file that cannot be read or written; the message names the file and key."""


@dataclass(frozen=True)
class TireFile:
    """A tire file's contents: the tire and what the file says about it."""

    tire: TireParameters
    name: str = ""
    description: str = ""
    source: str = ""
    path: Path | None = None
    #: parameters the file did not give (they took the GL073A defaults)
    defaulted: tuple[str, ...] = ()
    metadata: dict = field(default_factory=dict)
    #: the in-plane ring's tangential data (a [tangential] table), or None: the radial tire
    tangential: TangentialParameters | None = None


def shipped_tire_names() -> list[str]:
    """Names of the tire files that ship with the package (``GL073A``, ...)."""
    folder = resources.files("tire_fmu").joinpath(*_SHIPPED)
    return sorted(item.name[:-5] for item in folder.iterdir() if item.name.endswith(".toml"))


def shipped_tire_path(name: str) -> Path:
    """Path of a shipped tire file by name (case-insensitive), e.g. ``GL073A``."""
    by_key = {n.lower(): n for n in shipped_tire_names()}
    if name.lower() not in by_key:
        raise TireFileError(f"tire file {name!r}: no such file and no shipped tire of that "
                            f"name (shipped: {', '.join(shipped_tire_names())})")
    resource = resources.files("tire_fmu").joinpath(*_SHIPPED, f"{by_key[name.lower()]}.toml")
    return Path(str(resource))


def resolve_tire_file(spec: str | Path) -> Path:
    """An existing path as given, else the shipped tire file of that name."""
    path = Path(spec)
    if path.is_file():
        return path
    if path.suffix or path.parent != Path("."):
        raise TireFileError(f"tire file {str(spec)!r}: no such file (shipped tires: "
                            f"{', '.join(shipped_tire_names())})")
    return shipped_tire_path(str(spec))


def read_tire_file(spec: str | Path, warn: bool = True) -> TireFile:
    """Read a tire file (a path, or the name of a shipped one); every problem at once."""
    path = resolve_tire_file(spec)
    text = read_text(path, MAX_TIRE_FILE_BYTES, "a tire file", TireFileError)
    try:
        document = tomllib.loads(text)
    except ValueError as error:  # TOMLDecodeError, and integers of more than 4300 digits
        raise TireFileError(f"{path}: not valid TOML: {error}") from error
    except RecursionError as error:  # tomllib parses nested arrays and tables recursively
        raise TireFileError(f"{path}: not a tire file: arrays or tables nested too deeply "
                            "to read (a tire file nests at most a few levels)") from error
    values, problems = _parameters(document)
    tangential, more = _tangential_table(document)
    problems += more
    if tangential is not None and not more:  # its ranges, as the in-plane tire checks them
        radius = values.get("R", TireParameters().R)
        problems += [render(problem) for problem in
                     tangential_problems(TangentialParameters(**tangential), radius)]
    if problems:
        raise TireFileError(f"{path}: " + "; ".join(problems))
    defaulted = tuple(f.name for f in fields(TireParameters) if f.name not in values)
    if defaulted and warn:
        warnings.warn(f"{path} does not give {', '.join(defaulted)}: using the GL073A "
                      "defaults for them", stacklevel=2)
    return TireFile(
        tire=TireParameters(**values), path=path, defaulted=defaulted,
        name=str(document.get("name", "")), description=str(document.get("description", "")),
        source=str(document.get("source", "")),
        metadata={k: document[k] for k in METADATA_TABLES if k in document},
        tangential=None if tangential is None else TangentialParameters(**tangential))


def _parameters(document: dict) -> tuple[dict[str, float], list[str]]:
    problems = []
    allowed = {*TEXT_KEYS, "parameters", "units", *TANGENTIAL_TABLES, *METADATA_TABLES}
    for key in sorted(set(document) - allowed):
        problems.append(f"unknown key {key!r} (a tire file holds {sorted(allowed)})")
    fmt = document.get("format", FORMAT)
    if fmt != FORMAT:
        problems.append(f"format = {fmt!r}: this version reads {FORMAT!r}")
    for key in TEXT_KEYS:
        if key in document and not isinstance(document[key], str):
            problems.append(f"{key} = {document[key]!r}: must be a string")
    parameters = document.get("parameters")
    units = document.get("units", {})
    if not isinstance(parameters, dict):
        problems.append("no [parameters] table")
        return {}, problems
    if not isinstance(units, dict):
        problems.append("[units] must be a table of NAME = \"unit\"")
        units = {}
    known = {name: (spec.unit, spec.range_text()) for name, spec in TIRE_FIELDS.items()}
    values, more = _numbers_with_units(parameters, units, ("parameters", "units"), known,
                                       "a tire parameter")
    problems += more
    problems += [render(problem) for problem in tire_problems(values)]
    return values, problems


def _tangential_table(document: dict) -> tuple[dict[str, float] | None, list[str]]:
    """The [tangential] table's values, their [tangential_units] checked as [units] are."""
    table, units = (document.get(name) for name in TANGENTIAL_TABLES)
    if table is None:
        if units is not None:
            return None, ["[tangential_units] without a [tangential] table"]
        return None, []
    if not isinstance(table, dict):
        return None, ["[tangential] must be a table of NAME = number"]
    units = units if isinstance(units, dict) else {}
    known = {name: (unit, f"[{low:g}, {high:g}] {unit}".rstrip())
             for name, (low, high, unit) in TANGENTIAL_RANGES.items()}
    return _numbers_with_units(table, units, TANGENTIAL_TABLES, known,
                               "a tangential parameter")


def _numbers_with_units(table: dict, units: dict, names: tuple[str, str],
                        known: dict[str, tuple[str, str]], kind: str
                        ) -> tuple[dict[str, float], list[str]]:
    """A table of numbers and the table of their units, ``names`` = (its name, the units'
    name), ``known`` = name -> (unit, allowed range text): the values, and every problem."""
    table_name, units_name = names
    problems, values = [], {}
    for name, value in table.items():
        if name not in known:
            problems.append(f"{table_name}.{name}: not {kind}; known: {sorted(known)}")
            continue
        expected, allowed = known[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            problems.append(f"{table_name}.{name} = {value!r}: must be a number in {allowed}")
            continue
        try:
            number = float(value)
        except OverflowError:  # an integer beyond every double
            problems.append(f"{table_name}.{name} = an integer of {value.bit_length()} bits: "
                            f"must be a number in {allowed}")
            continue
        unit = units.get(name)
        shown = f'"{expected}"' if expected else '"1"'
        if unit is None:
            problems.append(f"{units_name}.{name} missing: state the unit of "
                            f"{table_name}.{name} ({name} = {shown})")
        elif not _same_unit(unit, expected):
            problems.append(f"{units_name}.{name} = {unit!r}: {table_name}.{name} must be "
                            f"given in {shown} (units are checked, not converted)")
        values[name] = number
    for name in sorted(set(units) - set(table)):
        problems.append(f"{units_name}.{name}: no {table_name}.{name} to go with it")
    return values, problems


def _same_unit(given: Any, expected: str) -> bool:
    if not isinstance(given, str):
        return False
    if expected == "":
        return given.strip() in DIMENSIONLESS
    return given.strip() == expected


# -- writing --------------------------------------------------------------------------------

def tire_file_text(tire: TireParameters, name: str = "", description: str = "",
                   source: str = "", metadata: dict | None = None,
                   tangential: TangentialParameters | None = None) -> str:
    """The TOML text of a tire file (a small emitter: strings, numbers, flat arrays, tables);
    ``tangential`` adds the in-plane ring's [tangential] and [tangential_units] tables."""
    lines = ["# tire_fmu tire data file: SI values in [parameters], their units in [units].",
             f"format = {_toml(FORMAT)}"]
    for key, value in (("name", name), ("description", description), ("source", source)):
        if value:
            lines.append(f"{key} = {_toml(value)}")
    lines += ["", "[parameters]"]
    for f in fields(TireParameters):
        spec = TIRE_FIELDS[f.name]
        lines.append(f"{f.name} = {_toml(getattr(tire, f.name))}  # {spec.description}")
    lines += ["", "[units]"]
    lines += [f"{f.name} = {_toml(TIRE_FIELDS[f.name].unit or '1')}"
              for f in fields(TireParameters)]
    if tangential is not None:
        lines += ["", "[tangential]"]
        lines += [f"{f.name} = {_toml(getattr(tangential, f.name))}"
                  for f in fields(TangentialParameters)]
        lines += ["", "[tangential_units]"]
        lines += [f"{f.name} = {_toml(TANGENTIAL_RANGES[f.name][2] or '1')}"
                  for f in fields(TangentialParameters)]
    for table, content in (metadata or {}).items():
        if table not in METADATA_TABLES:
            raise TireFileError(f"metadata table {table!r}: allowed are {list(METADATA_TABLES)}")
        lines += _table([table], content)
    return "\n".join(lines) + "\n"


def write_tire_file(path: str | Path, tire: TireParameters, name: str = "",
                    description: str = "", source: str = "", metadata: dict | None = None,
                    tangential: TangentialParameters | None = None) -> Path:
    """Write a tire file and check that it reads back to the same tire."""
    path = Path(path)
    text = tire_file_text(tire, name, description, source, metadata, tangential)
    try:  # the emitter's own guarantee: the text reads back to the same tire
        document = tomllib.loads(text)
        same = document["parameters"] == tire.as_dict() and (
            tangential is None or document["tangential"] == asdict(tangential))
    except tomllib.TOMLDecodeError as error:
        same, text = False, f"{error}"
    if not same:
        raise TireFileError(f"{path}: the text written does not read back to the tire")
    try:
        with published_file(path) as partial:
            partial.write_text(text, encoding="utf-8")
    except OSError as error:
        raise TireFileError(f"{path}: cannot be written: {error}") from error
    return path


def _table(keys: list[str], content: dict) -> list[str]:
    scalars = {k: v for k, v in content.items() if not isinstance(v, dict)}
    tables = {k: v for k, v in content.items() if isinstance(v, dict)}
    lines = ["", "[" + ".".join(_key(k) for k in keys) + "]"]
    lines += [f"{_key(k)} = {_toml(v)}" for k, v in scalars.items()]
    for k, v in tables.items():
        lines += _table(keys + [k], v)
    return lines


def _key(key: str) -> str:
    bare = key.replace("_", "").replace("-", "").isalnum() and key.isascii()
    return key if bare else _toml(key)


def _toml(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(float(value))  # plain float: numpy's repr would add its type name
    if isinstance(value, str):
        escaped = value.replace("\\", "\\\\").replace('"', '\\"')
        escaped = escaped.replace("\n", "\\n").replace("\t", "\\t").replace("\r", "\\r")
        return f'"{escaped}"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if value is None:
        raise TireFileError("TOML has no null: leave the key out instead")
    if hasattr(value, "item"):  # numpy scalars
        return _toml(value.item())
    raise TireFileError(f"cannot write {value!r} ({type(value).__name__}) to a tire file")
