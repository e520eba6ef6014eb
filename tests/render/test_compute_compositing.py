"""Full 3D's GPU-chosen plain splats composited by a compute pass over tiles binned on the GPU
(`compositing = "compute"`: `cloudcore.gl.tile_binning`, volume_blend.comp.glsl's PLAIN): the raster's
picture and counts, the bins' structure."""

import dataclasses

import numpy as np
import pytest

from cloudcore.light.volume_blending import TILE_PIXELS, screen_tiles
from cloudcore.measure.imagecompare import compare
from cloudcore.model.settings import RenderSettings
from cloudcore.resources import resource_path
from cloudcore.scenes.files import load_scene
from cloudcore.world.camera import NEAR_PLANE_M, projection_matrix, view_matrix
from tests.conftest import RENDER_HEIGHT, RENDER_WIDTH, VALLEY
from tests.render.test_render_golden import inside_a_cloud, into_the_sun

RASTER = RenderSettings(mode="full", splat_order="gpu", compositing="raster")
COMPUTE = dataclasses.replace(RASTER, compositing="compute")
VOLUME = RenderSettings(mode="full", blending="volume")


@pytest.fixture(scope="module")
def valley():
    return load_scene(VALLEY)


@pytest.mark.parametrize("view", ["default", "into_the_sun", "inside_a_cloud"])
def test_the_compute_pass_composites_the_rasters_picture(renderer, valley, view):
    """A splat left out of a tile it covers, or one out of order, or in front of terrain it is behind, would
    show: the pictures agree to a level, the compute pass keeping a pixel in float32 through its splats where
    the raster rounds it to half floats at each blend (measured 61 dB outside the clouds, 52.5 inside one,
    where a pixel takes hundreds of splats; one level at most).  And the raster's picture is the CPU order's."""
    camera = {"default": None, "into_the_sun": into_the_sun(valley), "inside_a_cloud": inside_a_cloud(valley)}[view]
    raster, raster_stats = renderer.render(valley, camera=camera, settings=RASTER)
    composited, stats = renderer.render(valley, camera=camera, settings=COMPUTE)
    difference = compare(raster, composited)
    assert difference.within(min_psnr_db=50.0, max_abs=1), f"{view}: {difference}"
    assert stats.particles_drawn == raster_stats.particles_drawn > 0
    assert (raster_stats.compositing, stats.compositing) == ("raster", "compute")
    # sorted on the CPU, asked for: "auto" takes whichever way it measured faster, which a loaded machine changes
    on_cpu, cpu_stats = renderer.render(valley, camera=camera, settings=RenderSettings(mode="full", splat_order="cpu"))
    assert compare(raster, on_cpu).psnr_db > 60
    assert cpu_stats.compositing == ""  # sorted on the CPU: nothing either way could composite


def test_layers_split_around_an_object_composite_as_the_raster_draws_them(renderer):
    """An aircraft inside a cloud: the cloud's layers behind and in front of it go through the compute pass
    one after the other, the aircraft drawn between."""
    scene = load_scene(resource_path("scenes", "aircraft_in_cloud.toml"))
    raster, _ = renderer.render(scene, settings=RASTER, time_s=10.0)
    composited, stats = renderer.render(scene, settings=COMPUTE, time_s=10.0)
    assert stats.plan.objects_in_clouds == 1 and stats.plan.layers_drawn == 2
    difference = compare(raster, composited)
    assert difference.within(min_psnr_db=50.0, max_abs=1), str(difference)


@pytest.fixture
def counts_on_gpu(monkeypatch):
    """Draws' tile pair counts kept on the GPU, as on a GPU (a software GL reads them back: `counts_stay_on_gpu`)."""
    from cloudcore.gl import tile_binning

    monkeypatch.setattr(tile_binning, "counts_stay_on_gpu", lambda: True)


def test_the_gpu_bins_each_tile_far_to_near_and_only_the_kept_splats(renderer, valley, counts_on_gpu):
    """The bins' structure as `ScreenTiles` has it: tile t's entries from starts[t] to starts[t + 1], each run
    ascending (the draw's far-to-near order), every entry a splat the selection kept, and every kept splat
    on screen in the tile of its centre; each tile as many as the numpy binning lists of the same splats (its
    disc's tiles, not its square's), but where float32 rounding puts a disc's edge across a tile's."""
    from cloudcore.gl.splats import SplatPass
    from cloudcore.gl.tile_binning import GpuTileBinning
    from cloudcore.particles.batch import SplatSelection

    renderer.render(valley, settings=RASTER)
    particles = renderer.particles  # the renderer's own, shaded for the scene (the valley in still air: not carried)
    camera = valley.camera
    view = view_matrix(camera)
    projection = projection_matrix(camera.fov_y_deg, RENDER_WIDTH / RENDER_HEIGHT)
    eye = np.asarray(camera.position, dtype=np.float64)
    renderer.context.make_current()
    splats, binning = SplatPass(), GpuTileBinning()
    try:
        selection = SplatSelection(particles, tuple(range(len(particles.cloud_starts) - 1)), eye, None, 0.0, None)
        instances, count_at = splats.selected_instances(selection, view)
        (order,) = splats.read_orders(selection, view)
        binned = binning.bin(instances, count_at, view, projection, (RENDER_WIDTH, RENDER_HEIGHT))
        starts, entries, occupied, groups = binning.read(binned)
        assert not binning.settle()  # counted here, nothing to draw again; the next draw's count stays on the GPU
        on_gpu = binning.bin(instances, count_at, view, projection, (RENDER_WIDTH, RENDER_HEIGHT))
        counted_on_gpu = binning.read(on_gpu)
    finally:
        splats.close()
        binning.close()
    assert on_gpu.pairs is None and on_gpu.room >= binned.pairs  # the same bins (the occupied tiles in no order)
    starts_there, entries_there, occupied_there, groups_there = counted_on_gpu
    np.testing.assert_array_equal(starts_there, starts)
    np.testing.assert_array_equal(entries_there, entries)
    np.testing.assert_array_equal(np.sort(occupied_there), np.sort(occupied))
    np.testing.assert_array_equal(groups_there, groups)
    tiles = binned.across * binned.up
    assert len(starts) == tiles + 1 and starts[0] == 0 and starts[-1] == binned.pairs == len(entries)
    assert np.all(np.diff(starts.astype(np.int64)) >= 0)
    kept = len(order)
    assert kept > 1000 and entries.max() < kept
    for tile in range(tiles):
        run = entries[starts[tile] : starts[tile + 1]].astype(np.int64)
        assert np.all(np.diff(run) > 0), tile  # far to near, each splat once
    # the compositing's groups: one a tile with splats, and only those
    np.testing.assert_array_equal(np.sort(occupied), np.flatnonzero(np.diff(starts) > 0))
    assert list(groups) == [len(occupied), 1, 1] and 0 < len(occupied) < tiles
    # the tile under each kept splat's centre lists it
    relative = particles.centres[order] - eye
    clip = (projection @ np.c_[relative @ view[:3, :3].T, np.ones(kept)].T).T
    ahead = clip[:, 3] > 1.0
    pixels = (clip[ahead, :2] / clip[ahead, 3:] * 0.5 + 0.5) * [RENDER_WIDTH, RENDER_HEIGHT] - 0.5
    on_screen = np.all((pixels >= 0) & (pixels <= [RENDER_WIDTH - 1, RENDER_HEIGHT - 1]), axis=1)
    columns, rows = (np.round(pixels[on_screen]).astype(np.int64) // TILE_PIXELS).T
    for slot, tile in zip(np.flatnonzero(ahead)[on_screen], rows * binned.across + columns):
        assert slot in entries[starts[tile] : starts[tile + 1]], (slot, tile)
    in_numpy = screen_tiles(relative, particles.radii[order], view, projection, binned.size, NEAR_PLANE_M)
    differing = np.abs(np.diff(starts.astype(np.int64)) - np.diff(in_numpy.starts.astype(np.int64))).sum()
    assert differing <= 1e-4 * binned.pairs, (differing, binned.pairs, in_numpy.starts[-1])


def test_dispatches_past_the_gls_group_limit_loop_to_the_same_picture(renderer, valley, monkeypatch):
    """At 1600x1200 inside a cloud the binning has 7 million pairs, 110,644 groups of 64 where llvmpipe
    dispatches 65,535 at most; a scene of 4.2 million particles passes it in the selection too.  With the
    limit made 100 groups, every compute shader of the GPU's ways loops over what it was given: the same
    pictures and counts.  (Not fewer: with 3, llvmpipe stopped each compositing invocation after about 45
    tiles of this view, some 65,000 splats walked, the iteration cap it puts on a shader's loops.)"""
    from cloudcore.gl import programs, tile_binning

    camera = inside_a_cloud(valley)
    expected = {
        name: renderer.render(valley, camera=camera, settings=settings)
        for name, settings in (("raster", RASTER), ("compute", COMPUTE), ("volume", VOLUME))
    }
    monkeypatch.setattr(programs, "max_dispatch_groups", lambda: 100)
    monkeypatch.setattr(tile_binning, "max_dispatch_groups", lambda: 100)  # the compositing's indirect dispatch
    for name, settings in (("raster", RASTER), ("compute", COMPUTE), ("volume", VOLUME)):
        image, stats = renderer.render(valley, camera=camera, settings=settings)
        assert compare(image, expected[name][0]).psnr_db >= 99.0, name
        assert stats.particles_drawn == expected[name][1].particles_drawn > 0, name


def test_a_draw_with_too_many_tile_pairs_is_left_to_the_raster(renderer, valley, monkeypatch):
    """Past `MAX_PAIRS` (512 MiB of bins; a 4K screen inside a cloud comes near) the draw is the raster's:
    its picture exactly, its particles counted once."""
    from cloudcore.gl import tile_binning

    raster, raster_stats = renderer.render(valley, settings=RASTER)
    monkeypatch.setattr(tile_binning, "MAX_PAIRS", 10)
    image, stats = renderer.render(valley, settings=COMPUTE)
    assert compare(image, raster).max_abs == 0
    assert stats.particles_drawn == raster_stats.particles_drawn > 0


def test_a_frame_reads_no_tile_count_back_before_its_one_wait(renderer, valley, counts_on_gpu, monkeypatch):
    """Once a frame has been binned, the next frames' counts stay on the GPU: the CPU never waits mid-frame for
    them (on the H200 reading the count back cost the compute pass 2.4 ms of CPU a frame)."""
    from OpenGL import GL

    renderer.render(valley, settings=COMPUTE)  # counted on the CPU's side if the renderer had not binned before
    events = []
    finish, read = GL.glFinish, GL.glGetBufferSubData
    monkeypatch.setattr(GL, "glFinish", lambda: (events.append("wait"), finish())[1])
    monkeypatch.setattr(GL, "glGetBufferSubData", lambda *arguments: (events.append("read"), read(*arguments))[1])
    _, stats = renderer.render(valley, settings=COMPUTE, read_back=False)
    assert stats.compositing == "compute" and not stats.drawn_again
    assert events[0] == "wait", events  # the counts are read after it, when reading waits for nothing


def test_a_draw_past_the_room_for_its_pairs_is_drawn_again_counted_first(renderer, valley, counts_on_gpu, monkeypatch):
    """With each draw's room half the pairs it had the frame before, a draw loses its nearest splats; the frame
    is drawn again with the count read back first: the picture is the one counted first, the frame's times both
    drawings'."""
    from cloudcore.gl import tile_binning

    expected, _ = renderer.render(valley, settings=COMPUTE)
    monkeypatch.setattr(tile_binning, "ROOM_FACTOR", 0.5)
    monkeypatch.setattr(tile_binning, "MIN_ROOM", 1)
    renderer.render(valley, settings=COMPUTE)  # settles with room for half its pairs
    image, stats = renderer.render(valley, settings=COMPUTE)
    assert stats.drawn_again and stats.compositing == "compute"
    assert compare(image, expected).max_abs == 0
    # the second drawing's parts, and the first drawing's whole frame beside them (some milliseconds anywhere)
    assert stats.frame_ms > stats.plan_ms + stats.world_ms + stats.impostor_update_ms + stats.cloud_ms + 0.1


def test_only_selections_of_plain_splats_are_compositable(renderer):
    """A selection is composited by compute only where all its clouds' particles are plain Gaussian splats of one
    colour; the formation scene's are sprites, the aircraft scene's cloud plain."""
    from cloudcore.artist.particle_styles import particle_styles
    from cloudcore.gl.splats import SplatPass
    from cloudcore.light.illumination import IlluminationCache
    from cloudcore.light.lighting import scene_lights
    from cloudcore.particles.batch import SplatSelection
    from cloudcore.particles.buffer import ParticleBuffer
    from cloudcore.particles.point_sprites import plain_splats

    sprites = load_scene(resource_path("scenes", "formation.toml"))
    clouds = sprites.clouds + load_scene(resource_path("scenes", "aircraft_in_cloud.toml")).clouds
    lights, ambient = scene_lights(sprites.lighting)
    particles = ParticleBuffer(
        clouds,
        sprites.shading,
        lights,
        ambient,
        "exact",
        IlluminationCache(),
        particle_styles(clouds, sprites.lighting),
    )
    plain, starts = plain_splats(particles.styles), particles.cloud_starts
    cloud_plain = [bool(plain[start:end].all()) for start, end in zip(starts[:-1], starts[1:])]
    assert cloud_plain == [False] * len(sprites.clouds) + [True]
    renderer.context.make_current()
    splats = SplatPass()
    try:
        for members in [(cloud,) for cloud in range(len(clouds))] + [tuple(range(len(clouds))), (3, 0)]:
            selection = SplatSelection(particles, members, np.zeros(3), None, 0.0, None)
            assert splats.plain_selection(selection) == all(cloud_plain[c] for c in members), members
    finally:
        splats.close()
