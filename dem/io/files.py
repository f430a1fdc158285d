"""Replacing an output file whole: a reader sees the old file or the new one, never a part.

Every file dem writes whole (summary.json, the ParaView collection and frames, the checkpoint,
a calibrated case.toml) is written to ``NAME.tmp`` beside it and renamed over it. On a full disk
the write fails in the middle, often inside ``close`` where Python's OSError carries no file
name; the helper removes the part-written temporary file and raises an OSError that names the
file being replaced, so ``dem`` can say which file and why in one line.

Every file dem writes goes through :func:`replace_file` (or :func:`replace_text`,
:func:`write_input`), every folder it makes inside an output folder through :func:`own_folder`:
dem never writes, truncates or deletes through a link it did not make. A link (live or dangling)
under a name dem writes is refused with an :class:`dem.errors.InputError` naming the option and
the path; commands check their names at the door (:func:`refuse_links`) before any work, and the
writers check again when they write. The temporary file is made afresh (``O_EXCL |
O_NOFOLLOW``): a link planted under its name is removed, never written through, and the rename
would replace a link planted at ``NAME`` after the check, not the file it points to. JSON files
are strict JSON (:func:`json_text`): no ``NaN`` or ``Infinity``.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import stat
from collections.abc import Callable
from pathlib import Path

from dem.errors import InputError
from dem.io.freetext import input_text

#: The option named by a refused link when the caller names none.
OUTPUT_KEY = "--out"


def link_refused(path: Path, key: str = OUTPUT_KEY) -> InputError:
    """The error for a link under a name dem writes (``key``: the option that chose the folder)."""
    return InputError(
        key, str(path), "a file or folder of dem's own, not a link (dem never writes or deletes "
        "through a link it did not make): remove the link or choose another folder",
    )  # fmt: skip


def refuse_links(folder: Path, names, key: str = OUTPUT_KEY) -> None:
    """Refuse a link, live or dangling, at ``folder`` / each of ``names``; before any work.

    ``names`` may hold paths below ``folder`` (``frames/trough.vtp``): each folder on the way
    is checked too.
    """
    folder = Path(folder)
    for name in names:
        path = folder
        for part in Path(name).parts:
            path = path / part
            if path.is_symlink():
                raise link_refused(path, key)


def own_folder(path: Path, key: str = OUTPUT_KEY) -> Path:
    """Make the folder ``path`` (and its parents) where dem writes; a link there is refused.

    The parents are the caller's choice (a folder a user named may be a link); ``path`` itself
    is a name dem chose inside it, and must be dem's own folder or not exist yet.
    """
    path = Path(path)
    if path.is_symlink():
        raise link_refused(path, key)
    if path.exists() and not path.is_dir():
        raise InputError(key, str(path), "a folder (this is a file): move it away")
    path.mkdir(parents=True, exist_ok=True)
    return path


def replace_file(
    path: Path, write: Callable[[Path], object], suffix: str = ".tmp", *, key: str = OUTPUT_KEY
) -> None:
    """Call ``write(tmp)`` on ``path`` + ``suffix``, then rename it over ``path``.

    ``tmp`` exists, empty, when ``write`` is called: a new file this call made, never a link.

    Raises:
        InputError: ``path`` is a link, live or dangling (named by ``key``); nothing is written.
        OSError: The write or the rename failed; the temporary file is gone, ``path`` is as it
            was, and the error's ``filename`` is ``path``.

    """
    path = Path(path)
    if path.is_symlink():
        raise link_refused(path, key)
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


def replace_text(
    path: Path, text: str, encoding: str = "utf-8", *, key: str = OUTPUT_KEY, errors: str = "strict"
) -> None:
    """:func:`replace_file` for a text file."""
    replace_file(path, lambda tmp: tmp.write_text(text, encoding=encoding, errors=errors), key=key)


def append_text(path: Path, text: str, *, key: str = OUTPUT_KEY) -> None:
    """Append ``text`` to dem's own file ``path`` (made by :func:`replace_text`), never to a link.

    Opened without following a link (``O_NOFOLLOW``): a link planted in its place since is
    refused, and its target is not written.
    """
    flags = os.O_WRONLY | os.O_APPEND | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except OSError as err:
        if Path(path).is_symlink():
            raise link_refused(Path(path), key) from None
        raise OSError(err.errno, err.strerror, str(path)) from err
    with os.fdopen(fd, "a", encoding="utf-8") as stream:
        stream.write(text)


def write_input(path: Path, lines, *, key: str = OUTPUT_KEY) -> Path:
    """Write a file LAMMPS or LIGGGHTS reads (a deck, data, molecule, template or STL file).

    Each line made inert (:func:`dem.io.freetext.input_line`: a name cannot start a command),
    written whole (:func:`replace_text`); returns ``path``.
    """
    path = Path(path)
    replace_text(path, input_text(lines), key=key)
    return path


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
