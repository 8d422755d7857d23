"""Build TireModal.fmu: ``python build_fmu.py [-o OUT_DIR]`` (default: the current folder).

Only parses the command line; the build lives in :mod:`tire_fmu.fmu.builder` (also reachable
as ``tire-fmu build-fmu OUT``).
"""

from __future__ import annotations

import sys

PROG = "build_fmu.py"


def main(argv=None) -> int:
    from tire_fmu.cli.parsing import interrupted, one_line_warnings

    try:
        with one_line_warnings(PROG):  # e.g. no compiler for a platform: what to install
            return _main(argv)
    except KeyboardInterrupt:  # the build cleans up after itself: nothing half-built stays
        return interrupted(PROG)


def _main(argv) -> int:
    from tire_fmu.cli.parsing import Parser, stdout_failure, write_stdout

    parser = Parser(prog=PROG, description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--out-dir", default=".", metavar="OUT_DIR",
                        help="folder to write TireModal.fmu into, created if missing "
                        "(default: .)")
    args = parser.parse_args(argv)
    from tire_fmu.fmu.builder import FmuBuildError, build_fmu

    try:
        path = build_fmu(args.out_dir)
    except FmuBuildError as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 2
    except OSError as error:
        print(f"{PROG}: error: --out-dir = {args.out_dir!r}: cannot write there: "
              f"{error.strerror or error}", file=sys.stderr)
        return 2
    try:
        write_stdout(str(path))
    except OSError as error:
        return stdout_failure(PROG, error)
    return 0


if __name__ == "__main__":
    sys.exit(main())
