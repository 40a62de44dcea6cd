"""Sample geometry and the scale search: patch size, scale factors and their limits.

ECO (and the JMMAC code) search scale inside the translation filter: the sample is extracted at ``n_scales`` scales
``step^k``, ``k = -(n-1)/2 .. (n-1)/2``, and the scale whose refined peak is highest wins (7 scales, step 1.01).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SampleGeometry:
    """Geometry fixed at initialisation.

    Attributes
    ----------
    patch : int
        Patch side in pixels (the Fourier period ``T``), an odd multiple of the sample stride.
    grid : int
        Response grid side (odd); grid step is ``patch / grid`` patch pixels.
    base_target : (float, float)
        Target (h, w) in patch pixels.
    init_scale : float
        Image pixels per patch pixel on the first frame.
    min_scale, max_scale : float
        Limits of the scale factor (ECO: target at least ~5 px; at most the image size).
    """

    patch: int
    grid: int
    base_target: tuple[float, float]
    init_scale: float
    min_scale: float
    max_scale: float


def sample_geometry(target_hw: tuple[float, float], image_hw: tuple[int, int], *, search_area_scale: float,
                    min_area: float, max_area: float, sample_stride: int, response_stride: int,
                    scale_step: float) -> SampleGeometry:
    """Patch size, grid and scale limits for a target of ``target_hw`` pixels (ECO ``init_features`` / tracker setup).

    Only the target size and these settings enter, never the features, so two trackers given the same box and the
    same search settings share their patch and response grid.
    """
    th, tw = float(target_hw[0]), float(target_hw[1])
    search_area = th * tw * search_area_scale**2
    if search_area > max_area:
        scale = np.sqrt(search_area / max_area)
    elif search_area < min_area:
        scale = np.sqrt(search_area / min_area)
    else:
        scale = 1.0
    base = (th / scale, tw / scale)
    side = np.sqrt(base[0] * base[1]) * search_area_scale
    patch = int((1 + 2 * round(side / (2 * sample_stride))) * sample_stride)
    grid = patch // response_stride
    grid += 1 - grid % 2
    min_scale = scale_step ** np.ceil(np.log(max(5.0 / patch, 5.0 / min(base))) / np.log(scale_step))
    max_scale = scale_step ** np.floor(np.log(min(image_hw[0] / base[0], image_hw[1] / base[1])) / np.log(scale_step))
    max_scale = max(max_scale, scale)
    min_scale = min(min_scale, scale)
    return SampleGeometry(patch, grid, base, float(scale), float(min_scale), float(max_scale))


def scale_factors(n_scales: int, step: float) -> np.ndarray:
    """Relative scales ``step^k`` for ``k = -(n-1)/2 .. (n-1)/2``."""
    return step ** (np.arange(n_scales) - (n_scales - 1) // 2)
