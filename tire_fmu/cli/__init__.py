"""``tire-fmu`` command line: argument parsing, JSON and plots over the physics core.

Each command group lives in its own module with a ``register(subparsers)`` function; handlers
take the parsed arguments and return a :class:`Output` (text for people, a dict for ``--json``).
Errors the user can fix end the program with a one-line message and exit status 2.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from collections.abc import Sequence

from ..core import ParameterError
from .common import CLI_NAMES, CLI_UNSET, CliError, Output, to_jsonable

COMMAND_MODULES = ("ring", "rolling", "reduce", "fmu")


class _Parser(argparse.ArgumentParser):
    """argparse that reports a bad command line in one line (usage stays in --help)."""

    def error(self, message: str):  # noqa: D401 - argparse's signature
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="tire-fmu",
        description="Modal ring tire model (in-plane, 0-300 Hz): analysis, reduction, FMU.",
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                       parser_class=_Parser)
    import importlib

    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as error:  # a command group not written yet
            if error.name != f"{__name__}.{name}":
                raise
            continue
        module.register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            output: Output = args.handler(args)
        for warning in caught:
            print(f"tire-fmu {args.command}: warning: {warning.message}", file=sys.stderr)
    except (ParameterError, CliError, OSError) as error:
        if args.debug:
            raise
        message = (error.message(CLI_NAMES, CLI_UNSET) if isinstance(error, ParameterError)
                   else str(error)).replace("\n", " ")
        print(f"tire-fmu {args.command}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"tire-fmu {args.command}: interrupted", file=sys.stderr)
        return 130
    except Exception as error:  # an unexpected failure still gets one line, not a traceback
        if args.debug:
            raise
        print(
            f"tire-fmu {args.command}: internal error: {type(error).__name__}: {error} "
            "(run with --debug for the traceback)",
            file=sys.stderr,
        )
        return 1
    if getattr(args, "json", False):
        json.dump(to_jsonable(output.data), sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    elif output.text:
        print(output.text)
    for path in output.written:
        print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
