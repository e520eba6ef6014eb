"""Where full-3D draws sort ("auto"): the CPU untried on a software rasterizer, else the way measured faster."""

import pytest

from cloudcore.lod.splat_order import TRIAL_FRAMES, SplatOrderChoice, software_rasterizer

GPU = "NVIDIA H200/PCIe/SSE2"
LLVMPIPE = "llvmpipe (LLVM 15.0.6, 256 bits)"


def run(choice: SplatOrderChoice, renderer: str, times: dict, frames: int, particles: int = 50_000):
    """The ways of `frames` frames under "auto", each frame's cloud pass taking times[way]() ms."""
    ways = []
    for _ in range(frames):
        way = choice.way("auto", renderer)
        ways.append(way)
        choice = choice.observe(way, times[way](), particles)
    return ways, choice


def test_a_set_way_is_taken_as_set():
    for way in ("cpu", "gpu"):
        assert SplatOrderChoice().way(way, GPU) == SplatOrderChoice().way(way, LLVMPIPE) == way


def test_on_a_software_rasterizer_the_cpu_is_taken_untried():
    ways, choice = run(SplatOrderChoice(), LLVMPIPE, {"cpu": lambda: 50.0, "gpu": lambda: 1.0}, 30)
    assert set(ways) == {"cpu"}
    assert len(choice.trials["cpu"]) <= TRIAL_FRAMES  # nothing piles up frame after frame
    assert software_rasterizer("softpipe") and not software_rasterizer(GPU)


@pytest.mark.parametrize("faster", ["cpu", "gpu"])
def test_on_a_gpu_the_ways_alternate_and_the_faster_is_kept(faster):
    slower = "gpu" if faster == "cpu" else "cpu"
    slow_frames = iter([400.0] + [10.0] * 100)  # one stall in the faster way's trial does not lose it
    times = {faster: lambda: next(slow_frames), slower: lambda: 14.0}
    ways, choice = run(SplatOrderChoice(), GPU, times, 20)
    assert ways[: 2 * TRIAL_FRAMES] == ["cpu", "gpu"] * TRIAL_FRAMES
    assert choice.kept == faster and set(ways[2 * TRIAL_FRAMES :]) == {faster}


def test_frames_without_full_3d_particles_or_a_time_are_not_counted():
    choice = SplatOrderChoice()
    for cloud_ms, particles in ((5.0, 0), (float("nan"), 10_000), (-1.0, 10_000)):
        choice = choice.observe("cpu", cloud_ms, particles)
    assert choice.trials["cpu"] == () and choice.way("auto", GPU) == "cpu"
