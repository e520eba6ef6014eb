"""The light a cloud's lit face sends back (`cloudcore.light.lit_face`, the light pass "octaves-lit-face"): the
medium behind a particle as an adding-doubling slab, and what it does to the octaves' light."""

import dataclasses

import numpy as np
import pytest

from cloudcore.light import octaves
from cloudcore.light.illumination import light_pass_method
from cloudcore.light.lit_face import MOST_RETURN, lit_face_return
from cloudcore.light.shading import incident_light
from cloudcore.light.slab import slab
from cloudcore.model.scene import Camera, Scene, Shading
from cloudcore.scenes.files import load_scene, save_scene
from tests.unit.light.test_octaves import SUN, random_particles, slab_fluxes


@pytest.mark.parametrize("albedo", [0.9, 0.99, 1.0])
@pytest.mark.parametrize("depth", [0.05, 0.7, 7.3, 130.0])
def test_the_return_is_twice_the_slab_s_spherical_albedo(depth, albedo):
    """Off the table's nodes too: within 1% of the slab made at that thickness."""
    expected = 2.0 * slab(depth, albedo, "rayleigh").spherical_albedo()
    assert lit_face_return([depth], albedo)[0] == pytest.approx(expected, rel=1e-2)


def test_nothing_behind_nothing_back_and_a_white_half_space_all_of_it():
    assert lit_face_return([0.0], 0.99)[0] == 0.0
    assert lit_face_return([1e6], 1.0)[0] == pytest.approx(MOST_RETURN, rel=1e-3)
    assert lit_face_return([1e6], 0.0)[0] == 0.0


def test_extremes_stay_finite_and_within_bounds():
    depths = np.array([0.0, 1e-12, 1.0, 1e4, 1e6, 1e300])
    for albedo in (0.0, 0.5, 0.999, 1.0):
        for phase, g in (("rayleigh", 0.0), ("henyey-greenstein", 0.999), ("henyey-greenstein", -0.999)):
            back = lit_face_return(depths, albedo, phase, g)
            assert np.all(np.isfinite(back)) and back.min() >= 0.0 and back.max() <= MOST_RETURN
            assert np.all(np.diff(back) >= -1e-12)  # more medium behind never sends back less


def test_a_forward_phase_function_sends_back_less_by_the_similarity_relations():
    """g = 0 is the isotropic slab; a forward lobe sends more of the light on, so less comes back."""
    isotropic = 2.0 * slab(20.0, 0.99, "isotropic").spherical_albedo()
    assert lit_face_return([20.0], 0.99, "henyey-greenstein", 0.0)[0] == pytest.approx(isotropic, rel=1e-2)
    forward = lit_face_return([20.0], 0.99, "henyey-greenstein", 0.85)[0]
    shrink = 1.0 - 0.99 * 0.85
    similar = 2.0 * slab(20.0 * shrink, 0.99 * 0.15 / shrink, "isotropic").spherical_albedo()
    assert forward == pytest.approx(similar, rel=1e-2) and forward < 0.8 * isotropic


def test_per_particle_albedos_each_take_their_own_slab():
    back = lit_face_return([50.0, 50.0, 50.0], np.array([0.9, 0.99, 0.9]))
    assert back[0] == back[2] < back[1]


def test_a_particle_with_one_behind_it_gets_the_slab_s_return_and_the_one_behind_nothing_more():
    """Two particles in a row along the light: the front one has the back one's optical depth behind its centre
    (its splat covers the centre with K(0) = 1), so its light 1 becomes 1 + 2 R(tau); the back one keeps its
    octaves' light."""
    tau, albedo = 6.0, 0.99
    pair = [[0.0, 10.0, 0.0], [0.0, 0.0, 0.0]]
    plain = incident_light(pair, 5.0, tau, albedo, SUN, method="octaves")
    lit = incident_light(pair, 5.0, tau, albedo, SUN, method="octaves-lit-face")
    assert lit[0] == pytest.approx(1.0 + 2.0 * slab(tau, albedo, "rayleigh").spherical_albedo(), rel=1e-2)
    assert lit[1] == pytest.approx(plain[1], rel=1e-12)


def test_the_lit_face_brightens_the_side_toward_the_light_more_and_never_darkens():
    positions, radii, tau = random_particles(2000, seed=3)
    plain = incident_light(positions, radii, tau, 0.99, SUN, method="octaves")
    lit = incident_light(positions, radii, tau, 0.99, SUN, method="octaves-lit-face")
    assert np.all(np.isfinite(lit)) and np.all(lit >= plain * (1.0 - 1e-12))  # the sums in another order
    assert lit.max() <= octaves.most_light() * (1.0 + MOST_RETURN)
    gain = lit / np.maximum(plain, np.finfo(np.float64).tiny)
    top, bottom = positions[:, 1] > 45.0, positions[:, 1] < -45.0
    assert gain[top].mean() > gain[bottom].mean() + 0.5


def test_extreme_optical_depths_give_no_nan():
    light = incident_light([[0.0, 10.0, 0.0], [0.0, 0.0, 0.0]], 5.0, [1e6, 1e6], 1.0, SUN, method="octaves-lit-face")
    # the light pass's transmittance stops at the smallest double, an optical depth of 708 behind: R = 0.998
    assert np.all(np.isfinite(light)) and light[0] == pytest.approx(1.0 + MOST_RETURN, rel=1e-2)


@pytest.mark.parametrize("column_tau", [1.0, 4.0, 16.0, 64.0])
def test_the_lit_face_sends_out_of_a_white_slab_no_more_than_comes_in(column_tau):
    reflected, transmitted, direct = slab_fluxes("saturated", "octaves-lit-face", 1.0, column_tau)
    assert reflected + transmitted + direct <= 1.0


def test_against_a_white_medium_the_lit_face_reflects_more_than_the_octaves_alone():
    """The slab of optical thickness 64 at albedo 1 sends back 0.97; the octaves 0.17 (docs/shading.md)."""
    medium_reflected = slab(64.0, 1.0, "rayleigh").plane_albedo()[-1]
    octave_reflected, _, _ = slab_fluxes("saturated", "octaves", 1.0, 64.0)
    lit_reflected, _, _ = slab_fluxes("saturated", "octaves-lit-face", 1.0, 64.0)
    assert octave_reflected < lit_reflected < medium_reflected


def test_the_light_pass_setting_chooses_it_for_exact_and_raster_only(tmp_path):
    shading = dataclasses.replace(Shading(), light_pass="octaves-lit-face")
    assert light_pass_method(shading, "exact") == "octaves-lit-face"
    assert light_pass_method(shading, "raster") == "octaves-lit-face"
    assert light_pass_method(shading, "preview") == "preview"
    scene = dataclasses.replace(Scene(camera=Camera((0.0, 0.0, 10.0), (0.0, 0.0, 0.0), 60.0)), shading=shading)
    save_scene(scene, tmp_path / "s.toml")
    assert load_scene(tmp_path / "s.toml").shading == shading


@pytest.mark.parametrize("spread_radii", [False, True])
def test_the_depth_behind_is_the_direct_light_from_the_other_side(monkeypatch, spread_radii):
    """One search finds the splats ahead and behind: the depth behind a particle is what the direct light alone
    (one octave) finds lit from the opposite direction, with radii alike and with radii far apart."""
    positions, radii, tau = random_particles(600, seed=5)
    if spread_radii:
        radii = radii * np.random.default_rng(6).choice([1.0, 8.0], len(radii))
    light = (0.3, 1.0, 0.2)
    lit = incident_light(positions, radii, tau, 0.99, light, method="octaves-lit-face")
    plain = incident_light(positions, radii, tau, 0.99, light, method="octaves")
    monkeypatch.setattr(octaves, "OCTAVES", 1)
    behind = incident_light(positions, radii, tau, 0.99, tuple(-v for v in light), method="octaves")
    expected = plain * (1.0 + lit_face_return(-np.log(np.maximum(behind, np.finfo(np.float64).tiny)), 0.99))
    np.testing.assert_allclose(lit, expected, rtol=1e-9, atol=1e-12)


def test_the_eye_pass_scatters_the_returned_light_with_the_phase_function_s_mean():
    """Two particles in a row along the sun: the front one's light is the sun's along its direction plus what the
    one behind sends back, which arrives from every direction; seen from anywhere, the eye pass scatters the first
    part at the angle to the sun and the second as the phase function's mean, 1."""
    from cloudcore.light.phase import phase_function
    from cloudcore.model.scene import Cloud, Light
    from cloudcore.particles.buffer import ParticleBuffer

    sun = Light(SUN, (1.0, 0.9, 0.8), 2.0)
    cloud = Cloud("pair", [[0.0, 10.0, 0.0, 5.0], [0.0, 0.0, 0.0, 5.0]], optical_depth=6.0)
    shading = Shading(albedo=0.99, eye_pass="saturated", light_pass="octaves-lit-face")
    particles = ParticleBuffer((cloud,), shading, (sun,), (0.0, 0.0, 0.0))
    plain = ParticleBuffer((cloud,), dataclasses.replace(shading, light_pass="octaves"), (sun,), (0.0, 0.0, 0.0))
    assert plain.returned is None
    back = particles.returned[0, 0]
    assert back == pytest.approx(particles.incident[0, 0] - plain.incident[0, 0], rel=1e-12) and back > 1.0
    for eye in ([0.0, 100.0, 0.0], [100.0, 10.0, 0.0], [0.0, 10.0, 100.0], [30.0, -80.0, 10.0]):
        colour, _ = particles.seen_from(eye, np.array([0]))
        view = (particles.centres[0] - eye) / np.linalg.norm(particles.centres[0] - eye)
        along = plain.incident[0, 0] * phase_function(view @ plain.light_directions[0], "rayleigh", 0.0)
        expected = particles.scattering[0] * (along + back) * np.array(sun.color) * sun.intensity
        np.testing.assert_allclose(colour[0], expected, rtol=1e-12)
