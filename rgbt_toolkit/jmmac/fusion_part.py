"""MFNet as the pipeline's ``FusionWeighting`` part: crop the search region from both frames, return w_G and W_L."""

from __future__ import annotations

import cv2
import numpy as np
import torch

from rgbt_toolkit.fusion.model import MFNet, to_tensor


def crop_resized(image: np.ndarray, region: np.ndarray, side: int) -> np.ndarray:
    """The square ``region`` (x, y, w, h; may leave the frame) resampled to ``side`` x ``side``, borders replicated.

    ``region`` is in continuous image coordinates where pixel ``(r, c)`` is centred at ``(c, r)``; its edges map onto
    the outer edges of the patch's border pixels, so patch cell ``k`` of ``G`` covers the ``k``-th ``G``-th of it.
    """
    x, y, w, h = region
    scale_x, scale_y = side / w, side / h
    matrix = np.array([[scale_x, 0, -x * scale_x - 0.5], [0, scale_y, -y * scale_y - 0.5]], dtype=np.float64)
    return cv2.warpAffine(image, matrix, (side, side), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


class MfnetWeighting:
    """``(rgb, thermal, region, grid_shape) -> (w_G, W_L)`` with a frozen MFNet on ``patch`` x ``patch`` crops.

    The paper feeds 200 x 200 patches; a smaller patch keeps the per-frame cost low on a CPU and is what the
    shipped heads were trained with when their configuration says so.
    """

    def __init__(self, net: MFNet, patch: int = 128):
        self.net = net
        self.patch = patch

    def __call__(self, rgb: np.ndarray, thermal: np.ndarray, region: np.ndarray,
                 grid_shape: tuple[int, int]) -> tuple[float, np.ndarray]:
        p_rgb = crop_resized(rgb, region, self.patch)
        p_t = crop_resized(thermal, region, self.patch)
        with torch.no_grad():
            w_g, w_l, _ = self.net.weights(to_tensor(p_rgb), to_tensor(p_t), tuple(grid_shape))
        return float(w_g.reshape(-1)[0]), w_l.reshape(grid_shape).numpy().astype(np.float64)
