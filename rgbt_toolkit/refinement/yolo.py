"""Decoding of YOLO-family detector outputs into class-agnostic boxes, and non-maximum suppression (pure numpy).

Three output layouts cover the common ONNX exports:

``fastestdet``
    One ``[1, 5 + C, H, W]`` map (FastestDet, dog-qiuqiu 2022): per cell, objectness (already a sigmoid), four box
    terms and C class probabilities (already a softmax). The centre is the cell index plus ``tanh`` of the first two
    terms, the width and height are ``sigmoid`` of the last two, as fractions of the input; the score is
    ``obj ** 0.6 * max_class ** 0.4`` (the repository's own post-processing).
``yolov5``
    ``[1, N, 5 + C]`` rows ``cx, cy, w, h, obj, classes...`` in input pixels (YOLOv5 / v7 exports, sigmoids
    applied); score = ``obj * max_class``.
``yolov8``
    ``[1, 4 + C, N]`` columns ``cx, cy, w, h, classes...`` in input pixels (YOLOv8 / v11 exports, no objectness);
    score = ``max_class``.

Every decoder returns ``(boxes, scores, labels)`` with boxes as ``x0, y0, x1, y1`` in input pixels.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import WeightsError

LAYOUTS = ("fastestdet", "yolov5", "yolov8")


def guess_layout(shape: tuple[int, ...]) -> str:
    """The layout of an output of this shape (see the module docstring), or :class:`WeightsError`."""
    if len(shape) == 4 and shape[0] == 1 and shape[1] > 5:
        return "fastestdet"
    if len(shape) == 3 and shape[0] == 1:
        if shape[2] > 5 and shape[1] > shape[2]:
            return "yolov5"
        if shape[1] > 4 and shape[2] > shape[1]:
            return "yolov8"
    raise WeightsError(
        f"unrecognised detector output of shape {list(shape)}; expected [1,5+C,H,W] (FastestDet), [1,N,5+C] "
        "(YOLOv5) or [1,4+C,N] (YOLOv8)")


def decode_fastestdet(out: np.ndarray, input_size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Decode a FastestDet map ``[1, 5 + C, H, W]`` for an input of ``(width, height)`` pixels."""
    out = np.asarray(out, dtype=np.float64)[0]
    _, h, w = out.shape
    gy, gx = np.mgrid[0:h, 0:w]
    cx = (np.tanh(out[1]) + gx) / w
    cy = (np.tanh(out[2]) + gy) / h
    bw, bh = 1 / (1 + np.exp(-out[3])), 1 / (1 + np.exp(-out[4]))
    cls = out[5:]
    scores = np.clip(out[0], 0, 1) ** 0.6 * np.clip(cls.max(axis=0), 0, 1) ** 0.4
    boxes = np.stack([(cx - bw / 2) * input_size[0], (cy - bh / 2) * input_size[1],
                      (cx + bw / 2) * input_size[0], (cy + bh / 2) * input_size[1]], axis=-1)
    return boxes.reshape(-1, 4), scores.ravel(), cls.argmax(axis=0).ravel()


def _from_centre_rows(rows: np.ndarray) -> np.ndarray:
    cx, cy, w, h = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3]
    return np.stack([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2], axis=1)


def decode_yolov5(out: np.ndarray, input_size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Decode YOLOv5-style rows ``[1, N, 5 + C]`` (pixels, sigmoids applied)."""
    rows = np.asarray(out, dtype=np.float64)[0]
    cls = rows[:, 5:]
    return _from_centre_rows(rows), rows[:, 4] * cls.max(axis=1), cls.argmax(axis=1)


def decode_yolov8(out: np.ndarray, input_size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Decode YOLOv8-style columns ``[1, 4 + C, N]`` (pixels, class sigmoids applied, no objectness)."""
    rows = np.asarray(out, dtype=np.float64)[0].T
    cls = rows[:, 4:]
    return _from_centre_rows(rows), cls.max(axis=1), cls.argmax(axis=1)


DECODERS = {"fastestdet": decode_fastestdet, "yolov5": decode_yolov5, "yolov8": decode_yolov8}


def nms(boxes: np.ndarray, scores: np.ndarray, iou_threshold: float = 0.45) -> np.ndarray:
    """Indices of the boxes kept by greedy class-agnostic non-maximum suppression, best first.

    ``boxes`` are ``x0, y0, x1, y1``; a box is dropped when its IoU with a better kept box exceeds the threshold.
    """
    boxes, scores = np.asarray(boxes, dtype=np.float64), np.asarray(scores, dtype=np.float64)
    order = np.argsort(-scores, kind="stable")
    area = np.clip(boxes[:, 2] - boxes[:, 0], 0, None) * np.clip(boxes[:, 3] - boxes[:, 1], 0, None)
    keep = []
    while len(order):
        i, rest = order[0], order[1:]
        keep.append(i)
        x0 = np.maximum(boxes[i, 0], boxes[rest, 0])
        y0 = np.maximum(boxes[i, 1], boxes[rest, 1])
        x1 = np.minimum(boxes[i, 2], boxes[rest, 2])
        y1 = np.minimum(boxes[i, 3], boxes[rest, 3])
        inter = np.clip(x1 - x0, 0, None) * np.clip(y1 - y0, 0, None)
        overlap = inter / np.maximum(area[i] + area[rest] - inter, 1e-12)
        order = rest[overlap <= iou_threshold]
    return np.asarray(keep, dtype=int)
