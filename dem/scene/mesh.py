"""Trough meshes: triangles read (STL by dem, other formats by meshio), checked, and binned.

A mesh trough is a surface of triangles in the trough frame (x along the trough, y across, z up
from the floor; metres), fixed to the trough and driven with it. STL (ASCII or binary) is read
here, its size and grammar checked (:func:`read_stl`); any other format meshio reads works too
(OBJ, VTK, VTU, PLY, ...), its face indices checked before use; quadrilaterals are split into
two triangles. Every file dem cannot use is refused in one line naming ``trough.mesh``.
Triangle normals (right-hand winding a -> b -> c) should point to the grains' side: the fill
places grains there.
The contact law and the rules against double counting are in :mod:`dem.kernels.mesh`.

The section stays periodic in x with period ``trough.length``: the mesh must span x from 0 to
``trough.length`` and have the same cross-section at both ends (a profile extruded along x, as
the shipped U and V troughs are); grains leaving at x = length come back at x = 0.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dem.errors import InputError

#: Relative tolerance on the mesh's x extent against [0, trough.length].
EXTENT_TOLERANCE = 1e-6
#: Most cells of the contact index (cells grow beyond 2 reach to stay below).
MAX_CELLS = 1 << 21


@dataclass
class TriangleMesh:
    """Triangles of a trough mesh with their cell index.

    Attributes:
        tri: Corners, (T, 3, 3), m, trough frame.
        normals: Unit normals (b - a) x (c - a) / |...|, (T, 3).
        grid: Index origin (3), cell edge and the period along x (0: none), (5,), m; ``dims``
            (3,) int64 cells along x, y, z.
        cell_start, cell_tris: CSR of the triangles listed in each cell, int64.
        source: Where the triangles came from (a path, or a description).

    """

    tri: np.ndarray
    period: float = 0.0
    normals: np.ndarray = field(init=False)
    grid: np.ndarray = field(init=False)
    dims: np.ndarray = field(init=False)
    cell_start: np.ndarray = field(init=False)
    cell_tris: np.ndarray = field(init=False)
    source: str = "triangles"

    def __post_init__(self):
        self.tri = np.ascontiguousarray(self.tri, dtype=np.float64).reshape(-1, 3, 3)
        cross = np.cross(self.tri[:, 1] - self.tri[:, 0], self.tri[:, 2] - self.tri[:, 0])
        area2 = np.linalg.norm(cross, axis=1)
        self.normals = cross / np.where(area2 > 0.0, area2, 1.0)[:, None]
        self.index(0.0)

    @property
    def count(self) -> int:
        """Number of triangles."""
        return self.tri.shape[0]

    def index(self, reach: float) -> None:
        """Bin the triangles for spheres of radius plus skin up to ``reach``, m.

        Cells of edge 2 ``reach`` (larger if that would make more than ``MAX_CELLS`` cells) over
        the bounding box padded by ``reach``; each cell lists the triangles whose padded bounding
        box meets it, so a sphere far from every triangle finds an empty list at once.
        """
        lo = self.tri.min(axis=(0, 1)) - reach
        hi = self.tri.max(axis=(0, 1)) + reach
        volume = float(np.prod(np.maximum(hi - lo, 1e-12)))
        cell = max(2.0 * reach, (volume / MAX_CELLS) ** (1.0 / 3.0), 1e-12)
        dims = np.maximum(1, np.ceil((hi - lo) / cell).astype(np.int64))
        tlo = np.floor((self.tri.min(axis=1) - reach - lo) / cell).astype(np.int64)
        thi = np.floor((self.tri.max(axis=1) + reach - lo) / cell).astype(np.int64)
        tlo = np.clip(tlo, 0, dims - 1)
        thi = np.clip(thi, 0, dims - 1)
        cell_parts: list[np.ndarray] = []
        tri_parts: list[np.ndarray] = []
        for t in range(self.count):
            ix = np.arange(tlo[t, 0], thi[t, 0] + 1)
            iy = np.arange(tlo[t, 1], thi[t, 1] + 1)
            iz = np.arange(tlo[t, 2], thi[t, 2] + 1)
            z, y, x = np.meshgrid(iz, iy, ix, indexing="ij")
            c = ((z * dims[1] + y) * dims[0] + x).ravel()
            cell_parts.append(c)
            tri_parts.append(np.full(c.size, t, dtype=np.int64))
        cells = np.concatenate(cell_parts) if cell_parts else np.zeros(0, dtype=np.int64)
        tris = np.concatenate(tri_parts) if tri_parts else np.zeros(0, dtype=np.int64)
        order = np.lexsort((tris, cells))  # by cell, triangles in index order within a cell
        n_cells = int(np.prod(dims))
        self.cell_start = np.zeros(n_cells + 1, dtype=np.int64)
        np.add.at(self.cell_start, cells + 1, 1)
        self.cell_start = np.cumsum(self.cell_start)
        self.cell_tris = np.ascontiguousarray(tris[order])
        self.grid = np.array([lo[0], lo[1], lo[2], cell, self.period])
        self.dims = dims

    def gaps(self, x: np.ndarray) -> np.ndarray:
        """Distance of points (n, 3) to the mesh, (n,), m (inf beyond the indexed reach)."""
        from dem.kernels.mesh import mesh_gaps

        x = np.ascontiguousarray(x, dtype=np.float64).reshape(-1, 3)
        return mesh_gaps(x, self.tri, self.grid, self.dims, self.cell_start, self.cell_tris)

    def sides(self, x: np.ndarray) -> np.ndarray:
        """Signed distance along the closest triangle's normal, (n,), m (nan beyond reach)."""
        from dem.kernels.mesh import mesh_sides

        x = np.ascontiguousarray(x, dtype=np.float64).reshape(-1, 3)
        return mesh_sides(
            x, self.tri, self.normals, self.grid, self.dims, self.cell_start, self.cell_tris
        )


def extrude(profile: np.ndarray, length: float, x_segments: int = 1):
    """A cross-section profile (m, 2) of (y, z) points extruded along x over [0, length].

    Returns a ``meshio.Mesh`` of 2 (m - 1) ``x_segments`` triangles. Walking the profile from -y
    to +y with the pan above it, every normal (b - a) x (c - a) points into the pan (the side the
    profile curves towards): the grains' side.
    """
    import meshio

    profile = np.asarray(profile, dtype=np.float64)
    m = len(profile)
    xs = np.linspace(0.0, length, x_segments + 1)
    pts = np.vstack([np.column_stack([np.full(m, xv), profile]) for xv in xs])
    tris = []
    for s in range(x_segments):
        for k in range(m - 1):
            a, b = s * m + k, s * m + k + 1  # at xs[s]
            c, d = a + m, b + m  # at xs[s + 1]
            tris += [[a, c, b], [b, c, d]]
    return meshio.Mesh(pts, [("triangle", np.array(tris, dtype=np.int64))])


#: Binary STL: an 80-byte header, the triangle count (uint32), then 50 bytes per triangle
#: (normal and three corners as float32, a uint16 attribute).
STL_HEADER, STL_RECORD = 84, 50
_STL_DTYPE = np.dtype([("normal", "<f4", (3,)), ("facet", "<f4", (3, 3)), ("attr", "<u2")])
#: The bytes an ASCII STL may hold: printable ASCII, tab, line feed, carriage return.
_TEXT = bytes(range(0x20, 0x7F)) + b"\t\n\r"


def _refuse(path: Path, allowed: str, where: str) -> InputError:
    return InputError("trough.mesh", str(path), allowed, where)


def read_stl(path: Path, where: str | None = None) -> np.ndarray:
    """The triangles (T, 3, 3) of an ASCII or binary STL file, every byte accounted for.

    dem reads STL itself: meshio's reader takes a binary file whose size disagrees with its
    triangle count for ASCII (a truncated file lost a wall triangle without a word, or ended
    in a decoding error), and reads ASCII without checking its grammar (a misspelt keyword or
    a missing vertex passed, or exited the process). Here a binary file must hold exactly
    84 + 50 T bytes for the T its header states, and an ASCII file must follow ``solid`` /
    ``facet normal`` / ``outer loop`` / three ``vertex x y z`` / ``endloop`` / ``endfacet`` /
    ``endsolid``; anything else is an InputError naming ``trough.mesh`` and the file. An
    unreadable file raises the OSError (an I/O fault, not a bad value).
    """
    where = where or str(path)
    data = Path(path).read_bytes()
    binary_size = None
    if len(data) >= STL_HEADER:
        count = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        binary_size = STL_HEADER + STL_RECORD * count
    if binary_size == len(data):
        records = np.frombuffer(data, dtype=_STL_DTYPE, count=count, offset=STL_HEADER)
        return records["facet"].astype(np.float64)
    if data.lstrip()[:5].lower() == b"solid" and not data.translate(None, _TEXT):
        return _read_ascii_stl(data.decode("ascii"), path, where)
    if binary_size is None:
        raise _refuse(
            path, f"an STL file: {len(data)} bytes is neither an ASCII STL (starting 'solid') "
            f"nor a binary one (at least {STL_HEADER} bytes)", where,
        )  # fmt: skip
    raise _refuse(
        path, f"a binary STL of {binary_size} bytes (84-byte header and triangle count "
        f"{count}, 50 bytes per triangle): the file has {len(data)} bytes (truncated or "
        "padded; write it again)", where,
    )  # fmt: skip


def _read_ascii_stl(text: str, path: Path, where: str) -> np.ndarray:
    """The facets of an ASCII STL, its grammar checked line by line (see :func:`read_stl`)."""
    expect = {
        "solid": "'solid'",
        "facet": "'facet normal nx ny nz' or 'endsolid'",
        "outer": "'outer loop'",
        "vertex": "'vertex x y z'",
        "endloop": "'endloop' (a facet has three vertices)",
        "endfacet": "'endfacet'",
    }
    corners: list[list[float]] = []
    state, vertices = "solid", 0  # state: what the next line must be
    for number, line in enumerate(text.splitlines(), start=1):
        words = line.split()
        if not words:
            continue
        key, lower = words[0].lower(), [w.lower() for w in words]
        if state == "solid":
            ok, after = key == "solid", "facet"
        elif state == "facet" and key == "endsolid":
            ok, after = True, "solid"
        elif state == "facet":
            ok = lower[:2] == ["facet", "normal"] and _numbers(words[2:]) is not None
            after = "outer"
        elif state == "outer":
            ok, after = lower == ["outer", "loop"], "vertex"
        elif state == "vertex":
            xyz = _numbers(words[1:]) if key == "vertex" else None
            ok = xyz is not None
            if xyz is not None:
                corners.append(xyz)
                vertices += 1
            after = "endloop" if vertices == 3 else "vertex"
        elif state == "endloop":
            ok, after, vertices = lower == ["endloop"], "endfacet", 0
        else:
            ok, after = lower == ["endfacet"], "facet"
        if not ok:
            found = " ".join(words)
            found = found if len(found) <= 40 else found[:37] + "..."
            raise _refuse(
                path, f"an ASCII STL: line {number} should be {expect[state]}, found {found!r}",
                where,
            )  # fmt: skip
        state = after
    if state != "solid":
        raise _refuse(path, f"an ASCII STL: it ends where {expect[state]} should be", where)
    return np.array(corners, dtype=np.float64).reshape(-1, 3, 3)


def _numbers(words: list[str]) -> list[float] | None:
    """Three numbers, or None (a word that is not one, or not three words)."""
    if len(words) != 3:
        return None
    try:
        return [float(w) for w in words]
    except ValueError:
        return None


def _read_meshio(path: Path, where: str) -> np.ndarray:
    """The triangles (T, 3, 3) of a file meshio reads, the face indices checked before use.

    meshio reports a file it cannot parse by printing to stdout and stderr and exiting the
    process (SystemExit 1) and raises many other kinds (ReadError, KeyError, ValueError...);
    here every failure is one InputError naming ``trough.mesh`` and the file, with meshio's
    own words kept as the cause. An OSError (the file cannot be read at all) passes through.
    """
    import contextlib
    import io

    import meshio

    said = io.StringIO()
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(said), \
                contextlib.redirect_stderr(said):  # fmt: skip
            warnings.simplefilter("ignore")
            mesh = meshio.read(path)
    except OSError:
        raise
    except (Exception, SystemExit) as exc:
        cause = str(exc) if not isinstance(exc, SystemExit) else ""
        cause = " ".join((cause or said.getvalue() or type(exc).__name__).split())
        cause = cause if len(cause) <= 160 else cause[:157] + "..."
        raise _refuse(path, f"a mesh file meshio can read (meshio: {cause})", where) from None
    points = np.asarray(mesh.points)
    if points.ndim != 2 or points.shape[1] not in (2, 3) or points.dtype.kind not in "fiu":
        raise _refuse(path, "points with 3 coordinates", where)
    points = points.astype(np.float64)
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    blocks = []
    for block in mesh.cells:
        if block.type == "triangle":
            blocks.append(block.data)
        elif block.type == "quad":
            q = block.data
            blocks += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
    if not blocks:
        kinds = sorted({b.type for b in mesh.cells}) or ["none"]
        raise _refuse(path, f"triangles or quads (the file has {', '.join(kinds)})", where)
    faces = np.concatenate(blocks)
    if faces.dtype.kind not in "iu":
        raise _refuse(path, "faces given by whole vertex numbers", where)
    # meshio has already made the file's numbers 0-based (OBJ counts from 1, and its negative
    # numbers count back from the end): numpy would wrap a negative index without a word
    bad = (faces < 0) | (faces >= len(points))
    if bad.any():
        face = int(np.argwhere(bad)[0, 0])
        raise _refuse(
            path, f"faces that name existing vertices: face {face + 1} names vertex "
            f"{int(faces[bad][0]) + 1} (counting from 1) of {len(points)}", where,
        )  # fmt: skip
    return points[faces]


def load_mesh(path: Path, *, length: float | None = None, source: str | None = None):
    """The triangles of a mesh file (STL read by dem, any other format meshio reads), checked.

    Every refusal is an InputError naming ``trough.mesh``, the file and what is allowed; an
    OSError (the file cannot be read) passes through. ``length``: the periodic section's
    length; the mesh must span x from 0 to it.
    """
    where = source or str(path)
    path = Path(path)
    if path.suffix.lower() == ".stl":
        tri = read_stl(path, where)
    else:
        tri = _read_meshio(path, where)
    if tri.shape[0] == 0:
        raise InputError("trough.mesh", str(path), "at least one triangle", where)
    if not np.isfinite(tri).all():
        raise InputError("trough.mesh", str(path), "finite coordinates (in metres)", where)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    scale = float(np.max(np.ptp(tri.reshape(-1, 3), axis=0)))
    keep = area > 1e-12 * scale * scale
    if not keep.any():
        raise InputError("trough.mesh", str(path), "triangles of nonzero area", where)
    tri = tri[keep]
    if length is not None:
        x0, x1 = float(tri[..., 0].min()), float(tri[..., 0].max())
        tol = EXTENT_TOLERANCE * length
        if abs(x0) > tol or abs(x1 - length) > tol:
            raise InputError(
                "trough.mesh", str(path),
                f"a mesh spanning x from 0 to trough.length = {length:g} m (it spans {x0:.6g} "
                f"to {x1:.6g} m; coordinates are in metres, x along the trough)", where,
            )  # fmt: skip
    return TriangleMesh(tri, period=float(length or 0.0), source=str(path))
