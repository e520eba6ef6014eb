"""Particles chosen and ordered on the GPU (`splat_order = "gpu"`) against the CPU's choice and order.

The radix sort must order exactly as the CPU's stable sort does; a selection must choose the particles
`splat_batch` chooses, far to near (the GPU's float32 distances may only swap near-ties), and a frame drawn
from selections must show the CPU's picture and count its particles."""

import dataclasses

import numpy as np
import pytest

from cloudcore.gl.prefix_sum import ONE_GROUP_ITEMS, GpuPrefixSum
from cloudcore.measure.imagecompare import compare
from cloudcore.model.scene import Camera, Cloud, Formation, Light, Shading
from cloudcore.model.settings import RenderSettings
from cloudcore.particles.buffer import ParticleBuffer
from cloudcore.scenes.files import load_scene
from cloudcore.world.camera import frustum_planes, projection_matrix, view_matrix
from tests.conftest import VALLEY


@pytest.fixture(scope="module")
def valley():
    return load_scene(VALLEY)


LIGHTS = (Light((0.0, 0.6, -0.8), (1.0, 0.95, 0.9), 1.0),)
AMBIENT = (0.05, 0.06, 0.09)


@pytest.mark.parametrize("items", ["gpu", "cpu"])
@pytest.mark.parametrize(
    "count, key_bits",
    [(0, 32), (1, 32), (2, 32), (2047, 32), (2048, 32), (2049, 32), (30000, 32), (5000, 8), (300_000, 16)],
)
def test_the_gpu_radix_sort_orders_as_a_stable_sort(renderer, count, key_bits, items):
    """8-bit keys (a selection's cells) need only two passes; the tiles of keys a workgroup takes are a GPU's
    (2048, the counts about them) and a software GL's (32,768: 300,000 keys in ten)."""
    from OpenGL import GL

    from cloudcore.gl.depth_sort import ITEMS_ON_CPU, ITEMS_ON_GPU, GpuDepthSort

    rng = np.random.default_rng(count)
    keys = rng.integers(0, 2**key_bits, count, dtype=np.uint64).astype(np.uint32)
    keys[::5] = keys[count // 2] if count else 0  # many equal keys: their input order must stay
    keys[1::7] = rng.integers(0, 4, len(keys[1::7]))  # and keys differing only in the lowest digits
    values = rng.permutation(count).astype(np.uint32)
    renderer.context.make_current()
    sort, buffers = GpuDepthSort({"gpu": ITEMS_ON_GPU, "cpu": ITEMS_ON_CPU}[items]), GL.glGenBuffers(2)
    try:
        for buffer, data in zip(buffers, (keys, values)):
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
            GL.glBufferData(
                GL.GL_SHADER_STORAGE_BUFFER, max(data.nbytes, 4), data if count else None, GL.GL_DYNAMIC_COPY
            )
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)
        sort.sort(*buffers, count, key_bits)
        GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        sorted_pairs = []
        for buffer in buffers:
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
            data = GL.glGetBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 0, 4 * count) if count else b""
            sorted_pairs.append(np.frombuffer(data, dtype=np.uint32))
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
    finally:
        sort.close()
        GL.glDeleteBuffers(2, list(buffers))
    expected = np.argsort(keys, kind="stable")
    np.testing.assert_array_equal(sorted_pairs[0], keys[expected])
    np.testing.assert_array_equal(sorted_pairs[1], values[expected])


@pytest.mark.parametrize("count", [0, 2049, 30_000])
def test_the_gpu_radix_sort_takes_a_count_only_the_gpu_holds(renderer, count):
    """The tile binning's pairs are counted on the GPU: the sort is given the room (here 40,000 pairs, the rest
    other keys) and where the count is; it sorts that many and leaves the rest of the room as it was."""
    from OpenGL import GL

    from cloudcore.gl.depth_sort import GpuDepthSort

    room, held_at = 40_000, 3
    rng = np.random.default_rng(count)
    keys = rng.integers(0, 2**16, room, dtype=np.uint32)
    values = rng.permutation(room).astype(np.uint32)
    counts = np.array([7, 7, 7, count], dtype=np.uint32)
    renderer.context.make_current()
    sort, buffers = GpuDepthSort(), GL.glGenBuffers(3)
    try:
        for buffer, data in zip(buffers, (keys, values, counts)):
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
            GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, data.nbytes, data, GL.GL_DYNAMIC_COPY)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)
        sort.sort(buffers[0], buffers[1], room, key_bits=16, count_at=(buffers[2], held_at))
        GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        sorted_pairs = []
        for buffer in buffers[:2]:
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
            sorted_pairs.append(
                np.frombuffer(GL.glGetBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 0, 4 * room), np.uint32)
            )
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
    finally:
        sort.close()
        GL.glDeleteBuffers(3, list(buffers))
    expected = np.argsort(keys[:count], kind="stable")
    np.testing.assert_array_equal(sorted_pairs[0][:count], keys[expected])
    np.testing.assert_array_equal(sorted_pairs[1][:count], values[expected])
    np.testing.assert_array_equal(sorted_pairs[0][count:], keys[count:])
    np.testing.assert_array_equal(sorted_pairs[1][count:], values[count:])


@pytest.mark.parametrize("count", [1, 2, 2047, 2048, 2049, 20_000, ONE_GROUP_ITEMS, ONE_GROUP_ITEMS + 1, 600_000])
def test_the_gpu_prefix_sum_is_the_sum_of_the_items_before_each(renderer, count):
    """Up to `ONE_GROUP_ITEMS` items are scanned by one workgroup, more block by block from the blocks' scanned
    sums (a last block part full, at 600,000);
    whatever the count, each item becomes the sum of those before it (the values past `count` untouched)."""
    from OpenGL import GL

    values = np.random.default_rng(count).integers(0, 1000, count + 3, dtype=np.uint32)
    renderer.context.make_current()
    prefix_sum, buffer = GpuPrefixSum(), GL.glGenBuffers(1)
    try:
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
        GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, values.nbytes, values, GL.GL_DYNAMIC_COPY)
        GL.glMemoryBarrier(GL.GL_SHADER_STORAGE_BARRIER_BIT)
        prefix_sum.scan(buffer, count)
        GL.glMemoryBarrier(GL.GL_BUFFER_UPDATE_BARRIER_BIT)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
        summed = np.frombuffer(GL.glGetBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, 0, values.nbytes), np.uint32)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
    finally:
        prefix_sum.close()
        GL.glDeleteBuffers(1, [buffer])
    expected = np.concatenate([[0], np.cumsum(values[: count - 1], dtype=np.uint32)])
    np.testing.assert_array_equal(summed[:count], expected)
    np.testing.assert_array_equal(summed[count:], values[count:])


def _cloud(rng, name: str, count: int, centre, **fields) -> Cloud:
    centres = rng.normal(size=(count, 3)) * [60.0, 25.0, 60.0] + centre
    return Cloud(name, np.column_stack([centres, rng.uniform(4.0, 20.0, count)]), **({"optical_depth": 1.0} | fields))


def _distances(particles: ParticleBuffer, order: np.ndarray, eye) -> np.ndarray:
    return np.linalg.norm(particles.centres[order] - eye, axis=1)


def _far_to_near_up_to_ties(order: np.ndarray, particles: ParticleBuffer, eye) -> None:
    distances = _distances(particles, order, eye)
    # float32 distances relative to the eye: a swap only between distances within a few float32 roundings
    assert np.all(distances[1:] <= distances[:-1] * (1.0 + 4e-7) + 1e-4)


def test_a_selection_chooses_and_orders_the_particles_splat_batch_does(renderer):
    from cloudcore.gl.splats import SplatPass
    from cloudcore.particles.batch import SplatSelection, splat_batch

    rng = np.random.default_rng(7)
    forming = Formation(start_s=0.0, duration_s=10.0, kind="form")
    clouds = (
        _cloud(rng, "around the eye", 4000, [0.0, 0.0, -30.0]),  # the near fade leaves out those next to the eye
        _cloud(rng, "ahead", 3000, [40.0, 10.0, -400.0]),
        _cloud(rng, "forming", 2000, [-150.0, 0.0, -300.0], formation=forming),
        _cloud(rng, "behind", 1000, [0.0, 0.0, 500.0]),  # outside the frustum
        _cloud(rng, "transparent", 500, [0.0, 40.0, -200.0], optical_depth=0.0),
    )
    particles = ParticleBuffer(clouds, Shading(), LIGHTS, AMBIENT)
    camera = Camera((0.0, 0.0, 0.0), (0.05, 0.0, -1.0), 60.0)
    view, projection = view_matrix(camera), projection_matrix(camera.fov_y_deg, 4 / 3)
    frustum, eye = frustum_planes(projection @ view), np.asarray(camera.position, dtype=np.float64)
    renderer.context.make_current()
    splats = SplatPass()
    try:
        for members, depth_ranges, time_s in (
            ((0, 1, 2, 3, 4), None, 4.0),
            ((1, 2), ((100.0, 380.0), (0.0, 310.0)), 4.0),  # layers of clouds split around objects
            ((2,), None, 0.0),  # a cloud not formed yet shows nothing
        ):
            expected = splat_batch(particles, members, eye, depth_ranges, time_s, frustum).order
            selection = SplatSelection(particles, members, eye, depth_ranges, time_s, frustum)
            (chosen,) = splats.read_orders(selection, view)
            # the CPU's float64 and the GPU's float32 may disagree on particles right on a boundary: none here
            assert set(chosen.tolist()) == set(expected.tolist()), (members, depth_ranges, time_s)
            _far_to_near_up_to_ties(chosen, particles, eye)
            if time_s == 0.0:
                assert len(expected) == 0
            else:
                assert len(expected) > 500
                # the very order but where two distances agree to float32 rounding (the GPU's, its FMAs): where
                # the orders differ, the particles there are as far (0.14% of the places on an H200)
                differ = chosen != expected
                assert np.mean(differ) < 0.01
                gap = np.abs(_distances(particles, chosen[differ], eye) - _distances(particles, expected[differ], eye))
                assert np.all(gap <= 4e-7 * _distances(particles, expected[differ], eye) + 1e-4)
    finally:
        splats.close()


def test_the_gpu_radix_sort_takes_keys_of_whole_bytes(renderer):
    from cloudcore.gl.depth_sort import GpuDepthSort

    renderer.context.make_current()
    sort = GpuDepthSort()
    try:
        with pytest.raises(ValueError, match="8, 16, 24 or 32 bits, not 12"):
            sort.sort(0, 0, 10, key_bits=12)
    finally:
        sort.close()


@pytest.mark.parametrize("mode", ["full", "auto", "impostor"])
def test_a_frame_drawn_from_gpu_selections_shows_the_cpus_picture_and_counts(renderer, valley, mode):
    """The GPU's way draws quads only; the CPU's draws as point sprites where the picture is the same, but on
    NVIDIA (H200) a point sprite covers other fragments than its quad (the overdraw 0.7% higher), so both ways
    here draw quads: the same fragments on any GL."""
    cpu_settings = RenderSettings(mode=mode, splat_order="cpu", point_sprites=False)
    gpu_settings = dataclasses.replace(cpu_settings, splat_order="gpu")
    renderer.lod_state = type(renderer.lod_state)()
    cpu_image, cpu_stats = renderer.render(valley, settings=cpu_settings)
    _, cpu_overdraw = renderer.measure_overdraw()
    renderer.lod_state = type(renderer.lod_state)()
    gpu_image, gpu_stats = renderer.render(valley, settings=gpu_settings)
    _, gpu_overdraw = renderer.measure_overdraw()
    difference = compare(cpu_image, gpu_image)
    assert difference.within(min_psnr_db=60.0, max_abs=4), str(difference)
    assert gpu_stats.particles_drawn == cpu_stats.particles_drawn
    # the regenerations too are chosen on the GPU: the same particles, counted from their commands
    assert gpu_stats.particles_to_impostors == cpu_stats.particles_to_impostors
    assert cpu_stats.particles_drawn + cpu_stats.particles_to_impostors > 0
    assert (cpu_stats.splat_order, gpu_stats.splat_order) == ("cpu", "gpu")
    assert gpu_overdraw.mean == pytest.approx(cpu_overdraw.mean, rel=1e-4)
    assert gpu_overdraw.analytic == pytest.approx(cpu_overdraw.analytic, rel=1e-9)
