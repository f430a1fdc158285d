"""Output paths checked before any work: each refused with the option or key and the cause.

A command that will write a file or a folder checks the path first (:func:`writable_path`), so
nothing is computed for output that cannot be written: a file where a folder is wanted or the
reverse, a name or path longer than the system allows, a missing parent folder, a place that is
not writable. :func:`plot_path` does the same for a figure named by a file or a folder.
"""

from __future__ import annotations

import os
from pathlib import Path

from dem.errors import InputError

#: Longest file name and path the guards accept (Linux NAME_MAX and PATH_MAX).
NAME_MAX, PATH_MAX = 255, 4096


def writable_path(key: str, path: str | Path, *, folder: bool) -> Path:
    """``path`` as an output file (``folder`` False) or folder, refused before any work.

    Refused with the key and the cause: a file where a folder is wanted or the reverse, a name
    or path longer than the system allows, or a nearest existing folder that is not writable.
    A file's parent folder must exist (dem does not create it); a folder is created later.
    """
    path = Path(path)
    if len(str(path.absolute())) >= PATH_MAX or any(len(part) > NAME_MAX for part in path.parts):
        raise InputError(key, str(path), f"a path the system allows (names <= {NAME_MAX} "
                         f"characters, paths < {PATH_MAX})")  # fmt: skip
    if path.exists() and path.is_dir() != folder:
        what = "a folder (this is a file)" if folder else "a file name (this is a folder)"
        raise InputError(key, str(path), what)
    parent = path if folder else path.parent
    if not folder and not parent.absolute().is_dir():
        raise InputError(key, str(path), f"a file in an existing folder ({parent} does not exist)")
    base = parent.absolute()
    while not base.exists():
        base = base.parent
    if not base.is_dir():
        raise InputError(key, str(path), f"a path under a folder ({base} is a file)")
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(key, str(path), f"a writable place ({base} is not writable)")
    return path


def output_folder(key: str, given: str | Path | None, default: Path) -> Path:
    """The output folder ``key`` names (``given``), else ``default``; checked before any work.

    Checked by :func:`writable_path`. The folder a user names is theirs, a link too; the
    default is a name dem chose inside the case folder (which may have come from anywhere), so
    a link there is refused.
    """
    if given is None and Path(default).is_symlink():
        from dem.io.files import link_refused

        raise link_refused(Path(default), key)
    return writable_path(key, default if given is None else given, folder=True)


def plot_path(key: str, text: str, default_name: str) -> Path:
    """The figure path that option ``key`` names, refused before any work if it cannot be one.

    A .png file name (any case) is taken as it is; an existing folder gets ``default_name``
    inside it; anything else is refused, since matplotlib would write it with .png added.
    """
    path = Path(text)
    if path.is_dir():
        path = path / default_name
    elif path.suffix.lower() != ".png":
        raise InputError(key, text, f"a .png file name, or an existing folder to write "
                         f"{default_name} in")  # fmt: skip
    if path.is_symlink():  # refused now, not after the work the figure shows
        from dem.io.files import link_refused

        raise link_refused(path, key)
    return writable_path(key, path, folder=False)


def refuse_replacing(key: str, folder: Path, names, what: str = "a deck") -> None:
    """Raise :class:`InputError` where ``folder`` holds any of ``names`` (an earlier export).

    Called before anything is written, unless the caller's ``--overwrite`` asks to replace them.
    A link under one of the names counts, dangling too (it would be replaced): the refusal of
    links themselves, overwrite or not, is :func:`dem.io.files.refuse_links`.
    """
    found = [n for n in names if os.path.lexists(Path(folder) / n)]
    if found:
        raise InputError(
            key, str(folder), f"a folder without {what}: it holds {', '.join(found)}, which the "
            "export would replace (pass --overwrite to replace them)",
        )  # fmt: skip
