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

With ``output.contacts`` every frame also lists its contacts (:mod:`dem.io.contacts`), stacked::

    /contacts/start         (F + 1,) int64: frame k's contacts are rows start[k] .. start[k + 1]
    /contacts/kind          (C,) int8: 0 pair, 1 floor, 2 side wall y-, 3 side wall y+, 4 back
    /contacts/i, /contacts/j (C,) int64: the spheres (their frame rows; j = -1 for a wall)
    /contacts/point         (C, 3) m, the middle of the overlap; /contacts/normal (C, 3) unit,
                            from j (or the wall) to i
    /contacts/normal_force  (C,) N on i (positive pushes); /contacts/tangential_force (C, 3) N
    /contacts/overlap       (C,) m
    /contacts/<load>        (F,) or (F, 3), N: the trough's loads summed per frame
                            (floor_normal_force, side_wall_normal_force, back_wall_normal_force,
                            floor_force_on_grains, wall_force_on_grains; :func:`dem.io.contacts.
                            wall_loads`), so the floor's normal force over a cycle is one column

A run whose grain count changes (a finite feeder: grains leave at the discharge and are fed at
the back) writes format version 3, the frames ragged: one row per sphere and frame, stacked::

    /frames/start           (F + 1,) int64: frame k holds rows start[k] .. start[k + 1]
    /frames/positions       (S, 3), /frames/velocity (S, 3), /frames/contact_count (S,),
    /frames/radius (S,), /frames/grain_id (S,): the grain's lasting id (fed grains get new ones)
    /frames/grain_index     (S,) int64: the grain's index within its frame (orientation rows)
    /frames/body_start      (F + 1,) int64, clump runs: frame k's clumps are rows
                            body_start[k] .. body_start[k + 1] of /frames/orientation (Bsum, 4)

Versions: 1 has no ``orientation`` and no ``git_commit``; 2 adds them; 3 is 2 with ragged
frames. :func:`read_results` (:mod:`dem.io.hdf5_read`) reads all three (``orientation`` is None
for version 1 and for plain spheres) and refuses any other; :class:`~dem.io.hdf5_read.Frames`
gives every frame the same dict.

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
such a viewer sees the file as it was when it opened it. The room checks and the guarded file
are :mod:`dem.io.hdf5_guard`.
"""

from __future__ import annotations

import datetime
import json
from collections.abc import Mapping
from pathlib import Path

import h5py
import numpy as np
from numpy.typing import ArrayLike

from dem.errors import InputError
from dem.io.contacts import CONTACT_ROW_NAMES, WALL_LOAD_NAMES, wall_loads
from dem.io.hdf5_guard import writing
from dem.io.hdf5_read import FRAME_VECTORS, read_results  # noqa: F401  (re-exported: README)
from dem.provenance import git_commit, package_versions  # noqa: F401  (re-exported)

FORMAT_VERSION = 2
#: The layout of runs whose grain count changes (ragged frames).
RAGGED_VERSION = 3
CYCLE_CHUNK = 256


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
        with writing(self.path, "w") as f:
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
        with writing(self.path, "a") as f:
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
        per_frame: Mapping[str, ArrayLike] | None = None,
        contacts: Mapping[str, np.ndarray] | None = None,
    ) -> None:
        """Append one frame to ``/frames`` (and its contacts to ``/contacts``).

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
            contacts: The frame's contact rows (:meth:`dem.engine.simulation.Simulation.
                contact_snapshot`), stored in ``/contacts`` with the trough's loads; the first
                frame decides whether a file holds contacts (every later frame then gives them).

        """
        self._check_open()
        if self.ragged:
            self._append_ragged(time, positions, velocity, radius, grain_id, contact_count,
                                orientation, grain_index, per_frame or {}, contacts)  # fmt: skip
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
        need += _contacts_bytes(contacts)
        with writing(self.path, "a", need) as f:
            _append_contacts(f, k, contacts)
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
                for name in FRAME_VECTORS:
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
                       orientation, grain_index, per_frame, contacts) -> None:  # fmt: skip
        """Append one frame of a ragged file (format version 3)."""
        pos = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        n = pos.shape[0]
        rows: dict[str, np.ndarray] = {
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
        need += _contacts_bytes(contacts)
        with writing(self.path, "a", need) as f:
            _append_contacts(f, k, contacts)
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
        with writing(self.path, "a") as f:
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
                for name in (*FRAME_VECTORS, "contact_count", "time"):
                    frames[name].resize(n_frames, axis=0)
                self._n_spheres = int(frames["radius"].shape[0])
                self._n_bodies = 0
                if "orientation" in frames:
                    frames["orientation"].resize(n_frames, axis=0)
                    self._n_bodies = int(frames["orientation"].shape[1])
            if "contacts" in f:
                _trim_contacts(f["contacts"], n_frames)
            f.attrs["complete"] = False
        self._cycle_keys = keys or None
        self._n_cycles = n_cycles
        self._n_frames = n_frames

    def flush(self) -> None:
        """Nothing to do: every append closes (and so flushes) the file; kept for callers."""

    def close(self) -> Path:
        """Mark the file complete; further appends raise. Returns the path."""
        if not self._closed:
            with writing(self.path, "a") as f:
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


#: The rows of a contact snapshot that ``/contacts`` stores, with their dtypes.
CONTACT_ROWS = dict(
    zip(
        CONTACT_ROW_NAMES,
        (np.int8, np.int64, np.int64, np.float64, np.float64, np.float64, np.float64, np.float64),
        strict=True,
    )
)


def _contacts_bytes(contacts) -> int:
    return 0 if contacts is None else sum(np.asarray(contacts[n]).nbytes for n in CONTACT_ROWS)


def _append_contacts(f: h5py.File, k: int, contacts) -> None:
    """Append frame k's contact rows and loads to ``/contacts`` (module docstring)."""
    if ("contacts" in f) != (contacts is not None) and (k > 0 or "contacts" in f):
        raise ValueError("every frame of a run gives its contacts, or none does")
    if contacts is None:
        return
    rows = {n: np.asarray(contacts[n], dtype=t) for n, t in CONTACT_ROWS.items()}
    loads = wall_loads(contacts)
    if "contacts" not in f:
        g = f.create_group("contacts")
        opts = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
        for name, data in rows.items():
            shape = data.shape[1:]
            g.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape), dtype=data.dtype,
                             chunks=(4096, *shape), **opts)  # fmt: skip
        for name, value in loads.items():
            shape = np.shape(value)
            g.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape), dtype=np.float64,
                             chunks=(CYCLE_CHUNK, *shape))  # fmt: skip
        g.create_dataset("start", data=np.zeros(1, np.int64), maxshape=(None,),
                         chunks=(CYCLE_CHUNK,))  # fmt: skip
    g = f["contacts"]
    c0 = int(g["start"][k])
    n = rows["kind"].shape[0]
    for name, data in rows.items():
        g[name].resize(c0 + n, axis=0)
        g[name][c0:] = data
    for name, value in loads.items():
        g[name].resize(k + 1, axis=0)
        g[name][k] = value
    g["start"].resize((k + 2,))
    g["start"][k + 1] = c0 + n


def _trim_contacts(g: h5py.Group, n_frames: int) -> None:
    """Cut ``/contacts`` back to its first n_frames frames (a resumed run)."""
    n_frames = min(n_frames, g["start"].shape[0] - 1)
    rows = int(g["start"][n_frames])
    for name in CONTACT_ROWS:
        g[name].resize(rows, axis=0)
    for name in WALL_LOAD_NAMES:
        g[name].resize(n_frames, axis=0)
    g["start"].resize((n_frames + 1,))


def check_resumable(path: Path, n_cycles: int, n_frames: int, *, ragged: bool) -> None:
    """Refuse, before a resumed run fills its trough, a results.h5 it could not continue.

    The file must open, be of the format this dem writes (``ragged``: a finite feeder's), and
    hold at least the ``n_cycles`` rows and ``n_frames`` frames the checkpoint counted (the run
    trims it back to them). Otherwise :class:`InputError` naming the file and ``--overwrite``.
    """
    expected = RAGGED_VERSION if ragged else FORMAT_VERSION

    def refuse(why: str) -> InputError:
        return InputError(
            "--resume", str(path), f"a results.h5 the interrupted run can continue ({why}): "
            "run it again from the start with --overwrite",
        )  # fmt: skip

    try:
        with h5py.File(path, "r", locking=False) as f:
            version = int(f.attrs.get("format_version", -1))
            if version != expected:
                raise refuse(f"format version {version}, not {expected}")
            cycles, frames = f["cycles"], f["frames"]
            rows = [int(cycles[k].shape[0]) for k in cycles]
            if n_cycles and (not rows or min(rows) < n_cycles):
                raise refuse(f"{min(rows, default=0)} cycle rows, the checkpoint counted "
                             f"{n_cycles}")  # fmt: skip
            held = int(frames["time"].shape[0]) if "time" in frames else 0
            if held < n_frames:
                raise refuse(f"{held} frames, the checkpoint counted {n_frames}")
    except InputError:
        raise
    except FileNotFoundError:
        raise refuse("it is missing") from None
    except (OSError, KeyError, ValueError, TypeError) as exc:
        raise refuse(f"HDF5 cannot read it: {exc}") from None


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
