"""Deformable Diversity Similarity (Talmi et al., CVPR 2017)."""

import cv2
import numpy as np
import pytest
import torch
from motion_synth import make_texture

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.ddis import TemplateMatcher, colour_patch_features, crop_window, ddis_score

BOX = np.array([60.0, 60.0, 48.0, 48.0])


@pytest.fixture(scope="module")
def scene():
    return make_texture(200, 200, 1, channels=3)


def _window(image, box):
    return colour_patch_features(crop_window(image, box, (48, 48)))


def test_hand_computed_example():
    # template a b c in a row; window a a c: NN = (0, 0, 2), kappa = (2, 2, 1), r = (0, 1, 0)
    a, b, c = [1.0, 0.0], [0.0, 1.0], [5.0, 5.0]
    template = np.array([[a, b, c]])
    window = np.array([[a, a, c]])
    expected = 100.0 / 3.0 * (np.exp(-1.0) + np.exp(-1.0) / 2.0 + 1.0)
    assert ddis_score(template, window) == pytest.approx(expected)


def test_window_with_itself_is_maximal(scene):
    template = _window(scene, BOX)
    assert ddis_score(template, template) == pytest.approx(100.0)
    others = [ddis_score(template, _window(scene, BOX + [dx, dy, 0, 0])) for dx, dy in ((2, 0), (0, 3), (9, -4))]
    assert max(others) < 100.0


def test_shifted_and_deformed_copies_beat_unrelated_patch(scene):
    template = _window(scene, BOX)
    shifted = ddis_score(template, _window(scene, BOX + [3, 2, 0, 0]))
    rot = cv2.getRotationMatrix2D((84.0, 84.0), 8.0, 1.05)
    deformed = ddis_score(template, _window(cv2.warpAffine(scene, rot, (200, 200)), BOX))
    unrelated = ddis_score(template, _window(make_texture(200, 200, 5, channels=3), BOX))
    assert shifted > 2 * unrelated and deformed > 2 * unrelated
    assert unrelated < 10.0


def test_similarity_falls_with_displacement(scene):
    template = _window(scene, BOX)
    scores = [ddis_score(template, _window(scene, BOX + [d, 0, 0, 0])) for d in (0, 3, 9, 24)]
    assert scores == sorted(scores, reverse=True)


def test_diversity_penalises_repetition():
    # a window that repeats one template vector everywhere scores far below one that uses them all
    rng = np.random.default_rng(0)
    template = rng.normal(size=(6, 6, 8))
    flat = np.broadcast_to(template[2, 3], (6, 6, 8))
    assert ddis_score(template, flat) < 5.0


def test_torch_and_size_mismatch(scene):
    template = _window(scene, BOX)
    window = colour_patch_features(crop_window(scene, BOX, (36, 36)))  # 12 x 12 grid vs 16 x 16
    score = ddis_score(torch.from_numpy(template), torch.from_numpy(window))
    assert score == pytest.approx(ddis_score(template, window))
    assert 0.0 < score < 100.0


def test_matcher_scores_pair(scene):
    matcher = TemplateMatcher(_window(scene, BOX))
    s_a, s_m = matcher.scores(_window(scene, BOX), _window(scene, BOX + [20, 0, 0, 0]))
    assert s_a == pytest.approx(100.0) and s_m < s_a


def test_crop_window_exact_pixels_and_outside(scene):
    np.testing.assert_array_equal(crop_window(scene, [10.0, 20.0, 30.0, 40.0], (30, 40)), scene[20:60, 10:40])
    outside = crop_window(scene, [-500.0, -500.0, 20.0, 20.0], (20, 20))
    assert outside.shape == (20, 20, 3)
    with pytest.raises(InputError, match="positive size"):
        crop_window(scene, [0.0, 0.0, 0.0, 5.0], (4, 4))


def test_errors():
    with pytest.raises(InputError, match="channels"):
        ddis_score(np.zeros((3, 3, 2)), np.zeros((3, 3, 4)))
    with pytest.raises(InputError, match="smaller than one"):
        colour_patch_features(np.zeros((2, 2, 3), np.uint8))
