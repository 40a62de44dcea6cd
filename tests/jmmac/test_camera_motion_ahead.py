"""The tracker told each pair's camera-motion measurement by its caller (``rgbt track`` measures on its reader thread,
ahead of the tracker) gives the boxes it gives when it measures itself, and the harness's prepared pairs carry it."""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.api.tracking import tracker_from_options
from rgbt_toolkit.synth import SceneConfig, SceneRenderer


def _frames(count: int = 24):
    renderer = SceneRenderer(SceneConfig(duration=count / 15, rgb_fps=15, t_fps=15, rgb_size=(320, 240),
                                         t_size=(320, 240), challenges=frozenset({"camera_motion"}), seed=3))
    times = np.arange(count) / 15
    return [(renderer.render(t, "rgb").image, renderer.render(t, "t").image) for t in times], \
        renderer.render(0.0, "rgb").box


def test_boxes_are_the_same_whoever_measures_the_camera_motion():
    frames, box = _frames()
    itself, told = tracker_from_options("default"), tracker_from_options("default")
    itself.initialize(*frames[0], box)
    told.initialize(*frames[0], box, camera=told.measure_camera_motion(*frames[0], first=True))
    compensated = 0
    for rgb, thermal in frames[1:]:
        expected = itself.track(rgb, thermal)
        got = told.track(rgb, thermal, camera=told.measure_camera_motion(rgb, thermal))
        np.testing.assert_array_equal(got.box, expected.box)
        assert (got.mode, got.camera_motion) == (expected.mode, expected.camera_motion)
        np.testing.assert_array_equal(told.camera_shift, itself.camera_shift)
        compensated += expected.camera_motion
    assert compensated >= 2  # the scene's camera moved enough for the compensation to act


def test_no_camera_motion_no_measurement():
    frames, _ = _frames(2)
    tracker = tracker_from_options("+MF")  # the ablation row without camera-motion estimation
    assert tracker.measure_camera_motion(*frames[0], first=True) is None
