"""VTK time series for ParaView: one ``.vtp`` per frame and a ``particles.pvd`` collection.

Layout of an output directory::

    particles.pvd                  ParaView Data collection (open this one)
    frames/particles_NNNNNN.vtp    spheres of frame NNNNNN (binary, zlib-compressed XML PolyData)
    frames/trough.vtp              trough (floor and the two side walls), trough frame: one file
    frames/trough_NNNNNN.vtp       trough of frame NNNNNN, lab frame (it moves with the drive)
    frames/grains_NNNNNN.vtp       clumps (screws) of frame NNNNNN: one point per grain

Every frame is one ``<DataSet timestep="t" part="0" name="spheres" .../>``, one with
``part="1" name="trough"`` and, for clumps, one with ``part="2" name="grains"`` in the
collection, t in seconds of simulated time; ParaView shows the three as named blocks
(``/Root/spheres``, ``/Root/trough``, ``/Root/grains``: Extract Block selects them by name).
pyvista's own PVD reader drops the names (``Block-00``, ``-01``, ``-02``, in that order);
:func:`read_frame` reads one frame with them.
The trough's geometry is that of :class:`dem.scene.trough.Trough`
(:meth:`~dem.scene.trough.Trough.wall_corners`, the kernel's walls), or the triangles of a mesh
trough (``trough.mesh``), built once per writer: in the trough frame it is written once and every
frame refers to it, in the lab frame each frame writes a shifted copy. The collection is rewritten
(atomically, write-then-rename) after every frame, so a run killed half-way leaves a collection that
opens with every frame written so far; :meth:`VTKSeriesWriter.close` writes it a last time.

Frames (coordinates in m):

- Trough frame (default, ``lab_frame=False``): x along the trough (conveying direction), y across,
  z normal to the floor; the floor is z = 0 for 0 <= x <= length, the side walls are
  y = -width/2 and y = +width/2 (README, Symbols). The trough is fixed in this frame, the axes
  are tilted by the inclination alpha against the horizontal (gravity is
  g (-sin alpha, 0, -cos alpha)); the inclination is stored as field data ``inclination_deg``.
- Lab frame (``lab_frame=True``): the same axes, but spheres AND trough are shifted by the drive
  displacement s(t) = A sin(omega t) e of the frame, so the trough is seen to move with the drive.
  Velocities are shifted by the optional ``drive_velocity`` s'(t) when it is given (otherwise they
  stay relative to the trough, as in the trough frame; field data ``velocity_frame`` says which).

Velocities: the trough frame moves with the drive without turning, so a grain's velocity in the
lab is its velocity relative to the trough plus the trough's velocity s'(t) at that time,
v_lab = v_trough + s'(t) (:meth:`dem.scene.trough.Trough.velocity`). Relative to the trough a
conveyed bed moves forward on average but backward for part of every cycle; in the lab it
moves with the trough.

Sphere point data (one value per sphere): ``radius`` (m, float32, the active scalars),
``velocity`` (m/s, float32, 3 components; relative to the trough, or in the lab where
field data ``velocity_frame`` says ``lab``), ``velocity_trough`` and ``speed_trough`` (m/s,
relative to the trough), ``velocity_lab`` and ``speed_lab`` (m/s, in the lab; written when the
drive velocity is given, as a run gives it), ``grain_id``, ``clump_id``, ``contact_count``
(int32), ``grain_type`` (int32, the index of the sphere's ``[[particles.types]]`` table from
0; only for a case of several types or sizes), and ``orientation`` (unit quaternion w, x, y,
z of the sphere's clump, float32, 4 components) when orientations are given.

Grain point data (clumps only, one point per grain at its centre of mass): ``grain_id`` (the
grain's lasting id), ``clump_id`` (its index in the frame, as the spheres give it), ``mass``
(kg), ``axis`` (unit vector, the template's long axis (least moment of inertia) in the trough
frame, pointing from the centre of mass towards the member that reaches farthest along it: a
screw's shank, not its head), ``orientation`` (quaternion w, x, y, z), ``velocity``,
``velocity_trough``, ``velocity_lab``, ``speed_trough``, ``speed_lab`` of the centre of mass
(m/s, as for the spheres), ``angular_velocity`` (rad/s, trough frame), ``contact_count``
(the members' contacts, summed) and ``spheres`` (members per grain).

Positions are float32 (2e-9 m resolution at 0.1 m: enough to look at) and x is wrapped into
[0, length) of the periodic section. Every point is also a vertex cell, so ParaView shows the
points as they are; for spheres use Filters > Glyph with Glyph Type Sphere, Scale Array
``radius`` and Scale Factor 2 (the unit glyph has radius 0.5), or
``mesh.glyph(scale="radius", geom=pyvista.Sphere(radius=1.0), orient=False)`` in pyvista.
``dem/data/paraview/open_run.py`` (:func:`paraview_script`) does that in ParaView.
The blocks are built, and each ``.vtp`` written whole, by :mod:`dem.io.vtk_blocks`.
"""

from __future__ import annotations

import errno
import math
import re
import time
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
import pyvista as pv

from dem.io.files import replace_text
from dem.io.vtk_blocks import (
    contacts_polydata,
    long_axis,
    mesh_polydata,
    point_velocities,
    save_vtp,
    trough_polydata,
)
from dem.io.vtk_blocks import rotate as rotate
from dem.scene.trough import Trough

PVD_NAME = "particles.pvd"
#: The collection is rewritten after a frame when this many seconds have passed since the last
#: rewrite ... (ParaView opening a running series sees the frames of up to then)
PVD_REWRITE_MIN_S = 1.0
#: ... and this many times the last rewrite's own cost (so rewrites cost at most 1/50 of the run)
PVD_REWRITE_FACTOR = 50.0
FRAMES_DIR = "frames"
#: The trough's file in the trough frame, shared by every frame.
TROUGH_FILE = "trough.vtp"
PARTICLE_ARRAYS = ("radius", "velocity", "grain_id", "clump_id", "contact_count")
#: Sphere arrays beside :data:`PARTICLE_ARRAYS`: the velocity in both frames and its magnitude
#: (the ``_lab`` pair when the drive velocity is given).
VELOCITY_ARRAYS = ("velocity_trough", "speed_trough", "velocity_lab", "speed_lab")
#: Point data of the per-grain dataset (clumps).
GRAIN_ARRAYS = ("grain_id", "clump_id", "mass", "axis", "orientation", "velocity",
                "velocity_trough", "velocity_lab", "speed_trough", "speed_lab",
                "angular_velocity", "contact_count", "spheres")  # fmt: skip
#: Block names of the collection's parts, in order (ParaView shows them as /Root/<name>); a
#: frame lists grains only for clumps and contacts only with ``output.contacts``.
BLOCK_NAMES = ("spheres", "trough", "grains", "contacts")
#: A grains file of frame NNNNNN.
GRAINS_FILE_RE = re.compile(r"grains_\d{6}\.vtp")
#: A contacts file of frame NNNNNN.
CONTACTS_FILE_RE = re.compile(r"contacts_\d{6}\.vtp")
#: Point data of the contacts dataset (one point per contact, at the middle of its overlap).
CONTACT_ARRAYS = ("kind", "sphere_i", "sphere_j", "normal", "normal_force",
                  "normal_force_vector", "tangential_force", "tangential_force_magnitude",
                  "overlap")  # fmt: skip


class VTKSeriesWriter:
    """Write sphere frames and the trough as a ParaView time series (see the module docstring).

    Args:
        out_dir: Output directory (created); ``particles.pvd`` goes here, the ``.vtp`` files to
            ``out_dir/frames``.
        trough_length: Length of the periodic section along x, m.
        trough_width: Distance between the side walls, m.
        inclination_deg: Inclination alpha, degrees (stored as field data; axes are not tilted).
        lab_frame: False (default): trough frame, trough fixed. True: spheres and trough shifted
            by the drive displacement given to :meth:`write_frame`.
        wall_height: Height of the drawn side walls, m (default: half the width).
        mesh: A trough mesh (:class:`dem.scene.mesh.TriangleMesh`): drawn instead of the flat walls.
        period: Period along x that positions are wrapped into, m (default ``trough_length``;
            a finite feeder's domain is longer than its trough).
        back_wall: Draw a finite feeder's back wall x = 0 (cell ``part`` 3).

    """

    def __init__(
        self,
        out_dir: Path,
        trough_length: float,
        trough_width: float,
        inclination_deg: float,
        *,
        lab_frame: bool = False,
        wall_height: float | None = None,
        entries: list[tuple[float, str, str]] | None = None,
        mesh=None,
        period: float | None = None,
        back_wall: bool = False,
    ):
        if trough_length <= 0 or trough_width <= 0:
            raise ValueError(
                f"trough length and width must be positive, got {trough_length}, {trough_width}"
            )
        self.out_dir = Path(out_dir)
        self.frames_dir = self.out_dir / FRAMES_DIR
        if self.frames_dir.is_symlink():  # never write into a folder through a link
            raise OSError(errno.ELOOP, "a link where dem writes its frames folder",
                          str(self.frames_dir))  # fmt: skip
        self.frames_dir.mkdir(parents=True, exist_ok=True)
        self.length = float(trough_length)
        self.width = float(trough_width)
        self.inclination_deg = float(inclination_deg)
        self.lab_frame = bool(lab_frame)
        self.wall_height = 0.5 * self.width if wall_height is None else float(wall_height)
        self.pvd_path = self.out_dir / PVD_NAME
        # (time, particles file, trough file); a resumed run passes the entries it had
        self._entries: list[tuple[float, str, str]] = [(t, p, w) for t, p, w in entries or []]
        self._section = Trough(self.length if period is None else float(period), self.width)
        if mesh is None:
            self._trough_mesh = trough_polydata(
                self.length, self.width, self.wall_height, back_wall=back_wall
            )
        else:
            self._trough_mesh = mesh_polydata(mesh.tri, back_wall=back_wall)
        self._trough_written = False  # trough frame: TROUGH_FILE written by this writer
        # the collection lists every frame, so writing it costs O(frames): it is rewritten after
        # a frame only once PVD_REWRITE_FACTOR times its last cost has passed (and on close), so
        # that the rewrites cost at most about 1/PVD_REWRITE_FACTOR of the run, not O(frames^2)
        self._pvd_written_at = -math.inf
        self._pvd_cost = 0.0
        # frames with a grains file: a resumed run's from its files, a new run's none (a grains
        # file an earlier run left is removed: only this writer's are listed)
        self._grain_frames: set[int] = set()
        self._contact_frames: set[int] = set()
        if self._entries:
            self._grain_frames = {
                i for i in range(len(self._entries))
                if (self.frames_dir / _grains_name(i)).is_file()
            }  # fmt: skip
            self._contact_frames = {
                i for i in range(len(self._entries))
                if (self.frames_dir / _contacts_name(i)).is_file()
            }  # fmt: skip
        else:
            for path in self.frames_dir.iterdir():
                stale = GRAINS_FILE_RE.fullmatch(path.name) or CONTACTS_FILE_RE.fullmatch(path.name)
                if stale and not path.is_symlink() and path.is_file():
                    path.unlink()

    @property
    def entries(self) -> list[tuple[float, str, str]]:
        """(time, particles file, trough file) of every frame so far (for a checkpoint)."""
        return list(self._entries)

    @property
    def frame_count(self) -> int:
        """Number of frames written so far."""
        return len(self._entries)

    def write_frame(
        self,
        time: float,
        positions: np.ndarray,
        radius: np.ndarray,
        velocity: np.ndarray,
        grain_id: np.ndarray,
        clump_id: np.ndarray,
        contact_count: np.ndarray,
        orientation: np.ndarray | None = None,
        drive_displacement: np.ndarray | None = None,
        *,
        drive_velocity: np.ndarray | None = None,
        bodies=None,
        contacts: dict | None = None,
        grain_type: np.ndarray | None = None,
    ) -> Path:
        """Write one frame (spheres, trough, and grains for clumps) and rewrite the collection.

        Args:
            time: Simulated time of the frame, s (the ParaView time value).
            positions: Sphere centres in the trough frame, (N, 3), m.
            radius: (N,), m.
            velocity: Velocities relative to the trough, (N, 3), m/s.
            grain_id: Grain index of each sphere, (N,), int.
            clump_id: Clump index of each sphere, (N,), int (the grain index for plain spheres).
            contact_count: Contacts per sphere, (N,), int.
            orientation: Unit quaternions (w, x, y, z) of the clumps, (M, 4), indexed by
                ``clump_id``; None for spheres.
            drive_displacement: Trough displacement s(t), (3,), m (default zeros); used in the
                lab frame only.
            drive_velocity: Trough velocity s'(t), (3,), m/s. When given, ``velocity_lab`` =
                ``velocity`` + s'(t) and ``speed_lab`` are written, and in the lab frame
                ``velocity`` is that lab velocity too.
            bodies: The clumps (:class:`dem.engine.state.Bodies`, or any object with its ``x``,
            ``v``,
                ``q``, ``omega``, ``mass``, ``moments``, ``offsets`` and ``body_of``), indexed by
                ``clump_id``: a grains dataset (``grains_NNNNNN.vtp``) is written beside the
                spheres. None for spheres.
            contacts: Every contact of the frame (:meth:`dem.engine.simulation.Simulation.
                contact_snapshot`): a contacts dataset (``contacts_NNNNNN.vtp``, one point a
                contact, :data:`CONTACT_ARRAYS`, the walls' summed loads as field data). None:
                none written.
            grain_type: Type index of each sphere (``particles.types``, in their order), (N,),
                int; written as ``grain_type``. None: one type, none written.

        Returns:
            Path of the sphere ``.vtp`` file.

        """
        pos = np.asarray(positions, dtype=np.float64)
        if pos.ndim != 2 or pos.shape[1] != 3:
            raise ValueError(f"positions must have shape (N, 3), got {pos.shape}")
        n = pos.shape[0]
        arrays = {
            "radius": _check(radius, (n,), "radius"),
            "velocity": _check(velocity, (n, 3), "velocity"),
            "grain_id": _check(grain_id, (n,), "grain_id"),
            "clump_id": _check(clump_id, (n,), "clump_id"),
            "contact_count": _check(contact_count, (n,), "contact_count"),
        }
        shift = np.zeros(3)
        if drive_displacement is not None:
            shift = _check(drive_displacement, (3,), "drive_displacement").astype(np.float64)
        if not np.all(np.isfinite(shift)):
            raise ValueError("drive_displacement must be finite")

        drive_v = None
        if drive_velocity is not None:
            drive_v = _check(drive_velocity, (3,), "drive_velocity").astype(np.float64)
            if not np.all(np.isfinite(drive_v)):
                raise ValueError("drive_velocity must be finite")

        pos = self._section.wrap(pos)
        rel = arrays["velocity"].astype(np.float64)
        vel = rel
        if self.lab_frame:
            pos += shift
            if drive_v is not None:
                vel = rel + drive_v

        mesh = pv.PolyData(pos.astype(np.float32))  # one vertex cell per point
        mesh.point_data["radius"] = arrays["radius"].astype(np.float32)
        mesh.point_data["velocity"] = vel.astype(np.float32)
        for key in ("grain_id", "clump_id", "contact_count"):
            mesh.point_data[key] = arrays[key].astype(np.int32)
        if grain_type is not None:
            mesh.point_data["grain_type"] = _check(grain_type, (n,), "grain_type").astype(np.int32)
        point_velocities(mesh, rel, drive_v)
        if orientation is not None:
            q = np.asarray(orientation, dtype=np.float64)
            cid = arrays["clump_id"].astype(np.int64)
            if q.ndim != 2 or q.shape[1] != 4 or (n and (cid.min() < 0 or cid.max() >= len(q))):
                raise ValueError(
                    f"orientation must have shape (M, 4) with M > max(clump_id), got {q.shape}"
                )
            mesh.point_data["orientation"] = q[cid].astype(np.float32)
        mesh.set_active_scalars("radius")
        self._field_data(mesh, time, shift, drive_v)

        index = len(self._entries)
        if bodies is not None:
            grains = self._grains(bodies, arrays, shift, drive_v)
            self._field_data(grains, time, shift, drive_v)
            save_vtp(grains, self.frames_dir / _grains_name(index))
            self._grain_frames.add(index)
        if contacts is not None:
            touching = contacts_polydata(contacts, self._section, shift if self.lab_frame
                                          else np.zeros(3))  # fmt: skip
            self._field_data(touching, time, shift, drive_v)
            save_vtp(touching, self.frames_dir / _contacts_name(index))
            self._contact_frames.add(index)
        p_name = f"particles_{index:06d}.vtp"
        save_vtp(mesh, self.frames_dir / p_name)
        t_name = self._write_trough(index, shift)
        self._entries.append((float(time), p_name, t_name))
        due = max(PVD_REWRITE_MIN_S, PVD_REWRITE_FACTOR * self._pvd_cost)
        if _clock() - self._pvd_written_at >= due:
            self._write_pvd()
        return self.frames_dir / p_name

    def _field_data(self, mesh: pv.PolyData, time: float, shift, drive_v) -> None:
        """The frame's time, inclination, drive displacement and velocity, and its frames."""
        mesh.field_data["time"] = np.array([time], dtype=np.float64)
        mesh.field_data["inclination_deg"] = np.array([self.inclination_deg])
        mesh.field_data["drive_displacement"] = shift
        if drive_v is not None:
            mesh.field_data["drive_velocity"] = drive_v
        frame = "lab" if self.lab_frame else "trough"
        mesh.field_data["frame"] = np.array([frame])
        lab_vel = self.lab_frame and drive_v is not None
        mesh.field_data["velocity_frame"] = np.array(["lab" if lab_vel else "trough"])

    def _grains(self, bodies, arrays: dict, shift: np.ndarray, drive_v) -> pv.PolyData:
        """One point per clump at its centre of mass, with the arrays of :data:`GRAIN_ARRAYS`."""
        x = np.asarray(bodies.x, dtype=np.float64).reshape(-1, 3)
        b = x.shape[0]
        q = np.asarray(bodies.q, dtype=np.float64).reshape(b, 4)
        cid = np.asarray(arrays["clump_id"], dtype=np.int64)
        if cid.size and (cid.min() < 0 or cid.max() >= b):
            raise ValueError(f"clump_id must lie in [0, {b}) for {b} bodies")
        pos = self._section.wrap(x)
        rel = np.asarray(bodies.v, dtype=np.float64).reshape(b, 3)
        vel = rel
        if self.lab_frame:
            pos += shift
            if drive_v is not None:
                vel = rel + drive_v
        ids = np.full(b, -1, dtype=np.int64)  # each grain's lasting id, from its members
        ids[cid] = np.asarray(arrays["grain_id"], dtype=np.int64)
        mesh = pv.PolyData(pos.astype(np.float32))
        mesh.point_data["grain_id"] = ids.astype(np.int32)
        mesh.point_data["clump_id"] = np.arange(b, dtype=np.int32)
        mesh.point_data["mass"] = np.asarray(bodies.mass, dtype=np.float32).reshape(b)
        mesh.point_data["axis"] = long_axis(q, bodies.moments, bodies.offsets,
                                            bodies.body_of).astype(np.float32)  # fmt: skip
        mesh.point_data["orientation"] = q.astype(np.float32)
        mesh.point_data["velocity"] = vel.astype(np.float32)
        point_velocities(mesh, rel, drive_v)
        mesh.point_data["angular_velocity"] = np.asarray(bodies.omega, np.float32).reshape(b, 3)
        counts = np.bincount(cid, weights=arrays["contact_count"], minlength=b)
        mesh.point_data["contact_count"] = counts.astype(np.int32)
        mesh.point_data["spheres"] = np.bincount(cid, minlength=b).astype(np.int32)
        mesh.set_active_scalars("speed_lab" if drive_v is not None else "speed_trough")
        return mesh

    def close(self) -> Path:
        """Write the collection a last time; returns the path of ``particles.pvd``."""
        self._write_pvd()
        return self.pvd_path

    def __enter__(self) -> VTKSeriesWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _write_trough(self, index: int, shift: np.ndarray) -> str:
        """Write the trough of frame ``index`` if it needs a file of its own; returns its name."""
        if not self.lab_frame:
            if not self._trough_written:
                save_vtp(self._trough_mesh, self.frames_dir / TROUGH_FILE)
                self._trough_written = True
            return TROUGH_FILE
        name = f"trough_{index:06d}.vtp"
        moved = self._trough_mesh.copy(deep=True)
        moved.points = self._trough_mesh.points + shift.reshape(1, 3)
        save_vtp(moved, self.frames_dir / name)
        return name

    def _write_pvd(self) -> None:
        start = _clock()
        lines = [
            '<?xml version="1.0"?>',
            '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
            "  <Collection>",
        ]
        for index, (t, p_name, t_name) in enumerate(self._entries):
            parts = [("spheres", p_name), ("trough", t_name)]
            if index in self._grain_frames:
                parts.append(("grains", _grains_name(index)))
            if index in self._contact_frames:
                parts.append(("contacts", _contacts_name(index)))
            for part, (block_name, name) in enumerate(parts):
                file = quoteattr(f"{FRAMES_DIR}/{name}")
                block = quoteattr(block_name)
                lines.append(f'    <DataSet timestep="{t!r}" group="" part="{part}" '
                             f"name={block} file={file}/>")  # fmt: skip
        lines += ["  </Collection>", "</VTKFile>", ""]
        replace_text(self.pvd_path, "\n".join(lines), encoding="ascii")
        self._pvd_written_at = _clock()
        self._pvd_cost = self._pvd_written_at - start


def read_frame(out_dir: str | Path, index: int = -1) -> tuple[float, pv.MultiBlock]:
    """Frame ``index`` (negative from the end) of a run's series: its time, s, and its blocks.

    The blocks are named as in ParaView (``spheres``, ``trough``, ``grains`` for clumps), from
    the ``name`` of each ``<DataSet>`` of ``particles.pvd``, which pyvista's own PVD reader
    drops.
    """
    from xml.etree import ElementTree

    out_dir = Path(out_dir)
    root = ElementTree.parse(out_dir / PVD_NAME).getroot()
    frames: dict[float, list] = {}
    for element in root.iter("DataSet"):
        a = element.attrib
        frames.setdefault(float(a["timestep"]), []).append((int(a.get("part", 0)), a))
    times = sorted(frames)
    t = times[index]
    blocks = pv.MultiBlock()
    for part, a in sorted(frames[t], key=lambda item: item[0]):
        blocks[a.get("name") or BLOCK_NAMES[part]] = pv.read(out_dir / a["file"])
    return t, blocks


def _clock() -> float:
    """Wall-clock seconds (monotonic) for the collection's rewrite schedule."""
    return time.monotonic()


def paraview_script() -> Path:
    """The ParaView Python script shipped with dem: ``pvpython SCRIPT OUT_DIR`` opens a run.

    It opens ``OUT_DIR/particles.pvd``, draws the spheres as sphere glyphs of their radius
    coloured by their speed in the lab, the grains' long axes (clumps) and the trough.
    """
    return Path(__file__).resolve().parent.parent / "data" / "paraview" / "open_run.py"


def _grains_name(index: int) -> str:
    return f"grains_{index:06d}.vtp"


def _contacts_name(index: int) -> str:
    return f"contacts_{index:06d}.vtp"


def _check(a, shape: tuple[int, ...], name: str) -> np.ndarray:
    arr = np.asarray(a)
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    return arr
