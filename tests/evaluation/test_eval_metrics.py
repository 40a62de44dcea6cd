"""Per-frame errors and curve arithmetic against hand-computed values."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.evaluation import metrics
from rgbt_toolkit.evaluation.ope import matlab_round


def test_inclusive_iou_counts_pixels():
    gt = np.array([[0.0, 0.0, 10.0, 10.0]] * 4)
    boxes = np.array([[0, 0, 10, 10], [5, 0, 10, 10], [10, 0, 10, 10], [9, 9, 10, 10]], dtype=float)
    # pixels 5..9 overlap (5 columns); the boxes at x = 10 touch only continuously, not on pixels
    np.testing.assert_allclose(metrics.iou_inclusive(boxes, gt), [1.0, 50 / 150, 0.0, 1 / 199])


def test_continuous_iou_and_bounds():
    gt = np.array([[0.0, 0.0, 10.0, 10.0]] * 3)
    boxes = np.array([[5, 0, 10, 10], [10, 0, 10, 10], [-5, 0, 10, 10]], dtype=float)
    np.testing.assert_allclose(metrics.iou_continuous(boxes, gt), [50 / 150, 0.0, 50 / 150])
    # clipped to a 100 x 100 image, the box at x = -5 keeps only [0, 5]
    np.testing.assert_allclose(metrics.iou_continuous(boxes, gt, bounds=(100, 100))[2], 0.5)


def test_zero_size_and_nan_boxes():
    gt = np.array([[0.0, 0.0, 10.0, 10.0]] * 2)
    boxes = np.array([[2, 2, 0, 0], [np.nan] * 4])
    iou = metrics.iou_inclusive(boxes, gt)
    assert iou[0] == 0.0 and np.isnan(iou[1])
    err = metrics.centre_error(boxes, gt)
    assert np.isnan(err[1])
    assert metrics.hits_below(err, [100.0])[0] == 1  # NaN never passes a threshold
    assert metrics.hits_above(iou, [-0.5])[0] == 1


def test_centre_error_and_normalised_error():
    gt = np.array([[0.0, 0.0, 10.0, 20.0]])
    boxes = np.array([[3.0, 4.0, 10.0, 20.0]])
    assert metrics.centre_error(boxes, gt)[0] == pytest.approx(5.0)
    assert metrics.normalised_centre_error(boxes, gt)[0] == pytest.approx(np.hypot(0.3, 0.2))


def test_strict_and_inclusive_precision_counts():
    errors = np.array([4.0, 5.0, 5.0, 6.0])
    assert metrics.hits_below(errors, [5.0], strict=True)[0] == 1
    assert metrics.hits_below(errors, [5.0])[0] == 3


def test_area_under_curve():
    t = np.linspace(0, 1, 3)
    curve = np.array([1.0, 0.5, 0.0])
    assert metrics.area_under_curve(curve, t, "mean") == pytest.approx(0.5)
    assert metrics.area_under_curve(np.array([1.0, 1.0, 0.0]), t, "trapezoid") == pytest.approx(0.75)
    with pytest.raises(ValueError, match="unknown area method"):
        metrics.area_under_curve(curve, t, "simpson")


def test_matlab_round_rounds_halves_away_from_zero():
    np.testing.assert_array_equal(matlab_round(np.array([0.5, 1.5, 2.5, -2.5, 2.4])), [1, 2, 3, -3, 2])
    assert np.isnan(matlab_round(np.array([np.nan]))[0])
