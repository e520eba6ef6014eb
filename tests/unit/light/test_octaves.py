"""Wrenninge's multiple-scattering octaves (`cloudcore.light.octaves`, the light pass "octaves"), and what the
shading models send out of a slab of particles against what comes in and against the adding-doubling slab."""

import dataclasses

import numpy as np
import pytest

from cloudcore.light import octaves, shading
from cloudcore.light.illumination import light_pass_method
from cloudcore.light.phase import phase_function
from cloudcore.light.shading import ALL_LIGHT, RETURNED_LIGHT, eye_pass_coefficients, incident_light, light_parts
from cloudcore.light.slab import slab
from cloudcore.maths.splat_kernel import KERNEL_DIAMETER_INTEGRAL, splat_kernel
from cloudcore.model.scene import Camera, Scene, Shading
from cloudcore.scenes.files import load_scene, save_scene

SUN = (0.0, 1.0, 0.0)  # overhead; y is up


def random_particles(count, seed=0, spread=30.0):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(count, 3)) * spread, rng.uniform(5.0, 15.0, count), rng.uniform(0.5, 8.0, count)


def test_one_octave_is_harris_s_frame_buffer_with_nothing_scattered_on(monkeypatch):
    """Octave 0 alone is the direct light: Harris's exact pass at albedo 0, where no particle scatters on."""
    positions, radii, tau = random_particles(400)
    monkeypatch.setattr(octaves, "OCTAVES", 1)
    direct = incident_light(positions, radii, tau, 0.9, (0.3, 1.0, 0.2), method="octaves")
    harris = incident_light(positions, radii, tau, 0.0, (0.3, 1.0, 0.2), method="exact")
    np.testing.assert_allclose(direct, harris, rtol=1e-12, atol=1e-15)


def test_the_octaves_add_the_light_the_direct_beam_lost_weighted():
    """Two particles in a row (the second's centre on the first's axis): the first, unshadowed, gets 1; the one
    behind exp(-tau) + sum_{i >= 1} b^i (exp(-a^i tau) - exp(-tau))."""
    tau = 6.0
    light = incident_light([[0.0, 10.0, 0.0], [0.0, 0.0, 0.0]], 5.0, tau, 0.99, SUN, method="octaves")
    i = np.arange(1, octaves.OCTAVES)
    direct = np.exp(-tau)
    expected = direct + np.sum(octaves.SCATTERING_SCALE**i * (np.exp(-(octaves.EXTINCTION_SCALE**i) * tau) - direct))
    assert light[0] == pytest.approx(1.0)
    assert light[1] == pytest.approx(expected, rel=1e-12)
    assert light[1] > 10.0 * direct  # the multiply scattered light reaches further than the direct


def test_the_octaves_light_stays_within_its_bounds_and_fades_into_a_cloud():
    positions, radii, tau = random_particles(2000, seed=3)
    light = incident_light(positions, radii, tau, 0.99, SUN, method="octaves")
    assert np.all(np.isfinite(light))
    assert light.min() >= 0.0 and light.max() <= 1.0 + 1e-12 and octaves.most_light() == 1.0
    top, bottom = positions[:, 1] > 30.0, positions[:, 1] < -30.0
    assert light[top].mean() > 2.0 * light[bottom].mean()


def test_extreme_optical_depths_give_no_nan():
    light = incident_light([[0.0, 10.0, 0.0], [0.0, 0.0, 0.0]], 5.0, [1e6, 1e6], 1.0, SUN, method="octaves")
    assert np.all(np.isfinite(light)) and light[1] == pytest.approx(0.0, abs=1e-300)


def test_the_light_pass_setting_chooses_the_octaves_for_exact_and_raster_only():
    shading = dataclasses.replace(Shading(), light_pass="octaves")
    assert light_pass_method(shading, "exact") == "octaves"
    assert light_pass_method(shading, "raster") == "octaves"
    assert light_pass_method(shading, "preview") == "preview"


# ---------------------------------------------------------------- a slab of particles: light in, light out

WIDTH, HEIGHT, MARGIN = 24.0, 6.0, 1.5  # particles of radius 1
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(16)
GAUSS_MU, GAUSS_WEIGHTS = 0.5 * (_NODES + 1.0), 0.5 * _WEIGHTS  # over (0, 1)


def _kernel_means() -> tuple[float, float]:
    """(mean of the splat kernel over its disc, integral of the blob's K(|u|) over the unit ball)."""
    q = np.linspace(0.0, 1.0, 4001)
    k = splat_kernel(q)
    return 2.0 * np.trapezoid(k * q, q), 4.0 * np.pi * np.trapezoid(k * q * q, q)


def slab_fluxes(eye_pass, method, albedo, column_tau, tau=8.0, phase="rayleigh", seed=0):
    """(reflected, transmitted scattered, transmitted direct) flux, per unit flux of a sun overhead, of a model's
    slab of random particles of radius 1 and optical depth `tau` whose medium (the truth's blobs) has vertical
    optical thickness `column_tau`.

    The model's picture averaged over where the particles fall: a ray meets splats at the rate n pi r^2 per unit
    length, each covering it with the kernel's mean over its disc, and is let through by the ones in front on
    average as exp(-n pi r^2 <alpha K> s) (independent positions); each splat sends its eye-pass colour, the
    scattering coefficient times the phase function times its light (the part a lit face sent back times the
    phase function's mean, 1).  The light comes from the model's pass over
    the particles, those within a margin of the sides left out (they miss their neighbours' shadows).
    """
    mean_kernel, blob_integral = _kernel_means()
    density = column_tau / (HEIGHT * tau / KERNEL_DIAMETER_INTEGRAL * blob_integral)
    rng = np.random.default_rng(seed)
    count = int(round(density * WIDTH * WIDTH * HEIGHT))
    positions = rng.uniform([-WIDTH / 2, 0.0, -WIDTH / 2], [WIDTH / 2, HEIGHT, WIDTH / 2], (count, 3))
    parts = light_parts(positions, 1.0, tau, albedo, SUN, phase=phase, method=method)
    scattering, _ = eye_pass_coefficients(np.full(count, tau), np.full(count, albedo), phase, 0.0, eye_pass)
    inside = np.all(np.abs(positions[:, [0, 2]]) < WIDTH / 2 - MARGIN, axis=1)
    area = (WIDTH - 2 * MARGIN) ** 2
    extinction = density * np.pi * -np.expm1(-tau) * mean_kernel  # the splats' <alpha K> per unit length
    # the light along the sun's direction, scattered at the angle to it; what a lit face sent back, from every
    # direction, with the phase function's mean
    returned = scattering[inside] * parts[inside, RETURNED_LIGHT]
    along = scattering[inside] * parts[inside, ALL_LIGHT] - returned
    below_top, above_bottom = HEIGHT - positions[inside, 1], positions[inside, 1]

    def flux(depth, toward_light):
        radiance = [
            np.sum(
                np.pi
                * mean_kernel
                / (mu * area)
                * (along * phase_function(toward_light * mu, phase, 0.0) + returned)
                * np.exp(-extinction * depth / mu)
            )
            for mu in GAUSS_MU
        ]
        return 2.0 * np.pi * np.sum(GAUSS_WEIGHTS * GAUSS_MU * np.array(radiance))

    # seen from above the view ray runs against the light (cos -mu), from below with it
    return flux(below_top, -1.0), flux(above_bottom, 1.0), float(np.exp(-extinction * HEIGHT))


@pytest.mark.parametrize("column_tau", [1.0, 4.0, 16.0, 64.0])
@pytest.mark.parametrize("eye_pass, method", [("saturated", "octaves"), ("saturated", "exact")])
def test_no_model_sends_out_of_a_white_slab_more_light_than_comes_in(eye_pass, method, column_tau):
    reflected, transmitted, direct = slab_fluxes(eye_pass, method, 1.0, column_tau)
    assert reflected > 0.0 and transmitted >= 0.0
    assert reflected + transmitted + direct <= 1.0


def test_frostbite_s_sum_of_octaves_sends_more_light_out_of_a_sparse_slab_than_comes_in(monkeypatch):
    """Why the octaves count only the light the direct beam lost: summed as Frostbite sums them, b^i T_i, a lone
    opaque particle gets 1 + b + b^2 of the light and scatters more than it stops."""
    monkeypatch.setattr(shading, "octave_light", lambda through: through @ octaves.octave_weights())
    monkeypatch.setattr(shading, "most_light", lambda: float(octaves.octave_weights().sum()))
    reflected, transmitted, direct = slab_fluxes("saturated", "octaves", 1.0, 1.0)
    assert reflected + transmitted + direct > 1.02


def test_harris_s_eye_pass_sends_out_of_a_slab_several_times_the_light_that_comes_in():
    """Why the new model does not build on it: each opaque particle scatters a tau / (4 pi) = 0.64 of its light
    per steradian-weighted phase (sigma_eff caps only the forward part), and the light pass keeps 94% a particle."""
    reflected, transmitted, direct = slab_fluxes("harris", "exact", 1.0, 16.0)
    assert reflected + transmitted + direct > 3.0


def test_against_a_white_medium_the_octaves_transmit_closer_and_both_models_reflect_far_less():
    """Against adding-doubling at albedo 1 (the truth's medium, a thick slab of optical thickness 64): it sends
    back 0.97 and on 0.03; the saturated eye pass over Harris's light sends back 0.29 and on 0.2 (Harris's light
    pass keeps 94% a particle), the octaves 0.17 and nothing: closer below, further above (docs/shading.md)."""
    medium = slab(64.0, 1.0, "rayleigh")
    medium_reflected, medium_transmitted = medium.plane_albedo()[-1], medium.plane_transmittance()[-1]
    octave_reflected, octave_transmitted, _ = slab_fluxes("saturated", "octaves", 1.0, 64.0)
    saturated_reflected, saturated_transmitted, _ = slab_fluxes("saturated", "exact", 1.0, 64.0)
    assert octave_reflected < saturated_reflected < 0.5 * medium_reflected
    assert abs(octave_transmitted - medium_transmitted) < abs(saturated_transmitted - medium_transmitted)


def test_a_scene_file_asks_for_the_octaves(tmp_path):
    scene = dataclasses.replace(
        Scene(camera=Camera((0.0, 0.0, 10.0), (0.0, 0.0, 0.0), 60.0)),
        shading=Shading(albedo=0.99, eye_pass="saturated", light_pass="octaves"),
    )
    save_scene(scene, tmp_path / "s.toml")
    assert 'light_pass = "octaves"' in (tmp_path / "s.toml").read_text()
    assert load_scene(tmp_path / "s.toml").shading == scene.shading
