"""Where a deck's grains and walls lie: the box, the walls and the insertion block, m.

Flat troughs: the walls are ``fix wall/gran`` primitives, floor z = 0 and side walls
y = +-width/2, and the box is periodic over x in [0, length].

Mesh troughs (``[trough] mesh``): the triangles the case reads (:func:`dem.scene.mesh.load_mesh`)
are written next to the deck as the ASCII STL ``trough.stl`` (exact coordinates, m, trough frame)
and become one granular wall, ``fix trough all mesh/surface file trough.stl type 2`` and
``fix walls all wall/gran MODEL mesh n_meshes 1 meshes trough SETTINGS``, in place of the three
primitive walls (``curvature_tolerant yes`` is added only if a triangle has a corner angle below
LIGGGHTS's default curvature, 0.256 deg, which it would otherwise refuse). The mesh is not
moved: the drive is a translation, so in the trough's frame the walls stand still and the same
effective gravity is exact (README, Symbols); no ``fix move/mesh`` is needed. The box is
periodic over x in [0, length], which the mesh spans, and reaches
:data:`MESH_BOX_MARGIN` grain reaches beyond the mesh across y and below it. LIGGGHTS copies
the triangles across the periodic boundary itself (ghost elements); a sphere rolling across
x = 0 on the U pan keeps its speed and height to all printed digits (checked by hand with
LIGGGHTS 3.8). ``insert/pack`` checks new grains against each other (``overlapcheck``) and,
with ``all_in``, keeps spheres inside the region (clumps are inserted at random orientations
with their centres of mass in a region inset by their reach: :func:`placement`), but not
against a mesh, so the insertion block must itself clear the mesh: :func:`mesh_fill_block`
takes the block over the pan with the largest cross-section below the mesh's top whose sides
and floor stay a neighbour skin away from every triangle, and the column above it is as tall as
the grains need at the loose fill fraction (:func:`layout`).

A finite feeder's box is open along x from a margin behind the back wall, a primitive plane
x = 0 also with a mesh, to the discharge edge x = L (:mod:`dem.io.liggghts.feeder`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dem.errors import InputError
from dem.io.files import write_input
from dem.io.liggghts.text import fmt
from dem.scene.case import Case
from dem.scene.mesh import load_mesh

#: File the trough mesh of a mesh case is written to, next to the deck (ASCII STL, m).
MESH_FILE = "trough.stl"
#: LIGGGHTS's default ``curvature`` of ``fix mesh/surface``, deg: a mesh with a smaller angle in
#: any triangle needs ``curvature_tolerant yes``.
MESH_DEFAULT_CURVATURE = 0.256235
#: Margin of the box around a mesh across y and below it, in grain reaches (radius or clump
#: bounding radius): every node lies strictly inside the box.
MESH_BOX_MARGIN = 2.0
#: Half-widths tried for the insertion block over a mesh pan.
MESH_FILL_TRIES = 256
#: Neighbour skin as a fraction of the sphere radius; the insertion block keeps a skin of the
#: smallest sphere away from a mesh.
SKIN_FRACTION = 0.5
#: Solid volume fraction of the loose column the spheres are inserted into.
FILL_VOLUME_FRACTION = 0.2
#: The same for clumps: ``insert/pack`` (``all_in``) placed only 174 of 200 screws of
#: ``cases/screw-trough`` at 0.14 and all of them at 0.10 (and at 0.08 with random orientations).
FILL_VOLUME_FRACTION_CLUMPS = 0.08
#: A feeder's fill column is shorter (fill in [reach, L - reach]); its loose fraction is scaled.
FEEDER_FILL_SCALE = 0.6


def write_stl(
    path: str | Path, tri: np.ndarray, name: str = "trough", *, key: str = "--out"
) -> Path:
    """Write triangles as an ASCII STL file (LIGGGHTS 3.8 reads ASCII STL only).

    Args:
        path: The file.
        tri: Corners, (T, 3, 3), m; each triangle keeps its winding a -> b -> c, and its facet
            normal is (b - a) x (c - a) / |...|.
        name: The solid's name.
        key: The option that named the folder, for a refused link.

    Coordinates are written exactly (shortest repr), so the file reads back to the same bits.

    """
    tri = np.asarray(tri, dtype=np.float64).reshape(-1, 3, 3)
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(cross, axis=1, keepdims=True)
    normals = cross / np.where(length > 0.0, length, 1.0)
    lines = [f"solid {name}"]
    for corners, normal in zip(tri, normals, strict=True):
        lines.append("facet normal " + " ".join(map(fmt, normal)))
        lines.append(" outer loop")
        lines += ["  vertex " + " ".join(map(fmt, v)) for v in corners]
        lines += [" endloop", "endfacet"]
    lines.append(f"endsolid {name}")
    return write_input(Path(path), lines, key=key)


def strip_top(tri: np.ndarray, y0: float, y1: float) -> float:
    """Highest z of the triangles' parts with y0 <= y <= y1 (any x), m; -inf where none is.

    The triangles (T, 3, 3) are clipped to the slab; z is linear on a triangle, so its highest
    point in the slab is a corner inside it or a point where an edge crosses y = y0 or y = y1.
    """
    y, z = tri[..., 1], tri[..., 2]
    inside = (y >= y0) & (y <= y1)
    top = float(np.max(np.where(inside, z, -np.inf), initial=-np.inf))
    for i, j in ((0, 1), (1, 2), (2, 0)):
        yi, yj, zi, zj = y[:, i], y[:, j], z[:, i], z[:, j]
        for s in (y0, y1):
            crosses = (yi - s) * (yj - s) < 0.0  # never where yi == yj
            t = np.divide(s - yi, yj - yi, out=np.zeros_like(yi), where=crosses)
            top = max(top, float(np.max(np.where(crosses, zi + t * (zj - zi), -np.inf))))
    return top


def mesh_fill_block(tri: np.ndarray, clearance: float) -> tuple[float, float, float]:
    """The insertion block over a mesh pan: (y0, y1, z0), m; it runs over all x and up from z0.

    The block is centred on the mesh's extent across y. For each half-width h (a fraction
    k / :data:`MESH_FILL_TRIES` of the mesh's half-width) its bottom z0 is ``clearance`` above
    the highest point of the mesh within ``clearance`` of the block's sides (:func:`strip_top`),
    so no triangle comes closer than ``clearance`` to the block, anywhere along x; the walls of
    the pan rule out wide blocks. Of these, the block with the largest cross-section below the
    mesh's top, 2 h (z_top - z0), is taken: the widest column that still reaches down into the
    pan. Widths are rounded down and z0 up to 1e-6 m.

    Raises:
        ValueError: No block fits (a pan closed at the top, or with a gap in its floor).

    """
    lo, hi = tri.min(axis=(0, 1)), tri.max(axis=(0, 1))
    y_mid, half = 0.5 * (lo[1] + hi[1]), 0.5 * (hi[1] - lo[1])
    best, best_area = None, 0.0
    for k in range(1, MESH_FILL_TRIES):
        h = math.floor(half * k / MESH_FILL_TRIES * 1e6) / 1e6
        below = strip_top(tri, y_mid - h - clearance, y_mid + h + clearance)
        z0 = math.ceil((below + clearance) * 1e6) / 1e6 if math.isfinite(below) else math.nan
        if h > 0.0 and below >= lo[2] and z0 < hi[2] and 2.0 * h * (hi[2] - z0) > best_area:
            best, best_area = (y_mid - h, y_mid + h, z0), 2.0 * h * (hi[2] - z0)
    if best is None:
        raise ValueError(
            "no block over the pan clears the mesh (is the pan open at the top, with no gap in "
            "its floor?)"
        )
    return best


def min_angle_deg(tri: np.ndarray) -> float:
    """Smallest corner angle of any triangle (T, 3, 3), degrees (LIGGGHTS checks it)."""
    smallest = 180.0
    for i in range(3):
        a = tri[:, (i + 1) % 3] - tri[:, i]
        b = tri[:, (i + 2) % 3] - tri[:, i]
        cos = np.sum(a * b, axis=1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        smallest = min(smallest, float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).min()))
    return smallest


def placement(case: Case) -> str:
    """The insert fixes' placement keywords: spheres ``all_in yes``, clumps ``all_in no``.

    Clumps get ``orientation random`` in a region inset by their reach (:func:`layout`).

    LIGGGHTS 3.8's insert fixes default to the template's orientation (``quat_random_`` is false
    in ``FixInsert``): without ``orientation random`` every screw starts with its axis along x,
    and such a bed conveyed 8 % faster than dem's randomly oriented one
    (validation/liggghts-screws, part D). Their ``all_in`` keeps a sphere of the template's
    bounding radius inside the region, but about the point where the clump's centre of mass is
    then put (``ParticleToInsertMultisphere::check_near_set_x_v_omega``), not about the
    bounding sphere's centre: a rotated screw's tip reached past the side walls and 2 of 200
    screws were deleted at once. The inset region holds the centre of mass instead, so every
    member stays inside at any orientation.
    """
    if not case.particles.clumps:
        return " all_in yes"
    return " all_in no orientation random"


class Layout(NamedTuple):
    """The box and the insertion block of a deck (:func:`layout`), m, trough frame.

    Attributes:
        boundary: The ``boundary`` command: ``p f f`` (periodic x), ``f f f`` for a feeder.
        box_x: (low, high) of the box along x.
        box_y: (low, high) of the box across y.
        box_z0: Bottom of the box.
        top: Top of the box, high enough that thrown grains never leave it.
        fill_x: (low, high) of the insertion block along x.
        fill_y: (low, high) of the insertion block across y (of centres of mass for clumps).
        fill_z0: Bottom of the insertion block.
        fill_height: Height of the insertion block: the grains' loose column.
        bottom: Lowest point of the walls (the floor z = 0, or the mesh's lowest node).
        tri: The mesh's triangles (T, 3, 3), or None for flat walls.
        wall_note: Header comment lines on a mesh's walls (none for flat walls).

    """

    boundary: str
    box_x: tuple[float, float]
    box_y: tuple[float, float]
    box_z0: float
    top: float
    fill_x: tuple[float, float]
    fill_y: tuple[float, float]
    fill_z0: float
    fill_height: float
    bottom: float
    tri: np.ndarray | None
    wall_note: list[str]


def layout(case: Case, out: Path, *, r_min: float, r_max: float, grain_volume: float) -> Layout:
    """The box and the loose insertion column of ``case``'s grains; a mesh goes to ``out``.

    The column holds the case's grains at the loose fill fraction (:data:`FILL_VOLUME_FRACTION`,
    or :data:`FILL_VOLUME_FRACTION_CLUMPS`; times :data:`FEEDER_FILL_SCALE` for a feeder) and is
    at least 4 radii (2.5 clump reaches) tall. Over a flat floor it spans the box; over a mesh
    it stands in the pan (:func:`mesh_fill_block`) and the box holds the mesh with
    :data:`MESH_BOX_MARGIN` reaches to spare. For clumps the block holds centres of mass and is
    inset by the grain's reach (:func:`placement`); a feeder fills [reach, L - reach] as dem
    does (:mod:`dem.engine.setup`), clear of the back wall and the edge.

    Args:
        case: A case read by :func:`dem.scene.case.load_case`.
        out: The deck's directory; a mesh case's triangles are written there as
            :data:`MESH_FILE`.
        r_min: Smallest sphere radius of a grain, m.
        r_max: Largest sphere radius of a grain, m.
        grain_volume: Volume of one grain, m^3.

    Raises:
        InputError: A mesh no insertion block fits in, or no room across y for a grain.

    """
    source = str(case.source)
    p, t = case.particles, case.trough
    n = p.count
    # loose insertion column and a box tall enough that thrown grains never leave it
    if not p.clumps:
        fill_fraction, fill_min = FILL_VOLUME_FRACTION, 4.0 * r_max
    else:
        fill_fraction, fill_min = FILL_VOLUME_FRACTION_CLUMPS, 2.5 * p.grain.bounding_radius
    tri = None
    if t.mesh is None:  # flat floor z = 0 and side walls y = +-width/2; the column spans the box
        half_w = 0.5 * t.width
        box_y, box_z0 = (-half_w, half_w), 0.0
        fill_y, fill_z0, bottom = box_y, 0.0, 0.0
        mesh_top, wall_note = 0.0, []
    else:  # the column stands in the pan (mesh_fill_block); the box holds the mesh
        tri = load_mesh(t.mesh, length=t.length, source=source).tri
        write_stl(out / MESH_FILE, tri, key="OUT_DIR")
        try:
            fill_block = mesh_fill_block(tri, SKIN_FRACTION * r_min)
        except ValueError as exc:
            raise InputError(
                "trough.mesh", str(t.mesh), f"a pan grains fit in ({exc})", source
            ) from None
        lo, hi = tri.min(axis=(0, 1)), tri.max(axis=(0, 1))
        margin = MESH_BOX_MARGIN * p.reach
        box_y, box_z0 = (float(lo[1] - margin), float(hi[1] + margin)), float(lo[2] - margin)
        fill_y, fill_z0, bottom = fill_block[:2], fill_block[2], float(lo[2])
        mesh_top = float(hi[2] + margin)
        wall_note = [
            f"# walls: {MESH_FILE}, the {len(tri)} triangles of {t.mesh.name} (m, trough frame),",
            "#   standing still: the drive translates the trough, so in its frame the walls do",
            "#   not move (no move/mesh; README, Symbols). The insertion block lies inside the",
            "#   pan, clear of the mesh: insert/pack does not check grains against a mesh",
        ]
    feeder = case.feeder
    reach = p.reach
    if p.clumps:  # the region holds centres of mass (placement)
        fill_y, fill_z0 = (fill_y[0] + reach, fill_y[1] - reach), fill_z0 + reach
    # a feeder fills [reach, L - reach] as dem does (dem.engine.setup), clear of the back wall and
    # edge
    fill_x = (0.0, t.length) if feeder is None else (reach, t.length - reach)
    fill_width = fill_y[1] - fill_y[0]
    if fill_width <= 0.0:
        raise InputError(
            "trough.width" if t.mesh is None else "trough.mesh",
            t.width if t.mesh is None else str(t.mesh),
            f"room across y for a grain's reach of {reach:g} m either side of its centre of "
            "mass (LIGGGHTS's insertion region)",
            source,
        )
    fill_length = fill_x[1] - fill_x[0]
    if feeder is not None:  # insert/pack placed 43 of cases/feeder's 50 screws at 0.08
        fill_fraction *= FEEDER_FILL_SCALE
    fill_height = max(n * grain_volume / (fill_fraction * fill_length * fill_width), fill_min)
    top = max(fill_z0 + 3.0 * fill_height + 20.0 * r_max, mesh_top)
    if feeder is None:
        box_x, boundary = (0.0, t.length), "boundary p f f"
    else:
        # open x: a sphere whose centre passes x = L leaves the box and is deleted (lost atoms
        # ignored); the back wall is the plane x = 0, as dem's
        box_x, boundary = (-MESH_BOX_MARGIN * reach, t.length), "boundary f f f"
    return Layout(
        boundary, box_x, box_y, box_z0, top, fill_x, fill_y, fill_z0, fill_height, bottom, tri,
        wall_note,
    )  # fmt: skip


def wall_block(case: Case, space: Layout, model: str, settings: str) -> list[str]:
    """The walls: floor and side planes, or the mesh; and a feeder's back wall x = 0.

    ``model`` and ``settings`` are the granular model and its settings
    (:func:`dem.io.liggghts.contact.contact_block`); walls are atom type 2.
    """
    t = case.trough
    if space.tri is None:
        half_w = 0.5 * t.width
        lines = [
            f"fix floor all wall/gran {model} primitive type 2 zplane 0.0 {settings}",
            f"fix side_lo all wall/gran {model} primitive type 2 yplane {fmt(-half_w)} {settings}",
            f"fix side_hi all wall/gran {model} primitive type 2 yplane {fmt(half_w)} {settings}",
        ]
    else:
        # LIGGGHTS refuses a triangle with a corner angle below the curvature unless told
        tolerant = min_angle_deg(space.tri) < MESH_DEFAULT_CURVATURE
        lines = [
            f"fix trough all mesh/surface file {MESH_FILE} type 2"
            + (" curvature_tolerant yes" if tolerant else ""),
            f"fix walls all wall/gran {model} mesh n_meshes 1 meshes trough {settings}",
        ]
    if case.feeder is not None:
        lines.append(f"fix back all wall/gran {model} primitive type 2 xplane 0.0 {settings}")
    return lines
