"""The fill as it was before its grid: every try tested against every grain placed (O(N^2)).

The oracle of tests/scene/test_fill.py: the grid fill must place the same grains, bit for bit.
"""

import numpy as np

from dem.config import DEM_FILL_TRIES
from dem.kernels.rigid import quat_to_matrix
from dem.scene.fill import clump_box_height, random_orientations, sphere_box_height
from dem.scene.trough import Trough


def naive_fill(
    n: int,
    radius: float,
    length: float,
    width: float,
    rng: np.random.Generator,
    *,
    height: float | None = None,
) -> tuple[np.ndarray, float]:
    """Random sequential placement of n non-overlapping spheres in the trough.

    Centres are drawn uniformly in x in [0, length), y in [-width/2 + r, width/2 - r],
    z in [r, height - r] and kept if they overlap no earlier sphere (periodic in x). After
    ``DEM_FILL_TRIES`` failed tries for one sphere the box is made 25 % taller.

    Args:
        n: Number of spheres.
        radius: Sphere radius, m.
        length, width: Trough section, m.
        rng: Random generator (seeded by the caller).
        height: Initial box height, m; default ``DEM_FILL_HEIGHT_FACTOR`` times the height of a
            dense bed (packing fraction 0.6) plus a diameter.

    Returns:
        (positions (n, 3) in m, final box height in m).

    """
    if width <= 2.0 * radius:
        raise ValueError(f"trough width {width} m leaves no room for spheres of radius {radius} m")
    if height is None:
        height = sphere_box_height(n, radius, length, width)
    section = Trough(length, width)
    pos = np.empty((n, 3))
    d2_min = (2.0 * radius) ** 2
    placed = 0
    while placed < n:
        for _ in range(DEM_FILL_TRIES):
            c = np.array(
                [
                    rng.uniform(0.0, length),
                    rng.uniform(-0.5 * width + radius, 0.5 * width - radius),
                    rng.uniform(radius, max(radius, height - radius)),
                ]
            )
            d = section.minimum_image(pos[:placed] - c)
            if placed == 0 or np.min(np.einsum("ij,ij->i", d, d)) >= d2_min:
                pos[placed] = c
                placed += 1
                break
        else:
            height *= 1.25
    return pos, height


def naive_fill_clumps(
    n: int,
    template,
    length: float,
    width: float,
    rng: np.random.Generator,
    *,
    height: float | None = None,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Random sequential placement of n clumps at random positions and orientations.

    Each try draws a centre of mass uniformly in x in [0, length), y across the trough and z in
    [r_min, height] and a uniform random orientation, and keeps it if every member sphere lies
    inside the walls (z >= r, |y| <= width/2 - r) and overlaps no member of an earlier clump
    (periodic in x). After ``DEM_FILL_TRIES`` failed tries the box is made 25 % taller.

    Args:
        n: Number of clumps.
        template: A :class:`dem.scene.shapes.Template`.
        length, width: Trough section, m.
        rng: Random generator (seeded by the caller).
        height: Initial box height, m; default ``DEM_FILL_HEIGHT_FACTOR`` times the height of a
            loose bed (packing fraction 0.3) plus the bounding diameter.

    Returns:
        (centres of mass (n, 3) in m, quaternions (n, 4), final box height in m).

    """
    centres = np.asarray(template.centres, dtype=np.float64)
    radii = np.asarray(template.radii, dtype=np.float64)
    r_min, r_max = float(radii.min()), float(radii.max())
    bound = template.bounding_radius
    if width <= 2.0 * r_max:
        raise ValueError(f"trough width {width} m leaves no room for spheres of radius {r_max} m")
    if height is None:
        height = clump_box_height(n, template, length, width)
    section = Trough(length, width)
    k = len(radii)
    pos = np.empty((n, 3))
    quat = np.empty((n, 4))
    members = np.empty((n * k, 3))
    member_r = np.tile(radii, n)
    y_max = 0.5 * width - r_min
    placed = 0
    while placed < n:
        for _ in range(DEM_FILL_TRIES):
            c = np.array(
                [
                    rng.uniform(0.0, length),
                    rng.uniform(-y_max, y_max),
                    rng.uniform(r_min, max(r_min, height - r_min)),
                ]
            )
            q = random_orientations(1, rng)[0]
            xs = c + centres @ quat_to_matrix(q).T
            if np.any(xs[:, 2] < radii) or np.any(np.abs(xs[:, 1]) > 0.5 * width - radii):
                continue
            m = placed * k
            if placed:
                near = section.minimum_image(pos[:placed] - c)
                close = np.einsum("ij,ij->i", near, near) < (2.0 * bound) ** 2
                if np.any(close):
                    idx = (np.flatnonzero(close)[:, None] * k + np.arange(k)).ravel()
                    d = section.minimum_image(members[idx][None, :, :] - xs[:, None, :])
                    dist2 = np.einsum("abi,abi->ab", d, d)
                    reach = radii[:, None] + member_r[idx][None, :]
                    if np.any(dist2 < reach**2):
                        continue
            pos[placed] = c
            quat[placed] = q
            members[m : m + k] = xs
            placed += 1
            break
        else:
            height *= 1.25
    return pos, quat, height
