"""``results.h5``: the self-describing record of a run, written incrementally.

Layout (format version 2; SI units)::

    /                       attributes:
        format_version      int, 2
        seed                int, the random seed of the fill
        timestep            float, s
        case_json           str, the resolved case as JSON (complete; the record of truth)
        created_utc         str, ISO 8601
        complete            bool, False until ResultsWriter.close() ran (False: killed run)
        git_commit          str, the dem checkout's commit (:func:`dem.provenance.git_commit`,
                            ``+`` when dem/ had uncommitted changes); absent outside a checkout
    /case/                  the resolved case as nested groups of attributes: one group per
                            table ([trough] -> /case/trough), one attribute per key; None values
                            are left out (case_json has them), lists become arrays
    /versions/              attributes dem, numpy, numba, h5py, python (version strings)
    /cycles/<key>           (C,) one row per drive cycle, one resizable 1-D dataset per key given
                            to ResultsWriter.append_cycle (e.g. cycle, time s, mean_velocity m/s,
                            kinetic_energy J, contacts); int keys int64, the rest float64
    /frames/time            (F,) float64, s
    /frames/positions       (F, N, 3) float64, m, trough frame
    /frames/velocity        (F, N, 3) float64, m/s, relative to the trough
    /frames/contact_count   (F, N) int32
    /frames/orientation     (F, B, 4) float64, clump runs only: unit quaternions (w, x, y, z),
                            body -> trough frame, of the B clumps; sphere s belongs to clump
                            grain_id[s] (the quaternion the VTK frames show per sphere)
    /frames/radius          (N,) float64, m (written once)
    /frames/grain_id        (N,) int64 (written once)

A run whose grain count changes (a finite feeder: grains leave at the discharge and are fed at
the back) writes format version 3, the frames ragged: one row per sphere and frame, stacked::

    /frames/start           (F + 1,) int64: frame k holds rows start[k] .. start[k + 1]
    /frames/positions       (S, 3), /frames/velocity (S, 3), /frames/contact_count (S,),
    /frames/radius (S,), /frames/grain_id (S,): the grain's lasting id (fed grains get new ones)
    /frames/grain_index     (S,) int64: the grain's index within its frame (orientation rows)
    /frames/body_start      (F + 1,) int64, clump runs: frame k's clumps are rows
                            body_start[k] .. body_start[k + 1] of /frames/orientation (Bsum, 4)

Versions: 1 has no ``orientation`` and no ``git_commit``; 2 adds them; 3 is 2 with ragged
frames. :func:`read_results` reads all three (``orientation`` is None for version 1 and for
plain spheres) and refuses any other; :class:`Frames` gives every frame the same dict.

Frame datasets are chunked one frame per chunk and gzip-compressed (with the shuffle filter);
cycle datasets are chunked by 256 rows. Both grow along their first axis.

Crash safety: the writer keeps no HDF5 handle open between calls. Each append opens the file,
resizes and writes, and closes it again (closing flushes the metadata), so a run killed between
two appends leaves a complete, closed file holding every cycle and frame appended so far, and a
reader may open the file at any time between appends (no SWMR needed). ``/frames/time`` is
written last within an append, and :func:`read_results` counts a frame only when every frame
dataset holds it. A kill during an append (a few milliseconds of each cycle) is not covered: HDF5
without SWMR gives no guarantee for a file whose metadata was being written. Opening and closing
costs a few milliseconds, negligible next to a cycle. The writer does not take HDF5's file lock,
so a viewer that holds the file open (HDFView, h5py) cannot make an append fail and stop the run;
such a viewer sees the file as it was when it opened it.
"""

from __future__ import annotations

import contextlib
import datetime
import errno
import io
import json
import os
import re
import shutil
from collections.abc import Mapping
from pathlib import Path

import h5py
import numpy as np

try:
    import resource
except ImportError:  # not on Windows: no file size limit to check
    resource = None

from dem.errors import InputError
from dem.provenance import git_commit, package_versions  # package_versions: re-exported too

FORMAT_VERSION = 2
#: Free bytes results.h5 keeps in reserve beyond a write's own data (HDF5's metadata and chunk
#: allocation): below it a write is refused rather than risked (:func:`_writing`).
HDF5_FREE_MARGIN = 1 << 20
#: The layout of runs whose grain count changes (ragged frames).
RAGGED_VERSION = 3
#: Layout versions :func:`read_results` understands.
READABLE_VERSIONS = (1, 2, 3)
CYCLE_CHUNK = 256
_FRAME_VECTORS = ("positions", "velocity")


class ResultsWriter:
    """Write ``results.h5`` incrementally (layout in the module docstring).

    The file is created (overwritten) with the metadata, the git commit of the dem checkout
    included, when the writer is constructed.

    Args:
        path: File to write.
        case: The resolved case as a nested dict (tables -> dicts); values JSON-serialisable or
            paths (written as strings).
        versions: Package versions, e.g. :func:`package_versions`.
        seed: Random seed.
        timestep: Time step, s.
        format_version: Layout version written to the file.
        resume_at: (cycles, frames) already in an interrupted file at ``path``: reopen it,
            trimmed to that many rows, instead of starting a new file.
        ragged: The grain count may change from frame to frame: ragged frames (format version
            3, see the module docstring).

    """

    def __init__(
        self,
        path: Path,
        *,
        case: dict,
        versions: dict,
        seed: int,
        timestep: float,
        format_version: int = FORMAT_VERSION,
        resume_at: tuple[int, int] | None = None,
        ragged: bool = False,
    ):
        self.path = Path(path)
        self.ragged = bool(ragged)
        if self.ragged:
            format_version = RAGGED_VERSION
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._cycle_keys: tuple[str, ...] | None = None
        self._n_cycles = 0
        self._n_frames = 0
        self._n_spheres: int | None = None
        self._n_bodies: int | None = None  # clumps in /frames/orientation, 0 for none
        self._closed = False
        if resume_at is not None:
            self._resume(*resume_at)
            return
        with _writing(self.path, "w") as f:
            f.attrs["format_version"] = int(format_version)
            f.attrs["seed"] = int(seed)
            f.attrs["timestep"] = float(timestep)
            f.attrs["case_json"] = json.dumps(case, default=str, sort_keys=True)
            f.attrs["created_utc"] = datetime.datetime.now(datetime.UTC).isoformat()
            f.attrs["complete"] = False
            commit = git_commit()
            if commit is not None:
                f.attrs["git_commit"] = commit
            _write_attr_tree(f.create_group("case"), case)
            g = f.create_group("versions")
            for key, value in versions.items():
                g.attrs[str(key)] = str(value)
            f.create_group("cycles")
            f.create_group("frames")

    def append_cycle(self, **stats: float) -> None:
        """Append one row to ``/cycles``; the first call fixes the keys, later calls repeat them.

        Args:
            **stats: Scalar per key (int or float), e.g. ``cycle=3, time=0.05,
                mean_velocity=0.012``.

        """
        self._check_open()
        if not stats:
            raise ValueError("append_cycle needs at least one statistic")
        values = {k: np.asarray(v) for k, v in stats.items()}
        for k, v in values.items():
            if v.ndim != 0 or v.dtype.kind not in "biuf":
                raise ValueError(f"cycle statistic {k!r} must be a real scalar, got {v!r}")
        keys = tuple(stats)
        if self._cycle_keys is not None and set(keys) != set(self._cycle_keys):
            raise ValueError(
                f"append_cycle keys {sorted(keys)} differ from the first row's "
                f"{sorted(self._cycle_keys)}"
            )
        row = self._n_cycles
        with _writing(self.path, "a") as f:
            g = f["cycles"]
            if self._cycle_keys is None:
                for k, v in values.items():
                    dtype = np.int64 if v.dtype.kind in "biu" else np.float64
                    g.create_dataset(
                        k, shape=(0,), maxshape=(None,), dtype=dtype, chunks=(CYCLE_CHUNK,)
                    )
                self._cycle_keys = keys
            for k, v in values.items():
                d = g[k]
                d.resize((row + 1,))
                d[row] = v
        self._n_cycles += 1

    def append_frame(
        self,
        time: float,
        positions: np.ndarray,
        velocity: np.ndarray,
        radius: np.ndarray | None = None,
        grain_id: np.ndarray | None = None,
        contact_count: np.ndarray | None = None,
        orientation: np.ndarray | None = None,
        grain_index: np.ndarray | None = None,
        per_frame: Mapping[str, np.ndarray] | None = None,
    ) -> None:
        """Append one frame to ``/frames``.

        Args:
            time: Simulated time, s.
            positions: Sphere centres in the trough frame, (N, 3), m.
            velocity: Velocities relative to the trough, (N, 3), m/s.
            radius: (N,), m; stored with the first frame (required then), ignored afterwards.
            grain_id: Grain index of each sphere, (N,); stored with the first frame
                (default 0..N-1), ignored afterwards.
            contact_count: Contacts per sphere, (N,) int (default zeros).
            orientation: Unit quaternions (w, x, y, z) of the clumps, body -> trough frame,
                (B, 4), indexed by ``grain_id``; None for plain spheres. The first frame decides
                whether a file holds orientations: every later frame must then give them too (or
                none).
            grain_index: Ragged files: each sphere's grain within this frame, (N,), indexing
                ``orientation``; ``grain_id`` is then the grain's lasting id, given every frame.
            per_frame: Ragged files: more per-frame records, name -> array of a fixed shape,
                stored as ``/frames/<name>`` (F, ...) (a feeder's grain balance).

        """
        self._check_open()
        if self.ragged:
            self._append_ragged(time, positions, velocity, radius, grain_id, contact_count,
                                orientation, grain_index, per_frame or {})  # fmt: skip
            return
        pos = np.asarray(positions, dtype=np.float64)
        if pos.ndim != 2 or pos.shape[1] != 3:
            raise ValueError(f"positions must have shape (N, 3), got {pos.shape}")
        n = pos.shape[0]
        if self._n_spheres is not None and n != self._n_spheres:
            raise ValueError(f"frame has {n} spheres, earlier frames {self._n_spheres}")
        vel = np.asarray(velocity, dtype=np.float64)
        if vel.shape != (n, 3):
            raise ValueError(f"velocity must have shape ({n}, 3), got {vel.shape}")
        cc = np.zeros(n, np.int32) if contact_count is None else np.asarray(contact_count)
        if cc.shape != (n,):
            raise ValueError(f"contact_count must have shape ({n},), got {cc.shape}")
        q = None if orientation is None else np.asarray(orientation, dtype=np.float64)
        if q is not None and (q.ndim != 2 or q.shape[1] != 4 or q.shape[0] < 1):
            raise ValueError(f"orientation must have shape (B, 4), got {q.shape}")
        if self._n_bodies is not None and (0 if q is None else q.shape[0]) != self._n_bodies:
            raise ValueError(
                f"orientation must have shape ({self._n_bodies}, 4) as in the first frame, got "
                f"{None if q is None else q.shape}"
            )
        k = self._n_frames
        need = pos.nbytes + vel.nbytes + cc.nbytes + (0 if q is None else q.nbytes)
        with _writing(self.path, "a", need) as f:
            g = f["frames"]
            if self._n_spheres is None:
                if radius is None:
                    raise ValueError("the first frame needs radius (N,)")
                r = np.asarray(radius, dtype=np.float64)
                gid = np.arange(n) if grain_id is None else np.asarray(grain_id)
                if r.shape != (n,) or gid.shape != (n,):
                    raise ValueError(f"radius and grain_id must have shape ({n},)")
                if q is not None and n and (gid.min() < 0 or gid.max() >= q.shape[0]):
                    raise ValueError(
                        f"orientation has {q.shape[0]} clumps; grain_id must lie in "
                        f"[0, {q.shape[0]})"
                    )
                g.create_dataset("radius", data=r)
                g.create_dataset("grain_id", data=gid.astype(np.int64))
                opts = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
                for name in _FRAME_VECTORS:
                    g.create_dataset(
                        name, shape=(0, n, 3), maxshape=(None, n, 3), dtype=np.float64,
                        chunks=(1, max(n, 1), 3), **opts,
                    )  # fmt: skip
                g.create_dataset(
                    "contact_count", shape=(0, n), maxshape=(None, n), dtype=np.int32,
                    chunks=(1, max(n, 1)), **opts,
                )  # fmt: skip
                if q is not None:
                    b = q.shape[0]
                    g.create_dataset(
                        "orientation", shape=(0, b, 4), maxshape=(None, b, 4), dtype=np.float64,
                        chunks=(1, b, 4), **opts,
                    )  # fmt: skip
                g.create_dataset(
                    "time", shape=(0,), maxshape=(None,), dtype=np.float64, chunks=(CYCLE_CHUNK,)
                )
                self._n_spheres = n
                self._n_bodies = 0 if q is None else q.shape[0]
            rows = [("positions", pos), ("velocity", vel), ("contact_count", cc)]
            if q is not None:
                rows.append(("orientation", q))
            for name, data in rows:
                d = g[name]
                d.resize(k + 1, axis=0)
                d[k] = data
            g["time"].resize((k + 1,))
            g["time"][k] = float(time)
        self._n_frames += 1

    def _append_ragged(self, time, positions, velocity, radius, grain_id, contact_count,
                       orientation, grain_index, per_frame) -> None:  # fmt: skip
        """Append one frame of a ragged file (format version 3)."""
        pos = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        n = pos.shape[0]
        rows = {
            "positions": pos,
            "velocity": np.asarray(velocity, dtype=np.float64).reshape(n, 3),
            "contact_count": (np.zeros(n, np.int32) if contact_count is None
                              else np.asarray(contact_count, dtype=np.int32).reshape(n)),
            "radius": np.asarray(radius, dtype=np.float64).reshape(n),
            "grain_id": np.asarray(grain_id, dtype=np.int64).reshape(n),
            "grain_index": (np.arange(n) if grain_index is None
                            else np.asarray(grain_index)).astype(np.int64).reshape(n),
        }  # fmt: skip
        q = None if orientation is None else np.asarray(orientation, dtype=np.float64)
        k = self._n_frames
        opts = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
        need = sum(a.nbytes for a in rows.values()) + (0 if q is None else q.nbytes)
        with _writing(self.path, "a", need) as f:
            g = f["frames"]
            if "start" not in g:
                for name, data in rows.items():
                    shape = data.shape[1:]
                    g.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape),
                                     dtype=data.dtype, chunks=(4096, *shape), **opts)  # fmt: skip
                g.create_dataset("start", data=np.zeros(1, np.int64), maxshape=(None,),
                                 chunks=(CYCLE_CHUNK,))  # fmt: skip
                if q is not None:
                    g.create_dataset("orientation", shape=(0, 4), maxshape=(None, 4),
                                     dtype=np.float64, chunks=(4096, 4), **opts)  # fmt: skip
                    g.create_dataset("body_start", data=np.zeros(1, np.int64),
                                     maxshape=(None,), chunks=(CYCLE_CHUNK,))  # fmt: skip
                g.create_dataset(
                    "time", shape=(0,), maxshape=(None,), dtype=np.float64, chunks=(CYCLE_CHUNK,)
                )
                for name, value in per_frame.items():
                    value = np.asarray(value)
                    shape = value.shape
                    g.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape),
                                     dtype=value.dtype, chunks=(CYCLE_CHUNK, *shape))  # fmt: skip
                g.attrs["per_frame"] = json.dumps(sorted(per_frame))
            if sorted(per_frame) != json.loads(g.attrs["per_frame"]):
                raise ValueError(
                    f"per_frame keys {sorted(per_frame)} differ from the first frame's"
                )
            for name, value in per_frame.items():
                g[name].resize(k + 1, axis=0)
                g[name][k] = value
            if ("orientation" in g) != (q is not None):
                raise ValueError("every frame of a clump run gives orientation, or none does")
            s0 = int(g["start"][k])
            for name, data in rows.items():
                d = g[name]
                d.resize(s0 + n, axis=0)
                d[s0:] = data
            g["start"].resize((k + 2,))
            g["start"][k + 1] = s0 + n
            if q is not None:
                b0 = int(g["body_start"][k])
                g["orientation"].resize(b0 + q.shape[0], axis=0)
                g["orientation"][b0:] = q
                g["body_start"].resize((k + 2,))
                g["body_start"][k + 1] = b0 + q.shape[0]
            g["time"].resize((k + 1,))
            g["time"][k] = float(time)
        self._n_frames += 1

    def _resume(self, n_cycles: int, n_frames: int) -> None:
        """Reopen an interrupted file, trimmed back to its first n_cycles rows and n_frames."""
        with _writing(self.path, "a") as f:
            version = int(f.attrs.get("format_version", -1))
            expected = RAGGED_VERSION if self.ragged else FORMAT_VERSION
            if version != expected:
                raise InputError(
                    "format_version",
                    version,
                    f"a run continues only in a results.h5 of format version {expected} "
                    "(an older dem began it): run it again with --overwrite",
                    source=str(self.path),
                )
            cycles, frames = f["cycles"], f["frames"]
            keys = tuple(cycles.keys())
            for key in keys:
                cycles[key].resize((n_cycles,))
            if "start" in frames:  # ragged
                rows = int(frames["start"][n_frames])
                for name in ("positions", "velocity", "contact_count", "radius", "grain_id",
                             "grain_index"):  # fmt: skip
                    frames[name].resize(rows, axis=0)
                frames["start"].resize((n_frames + 1,))
                frames["time"].resize((n_frames,))
                for name in json.loads(frames.attrs.get("per_frame", "[]")):
                    frames[name].resize(n_frames, axis=0)
                if "orientation" in frames:
                    bodies = int(frames["body_start"][n_frames])
                    frames["orientation"].resize(bodies, axis=0)
                    frames["body_start"].resize((n_frames + 1,))
            elif "time" in frames:
                for name in (*_FRAME_VECTORS, "contact_count", "time"):
                    frames[name].resize(n_frames, axis=0)
                self._n_spheres = int(frames["radius"].shape[0])
                self._n_bodies = 0
                if "orientation" in frames:
                    frames["orientation"].resize(n_frames, axis=0)
                    self._n_bodies = int(frames["orientation"].shape[1])
            f.attrs["complete"] = False
        self._cycle_keys = keys or None
        self._n_cycles = n_cycles
        self._n_frames = n_frames

    def flush(self) -> None:
        """Nothing to do: every append closes (and so flushes) the file; kept for callers."""

    def close(self) -> Path:
        """Mark the file complete; further appends raise. Returns the path."""
        if not self._closed:
            with _writing(self.path, "a") as f:
                f.attrs["complete"] = True
            self._closed = True
        return self.path

    def __enter__(self) -> ResultsWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _check_open(self) -> None:
        if self._closed:
            raise ValueError(f"{self.path} is closed")


class Frames:
    """Lazy access to the frames of a ``results.h5``; each access opens the file read-only.

    ``len(frames)`` is the number of complete frames; ``frames[i]`` (negative i allowed) returns
    a dict with ``time`` (s), ``positions`` (N, 3) m, ``velocity`` (N, 3) m/s, ``contact_count``
    (N,), ``radius`` (N,) m, ``grain_id`` (N,), ``grain_index`` (N,) and ``orientation`` (B, 4)
    (unit quaternions w, x, y, z of the clumps, indexed by ``grain_index``; None for plain
    spheres and version 1). N and B may change from frame to frame in a ragged file (version
    3), where ``grain_id`` is the grain's lasting id; elsewhere the two are the same.
    """

    def __init__(self, path: Path, count: int, time: np.ndarray):
        self.path = Path(path)
        self.count = int(count)
        self.time = time

    def __len__(self) -> int:
        return self.count

    def __getitem__(self, i: int) -> dict:
        i = int(i)
        if i < 0:
            i += self.count
        if not 0 <= i < self.count:
            raise IndexError(f"frame {i} out of range ({self.count} frames)")
        with h5py.File(self.path, "r", locking=False) as f:
            g = f["frames"]
            if "start" in g:  # ragged (format version 3)
                a, b = int(g["start"][i]), int(g["start"][i + 1])
                orientation = None
                if "orientation" in g:
                    c, d = int(g["body_start"][i]), int(g["body_start"][i + 1])
                    orientation = g["orientation"][c:d]
                extra = {k: g[k][i] for k in json.loads(g.attrs.get("per_frame", "[]"))}
                return {
                    **extra,
                    "time": float(g["time"][i]),
                    "positions": g["positions"][a:b],
                    "velocity": g["velocity"][a:b],
                    "contact_count": g["contact_count"][a:b],
                    "radius": g["radius"][a:b],
                    "grain_id": g["grain_id"][a:b],
                    "grain_index": g["grain_index"][a:b],
                    "orientation": orientation,
                }
            return {
                "time": float(g["time"][i]),
                "positions": g["positions"][i],
                "velocity": g["velocity"][i],
                "contact_count": g["contact_count"][i],
                "radius": g["radius"][()],
                "grain_id": g["grain_id"][()],
                "grain_index": g["grain_id"][()],
                "orientation": g["orientation"][i] if "orientation" in g else None,
            }


#: errno values of a write refused for room: a full disk, a file-size limit, a full quota.
NO_ROOM = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)


def _check_room(path: Path, need: int) -> None:
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


class _GuardedFile(io.RawIOBase):
    """results.h5 as HDF5's file driver sees it: after the first failed write, writes go nowhere.

    HDF5 cannot close a file whose write failed (a quota or a disk filled by another process,
    which :func:`_check_room` cannot foresee): the dataset stays in HDF5's table of open objects,
    h5py prints "Exception ignored" tracebacks, and HDF5's own exit handler segfaults closing it
    again (exit 139 after dem's one-line error; h5py 3.16, HDF5 2.0). Here the failed write is
    recorded in :attr:`failed` and reported to HDF5 as done, and every write after it is
    dropped, so HDF5 closes the file and :func:`_writing` raises the recorded error.
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
def _writing(path: Path, mode: str, need: int = 0):
    """``h5py.File(path, mode)`` ("w" or "a") whose write failures raise OSError naming ``path``.

    The room for the write is checked first (:func:`_check_room`: free space, the file size
    limit). Should a write fail all the same (a quota, another process filling the disk), it
    fails in :class:`_GuardedFile`, HDF5 still closes the file, and the system's error (ENOSPC,
    EFBIG, EDQUOT) is raised as OSError naming ``path``. The file is opened without following a
    link (``O_NOFOLLOW``): results.h5 planted as a link to another file is refused, not written
    through.
    """
    path = Path(path)
    _check_room(path, need)
    flags = os.O_RDWR | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0)
    flags |= os.O_CREAT | os.O_TRUNC if mode == "w" else 0
    try:
        raw = _GuardedFile(os.open(path, flags, 0o666))
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


def read_results(path: Path) -> dict:
    """Read a ``results.h5`` (complete or from a killed run) of a version in READABLE_VERSIONS.

    Returns:
        dict with ``case`` (dict, from ``case_json``), ``versions`` (dict of str), ``seed``,
        ``timestep`` (s), ``format_version``, ``git_commit`` (str, None where not recorded),
        ``complete`` (bool), ``cycles`` (dict key -> (C,) array, truncated to the shortest
        column), ``frame_count`` and ``frames`` (:class:`Frames`).

    Raises:
        InputError: The file's ``format_version`` is not one this dem reads (a newer dem wrote
            it, or it is not a dem results file).

    """
    path = Path(path)
    with h5py.File(path, "r", locking=False) as f:
        a = f.attrs
        version = a.get("format_version")
        version = int(version) if version is not None else None
        if version not in READABLE_VERSIONS:
            readable = ", ".join(str(v) for v in READABLE_VERSIONS)
            raise InputError(
                "format_version",
                version,
                f"this dem ({package_versions()['dem']}) reads results.h5 format versions "
                f"{readable} (a newer dem wrote the file, or it is no dem results.h5)",
                source=str(path),
            )
        cycles = {k: d[()] for k, d in f["cycles"].items()}
        if cycles:
            rows = min(len(v) for v in cycles.values())
            cycles = {k: v[:rows] for k, v in cycles.items()}
        g = f["frames"]
        if "start" in g:  # ragged: a frame counts once its start row is written
            count = min(g["time"].shape[0], g["start"].shape[0] - 1)
            time = g["time"][:count]
        elif "time" in g:
            names = ("time", "contact_count", *_FRAME_VECTORS)
            names += ("orientation",) if "orientation" in g else ()
            count = min(g[k].shape[0] for k in names)
            time = g["time"][:count]
        else:
            count, time = 0, np.zeros(0)
        return {
            "case": json.loads(a["case_json"]),
            "versions": {k: str(v) for k, v in f["versions"].attrs.items()},
            "seed": int(a["seed"]),
            "timestep": float(a["timestep"]),
            "format_version": version,
            "git_commit": str(a["git_commit"]) if "git_commit" in a else None,
            "complete": bool(a["complete"]),
            "cycles": cycles,
            "frame_count": count,
            "frames": Frames(path, count, time),
        }


def _write_attr_tree(group: h5py.Group, tree: Mapping) -> None:
    for key, value in tree.items():
        key = str(key)
        if isinstance(value, Mapping):
            _write_attr_tree(group.create_group(key), value)
        elif value is None:
            continue
        elif isinstance(value, bool | int | float | str | np.generic):
            group.attrs[key] = value
        elif isinstance(value, Path):
            group.attrs[key] = str(value)
        elif isinstance(value, list | tuple | np.ndarray):
            arr = np.asarray(value)
            if arr.dtype.kind in "biuf":
                group.attrs[key] = arr
            else:
                group.attrs[key] = json.dumps(value, default=str)
        else:
            group.attrs[key] = str(value)
