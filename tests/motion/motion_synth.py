"""Synthetic textured frames for the motion tests (no ../shared needed); imported by the test modules."""

from __future__ import annotations

import cv2
import numpy as np



def make_texture(height: int, width: int, seed: int, channels: int = 1) -> np.ndarray:
    """Band-limited random texture, uint8: blobs at three scales, rich in SIFT keypoints."""
    rng = np.random.default_rng(seed)
    shape = (height, width) if channels == 1 else (height, width, channels)
    img = np.zeros(shape)
    for sigma in (2, 5, 11):
        img += cv2.GaussianBlur(rng.normal(size=shape), (0, 0), sigma) * sigma
    img = (img - img.min()) / (img.max() - img.min()) * 255.0
    return img.astype(np.uint8)


def warp(image: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """The image seen by a camera that moved so that previous pixel p lands at matrix @ p."""
    h, w = image.shape[:2]
    return cv2.warpPerspective(
        image, np.asarray(matrix, np.float64), (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT
    )
