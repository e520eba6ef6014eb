"""The Statistics panel's window rate: the median gap between the window's frames, which a stall does not move."""

from types import SimpleNamespace

import pytest

from app.panels.statistics import WINDOW_RATE_GAPS, window_frame_ms, window_gaps_ms


def frames_started_at(*seconds):
    return [SimpleNamespace(frame_start_s=s) for s in seconds]


def test_the_gaps_are_between_consecutive_frame_starts():
    assert window_gaps_ms(frames_started_at(1.0, 1.016, 1.05)) == pytest.approx([16.0, 34.0])


def test_the_rate_is_the_median_gap_so_one_stall_does_not_move_it():
    starts = [0.016 * i for i in range(20)]
    starts.append(starts[-1] + 2.5)  # a relit scene's shading
    assert window_frame_ms(frames_started_at(*starts)) == pytest.approx(16.0)


def test_the_rate_follows_the_last_frames_only():
    """An editor that went idle (9 frames a second) shows the idle rate, not the rate it ran at before."""
    busy = [0.016 * i for i in range(200)]
    idle = [busy[-1] + 0.111 * (i + 1) for i in range(WINDOW_RATE_GAPS)]
    assert window_frame_ms(frames_started_at(*busy, *idle)) == pytest.approx(111.0)


@pytest.mark.parametrize("starts", [(), (3.0,)])
def test_before_two_frames_there_is_no_rate(starts):
    assert window_frame_ms(frames_started_at(*starts)) == 0.0
