"""Replacing an output file whole: a reader sees the old file or the new one, never a part.

Every file dem rewrites in place (the ParaView collection, the checkpoint, a calibrated
case.toml) is written to ``NAME.tmp`` beside it and renamed over it. On a full disk the write
fails in the middle, often inside ``close`` where Python's OSError carries no file name; the
helper removes the part-written temporary file and raises an OSError that names the file being
replaced, so ``dem`` can say which file and why in one line.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable
from pathlib import Path


def replace_file(path: Path, write: Callable[[Path], None], suffix: str = ".tmp") -> None:
    """Call ``write(tmp)`` on ``path`` + ``suffix``, then rename it over ``path``.

    Raises:
        OSError: The write or the rename failed; the temporary file is gone, ``path`` is as it
            was, and the error's ``filename`` is ``path``.

    """
    path = Path(path)
    tmp = path.with_name(path.name + suffix)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException as err:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(err, OSError) and (err.filename is None or Path(err.filename) == tmp):
            raise OSError(err.errno, err.strerror or str(err), str(path)) from err
        raise


def replace_text(path: Path, text: str, encoding: str = "utf-8") -> None:
    """:func:`replace_file` for a text file."""
    replace_file(path, lambda tmp: tmp.write_text(text, encoding=encoding))
