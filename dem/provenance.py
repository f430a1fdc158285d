"""Where a result came from: package versions, the git commit, the machine and its load.

Every file dem writes for others to trust (``summary.json``, ``results.h5``, the CSV and JSON of
the validation studies) records who made it. The pieces live here once:

- :func:`package_versions`: dem, numpy, numba, h5py and Python;
- :func:`git_commit`: the commit of the dem checkout in use, with a mark when ``dem/`` has
  uncommitted changes (None outside a git checkout, e.g. an installed wheel);
- :func:`record`: all of it plus the UTC time, the host and its load average, as a dict;
- :func:`header_lines`: the same as ``#`` comment lines for the top of a CSV file.
"""

from __future__ import annotations

import datetime
import os
import platform
import subprocess
from importlib import metadata
from pathlib import Path

from dem import __version__

PACKAGE_ROOT = Path(__file__).resolve().parent


def package_versions() -> dict[str, str]:
    """Versions of dem, numpy, numba, h5py and python, as strings ("unknown" if not found)."""
    out = {"dem": __version__}
    for name in ("numpy", "numba", "h5py"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "unknown"
    out["python"] = platform.python_version()
    return out


def git_commit() -> str | None:
    """Short commit of the checkout that holds this ``dem`` package, or None if there is none.

    A ``+`` suffix marks uncommitted changes to tracked files under ``dem/``: the code that ran
    is then not exactly the commit named.
    """
    root = PACKAGE_ROOT.parent
    try:
        done = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            cwd=root, capture_output=True, text=True, timeout=10,
        )  # fmt: skip
        if done.returncode != 0 or not done.stdout.strip():
            return None
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", "dem"],
            cwd=root, capture_output=True, text=True, timeout=10,
        )  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip() + ("+" if dirty.stdout.strip() else "")


def utc_now() -> str:
    """The current UTC time, ISO 8601 to the second."""
    return datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")


def load_average() -> float | None:
    """One-minute load average of this machine (None where the OS has none)."""
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return None


def record() -> dict:
    """Versions, commit, UTC time, host name and load average, JSON-serialisable."""
    return {
        "versions": package_versions(),
        "git_commit": git_commit(),
        "date": utc_now(),
        "host": platform.node(),
        "load_average": load_average(),
    }


def header_lines(command: str | None = None) -> list[str]:
    """``#`` lines for the top of a CSV file: dem version, commit, date, host and load.

    Args:
        command: The command line that produced the file, written on its own line if given.

    """
    r = record()
    v = r["versions"]
    lines = [
        f"# dem {v['dem']}, commit {r['git_commit'] or 'unknown'}, {r['date']}",
        f"# {r['host']}, load average {r['load_average']}, numpy {v['numpy']}, "
        f"numba {v['numba']}, python {v['python']}",
    ]
    if command:
        lines.append(f"# command: {command}")
    return lines
