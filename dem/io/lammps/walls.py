"""The trough's walls in a LAMMPS deck: flat walls, or a mesh pan as an intersection of planes.

A flat trough is LAMMPS's ``fix wall/gran`` floor (z = 0) and side walls (y = -+width/2). A mesh
trough (``trough.mesh``: the U and V pans of cases/u-trough and cases/v-trough, a CAD pan) has
no triangle-mesh wall in LAMMPS's GRANULAR package, but a pan that is a profile extruded along x
with a convex cross-section is exactly the intersection of the half-spaces of its faces: ``region
plane`` per face, ``region intersect`` of them, and ``fix wall/gran/region`` on it.

Why that is the same wall as dem's mesh (:mod:`dem.kernels.mesh`): inside a convex pan the point
of the surface nearest a grain is on a face, so dem counts only face contacts there (an edge or
vertex contact whose point lies on a touched face is dropped), and LAMMPS's intersection keeps a
plane's contact only where its point is inside every other half-space, i.e. on the face itself.
Each face touches a grain with the contact law of the flat walls in both codes (a wall of
infinite mass and radius). The planes run on above the mesh's top edge, where dem's pan ends: the
deck says where, and a grain thrown above the rim in dem leaves the pan, in LAMMPS it does not.

Refused, naming ``trough.mesh`` (:class:`dem.errors.InputError`): a mesh with a face that is
not parallel to x (not an extruded profile), and a mesh whose cross-section is not convex (a
vertex behind another face's plane: an intersection of half-spaces would cut it off).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dem.errors import InputError
from dem.io.liggghts.text import fmt

#: Two faces lie in one plane when their unit normals differ by less than this, and their
#: offsets by less than this times the mesh's size.
PLANE_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Pan:
    """A mesh pan as planes: each face plane's point and inward unit normal, and its extent.

    Attributes:
        points: A point of each plane, (K, 3), m.
        normals: Unit normals pointing into the pan (the grains' side), (K, 3).
        lo, hi: The mesh's bounding box corners, (3,) each, m.
        faces: How many triangles each plane holds, (K,).

    """

    points: np.ndarray
    normals: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    faces: np.ndarray


def pan_planes(tri: np.ndarray, source: str = "trough.mesh") -> Pan:
    """The face planes of a convex pan extruded along x (``tri``: corners, (T, 3, 3), m).

    Faces in one plane merge into one; each plane's normal is turned to the side of the mesh's
    vertex centroid (inside a convex pan open at the top), whatever the triangles' winding.
    Raises :class:`InputError` for a face not parallel to x, or a cross-section that is not
    convex.
    """
    tri = np.asarray(tri, dtype=np.float64).reshape(-1, 3, 3)
    verts = tri.reshape(-1, 3)
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    size = float(np.max(hi - lo))
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(cross, axis=1)
    keep = area2 > PLANE_TOLERANCE * size * size
    normals = cross[keep] / area2[keep, None]
    corners = tri[keep, 0]
    tilted = np.abs(normals[:, 0]) > PLANE_TOLERANCE
    if np.any(tilted):
        t = int(np.flatnonzero(keep)[np.argmax(tilted)])
        raise InputError(
            "trough.mesh", source,
            "a pan extruded along x for a LAMMPS deck (every face parallel to x: LAMMPS's "
            f"region walls here are planes of the profile); triangle {t} has the normal "
            f"{np.round(normals[np.argmax(tilted)], 6).tolist()}",
        )  # fmt: skip
    centre = verts.mean(axis=0)
    flip = np.einsum("ij,ij->i", centre - corners, normals) < 0.0
    normals[flip] *= -1.0
    offsets = np.einsum("ij,ij->i", corners, normals)
    planes: list[list] = []  # [normal, offset, point, faces]
    for n, d, p in zip(normals, offsets, corners, strict=True):
        for plane in planes:
            if np.all(np.abs(plane[0] - n) < PLANE_TOLERANCE) and abs(plane[1] - d) < (
                PLANE_TOLERANCE * size
            ):
                plane[3] += 1
                break
        else:
            planes.append([n, d, p, 1])
    pn = np.array([p[0] for p in planes])
    pd = np.array([p[1] for p in planes])
    behind = verts @ pn.T - pd[None, :]  # (V, K): >= 0 inside every half-space
    worst = np.unravel_index(np.argmin(behind), behind.shape)
    if behind[worst] < -1e-6 * size:
        raise InputError(
            "trough.mesh", source,
            "a pan with a convex cross-section for a LAMMPS deck (the intersection of its face "
            f"planes); the vertex {np.round(verts[worst[0]], 6).tolist()} m lies "
            f"{-behind[worst]:.3g} m behind the plane of another face",
        )  # fmt: skip
    return Pan(
        points=np.array([p[2] for p in planes]), normals=pn, lo=lo, hi=hi,
        faces=np.array([p[3] for p in planes]),
    )  # fmt: skip


def flat_wall_lines(words: str, width: float) -> list[str]:
    """The floor z = 0 and the side walls y = -+width/2 as ``fix wall/gran``."""
    half = 0.5 * width
    return [
        "# the floor z = 0 and the side walls y = -+width/2 (each grain feels the nearer one)",
        f"fix floor all wall/gran granular {words} zplane 0.0 NULL",
        f"fix sides all wall/gran granular {words} yplane {fmt(-half)} {fmt(half)}",
    ]


def pan_wall_lines(words: str, pan: Pan, source: str) -> list[str]:
    """The pan as ``region plane`` per face, their ``region intersect`` and ``wall/gran/region``."""
    k = len(pan.points)
    lines = [
        f"# the trough: the pan of {source} as the intersection of its {k} face planes "
        f"({int(pan.faces.sum())} triangles; the profile is extruded along x and convex, so a "
        "grain touches a plane where it touches a face in dem)",
        f"# the planes run on above the mesh's top edge at z = {fmt(float(pan.hi[2]))} m, where "
        "dem's pan ends",
    ]
    for i, (p, n) in enumerate(zip(pan.points, pan.normals, strict=True)):
        lines.append(f"region pan{i + 1} plane {fmt(p[0])} {fmt(p[1])} {fmt(p[2])} "
                     f"{fmt(n[0])} {fmt(n[1])} {fmt(n[2])} side in units box")  # fmt: skip
    names = " ".join(f"pan{i + 1}" for i in range(k))
    lines += [
        f"region pan intersect {k} {names} side in units box",
        f"fix pan all wall/gran/region granular {words} region pan",
    ]
    return lines
