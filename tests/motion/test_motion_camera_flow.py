"""Camera motion from corner flow (``points="flow"``, the tracker's fast default): the same transform as SIFT on
consecutive frames at a fraction of the cost, and SIFT where the flow cannot follow."""

from dataclasses import replace

import numpy as np
import pytest
from motion_synth import make_texture, warp

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.camera_motion import (
    FAST_CAMERA_MOTION,
    CameraMotionCompensation,
    CameraMotionEstimator,
    CameraMotionSettings,
    apply_transform,
)

AFFINE = np.array([[1.01, 0.02, 6.0], [-0.015, 0.995, -4.0], [0.0, 0.0, 1.0]])
BOX = np.array([180.0, 150.0, 50.0, 40.0])


@pytest.fixture(scope="module")
def previous():
    return make_texture(360, 480, 11)


def _probe_error(matrix: np.ndarray, truth: np.ndarray, width: int, height: int) -> float:
    probe = np.array([[20.0, 20.0], [width - 20.0, 30.0], [width / 2, height / 2], [40.0, height - 20.0]])
    return float(np.abs(apply_transform(matrix, probe) - apply_transform(truth, probe)).max())


@pytest.mark.parametrize("downscale", [1.0, 0.5])
def test_flow_recovers_a_known_affine_motion_as_sift_does(previous, downscale):
    settings = CameraMotionSettings(points="flow", downscale=downscale, max_keypoints=500)
    estimator = CameraMotionEstimator(settings)
    current = warp(previous, AFFINE)
    flow = estimator.estimate_flow(estimator.small_grey(previous), estimator.small_grey(current), BOX,
                                   previous.shape[:2])
    assert flow is not None and flow.valid and flow.is_motion
    assert flow.n_inliers >= 0.8 * flow.n_matches > 100
    h, w = previous.shape
    assert _probe_error(flow.matrix, AFFINE, w, h) < 0.15 / downscale
    sift = CameraMotionEstimator(replace(settings, points="sift")).estimate(previous, current, BOX)
    np.testing.assert_allclose(flow.shift, sift.shift, atol=0.2 / downscale)


def test_consecutive_frames_run_no_sift(previous, monkeypatch):
    """A pan followed frame by frame: every estimate comes from the flow, none from SIFT."""
    scene = make_texture(360, 640, 12)
    cme = CameraMotionCompensation(FAST_CAMERA_MOTION)
    monkeypatch.setattr(cme.estimator, "keypoints",
                        lambda image, allowed=None: pytest.fail("SIFT ran on a frame the flow follows"))
    cme.initialize(scene[:, :480], scene[:, :480])
    for k in (1, 2, 3):
        frame = scene[:, 12 * k: 12 * k + 480]
        step = cme.step(frame, frame, BOX)
        assert step.camera_motion
        np.testing.assert_allclose(step.motion.shift, [-12.0, 0.0], atol=0.15)
    assert cme.sift_frames == 0
    np.testing.assert_allclose(cme.accumulator.total, [-36.0, 0.0], atol=0.3)


def test_a_jump_beyond_the_flow_falls_back_to_sift():
    """A gimbal jump of 150 px in one frame (more than the flow's pyramid reaches): the flow is refused and SIFT
    finds the jump, as the paper's estimator would."""
    scene = make_texture(360, 700, 13)
    cme = CameraMotionCompensation(FAST_CAMERA_MOTION)
    cme.initialize(scene[:, :480], scene[:, :480])
    previous_small = cme.estimator.small_grey(scene[:, :480])
    current = scene[:, 150:630]
    assert cme.estimator.estimate_flow(previous_small, cme.estimator.small_grey(current), BOX, (360, 480)) is None
    step = cme.step(current, current, BOX)
    assert step.camera_motion and cme.sift_frames == 1
    np.testing.assert_allclose(step.motion.shift, [-150.0, 0.0], atol=0.5)


def test_flat_frames_give_no_flow_and_no_motion():
    flat = np.full((240, 320), 90, np.uint8)
    estimator = CameraMotionEstimator(FAST_CAMERA_MOTION)
    assert estimator.estimate_flow(estimator.small_grey(flat), estimator.small_grey(flat), BOX, flat.shape) is None


def test_unknown_point_source_is_refused():
    with pytest.raises(InputError, match="camera motion points"):
        CameraMotionSettings(points="orb")


@pytest.mark.parametrize("points", ["flow", "sift"])
def test_a_pan_is_found_with_a_burned_in_overlay_on(points):
    """A rig panning 6 px a frame; the thermal camera sees a faint scene (a night sky: 30 grey levels) under its
    on-screen display (clock, name, angles) burned in at fixed places. The display's sharp corners stay put and
    outnumber the scene's, so without the overlay mask the thermal estimate reads "no motion"; with it the pan is
    found."""
    from rgbt_toolkit.synth.osd import draw_osd

    scene = make_texture(240, 460, 14)
    faint = (scene.astype(np.float32) * 0.12 + 100).astype(np.uint8)
    rgb = [scene[:, 6 * k: 6 * k + 320] for k in range(20)]  # the visible camera sees the pan: the trigger fires
    thermal = [draw_osd(faint[:, 6 * k: 6 * k + 320], k / 30, "t") for k in range(20)]
    box = np.array([150.0, 110.0, 20.0, 20.0])
    settings = replace(FAST_CAMERA_MOTION, points=points)
    found = {}
    for refresh in (0, FAST_CAMERA_MOTION.overlay_refresh):
        cme = CameraMotionCompensation(replace(settings, overlay_refresh=refresh))
        cme.initialize(rgb[0], thermal[0])
        steps = [cme.step(a, b, box) for a, b in zip(rgb[1:], thermal[1:])]
        assert sum(step.trigger.triggered for step in steps) >= 15
        found[refresh] = np.array([step.motion.shift if step.motion is not None and step.motion.valid
                                   else [np.nan, np.nan] for step in steps])
    masked = found[FAST_CAMERA_MOTION.overlay_refresh]
    assert np.nanmedian(np.abs(found[0][:, 0] + 6.0)) > 2.0  # without the mask: fooled by the display
    if points == "flow":  # corners of the faint scene are followed
        assert np.mean(np.abs(masked[:, 0] + 6.0) < 0.5) > 0.9
    else:  # SIFT finds too little in the faint scene: no estimate, which is not a wrong one
        assert np.all(np.isnan(masked[:, 0]) | (np.abs(masked[:, 0] + 6.0) < 0.5))
