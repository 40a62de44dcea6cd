"""Hand labels made from truth boxes: each box moved and resized by a few pixels and rounded, as people label.

Calibration from a target's boxes (``rgbt register --from-boxes``) meets such labels on real footage: annotators
place each box edge to within a few pixels, independently per frame and per camera, and write whole pixels. The
truth boxes of a scene are exact; these labels let the calibration be tested on evidence with a known noise.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import InputError


def hand_labels(boxes: np.ndarray, jitter: float, rng: np.random.Generator) -> np.ndarray:
    """``boxes`` (N, 4) ``x, y, w, h`` with Gaussian noise of ``jitter`` px on each value, rounded to whole pixels.

    Rows of zero size (``0,0,0,0``: the target is not seen) stay zero; a jittered size never drops below 1 px.
    """
    if not (np.isfinite(jitter) and jitter >= 0):
        raise InputError(f"label jitter must be a number of pixels >= 0, got {jitter}")
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    absent = ~(boxes[:, 2:] > 0).all(axis=1)
    labels = np.round(boxes + rng.normal(0.0, jitter, boxes.shape))
    labels[:, 2:] = np.maximum(labels[:, 2:], 1.0)
    labels[absent] = 0.0
    return labels
