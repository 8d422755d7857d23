"""``tire-fmu`` command line: argument parsing, JSON and plots over the physics core.

Each command group lives in its own module with a ``register(subparsers)`` function; handlers
take the parsed arguments and return a :class:`Output` (text for people, a dict for ``--json``).
Errors the user can fix end the program with a one-line message and exit status 2.

Only the module of the command given is imported (:mod:`.commands` lists the others with
their help lines), so ``tire-fmu --help`` answers without loading numpy or scipy. Commands run
with one BLAS thread unless ``--blas-threads`` or ``TIRE_FMU_BLAS_THREADS`` says otherwise: the
dense eigenproblems here are small enough that threads on a shared machine mostly fight.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import warnings
from collections.abc import Sequence

from .commands import COMMANDS

COMMAND_MODULES = tuple(dict.fromkeys(module for module, _ in COMMANDS.values()))
#: Environment variable with the BLAS thread count (0: the library's default).
BLAS_THREADS_ENV = "TIRE_FMU_BLAS_THREADS"
DEBUG_HELP = "show tracebacks on errors"


class _Parser(argparse.ArgumentParser):
    """argparse that reports a bad command line in one line (usage stays in --help)."""

    def error(self, message: str):  # noqa: D401 - argparse's signature
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _blas_threads(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be an integer >= 0 (0: the BLAS "
                                         "library's default)")
    return value


def _default_blas_threads() -> int:
    text = os.environ.get(BLAS_THREADS_ENV, "1")
    try:
        return _blas_threads(text)
    except argparse.ArgumentTypeError as error:
        sys.exit(f"tire-fmu: error: {BLAS_THREADS_ENV} = {error}")


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The parser; with ``argv``, only the module of the command named there is imported
    (the other commands are listed with their help line), without it every module is."""
    parser = _Parser(
        prog="tire-fmu",
        description="Modal ring tire model (in-plane, 0-300 Hz): analysis, reduction, FMU.",
    )
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    parser.add_argument("--blas-threads", metavar="T", type=_blas_threads, default=None,
                        help="BLAS/LAPACK threads for the computation (default 1, or "
                        f"${BLAS_THREADS_ENV}; 0: the library's default)")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                       parser_class=_Parser)
    if argv is None:
        wanted = set(COMMAND_MODULES)
    else:
        named = next((arg for arg in argv if arg in COMMANDS), None)
        wanted = {COMMANDS[named][0]} if named else set()
    for name, (module_name, help_line) in COMMANDS.items():
        if module_name in wanted:
            wanted.discard(module_name)
            importlib.import_module(f"{__name__}.{module_name}").register(subparsers)
        elif name not in subparsers.choices:  # listed only; never parsed in this run
            subparsers.add_parser(name, help=help_line)
    for command in subparsers.choices.values():
        # also after the command; SUPPRESS keeps a --debug given before it
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                             help=DEBUG_HELP)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    import json

    import scipy.linalg  # noqa: F401  (numpy's and scipy's BLAS loaded, so both are limited)
    from threadpoolctl import threadpool_limits

    from ..core.parameters import ParameterError
    from .common import CLI_NAMES, CLI_UNSET, CliError, Output, check_plot_option, to_jsonable

    threads = _default_blas_threads() if args.blas_threads is None else args.blas_threads
    try:
        check_plot_option(args)  # before computing: a bad --plot must not cost a whole run
        with warnings.catch_warnings(record=True) as caught, \
                threadpool_limits(limits=threads or None, user_api="blas"):
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
