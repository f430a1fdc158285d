"""A run's output folder: the names dem writes there, the lock, and what ``overwrite`` removes.

The folder holds only what dem made. A link under a name dem writes (``frames``,
``results.h5``, the lock ``.dem-run.lock``) is refused before anything is written, so nothing
is written, truncated or deleted through it. An earlier run is refused unless the caller asks
to overwrite it (then only the files and folders of :data:`RUN_OUTPUTS` are removed, and in
``frames/`` only the VTK files dem names) or to resume it (then its checkpoint must be there).
While a run writes, it holds an exclusive ``flock`` on :data:`LOCK_FILE`, so a second run
into the same folder is refused.
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from dem.errors import InputError
from dem.io.tables import CYCLES_CSV, sidecar_path
from dem.io.vtk import FRAMES_DIR, PVD_NAME

CHECKPOINT = "checkpoint.npz"
SUMMARY = "summary.json"
RESULTS = "results.h5"
#: Files and folders a run writes; only these are removed by ``overwrite``.
RUN_OUTPUTS = (SUMMARY, RESULTS, CHECKPOINT, PVD_NAME, FRAMES_DIR, CYCLES_CSV,
               str(sidecar_path(Path(CYCLES_CSV))))  # fmt: skip
#: Lock file a run holds in its output folder while it writes there (``fcntl.flock``).
LOCK_FILE = ".dem-run.lock"
#: The files dem writes into ``frames/`` (:mod:`dem.io.vtk`); nothing else there is removed.
FRAME_FILE_RE = re.compile(r"(particles_\d{6}|grains_\d{6}|trough_\d{6}|trough)\.vtp")


def prepare_output(out_dir: Path, *, overwrite: bool, resume: bool) -> None:
    """Refuse to overwrite an earlier run silently; clear it only when asked to.

    A link under a name dem writes (a planted ``frames`` -> somewhere else) is refused in every
    mode: dem neither writes into nor deletes through a link it did not make.
    """
    refuse_links(out_dir)
    earlier = [name for name in RUN_OUTPUTS if (out_dir / name).exists()]
    if resume:
        if not (out_dir / CHECKPOINT).exists():
            raise InputError(
                "--resume", str(out_dir), f"needs {CHECKPOINT} of an interrupted run in the folder"
            )
        return
    if earlier and not overwrite:
        raise InputError(
            "--out",
            str(out_dir),
            f"holds an earlier run ({', '.join(earlier)}): choose another --out, pass "
            "--overwrite to replace it, or --resume an interrupted run",
        )
    for name in earlier:  # all checked before anything is removed
        if (out_dir / name).is_dir() != (name == FRAMES_DIR):
            raise InputError(
                "--out", str(out_dir), f"a run folder ({name} here is not what dem writes "
                "under that name: move it away)",
            )  # fmt: skip
    for name in earlier:
        path = out_dir / name
        remove_frames(path) if name == FRAMES_DIR else path.unlink()
    out_dir.mkdir(parents=True, exist_ok=True)


def refuse_links(out_dir: Path) -> None:
    """Refuse a symbolic link at any name dem writes in ``out_dir`` (checked before any change)."""
    frames = out_dir / FRAMES_DIR
    inside = []
    if frames.is_dir() and not frames.is_symlink():  # the frames dem names, planted as links
        inside = [f"{FRAMES_DIR}/{p.name}" for p in frames.iterdir()
                  if p.is_symlink() and FRAME_FILE_RE.fullmatch(p.name)]  # fmt: skip
    for name in (*RUN_OUTPUTS, *inside):
        path = out_dir / name
        if path.is_symlink():
            raise InputError(
                "--out", str(path), "a file or folder of dem's own, not a link (dem never writes "
                "or deletes through a link it did not make): remove the link or choose another "
                "--out",
            )  # fmt: skip


def remove_frames(frames: Path) -> None:
    """Remove the VTK files dem wrote into ``frames``, by name.

    Anything else stays (a link too, even under a frame's name), and so does the folder if
    anything is left in it.
    """
    for path in frames.iterdir():
        if not path.is_symlink() and path.is_file() and FRAME_FILE_RE.fullmatch(path.name):
            path.unlink()
    if not any(frames.iterdir()):
        frames.rmdir()


@contextmanager
def locked(out_dir: Path) -> Iterator[None]:
    """Hold the lock of ``out_dir`` (:func:`lock_output`) while the ``with`` block runs.

    On the way out the lock file is removed (if it is still the one this run made) and
    released; a folder this call made and nothing was written into is removed too, so a run
    refused before it wrote anything leaves no folder.
    """
    made = not out_dir.exists()
    lock = lock_output(out_dir)
    try:
        yield
    finally:
        if same_file(out_dir / LOCK_FILE, lock):  # still held: no one else has it
            (out_dir / LOCK_FILE).unlink()
        lock.close()
        if made and out_dir.is_dir() and not any(out_dir.iterdir()):
            out_dir.rmdir()  # a run refused before it wrote anything leaves no folder


def lock_output(out_dir: Path):
    """Hold an exclusive lock on ``out_dir``: a second run into the same folder is refused.

    Returns the open lock file (closing it releases the lock; the kernel releases it too if the
    process dies). The lock file is made afresh (``O_EXCL``) and written only then; one left by
    a run that died (its lock gone with it) is removed and made again, so it never blocks a new
    run. It is opened without following a link (``O_NOFOLLOW``): a link planted under its name
    is refused (exit 2) and its target is neither written nor truncated.
    """
    import fcntl

    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / LOCK_FILE
    cloexec = getattr(os, "O_CLOEXEC", 0)
    while True:
        created = True
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | cloexec, 0o644)
        except FileExistsError:
            created = False
            try:
                fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW | cloexec)
            except FileNotFoundError:  # the run before removed it between our two opens
                continue
            except OSError as err:  # ELOOP: a link; EISDIR: a folder
                raise _lock_refused(path, err) from None
        stream = os.fdopen(fd, "r+")  # noqa: SIM115 - held until the run ends
        if not stat.S_ISREG(os.fstat(fd).st_mode):  # a FIFO or a device under the lock's name
            stream.close()
            raise _lock_refused(path, None)
        try:
            fcntl.flock(stream, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = stream.read(200).strip() or "another process"
            stream.close()
            raise InputError(
                "--out", str(out_dir), f"a folder no other run is writing ({holder} is writing "
                "it now: wait for it, or choose another --out)",
            ) from None  # fmt: skip
        if same_file(path, stream):
            if created:
                break
            os.unlink(path)  # a stale lock of a run that died: made again, never written into
        stream.close()
    stream.write(f"dem run pid {os.getpid()}\n")
    stream.flush()
    return stream


def same_file(path: Path, stream) -> bool:
    """Whether ``path`` (not followed if a link) is the file ``stream`` has open."""
    try:
        return os.lstat(path).st_ino == os.fstat(stream.fileno()).st_ino
    except FileNotFoundError:
        return False


def _lock_refused(path: Path, err: OSError | None) -> InputError:
    what = "a link" if path.is_symlink() else "not a plain file"
    if err is not None and not path.is_symlink():
        what = err.strerror or what
    return InputError(
        "--out", str(path), f"dem's own lock file ({what} here: dem does not open a lock it did "
        "not make; remove it, or choose another --out)",
    )  # fmt: skip
