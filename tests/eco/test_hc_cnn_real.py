"""The collapse that ``hc+cnn`` fixes, on the real clip that shows it (skips without ``../shared``).

svan_v_bird_013: a bird of 28x24 px crossing a textured background at about 3.5 px per frame. ECO-hc's hand-crafted
filter learns the background inside the first box as much as the bird and stays where the bird started (success 0.5
over the clip); with the backbone's stride-4 layer added (``hc+cnn``, docs/decisions.md D49) it follows the bird up
to the clip's first shot cut at frame 141, as ECO-deep does (success 60.7 for both over the clip).
"""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.eco import EcoTracker, preset
from tests.real_clips import real_clip

FRAMES = 80  # well before the first shot cut (frame 141); the bird moves about 250 px by then


def _centre_errors(frames: list[np.ndarray], labels: np.ndarray, name: str) -> np.ndarray:
    tracker = EcoTracker(preset(name))
    tracker.initialize(frames[0], labels[0])
    errors = []
    for frame, label in zip(frames[1:], labels[1:]):
        box = tracker.predict(frame).box
        tracker.update(frame, box)
        errors.append(np.hypot(*((box[:2] + box[2:] / 2) - (label[:2] + label[2:] / 2))))
    return np.asarray(errors)


def test_hc_cnn_follows_the_bird_that_hc_loses(shared_dir):
    frames, labels = real_clip(shared_dir, "svan_v_bird_013", FRAMES, folder="real_more")
    hc = _centre_errors(frames, labels, "hc")
    cnn = _centre_errors(frames, labels, "hc+cnn")
    # hc stays where the bird started: by the end the bird is far from its box
    assert np.median(hc[-20:]) > 60.0
    # hc+cnn stays on it: within about half the bird's size
    assert np.median(cnn) < 8.0 and np.median(cnn[-20:]) < 8.0
