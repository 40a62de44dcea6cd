"""Closed-form ridge regression with exact leave-one-out errors (pure numpy).

The regressor is fitted in its dual form: with ``n`` = 1000 samples and a few thousand feature dimensions the
``n x n`` Gram matrix is the smaller system. One eigendecomposition of it gives, for every candidate
regularisation weight, the fitted values and the exact leave-one-out residuals
``e_i = (y_i - yhat_i) / (1 - H_ii)`` (the hat-matrix identity), so the weight is chosen and the regressor judged
against the identity (predicting no change) without refitting.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.errors import InputError


@dataclass(frozen=True)
class RidgeModel:
    """``y = ((x - mean) / scale) @ weights + bias``, with the leave-one-out figures of the chosen fit."""

    mean: np.ndarray  # (d,)
    scale: np.ndarray  # (d,)
    weights: np.ndarray  # (d, k)
    bias: np.ndarray  # (k,)
    alpha: float  # the chosen regularisation weight (relative to the mean Gram eigenvalue)
    loo_error: float  # mean squared leave-one-out residual over samples and outputs
    identity_error: float  # mean squared target: the error of predicting no change

    def predict(self, x: np.ndarray) -> np.ndarray:
        """Predictions ``(n, k)`` for features ``(n, d)``."""
        return ((np.asarray(x, dtype=np.float64) - self.mean) / self.scale) @ self.weights + self.bias


def fit_ridge(x: np.ndarray, y: np.ndarray, alphas: tuple[float, ...] = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0),
              fixed_alpha: float | None = None) -> RidgeModel:
    """Fit ridge regression of ``y`` on standardised ``x``, choosing the weight by leave-one-out error.

    Parameters
    ----------
    x : numpy.ndarray
        ``(n, d)`` features.
    y : numpy.ndarray
        ``(n, k)`` targets.
    alphas : tuple of float
        Candidate weights, relative to the mean eigenvalue of the Gram matrix (so they do not depend on the feature
        count or magnitude).
    fixed_alpha : float, optional
        Use this relative weight instead of choosing one (the leave-one-out error is still reported).

    Returns
    -------
    RidgeModel
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if x.ndim != 2 or y.ndim != 2 or len(x) != len(y) or len(x) < 2:
        raise InputError(f"ridge needs x (n, d) and y (n, k) with the same n >= 2, got {x.shape} and {y.shape}")
    mean, scale = x.mean(axis=0), x.std(axis=0)
    scale = np.where(scale > 1e-6 * max(float(scale.max()), 1e-12), scale, 1.0)
    xs = (x - mean) / scale
    bias = y.mean(axis=0)
    yc = y - bias
    lam, u = np.linalg.eigh(xs @ xs.T)
    lam = np.clip(lam, 0.0, None)
    unit = max(float(lam.mean()), 1e-12)
    uty = u.T @ yc
    u2 = u * u
    best = None
    for a in (alphas if fixed_alpha is None else (fixed_alpha,)):
        shrink = lam / (lam + a * unit)
        fitted = u @ (shrink[:, None] * uty)
        hat = u2 @ shrink
        loo = (yc - fitted) / np.maximum(1.0 - hat, 1e-6)[:, None]
        err = float(np.mean(loo**2))
        if best is None or err < best[1]:
            best = (a, err)
    a, err = best
    coef = u @ (uty / (lam + a * unit)[:, None])  # dual coefficients (K + a I)^-1 yc
    weights = xs.T @ coef
    return RidgeModel(mean, scale, weights, bias, float(a), err, float(np.mean(y**2)))
