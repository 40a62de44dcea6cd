"""Pick a target when the user gave none: the most salient warm object in the first thermal frame.

People and vehicles are usually the warmest compact blobs in a thermal image, so a contrast-weighted connected
component of the hot tail of the histogram is a sensible default. The chosen box is reported to the user so they can
re-run with ``--init``.
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError


def salient_warm_object(thermal: np.ndarray, min_area_fraction: float = 2e-4,
                        max_area_fraction: float = 0.15) -> np.ndarray:
    """Box ``[x, y, w, h]`` of the warm blob with the highest contrast-times-size score.

    Raises :class:`InputError` when the frame has no warm compact object (e.g. a blank frame).
    """
    grey = thermal if thermal.ndim == 2 else cv2.cvtColor(thermal, cv2.COLOR_RGB2GRAY)
    grey = cv2.GaussianBlur(grey.astype(np.float32), (0, 0), 1.5)
    spread = float(np.percentile(grey, 99) - np.percentile(grey, 50))
    if spread < 8:
        raise InputError("no warm object stands out in the first thermal frame; give the target with --init x,y,w,h")
    background = cv2.blur(grey, (max(3, grey.shape[1] // 8) | 1, max(3, grey.shape[0] // 8) | 1))
    local = grey - background
    threshold = np.percentile(local, 97)
    mask = (local > max(threshold, 0.25 * spread)).astype(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    area_total = grey.size
    best, best_score = None, 0.0
    for label in range(1, count):
        x, y, w, h, area = stats[label]
        if not (min_area_fraction * area_total <= area <= max_area_fraction * area_total):
            continue
        fill = area / float(w * h)
        contrast = float(local[labels == label].mean())
        score = contrast * np.sqrt(area) * fill
        if score > best_score:
            best, best_score = np.array([x, y, w, h], dtype=float), score
    if best is None:
        raise InputError("no warm object stands out in the first thermal frame; give the target with --init x,y,w,h")
    return best
