"""`scale_search_interval`: the 7-scale search on every k-th tracked frame only, the current scale in between (an
option for speed, issue #21; off by default because it costs accuracy on generated scale changes)."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.eco import EcoTracker, preset
from rgbt_toolkit.errors import InputError


def _frames(n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(3)
    out = []
    for k in range(n):
        frame = rng.integers(40, 80, (120, 160), dtype=np.uint8)
        frame[40 + k : 64 + k, 60:84] = 200
        out.append(frame)
    return out


@pytest.mark.parametrize("interval, expected", [(1, [7, 7, 7, 7, 7]), (2, [7, 1, 7, 1, 7]), (3, [7, 1, 1, 7, 1])])
def test_scales_searched_every_kth_frame(interval, expected):
    frames = _frames(6)
    tracker = EcoTracker(preset("hc").with_(scale_search_interval=interval))
    tracker.initialize(frames[0], np.array([60.0, 40.0, 24.0, 24.0]))
    searched = []
    for k, frame in enumerate(frames[1:], start=1):
        pred = tracker.predict(frame)
        searched.append(len(tracker._last_peaks))
        tracker.update(frame, pred.box)
        assert abs(pred.center[1] - (51.5 + k)) < 1.5  # still on the moving square
    assert searched == expected


def test_a_single_scale_look_does_not_count_as_a_tracked_frame():
    frames = _frames(3)
    tracker = EcoTracker(preset("hc").with_(scale_search_interval=2))
    tracker.initialize(frames[0], np.array([60.0, 40.0, 24.0, 24.0]))
    tracker.predict(frames[1], search_scales=False)  # e.g. a re-acquisition check: no update follows
    assert len(tracker._last_peaks) == 1
    tracker.predict(frames[1])
    assert len(tracker._last_peaks) == 7  # the first tracked frame still searches scales


def test_bad_interval_is_a_clear_error():
    with pytest.raises(InputError, match="scale_search_interval must be at least 1"):
        preset("hc").with_(scale_search_interval=0)
