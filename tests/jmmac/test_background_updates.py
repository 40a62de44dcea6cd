"""With two tracker threads the model updates of frame t run in the background while frame t+1's camera motion is
estimated (issue #21); they are waited for before the next search, so the boxes are the same, and they run in the
background only when they do not read the frames' pixels (a caller may refill its frame buffer meanwhile)."""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np
import pytest

from rgbt_toolkit.eco import EcoTracker, preset as eco_preset
from rgbt_toolkit.jmmac.config import preset
from rgbt_toolkit.jmmac.pipeline import JmmacTracker

from .fakes import ScriptedTracker


class _SlowUpdates(ScriptedTracker):
    def __init__(self, truth, reads_frame: bool, fail: bool = False):
        super().__init__(truth)
        self.reads_frame, self.fail = reads_frame, fail
        self.finished: list[float] = []

    def update_reads_frame(self, frame, box):
        return self.reads_frame

    def update(self, frame, box):
        time.sleep(0.2)
        if self.fail:
            raise RuntimeError("update failed")
        self.finished.append(time.perf_counter())


class _StillCamera:
    def __init__(self):
        self.started: list[float] = []

    def initialize(self, rgb, thermal):
        pass

    def step(self, rgb, thermal, box):
        self.started.append(time.perf_counter())
        return SimpleNamespace(camera_motion=False, box=box, total_shift=np.zeros(2))


def _track(reads_frame: bool, parallel: bool = True, fail: bool = False, frames: int = 3):
    truth = [np.array([50.0, 50.0])] * (frames + 1)
    rgb, t = _SlowUpdates(truth, reads_frame, fail), _SlowUpdates(truth, reads_frame, fail)
    camera = _StillCamera()
    tracker = JmmacTracker(preset("average", camera_motion=True, parallel_trackers=parallel), rgb, t,
                           camera_motion=camera)
    frame = np.zeros((100, 100), np.uint8)
    tracker.initialize(frame, frame, np.array([45.0, 41.0, 11.0, 19.0]))
    for _ in range(frames):
        tracker.track(frame, frame)
    return rgb, camera


def test_updates_overlap_the_next_camera_motion_step():
    rgb, camera = _track(reads_frame=False)
    # frame 2's camera step started before frame 1's update had finished
    assert camera.started[1] < rgb.finished[0]
    assert len(rgb.finished) == 2  # frame 3's update is still running or just done; frames 1 and 2 were waited for


@pytest.mark.parametrize("reads_frame, parallel", [(True, True), (False, False)])
def test_updates_that_read_the_frame_or_one_thread_stay_in_line(reads_frame, parallel):
    rgb, camera = _track(reads_frame=reads_frame, parallel=parallel)
    assert camera.started[1] > rgb.finished[0]
    assert len(rgb.finished) == 3


def test_an_error_in_a_background_update_is_raised_by_the_next_frame():
    with pytest.raises(RuntimeError, match="update failed"):
        _track(reads_frame=False, fail=True, frames=2)


def test_eco_says_when_its_update_reads_the_frame():
    rng = np.random.default_rng(0)
    frame = rng.integers(40, 80, (120, 160), dtype=np.uint8)
    frame[40:64, 60:84] = 200
    tracker = EcoTracker(eco_preset("hc"))
    tracker.initialize(frame, np.array([60.0, 40.0, 24.0, 24.0]))
    pred = tracker.predict(frame)
    assert not tracker.update_reads_frame(frame, pred.box)  # the search's own sample is shifted
    assert tracker.update_reads_frame(frame.copy(), pred.box)  # another array: extracted anew
    far = pred.box + np.array([60.0, 0.0, 0.0, 0.0])
    assert tracker.update_reads_frame(frame, far)  # too far from the search centre: extracted anew
    bigger = np.r_[pred.box[:2] - 6, pred.box[2:] * 1.5]
    assert tracker.update_reads_frame(frame, bigger)  # another scale: extracted anew
