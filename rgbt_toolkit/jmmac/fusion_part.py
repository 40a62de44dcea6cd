"""MFNet as the pipeline's ``FusionWeighting`` part: crop the search region from both frames, return w_G and W_L."""

from __future__ import annotations

import cv2
import numpy as np


def crop_resized(image: np.ndarray, region: np.ndarray, side: int) -> np.ndarray:
    """The square ``region`` (x, y, w, h; may leave the frame) resampled to ``side`` x ``side``, borders replicated.

    ``region`` is in continuous image coordinates where pixel ``(r, c)`` is centred at ``(c, r)``; its edges map onto
    the outer edges of the patch's border pixels, so patch cell ``k`` of ``G`` covers the ``k``-th ``G``-th of it.
    """
    x, y, w, h = region
    scale_x, scale_y = side / w, side / h
    matrix = np.array([[scale_x, 0, -x * scale_x - 0.5], [0, scale_y, -y * scale_y - 0.5]], dtype=np.float64)
    return cv2.warpAffine(image, matrix, (side, side), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


class TorchPatchWeights:
    """A torch :class:`~rgbt_toolkit.fusion.model.MFNet` behind the ``patch_weights`` interface of
    :class:`~rgbt_toolkit.fusion.onnx_model.OnnxMfnet` (user ``.pt`` heads, training, reference runs)."""

    def __init__(self, net) -> None:
        self.net = net

    def patch_weights(self, rgb: np.ndarray, thermal: np.ndarray, grid: tuple[int, int]) -> tuple[float, np.ndarray]:
        import torch

        from rgbt_toolkit.fusion.model import to_tensor

        with torch.no_grad():
            w_g, w_l, _ = self.net.weights(to_tensor(rgb), to_tensor(thermal), tuple(grid))
        return float(w_g.reshape(-1)[0]), w_l.reshape(grid).numpy().astype(np.float64)


# Side of the square crops MFNet sees in the tracker (a multiple of the backbone's stride, 16). The paper feeds 200 x
# 200 px. Measured (docs/decisions.md, D14; shipped heads): 128 / 96 / 80 / 64 px gave 91.1 / 91.7 / 91.1 / 90.4
# mean MSR on the generated ablation (bench_jmmac.py, default preset, seeds 0-5) and +MF 93.3 / 93.6 / 93.4 on the
# fusion benchmark (bench_fusion_tracking.py); the two-patch ONNX call took 8.3 / 6.1 / 4.8 ms (one thread).
TRACKING_PATCH = 80


class MfnetWeighting:
    """``(rgb, thermal, region, grid_shape) -> (w_G, W_L)`` with a frozen MFNet on ``patch`` x ``patch`` crops.

    ``net`` is an :class:`~rgbt_toolkit.fusion.onnx_model.OnnxMfnet` (the default: no torch at run time) or a torch
    ``MFNet`` (wrapped). The search region is resampled to ``patch`` px (:data:`TRACKING_PATCH` by default, where
    the tracker's measured accuracy is unchanged and MFNet costs 40 % less than at 128 px).
    """

    def __init__(self, net, patch: int = TRACKING_PATCH):
        self.net = net if hasattr(net, "patch_weights") else TorchPatchWeights(net)
        self.patch = patch

    def __call__(self, rgb: np.ndarray, thermal: np.ndarray, region: np.ndarray,
                 grid_shape: tuple[int, int]) -> tuple[float, np.ndarray]:
        p_rgb = crop_resized(rgb, region, self.patch)
        p_t = crop_resized(thermal, region, self.patch)
        return self.net.patch_weights(p_rgb, p_t, tuple(grid_shape))
