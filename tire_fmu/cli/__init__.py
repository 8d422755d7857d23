"""``tire-fmu`` command line: argument parsing, JSON and plots over the physics core.

Each command group lives in its own module with a ``register(subparsers)`` function; handlers
take the parsed arguments and return a :class:`Output` (text for people, a dict for ``--json``).
Errors the user can fix end the program with a one-line message and exit status 2.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from collections.abc import Sequence

from ..core import ParameterError
from .common import CliError, Output, check_plot_option, to_jsonable

COMMAND_MODULES = ("ring", "rolling", "reduce", "fmu", "fit")
DEBUG_HELP = "show tracebacks on errors"


class _Parser(argparse.ArgumentParser):
    """argparse that reports a bad command line in one line (usage stays in --help)."""

    def error(self, message: str):  # noqa: D401 - argparse's signature
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="tire-fmu",
        description="Modal ring tire model (in-plane, 0-300 Hz): analysis, reduction, FMU.",
    )
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
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
    for command in subparsers.choices.values():
        # also after the command; SUPPRESS keeps a --debug given before it
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                             help=DEBUG_HELP)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        check_plot_option(args)  # before computing: a bad --plot must not cost a whole run
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            output: Output = args.handler(args)
        for warning in caught:
            print(f"tire-fmu {args.command}: warning: {warning.message}", file=sys.stderr)
    except (ParameterError, CliError, OSError) as error:
        if args.debug:
            raise
        message = str(error).replace("\n", " ")
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
    try:
        if getattr(args, "json", False):
            json.dump(to_jsonable(output.data), sys.stdout, indent=2, allow_nan=False)
            sys.stdout.write("\n")
        elif output.text:
            print(output.text)
        sys.stdout.flush()
    except BrokenPipeError:
        # the reader stopped early (`tire-fmu modes --json | head`): not an error of ours.
        # Point stdout at /dev/null so the interpreter's final flush does not fail again.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    for path in output.written:
        print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
