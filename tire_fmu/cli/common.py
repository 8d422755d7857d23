"""Options and helpers shared by the CLI command groups."""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from collections.abc import Callable, Collection, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..core import TIRE_FIELDS, TireParameters, build_model, validate
from ..core.inplane_host import HOST_FIELDS
from ..core.parameters import (
    ELEMENTS_REASON,
    MAX_ELEMENTS,
    MAX_PATCH_FRACTION,
    MIN_ELEMENTS,
    FieldSpec,
    ParameterError,
    render,
    tire_problems,
    value_text,
)

#: The options that set the core's inputs, for its problems to name them (tire data keep
#: their names: they are set with --tire NAME=VALUE).
CLI_NAMES = {
    "load_n": "--load", "patch_length_m": "--patch-length", "speed_m_s": "--speed",
    "n_elements": "--elements", "inflation_pressure": "--inflation-pressure",
    "allow_supercritical": "--allow-supercritical", "f_max_hz": "--f-max",
    "n_modes": "--n-modes", "n_states": "--n-states", "contribution_threshold": "--threshold",
    "target_error": "--target-error", "error_band_hz": "--band", "method": "--method",
    "nmax": "--nmax", "input": "--input", "output": "--output",
    "contact_zone_length_m": "--zone-length", "contact_point_spacing_m": "--point-spacing",
}
#: how "no limit" reads on the command line
CLI_UNSET = "left out"


def cli_message(error: ParameterError, options: Collection[str]) -> str:
    """The core's problems in one line in the command's own words: each names its input by
    its option (:data:`CLI_NAMES`), and a setting the text names by its core name
    (``allow_supercritical runs anyway``) reads as the option that sets it when this command
    has that option (``--allow-supercritical``); the others keep their names."""
    text = error.message(CLI_NAMES, CLI_UNSET)
    for core, option in CLI_NAMES.items():
        if "_" in core and option in options:  # identifiers only, not words such as "input"
            text = re.sub(rf"(?<![\w-]){re.escape(core)}(?![\w-])", option, text)
    return text


class CliError(Exception):
    """A problem with the command line the user can fix; printed as one line. ``problems``:
    each problem it holds (:func:`raise_problems` puts several in one)."""

    def __init__(self, message: str, problems: Sequence[str] | None = None):
        super().__init__(message)
        self.problems = list(problems) if problems is not None else [message]


@dataclass
class Output:
    """What a command produced: text for a terminal, data for --json, files written."""

    text: str = ""
    data: Any = None
    written: list[Path] = field(default_factory=list)


def to_jsonable(value: Any) -> Any:
    """Plain JSON types; nan and inf become null (JSON has neither)."""
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        number = float(value)
        return number if math.isfinite(number) else None
    if isinstance(value, (np.bool_,)):
        return bool(value)
    if isinstance(value, Path):
        return str(value)
    return value


class OutputPath(type(Path())):
    """A path an output option names, remembering whether the text named a folder (a
    trailing separator, which Path drops: ``--out x.npz/`` is a folder named x.npz, not the
    file x.npz)."""

    names_folder = False


def output_path(text: str) -> OutputPath:
    """argparse type of every output option (:func:`output_file` reads it)."""
    path = OutputPath(text)
    path.names_folder = len(text) > 1 and text.endswith(("/", os.sep))
    return path


def add_output_options(parser: argparse.ArgumentParser, plot: bool = True) -> None:
    parser.add_argument("--json", action="store_true", help="print machine-readable JSON")
    if plot:
        parser.add_argument("--plot", metavar="FILE", type=output_path,
                            help="write a figure (format from the extension: .png, .pdf, .svg)")


def add_tire_options(parser: argparse.ArgumentParser) -> None:
    names = ", ".join(f"{name} [{spec.unit or '1'}]" for name, spec in TIRE_FIELDS.items())
    parser.add_argument(
        "--tire-file", metavar="FILE",
        help="read the tire data from a TOML tire file, or a shipped one by name (GL073A, "
        "GL073A_shear); --tire and --inflation-pressure override its values",
    )
    parser.add_argument(
        "--tire", metavar="NAME=VALUE", action="append", default=[],
        help="override a tire parameter (repeatable); defaults are the GL073A tire. "
        f"Names: {names}",
    )
    parser.add_argument("--inflation-pressure", metavar="PA", type=float,
                        help="inflation pressure in Pa (default 7.9e5)")


def add_mesh_option(parser: argparse.ArgumentParser, default: int = 100) -> None:
    parser.add_argument("--elements", metavar="N", type=int, default=default,
                        help=f"number of elements around the ring (default {default})")
    parser.add_argument("--point-spacing", metavar="M", type=float, default=None,
                        help="largest distance in m between the contact points on the tread "
                        # core.contact.DEFAULT_CONTACT_POINT_SPACING_M (no numpy before parsing;
                        # tests/test_cli.py holds the two equal)
                        "(default 0.0025; at least the node "
                        "arc 2*pi*R/N gives one point per node)")


#: What --load 0 means, wherever --load is taken.
LOAD_ZERO = ("0 N: the tire touches the road without pressing on it, no tread node pushes "
             "and the road does not reach it: the undeformed tire")


def load_default_text(load_n: float) -> str:
    """How a --help states a command's default load."""
    if load_n == 0.0:
        return "default 0 N"
    return (f"default {value_text(load_n, 'N')}, the FMU's default load: one wheel of the "
            "heavy vehicle")


def add_contact_options(parser: argparse.ArgumentParser, default_load_n: float) -> None:
    """--load, with the command's default (0: the undeformed tire, for the modes as the paper
    tabulates them; the FMU's default load where the road must reach the tire), or the paper's
    --patch-length instead."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--patch-length", metavar="M", type=float,
                       help="the paper's prescribed contact patch of this length in m, instead "
                       "of the footprint computed for --load (0: the undeformed tire)")
    group.add_argument("--load", metavar="N", type=float,
                       help="static vertical load in N; the footprint is computed from it "
                       f"({load_default_text(default_load_n)}; {LOAD_ZERO})")


def add_speed_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--speed", metavar="M_PER_S", type=float, default=0.0,
                        help="forward speed in m/s (default 0; spin = speed / R)")
    parser.add_argument("--allow-supercritical", action="store_true",
                        help="run at or above the mesh's critical (standing-wave) speed")


def tire_file_values(args: argparse.Namespace) -> dict[str, Any]:
    """The tire data of --tire-file (empty without one); a bad file is a one-line error."""
    spec = getattr(args, "tire_file", None)
    if spec is None:
        return {}
    from ..tire_files import TireFileError, read_tire_file

    try:
        return read_tire_file(spec).tire.as_dict()
    except TireFileError as error:
        raise CliError(f"--tire-file: {error}") from error


def parse_tire_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """Tire values: --tire-file first, then --tire NAME=VALUE and --inflation-pressure."""
    values: dict[str, Any] = tire_file_values(args)
    for item in getattr(args, "tire", []) or []:
        name, sep, text = item.partition("=")
        if not sep:
            raise CliError(f"--tire {item!r}: expected NAME=VALUE, e.g. --tire k_r1=7e6")
        try:
            values[name.strip()] = float(text)
        except ValueError:
            values[name.strip()] = text  # validation names it with its allowed range
    if getattr(args, "inflation_pressure", None) is not None:
        values["inflation_pressure"] = args.inflation_pressure
    return values


def operating_point_values(args: argparse.Namespace, undeformed_default: bool) -> dict[str, Any]:
    values: dict[str, Any] = {"n_elements": getattr(args, "elements", 100)}
    if getattr(args, "load", None) is not None:
        values["load_n"] = args.load
    elif getattr(args, "patch_length", None) is not None:
        values["patch_length_m"] = args.patch_length
    elif undeformed_default:
        values["patch_length_m"] = 0.0
    if getattr(args, "speed", None) is not None:
        values["speed_m_s"] = args.speed
    if getattr(args, "allow_supercritical", False):
        values["allow_supercritical"] = True
    if getattr(args, "zone_length", None) is not None:
        values["contact_zone_length_m"] = args.zone_length
    if getattr(args, "point_spacing", None) is not None:
        values["contact_point_spacing_m"] = args.point_spacing
    return values


def validated_args(args: argparse.Namespace, undeformed_default: bool = True):
    """(tire, operating point) from the options, every problem with them at once."""
    return validate(parse_tire_overrides(args), operating_point_values(args, undeformed_default))


def model_from_args(args: argparse.Namespace, undeformed_default: bool = True, checked=None):
    """The model of the options (``checked``: their :func:`validated_args` already)."""
    return build_model(*(checked or validated_args(args, undeformed_default)))


def write_plot(args: argparse.Namespace, output: Output, draw: Callable[[Path], Path]) -> None:
    """Call ``draw(path)`` when --plot was given and record the file (the path was checked
    before the computation by :func:`check_plot_option`)."""
    path = getattr(args, "plot", None)
    if path is None:
        return
    with writing("--plot", path):
        output.written.append(draw(path))


@contextmanager
def writing(option: str, path: Path):
    """Turn an OSError of writing the output file ``path`` into a CliError naming the option
    that chose it, the path and the reason."""
    try:
        yield
    except OSError as error:
        raise CliError(f"{option} = {str(path)!r}: cannot write it: "
                       f"{error.strerror or error}") from error


def figure_formats() -> dict[str, str]:
    """File extensions matplotlib can write (without the dot), with their descriptions."""
    try:
        from matplotlib.backend_bases import FigureCanvasBase
    except ImportError as error:
        raise CliError("--plot needs matplotlib: pip install 'tire_fmu[plot]'") from error
    return FigureCanvasBase.get_supported_filetypes()


def check_plot_option(args: argparse.Namespace) -> None:
    """A --plot path with a figure format matplotlib writes, in an existing folder."""
    path = getattr(args, "plot", None)
    if path is None:
        return
    if getattr(path, "names_folder", False):
        raise CliError(f"--plot = {str(path) + os.sep!r} names a folder: give a file name")
    formats = figure_formats()
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in formats:
        known = ", ".join(f".{name}" for name in sorted(formats))
        what = f"unknown figure format .{suffix}" if suffix else "no file extension"
        raise CliError(f"--plot = {str(path)!r}: {what}; the extension picks the format, one "
                       f"of {known}")
    if path.is_dir():
        raise CliError(f"--plot = {str(path)!r} is a folder: give a file name")
    check_parent_folder("--plot", path)


def check_parent_folder(option: str, path: Path) -> None:
    """Refuse a file whose folder is missing or is a file, naming the option."""
    parent = path.parent
    if parent.is_dir():
        return
    why = "is a file, not a folder" if parent.exists() else "does not exist"
    raise CliError(f"{option} = {str(path)!r}: folder {str(parent)!r} {why}")


def output_file(option: str, path: Path, suffix: str, default_name: str | None = None) -> Path:
    """The file an output option names: a path ending in ``suffix`` (case-insensitive) in an
    existing folder, or, given ``default_name``, a folder to hold that file: an existing one,
    or a path without an extension (created with its parents by :func:`make_folder` when the
    file is written)."""
    folder_named = getattr(path, "names_folder", False)
    path = Path(path)
    if default_name is not None and (path.is_dir() or folder_named or (
            path.suffix == "" and not path.exists())):
        if path.exists() and not path.is_dir():
            raise CliError(f"{option} = {str(path) + os.sep!r}: {str(path)!r} is a file, not "
                           "a folder")
        _check_ancestors(option, path)
        return path / default_name
    if folder_named:
        raise CliError(f"{option} = {str(path) + os.sep!r} names a folder (it ends in "
                       f"{os.sep}): give a file name ending in {suffix}")
    if path.is_dir():
        raise CliError(f"{option} = {str(path)!r} is a folder: give a file name ending "
                       f"in {suffix}")
    if path.suffix.lower() != suffix:
        folder = " (or a folder)" if default_name else ""
        raise CliError(f"{option} = {str(path)!r}: must be a file name ending in "
                       f"{suffix}{folder}")
    check_parent_folder(option, path)
    return path


def _check_ancestors(option: str, folder: Path) -> None:
    """A folder that exists or can be made: its nearest existing ancestor is a folder."""
    for ancestor in (folder, *folder.parents):
        if ancestor.exists():
            if not ancestor.is_dir():
                raise CliError(f"{option} = {str(folder)!r}: {str(ancestor)!r} is a file, "
                               "not a folder")
            return


def make_folder(option: str, file: Path) -> None:
    """The folder of an output file, created with its parents if missing."""
    with writing(option, file.parent):
        file.parent.mkdir(parents=True, exist_ok=True)


def table(rows: list[list[Any]], header: list[str]) -> str:
    """A plain aligned text table."""
    text_rows = [[_cell(v) for v in row] for row in rows]
    widths = [max(len(h), *(len(r[i]) for r in text_rows)) if text_rows else len(h)
              for i, h in enumerate(header)]
    lines = ["  ".join(h.rjust(w) for h, w in zip(header, widths)),
             "  ".join("-" * w for w in widths)]
    lines += ["  ".join(c.rjust(w) for c, w in zip(row, widths)) for row in text_rows]
    return "\n".join(lines)


def _cell(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, (float, np.floating)):
        return f"{value:.4g}" if abs(value) < 1e5 else f"{value:.4e}"
    return str(value)


# ------------------------------------------------------------------------------------------
# Option checks: every problem with the command line, the tire and the operating point is
# collected and reported in one line, so a user fixes them all in one go.


def range_problem(option: str, value: Any, low: float, high: float, unit: str = "",
                  integer: bool = False, low_inclusive: bool = True,
                  reason: str = "") -> str | None:
    """The option's problem as the FMUs' parameters find theirs (:class:`FieldSpec`: a
    finite number, an integer if asked, in [low, high] or (low, high]) and words it
    (:func:`render`), or None."""
    problem = FieldSpec(option, unit, reason, low, high, low_inclusive, integer).problem(
        _number(value))
    return None if problem is None else render(problem)


def field_problem(option: str, value: Any, spec: FieldSpec, reason: str | None = None
                  ) -> str | None:
    """The option's problem against a setting's own range (``spec``: the FMU's parameter it
    sets, :data:`~tire_fmu.core.inplane_host.HOST_FIELDS`, :data:`TIRE_FIELDS`), or None."""
    problem = replace(spec, name=option, description=spec.description if reason is None
                      else reason).problem(_number(value))
    return None if problem is None else render(problem)


def _number(value: Any) -> Any:
    """What FieldSpec.problem reads: True is no number on a command line (float makes it 1)."""
    return repr(value) if isinstance(value, bool) else value


#: The highest frequency any command computes or lists (Hz): the in-plane FMU's f_max limit,
#: 300 times the band the model is made for.
MAX_FREQUENCY_HZ = HOST_FIELDS["f_max_hz"].high


def frequency_problem(option: str, value: Any) -> str | None:
    """A frequency limit in (0, MAX_FREQUENCY_HZ] Hz."""
    return range_problem(option, value, 0.0, MAX_FREQUENCY_HZ, "Hz", low_inclusive=False)


def frequency_grid_problems(args: argparse.Namespace) -> list[str | None]:
    """What is wrong with --min-frequency, --max-frequency and --points."""
    low, high = args.min_frequency, args.max_frequency
    return [
        range_problem("--min-frequency", low, 1e-3, MAX_FREQUENCY_HZ, "Hz"),
        range_problem("--max-frequency", high, 1e-3, MAX_FREQUENCY_HZ, "Hz"),
        range_problem("--points", args.points, 2, 100_000, integer=True),
        None if high > low else
        f"--max-frequency = {high:g} Hz: must be above --min-frequency = {low:g} Hz",
    ]


def frequency_grid(args: argparse.Namespace) -> np.ndarray:
    """The log-spaced frequencies (Hz) of --min-frequency, --max-frequency and --points, every
    problem with them at once."""
    raise_problems(frequency_grid_problems(args))
    return np.geomspace(args.min_frequency, args.max_frequency, args.points)


def response_table(responses, marks_hz=(1.0, 10.0, 50.0, 100.0, 150.0, 200.0, 300.0)) -> str:
    """|H| of each FrequencyResponse at the frequencies nearest the marks in their band."""
    freqs = responses[0].frequencies_hz
    rows = []
    for f in marks_hz:
        if freqs[0] <= f <= freqs[-1]:
            i = int(np.argmin(np.abs(freqs - f)))
            rows.append([freqs[i]] + [r.magnitude[i] for r in responses])
    return table(rows, ["f [Hz]"] + [f"|H| {r.label} [{r.unit}]" for r in responses])


def positive_problem(option: str, value: Any, unit: str, high: float) -> str | None:
    """A number in (0, high]."""
    return range_problem(option, value, 0.0, high, unit, low_inclusive=False)


def elements_problem(value: int, option: str = "--elements") -> str | None:
    """A mesh, worded as the core's n_elements."""
    return range_problem(option, value, MIN_ELEMENTS, MAX_ELEMENTS, integer=True,
                         reason=ELEMENTS_REASON)


def order_problem(option: str, value: Any, elements: Any, low: int = 1,
                  most: int | None = None) -> str | None:
    """The highest order a command lists: an integer from ``low`` up to what the mesh
    resolves (N / 2; MAX_ELEMENTS / 2 while --elements itself is wrong, so that one mistake
    is not reported twice), at most ``most``."""
    valid = elements_problem(elements) is None
    high = int(elements) // 2 if valid else MAX_ELEMENTS // 2
    return range_problem(option, value, low, min(high, most or high), integer=True,
                         reason=f"orders up to N/2 = {high} on this mesh" if valid else "")


def checked_together(*steps: Callable[[], Any]) -> list[Any]:
    """The results of ``steps`` (callables that check options and build from them), once
    every one has run: the problems they raise (CliError, ParameterError in the command's
    words) are raised together in one line instead of one group at a time."""
    results, errors = [], []
    for step in steps:
        try:
            results.append(step())
        except (CliError, ParameterError) as error:
            errors.append(error)
            results.append(None)
    if len(errors) == 1:  # as it is (--debug shows where it came from)
        raise errors[0]
    raise_problems([problem for error in errors for problem in (
        error.problems if isinstance(error, CliError) else
        [cli_message(ParameterError([detail]), CLI_NAMES.values())
         for detail in error.details])])
    return results


def raise_problems(problems: Sequence[str | None]) -> None:
    found = [p for p in problems if p]
    if len(found) == 1:
        raise CliError(found[0])
    if found:
        raise CliError(f"{len(found)} problems: " + "; ".join(found), found)


def patch_length_problem(option: str, value: float, tire: TireParameters,
                         positive: bool = False) -> str | None:
    """A patch length checked against the tire's credible limit (a fraction of its
    circumference), named after the command's own option."""
    high = tire.max_patch_length_m
    low_ok = value > 0 if positive else value >= 0
    if value is None or not np.isfinite(value) or not low_ok or value > high:
        left = "(" if positive else "["
        return (f"{option} = {value!r} m: must be in {left}0, {high:.4g}] m, at most "
                f"{MAX_PATCH_FRACTION:g} of the circumference, beyond which the linear ring is "
                "not credible")
    return None


def checked_tire(args: argparse.Namespace, problems: Sequence[str | None] = (),
                 tire_checks: Callable[[TireParameters], Sequence[str | None]] | None = None,
                 ) -> TireParameters:
    """The tire from --tire/--inflation-pressure. Raises once with the option problems given,
    the tire's own, and those ``tire_checks(tire)`` finds for a valid tire."""
    values = parse_tire_overrides(args)
    own = [render(problem, CLI_NAMES, CLI_UNSET) for problem in tire_problems(values)]
    tire = None if own else TireParameters(**values)
    found = list(problems) + own
    if tire is not None and tire_checks is not None:
        found += list(tire_checks(tire))
    raise_problems(found)
    return tire


@contextmanager
def progress_bar(description: str):
    """A ``progress(done, total)`` callback drawing a tqdm bar on a terminal, else None."""
    try:
        from tqdm import tqdm
    except ImportError:
        tqdm = None
    if tqdm is None or not sys.stderr.isatty():
        yield None
        return
    bar = None

    def update(done: int, total: int) -> None:
        nonlocal bar
        if bar is None:
            bar = tqdm(total=total, desc=description, leave=False, file=sys.stderr)
        bar.update(done - bar.n)

    try:
        yield update
    finally:
        if bar is not None:
            bar.close()


def plot_with(function_name: str, *args: Any, **kwargs: Any) -> Callable:
    """A ``draw(path)`` for :func:`write_plot` that imports the plots module only when used."""

    def draw(path):
        from .. import plots

        return getattr(plots, function_name)(*args, path, **kwargs)

    return draw


def element_list(text: str, example: str) -> tuple[list[int], str | None]:
    """--elements-list: distinct meshes, ascending (repeats dropped), or the one-line problem."""
    from ..core.parameters import MAX_ELEMENTS, MIN_ELEMENTS

    try:
        counts = [int(item) for item in text.split(",") if item.strip()]
    except ValueError:
        counts = []
    bad = [n for n in counts if not MIN_ELEMENTS <= n <= MAX_ELEMENTS]
    if not counts or bad:
        return [], (f"--elements-list = {text!r}: must be comma-separated integers in "
                    f"[{MIN_ELEMENTS}, {MAX_ELEMENTS}], e.g. {example}")
    return sorted(set(counts)), None
