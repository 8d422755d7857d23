"""Where a demo run puts its files: a folder of its own that one run's set replaces whole.

A run writes its figures, tables and summary into a private folder beside OUT, and that folder
takes OUT's place only once the run is complete (:func:`tire_fmu.publish.published_folder`):
OUT holds one run's set, never a mix of two runs or a file cut short. So OUT must be new, or
hold only what a run writes.
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path


def check_output_folder(out: Path, option: str, outputs, error: type[Exception]) -> None:
    """OUT must be new, or a folder holding only what a run writes (``outputs``): a run
    replaces it whole."""
    from tire_fmu.publish import foreign_entries

    if out.exists() and not out.is_dir():
        raise error(f"{option} = {str(out)!r} is a file: give a folder")
    foreign = foreign_entries(out, outputs)
    if foreign:
        shown = ", ".join(foreign[:5]) + (", ..." if len(foreign) > 5 else "")
        raise error(f"{option} = {str(out)!r} holds files a demo run does not write "
                    f"({shown}); a run replaces its folder whole: give a new folder, or one "
                    "an earlier run wrote")


@contextmanager
def run_folder(out: Path, option: str, error: type[Exception], carry=()):
    """The private folder a run writes its set of files into, put in place of OUT whole when
    the run completes (:func:`tire_fmu.publish.published_folder`); an OSError of writing
    there is ``error`` naming the option and the file as OUT will hold it."""
    from tire_fmu.publish import published_folder

    work = None
    try:
        with published_folder(out, carry) as work:
            yield work
    except OSError as cause:
        if work is None:  # not even the private folder could be made
            raise error(f"{option} = {str(out)!r}: cannot write there: "
                        f"{cause.strerror or cause}") from cause
        if cause.filename is None or not Path(cause.filename).is_relative_to(work):
            raise
        written = out / Path(cause.filename).relative_to(work)
        raise error(f"{option} = {str(out)!r}: cannot write {str(written)!r}: "
                    f"{cause.strerror or cause}") from cause
