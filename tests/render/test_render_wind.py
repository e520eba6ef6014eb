"""Clouds in the wind, rendered: drawn where the wind took them, in full 3D and as impostors that follow them,
remade when their cloud has moved past the tolerance, and lit once while they only drift."""

import dataclasses

import numpy as np
import pytest

from cloudcore.artist.cloudgen import preset_cloud
from cloudcore.gl.frame import FrameRenderer
from cloudcore.light.illumination import IlluminationCache
from cloudcore.model.scene import Camera, CloudField, Scene, Weather, Wind
from cloudcore.model.settings import FULL_3D, RenderSettings
from cloudcore.world.wind import drift

pytestmark = pytest.mark.gl

IMPOSTOR = RenderSettings(mode="impostor", ring_radius=float("inf"))
MODES = {"full": FULL_3D, "impostor": IMPOSTOR}
#: a westerly: the clouds drift toward +x, across the view
WIND = Wind(bands=((0.0, 10.0, 270.0),))


@pytest.fixture(scope="module")
def still() -> Scene:
    # Harris's splats: Wang's artist model shades groups on a grid that stays with the cloud as it drifts (made at
    # rest), where a cloud put at the drifted place has groups of its own
    clouds = tuple(
        dataclasses.replace(preset_cloud("cumulus_humilis", name, centre, seed=seed), sprite=None, artist=None)
        for name, centre, seed in (("left", (-300.0, 1000.0, 0.0), 3), ("right", (500.0, 1100.0, -400.0), 5))
    )
    return Scene(camera=Camera((0.0, 1100.0, 2600.0), (0.0, 1050.0, 0.0), 50.0), clouds=clouds)


def carried(scene: Scene, wind: Wind, time_s: float) -> Scene:
    """`scene` in still air with its clouds where `wind` has carried them by `time_s`."""
    clouds = tuple(
        dataclasses.replace(
            cloud,
            particles=np.column_stack(
                [cloud.centres + drift(wind, [cloud.bounding_sphere()[0][1]], time_s)[0], cloud.radii]
            ),
        )
        for cloud in scene.clouds
    )
    return dataclasses.replace(scene, clouds=clouds)


@pytest.mark.parametrize("mode", MODES)
def test_at_time_zero_a_windy_scene_is_the_still_one(renderer, still, mode):
    settings = MODES[mode]
    image = renderer.render(still, settings=settings)[0]
    windy = renderer.render(dataclasses.replace(still, wind=WIND), settings=settings)[0]
    np.testing.assert_array_equal(windy, image)


def test_a_drifting_cloud_is_drawn_where_the_wind_took_it(renderer, still):
    windy = dataclasses.replace(still, wind=WIND)
    image, _ = renderer.render(windy, settings=FULL_3D, time_s=30.0)
    centres = renderer.units.centres.copy()
    expected, _ = renderer.render(carried(still, WIND, 30.0), settings=FULL_3D)
    # the same splats 300 m east; their light made at rest (a translation leaves Harris's self-shading)
    assert np.abs(image.astype(int) - expected.astype(int)).max() <= 2
    np.testing.assert_allclose(centres, renderer.units.centres, atol=1e-6)
    rest, _ = renderer.render(still, settings=FULL_3D)
    assert np.abs(image.astype(int) - rest.astype(int)).mean() > 1.0  # and it did move


def test_impostors_follow_their_clouds_and_are_remade_once_the_drift_passes_the_tolerance(still):
    windy = dataclasses.replace(still, wind=WIND)
    with FrameRenderer(160, 120) as renderer:
        _, first = renderer.render(windy, settings=IMPOSTOR)
        made = first.plan.impostors_regenerated
        assert made >= 1 and first.plan.regeneration_reasons == {"new": made}
        # 5 m of drift: within the tolerance, the impostors are kept and drawn 5 m on
        image, kept = renderer.render(windy, settings=IMPOSTOR, time_s=0.5)
        assert kept.plan.impostors_regenerated == 0
    with FrameRenderer(160, 120) as fresh:
        made_there, _ = fresh.render(carried(still, WIND, 0.5), settings=IMPOSTOR)
    # the kept impostors moved with their clouds: as close to ones made there as their parallax allows
    assert np.abs(image.astype(int) - made_there.astype(int)).max() <= 6
    with FrameRenderer(160, 120) as renderer:
        _, first = renderer.render(windy, settings=IMPOSTOR)
        _, later = renderer.render(windy, settings=IMPOSTOR, time_s=60.0)  # 600 m across the view, the eye still
        assert later.plan.regeneration_reasons == {"translation": first.plan.impostors_regenerated}


class CountingCache(IlluminationCache):
    """Counts every (cloud, light direction) pair it shades: `last_recomputed` holds only its last call's."""

    shaded = 0

    def light_parts(self, *args, **kwargs):
        parts = super().light_parts(*args, **kwargs)
        self.shaded += self.last_recomputed
        return parts


def test_a_drift_keeps_the_light_and_turbulence_relights_at_its_period(still):
    cache = CountingCache()
    churning = Wind(bands=((0.0, 10.0, 270.0),), turbulence_m=20.0, relight_period_s=10.0)
    with FrameRenderer(96, 72, illumination=cache) as renderer:
        renderer.render(dataclasses.replace(still, wind=WIND), settings=FULL_3D)
        every = cache.shaded  # (cloud, light direction) pairs: both clouds, each light
        assert every >= 2
        for time_s in (20.0, 45.0):
            renderer.render(dataclasses.replace(still, wind=WIND), settings=FULL_3D, time_s=time_s)
        assert cache.shaded == every
        shaded = []
        for time_s in (1.0, 4.0, 9.5, 10.5, 12.0, 21.0):
            renderer.render(dataclasses.replace(still, wind=churning), settings=FULL_3D, time_s=time_s)
            shaded.append(cache.shaded - every)
        # the first period's light is the clouds' at rest (held from above); then once a period, both clouds
        assert shaded == [0, 0, 0, every, every, 2 * every]


def test_a_frame_lit_at_an_earlier_period_draws_those_shapes_carried_to_now(still):
    """`render(lit_at=...)` (the editor's while its worker lights the next period): the light of the shapes at
    `lit_at`, nothing shaded anew, every particle carried to where the wind has it now, as the frame lit for now
    places them."""
    cache = CountingCache()
    churning = Wind(bands=((0.0, 10.0, 270.0),), turbulence_m=20.0, relight_period_s=10.0)
    scene = dataclasses.replace(still, wind=churning)
    with FrameRenderer(96, 72, illumination=cache) as renderer:
        renderer.render(scene, settings=FULL_3D, time_s=4.0)
        shaded = cache.shaded
        renderer.render(scene, settings=FULL_3D, time_s=14.0, lit_at=0.0)
        assert cache.shaded == shaded  # the shapes at rest, whose light is held
        assert renderer.drawn_clouds(scene, 0.0) is scene.clouds
        earlier = renderer.particles.centres.copy()
        renderer.render(scene, settings=FULL_3D, time_s=14.0)  # lit for its own period, 10 s
        assert cache.shaded > shaded
        np.testing.assert_allclose(renderer.particles.centres, earlier, atol=1e-6)


def test_a_change_of_weather_forms_without_a_jump():
    """The field's cells carried by the air are `FrameClouds`' (tests/unit/particles/test_frame_clouds.py); drawn, a
    change of weather forms one sky as the other dissipates."""
    field = CloudField(seed=2, coverage=0.5, cell_size=600.0, rings=1)
    scene = Scene(camera=Camera((0.0, 1500.0, 0.0), (0.0, 1800.0, -3000.0), 60.0), cloud_field=field, wind=WIND)
    with FrameRenderer(96, 72) as renderer:
        changing = dataclasses.replace(
            scene, wind=None, weather=Weather("scattered", to="overcast", start_s=0.0, duration_s=100.0)
        )
        previous, largest = None, 0.0
        for time_s in np.arange(0.0, 101.0, 5.0):
            image, _ = renderer.render(changing, settings=FULL_3D, time_s=float(time_s))
            if previous is not None:
                largest = max(largest, float(np.abs(image.astype(float) - previous).max()))
            previous = image.astype(float)
        # the overcast formed as the scattered sky dissipated, each made once: no frame a twentieth of the change
        # after another differs by more than 20 levels in any pixel (the field remade at each step of the coverage
        # had jumps of 51)
        assert renderer.field_state.field.coverage == 0.95 and largest <= 20.0


def test_another_wind_at_the_same_time_carries_the_clouds_by_its_own_drift(renderer, still):
    renderer.render(still, settings=FULL_3D)
    rest = renderer.units.centres.copy()
    for speed in (10.0, 20.0, 0.0):  # the editor's slider: a new wind, the clock where it was
        renderer.render(
            dataclasses.replace(still, wind=Wind(bands=((0.0, speed, 270.0),))), settings=FULL_3D, time_s=30.0
        )
        np.testing.assert_allclose(
            renderer.units.centres - rest, np.tile([30.0 * speed, 0.0, 0.0], (len(rest), 1)), atol=1e-6
        )


def test_wang_s_ring_follows_its_clouds_drifting_alike_without_being_made_again(still):
    far = dataclasses.replace(still, camera=Camera((0.0, 1100.0, 6500.0), (0.0, 1050.0, 0.0), 50.0), wind=WIND)
    # Wang's rule alone (a tolerance no panel's error reaches): the tolerance rebuilds sooner, tested below
    ring = RenderSettings(mode="impostor", ring_radius=4000.0, tolerance_deg=179.0)
    with FrameRenderer(96, 72) as renderer:
        for _ in range(20):  # its segments built, one a frame, and faded in
            renderer.render(far, settings=ring)
        built = renderer.last_plan.ring_state.current
        assert built is not None and renderer.last_plan.ring_shifts
        _, stats = renderer.render(far, settings=ring, time_s=25.0)  # 250 m: within half a rebuild distance (600 m)
        assert renderer.last_plan.ring_state.current is built and stats.plan.ring_segments_built == 0
        np.testing.assert_allclose(renderer.last_plan.ring_shifts[0], [250.0, 0.0, 0.0], atol=1e-6)
        _, stats = renderer.render(far, settings=ring, time_s=31.0)  # 310 m: the eye relative to the clouds stepped
        assert stats.plan.ring_segments_built > 0


def test_wang_s_ring_drifting_with_its_clouds_is_made_again_once_its_panels_error_passes_the_tolerance(still):
    """The panels stand at the ring's radius, their clouds beyond it: carried 250 m across the eye, the panels and
    the clouds shift apart by about 250 m (1/4000 - 1/D), past the default tolerance long before Wang's 600 m."""
    far = dataclasses.replace(still, camera=Camera((0.0, 1100.0, 6500.0), (0.0, 1050.0, 0.0), 50.0), wind=WIND)
    ring = RenderSettings(mode="impostor", ring_radius=4000.0)
    with FrameRenderer(96, 72) as renderer:
        for _ in range(20):
            renderer.render(far, settings=ring)
        built = renderer.last_plan.ring_state.current
        _, stats = renderer.render(far, settings=ring, time_s=25.0)
        assert renderer.last_plan.ring_state.current is not built or stats.plan.ring_segments_built > 0


def test_a_field_s_particles_swirl_with_the_turbulence_about_their_drifting_places_their_light_kept():
    """Under a turbulent wind a field's particles leave the grid's drift each by its own offset, within twice the
    turbulence's amplitude, and the field's clouds are lit once: their light is the cells' at rest."""
    field = CloudField(seed=2, coverage=0.5, cell_size=600.0, rings=1)
    camera = Camera((0.0, 1500.0, 0.0), (0.0, 1800.0, -3000.0), 60.0)
    places, shaded = {}, {}
    for turbulence in (0.0, 30.0):
        wind = Wind(bands=((0.0, 10.0, 270.0),), turbulence_m=turbulence)
        cache = CountingCache()
        with FrameRenderer(96, 72, illumination=cache) as renderer:
            for time_s in (0.0, 45.0, 130.0):
                renderer.render(Scene(camera=camera, cloud_field=field, wind=wind), settings=FULL_3D, time_s=time_s)
            places[turbulence], shaded[turbulence] = renderer.particles.centres.copy(), cache.shaded
    swirl = np.linalg.norm(places[30.0] - places[0.0], axis=1)
    assert len(swirl) > 100 and swirl.max() <= 2.0 * 30.0 + 1e-6
    assert np.median(swirl) > 3.0 and np.std(places[30.0] - places[0.0], axis=0).min() > 1.0  # each its own way
    assert shaded[30.0] == shaded[0.0]  # no field cloud relit for its turbulent shape
