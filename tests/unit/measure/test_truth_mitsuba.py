"""The path-traced truth (Mitsuba 3, `cloudview[truth]`): transmittance, determinism, orientation, the CLI."""

import dataclasses
import json
import subprocess
import sys

import imageio.v3 as iio
import numpy as np
import pytest

from cloudcore.light.phase import phase_function
from cloudcore.light.shading import scattering_coefficient
from cloudcore.light.slab import slab
from cloudcore.measure.truth import (
    integrator_description,
    medium_grids,
    mitsuba_scene_description,
    mitsuba_variant,
    optical_depths,
    render_truth,
)
from cloudcore.model.scene import Camera, Cloud, Light, Lighting, Scene, Shading, Terrain
from cloudcore.scenes.files import save_scene
from cloudcore.world.camera import pixel_rays

mi = pytest.importorskip("mitsuba")

CENTRE = (0.0, 1000.0, 0.0)
#: a light of intensity 0: explicit lights that give none (no lights at all would mean the time of day's)
DARK = (Light((0.0, 1.0, 0.0), intensity=0.0),)
RADIUS = 50.0


def particle_scene(tau, albedo=0.9, lights=(Light((0.3, 0.9, 0.3), (1.0, 1.0, 1.0), 1.0),), ambient=(0.0, 0.0, 0.0)):
    return Scene(
        camera=Camera((0.0, 1000.0, 300.0), CENTRE, 40.0),
        lighting=Lighting(time_of_day=None, lights=lights, ambient=ambient),
        shading=Shading(albedo=albedo, optical_depth=tau),
        clouds=(Cloud("one", [[*CENTRE, RADIUS]]),),
    )


@pytest.mark.parametrize("tau", [0.3, 4.0])
def test_the_background_through_a_particle_s_centre_is_dimmed_by_exp_minus_tau(tau):
    """Absorbing only, lit by nothing but a visible white environment: each pixel is the transmittance."""
    scene = particle_scene(tau, albedo=0.0, lights=DARK, ambient=(1.0, 1.0, 1.0))
    # a narrow view (about 3 m across at the particle) of rays through its centre
    camera = Camera((0.0, 1000.0, 1000.0), CENTRE, 0.2)
    mitsuba_variant()
    grids = medium_grids(scene, 6.0)
    description = mitsuba_scene_description(grids, scene, camera, 4, 4)
    description["integrator"]["hide_emitters"] = False
    image = np.asarray(mi.render(mi.load_dict(description), spp=1024, seed=3), dtype=np.float64)
    seen = image.mean()
    # the grid's own optical depth through the centre, within 2% of tau (tests/unit/measure/test_truth.py)
    marched = optical_depths(grids, [camera.position], [[0.0, 0.0, -1.0]])[0][0]
    assert marched == pytest.approx(tau, rel=0.02)
    # the estimator of an absorbing medium is a hit or a miss per sample: binomial noise over 16 x 1024 samples
    expected = np.exp(-marched)
    noise = np.sqrt(expected * (1 - expected) / (16 * 1024))
    assert abs(seen - expected) < 4 * noise + 0.002 * expected


def test_a_seed_gives_the_same_picture_and_another_seed_another():
    scene = particle_scene(4.0)
    first, again, other = (render_truth(scene, 16, 12, spp=16, seed=seed) for seed in (5, 5, 6))
    np.testing.assert_array_equal(first.linear, again.linear)
    assert not np.array_equal(first.linear, other.linear)
    assert np.all(np.isfinite(first.linear)) and first.linear.min() >= 0


def test_the_picture_is_oriented_as_the_camera_module_says():
    """A lit particle up and to the right of the view centre shows there, where its alpha (from
    cloudcore.world.camera's rays) says it is."""
    scene = particle_scene(6.0)
    camera = Camera((0.0, 1000.0, 300.0), (-40.0, 980.0, 0.0), 40.0)  # the particle is right of and above it
    truth = render_truth(scene, 32, 24, camera=camera, spp=32)
    brightness = truth.radiance.sum(axis=2)
    rows, columns = np.indices(brightness.shape)

    def centroid(weight):
        return np.array([(rows * weight).sum(), (columns * weight).sum()]) / weight.sum()

    row, column = centroid(truth.alpha)
    assert row < 11.5 and column > 16.5  # the top half, the right half
    np.testing.assert_allclose(centroid(brightness), centroid(truth.alpha), atol=1.0)


def test_cloudview_truth_writes_the_picture(tmp_path):
    save_scene(particle_scene(4.0), tmp_path / "s.toml")
    out = tmp_path / "t.png"
    result = subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "truth", str(tmp_path / "s.toml"), "--out", str(out)]
        + ["--width", "16", "--height", "12", "--spp", "8"],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr
    assert out.exists() and "8 spp" in result.stdout


def test_cloudview_truth_path_traces_the_terrain_when_asked_and_refuses_to_compare_it(tmp_path):
    """--terrain: the ground under the particle fills the picture's bottom rows, which show the sky without it;
    with --json, one line and exit 2 (the models draw no terrain)."""
    terrain = Terrain(size=(12000.0, 12000.0), resolution=9, height=0.0, color=(0.5, 0.5, 0.5))
    save_scene(dataclasses.replace(particle_scene(4.0), terrain=terrain), tmp_path / "s.toml")
    command = [sys.executable, "-m", "cloudcore.cli", "truth", str(tmp_path / "s.toml")]
    command += ["--width", "16", "--height", "12", "--spp", "4"]
    for name, extra in (("ground.png", ["--terrain"]), ("sky.png", [])):
        result = subprocess.run(command + ["--out", str(tmp_path / name)] + extra, capture_output=True, text=True)
        assert result.returncode == 0, result.stderr
    ground, sky = (iio.imread(tmp_path / name).astype(float) for name in ("ground.png", "sky.png"))
    assert np.abs(ground[-1] - sky[-1]).mean() > 20 and np.abs(ground[0] - sky[0]).max() <= 1
    refused = subprocess.run(
        command + ["--terrain", "--out", str(tmp_path / "r.png"), "--json", str(tmp_path / "r.json")],
        capture_output=True,
        text=True,
    )
    assert refused.returncode == 2 and len(refused.stderr.strip().splitlines()) == 1 and "--terrain" in refused.stderr


@pytest.mark.gl
def test_the_report_compares_every_shading_method_region_by_region(tmp_path):
    save_scene(particle_scene(4.0, ambient=(0.1, 0.1, 0.12)), tmp_path / "s.toml")
    report_path = tmp_path / "r.json"
    result = subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "truth", str(tmp_path / "s.toml"), "--out", str(tmp_path / "t.png")]
        + ["--width", "32", "--height", "24", "--spp", "16", "--json", str(report_path)]
        + ["--model-images", str(tmp_path / "models")],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr
    report = json.loads(report_path.read_text())
    assert set(report["models"]) == {
        "harris-exact",
        "harris-raster",
        "harris-preview",
        "saturated-exact",
        "saturated-octaves",
    }
    assert 10 < report["truth"]["noise_psnr_db"] < 100
    exact = report["models"]["harris-exact"]
    assert set(exact["errors"]) == {"image", "sky", "silhouette", "lit", "shadowed"}
    assert report["regions"]["sky"] > 0 and report["regions"]["lit"] > 0
    # the sky behind is the same picture in both: only the clouds differ
    assert exact["errors"]["sky"]["psnr_db"] > 35
    assert (tmp_path / "models" / "harris-exact.png").exists()
    assert (tmp_path / "models" / "saturated-exact_diff.png").exists()


def test_a_thin_particle_scatters_the_sun_as_harris_s_eye_pass_says():
    """Optically thin, the truth is single scattering, which is what the model's eye pass computes: the
    sun's irradiance times the scattering coefficient times the phase function (here at 90 degrees)."""
    scene = particle_scene(0.02, albedo=1.0, lights=(Light((1.0, 0.0, 0.0), (1.0, 1.0, 1.0), 1.0),))
    camera = Camera((0.0, 1000.0, 300.0), CENTRE, 2.0)
    truth = render_truth(scene, 4, 4, camera=camera, spp=4096, voxels_per_radius=6.0)
    marched = optical_depths(medium_grids(scene, 6.0), [camera.position], [[0.0, 0.0, -1.0]])[0][0]
    model = scattering_coefficient(marched, 1.0) * phase_function(0.0)
    # second-order scattering and the sun's dimming inside are both of order tau: a few percent
    assert truth.radiance.mean() == pytest.approx(model, rel=0.05)


def test_in_the_ambient_light_alone_a_white_cloud_returns_the_model_s_ambient_term():
    """A cloud of albedo 1 in a uniform radiance L sends L (1 - T) toward the eye, exactly what the
    model's ambient term adds (ambient * opacity)."""
    scene = particle_scene(2.0, albedo=1.0, lights=DARK, ambient=(0.5, 0.5, 0.5))
    camera = Camera((0.0, 1000.0, 300.0), CENTRE, 2.0)
    truth = render_truth(scene, 4, 4, camera=camera, spp=1024, voxels_per_radius=6.0)
    assert truth.radiance.mean() == pytest.approx(0.5 * truth.alpha.mean(), rel=0.01)


def test_the_ground_has_the_colours_the_renderer_gives_it():
    """The terrain's colour ramp by height reaches the truth's ground: a flat ground whose ramp is red at its height
    and green above it is red in the picture, as the renderer draws it, not the terrain's plain `color`."""
    ramp = ((0.0, 0.6, 0.1, 0.1), (500.0, 0.1, 0.6, 0.1))
    terrain = Terrain(size=(6000.0, 6000.0), resolution=9, height=0.0, color=(0.1, 0.1, 0.6), color_ramp=ramp)
    scene = Scene(
        camera=Camera((0.0, 3000.0, 1.0), (0.0, 0.0, 0.0), 40.0),
        lighting=Lighting(time_of_day=None, lights=(Light((0.0, 1.0, 0.0), (1.0, 1.0, 1.0), 1.0),), ambient=(0.0,) * 3),
        terrain=terrain,
    )
    ground = render_truth(scene, 8, 8, spp=8, seed=1, terrain=True).linear.reshape(-1, 3).mean(axis=0)
    # lit from straight above: albedo / pi
    np.testing.assert_allclose(ground, np.array(ramp[0][1:]) / np.pi, rtol=0.03)


def test_a_cloud_s_shadow_falls_where_the_sun_s_rays_through_it_meet_the_ground():
    """One thick particle 600 m over a flat grey terrain, the sun 32 degrees from the zenith, seen from straight
    above: the ground is darkest, with the cloud taken away lit evenly, where the sun's ray through the cloud's
    centre meets the ground; the terrain's pixels show no sky."""
    sun = np.array([0.5, 0.8, 0.0]) / np.linalg.norm([0.5, 0.8, 0.0])
    centre = np.array([0.0, 600.0, 0.0])
    scene = Scene(
        camera=Camera((0.0, 3000.0, 1.0), (0.0, 0.0, 0.0), 60.0),
        lighting=Lighting(time_of_day=None, lights=(Light(tuple(sun), (1.0, 1.0, 1.0), 1.0),), ambient=(0.1,) * 3),
        shading=Shading(albedo=0.9, optical_depth=6.0),
        clouds=(Cloud("one", [[*centre, 250.0]]),),
        terrain=Terrain(size=(6000.0, 6000.0), resolution=9, height=0.0, color=(0.5, 0.5, 0.5)),
    )
    size = 48
    shaded, bare = (
        render_truth(s, size, size, spp=32, seed=2, terrain=True)
        for s in (scene, dataclasses.replace(scene, clouds=()))
    )
    assert np.isfinite(shaded.ground_distance).all() and np.isfinite(bare.ground_distance).all()
    ground = bare.linear.mean(axis=-1)
    # lit ground: albedo E cos / pi plus the ambient's albedo * L
    lit = 0.5 * sun[1] / np.pi + 0.5 * 0.1
    assert ground.mean() == pytest.approx(lit, rel=0.03)
    clear = shaded.alpha < 0.02
    light = shaded.linear.mean(axis=-1)
    blurred = sum(np.roll(light, (dy, dx), axis=(0, 1)) for dy in (-1, 0, 1) for dx in (-1, 0, 1)) / 9.0
    darkest = np.unravel_index(np.argmin(np.where(clear, blurred, np.inf)), clear.shape)
    shadow = centre - centre[1] / sun[1] * sun  # on the ground, y = 0
    toward = (shadow - scene.camera.position) / np.linalg.norm(shadow - scene.camera.position)
    rays = pixel_rays(scene.camera, size, size)
    expected = np.unravel_index(np.argmax(rays @ toward), clear.shape)
    assert np.hypot(*np.subtract(darkest, expected)) <= 1.5, (darkest, expected)
    assert blurred[darkest] < 0.5 * lit


@pytest.mark.parametrize("tau, albedo", [(20.0, 1.0), (50.0, 0.999), (50.0, 0.99)])
def test_the_truth_s_path_tracer_sees_a_thick_slab_as_adding_doubling_does(tau, albedo):
    """A wide homogeneous slab (isotropic scattering) in uniform light of radiance 1 above and below, seen along
    its normal with the truth's integrator: the light it sends back and on is the adding-doubling value.  Mitsuba's
    default Russian roulette made this 0.82 at albedo 1 and 0.81 at 0.999 (against 1 and 0.92): the truth has
    none."""
    mitsuba_variant()
    half = 50.0 * tau
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": integrator_description(albedo),
            "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}},
            "slab": {
                "type": "cube",
                "bsdf": {"type": "null"},
                "to_world": mi.ScalarTransform4f().scale([half, tau / 2.0, half]),
                "interior": {"type": "homogeneous", "sigma_t": 1.0, "albedo": albedo, "phase": {"type": "isotropic"}},
            },
            "sensor": {
                "type": "perspective",
                "fov": 2.0,
                "to_world": mi.ScalarTransform4f().look_at(origin=[0, tau, 0], target=[0, 0, 0], up=[0, 0, 1]),
                "film": {"type": "hdrfilm", "width": 8, "height": 8, "rfilter": {"type": "box"}},
                "sampler": {"type": "independent", "sample_count": 64},
            },
        }
    )
    traced = float(np.asarray(mi.render(scene, seed=1), dtype=np.float64).mean())
    layer = slab(tau, albedo, "isotropic")
    arriving = 2.0 * np.pi * layer.weights * layer.mu  # flux along each node from radiance 1
    leaving = (layer.reflection + layer.transmission) @ arriving / arriving  # radiance along each node
    assert traced == pytest.approx(leaving[-1], rel=0.03)  # the node nearest the normal (mu 0.995)
