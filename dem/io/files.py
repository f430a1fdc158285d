"""Replacing an output file whole: a reader sees the old file or the new one, never a part.

Every file dem writes whole (summary.json, the ParaView collection and frames, the checkpoint,
a calibrated case.toml) is written to ``NAME.tmp`` beside it and renamed over it. On a full disk
the write fails in the middle, often inside ``close`` where Python's OSError carries no file
name; the helper removes the part-written temporary file and raises an OSError that names the
file being replaced, so ``dem`` can say which file and why in one line.

The temporary file is made afresh (``O_EXCL | O_NOFOLLOW``): a link planted under its name is
removed, never written through, and the rename replaces a link at ``NAME`` itself, not the file
it points to. JSON files are strict JSON (:func:`json_text`): no ``NaN`` or ``Infinity``.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import stat
from collections.abc import Callable
from pathlib import Path


def replace_file(path: Path, write: Callable[[Path], None], suffix: str = ".tmp") -> None:
    """Call ``write(tmp)`` on ``path`` + ``suffix``, then rename it over ``path``.

    ``tmp`` exists, empty, when ``write`` is called: a new file this call made, never a link.

    Raises:
        OSError: The write or the rename failed; the temporary file is gone, ``path`` is as it
            was, and the error's ``filename`` is ``path``.

    """
    path = Path(path)
    tmp = path.with_name(path.name + suffix)
    try:
        _fresh(tmp)
        write(tmp)
        os.replace(tmp, path)
    except BaseException as err:
        with contextlib.suppress(OSError):
            if not tmp.is_dir():
                tmp.unlink()
        if isinstance(err, OSError) and (err.filename is None or Path(err.filename) == tmp):
            raise OSError(err.errno, err.strerror or str(err), str(path)) from err
        raise


def _fresh(tmp: Path) -> None:
    """Make ``tmp`` a new empty file of this process: a leftover (a link too) is removed first."""
    with contextlib.suppress(FileNotFoundError):
        if not stat.S_ISDIR(os.lstat(tmp).st_mode):  # a folder is left alone: O_EXCL refuses it
            os.unlink(tmp)  # a link itself, never its target
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0)
    os.close(os.open(tmp, flags, 0o666))


def replace_text(path: Path, text: str, encoding: str = "utf-8") -> None:
    """:func:`replace_file` for a text file."""
    replace_file(path, lambda tmp: tmp.write_text(text, encoding=encoding))


def finite_or_none(value):
    """``value`` with every non-finite float (NaN, +-inf) in it, nested too, replaced by None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite_or_none(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_or_none(v) for v in value]
    if hasattr(value, "dtype") and hasattr(value, "tolist"):  # numpy scalars and arrays
        return finite_or_none(value.tolist())
    return value


def json_text(value, *, indent: int | None = 2, default=None) -> str:
    """``value`` as strict JSON text (RFC 8259): a value without a number (NaN, inf) is null.

    Python's ``json.dumps`` writes ``NaN`` and ``Infinity``, which are not JSON: a strict
    reader (``jq``, a browser, ``json.loads(..., parse_constant=...)``) refuses the file.
    """
    if default is not None:  # convert what json cannot, then look for non-finite numbers in it
        value = json.loads(json.dumps(value, default=default, allow_nan=True))
    return json.dumps(finite_or_none(value), indent=indent, allow_nan=False)
