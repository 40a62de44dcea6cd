"""The crossing look-alikes: one modality sees a second target passing behind the real one, the other does not."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.synth import SceneConfig, SceneRenderer


def _look_alike(renderer: SceneRenderer, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Mean RGB colour of the look-alike's upper half and mean thermal grey of its core, at time ``t``."""
    a = renderer.camera_matrix(t)
    cx, cy = a[:, :2] @ renderer.timeline.at("crossing_xy", t) + a[:, 2]
    hx, hy = renderer.target_half * 0.5
    rows, cols = slice(int(cy - hy), int(cy)), slice(int(cx - hx), int(cx + hx))
    rgb = renderer.render(t, "rgb", 0).image[rows, cols].reshape(-1, 3).mean(axis=0)
    thermal = renderer.render(t, "t", 0).image[rows, cols].mean()
    return rgb, thermal


def test_look_alike_passes_behind_the_target_at_60_percent():
    renderer = SceneRenderer(SceneConfig.aligned(challenges=frozenset({"crossing_thermal"}), seed=3))
    tl = renderer.timeline
    gaps = np.linalg.norm(tl.crossing_xy - tl.target_xy, axis=1)
    assert abs(tl.times[np.argmin(gaps)] - 0.6 * renderer.config.duration) < 0.05
    assert gaps.min() < 0.5 * renderer.target_half[1]
    assert renderer.flags(0.6 * renderer.config.duration)["distractor"]
    assert not renderer.flags(0.0)["distractor"]


@pytest.mark.parametrize("challenge, red_jacket, warm", [("crossing_color", True, False),
                                                         ("crossing_thermal", False, True)])
def test_look_alike_shows_in_one_modality_only(challenge, red_jacket, warm):
    renderer = SceneRenderer(SceneConfig.aligned(challenges=frozenset({challenge}), seed=3))
    rgb, thermal = _look_alike(renderer, 0.6 * renderer.config.duration + 0.4)  # beside the target after the pass
    assert (rgb[0] > 150 and rgb[1] < 80 and rgb[2] < 80) == red_jacket  # TARGET_TOP is (0.85, 0.15, 0.10)
    assert (thermal > 200) == warm  # the target's core renders at ~250, the background below ~150


def test_scenes_without_crossing_keep_their_random_stream():
    plain = SceneRenderer(SceneConfig.aligned(challenges=frozenset({"distractor_thermal"}), seed=5))
    crossing = SceneRenderer(SceneConfig.aligned(challenges=frozenset({"distractor_thermal", "crossing_color"}),
                                                 seed=5))
    assert plain.timeline.crossing_xy is None
    np.testing.assert_array_equal(plain.timeline.distractor_xy, crossing.timeline.distractor_xy)
