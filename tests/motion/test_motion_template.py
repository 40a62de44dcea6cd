"""Template matching moves to the thermal frame when the visible patch is dark."""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.motion.template import ModalityAwareTemplate, patch_mean


class _Stub:
    def __init__(self, value):
        self.value, self.frames = value, []

    def initialize(self, frame, box):
        self.frames.append(frame.shape)

    def __call__(self, frame, box_a, box_m):
        return self.value, self.value


def test_dark_visible_patch_uses_the_thermal_template():
    rgb_scorer, t_scorer = _Stub(1.0), _Stub(2.0)
    template = ModalityAwareTemplate(rgb_scorer, t_scorer, min_light=40)
    box = np.array([10.0, 10.0, 20.0, 20.0])
    bright, dark = np.full((60, 60, 3), 120, np.uint8), np.full((60, 60, 3), 10, np.uint8)
    thermal = np.full((60, 60), 200, np.uint8)
    template.initialize(bright, thermal, box)
    assert t_scorer.frames == [(60, 60, 3)]  # grey thermal frames reach DDIS as three channels
    assert template(bright, thermal, box, box) == (1.0, 1.0) and template.last_modality == "rgb"
    assert template(dark, thermal, box, box) == (2.0, 2.0) and template.last_modality == "t"
    assert patch_mean(bright, np.array([100.0, 100, 5, 5])) == 0.0  # outside the frame
