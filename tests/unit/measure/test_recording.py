"""Frame times at a frame rate and the per-frame statistics row of `cloudview record`."""

import dataclasses
import math

import numpy as np
import pytest

from cloudcore.lod.plan.plan_stats import PlanStats
from cloudcore.measure.recording import COLUMNS, MAX_RECORDED_FRAMES, frame_row, frame_times
from cloudcore.stats.frame_stats import FrameStats
from cloudcore.stats.overdraw import Overdraw


def test_a_30_s_path_at_30_fps_is_901_frames_ending_on_the_last_key():
    times = frame_times(30.0, 30.0)
    assert len(times) == 901
    np.testing.assert_allclose(times[[0, 1, -1]], [0.0, 1 / 30, 30.0])


def test_frame_count_survives_floating_point_products():
    assert 1.16 * 25 < 29  # 28.999999999999996: floor alone would lose the frame at 1.16 s
    assert len(frame_times(1.16, 25.0)) == 30


def test_the_last_frame_is_the_last_whole_step_within_the_path():
    times = frame_times(1.0, 2.5)
    np.testing.assert_allclose(times, [0.0, 0.4, 0.8])


def test_frames_keeps_only_the_first_n():
    np.testing.assert_array_equal(frame_times(30.0, 30.0, frames=3), [0.0, 1 / 30, 2 / 30])
    assert len(frame_times(1.0, 2.0, frames=100)) == 3


@pytest.mark.parametrize("fps", [0.0, -1.0, math.nan, math.inf])
def test_frame_rates_must_be_finite_and_positive(fps):
    with pytest.raises(ValueError, match="fps"):
        frame_times(30.0, fps)


STATS = FrameStats(
    PlanStats(impostors_drawn=3, impostors_regenerated=1, regeneration_reasons={"angle": 1}),
    frame_ms=10.0,
    world_ms=2.5,
    cloud_ms=6.0,
    impostor_update_ms=1.5,
    particles_drawn=1200,
    clouds_drawn=5,
    texture_bytes=4096,
)


def test_row_splits_the_frame_time_and_leaves_overdraw_not_measured_empty():
    row = frame_row(7, 0.25, STATS)
    assert set(row) == set(COLUMNS)
    assert row["frame"] == 7 and row["time_s"] == 0.25
    assert row["other_ms"] == pytest.approx(2.5)
    assert row["layers_drawn"] == row["layers_rebuilt"] == 0
    assert row["overdraw_mean"] == row["overdraw_max"] == row["overdraw_analytic"] == ""


def test_row_takes_layers_and_overdraw_when_given():
    stats = dataclasses.replace(
        STATS, plan=dataclasses.replace(STATS.plan, layers_drawn=4, layers_rebuilt=2)
    ).with_overdraw(Overdraw(mean=3.25, mean_covered=5.0, max=17.0, analytic=3.5))
    row = frame_row(0, 0.0, stats)
    assert (row["layers_drawn"], row["layers_rebuilt"]) == (4, 2)
    assert (row["overdraw_mean"], row["overdraw_max"], row["overdraw_analytic"]) == (3.25, 17.0, 3.5)


def test_a_recording_past_the_frame_limit_is_refused_unless_frames_cut_it():
    """A 2e12 s path asked for 6e13 frame times at once (a MemoryError); 1e300 fps overflowed to inf."""
    with pytest.raises(ValueError, match="past the 10,000,000"):
        frame_times(2e12, 30.0)
    with pytest.raises(ValueError, match="past the 10,000,000"):
        frame_times(2e12, 1e300)
    assert len(frame_times(2e12, 30.0, frames=3)) == 3
    assert len(frame_times((MAX_RECORDED_FRAMES - 1) / 30.0, 30.0)) == MAX_RECORDED_FRAMES
