"""Box arithmetic: deltas round-trip, IoU values, frame-1 sampling bounds."""

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.refinement.boxes import apply_deltas, as_box, encode_deltas, iou, sample_boxes


def test_iou_known_values():
    a = np.array([0.0, 0.0, 10.0, 10.0])
    assert iou(a, a) == pytest.approx(1.0)
    assert iou(a, [5.0, 0.0, 10.0, 10.0]) == pytest.approx(50 / 150)
    assert iou(a, [20.0, 20.0, 5.0, 5.0]) == 0.0
    many = iou(np.stack([a, a + [5, 0, 0, 0]]), a)
    assert many.shape == (2,) and many[1] == pytest.approx(1 / 3)


def test_deltas_round_trip_and_meaning():
    rng = np.random.default_rng(0)
    boxes = np.column_stack([rng.uniform(0, 100, (50, 2)), rng.uniform(5, 50, (50, 2))])
    target = np.column_stack([rng.uniform(0, 100, (50, 2)), rng.uniform(5, 50, (50, 2))])
    d = encode_deltas(boxes, target)
    np.testing.assert_allclose(apply_deltas(boxes, d), target, atol=1e-9)
    # a box twice as wide with the same centre: dx = 0, log-width = log 2
    d1 = encode_deltas(np.array([10.0, 10.0, 10.0, 20.0]), np.array([5.0, 10.0, 20.0, 20.0]))
    np.testing.assert_allclose(d1, [0.0, 0.0, np.log(2), 0.0], atol=1e-12)


def test_samples_respect_iou_and_are_reproducible():
    box = np.array([50.0, 40.0, 20.0, 60.0])
    s = sample_boxes(box, 1000, np.random.default_rng(3), min_iou=0.6)
    assert s.shape == (1000, 4)
    assert np.all(iou(s, box) > 0.6)
    assert np.all(s[:, 2:] > 0)
    # the draw is varied (not collapsed on the box) and spans scale and aspect changes
    assert iou(s, box).min() < 0.65
    assert np.ptp(np.log(s[:, 2] / s[:, 3])) > 0.5
    np.testing.assert_array_equal(s, sample_boxes(box, 1000, np.random.default_rng(3), min_iou=0.6))


@pytest.mark.parametrize("bad", [[1, 2, 3], [0, 0, -1, 5], [0, 0, np.nan, 5]])
def test_bad_box_message(bad):
    with pytest.raises(InputError, match="positive width and height"):
        as_box(bad)
