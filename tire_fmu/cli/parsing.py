"""The argument parser of every command line here (``tire-fmu``, ``build_fmu.py``, ``python -m
vehicle_demo``), how they end on Ctrl-C and on an output they cannot write, and how they show
a warning: one line, ``PROG: warning: ...``, with no source line.

Kept free of numpy and scipy, like :mod:`.commands`: ``tire-fmu --help`` imports only these.
"""

from __future__ import annotations

import argparse
import difflib
import errno
import os
import re
import sys
import warnings
from collections.abc import Sequence
from contextlib import contextmanager

_NEGATIVE_NUMBER = re.compile(r"^-(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf|infinity|nan)$",
                              re.IGNORECASE)
#: exit status after Ctrl-C (128 + SIGINT, what a shell reports for a process it stopped)
INTERRUPTED = 130
#: exit status when stdout's reader went away (128 + SIGPIPE, as for a C tool)
BROKEN_PIPE = 141


class Parser(argparse.ArgumentParser):
    """argparse that takes options only as spelled (no abbreviations: ``--lo`` is not
    ``--load``), names an unknown option with the closest known one before anything else is
    checked, and reports a bad command line in one line (usage stays in --help)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        # a negative number in any float spelling is a value (argparse's own pattern knows
        # -5 and -0.5, not -1e-3): --load -1e-300 reaches the check of --load's range
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message: str):  # noqa: D401 - argparse's signature
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def parse_known_args(self, args: Sequence[str] | None = None, namespace=None):
        args = list(sys.argv[1:] if args is None else args)
        unknown = self.unknown_options(args)
        if unknown:
            self.error(unknown)
        return super().parse_known_args(args, namespace)

    def unknown_options(self, args: Sequence[str]) -> str | None:
        """What is wrong with the options among ``args`` that this parser does not know (up
        to its subcommand, whose own parser checks the rest), or None."""
        known = [o for o in self._option_string_actions if o.startswith("--")]
        commands = {name for action in self._actions
                    if isinstance(action, argparse._SubParsersAction) for name in action.choices}
        found = []
        for arg in args:
            if arg == "--" or arg in commands:
                break
            if not _looks_like_an_option(arg):
                continue
            # --name=value; -x and -xVALUE (a short option with its value attached)
            option = arg.split("=", 1)[0] if arg.startswith("--") else arg
            if option in self._option_string_actions or (
                    not arg.startswith("--") and arg[:2] in self._option_string_actions):
                continue
            # an abbreviation: the options it starts; else the closest spelling
            close = ([k for k in known if k.startswith(option)][:3]
                     or difflib.get_close_matches(option, known, n=1, cutoff=0.6))
            found.append(f"{option} (did you mean {' or '.join(close)}?)" if close else option)
        if not found:
            return None
        return f"unknown option{'s' if len(found) > 1 else ''} {', '.join(found)}"


def _looks_like_an_option(arg: str) -> bool:
    """What argparse itself would read as an option: a leading dash, and not a number (a
    negative value such as -5 or -1e-3), a lone dash or text with spaces."""
    if not arg.startswith("-") or arg == "-" or " " in arg:
        return False
    try:
        float(arg)
    except ValueError:
        return True
    return False


def write_stdout(text: str) -> None:
    """``text`` and a newline to stdout, flushed, so that a failure to write shows here."""
    sys.stdout.write(text + "\n")
    sys.stdout.flush()


def stdout_failure(prog: str, error: OSError) -> int:
    """The exit status, and a one-line message on stderr, for an output stdout could not take.

    A reader that stopped early (``| head``) is not an error worth a message: the status says
    it (141, as for a C tool stopped by SIGPIPE). Anything else (a full disk, /dev/full) is one
    line. Either way stdout then points at /dev/null, so that the interpreter's last flush of
    what is still buffered does not fail again with a traceback.
    """
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass
    if isinstance(error, BrokenPipeError) or error.errno == errno.EPIPE:
        return BROKEN_PIPE
    print(f"{prog}: error: cannot write the output to stdout: "
          f"{error.strerror or error}", file=sys.stderr)
    return 2


def interrupted(prog: str) -> int:
    """The exit status, and its one line on stderr, after Ctrl-C."""
    print(f"{prog}: interrupted", file=sys.stderr)
    return INTERRUPTED


def warning_line(prog: str, message) -> str:
    """A warning as a command shows it: ``PROG: warning: MESSAGE`` on one line (a message of
    several lines, a compiler's output in it, joined)."""
    return f"{prog}: warning: {' '.join(str(message).split())}"


@contextmanager
def one_line_warnings(prog: str):
    """Warnings shown on stderr as :func:`warning_line` has them instead of Python's file,
    line number and source line (which tell a user of the command nothing); the filters as
    they are, and Python's display back after."""
    def show(message, category, filename, lineno, file=None, line=None):
        print(warning_line(prog, message), file=sys.stderr)

    with warnings.catch_warnings():
        warnings.showwarning = show
        yield
