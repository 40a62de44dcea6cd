"""The crossing look-alikes: one modality sees a second target passing behind the real one, the other does not."""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.synth import SceneConfig, SceneRenderer


def _hot_columns(image: np.ndarray, box: np.ndarray, threshold: float) -> int:
    """Columns outside the target's box (in its rows) holding pixels above ``threshold``."""
    x, y, w, h = box.astype(int)
    rows = image[y + 2: y + h - 2]
    hot = (rows > threshold).any(axis=0)
    hot[max(x - 2, 0): x + w + 2] = False
    return int(hot.sum())


def test_warm_crossing_is_a_second_warm_body_in_thermal_only_and_passes_at_60_percent():
    renderer = SceneRenderer(SceneConfig.aligned(challenges=frozenset({"crossing_thermal"}), seed=3))
    tl = renderer.timeline
    gaps = np.linalg.norm(tl.crossing_xy - tl.target_xy, axis=1)
    meet = tl.times[np.argmin(gaps)]
    assert abs(meet - 0.6 * renderer.config.duration) < 0.05 and gaps.min() < 0.5 * renderer.target_half[1]
    t = 0.6 * renderer.config.duration + 0.4  # just after the pass: beside the target
    thermal = renderer.render(t, "t", 0)
    assert _hot_columns(thermal.image, thermal.box, 200) >= 10
    rgb = renderer.render(t, "rgb", 0)
    red = (rgb.image[:, :, 0] > 150) & (rgb.image[:, :, 1] < 90)
    assert _hot_columns(red.astype(np.uint8), rgb.box, 0) == 0  # no second red jacket
    assert renderer.flags(0.6 * renderer.config.duration)["distractor"]


def test_colour_crossing_is_a_second_red_jacket_in_rgb_only():
    renderer = SceneRenderer(SceneConfig.aligned(challenges=frozenset({"crossing_color"}), seed=3))
    t = 0.6 * renderer.config.duration + 0.4
    rgb = renderer.render(t, "rgb", 0)
    red = (rgb.image[:, :, 0] > 150) & (rgb.image[:, :, 1] < 90)
    assert _hot_columns(red.astype(np.uint8), rgb.box, 0) >= 10
    thermal = renderer.render(t, "t", 0)
    assert _hot_columns(thermal.image, thermal.box, 200) == 0


def test_scenes_without_crossing_keep_their_frames():
    config = SceneConfig.aligned(challenges=frozenset({"distractor_thermal"}), seed=5)
    assert SceneRenderer(config).timeline.crossing_xy is None
    with_crossing = SceneRenderer(SceneConfig.aligned(challenges=frozenset({"distractor_thermal", "crossing_color"}),
                                                      seed=5))
    plain = SceneRenderer(config)
    np.testing.assert_array_equal(plain.timeline.distractor_xy, with_crossing.timeline.distractor_xy)
