"""Two ways picked by measurement ("auto"): the first untried on a software rasterizer, else the way measured
faster."""

import pytest

from cloudcore.gl.measured_way import TRIAL_FRAMES, MeasuredWay, software_rasterizer
from cloudcore.model.settings import COMPOSITING_WAYS

GPU = "NVIDIA H200/PCIe/SSE2"
LLVMPIPE = "llvmpipe (LLVM 15.0.6, 256 bits)"


def run(choice: MeasuredWay, renderer: str, times: dict, frames: int, particles: int = 50_000):
    """The ways of `frames` frames under "auto", each frame's cloud pass taking times[way]() ms."""
    ways = []
    for _ in range(frames):
        way = choice.way("auto", renderer)
        ways.append(way)
        choice = choice.observe(way, times[way](), particles)
    return ways, choice


def test_a_set_way_is_taken_as_set():
    for way in ("cpu", "gpu"):
        assert MeasuredWay().way(way, GPU) == MeasuredWay().way(way, LLVMPIPE) == way


def test_on_a_software_rasterizer_the_cpu_is_taken_untried():
    ways, choice = run(MeasuredWay(), LLVMPIPE, {"cpu": lambda: 50.0, "gpu": lambda: 1.0}, 30)
    assert set(ways) == {"cpu"}
    assert len(choice.times("cpu")) <= TRIAL_FRAMES  # nothing piles up frame after frame
    assert software_rasterizer("softpipe") and not software_rasterizer(GPU)


@pytest.mark.parametrize("faster", ["cpu", "gpu"])
def test_on_a_gpu_the_ways_alternate_and_the_faster_is_kept(faster):
    slower = "gpu" if faster == "cpu" else "cpu"
    slow_frames = iter([400.0] + [10.0] * 100)  # one stall in the faster way's trial does not lose it
    times = {faster: lambda: next(slow_frames), slower: lambda: 14.0}
    ways, choice = run(MeasuredWay(), GPU, times, 20)
    assert ways[: 2 * TRIAL_FRAMES] == ["cpu", "gpu"] * TRIAL_FRAMES
    assert choice.kept == faster and set(ways[2 * TRIAL_FRAMES :]) == {faster}


def test_frames_without_full_3d_particles_or_a_time_are_not_counted():
    choice = MeasuredWay()
    for cloud_ms, particles in ((5.0, 0), (float("nan"), 10_000), (-1.0, 10_000)):
        choice = choice.observe("cpu", cloud_ms, particles)
    assert choice.times("cpu") == () and choice.way("auto", GPU) == "cpu"


def test_compositing_takes_the_raster_untried_on_llvmpipe_and_the_faster_on_a_gpu():
    """The same trial for what composites full 3D's splats: on the H200 the compute pass took 7.4 ms where the
    raster took 17.5 (full 3D, 640x480), and it is kept; on llvmpipe, 8 times slower, it is never tried."""
    times = {"raster": lambda: 17.5, "compute": lambda: 7.4}
    ways, _ = run(MeasuredWay(COMPOSITING_WAYS), LLVMPIPE, times, 12)
    assert set(ways) == {"raster"}
    ways, choice = run(MeasuredWay(COMPOSITING_WAYS), GPU, times, 12)
    assert ways[: 2 * TRIAL_FRAMES] == ["raster", "compute"] * TRIAL_FRAMES and choice.kept == "compute"
    assert MeasuredWay(COMPOSITING_WAYS).way("raster", GPU) == "raster"
