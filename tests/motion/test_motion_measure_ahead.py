"""Camera motion measured ahead of the tracker: :meth:`CameraMotionCompensation.measure` (the trigger and the fit,
no box needed) then :meth:`apply` (the box's shift) give what :meth:`step` gives, frame for frame, so ``rgbt track``
can run the first half on its reader thread."""

import numpy as np
from motion_synth import make_texture, warp

from rgbt_toolkit.motion.camera_motion import (
    FAST_CAMERA_MOTION,
    CameraMotionCompensation,
    CameraMotionEstimator,
    CameraMotionTrigger,
)

FAST_TRIGGER_OF_CME = CameraMotionCompensation(FAST_CAMERA_MOTION).trigger.settings

BOXES = [np.array([180.0, 150.0, 50.0, 40.0]), np.array([60.0, 40.0, 30.0, 30.0]),
         np.array([300.0, 200.0, 80.0, 60.0]), np.array([10.0, 300.0, 20.0, 20.0])]


def _pan(frames: int = 8):
    """A textured scene seen by a camera that pans, rolls and zooms by varying steps (small ones the trigger
    ignores, large ones it does not): the motion's shift differs from box to box."""
    scene = make_texture(360, 480, 21)
    steps = [(1.0, 0.0, 1.0), (1.02, 0.01, 14.0), (1.0, 0.0, 0.0), (0.98, -0.02, -22.0), (1.0, 0.0, 3.0),
             (1.03, 0.015, 18.0), (1.0, -0.01, -25.0)]
    out, total = [scene], np.eye(3)
    for zoom, roll, shift in steps[: frames - 1]:
        c, s = zoom * np.cos(roll), zoom * np.sin(roll)
        total = np.array([[c, -s, shift], [s, c, 0.4 * shift], [0.0, 0.0, 1.0]]) @ total
        out.append(warp(scene, total))
    return out


def test_measure_then_apply_matches_a_direct_estimate_with_the_box():
    """The reference is computed apart: the trigger on the pair, and the flow estimate told the box, whose shift is
    measured at the box's centre. Measuring without the box and applying it later must give the same numbers."""
    frames = _pan()
    cme = CameraMotionCompensation(FAST_CAMERA_MOTION)
    trigger, estimator = CameraMotionTrigger(FAST_TRIGGER_OF_CME), CameraMotionEstimator(FAST_CAMERA_MOTION)
    first = cme.measure(frames[0], frames[0], restart=True)
    assert first.first and first.motion is None
    cme.apply(first, BOXES[0])
    trigger.update(frames[0], frames[0])
    total, moved = np.zeros(2), 0
    for k, frame in enumerate(frames[1:], start=1):
        box = BOXES[k % len(BOXES)]  # the box differs frame to frame: only apply() may depend on it
        step = cme.apply(cme.measure(frame, frame), box)
        assert step.trigger == trigger.update(frame, frame)
        if not step.trigger.triggered:
            assert step.motion is None
            continue
        reference = estimator.estimate_flow(estimator.small_grey(frames[k - 1]), estimator.small_grey(frame), box,
                                            frame.shape[:2])
        assert reference is not None and step.motion is not None
        np.testing.assert_array_equal(step.motion.matrix, reference.matrix)
        np.testing.assert_allclose(step.motion.shift, reference.shift, atol=1e-9)
        assert step.motion.is_motion == reference.is_motion
        if reference.is_motion:
            total += reference.shift
            moved += 1
        np.testing.assert_allclose(step.total_shift, total, atol=1e-9)
    assert moved >= 3  # compensated frames were compared, whose shifts differ from box to box


def test_a_restart_forgets_the_last_sequence():
    frames = _pan()
    cme = CameraMotionCompensation(FAST_CAMERA_MOTION)
    cme.apply(cme.measure(frames[0], frames[0]), BOXES[0])
    for frame in frames[1:5]:
        cme.apply(cme.measure(frame, frame), BOXES[0])
    assert np.any(cme.accumulator.total != 0)
    restarted = cme.measure(frames[6], frames[6], restart=True)  # a new sequence: nothing to compare with
    assert restarted.first and restarted.motion is None
    step = cme.apply(restarted, BOXES[0])
    np.testing.assert_array_equal(step.total_shift, [0.0, 0.0])
    # the next pair is compared with the restarting pair, not with the last sequence's frame
    fresh = CameraMotionCompensation(FAST_CAMERA_MOTION)
    fresh.initialize(frames[6], frames[6])
    np.testing.assert_array_equal(cme.apply(cme.measure(frames[7], frames[7]), BOXES[1]).total_shift,
                                  fresh.step(frames[7], frames[7], BOXES[1]).total_shift)
