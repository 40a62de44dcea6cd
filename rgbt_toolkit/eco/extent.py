"""The target's own extent inside a loose first box.

Labels of small targets often hold a few pixels of target in a box of mostly background (a bird of 3 px in an
11 px box, a helicopter of 5 px in a 22x29 px box). ECO's spatial regularisation lets the filter use everything
inside the box at almost no cost, so on such a box it learns the static background around the target as much as the
target, and stays on that background when the target moves away. This module finds the small blob that stands out
from its surroundings near the box centre; the tracker then regularises and labels on that blob while it keeps
reporting boxes of the given size (docs/eco.md, "Loose boxes around small targets").
"""

from __future__ import annotations

import cv2
import numpy as np


def target_extent(grey: np.ndarray, box: np.ndarray, *, min_contrast: float = 8.0, noise_factor: float = 4.0,
                  max_share: float = 0.35, pad: float = 1.0, max_offset: float = 0.1) -> np.ndarray | None:
    """Height and width ``[h, w]`` (pixels) of the blob that stands out from its surroundings at the centre of
    ``box`` (``[x, y, w, h]`` in the uint8 grey frame), or None when the box is not loose around one.

    The background is the median over a window as large as the box (a blob smaller than half the window leaves it
    unchanged); pixels that differ from it by more than ``min_contrast`` grey levels and ``noise_factor`` times the
    residual's spread in the ring around the box are the blob's candidates. The connected group that covers the
    central half of the box is the target; its bounding box plus ``pad`` pixels a side is the extent, returned only
    when its area is at most ``max_share`` of the box and its centre lies within ``max_offset`` of the box's size of
    the box's centre (a box that is already tight, a target that does not stand out, or one beside the centre, on
    which a window centred in the box would not sit, gives None).
    """
    x, y, w, h = (float(v) for v in box)
    H, W = grey.shape
    side = max(w, h)
    x0, y0 = int(max(0, np.floor(x - side))), int(max(0, np.floor(y - side)))
    x1, y1 = int(min(W, np.ceil(x + w + side))), int(min(H, np.ceil(y + h + side)))
    region = grey[y0:y1, x0:x1]
    if region.shape[0] < 3 or region.shape[1] < 3:
        return None
    k = int(2 * round(side / 2) + 1)  # odd, about the box's longer side
    background = _median(region, k)
    resid = np.abs(region.astype(np.float32) - background.astype(np.float32))
    yy, xx = np.mgrid[y0:y1, x0:x1]
    inside = (xx >= x) & (xx < x + w) & (yy >= y) & (yy < y + h)
    ring = resid[~inside]
    spread = 1.4826 * float(np.median(np.abs(ring - np.median(ring)))) if ring.size else 0.0
    mask = (resid > max(min_contrast, noise_factor * spread)) & inside
    if not mask.any():
        return None
    _, labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    cx, cy = x + (w - 1) / 2, y + (h - 1) / 2
    central = (np.abs(xx - cx) <= w / 4) & (np.abs(yy - cy) <= h / 4)
    ids = np.unique(labels[central & mask])
    if ids.size == 0:
        return None
    blob = np.isin(labels, ids)
    rows, cols = np.nonzero(blob)
    bh = float(rows.max() - rows.min() + 1) + 2 * pad
    bw = float(cols.max() - cols.min() + 1) + 2 * pad
    bh, bw = min(bh, h), min(bw, w)
    if bh * bw > max_share * w * h:
        return None
    off = np.array([(rows.max() + rows.min()) / 2 + y0 - cy, (cols.max() + cols.min()) / 2 + x0 - cx])
    if np.any(np.abs(off) > max_offset * np.array([h, w])):
        return None
    return np.array([bh, bw])


def _median(region: np.ndarray, k: int) -> np.ndarray:
    """Median over a ``k`` x ``k`` window (OpenCV's uint8 median filter, any odd size) of a border-replicated copy,
    so that the frame's edge does not count as black."""
    r = k // 2
    padded = cv2.copyMakeBorder(region, r, r, r, r, cv2.BORDER_REPLICATE)
    return cv2.medianBlur(padded, k)[r:-r, r:-r]
