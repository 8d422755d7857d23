"""``tire-fmu`` command line: argument parsing, JSON and plots over the physics core.

Each command group lives in its own module with a ``register(subparsers)`` function; handlers
take the parsed arguments and return a :class:`Output` (text for people, a dict for ``--json``).
Errors the user can fix (a bad command line or value, a file that cannot be read or used, an
output that cannot be written, stdout included) end the program with a one-line message and
exit status 2; an unexpected one with one line and status 1; Ctrl-C with one line and 130; a
reader that stopped early (``| head``) silently with 141 (:mod:`.parsing`).

Only the module of the command given is imported (:mod:`.commands` lists the others with
their help lines), so ``tire-fmu --help`` answers without loading numpy or scipy. Commands run
with one BLAS thread unless ``--blas-threads`` or ``TIRE_FMU_BLAS_THREADS`` says otherwise: the
dense eigenproblems here are small enough that threads on a shared machine mostly fight
(:mod:`tire_fmu.core.blas_threads`, which the library's own calls and the FMUs use too).
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from collections.abc import Sequence

from ..core.blas_threads import (  # noqa: F401  (BLAS_THREADS_ENV: the CLI's name for it)
    BLAS_THREADS_ENV,
    blas_threads,
    configured_blas_threads,
    parse_blas_threads,
)
from .commands import COMMANDS
from .parsing import Parser, interrupted, stdout_failure, warning_line, write_stdout

COMMAND_MODULES = tuple(dict.fromkeys(module for module, _ in COMMANDS.values()))
DEBUG_HELP = "show tracebacks on errors"


def _blas_threads(text: str) -> int:
    try:
        return parse_blas_threads(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _default_blas_threads() -> int:
    try:
        return configured_blas_threads()
    except ValueError as error:
        sys.exit(f"tire-fmu: error: {error}")


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The parser; with ``argv``, only the module of the command named there is imported
    (the other commands are listed with their help line), without it every module is."""
    parser = Parser(
        prog="tire-fmu",
        description="Modal ring tire model (in-plane, 0-300 Hz): analysis, reduction, FMU.",
    )
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    parser.add_argument("--blas-threads", metavar="T", type=_blas_threads, default=None,
                        help="BLAS/LAPACK threads for the computation (default 1, or "
                        f"${BLAS_THREADS_ENV}; 0: the library's default)")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                       parser_class=Parser)
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
    command = next((arg for arg in argv if arg in COMMANDS), None)
    prog = f"tire-fmu {command}" if command else "tire-fmu"
    try:
        return _main(argv, prog)
    except KeyboardInterrupt:  # wherever it comes: parsing, imports, the work, the output
        if "--debug" in argv:
            raise
        return interrupted(prog)


def _main(argv: list[str], prog: str) -> int:
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    import json

    from ..core.parameters import ParameterError
    from ..file_checks import FileContentError
    from .common import CliError, Output, check_plot_option, cli_message, to_jsonable

    threads = _default_blas_threads() if args.blas_threads is None else args.blas_threads
    try:
        check_plot_option(args)  # before computing: a bad --plot must not cost a whole run
        with warnings.catch_warnings(record=True) as caught, \
                blas_threads(threads):
            warnings.simplefilter("always")
            try:
                output: Output = args.handler(args)
            finally:  # also before the error line of a command that then failed
                for warning in caught:
                    print(warning_line(prog, warning.message), file=sys.stderr)
    except (ParameterError, CliError, FileContentError, OSError) as error:
        if args.debug:
            raise
        message = (cli_message(error, _command_options(parser, args.command))
                   if isinstance(error, ParameterError) else str(error)).replace("\n", " ")
        print(f"{prog}: error: {message}", file=sys.stderr)
        return 2
    except Exception as error:  # an unexpected failure still gets one line, not a traceback
        if args.debug:
            raise
        print(
            f"{prog}: internal error: {type(error).__name__}: {error} "
            "(run with --debug for the traceback)",
            file=sys.stderr,
        )
        return 1
    status = 0
    try:
        if getattr(args, "json", False):
            write_stdout(json.dumps(to_jsonable(output.data), indent=2, allow_nan=False))
        elif output.text:
            write_stdout(output.text)
    except OSError as error:  # /dev/full, or a reader that stopped early (`| head`)
        status = stdout_failure(prog, error)
    for path in output.written:
        print(f"wrote {path}", file=sys.stderr)
    return status


def _command_options(parser: argparse.ArgumentParser, command: str) -> set[str]:
    """The option strings the command's own parser takes."""
    (commands,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return set(commands.choices[command]._option_string_actions)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
