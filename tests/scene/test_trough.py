"""The Python description of the kernel's walls and of the periodic section (dem.scene.trough)."""

import numpy as np

from dem.scene.trough import WALLS, Trough

L, W = 0.1, 0.04


def _points(n=200, seed=0):
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [rng.uniform(-L, 2 * L, n), rng.uniform(-W / 2, W / 2, n), rng.uniform(0, 0.02, n)]
    )


def test_wall_gaps_are_the_distances_along_the_inward_normals():
    x = _points()
    gaps = Trough(L, W).wall_gaps(x)
    assert gaps.shape == (4, len(x))
    assert np.all(np.isinf(gaps[3]))  # no back wall in a periodic section
    # the naive twin's walls (tests/oracles/naive_dem.py): floor, y = -W/2 (+y), y = +W/2 (-y)
    np.testing.assert_array_equal(gaps[0], x[:, 2])
    np.testing.assert_array_equal(gaps[1], x[:, 1] + W / 2)
    np.testing.assert_array_equal(gaps[2], W / 2 - x[:, 1])
    # moving a point by s along wall w's inward normal adds s to its gap there
    finite = Trough(L, W, discharge=0.8 * L)
    gaps = finite.wall_gaps(x)
    np.testing.assert_array_equal(gaps[3], x[:, 0])  # a feeder's back wall x = 0 (+x)
    for w, (_, normal) in enumerate(WALLS):
        moved = finite.wall_gaps(x + 1e-3 * np.array(normal))
        np.testing.assert_allclose(moved[w] - gaps[w], 1e-3, atol=1e-15)


def test_wall_corners_lie_on_their_walls():
    trough = Trough(L, W)
    corners = trough.wall_corners(0.02)
    assert corners.shape == (3, 4, 3)
    for w in range(3):
        np.testing.assert_array_equal(trough.wall_gaps(corners[w])[w], 0.0)
    lo, hi = corners.reshape(-1, 3).min(axis=0), corners.reshape(-1, 3).max(axis=0)
    np.testing.assert_array_equal(lo, [0.0, -W / 2, 0.0])
    np.testing.assert_array_equal(hi, [L, W / 2, 0.02])
    feeder = Trough(1.3 * L, W, discharge=L)  # the domain is longer than the trough
    corners = feeder.wall_corners(0.02)
    assert corners.shape == (4, 4, 3)
    for w in range(4):
        np.testing.assert_array_equal(feeder.wall_gaps(corners[w])[w], 0.0)
    assert corners[..., 0].max() == L


def test_wrap_and_minimum_image():
    trough = Trough(L, W)
    x = _points()
    wrapped = trough.wrap(x)
    assert np.all((wrapped[:, 0] >= 0.0) & (wrapped[:, 0] < L))
    np.testing.assert_array_equal(wrapped[:, 1:], x[:, 1:])
    assert not np.shares_memory(wrapped, x)
    d = x[:, None, :] - x[None, :20, :]
    m = trough.minimum_image(d)
    assert m.shape == d.shape and np.all(np.abs(m[..., 0]) <= L / 2 + 1e-15)
    shift = (d[..., 0] - m[..., 0]) / L
    np.testing.assert_allclose(shift, np.round(shift), atol=1e-9)
    np.testing.assert_array_equal(m[..., 1:], d[..., 1:])
