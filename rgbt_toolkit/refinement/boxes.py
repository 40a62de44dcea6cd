"""Box arithmetic for refinement: IoU, regression deltas, random samples around a box (all vectorised).

Boxes are the project's ``[x, y, w, h]`` (``x, y`` = first pixel column / row covered), as float arrays of shape
``(4,)`` or ``(N, 4)``. Centres follow the pipeline's convention ``xy + (wh - 1) / 2``; deltas are relative, so the
convention only has to be the same on both sides of :func:`encode_deltas` / :func:`apply_deltas`.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import InputError


def as_box(box, name: str = "box") -> np.ndarray:
    """``box`` as a float ``(4,)`` array with positive finite size, or :class:`InputError`."""
    b = np.asarray(box, dtype=float)
    if b.shape != (4,) or not np.all(np.isfinite(b)) or b[2] <= 0 or b[3] <= 0:
        shown = b.tolist() if b.size <= 8 else f"array of shape {b.shape}"
        raise InputError(f"{name} must be x,y,w,h with positive width and height, got {shown}")
    return b


def centres(boxes: np.ndarray) -> np.ndarray:
    """Centres ``(..., 2)`` of ``(..., 4)`` boxes."""
    boxes = np.asarray(boxes, dtype=float)
    return boxes[..., :2] + (boxes[..., 2:] - 1) / 2


def from_centres(centre: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Boxes with the given centres and sizes (inverse of :func:`centres`)."""
    centre, size = np.asarray(centre, dtype=float), np.asarray(size, dtype=float)
    return np.concatenate([centre - (size - 1) / 2, size], axis=-1)


def iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Intersection over union of boxes ``a`` and ``b`` (broadcast over leading axes), areas as ``w * h``."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    x1 = np.maximum(a[..., 0], b[..., 0])
    y1 = np.maximum(a[..., 1], b[..., 1])
    x2 = np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2])
    y2 = np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3])
    inter = np.clip(x2 - x1, 0, None) * np.clip(y2 - y1, 0, None)
    union = a[..., 2] * a[..., 3] + b[..., 2] * b[..., 3] - inter
    return inter / np.maximum(union, 1e-12)


def encode_deltas(boxes: np.ndarray, target: np.ndarray) -> np.ndarray:
    """R-CNN / MDNet regression targets taking ``boxes`` to ``target``: ``(dx/w, dy/h, log tw/w, log th/h)``."""
    boxes, target = np.asarray(boxes, dtype=float), np.asarray(target, dtype=float)
    shift = (centres(target) - centres(boxes)) / boxes[..., 2:]
    scale = np.log(target[..., 2:] / boxes[..., 2:])
    return np.concatenate([shift, scale], axis=-1)


def apply_deltas(boxes: np.ndarray, deltas: np.ndarray) -> np.ndarray:
    """The boxes that :func:`encode_deltas` maps ``boxes`` to (its inverse)."""
    boxes, deltas = np.asarray(boxes, dtype=float), np.asarray(deltas, dtype=float)
    centre = centres(boxes) + deltas[..., :2] * boxes[..., 2:]
    size = boxes[..., 2:] * np.exp(deltas[..., 2:])
    return from_centres(centre, size)


def sample_boxes(box: np.ndarray, n: int, rng: np.random.Generator, min_iou: float = 0.6,
                 shift: float = 0.3, scale: float = 1.5, aspect: float = 1.4) -> np.ndarray:
    """``n`` random boxes around ``box`` whose IoU with it exceeds ``min_iou`` (MDNet's bbreg training set).

    Centres move uniformly by up to ``shift`` times the box size per axis, the area changes log-uniformly within
    ``[1/scale, scale]`` (per side) and the aspect ratio within ``[1/aspect, aspect]``. Candidates are drawn in
    batches and filtered by IoU until ``n`` are kept, so every returned box satisfies the IoU bound.
    """
    box = as_box(box)
    if not 0.0 <= min_iou < 1.0:
        raise InputError(f"min_iou must be in [0, 1), got {min_iou}")
    kept: list[np.ndarray] = []
    have, rounds = 0, 0
    while have < n:
        m = max(4 * (n - have), 64)
        c = centres(box) + rng.uniform(-shift, shift, (m, 2)) * box[2:]
        s = np.exp(rng.uniform(-np.log(scale), np.log(scale), (m, 1)))
        r = np.exp(rng.uniform(-np.log(aspect), np.log(aspect), (m, 1)) / 2)
        size = box[2:] * s * np.concatenate([r, 1 / r], axis=1)
        cand = from_centres(c, size)
        cand = cand[iou(cand, box) > min_iou]
        kept.append(cand)
        have += len(cand)
        rounds += 1
        if rounds > 100:  # pragma: no cover - only with an IoU bound no random box can meet
            raise InputError(f"cannot draw boxes with IoU > {min_iou} within the sampling ranges")
    return np.concatenate(kept)[:n]
