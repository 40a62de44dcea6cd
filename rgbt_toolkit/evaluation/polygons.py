"""Region overlap for VOT trajectories: rectangles vectorised, rotated (convex) polygons by exact clipping.

Regions are ``[x, y, w, h]`` rectangles or ``[x1, y1, ..., xk, yk]`` polygons in continuous image coordinates
(a rectangle spans ``[x, x + w]``). Marker entries (ints) and NaN regions give NaN overlaps.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from rgbt_toolkit.evaluation.metrics import iou_continuous
from rgbt_toolkit.io.boxes import VotEntry


def _as_points(entry: VotEntry) -> np.ndarray:
    e = np.asarray(entry, dtype=float)
    if e.size == 4:
        x, y, w, h = e
        return np.array([[x, y], [x + w, y], [x + w, y + h], [x, y + h]])
    return e.reshape(-1, 2)


def polygon_area(points: np.ndarray) -> float:
    """Absolute shoelace area of a simple polygon (k, 2)."""
    if len(points) < 3:
        return 0.0
    x, y = points[:, 0], points[:, 1]
    return float(abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))) / 2.0)


def _orient_ccw(points: np.ndarray) -> np.ndarray:
    x, y = points[:, 0], points[:, 1]
    signed = np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))
    return points if signed >= 0 else points[::-1]


def clip_polygon(subject: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """Sutherland-Hodgman: the part of ``subject`` inside the convex polygon ``clip`` (both (k, 2))."""
    out = subject
    clip = _orient_ccw(clip)
    for a, b in zip(clip, np.roll(clip, -1, axis=0)):
        if len(out) == 0:
            break
        edge = b - a
        side = edge[0] * (out[:, 1] - a[1]) - edge[1] * (out[:, 0] - a[0])  # >= 0: inside (left of a->b)
        prev, prev_side = out[-1], side[-1]
        kept = []
        for point, s in zip(out, side):
            if s >= 0:
                if prev_side < 0:
                    kept.append(prev + (point - prev) * (prev_side / (prev_side - s)))
                kept.append(point)
            elif prev_side >= 0:
                kept.append(prev + (point - prev) * (prev_side / (prev_side - s)))
            prev, prev_side = point, s
        out = np.array(kept).reshape(-1, 2)
    return out


def polygon_iou(a: np.ndarray, b: np.ndarray, bounds: tuple[float, float] | None = None) -> float:
    """Overlap of two convex polygons, each clipped to ``[0, width] x [0, height]`` first when ``bounds`` is given."""
    if bounds is not None:
        frame = np.array([[0, 0], [bounds[0], 0], [bounds[0], bounds[1]], [0, bounds[1]]], dtype=float)
        a, b = clip_polygon(a, frame), clip_polygon(b, frame)
    area_a, area_b = polygon_area(a), polygon_area(b)
    if area_a + area_b <= 0:
        return 0.0
    inter = polygon_area(clip_polygon(a, b)) if area_a > 0 and area_b > 0 else 0.0
    return inter / (area_a + area_b - inter)


def _split_entries(entries: Sequence[VotEntry], n: int) -> tuple[np.ndarray, list[int]]:
    """Rectangles (n, 4) of the first ``n`` entries (NaN for markers and polygons) and the indices of true polygons.

    Axis-aligned 4-point polygons (the usual VOT-RGBT rows) are turned into rectangles here, vectorised.
    """
    rects = np.full((n, 4), np.nan)
    quads, others = [], []
    for i in range(n):
        e = entries[i]
        if isinstance(e, (int, np.integer)):
            continue
        if e.size == 4:
            rects[i] = e
        elif e.size == 8:
            quads.append(i)
        else:
            others.append(i)
    if quads:
        p = np.array([entries[i] for i in quads], dtype=float)
        xs, ys = np.sort(p[:, 0::2], axis=1), np.sort(p[:, 1::2], axis=1)
        aligned = (xs[:, 0] == xs[:, 1]) & (xs[:, 2] == xs[:, 3]) & (ys[:, 0] == ys[:, 1]) & (ys[:, 2] == ys[:, 3])
        idx = np.array(quads)
        rects[idx[aligned]] = np.column_stack([xs[aligned, 0], ys[aligned, 0], xs[aligned, 3] - xs[aligned, 0],
                                               ys[aligned, 3] - ys[aligned, 0]])
        others.extend(idx[~aligned].tolist())
    return rects, sorted(others)


def region_overlaps(
    trajectory: Sequence[VotEntry], groundtruth: Sequence[VotEntry], bounds: tuple[float, float] | None = None
) -> np.ndarray:
    """Per-frame overlap over the common length; NaN where either entry is a marker or has NaN values."""
    n = min(len(trajectory), len(groundtruth))
    rt, poly_t = _split_entries(trajectory, n)
    rg, poly_g = _split_entries(groundtruth, n)
    out = iou_continuous(rt, rg, bounds)  # NaN wherever either side is not a rectangle
    for i in sorted(set(poly_t) | set(poly_g)):
        t, g = trajectory[i], groundtruth[i]
        if isinstance(t, (int, np.integer)) or isinstance(g, (int, np.integer)):
            continue
        if np.isnan(t).any() or np.isnan(g).any():
            out[i] = np.nan
            continue
        out[i] = polygon_iou(_as_points(t), _as_points(g), bounds)
    return out
