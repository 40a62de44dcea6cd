"""From per-pixel (or coarse) feature maps of one patch to cell maps at several nearby scales.

ECO extracts every feature once per scale. Here each feature is computed once per frame, on a single patch sampled at
the finest scale that covers the largest one, and the cell maps of every scale are read off it: a pixel-level map is
blurred with the 7-tap tent ``[1 2 3 4 3 2 1] / 16`` and sampled bilinearly at the cell centres, which at unit scale
is exactly the bilinear cell voting of HOG (a cell centre lies between pixels, so the bilinear read adds the
``[1 1] / 2`` that turns the tent into ``[1 3 5 7 7 5 3 1] / 32``). Coarse maps (CNN layers) are sampled bilinearly.
With the JMMAC scale step (1.01, 7 scales) the scales differ by at most 6%, so nothing is lost that matters, and the
feature cost no longer grows with the number of scales.
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.features.native import kernels as _kernels

_TENT = np.array([1, 2, 3, 4, 3, 2, 1], np.float32) / 16.0


def cell_centres(n: int, stride: int, patch: int, ratio: float, base: int) -> np.ndarray:
    """Base-patch pixel coordinates of the ``n`` cell centres of a ``patch``-pixel patch at ``ratio`` x the base scale.

    Cell ``i`` of a stride-``stride`` map is centred at patch pixel ``stride * i + (stride - 1) / 2``; the patch centre
    ``(patch - 1) / 2`` sits on the base patch centre ``(base - 1) / 2``.
    """
    local = stride * np.arange(n) + (stride - 1) / 2 - (patch - 1) / 2
    return (base - 1) / 2 + ratio * local


def _read_cells(kernel, fmap: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """``kernel`` (a compiled cell reader) on ``fmap`` (H, W, D) at map positions ``rows`` (S, n) x ``cols`` (S, m)."""
    u = np.ascontiguousarray(rows, dtype=np.float64)
    v = np.ascontiguousarray(cols, dtype=np.float64)
    if u.shape[0] != v.shape[0]:
        raise ValueError(f"row centres for {u.shape[0]} scales but column centres for {v.shape[0]}")
    fmap = np.ascontiguousarray(fmap, dtype=np.float32)
    h, w, d = fmap.shape
    out = np.empty((u.shape[0], u.shape[1], v.shape[1], d), np.float32)
    kernel(fmap, h, w, d, u, v, u.shape[0], u.shape[1], v.shape[1], out)
    return out


def sample_map(fmap: np.ndarray, map_stride: int, centres: np.ndarray, centres_x: np.ndarray | None = None
               ) -> np.ndarray:
    """Bilinear read of ``fmap`` (H, W, D) at base-pixel ``centres`` ``(S, n)`` -> ``(S, n, n, D)``.

    ``centres`` are used on both axes unless ``centres_x`` ``(S, m)`` gives the columns (then ``(S, n, m, D)``).
    Positions are clamped to the map. The loop is compiled (``_kernels.bilinear_cells``): only the ``n x n`` outputs
    are touched, in one pass and without the GIL.
    """
    centres = np.atleast_2d(centres)
    cx = centres if centres_x is None else np.atleast_2d(centres_x)
    offset = (map_stride - 1) / 2
    return _read_cells(_kernels.bilinear_cells, fmap, (centres - offset) / map_stride, (cx - offset) / map_stride)


def pixel_prefilter(fmap: np.ndarray) -> np.ndarray:
    """Tent blur of a pixel-level ``(H, W, D)`` float32 map (OpenCV handles any channel count)."""
    out = cv2.sepFilter2D(fmap, -1, _TENT, _TENT, borderType=cv2.BORDER_REPLICATE)
    return out.reshape(fmap.shape)


def tent_cells(fmap: np.ndarray, centres: np.ndarray, centres_x: np.ndarray | None = None) -> np.ndarray:
    """``sample_map(pixel_prefilter(fmap), 1, centres, centres_x)``, the blur evaluated only where it is read.

    One scale of stride-4 cells reads a quarter of the rows and columns, so this costs a third to a half of blurring
    the whole map (the same values to a float32 ulp or two; the sums run in another order). For several scales the
    reads cover the map several times over and the whole-map blur is cheaper.
    """
    centres = np.atleast_2d(centres)
    return _read_cells(_kernels.tent_cells, fmap, centres, centres if centres_x is None else np.atleast_2d(centres_x))


def cells_at_scales(fmap: np.ndarray, map_stride: int, stride: int, patch: int, ratios: np.ndarray,
                    base: int) -> np.ndarray:
    """Cell maps ``(S, n, n, D)`` at each ``ratio`` (scale / base scale) from one map of the base patch."""
    n = -(-patch // stride)
    ratios = np.atleast_1d(ratios)
    centres = np.stack([cell_centres(n, stride, patch, r, base) for r in ratios])
    if map_stride == 1:
        if len(ratios) == 1:
            return tent_cells(fmap, centres)
        fmap = pixel_prefilter(fmap)
    return sample_map(fmap, map_stride, centres)
