"""The fill: seeded, overlap-free, inside the walls, and the same grains as the O(N^2) oracle."""

import numpy as np
import pytest
from naive_fill import naive_fill, naive_fill_clumps

from dem.scene import fill, shapes
from dem.scene.trough import Trough


def overlaps(pos: np.ndarray, radius: np.ndarray, length: float) -> int:
    """Pairs closer than the sum of their radii (periodic in x), brute force in chunks."""
    section = Trough(length, 1.0)
    bad = 0
    for i in range(0, len(pos), 500):
        d = section.minimum_image(pos[i : i + 500, None, :] - pos[None, :, :])
        dist2 = np.einsum("abk,abk->ab", d, d)
        reach = radius[i : i + 500, None] + radius[None, :]
        close = dist2 < reach**2 * (1 - 1e-12)
        rows = np.arange(i, min(i + 500, len(pos)))
        close[rows - i, rows] = False
        bad += int(close.sum())
    return bad // 2


@pytest.mark.parametrize(
    ("n", "length", "width"),
    [(1500, 0.10, 0.04), (400, 0.012, 0.01), (3000, 0.05, 0.02)],
    ids=["sphere-bed", "narrow: fewer than 3 cells, the box grows", "deep"],
)
@pytest.mark.validation
def test_sphere_fill_is_the_oracles_bit_for_bit(n, length, width):
    new, h_new = fill.random_fill(n, 0.002, length, width, np.random.default_rng(11))
    old, h_old = naive_fill(n, 0.002, length, width, np.random.default_rng(11))
    assert np.array_equal(new, old) and h_new == h_old


@pytest.mark.validation
def test_clump_fill_is_the_oracles_bit_for_bit():
    screw = shapes.screw(0.022, 0.0018, 0.0036, mass=0.0025)
    for n, length, width in [(200, 0.12, 0.06), (60, 0.05, 0.02)]:
        new = fill.random_fill_clumps(n, screw, length, width, np.random.default_rng(5))
        old = naive_fill_clumps(n, screw, length, width, np.random.default_rng(5))
        assert all(np.array_equal(a, b) for a, b in zip(new[:2], old[:2], strict=True))
        assert new[2] == old[2]


@pytest.mark.validation
def test_fill_is_seeded_overlap_free_and_inside_the_walls():
    r, length, width = 0.002, 0.08, 0.03
    a, h = fill.random_fill(4000, r, length, width, np.random.default_rng(1))
    b, _ = fill.random_fill(4000, r, length, width, np.random.default_rng(1))
    c, _ = fill.random_fill(4000, r, length, width, np.random.default_rng(2))
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert overlaps(a, np.full(len(a), r), length) == 0
    assert (a[:, 0] >= 0).all() and (a[:, 0] < length).all()
    assert (np.abs(a[:, 1]) <= width / 2 - r + 1e-15).all()
    assert (a[:, 2] >= r).all() and (a[:, 2] <= h - r + 1e-15).all()


@pytest.mark.validation
def test_clump_fill_members_never_overlap():
    screw = shapes.screw(0.022, 0.0018, 0.0036, mass=0.0025)
    length, width = 0.1, 0.05
    pos, quat, _ = fill.random_fill_clumps(300, screw, length, width, np.random.default_rng(3))
    from dem.kernels.rigid import quat_to_matrix

    members = np.concatenate(
        [p + screw.centres @ quat_to_matrix(q).T for p, q in zip(pos, quat, strict=True)]
    )
    radii = np.tile(screw.radii, len(pos))
    body = np.repeat(np.arange(len(pos)), screw.count)
    section = Trough(length, 1.0)
    d = section.minimum_image(members[:, None, :] - members[None, :, :])
    dist2 = np.einsum("abk,abk->ab", d, d)
    close = (dist2 < (radii[:, None] + radii[None, :]) ** 2) & (body[:, None] != body[None, :])
    assert not close.any()
    assert (members[:, 2] >= radii - 1e-15).all()
    assert (np.abs(members[:, 1]) <= width / 2 - radii + 1e-15).all()


@pytest.mark.validation
def test_a_large_fill_scales_linearly():
    """200,000 spheres: the grid keeps each try local (the O(N^2) oracle would take hours)."""
    pos, h = fill.random_fill(200_000, 0.002, 1.0, 0.2, np.random.default_rng(4))
    assert pos.shape == (200_000, 3) and np.isfinite(pos).all()
    # overlap-free in a sample: 2000 spheres against all their neighbours in a thin slab
    slab = pos[(pos[:, 0] > 0.5) & (pos[:, 0] < 0.52)]
    assert overlaps(slab, np.full(len(slab), 0.002), 1.0) == 0
