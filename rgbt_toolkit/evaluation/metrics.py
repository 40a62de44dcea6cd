"""Per-frame tracking errors and the threshold curves built from them, as pure vectorised functions.

Boxes are float (N, 4) ``x, y, w, h`` arrays. The conventions are those of the OTB-derived RGB-T toolkits, which the
published GTOT / RGBT234 / RGBT210 / LasHeR numbers depend on:

* overlap (IoU) on inclusive pixels: ``x2 = x + w - 1`` and the intersection side is ``min(x2) - max(x1) + 1``;
* centre error between centres ``x + (w - 1) / 2`` (the ``-1/2`` cancels in every difference, so using ``w / 2``
  gives the same errors);
* normalised centre error (LaSOT / LasHeR NPR): both centres divided by the ground-truth width and height.

NaN boxes give NaN errors, which compare false with every threshold: a missing box is a failed frame.
"""

from __future__ import annotations

import numpy as np


def centres(boxes: np.ndarray) -> np.ndarray:
    """Box centres (N, 2) as ``x + (w - 1) / 2, y + (h - 1) / 2``."""
    b = np.asarray(boxes, dtype=float)
    return b[:, :2] + (b[:, 2:4] - 1.0) / 2.0


def centre_error(boxes: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """Euclidean distance between box centres, per frame (pixels)."""
    d = centres(boxes) - centres(gt)
    return np.hypot(d[:, 0], d[:, 1])


def normalised_centre_error(boxes: np.ndarray, gt: np.ndarray, eps: float = 1e-8) -> np.ndarray:
    """Centre error with x divided by the ground-truth width and y by its height (LaSOT's normalised precision)."""
    g = np.asarray(gt, dtype=float)
    d = (centres(boxes) - centres(g)) / (g[:, 2:4] + eps)
    return np.hypot(d[:, 0], d[:, 1])


def iou_inclusive(boxes: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """Intersection over union on inclusive pixel boxes, per frame, as the RGB-T toolkits compute it.

    Zero-size boxes give 0 (no intersection); two zero-size boxes give NaN (0 / 0), a failed frame.
    """
    a = np.asarray(boxes, dtype=float)
    b = np.asarray(gt, dtype=float)
    iw = np.minimum(a[:, 0] + a[:, 2], b[:, 0] + b[:, 2]) - np.maximum(a[:, 0], b[:, 0])
    ih = np.minimum(a[:, 1] + a[:, 3], b[:, 1] + b[:, 3]) - np.maximum(a[:, 1], b[:, 1])
    inter = np.maximum(iw, 0.0) * np.maximum(ih, 0.0)
    union = a[:, 2] * a[:, 3] + b[:, 2] * b[:, 3] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        return inter / union


def iou_continuous(boxes: np.ndarray, gt: np.ndarray, bounds: tuple[float, float] | None = None) -> np.ndarray:
    """IoU of continuous rectangles ``[x, x + w] x [y, y + h]`` (VOT geometry), optionally clipped to an image.

    ``bounds = (width, height)`` clips both boxes to ``[0, width] x [0, height]`` first, as VOT's bounded overlap.
    """
    a = np.asarray(boxes, dtype=float).copy()
    b = np.asarray(gt, dtype=float).copy()
    ax1, ay1, ax2, ay2 = a[:, 0], a[:, 1], a[:, 0] + a[:, 2], a[:, 1] + a[:, 3]
    bx1, by1, bx2, by2 = b[:, 0], b[:, 1], b[:, 0] + b[:, 2], b[:, 1] + b[:, 3]
    if bounds is not None:
        w, h = bounds
        ax1, ax2, bx1, bx2 = (np.clip(v, 0.0, w) for v in (ax1, ax2, bx1, bx2))
        ay1, ay2, by1, by2 = (np.clip(v, 0.0, h) for v in (ay1, ay2, by1, by2))
    iw = np.maximum(np.minimum(ax2, bx2) - np.maximum(ax1, bx1), 0.0)
    ih = np.maximum(np.minimum(ay2, by2) - np.maximum(ay1, by1), 0.0)
    inter = iw * ih
    union = np.maximum(ax2 - ax1, 0) * np.maximum(ay2 - ay1, 0) + np.maximum(bx2 - bx1, 0) * np.maximum(by2 - by1, 0)
    union = union - inter
    out = np.zeros_like(inter)
    ok = union > 0
    out[ok] = inter[ok] / union[ok]
    out[np.isnan(union)] = np.nan  # a NaN box stays unknown
    return out


def hits_below(errors: np.ndarray, thresholds: np.ndarray, strict: bool = False) -> np.ndarray:
    """Number of frames with error ``<= t`` (``< t`` when ``strict``) for each threshold ``t``."""
    e = np.asarray(errors, dtype=float)[:, None]
    t = np.asarray(thresholds, dtype=float)[None, :]
    return (e < t).sum(axis=0) if strict else (e <= t).sum(axis=0)


def hits_above(overlaps: np.ndarray, thresholds: np.ndarray) -> np.ndarray:
    """Number of frames with overlap ``> t`` for each threshold ``t`` (the success-plot count)."""
    return (np.asarray(overlaps, dtype=float)[:, None] > np.asarray(thresholds, dtype=float)[None, :]).sum(axis=0)


def area_under_curve(curve: np.ndarray, thresholds: np.ndarray, method: str) -> float:
    """Success score from a success curve: ``"mean"`` of its points or the ``"trapezoid"`` area over [t0, t1]."""
    curve = np.asarray(curve, dtype=float)
    if method == "mean":
        return float(curve.mean())
    if method == "trapezoid":
        t = np.asarray(thresholds, dtype=float)
        return float(np.sum((curve[1:] + curve[:-1]) * np.diff(t)) / 2.0 / (t[-1] - t[0]))
    raise ValueError(f"unknown area method '{method}'; use 'mean' or 'trapezoid'")
