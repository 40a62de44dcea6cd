"""Cutting square sample patches out of a frame at several scales, and locating score peaks.

Coordinates: image pixel ``(row, col)`` has its centre at ``(row, col)``. A patch of side ``P`` sampled at scale ``a``
(image pixels per patch pixel) around ``(cy, cx)`` maps patch pixel ``(i, j)`` to image point
``(cy + (i - (P-1)/2) a, cx + (j - (P-1)/2) a)``; outside the frame the border is replicated (ECO does the same).
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.eco.fourier import evaluate_with_derivatives


def extract_patches(frame: np.ndarray, center: tuple[float, float], scales: np.ndarray, size: int) -> np.ndarray:
    """Sample ``len(scales)`` square patches of ``size`` pixels; returns ``(S, size, size[, 3])`` uint8.

    When the smallest scale shrinks the image by 2x or more, the frame is first reduced by that integer factor with
    area averaging (once for all scales), so the bilinear sampling does not alias.
    """
    scales = np.asarray(scales, dtype=np.float64)
    cy, cx = center
    factor = int(np.floor(scales.min()))
    src = frame
    if factor >= 2:
        h, w = frame.shape[:2]
        src = cv2.resize(frame, (max(1, w // factor), max(1, h // factor)), interpolation=cv2.INTER_AREA)
        cy, cx = (cy + 0.5) / factor - 0.5, (cx + 0.5) / factor - 0.5
        scales = scales / factor
    out = np.empty((len(scales), size, size) + frame.shape[2:], dtype=np.uint8)
    half = (size - 1) / 2
    for s, a in enumerate(scales):
        m = np.array([[a, 0.0, cx - half * a], [0.0, a, cy - half * a]])
        out[s] = cv2.warpAffine(src, m, (size, size), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                borderMode=cv2.BORDER_REPLICATE).reshape(out.shape[1:])
    return out


def grid_offsets(grid: int, period: float) -> np.ndarray:
    """Displacement (patch pixels) of each response-grid index: ``(i - (grid-1)/2) * period / grid``."""
    return (np.arange(grid) - (grid - 1) // 2) * (period / grid)


def refine_peaks(scores_half: np.ndarray, responses: np.ndarray, period: float, iterations: int):
    """Sub-grid peak of each scale's score by Newton's method on its Fourier series (ECO ``optimize_scores``).

    Parameters
    ----------
    scores_half : (S, Ny, Nxh) complex
        Score coefficients per scale.
    responses : (S, G, G) float
        The same scores sampled on the response grid (:func:`rgbt_toolkit.eco.fourier.sample_grid`).
    period : float
        Patch side in pixels.

    Returns
    -------
    ty, tx, value : (S,) arrays
        Peak displacement from the patch centre (patch pixels) and the score there.
    """
    s, g, _ = responses.shape
    flat = responses.reshape(s, -1).argmax(axis=1)
    iy, ix = np.unravel_index(flat, (g, g))
    offs = grid_offsets(g, period)
    ty, tx = offs[iy].astype(np.float64), offs[ix].astype(np.float64)
    start_val = responses.reshape(s, -1).max(axis=1).astype(np.float64)
    coef = scores_half.astype(np.complex128)
    step_limit = period / g  # Newton must not leave the grid cell it started in by much
    for _ in range(iterations):
        _, gy, gx, hyy, hxx, hxy = evaluate_with_derivatives(coef, ty, tx, period)
        det = hyy * hxx - hxy * hxy
        ok = (det > 0) & (hyy < 0)  # a maximum: negative definite Hessian
        dy = np.where(ok, (hxx * gy - hxy * gx) / np.where(ok, det, 1.0), 0.0)
        dx = np.where(ok, (hyy * gx - hxy * gy) / np.where(ok, det, 1.0), 0.0)
        ty = ty - np.clip(dy, -step_limit, step_limit)
        tx = tx - np.clip(dx, -step_limit, step_limit)
    value = evaluate_with_derivatives(coef, ty, tx, period)[0]
    worse = value < start_val  # keep the grid maximum if Newton did not improve on it
    ty = np.where(worse, offs[iy], ty)
    tx = np.where(worse, offs[ix], tx)
    value = np.where(worse, start_val, value)
    return ty, tx, value


def parabolic_peak(response: np.ndarray) -> tuple[float, float, float]:
    """Peak of a sampled map refined by a separable parabola through the maximum and its neighbours (grid units)."""
    g0, g1 = response.shape
    i, j = np.unravel_index(int(np.argmax(response)), response.shape)
    peak = float(response[i, j])

    def vertex(a: float, b: float, c: float) -> float:
        den = a - 2 * b + c
        return 0.0 if den >= 0 else float(np.clip(0.5 * (a - c) / den, -0.5, 0.5))

    di = vertex(response[i - 1, j], peak, response[i + 1, j]) if 0 < i < g0 - 1 else 0.0
    dj = vertex(response[i, j - 1], peak, response[i, j + 1]) if 0 < j < g1 - 1 else 0.0
    return i + di, j + dj, peak
