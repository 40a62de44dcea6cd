"""YOLO-family output decoding and suppression on hand-built outputs."""

import numpy as np
import pytest

from rgbt_toolkit.errors import WeightsError
from rgbt_toolkit.refinement.yolo import decode_fastestdet, decode_yolov5, decode_yolov8, guess_layout, nms


def _logit(p):
    return np.log(p / (1 - p))


def test_fastestdet_cell_decoding():
    h = w = 4
    out = np.zeros((1, 5 + 3, h, w))
    out[0, 5:] = 1 / 3  # softmaxed classes
    out[0, 0, 2, 1] = 0.81  # objectness at row 2, column 1
    out[0, 1, 2, 1] = np.arctanh(0.5)  # centre x = (0.5 + 1) / 4
    out[0, 2, 2, 1] = np.arctanh(-0.25)  # centre y = (-0.25 + 2) / 4
    out[0, 3, 2, 1] = _logit(0.25)  # width = 0.25 of the input
    out[0, 4, 2, 1] = _logit(0.5)
    out[0, 5:, 2, 1] = [0.1, 0.0, 0.9]
    boxes, scores, labels = decode_fastestdet(out, (352, 352))
    k = 2 * w + 1
    cx, cy = 1.5 / 4 * 352, 1.75 / 4 * 352
    np.testing.assert_allclose(boxes[k], [cx - 44, cy - 88, cx + 44, cy + 88])
    assert scores[k] == pytest.approx(0.81**0.6 * 0.9**0.4)
    assert labels[k] == 2
    assert scores.argmax() == k


def test_yolov5_and_v8_rows():
    v5 = np.array([[[100, 50, 20, 40, 0.9, 0.1, 0.8], [10, 10, 4, 4, 0.2, 0.5, 0.5]]])
    b, s, l = decode_yolov5(v5, (640, 640))
    np.testing.assert_allclose(b[0], [90, 30, 110, 70])
    np.testing.assert_allclose(s, [0.72, 0.1])
    assert l[0] == 1
    v8 = np.transpose(np.array([[[100, 50, 20, 40, 0.3, 0.6]]]), (0, 2, 1))
    b, s, l = decode_yolov8(v8, (640, 640))
    np.testing.assert_allclose(b[0], [90, 30, 110, 70])
    assert s[0] == pytest.approx(0.6) and l[0] == 1


def test_layout_guess():
    assert guess_layout((1, 85, 22, 22)) == "fastestdet"
    assert guess_layout((1, 25200, 85)) == "yolov5"
    assert guess_layout((1, 84, 8400)) == "yolov8"
    with pytest.raises(WeightsError, match="unrecognised detector output"):
        guess_layout((1, 1000))


def test_nms_keeps_best_of_overlapping():
    boxes = np.array([[0, 0, 10, 10], [1, 1, 11, 11], [20, 20, 30, 30], [0, 0, 10, 9]], float)
    scores = np.array([0.5, 0.9, 0.7, 0.4])
    keep = nms(boxes, scores, 0.45)
    assert keep.tolist() == [1, 2]
    assert nms(np.zeros((0, 4)), np.zeros(0)).tolist() == []
