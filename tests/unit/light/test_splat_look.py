"""The splats' look per pixel, pure (`cloudcore.light.splat_look`, the kernel's chord integrals of
`cloudcore.maths.splat_kernel`), and its settings refused in one line."""

import math

import numpy as np
import pytest

from cloudcore.light.splat_look import (
    SplatLook,
    chord_opacity,
    inner_light_depth,
    own_optical_depth,
    sun_light_factor,
)
from cloudcore.maths.splat_kernel import (
    KERNEL_DIAMETER_INTEGRAL,
    kernel_chord_integral,
    kernel_ray_integral,
    splat_kernel,
)
from cloudcore.model.settings import RenderSettings
from tests.conftest import assert_file_refused_in_one_line


def quadrature(start, direction, points=20001) -> float:
    """K's integral from `start` to the unit sphere along `direction`, by the trapezoid rule."""
    along = float(np.dot(start, direction))
    exit_at = -along + math.sqrt(along * along - float(np.dot(start, start)) + 1.0)
    u = np.linspace(0.0, exit_at, points)
    return float(np.trapezoid(splat_kernel(np.linalg.norm(start + u[:, None] * direction, axis=1)), u))


@pytest.mark.parametrize(
    "start, direction",
    [
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.3, -0.2, 0.1], [0.6, 0.0, 0.8]),
        ([0.3, -0.2, 0.1], [-0.6, 0.0, -0.8]),
        ([0.0, 0.9, 0.0], [0.0, -1.0, 0.0]),
        ([0.7, 0.0, -0.7], [0.0, 0.0, 1.0]),
    ],
)
def test_the_ray_integral_is_the_kernel_summed_to_the_sphere(start, direction):
    start, direction = np.array(start), np.array(direction)
    assert float(kernel_ray_integral(start, direction)) == pytest.approx(quadrature(start, direction), rel=1e-6)


def test_the_chord_integral_is_the_diameter_through_the_centre_and_none_past_the_edge():
    assert float(kernel_chord_integral(0.0)) == pytest.approx(KERNEL_DIAMETER_INTEGRAL, rel=1e-12)
    b = 0.6
    assert float(kernel_chord_integral(b * b)) == pytest.approx(
        quadrature(np.array([b, 0.0, -math.sqrt(1 - b * b)]), np.array([0.0, 0.0, 1.0])), rel=1e-6
    )
    np.testing.assert_array_equal(kernel_chord_integral([1.0, 2.0]), [0.0, 0.0])
    assert np.all(np.diff(kernel_chord_integral(np.linspace(0.0, 1.0, 50))) < 0)


def test_a_pixel_is_the_particle_through_its_centre_and_clear_past_its_edge():
    alphas = np.array([0.0, 0.1, 0.5, 0.99, 1.0])
    np.testing.assert_allclose(chord_opacity(alphas, 0.0), np.minimum(alphas, 1 - 1e-6), rtol=1e-12)
    np.testing.assert_array_equal(chord_opacity(alphas, 1.0), 0.0)
    assert np.all(np.isfinite(own_optical_depth(alphas)))
    # the chord's depth falls as the kernel's profile, its opacity slower: more opaque than alpha K(b) off the centre
    b2 = np.linspace(0.05, 0.85, 9)  # within 0.92 radii; at the very rim the kernel, floored, holds on longer
    assert np.all(chord_opacity(0.9, b2) > 0.9 * splat_kernel(np.sqrt(b2)))


def test_the_sun_light_is_the_particles_at_its_centre_and_more_on_the_sun_side():
    sun = np.array([0.0, 1.0, 0.0])
    assert float(sun_light_factor(np.zeros(3), sun, 3.0)) == pytest.approx(1.0)
    toward, away = sun_light_factor(np.array([0.0, 0.4, 0.0]), sun, 3.0), sun_light_factor(-0.4 * sun, sun, 3.0)
    assert toward > 1.0 > away > 0.0
    np.testing.assert_array_equal(sun_light_factor(np.array([0.0, 0.4, 0.0]), sun, 0.0), 1.0)
    # the diffusion's attenuation: none in a conservative particle, the extinction's at albedo 2/3
    np.testing.assert_allclose(inner_light_depth([8.0, 8.0, 8.0], [1.0, 0.99, 2.0 / 3.0]), [0.0, 8 * 0.03**0.5, 8.0])


def test_the_look_is_plain_by_default_and_keys_the_clouds_otherwise():
    assert SplatLook.of(RenderSettings()) == SplatLook() and SplatLook().plain and SplatLook().key == ()
    look = SplatLook.of(RenderSettings(particle_shading="per_pixel", detail_noise=0.25, detail_noise_scale_m=5.0))
    assert look == SplatLook(True, 0.25, 5.0) and not look.plain and look.key == (True, 0.25, 5.0)
    assert SplatLook.of(RenderSettings(detail_noise_scale_m=5.0)).plain  # a scale without noise is no look


@pytest.mark.parametrize(
    "setting, message",
    [
        ({"particle_shading": "per_voxel"}, "particle_shading must be one of per_particle, per_pixel, got 'per_voxel'"),
        ({"detail_noise": -0.1}, "detail_noise must be within [0, 1], got -0.1"),
        ({"detail_noise": math.nan}, "detail_noise must be within [0, 1], got nan"),
        ({"detail_noise": True}, "detail_noise must be within [0, 1], got True"),
        ({"detail_noise_scale_m": 0.0}, "detail_noise_scale_m must be within (0, 10000] metres, got 0.0"),
        ({"detail_noise_scale_m": math.inf}, "detail_noise_scale_m must be within (0, 10000] metres, got inf"),
        (
            {"blending": "volume", "particle_shading": "per_pixel"},
            "blending 'volume' composites splats of one colour: it takes neither per-pixel shading nor detail noise",
        ),
    ],
)
def test_bad_looks_are_refused_in_one_line(setting, message):
    with pytest.raises(ValueError) as caught:
        RenderSettings(**setting)
    assert str(caught.value) == message


@pytest.mark.parametrize(
    "line, field, problem",
    [
        ('particle_shading = "per_voxel"', "particle_shading", "'per_voxel' is not one of: per_particle, per_pixel"),
        ("detail_noise = 2.0", "settings", "detail_noise must be within [0, 1], got 2.0"),
        ("detail_noise_scale_m = -3.0", "settings", "detail_noise_scale_m must be within (0, 10000] metres, got -3.0"),
    ],
)
def test_a_views_bad_look_is_refused_in_one_line_naming_file_and_field(tmp_path, line, field, problem):
    path = tmp_path / "scene.toml"
    path.write_text(
        "[camera]\nposition = [0.0, 500.0, 1500.0]\nlook_at = [0.0, 800.0, 0.0]\n\n"
        f'[[views]]\nname = "v"\n[views.settings]\n{line}\n'
    )
    full_field = "views[0]." + ("settings" if field == "settings" else f"settings.{field}")
    assert_file_refused_in_one_line(path, full_field, problem)


def test_the_closed_form_is_yusovs_chord_table():
    """The shader's closed form and the reference particle's chord table (`cloudcore.light.precomputed`, by
    quadrature and read bilinearly) are the same depth: the per-pixel pass needs no table."""
    from cloudcore.light.precomputed import chord_depths, chord_optical_depth

    rng = np.random.default_rng(3)
    points = rng.uniform(-0.55, 0.55, (200, 3))
    directions = rng.normal(size=(200, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    closed = kernel_ray_integral(points, directions) / KERNEL_DIAMETER_INTEGRAL
    np.testing.assert_allclose(closed, chord_optical_depth(chord_depths(), points, directions), atol=2e-3)
