"""Relighting off the GUI thread: the illumination cache per light direction, and the worker's newest-wins queue."""

import dataclasses
import time

import numpy as np
import pytest

from cloudcore.light.illumination import IlluminationCache, illuminate_clouds
from cloudcore.light.lighting import scene_lights
from cloudcore.light.relighting import SYNCHRONOUS_PARTICLES, LiveIllumination, Look, dragged_look_settings
from cloudcore.model.scene import Cloud, Lighting, Scene, Shading
from cloudcore.model.settings import FULL_3D, RenderSettings

SHADING = Shading()


def cloud(seed: int, particles: int) -> Cloud:
    rng = np.random.default_rng(seed)
    centres = rng.normal(0.0, 300.0, (particles, 3)) + [seed * 3000.0, 1500.0, 0.0]
    return Cloud(f"cloud {seed}", np.column_stack([centres, rng.uniform(30.0, 60.0, particles)]))


def look(hours: float, method: str = "raster") -> Look:
    return Look(SHADING, Lighting(time_of_day=hours), method)


def test_the_cache_gives_what_illuminate_clouds_gives_and_shades_only_the_moved_sun():
    clouds = [cloud(0, 300), cloud(1, 200)]
    cache = IlluminationCache()
    noon, _ = scene_lights(Lighting(time_of_day=12.0))
    for got, expected in zip(
        cache.incident(clouds, SHADING, noon, "raster"), illuminate_clouds(clouds, SHADING, noon, "raster")
    ):
        np.testing.assert_array_equal(got, expected)
    assert cache.last_recomputed == 4  # two clouds, sun and skylight
    brighter_sky = (noon[0], dataclasses.replace(noon[1], intensity=2.0 * noon[1].intensity))
    cache.incident(clouds, SHADING, brighter_sky, "raster")
    assert cache.last_recomputed == 0  # what fraction arrives does not depend on how bright the light is
    evening, _ = scene_lights(Lighting(time_of_day=17.0))
    assert evening[1].direction == noon[1].direction
    cache.incident(clouds, SHADING, evening, "raster")
    assert cache.last_recomputed == 2  # the sun moved; the skylight stays overhead


def test_a_small_change_is_shaded_in_the_frame_that_needs_it():
    live = LiveIllumination(IlluminationCache())
    try:
        scene = Scene(clouds=(cloud(0, 400),))
        assert live.look_for(scene, look(12.0)) == look(12.0)
        assert live.look_for(scene, look(15.0)) == look(15.0)  # 400 particles: nothing to wait for
        assert not live.busy
    finally:
        live.close()


def wait_for(live: LiveIllumination, scene: Scene, wanted: Look, seconds: float = 60.0) -> list[Look]:
    """The looks shown, frame by frame, until `wanted` is."""
    shown, deadline = [], time.monotonic() + seconds
    while time.monotonic() < deadline:
        current = live.look_for(scene, wanted)
        if not shown or shown[-1] != current:
            shown.append(current)
        if current == wanted:
            return shown
        time.sleep(0.01)
    pytest.fail(f"{wanted} was not shown within {seconds} s; shown: {shown}")


def test_a_large_change_shows_the_last_look_until_the_worker_has_the_new_one_and_the_newest_wins():
    big = Scene(clouds=(cloud(0, SYNCHRONOUS_PARTICLES), cloud(1, SYNCHRONOUS_PARTICLES)))
    cache = IlluminationCache()
    live = LiveIllumination(cache)
    try:
        live.start()
        assert live.look_for(big, look(12.0)) == look(12.0)  # nothing shown yet: the first look is shaded here
        cache.incident(big.clouds, SHADING, look(12.0).lights(), "raster")  # as the renderer does
        assert live.look_for(big, look(13.0)) == look(12.0)  # answered with the old look
        # ... and without shading the new one here: the worker has it
        assert live.busy and cache.missing(big.clouds, SHADING, look(13.0).lights(), "raster")
        live.look_for(big, look(14.0))
        shown = wait_for(live, big, look(15.0))  # 14 waited in the slot, and 15 took its place
        assert look(14.0) not in shown and shown[-1] == look(15.0)
        assert not cache.missing(big.clouds, SHADING, look(15.0).lights(), "raster")
        cache.incident(big.clouds, SHADING, look(15.0).lights(), "raster")
        assert cache.last_recomputed == 0  # the renderer finds it all held
        assert not live.busy
    finally:
        live.close()


def test_a_pause_while_the_worker_runs_ends_when_its_look_is_in_and_the_next_frame_shows_it():
    big = Scene(clouds=(cloud(0, SYNCHRONOUS_PARTICLES), cloud(1, SYNCHRONOUS_PARTICLES)))
    cache = IlluminationCache()
    live = LiveIllumination(cache)
    try:
        live.start()
        live.look_for(big, look(12.0))
        cache.incident(big.clouds, SHADING, look(12.0).lights(), "raster")
        assert live.look_for(big, look(13.0)) == look(12.0)  # the worker has 13 to light
        started = time.monotonic()
        live.pause(120.0)
        assert time.monotonic() - started < 60.0  # the worker's look, not the pause, ended it
        assert live.look_for(big, look(13.0)) == look(13.0)
        started = time.monotonic()
        live.pause(0.05)  # nothing running: the whole pause
        assert time.monotonic() - started >= 0.05
    finally:
        live.close()


def test_an_edit_while_relighting_keeps_the_old_look_and_shades_only_the_edited_cloud_here():
    clouds = (cloud(0, SYNCHRONOUS_PARTICLES), cloud(1, SYNCHRONOUS_PARTICLES))
    cache = IlluminationCache()
    live = LiveIllumination(cache)

    def frame(scene: Scene, wanted: Look) -> Look:
        """What the viewport does: ask for the look, draw with the one given (shading what is missing)."""
        shown = live.look_for(scene, wanted)
        cache.incident(scene.clouds, shown.shading, shown.lights(), shown.method)
        return shown

    try:
        frame(Scene(clouds=clouds), look(12.0))
        assert frame(Scene(clouds=clouds), look(16.0)) == look(12.0)
        edited = Scene(clouds=(clouds[0], cloud(2, 50)))  # one cloud replaced, mid-relight
        assert frame(edited, look(16.0)) == look(12.0)
        assert cache.last_recomputed == 2  # the new cloud, for the old look's sun and skylight
        wait_for(live, edited, look(16.0))
        frame(edited, look(16.0))
        assert cache.last_recomputed <= 1  # at most the new cloud's sun; the worker did the big one's
        assert not cache.missing(edited.clouds, SHADING, look(16.0).lights(), "raster")
    finally:
        live.close()


def test_a_dragged_slider_s_look_leaves_out_the_light_shafts_alone():
    for settings in (RenderSettings(), FULL_3D, dataclasses.replace(FULL_3D, light_shafts=False)):
        dragged = dragged_look_settings(settings)
        assert not dragged.light_shafts
        assert dataclasses.replace(dragged, light_shafts=settings.light_shafts) == settings
