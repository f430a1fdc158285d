"""The provenance header of a validation study's result files.

A results.json records the command that wrote it, the dem version and commit and the machine
(:func:`results_header`); each run in it records when it started (:func:`stamp`); a CSV file
starts with ``#`` lines of the same (:func:`write_csv_header`). The values come from
:mod:`dem.provenance` and :func:`dem.io.liggghts.machine_info`.
"""

from __future__ import annotations

import sys

from dem import __version__, provenance


def invocation(script: str, argv: list[str] | None = None) -> str:
    """The command line of a study: ``script`` and its arguments (``sys.argv[1:]`` if None)."""
    return script + " " + " ".join(sys.argv[1:] if argv is None else argv)


def results_header(script: str, argv: list[str] | None = None, *, dated: bool = False) -> dict:
    """The top keys of a results.json: script, dem_version, git_commit, machine.

    Args:
        script: The study's path from the repository root, e.g. ``validation/liggghts-bulk/run.py``.
        argv: The study's arguments (``sys.argv[1:]`` if None).
        dated: Also the UTC date (after ``script``) and the load average (at the end).

    """
    from dem.io.liggghts import machine_info  # here: CSV-only studies need no LIGGGHTS code

    out = {"script": invocation(script, argv)}
    if dated:
        out["date"] = provenance.utc_now()
    out.update(
        {
            "dem_version": __version__,
            "git_commit": provenance.git_commit(),
            "machine": machine_info(),
        }
    )
    if dated:
        out["load_average"] = provenance.load_average()
    return out


def stamp(**extra) -> dict:
    """The start of one run's entry: its UTC date, then ``extra`` (e.g. the invocation)."""
    return {"date": provenance.utc_now(), **extra}


def write_csv_header(fh, command: str | None = None) -> None:
    """Write :func:`dem.provenance.header_lines` (``#`` lines, with ``command``) to ``fh``."""
    fh.write("\n".join(provenance.header_lines(command)) + "\n")
