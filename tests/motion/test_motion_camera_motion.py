"""SIFT + MSAC camera motion on frames warped by known transforms."""

import numpy as np
import pytest
from motion_synth import make_texture, warp

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.camera_motion import (
    CameraMotionCompensation,
    CameraMotionEstimator,
    CameraMotionSettings,
    CameraShiftAccumulator,
    apply_transform,
    compensate_box,
    compensate_position,
)


def _similarity(angle, scale, tx, ty):
    c, s = scale * np.cos(angle), scale * np.sin(angle)
    return np.array([[c, -s, tx], [s, c, ty], [0.0, 0.0, 1.0]])


TRUE_MOTION = {
    "translation": np.array([[1.0, 0.0, 6.0], [0.0, 1.0, -4.0], [0.0, 0.0, 1.0]]),
    "similarity": _similarity(0.03, 1.02, 6.0, -4.0),
    "affine": np.array([[1.01, 0.02, 6.0], [-0.015, 0.995, -4.0], [0.0, 0.0, 1.0]]),
    "projective": np.array([[1.01, 0.02, 6.0], [-0.015, 0.995, -4.0], [2e-5, -1e-5, 1.0]]),
}


@pytest.fixture(scope="module")
def previous():
    return make_texture(240, 320, 0)


def test_threshold_matches_toolbox_chi_square():
    # chi-square 0.9999 quantile with 4 dof is 23.513 (published tables); one-way error = sqrt(23.513 / 2)
    assert CameraMotionSettings().threshold_px == pytest.approx(np.sqrt(23.513 / 2), abs=1e-3)


@pytest.mark.parametrize("model", list(TRUE_MOTION))
def test_recovers_known_transform(previous, model):
    truth = TRUE_MOTION[model]
    current = warp(previous, truth)
    box = np.array([100.0, 80.0, 40.0, 60.0])
    result = CameraMotionEstimator(CameraMotionSettings(model=model)).estimate(previous, current, box)
    assert result.valid and result.is_motion and result.model == model
    assert result.n_inliers >= 0.8 * result.n_matches > 100
    probe = np.array([[20.0, 20.0], [300.0, 30.0], [160.0, 120.0], [40.0, 220.0]])
    np.testing.assert_allclose(apply_transform(result.matrix, probe), apply_transform(truth, probe), atol=0.1)
    centre = np.array([120.0, 110.0])
    np.testing.assert_allclose(result.shift, apply_transform(truth, centre) - centre, atol=0.1)


def test_small_motion_is_not_camera_motion(previous):
    truth = np.array([[1.0, 0.0, 2.0], [0.0, 1.0, 1.5], [0.0, 0.0, 1.0]])  # 2.5 px < 5 px
    result = CameraMotionEstimator().estimate(previous, warp(previous, truth), np.array([100.0, 80, 40, 60]))
    assert result.valid and not result.is_motion
    np.testing.assert_allclose(result.shift, [2.0, 1.5], atol=0.1)


def test_outlier_matches_are_rejected(previous):
    # a moving object (a pasted patch from another texture) inside a camera pan: MSAC keeps the background motion
    truth = TRUE_MOTION["translation"]
    current = warp(previous, truth)
    current[60:180, 80:240] = make_texture(120, 160, 9)
    result = CameraMotionEstimator(CameraMotionSettings(model="affine")).estimate(previous, current)
    assert result.valid
    np.testing.assert_allclose(result.matrix[:2], truth[:2], atol=0.02)


def test_blank_frames_give_invalid_identity():
    blank = np.full((120, 160), 128, np.uint8)
    result = CameraMotionEstimator().estimate(blank, blank)
    assert not result.valid and not result.is_motion
    np.testing.assert_array_equal(result.matrix, np.eye(3))
    assert result.n_matches == 0


def test_bad_settings_and_inputs():
    with pytest.raises(InputError, match="unknown camera motion model 'rigid'"):
        CameraMotionSettings(model="rigid")
    with pytest.raises(InputError, match="differ in size"):
        CameraMotionEstimator().estimate(np.zeros((10, 10), np.uint8), np.zeros((12, 10), np.uint8))


def test_compensation_helpers():
    m = np.array([[1.0, 0.0, 5.0], [0.0, 1.0, -3.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(compensate_position(m, [10.0, 20.0]), [15.0, 17.0])
    np.testing.assert_allclose(compensate_box(m, [10.0, 20.0, 8.0, 6.0]), [15.0, 17.0, 8.0, 6.0])
    # box [10, 10, 4, 4] covers pixels 10..13, centre 11.5 (pixel-centre coordinates, as OpenCV and ECO)
    zoom = np.diag([2.0, 2.0, 1.0])
    np.testing.assert_allclose(compensate_box(zoom, [10.0, 10.0, 4.0, 4.0]), [21.5, 21.5, 4.0, 4.0])
    np.testing.assert_allclose(compensate_box(zoom, [10.0, 10.0, 4.0, 4.0], keep_size=False), [19.5, 19.5, 8.0, 8.0])


def test_accumulator_round_trip_and_sign():
    acc = CameraShiftAccumulator()
    acc.add([5.0, -3.0])
    acc.add([1.0, 1.0])
    np.testing.assert_allclose(acc.total, [6.0, -2.0])
    # a target standing still in the world appears shifted with the camera; in stable coordinates it does not move
    np.testing.assert_allclose(acc.to_stable([106.0, 98.0]), [100.0, 100.0])
    np.testing.assert_allclose(acc.to_image(acc.to_stable([3.0, 4.0])), [3.0, 4.0])


def test_per_frame_compensation_accumulates():
    rgb_scene, t_scene = make_texture(240, 400, 4, channels=3), make_texture(240, 400, 5)
    cme = CameraMotionCompensation()
    cme.initialize(rgb_scene[:, :320], t_scene[:, :320])
    box = np.array([100.0, 80.0, 40.0, 60.0])
    still = cme.step(rgb_scene[:, :320], t_scene[:, :320], box)
    assert not still.trigger.triggered and still.motion is None and not still.camera_motion
    np.testing.assert_array_equal(still.box, box)
    # the camera pans right by 24 px: the scene (and a static target) moves 24 px left in the image
    moved = cme.step(rgb_scene[:, 24:344], t_scene[:, 24:344], box)
    assert moved.trigger.triggered and moved.camera_motion
    np.testing.assert_allclose(moved.box, box - [24.0, 0.0, 0.0, 0.0], atol=0.1)
    np.testing.assert_allclose(moved.total_shift, [-24.0, 0.0], atol=0.1)
    with pytest.raises(InputError, match="before initialize"):
        CameraMotionCompensation().step(rgb_scene, t_scene, box)


def test_reused_frame_buffer_and_keypoint_reuse():
    # a reader that decodes every frame into the same array must not fool the module; consecutive motion frames
    # compute SIFT once per frame
    rgb_scene, t_scene = make_texture(240, 440, 6, channels=3), make_texture(240, 440, 7)
    cme = CameraMotionCompensation()
    calls = []
    original = cme.estimator.keypoints
    cme.estimator.keypoints = lambda image, allowed=None: calls.append(1) or original(image, allowed)
    rgb_buf, t_buf = rgb_scene[:, :320].copy(), t_scene[:, :320].copy()
    cme.initialize(rgb_buf, t_buf)
    box = np.array([100.0, 80.0, 40.0, 60.0])
    for k in (1, 2, 3):
        rgb_buf[:], t_buf[:] = rgb_scene[:, 30 * k : 30 * k + 320], t_scene[:, 30 * k : 30 * k + 320]
        step = cme.step(rgb_buf, t_buf, box)
        assert step.camera_motion
        np.testing.assert_allclose(step.motion.shift, [-30.0, 0.0], atol=0.1)
    assert len(calls) == 4  # frames 0 and 1 for the first estimate, then one per frame
    np.testing.assert_allclose(cme.accumulator.total, [-90.0, 0.0], atol=0.2)


def test_chi_square_quantile_matches_scipy():
    from scipy.stats import chi2

    from rgbt_toolkit.motion.camera_motion import _chi2_quantile

    for dof in (2, 4, 6):
        for p in (0.5, 0.9, 0.95, 0.99):
            assert _chi2_quantile(p, dof) == pytest.approx(chi2.ppf(p, dof), rel=1e-9)
    with pytest.raises(InputError):
        _chi2_quantile(0.95, 3)
