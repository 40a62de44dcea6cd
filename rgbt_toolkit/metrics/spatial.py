"""Single-image and difference metrics: SD, SF, AG, EI, PSNR, RMSE, CC, SCD.

Formulas follow VIFB's MATLAB files where VIFB has the metric; the ``standard`` variants of PSNR and RMSE use the
textbook mean squared error. Images are 2-D on the 0-255 scale.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.metrics._filters import as_float_image, check_same_shape, sobel_xy


def standard_deviation(f: np.ndarray) -> float:
    """SD (VIFB's "Variance"): population standard deviation of F."""
    f = as_float_image(f, "fused")
    return float(np.sqrt(np.mean((f - f.mean()) ** 2)))


def spatial_frequency(f: np.ndarray) -> float:
    """SF = sqrt(RF^2 + CF^2), each the sum of squared neighbour differences over the pixel count.

    VIFB folds colour channels side by side into one wide image before calling this (see the conventions).
    """
    f = as_float_image(f, "fused")
    rf = np.sum(np.diff(f, axis=1) ** 2) / f.size
    cf = np.sum(np.diff(f, axis=0) ** 2) / f.size
    return float(np.sqrt(rf + cf))


def average_gradient(f: np.ndarray) -> float:
    """AG: mean of sqrt((dx^2 + dy^2) / 2) with MATLAB ``gradient`` (central inside, one-sided at borders).

    As in VIFB, the sum is divided by (rows - 1) * (cols - 1), not by the pixel count.
    """
    f = as_float_image(f, "fused")
    if f.shape[0] < 2 or f.shape[1] < 2:  # no gradient along a 1-pixel side, and a division by zero below
        raise InputError(f"AG needs images of at least 2x2 pixels, got {f.shape[0]}x{f.shape[1]}")
    dy, dx = np.gradient(f)
    s = np.sqrt((dx * dx + dy * dy) / 2.0)
    return float(s.sum() / ((f.shape[0] - 1) * (f.shape[1] - 1)))


def edge_intensity(f: np.ndarray) -> float:
    """EI: mean Sobel gradient magnitude with replicate padding (VIFB's ``imfilter(..., 'replicate')``)."""
    gx, gy = sobel_xy(as_float_image(f, "fused"), pad="replicate")
    return float(np.mean(np.sqrt(gx * gx + gy * gy)))


def _vifb_error(s: np.ndarray, f: np.ndarray) -> float:
    """VIFB's ``mse``: sqrt(sum of squared differences) / pixel count (not a mean square)."""
    return float(np.sqrt(np.sum((s - f) ** 2)) / f.size)


def _mse(s: np.ndarray, f: np.ndarray) -> float:
    return float(np.mean((s - f) ** 2))


def _three(a, b, f):
    check_same_shape(visible=a, infrared=b, fused=f)
    return as_float_image(a, "visible"), as_float_image(b, "infrared"), as_float_image(f, "fused")


def psnr_vifb(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """PSNR as VIFB computes it: 20 log10(255 / sqrt(e)), e the mean of VIFB's error of each source (~57-60)."""
    a, b, f = _three(a, b, f)
    e = (_vifb_error(a, f) + _vifb_error(b, f)) / 2.0
    return float(20.0 * np.log10(255.0 / np.sqrt(e)))


def rmse_vifb(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """RMSE as VIFB computes it: mean over sources of sqrt(sum of squared differences) / pixel count."""
    a, b, f = _three(a, b, f)
    return (_vifb_error(a, f) + _vifb_error(b, f)) / 2.0


def psnr(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """PSNR = 10 log10(255^2 / MSE), MSE the mean of MSE(A, F) and MSE(B, F)."""
    a, b, f = _three(a, b, f)
    mse = (_mse(a, f) + _mse(b, f)) / 2.0
    return float("inf") if mse == 0 else float(10.0 * np.log10(255.0**2 / mse))


def rmse(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """RMSE = sqrt of the mean of MSE(A, F) and MSE(B, F)."""
    a, b, f = _three(a, b, f)
    return float(np.sqrt((_mse(a, f) + _mse(b, f)) / 2.0))


def _corr2(x: np.ndarray, y: np.ndarray) -> float:
    """MATLAB ``corr2``: Pearson correlation of all pixels (nan when either image is constant)."""
    xc, yc = x - x.mean(), y - y.mean()
    denominator = np.sqrt(np.sum(xc * xc) * np.sum(yc * yc))
    return float(np.sum(xc * yc) / denominator) if denominator > 0 else float("nan")


def correlation_coefficient(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """CC: mean of corr2(A, F) and corr2(B, F)."""
    a, b, f = _three(a, b, f)
    return (_corr2(a, f) + _corr2(b, f)) / 2.0


def scd(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """SCD (Aslantas & Bendes 2015): corr2(F - B, A) + corr2(F - A, B), the sum of correlations of differences."""
    a, b, f = _three(a, b, f)
    return _corr2(f - b, a) + _corr2(f - a, b)
