"""Trough meshes for the shipped mesh cases: a U (half-cylinder pan) and a V, as STL files.

    python cases/geometry/make_troughs.py [--length 0.12] [--out cases/geometry]

Each trough is a cross-section profile in the y-z plane extruded along x from 0 to the section
length (the periodic section of the case, ``trough.length``), in metres, trough frame (x along the
trough, y across, z up from the lowest point of the pan). Triangle normals point into the pan,
to the grains' side, as dem's fill expects:

- ``u_trough.stl``: a half cylinder of radius 30 mm (60 mm wide at the rim, 30 mm deep), 48
  segments, with straight side walls 20 mm tall above the rim;
- ``v_trough.stl``: two flanks at 45 degrees meeting at the bottom (60 mm wide, 30 mm deep),
  with straight side walls 20 mm tall above the rim.

Each profile segment is one rectangle along x, split into two triangles
(``dem.scene.mesh.extrude``; a
long triangle is fine: the contact index bins triangles by their bounding boxes). Only numpy,
meshio and that function are used.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import meshio
import numpy as np

from dem.scene.mesh import extrude

RADIUS = 0.030
DEPTH = 0.030
WALL = 0.020
SEGMENTS = 48


def u_profile(radius: float = RADIUS, segments: int = SEGMENTS, wall: float = WALL) -> np.ndarray:
    """(y, z) points of the U from the rim at -y round the bottom to the rim at +y, walls on top."""
    theta = np.linspace(np.pi, 2.0 * np.pi, segments + 1)
    arc = np.column_stack([radius * np.cos(theta), radius + radius * np.sin(theta)])
    top_left = [[-radius, radius + wall]]
    top_right = [[radius, radius + wall]]
    return np.vstack([top_left, arc, top_right])


def v_profile(half_width: float = RADIUS, depth: float = DEPTH, wall: float = WALL) -> np.ndarray:
    """(y, z) points of the V from the rim at -y through the bottom to the rim at +y."""
    return np.array(
        [[-half_width, depth + wall], [-half_width, depth], [0.0, 0.0], [half_width, depth],
         [half_width, depth + wall]]
    )  # fmt: skip


def main(argv=None) -> int:
    """Write both troughs; returns 0."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--length", type=float, default=0.12, help="section length, m")
    parser.add_argument("--out", default=str(Path(__file__).resolve().parent))
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name, profile in (("u_trough.stl", u_profile()), ("v_trough.stl", v_profile())):
        mesh = extrude(profile, args.length)
        meshio.write(out / name, mesh, binary=False)
        print(f"wrote {out / name}: {len(mesh.cells[0].data)} triangles")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
