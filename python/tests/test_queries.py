"""Water queries against the surface mesh: a numpy brute force (every triangle) is the twin."""
from __future__ import annotations

import numpy as np
import pytest

import metariver


def vertical_crossings(v: np.ndarray, tri: np.ndarray, xz: np.ndarray) -> np.ndarray:
    """The highest y where the vertical line at each (x, z) crosses a triangle; NaN where none."""
    a, b, c = (v[tri[:, k]].astype(np.float64) for k in range(3))
    out = np.full(len(xz), np.nan)
    for k, (x, z) in enumerate(xz.astype(np.float64)):
        # barycentric coordinates in the xz plane
        d = (b[:, 2] - c[:, 2]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 2] - c[:, 2])
        ok = np.abs(d) > 1e-12
        d = np.where(ok, d, 1.0)
        l1 = ((b[:, 2] - c[:, 2]) * (x - c[:, 0]) + (c[:, 0] - b[:, 0]) * (z - c[:, 2])) / d
        l2 = ((c[:, 2] - a[:, 2]) * (x - c[:, 0]) + (a[:, 0] - c[:, 0]) * (z - c[:, 2])) / d
        l3 = 1.0 - l1 - l2
        inside = ok & (l1 >= -1e-6) & (l2 >= -1e-6) & (l3 >= -1e-6)
        if inside.any():
            y = l1 * a[:, 1] + l2 * b[:, 1] + l3 * c[:, 1]
            out[k] = y[inside].max()
    return out


@pytest.fixture
def upward_centroids(world):
    """Centroids (x, z) of 40 surface triangles that face up, and the mesh."""
    v, n, tri = world.surface()
    a, b, c = (v[tri[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    area = np.linalg.norm(normal, axis=1)
    up = np.flatnonzero(normal[:, 1] > 0.5 * area)
    assert len(up) >= 40
    pick = up[np.linspace(0, len(up) - 1, 40).astype(int)]
    centroids = (a[pick] + b[pick] + c[pick]) / 3.0
    return centroids, v, tri


def test_a_point_in_a_surface_triangle_is_wet_at_the_highest_crossing(world, upward_centroids):
    centroids, v, tri = upward_centroids
    xz = centroids[:, [0, 2]]
    s = world.sample(xz)
    assert s.shape == (40,) and s.dtype == metariver.WATER_SAMPLE_DTYPE
    assert s["wet"].all()
    expected = vertical_crossings(v, tri, xz)
    np.testing.assert_allclose(s["surface_y"], expected, atol=2e-3)
    assert np.all(s["surface_y"] >= centroids[:, 1] - 2e-3)  # at least the triangle's own plane
    assert np.all(s["depth"] >= 0) and (s["depth"] > 0).mean() > 0.8  # 0 where the surface dips under the ground
    assert np.all(np.isfinite(s["velocity"]))


def test_a_dry_point_is_the_ground(world):
    far = np.array([[0.5, 0.5], [39.0, 0.5]])  # the valley's upper rim corners: no water there
    s = world.sample(far)
    assert not s["wet"].any()
    assert np.all(s["depth"] == 0)
    np.testing.assert_allclose(s["surface_y"], world.terrain_heights()[0, [0, 39]], atol=0.2)


def test_sample_keeps_the_batch_shape(world):
    s = world.sample(np.zeros((4, 5, 2)) + 10.0)
    assert s.shape == (4, 5)
    with pytest.raises(ValueError, match="xz"):
        world.sample(np.zeros((3, 3)))


def test_a_non_finite_point_is_answered_alone(world, upward_centroids):
    """NaN or infinity in one point: that point is dry / still / missed, the others as without it
    (the rule of the C and C++ queries too)."""
    centroids, _, _ = upward_centroids
    xz = centroids[:, [0, 2]].copy()
    origins = centroids + np.array([0.0, 50.0, 0.0])
    good_s, good_v = world.sample(xz), world.velocity_at(centroids)
    good_h = world.raycast(origins, [0.0, -1.0, 0.0], max_distance=200.0)
    k = int(np.flatnonzero(good_s["wet"] & good_h["hit"].astype(bool) & (good_v[:, 0] != 0))[0])
    xz[k, 1], centroids[k, 0], origins[k, 2] = np.nan, np.inf, -np.inf
    bad_s, bad_v = world.sample(xz), world.velocity_at(centroids)
    bad_h = world.raycast(origins, [0.0, -1.0, 0.0], max_distance=200.0)
    others = np.arange(len(xz)) != k
    assert bad_s[k]["wet"] == 0 and bad_s[k]["surface_y"] == 0 and bad_s[k]["depth"] == 0
    assert np.all(bad_v[k] == 0) and bad_h[k]["hit"] == 0
    np.testing.assert_array_equal(bad_s[others], good_s[others])
    np.testing.assert_array_equal(bad_v[others], good_v[others])
    np.testing.assert_array_equal(bad_h[others], good_h[others])
    with pytest.raises(metariver.Error, match="max_distance"):
        world.raycast(origins, [0.0, -1.0, 0.0], max_distance=np.nan)


def test_a_ray_down_hits_the_highest_crossing(world, upward_centroids):
    centroids, v, tri = upward_centroids
    origins = centroids + np.array([0.0, 50.0, 0.0])
    hits = world.raycast(origins, [0.0, -1.0, 0.0], max_distance=200.0)
    assert hits["hit"].all()
    expected = vertical_crossings(v, tri, centroids[:, [0, 2]])
    np.testing.assert_allclose(hits["point"][:, 1], expected, atol=2e-3)
    np.testing.assert_allclose(hits["t"], 50.0 + centroids[:, 1] - expected, atol=2e-3)
    assert np.all(hits["normal"][:, 1] > 0)  # facing the origin above
    short = world.raycast(origins, [0.0, -1.0, 0.0], max_distance=1.0)
    assert not short["hit"].any()


def test_velocity_at_the_surface_and_far_away(world, upward_centroids):
    centroids, _, _ = upward_centroids
    near = world.velocity_at(centroids)
    assert near.shape == (40, 3) and np.all(np.isfinite(near))
    assert np.abs(near).sum() > 0
    far = world.velocity_at([[20.0, 1000.0, 30.0]])
    np.testing.assert_array_equal(far, np.zeros((1, 3), np.float32))
