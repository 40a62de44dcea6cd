"""Scale-normalised context patches and RoI-align pooling of backbone features (torch ``grid_sample``, no torchvision).

One backbone pass on a small patch around the target serves every box inside it: :func:`roi_align` bilinearly
samples each box's region of the feature map into a fixed grid (Mask R-CNN's RoI-align: several points per bin,
averaged), so 1000 training boxes cost one forward pass and a gather, and a per-frame prediction costs one pass on
a ~100 px patch.

Coordinates: image and patch pixels have their centres at integer coordinates; a box ``[x, y, w, h]`` covers the
continuous extent ``[x - 0.5, x + w - 0.5]`` (and likewise in y).
"""

from __future__ import annotations

import cv2
import numpy as np
import torch
import torch.nn.functional as F


def patch_transform(centre: np.ndarray, scale: float, size: int) -> np.ndarray:
    """2x3 affine taking image pixel coordinates to patch pixel coordinates (``centre`` lands mid-patch)."""
    c = (size - 1) / 2
    return np.array([[scale, 0.0, c - scale * centre[0]], [0.0, scale, c - scale * centre[1]]])


def crop_patch(image: np.ndarray, centre: np.ndarray, scale: float, size: int) -> np.ndarray:
    """A ``size x size`` patch of ``image`` around ``centre`` resampled by ``scale`` (patch px per image px).

    Pixels outside the image repeat the border, as trackers' samples do, so a target at the edge keeps its context.
    """
    return cv2.warpAffine(image, patch_transform(centre, scale, size), (size, size), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_REPLICATE)


def boxes_to_regions(boxes: np.ndarray, transform: np.ndarray, context: float = 1.0) -> np.ndarray:
    """Continuous extents ``(N, 4)`` as ``x0, y0, x1, y1`` in patch coordinates of boxes grown by ``context``."""
    boxes = np.atleast_2d(np.asarray(boxes, dtype=float))
    s, tx, ty = transform[0, 0], transform[0, 2], transform[1, 2]
    centre = boxes[:, :2] + (boxes[:, 2:] - 1) / 2
    half = boxes[:, 2:] * context / 2
    lo, hi = (centre - half) * s, (centre + half) * s
    return np.stack([lo[:, 0] + tx, lo[:, 1] + ty, hi[:, 0] + tx, hi[:, 1] + ty], axis=1)


def roi_align(features: torch.Tensor, regions: np.ndarray, stride: int, grid: int, points: int = 2) -> torch.Tensor:
    """Pool each region of a ``[1, C, Hf, Wf]`` feature map into ``grid x grid`` bins.

    Parameters
    ----------
    features : torch.Tensor
        Feature map of one patch; feature cell ``k`` covers patch pixels ``[k * stride, (k + 1) * stride)``.
    regions : numpy.ndarray
        ``(N, 4)`` continuous extents ``x0, y0, x1, y1`` in patch pixel coordinates.
    stride : int
        Patch pixels per feature cell.
    grid : int
        Bins per side.
    points : int
        Bilinear samples per bin and axis, averaged (2 as in Mask R-CNN).

    Returns
    -------
    torch.Tensor
        ``[N, C, grid, grid]``; samples beyond the map read zeros (the patch already carries image context).
    """
    n = len(regions)
    _, c, hf, wf = features.shape
    r = torch.as_tensor(regions, dtype=features.dtype)
    steps = (torch.arange(grid * points, dtype=features.dtype) + 0.5) / (grid * points)  # fractions inside the box
    # patch pixel-centre coordinate x -> edge coordinate x + 0.5 -> grid_sample's [-1, 1] over stride * Wf pixels
    xs = r[:, 0:1] + steps * (r[:, 2:3] - r[:, 0:1]) + 0.5
    ys = r[:, 1:2] + steps * (r[:, 3:4] - r[:, 1:2]) + 0.5
    gx = 2 * xs / (stride * wf) - 1
    gy = 2 * ys / (stride * hf) - 1
    m = grid * points
    sample = torch.stack([gx[:, None, :].expand(n, m, m), gy[:, :, None].expand(n, m, m)], dim=-1)
    out = F.grid_sample(features, sample.reshape(1, n * m, m, 2), mode="bilinear", padding_mode="zeros",
                        align_corners=False)  # [1, C, n * m, m]
    out = out.reshape(c, n, grid, points, grid, points).mean(dim=(3, 5))
    return out.permute(1, 0, 2, 3).contiguous()
