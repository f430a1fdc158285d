"""Opening ``results.h5`` for writing so that a full disk leaves it readable.

:func:`writing` opens the file for one append: it first checks the room for the write (free
space, the file size limit: :func:`check_room`), opens the file without following a link, and
hands HDF5 a :class:`GuardedFile` that records the first failed write (a quota, or a disk another
process filled) and drops the writes after it, so that HDF5 can still close the file; the
recorded error is then raised as OSError naming the file. results.h5 thus stays as its last
complete write left it.
"""

from __future__ import annotations

import contextlib
import errno
import io
import os
import re
import shutil
from pathlib import Path

import h5py

try:
    import resource
except ImportError:  # not on Windows: no file size limit to check
    resource = None  # type: ignore[assignment]  # the module, or None where there is none

#: Free bytes results.h5 keeps in reserve beyond a write's own data (HDF5's metadata and chunk
#: allocation): below it a write is refused rather than risked (:func:`writing`).
HDF5_FREE_MARGIN = 1 << 20

#: errno values of a write refused for room: a full disk, a file-size limit, a full quota.
NO_ROOM = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)


def check_room(path: Path, need: int) -> None:
    """Raise OSError (ENOSPC or EFBIG) when a write of ``need`` bytes to ``path`` may not fit.

    Free space below ``need`` plus :data:`HDF5_FREE_MARGIN`, or a file size limit (``ulimit
    -f``, RLIMIT_FSIZE) the file would pass by then: the write is refused before the file is
    opened, so results.h5 stays as its last complete write left it.
    """
    free = shutil.disk_usage(path.parent).free
    if free < need + HDF5_FREE_MARGIN:
        raise OSError(
            errno.ENOSPC,
            f"{os.strerror(errno.ENOSPC)} ({free} bytes free; dem stops writing results.h5 "
            f"below {need + HDF5_FREE_MARGIN} so that it stays readable)",
            str(path),
        )
    limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0] if resource else -1
    if limit not in (-1, getattr(resource, "RLIM_INFINITY", -1)):
        size = path.stat().st_size if path.exists() else 0
        if size + need + HDF5_FREE_MARGIN > limit:
            raise OSError(
                errno.EFBIG,
                f"{os.strerror(errno.EFBIG)} (the file size limit is {limit} bytes, ulimit -f; "
                f"results.h5 holds {size}: dem stops writing it {need + HDF5_FREE_MARGIN} "
                "bytes below the limit so that it stays readable)",
                str(path),
            )


class GuardedFile(io.RawIOBase):
    """results.h5 as HDF5's file driver sees it: after the first failed write, writes go nowhere.

    HDF5 cannot close a file whose write failed (a quota or a disk filled by another process,
    which :func:`check_room` cannot foresee): the dataset stays in HDF5's table of open objects,
    h5py prints "Exception ignored" tracebacks, and HDF5's own exit handler segfaults closing it
    again (exit 139 after dem's one-line error; h5py 3.16, HDF5 2.0). Here the failed write is
    recorded in :attr:`failed` and reported to HDF5 as done, and every write after it is
    dropped, so HDF5 closes the file and :func:`writing` raises the recorded error.
    """

    def __init__(self, fd: int):
        super().__init__()
        self._raw = io.FileIO(fd, "r+", closefd=True)
        self.failed: OSError | None = None

    def readable(self) -> bool:  # noqa: D102
        return True

    def writable(self) -> bool:  # noqa: D102
        return True

    def seekable(self) -> bool:  # noqa: D102
        return True

    def seek(self, offset: int, whence: int = 0) -> int:  # noqa: D102
        return self._raw.seek(offset, whence)

    def tell(self) -> int:  # noqa: D102
        return self._raw.tell()

    def readinto(self, buffer) -> int:  # noqa: D102
        return self._raw.readinto(buffer)

    def write(self, data) -> int:  # noqa: D102
        size = memoryview(data).nbytes
        if self.failed is None:
            try:
                done = 0
                while done < size:  # a short write (the disk filled mid-way) goes on or fails
                    done += self._raw.write(memoryview(data).cast("B")[done:])
            except OSError as err:
                self.failed = err
        return size

    def truncate(self, size: int | None = None) -> int:  # noqa: D102
        if self.failed is None:
            try:
                return self._raw.truncate(size)
            except OSError as err:
                self.failed = err
        return self.tell() if size is None else size

    def flush(self) -> None:  # noqa: D102
        pass  # FileIO is unbuffered

    def close(self) -> None:  # noqa: D102
        if not self.closed:
            self._raw.close()
        super().close()


@contextlib.contextmanager
def writing(path: Path, mode: str, need: int = 0):
    """``h5py.File(path, mode)`` ("w" or "a") whose write failures raise OSError naming ``path``.

    The room for the write is checked first (:func:`check_room`: free space, the file size
    limit). Should a write fail all the same (a quota, another process filling the disk), it
    fails in :class:`GuardedFile`, HDF5 still closes the file, and the system's error (ENOSPC,
    EFBIG, EDQUOT) is raised as OSError naming ``path``. The file is opened without following a
    link (``O_NOFOLLOW``): results.h5 planted as a link to another file is refused, not written
    through.
    """
    path = Path(path)
    check_room(path, need)
    flags = os.O_RDWR | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0)
    flags |= os.O_CREAT | os.O_TRUNC if mode == "w" else 0
    try:
        raw = GuardedFile(os.open(path, flags, 0o666))
    except OSError as err:
        raise OSError(err.errno, err.strerror, str(path)) from None
    try:
        try:
            with h5py.File(raw, "w" if mode == "w" else "r+", locking=False) as f:
                yield f
        except (OSError, RuntimeError) as err:
            if raw.failed is not None:
                raise _as_os_error(raw.failed, path) from err
            raise _as_os_error(err, path) from err
        if raw.failed is not None:
            raise _as_os_error(raw.failed, path)
    finally:
        raw.close()


def _as_os_error(err: Exception, path: Path) -> OSError:
    code = err.errno if isinstance(err, OSError) and err.errno else None
    if code is None:
        found = re.search(r"errno = (\d+)", str(err))
        code = int(found.group(1)) if found else errno.EIO
    message = os.strerror(code) if code != errno.EIO else str(err).splitlines()[0]
    return OSError(code, message, str(path))
