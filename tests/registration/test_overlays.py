"""Overlay masks (registration/overlays.py) on the generator's OSDs: they cover the overlay, and little else."""

import cv2
import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.registration.overlays import (
    OverlayMask, StaticOverlayMask, blank_out, feature_mask, fitted, overlay_mask, static_mask, text_mask,
)
from rgbt_toolkit.synth.config import SceneConfig
from rgbt_toolkit.synth.osd import osd_pixels
from rgbt_toolkit.synth.render import SceneRenderer

TIMES = np.linspace(0.0, 3.9, 4)


def _frames(challenges: set[str], modality: str, seed: int = 0, **sizes) -> list[np.ndarray]:
    renderer = SceneRenderer(SceneConfig(challenges=frozenset({"overlays", *challenges}), seed=seed, **sizes))
    return [renderer.render(t, modality, i).image for i, t in enumerate(TIMES)]


def _truth(frames: list[np.ndarray], modality: str, times=TIMES) -> np.ndarray:
    size = (frames[0].shape[1], frames[0].shape[0])
    return np.any([osd_pixels(size, t, modality) for t in times], axis=0)


def _scores(mask: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    return float(mask[truth].mean()), float(mask[~truth].mean())


@pytest.mark.parametrize("modality", ["rgb", "t"])
@pytest.mark.parametrize("challenges", [set(), {"low_light"}, {"far_target"}])
def test_text_mask_covers_the_osd_of_one_still_and_little_else(modality, challenges):
    frames = _frames(challenges, modality)
    covered, rest = _scores(text_mask(frames[0]), _truth(frames[:1], modality, TIMES[:1]))
    assert covered >= 0.9 and rest < 0.05


@pytest.mark.parametrize("modality", ["rgb", "t"])
def test_text_mask_at_full_hd_covers_the_osd(modality):
    frames = _frames(set(), modality, rgb_size=(1920, 1080), t_size=(640, 512), duration=0.3)
    covered, rest = _scores(text_mask(frames[0]), _truth(frames[:1], modality, TIMES[:1]))
    assert covered >= 0.9 and rest < 0.05


def test_text_mask_leaves_a_plain_scene_alone():
    renderer = SceneRenderer(SceneConfig(seed=0))
    assert text_mask(renderer.render(0.5, "rgb").image).mean() < 0.01


@pytest.mark.parametrize("modality", ["rgb", "t"])
def test_static_mask_finds_the_fixed_osd_under_a_moving_camera(modality):
    frames = _frames({"camera_motion"}, modality)
    mask = static_mask(frames)
    assert mask is not None
    covered, rest = _scores(mask, _truth(frames, modality))
    assert covered >= 0.8 and rest < 0.05


def test_static_mask_says_nothing_for_a_still_camera():
    assert static_mask(_frames(set(), "t")) is None
    assert static_mask(_frames({"real_sensor"}, "t")) is None  # sensor noise alone does not make it move


@pytest.mark.parametrize("modality", ["rgb", "t"])
def test_overlay_mask_of_a_sequence_covers_the_osd(modality):
    frames = _frames({"camera_motion"}, modality)
    covered, rest = _scores(overlay_mask(frames), _truth(frames, modality))
    assert covered >= 0.9 and rest < 0.06


def test_accumulator_is_cheap_state_and_checks_sizes():
    accumulator = StaticOverlayMask()
    assert accumulator.update(np.zeros((480, 640), np.uint8)) is None
    assert accumulator._low.shape == (240, 320)  # frames are shrunk to 320 px
    with pytest.raises(InputError, match="differ in size"):
        accumulator.update(np.zeros((240, 320), np.uint8))


def test_blank_out_leaves_no_edge_in_the_mask():
    frames = _frames(set(), "rgb")
    mask = text_mask(frames[0])
    grey = blank_out(frames[0], mask)
    strokes = cv2.morphologyEx(np.round(grey * 255).astype(np.uint8), cv2.MORPH_TOPHAT, np.ones((5, 5), np.uint8))
    assert strokes[_truth(frames[:1], "rgb", TIMES[:1])].max() < 30
    assert np.array_equal(grey[~mask], blank_out(frames[0], None)[~mask])


def test_fitted_resizes_a_hand_mask_keeping_every_masked_pixel():
    hand = np.zeros((100, 200), np.uint8)
    hand[10, 21] = 255
    small = fitted(hand, (50, 100))
    assert small.shape == (50, 100) and small[5, 10] and small.sum() == 1
    with pytest.raises(InputError, match="2-D"):
        fitted(np.zeros(5), (5, 5))


def test_a_fine_texture_is_not_taken_for_text():
    rng = np.random.default_rng(0)
    noise = [rng.integers(0, 256, (480, 640), dtype=np.uint8) for _ in range(3)]
    assert text_mask(noise[0]).mean() == 0.0
    assert overlay_mask(noise).mean() < 0.15


def test_accumulator_answers_at_the_size_asked():
    accumulator = StaticOverlayMask()
    for frame in _frames({"camera_motion"}, "rgb"):
        accumulator.update(frame)
    small = accumulator.mask((120, 160))
    assert small.shape == (120, 160) and small[:20].any()  # the OSD's top rows


def test_per_frame_mask_keeps_corners_off_the_osd_over_a_panning_sky():
    """Over a dark sky the OSD holds most of the corners a camera-motion estimator would follow (they say the camera
    stands still); the per-frame mask, at the estimator's half size, leaves none of them."""
    renderer = SceneRenderer(SceneConfig(challenges=frozenset({"overlays", "camera_motion", "far_target"}), seed=1))
    frames = [renderer.render(i / 15, "t", i).image for i in range(0, 60, 6)]
    accumulator = OverlayMask()
    for frame in frames:
        accumulator.update(frame)
    small = cv2.resize(frames[5], None, fx=0.5, fy=0.5, interpolation=cv2.INTER_AREA)
    osd = cv2.resize(osd_pixels((256, 192), 5 * 6 / 15, "t").astype(np.uint8), (128, 96)) > 0
    osd = cv2.dilate(osd.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0  # a corner sits beside the stroke
    corners = cv2.goodFeaturesToTrack(small, 200, 0.01, 7, blockSize=7).reshape(-1, 2).astype(int)
    assert osd[corners[:, 1], corners[:, 0]].mean() > 0.5
    allowed = feature_mask(accumulator.mask(small.shape), small.shape)
    kept = cv2.goodFeaturesToTrack(small, 200, 0.01, 7, blockSize=7, mask=allowed)
    kept = np.zeros((0, 2), int) if kept is None else kept.reshape(-1, 2).astype(int)
    assert not osd[kept[:, 1], kept[:, 0]].any()
    assert feature_mask(None, small.shape) is None
