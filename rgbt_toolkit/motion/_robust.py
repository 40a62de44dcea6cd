"""Robust fitting of 2-D transforms to point matches with MSAC (Torr and Zisserman), vectorised over hypotheses.

OpenCV offers MSAC scoring (``cv2.UsacParams``) only for the affine and projective estimators; its translation and
similarity estimators are plain RANSAC. Both of these models have tiny closed-form minimal solvers (one and two
matches), so they are fitted here: all hypotheses are scored at once as a matrix of truncated squared residuals,
then the best one is re-fitted by least squares on its inliers, as the authors' RANSAC toolbox does with
``reestimate = true``.
"""

from __future__ import annotations

import cv2
import numpy as np


def msac_cost(residual_sq: np.ndarray, threshold_px: float) -> np.ndarray:
    """MSAC cost per hypothesis: sum over matches of ``min(e^2, T^2)`` (last axis summed)."""
    return np.minimum(residual_sq, threshold_px**2).sum(axis=-1)


def _translation_residuals(src: np.ndarray, dst: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Squared transfer errors, shape (hypotheses, matches), for translations ``t`` (hypotheses, 2)."""
    diff = dst[None, :, :] - src[None, :, :] - t[:, None, :]
    return (diff**2).sum(axis=-1)


def fit_translation(
    src: np.ndarray, dst: np.ndarray, threshold_px: float, iterations: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Translation by MSAC; every match is a hypothesis when there are at most ``max(iterations, 2000)`` of them."""
    n = len(src)
    if n <= max(iterations, 2000):
        picks = np.arange(n)
    else:
        picks = rng.choice(n, size=iterations, replace=True)
    hyp = dst[picks] - src[picks]
    best = hyp[np.argmin(msac_cost(_translation_residuals(src, dst, hyp), threshold_px))]
    inliers = _translation_residuals(src, dst, best[None])[0] <= threshold_px**2
    t = (dst[inliers] - src[inliers]).mean(axis=0)
    inliers = _translation_residuals(src, dst, t[None])[0] <= threshold_px**2
    matrix = np.eye(3)
    matrix[:2, 2] = t
    return matrix, inliers


def _similarity_from_pairs(
    ps: np.ndarray, qs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form similarities ``z -> a z + b`` (complex) through two matches each; ps, qs: (h, 2) complex."""
    dp = ps[:, 1] - ps[:, 0]
    a = (qs[:, 1] - qs[:, 0]) / np.where(np.abs(dp) > 1e-9, dp, 1e-9)
    b = qs[:, 0] - a * ps[:, 0]
    return a, b


def fit_similarity(
    src: np.ndarray, dst: np.ndarray, threshold_px: float, iterations: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Similarity (rotation, uniform scale, translation) by MSAC over ``iterations`` random match pairs."""
    zs = src[:, 0] + 1j * src[:, 1]
    zd = dst[:, 0] + 1j * dst[:, 1]
    n = len(src)
    first = rng.integers(0, n, size=iterations)
    second = (first + rng.integers(1, n, size=iterations)) % n  # never the same match twice
    pairs = np.stack([first, second], axis=1)
    a, b = _similarity_from_pairs(zs[pairs], zd[pairs])
    residual_sq = np.abs(a[:, None] * zs[None, :] + b[:, None] - zd[None, :]) ** 2
    k = int(np.argmin(msac_cost(residual_sq, threshold_px)))
    a_best, b_best = a[k], b[k]
    inliers = residual_sq[k] <= threshold_px**2
    for _ in range(2):  # least-squares re-fit on the consensus set, then its own consensus set
        if inliers.sum() < 2:
            break
        design = np.stack([zs[inliers], np.ones(int(inliers.sum()), dtype=complex)], axis=1)
        (a_best, b_best), *_ = np.linalg.lstsq(design, zd[inliers], rcond=None)
        inliers = np.abs(a_best * zs + b_best - zd) ** 2 <= threshold_px**2
    matrix = np.array(
        [[a_best.real, -a_best.imag, b_best.real], [a_best.imag, a_best.real, b_best.imag], [0.0, 0.0, 1.0]]
    )
    return matrix, inliers


def usac_params(threshold_px: float, iterations: int, confidence: float, seed: int) -> cv2.UsacParams:
    """OpenCV USAC with MSAC scoring, uniform sampling and inner local optimisation."""
    params = cv2.UsacParams()
    params.score = cv2.SCORE_METHOD_MSAC
    params.sampler = cv2.SAMPLING_UNIFORM
    params.threshold = float(threshold_px)
    params.maxIterations = int(iterations)
    params.confidence = float(confidence)
    params.loMethod = cv2.LOCAL_OPTIM_INNER_LO
    params.loIterations = 10
    params.loSampleSize = 14
    params.final_polisher = cv2.LSQ_POLISHER
    params.final_polisher_iterations = 3
    params.isParallel = False
    params.randomGeneratorState = int(seed)
    return params


def fit_opencv(
    model: str, src: np.ndarray, dst: np.ndarray, threshold_px: float, iterations: int, confidence: float, seed: int
) -> tuple[np.ndarray | None, np.ndarray]:
    """Affine or projective fit with OpenCV's USAC-MSAC; falls back to OpenCV's RANSAC if USAC fails or errors."""
    s = src.astype(np.float32)
    d = dst.astype(np.float32)
    matrix = mask = None
    try:
        params = usac_params(threshold_px, iterations, confidence, seed)
        if model == "affine":
            matrix, mask = cv2.estimateAffine2D(s, d, params)
        else:
            matrix, mask = cv2.findHomography(s, d, params)
    except cv2.error:
        matrix = None
    if matrix is None:
        conf = min(confidence, 0.9999)
        if model == "affine":
            matrix, mask = cv2.estimateAffine2D(
                s, d, method=cv2.RANSAC, ransacReprojThreshold=threshold_px, maxIters=iterations, confidence=conf
            )
        else:
            matrix, mask = cv2.findHomography(s, d, cv2.RANSAC, threshold_px, maxIters=iterations, confidence=conf)
    if matrix is None:
        return None, np.zeros(len(src), dtype=bool)
    if matrix.shape == (2, 3):
        matrix = np.vstack([matrix, [0.0, 0.0, 1.0]])
    return np.asarray(matrix, dtype=np.float64), np.asarray(mask).ravel().astype(bool)
