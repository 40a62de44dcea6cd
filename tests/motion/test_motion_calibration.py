"""Mapping raw q and DDIS onto the paper's scales."""

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.calibration import (
    CalibrationSettings,
    ScoreCalibrator,
    geometry_q_scale,
    jitter_boxes,
)


def test_geometry_scale():
    # our geometry equal to the paper's (side / sigma = 48) needs no change; a peak twice as wide has a quarter of
    # the ideal q (q ~ area / sigma^2), so it is scaled up about four times
    assert geometry_q_scale((96, 96), 2.0) == pytest.approx(1.0)
    assert geometry_q_scale((96, 96), 4.0) == pytest.approx(4.0, rel=0.02)


def test_running_q_scale_maps_early_level_to_reference_then_freezes():
    cal = ScoreCalibrator(CalibrationSettings(warmup_frames=4, q_reference=300.0))
    assert cal.paper_q(50.0) == pytest.approx(300.0)  # the first value is the early level itself
    for raw in (40.0, 60.0, 50.0):
        cal.paper_q(raw)
    assert cal.q_frozen and cal.q_scale == pytest.approx(6.0)  # median 50 -> 300
    assert cal.paper_q(25.0) == pytest.approx(150.0)  # a halved raw q: between q_low and q_hi
    assert cal.q_scale == pytest.approx(6.0)  # no longer observed


def test_fixed_and_limits():
    cal = ScoreCalibrator(CalibrationSettings(q_method="fixed", s_method="fixed", q_scale=2.0, s_scale=0.5))
    assert cal.paper_q(100.0) == 200.0 and cal.paper_s(40.0) == 20.0
    cal = ScoreCalibrator(CalibrationSettings(scale_limits=(0.5, 2.0)))
    assert cal.set_template_baseline([1.0, 1.0, 1.0]) == 2.0  # 48 / 1 clipped to 2
    cal.reset()
    assert cal.s_scale == 1.0


def test_template_baseline_maps_median_to_reference():
    cal = ScoreCalibrator()
    assert cal.set_template_baseline([40.0, 60.0, 50.0, np.nan]) == pytest.approx(48.0 / 50.0)
    assert cal.paper_s(50.0) == pytest.approx(48.0)


def test_jitter_boxes():
    boxes = jitter_boxes(np.array([10.0, 20.0, 50.0, 100.0]), shift=0.04, scale=0.05)
    assert boxes.shape == (6, 4)
    np.testing.assert_allclose(boxes[0], [12.0, 20.0, 50.0, 100.0])
    np.testing.assert_allclose(boxes[3], [10.0, 16.0, 50.0, 100.0])
    centres = boxes[:, :2] + (boxes[:, 2:] - 1) / 2
    np.testing.assert_allclose(centres[4:], [[34.5, 69.5], [34.5, 69.5]])
    np.testing.assert_allclose(boxes[4, 2:], [52.5, 105.0])


def test_bad_settings():
    with pytest.raises(InputError, match="unknown q calibration"):
        CalibrationSettings(q_method="percentile")
    with pytest.raises(InputError, match="warmup_frames"):
        CalibrationSettings(warmup_frames=0)


def test_reset_forgets_the_frozen_q_scale():
    """The frozen scale is kept between frames; a new sequence must start its own warm-up."""
    cal = ScoreCalibrator(CalibrationSettings(warmup_frames=2, q_reference=300.0))
    for raw in (50.0, 50.0, 10.0):
        cal.paper_q(raw)
    assert cal.q_scale == pytest.approx(6.0)
    cal.reset()
    assert not cal.q_frozen and cal.q_scale == 1.0
    for raw in (100.0, 100.0):
        cal.paper_q(raw)
    assert cal.q_scale == pytest.approx(3.0)
