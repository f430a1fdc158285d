"""Reading ``results.h5`` (format versions 1, 2 and 3; layout in :mod:`dem.io.hdf5`).

:func:`read_results` reads the file a run writes, complete or from a killed run, and refuses a
format version it does not know; :class:`Frames` opens the file again for each frame asked for,
so a frame of a run still writing is read as it stands. A frame counts only when every frame
dataset holds it (``/frames/time`` is written last). ``read_results`` is also importable from
:mod:`dem.io.hdf5`, its documented home.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np

from dem.errors import InputError
from dem.io.contacts import CONTACT_ROW_NAMES, WALL_LOAD_NAMES
from dem.provenance import package_versions

#: Layout versions :func:`read_results` understands.
READABLE_VERSIONS = (1, 2, 3)
#: The per-sphere vector datasets of a frame, (N, 3) each.
FRAME_VECTORS = ("positions", "velocity")


class Frames:
    """Lazy access to the frames of a ``results.h5``; each access opens the file read-only.

    ``len(frames)`` is the number of complete frames; ``frames[i]`` (negative i allowed) returns
    a dict with ``time`` (s), ``positions`` (N, 3) m, ``velocity`` (N, 3) m/s, ``contact_count``
    (N,), ``radius`` (N,) m, ``grain_id`` (N,), ``grain_index`` (N,) and ``orientation`` (B, 4)
    (unit quaternions w, x, y, z of the clumps, indexed by ``grain_index``; None for plain
    spheres and version 1). N and B may change from frame to frame in a ragged file (version
    3), where ``grain_id`` is the grain's lasting id; elsewhere the two are the same. A run
    with ``output.contacts`` adds ``contacts``: the frame's contact rows (``kind``, ``i``, ``j``,
    ``point``, ``normal``, ``normal_force``, ``tangential_force``, ``overlap``;
    :mod:`dem.io.contacts`).
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
            frame = self._frame(f["frames"], i)
            if "contacts" in f:
                c = f["contacts"]
                a, b = int(c["start"][i]), int(c["start"][i + 1])
                frame["contacts"] = {k: c[k][a:b] for k in CONTACT_ROW_NAMES}
            return frame

    @staticmethod
    def _frame(g: h5py.Group, i: int) -> dict:
        """Frame i of ``/frames`` (ragged or not), without its contacts."""
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


def read_results(path: Path) -> dict:
    """Read a ``results.h5`` (complete or from a killed run) of a version in READABLE_VERSIONS.

    Returns:
        dict with ``case`` (dict, from ``case_json``), ``versions`` (dict of str), ``seed``,
        ``timestep`` (s), ``format_version``, ``git_commit`` (str, None where not recorded),
        ``complete`` (bool), ``cycles`` (dict key -> (C,) array, truncated to the shortest
        column), ``frame_count`` and ``frames`` (:class:`Frames`), and ``wall_loads``: with
        ``output.contacts`` the trough's loads per frame (name -> (F,) or (F, 3) array, N;
        :func:`dem.io.contacts.wall_loads`), else None.

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
            names: tuple[str, ...] = ("time", "contact_count", *FRAME_VECTORS)
            names += ("orientation",) if "orientation" in g else ()
            count = min(g[k].shape[0] for k in names)
            time = g["time"][:count]
        else:
            count, time = 0, np.zeros(0)
        loads = None
        if "contacts" in f:  # written before the frame's time: a counted frame has its contacts
            c = f["contacts"]
            count = min(count, c["start"].shape[0] - 1)
            time = time[:count]
            loads = {k: c[k][:count] for k in WALL_LOAD_NAMES}
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
            "wall_loads": loads,
        }
