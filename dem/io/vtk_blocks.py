"""The blocks of a VTK frame as polydata, and one ``.vtp`` file written whole or not at all.

Builds what :class:`dem.io.vtk.VTKSeriesWriter` writes (the layout, frames and arrays are in
:mod:`dem.io.vtk`): the trough's walls (:func:`trough_polydata`) or mesh (:func:`mesh_polydata`),
the contacts block (:func:`contacts_polydata`), the spheres' and grains' velocities in both frames
(:func:`point_velocities`) and the clumps' long axes (:func:`long_axis`, by :func:`rotate`);
:func:`save_vtp` writes a block. Coordinates in m, velocities in m/s, forces in N.

Cost: O(points) per block.
"""

from __future__ import annotations

import errno
import math
import os
from pathlib import Path

import numpy as np
import pyvista as pv

from dem.io.contacts import CONTACT_KINDS, wall_loads
from dem.io.files import replace_file
from dem.scene.trough import Trough


def trough_polydata(
    length: float,
    width: float,
    wall_height: float,
    shift: np.ndarray | None = None,
    back_wall: bool = False,
) -> pv.PolyData:
    """Floor and side walls of the trough section as three quads, coordinates in m.

    The kernel's walls as :meth:`dem.scene.trough.Trough.wall_corners` gives them. Floor: z = 0,
    0 <= x <= length, |y| <= width/2; side walls: y = +-width/2, 0 <= z <= wall_height; with
    ``back_wall`` a finite feeder's back wall x = 0 as a fourth quad. Cell data ``part``: the
    kernel's wall index, 0 floor, 1 wall y = -width/2, 2 wall y = +width/2, 3 the back wall.
    ``shift`` (3,) is added to every point (the lab-frame drive displacement).
    """
    discharge = length if back_wall else math.inf
    corners = Trough(length, width, discharge=discharge).wall_corners(wall_height)
    pts = corners.reshape(-1, 3)
    if shift is not None:
        pts = pts + np.asarray(shift, dtype=np.float64).reshape(1, 3)
    faces = np.column_stack([np.full(len(corners), 4), np.arange(pts.shape[0]).reshape(-1, 4)])
    mesh = pv.PolyData(pts, faces=faces.ravel())
    mesh.cell_data["part"] = np.arange(len(corners), dtype=np.int32)
    return mesh


def mesh_polydata(tri: np.ndarray, back_wall: bool = False) -> pv.PolyData:
    """Triangles (T, 3, 3) of a trough mesh as polydata, m; cell data ``part`` = 0 (the mesh).

    With ``back_wall`` a finite feeder's back wall x = 0 is added as a quad over the mesh's y-z
    extent (``part`` 3, as for the flat walls).
    """
    tri = np.asarray(tri, dtype=np.float64).reshape(-1, 3, 3)
    t = len(tri)
    pts = tri.reshape(-1, 3)
    faces = np.column_stack([np.full(t, 3), np.arange(3 * t).reshape(-1, 3)]).ravel()
    part = np.zeros(t, dtype=np.int32)
    if back_wall:
        lo, hi = tri.min(axis=(0, 1)), tri.max(axis=(0, 1))
        quad = [[0.0, lo[1], lo[2]], [0.0, hi[1], lo[2]], [0.0, hi[1], hi[2]], [0.0, lo[1], hi[2]]]
        pts = np.concatenate([pts, quad])
        faces = np.concatenate([faces, [4, 3 * t, 3 * t + 1, 3 * t + 2, 3 * t + 3]])
        part = np.append(part, np.int32(3))
    mesh = pv.PolyData(pts, faces=faces)
    mesh.cell_data["part"] = part
    return mesh


def save_vtp(mesh: pv.PolyData, path: Path) -> None:
    """Write ``mesh`` as a binary, zlib-compressed .vtp file, whole or not at all.

    pyvista's ``save`` ignores the VTK writer's result: on a full disk it printed VTK's error
    and left a truncated frame that the collection then listed. Here a failed write raises
    OSError naming the file (errno ENOSPC on a full disk), VTK's own message is kept off the
    terminal, and the file is written beside its name and renamed (:mod:`dem.io.files`).
    """
    from vtkmodules.vtkCommonCore import vtkObject
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    def write(tmp: Path) -> None:
        writer = vtkXMLPolyDataWriter()  # a fresh one: VTK aborts when a failed one is reused
        writer.SetFileName(str(tmp))
        writer.SetInputData(mesh)
        writer.SetDataModeToBinary()
        writer.SetCompressorTypeToZLib()
        shown = vtkObject.GetGlobalWarningDisplay()
        vtkObject.GlobalWarningDisplayOff()
        try:
            ok = writer.Write()
        finally:
            vtkObject.SetGlobalWarningDisplay(shown)
        if not ok:
            code = writer.GetErrorCode()  # the system's errno for a failed write (28: ENOSPC)
            system = 0 < code < 4096
            raise OSError(
                code if system else errno.EIO,
                os.strerror(code) if system else f"VTK's writer failed (error code {code})",
                str(tmp),
            )

    replace_file(path, write)


def contacts_polydata(contacts: dict, section, shift: np.ndarray) -> pv.PolyData:
    """One point per contact (the middle of its overlap), its arrays, and the walls' loads.

    The points are wrapped into the section (and shifted in the lab frame); the loads on the
    trough, summed as field data: the floor's normal force (N), the side walls' and the back
    wall's, and the total force of every wall contact on the grains.
    """
    point = section.wrap(np.asarray(contacts["point"], dtype=np.float64)) + shift
    mesh = pv.PolyData(point.astype(np.float32))
    normal = np.asarray(contacts["normal"], dtype=np.float64)
    fn = np.asarray(contacts["normal_force"], dtype=np.float64)
    ft = np.asarray(contacts["tangential_force"], dtype=np.float64)
    kind = np.asarray(contacts["kind"], dtype=np.int64)
    mesh.point_data["kind"] = kind.astype(np.int32)
    mesh.point_data["sphere_i"] = np.asarray(contacts["i"]).astype(np.int32)
    mesh.point_data["sphere_j"] = np.asarray(contacts["j"]).astype(np.int32)
    mesh.point_data["normal"] = normal.astype(np.float32)
    mesh.point_data["normal_force"] = fn.astype(np.float32)
    mesh.point_data["normal_force_vector"] = (fn[:, None] * normal).astype(np.float32)
    mesh.point_data["tangential_force"] = ft.astype(np.float32)
    mesh.point_data["tangential_force_magnitude"] = np.linalg.norm(ft, axis=1).astype(np.float32)
    mesh.point_data["overlap"] = np.asarray(contacts["overlap"]).astype(np.float32)
    mesh.set_active_scalars("normal_force")
    for name, value in wall_loads(contacts).items():
        mesh.field_data[name] = np.atleast_1d(value)
    mesh.field_data["contact_kinds"] = np.array(CONTACT_KINDS)
    return mesh


def point_velocities(mesh: pv.PolyData, rel: np.ndarray, drive_v: np.ndarray | None) -> None:
    """``velocity_trough`` and ``speed_trough``; with the drive velocity the ``_lab`` pair."""
    mesh.point_data["velocity_trough"] = rel.astype(np.float32)
    mesh.point_data["speed_trough"] = np.linalg.norm(rel, axis=1).astype(np.float32)
    if drive_v is not None:
        lab = rel + drive_v
        mesh.point_data["velocity_lab"] = lab.astype(np.float32)
        mesh.point_data["speed_lab"] = np.linalg.norm(lab, axis=1).astype(np.float32)


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Vectors ``v`` (B, 3) turned by unit quaternions ``q`` (B, 4) (w, x, y, z): R(q) v."""
    q = np.asarray(q, dtype=np.float64).reshape(-1, 4)
    v = np.asarray(v, dtype=np.float64).reshape(-1, 3)
    w, u = q[:, :1], q[:, 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def long_axis(q, moments, offsets, body_of) -> np.ndarray:
    """Each clump's long axis in the trough frame, (B, 3) unit vectors.

    The body axis of the least principal moment (``moments`` (B, 3), body frame), turned by the
    orientation ``q`` (B, 4); it points from the centre of mass towards the member that reaches
    farthest along it (``offsets`` (n, 3) body frame, ``body_of`` (n,)): along a screw's shank,
    away from its head. A clump as long one way as the other keeps the body axis' sign.
    """
    q = np.asarray(q, dtype=np.float64).reshape(-1, 4)
    b = q.shape[0]
    k = np.argmin(np.asarray(moments, dtype=np.float64).reshape(b, 3), axis=1)
    owner = np.asarray(body_of, dtype=np.int64)
    along = np.asarray(offsets, dtype=np.float64).reshape(-1, 3)[np.arange(owner.size), k[owner]]
    reach = np.zeros(b)
    np.maximum.at(reach, owner, np.abs(along))
    tip = np.abs(along) >= reach[owner] * (1.0 - 1e-9)
    vote = np.zeros(b)
    np.add.at(vote, owner, np.where(tip, np.sign(along), 0.0))
    axis = np.zeros((b, 3))
    axis[np.arange(b), k] = np.where(vote < 0.0, -1.0, 1.0)
    return rotate(q, axis)
