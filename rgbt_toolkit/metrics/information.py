"""Histogram metrics: entropy (EN), mutual information (MI) and cross entropy (CE).

All take images on the 0-255 scale (float or uint8). Histograms use 256 bins of ``floor(x)`` as the MATLAB codes
do (``X(floor(h)+1)``), so non-integer inputs are binned, not rejected.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.metrics._filters import as_float_image, check_same_shape


def _levels(image: np.ndarray, name: str) -> np.ndarray:
    """Integer grey levels 0..255 of an image on the 0-255 scale."""
    levels = np.floor(as_float_image(image, name)).astype(np.int64)
    if levels.min() < 0 or levels.max() > 255:
        raise InputError(f"{name}: values outside 0..255 (range {levels.min()}..{levels.max()}); scale to 8 bits")
    return levels


def _entropy_of_counts(counts: np.ndarray, log) -> float:
    p = counts[counts > 0] / counts.sum()
    return float(-np.sum(p * log(p)))


def entropy(image: np.ndarray) -> float:
    """EN: Shannon entropy in bits of the 256-bin grey-level histogram.

    Parameters
    ----------
    image : ndarray
        2-D image on the 0-255 scale.

    Returns
    -------
    float
        0 for a constant image, 8 for a flat histogram over all 256 levels.
    """
    counts = np.bincount(_levels(image, "image").ravel(), minlength=256)
    return _entropy_of_counts(counts.astype(np.float64), np.log2)


def round_half_away(x: np.ndarray) -> np.ndarray:
    """MATLAB ``round``/``int16`` for non-negative input: halves go up (numpy rounds halves to even)."""
    r = np.floor(x)
    return r + (x - r >= 0.5)


def _minmax_quantise(image: np.ndarray) -> np.ndarray:
    """VIFB's MI quantisation: min-max normalise to [0, 1] (zeros when constant), then ``int16(x * 255)``."""
    lo, hi = image.min(), image.max()
    if hi == lo:
        return np.zeros(image.shape, dtype=np.int64)
    return round_half_away((image - lo) / (hi - lo) * 255.0).astype(np.int64)


def mutual_information(a: np.ndarray, f: np.ndarray, *, normalise: bool = False, base: float = 2.0) -> float:
    """MI(A, F) from the 256x256 joint histogram.

    Parameters
    ----------
    a, f : ndarray
        2-D images of equal size on the 0-255 scale.
    normalise : bool
        ``True`` reproduces VIFB's ``mutinf``: each image is min-max stretched to 0..255 and rounded first.
        ``False`` bins the raw grey levels (Qu's definition on 8-bit images).
    base : float
        Logarithm base: 2 for bits, ``e`` for nats (VIFB).
    """
    check_same_shape(source=a, fused=f)
    if normalise:
        qa = _minmax_quantise(as_float_image(a, "source"))
        qf = _minmax_quantise(as_float_image(f, "fused"))
    else:
        qa, qf = _levels(a, "source"), _levels(f, "fused")
    joint = np.bincount((qa * 256 + qf).ravel(), minlength=256 * 256).astype(np.float64).reshape(256, 256)
    log = (lambda p: np.log(p) / np.log(base)) if base != 2.0 else np.log2
    h_a = _entropy_of_counts(joint.sum(axis=1), log)
    h_f = _entropy_of_counts(joint.sum(axis=0), log)
    h_af = _entropy_of_counts(joint.ravel(), log)
    return h_a + h_f - h_af


def fusion_mutual_information(a: np.ndarray, b: np.ndarray, f: np.ndarray, **kwargs) -> float:
    """MI = MI(A, F) + MI(B, F); keyword arguments go to :func:`mutual_information`."""
    return mutual_information(a, f, **kwargs) + mutual_information(b, f, **kwargs)


def paper_mutual_information(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """Compatibility mode for the JMMAC/DenseFuse table: that code's MI always equals ``2 * EN(F)``.

    Its joint-entropy helper saturates to zero, so the reported "MI" is the sum of the two marginal entropies of F.
    Offered only to reproduce published tables; it measures nothing about the sources.
    """
    check_same_shape(visible=a, infrared=b, fused=f)
    return 2.0 * entropy(f)


def cross_entropy(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """CE (VIFB): mean over sources of ``sum p_S log2(p_S / p_F)`` over levels present in both histograms."""
    check_same_shape(visible=a, infrared=b, fused=f)
    pf = np.bincount(_levels(f, "fused").ravel(), minlength=256) / f.size
    total = 0.0
    for source, name in ((a, "visible"), (b, "infrared")):
        ps = np.bincount(_levels(source, name).ravel(), minlength=256) / f.size
        both = (ps > 0) & (pf > 0)
        total += float(np.sum(ps[both] * np.log2(ps[both] / pf[both])))
    return total / 2.0
