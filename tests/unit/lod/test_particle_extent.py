"""`particle_extent`: the part of a texture that splats can cover, which impostor quads and screen
impostors are cropped to, must hold every point of every splat (a crop too tight cuts clouds off)."""

import numpy as np

from cloudcore.lod.impostors import particle_extent
from cloudcore.world.camera import projection_matrix

SIZE = (160, 120)
PROJECTION = projection_matrix(60.0, SIZE[0] / SIZE[1], near=0.1, far=1e4)


def sphere_points(centres, radii, per_sphere=400, seed=0) -> np.ndarray:
    """Points on the spheres' surfaces, the silhouettes among them to within a fraction of a degree."""
    directions = np.random.default_rng(seed).normal(size=(per_sphere, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return (centres[:, None, :] + radii[:, None, None] * directions[None]).reshape(-1, 3)


def texture_uv(points) -> np.ndarray:
    """(u, v) in [0, 1] of eye-space `points` through PROJECTION (the view is the identity)."""
    clip = np.c_[points, np.ones(len(points))] @ PROJECTION.T
    return 0.5 * (clip[:, :2] / clip[:, 3:] + 1.0)


def covers(extent, uv) -> bool:
    """Whether `extent` holds the points `uv` that fall on the texture."""
    uv = np.clip(uv, 0.0, 1.0)
    u0, v0, u1, v1 = extent
    return bool(np.all((uv[:, 0] >= u0) & (uv[:, 0] <= u1) & (uv[:, 1] >= v0) & (uv[:, 1] <= v1)))


def test_a_sphere_off_to_one_side_is_covered_to_its_silhouette():
    # wholly right of and above the axis, near: (x - r) / (depth - r) would start right of its left edge
    centres, radii = np.array([[4.0, 2.5, -6.0]]), np.array([1.0])
    extent = particle_extent(np.eye(4), PROJECTION, centres, radii, SIZE)
    assert covers(extent, texture_uv(sphere_points(centres, radii)))
    assert extent[0] > 0.5 and extent[1] > 0.5  # and still cropped: all of it right of and above the centre


def test_random_splats_in_front_of_the_eye_are_covered():
    rng = np.random.default_rng(7)
    for _ in range(50):
        count = rng.integers(1, 30)
        radii = rng.uniform(0.1, 3.0, count)
        depths = radii + rng.uniform(0.05, 40.0, count)
        centres = np.c_[rng.uniform(-1.0, 1.0, (count, 2)) * depths[:, None], -depths]
        extent = particle_extent(np.eye(4), PROJECTION, centres, radii, SIZE)
        uv = texture_uv(sphere_points(centres, radii, per_sphere=200, seed=int(rng.integers(1 << 30))))
        assert covers(extent, uv)


def test_a_splat_reaching_behind_the_eye_takes_the_whole_texture_and_none_takes_nothing():
    assert particle_extent(np.eye(4), PROJECTION, np.array([[0.0, 0.0, -0.5]]), np.array([1.0]), SIZE) == (
        0.0,
        0.0,
        1.0,
        1.0,
    )
    assert particle_extent(np.eye(4), PROJECTION, np.zeros((0, 3)), np.zeros(0), SIZE) == (0.0, 0.0, 0.0, 0.0)
