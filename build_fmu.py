"""Build TireModal.fmu: ``python build_fmu.py [-o OUT_DIR]`` (default: the current folder).

Only parses the command line; the build lives in :mod:`tire_fmu.fmu.builder` (also reachable
as ``tire-fmu build-fmu OUT``).
"""

from __future__ import annotations

import argparse
import sys


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--out-dir", default=".", metavar="OUT_DIR",
                        help="folder to write TireModal.fmu into (default: .)")
    args = parser.parse_args(argv)
    from tire_fmu.fmu.builder import FmuBuildError, build_fmu

    try:
        path = build_fmu(args.out_dir)
    except (FmuBuildError, OSError) as error:
        print(f"build_fmu.py: error: {error}", file=sys.stderr)
        return 2
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
