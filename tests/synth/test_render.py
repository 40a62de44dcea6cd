"""The generator's ground truth: the rendered target is where the box says, in both cameras."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.synth import CHALLENGES, SceneConfig, SceneRenderer
from rgbt_toolkit.registration.transforms import project


def _extent(mask: np.ndarray) -> np.ndarray:
    """x, y, w, h of a boolean mask in the benchmark first-pixel convention."""
    ys, xs = np.nonzero(mask)
    return np.array([xs.min(), ys.min(), xs.max() - xs.min() + 1, ys.max() - ys.min() + 1], float)


@pytest.mark.parametrize("challenges", [(), ("camera_motion",), ("scale_change", "camera_motion")])
def test_thermal_box_matches_the_hot_pixels(challenges):
    renderer = SceneRenderer(SceneConfig(challenges=frozenset(challenges), seed=3))
    for index in (0, 17, 41):
        frame = renderer.render(index / 15, "t", index)
        hot = _extent(frame.image > 165)  # the target is >= 0.74 -> ~178 grey; the background stays below ~150
        np.testing.assert_allclose(hot, frame.box, atol=2.0)


@pytest.mark.parametrize("challenges", [(), ("camera_motion",)])
def test_rgb_box_matches_the_red_jacket(challenges):
    renderer = SceneRenderer(SceneConfig(challenges=frozenset(challenges), seed=5))
    for index in (0, 30):
        frame = renderer.render(index / 15, "rgb", index)
        image = frame.image.astype(int)
        red = (image[:, :, 0] > 150) & (image[:, :, 1] < 90) & (image[:, :, 2] < 90)
        x, y, w, h = frame.box
        jacket = _extent(red)
        assert abs(jacket[0] - x) < 2.0 and abs(jacket[1] - y) < 2.0  # left and top edges
        assert abs(jacket[0] + jacket[2] - (x + w)) < 2.0  # right edge


def test_thermal_box_is_the_rgb_outline_through_the_rig_homography():
    renderer = SceneRenderer(SceneConfig(challenges=frozenset({"camera_motion"}), seed=2))
    t = 1.3
    rgb_outline = project(renderer.world_to_camera(t, "rgb"), renderer.target_outline(t))
    via_rig = project(renderer.h_rgb_to_t, rgb_outline)
    direct = project(renderer.world_to_camera(t, "t"), renderer.target_outline(t))
    np.testing.assert_allclose(via_rig, direct, atol=1e-9)


def test_same_seed_same_frames_and_other_seed_differs():
    config = SceneConfig(challenges=frozenset({"degradation", "low_light"}), seed=7)
    a = SceneRenderer(config).render(0.5, "rgb", 7).image
    b = SceneRenderer(config).render(0.5, "rgb", 7).image
    c = SceneRenderer(SceneConfig(challenges=config.challenges, seed=8)).render(0.5, "rgb", 7).image
    np.testing.assert_array_equal(a, b)
    assert np.abs(a.astype(int) - c.astype(int)).mean() > 5


def test_challenge_flags_follow_the_switches():
    def flagged(challenges):
        renderer = SceneRenderer(SceneConfig(challenges=frozenset(challenges), seed=1, duration=4.0))
        return {name for i in range(60) for name, on in renderer.flags(i / 15).items() if on}

    assert flagged(()) == set()
    for challenge, flag in [("occlusion", "occlusion"), ("low_light", "low_light"),
                            ("thermal_crossover", "thermal_crossover"), ("camera_motion", "camera_motion"),
                            ("scale_change", "scale_change"), ("fast_motion", "fast_motion")]:
        assert flag in flagged((challenge,)), challenge


def test_low_light_darkens_rgb_only_and_crossover_hides_the_target_in_thermal():
    dark = SceneRenderer(SceneConfig(challenges=frozenset({"low_light"}), seed=4))
    assert dark.render(3.5, "rgb", 0).image.mean() < 0.35 * dark.render(0.0, "rgb", 0).image.mean()

    cross = SceneRenderer(SceneConfig(challenges=frozenset({"thermal_crossover"}), seed=4))
    def contrast(t):
        frame = cross.render(t, "t", 0)
        x, y, w, h = frame.box.astype(int)
        inside = frame.image[y + 2: y + h - 2, x + 2: x + w - 2].mean()
        ring = frame.image[max(y - 10, 0): y + h + 10, max(x - 10, 0): x + w + 10].mean()
        return inside - ring
    assert contrast(0.0) > 40 and abs(contrast(2.2)) < 20


def test_unknown_challenge_is_a_clear_error():
    with pytest.raises(InputError, match="unknown challenge.*teleport"):
        SceneConfig(challenges=frozenset({"teleport"}))
    assert "occlusion" in CHALLENGES


def test_aligned_rig_has_identity_homography_and_equal_boxes():
    renderer = SceneRenderer(SceneConfig.aligned(seed=4, challenges=frozenset({"camera_motion"})))
    np.testing.assert_allclose(renderer.h_rgb_to_t, np.eye(3), atol=1e-12)
    rgb, t = renderer.render(1.0, "rgb", 15), renderer.render(1.0, "t", 15)
    assert rgb.image.shape[:2] == t.image.shape
    np.testing.assert_allclose(rgb.box, t.box, atol=1e-9)
