"""Feature mutual information (FMI, Haghighat et al. 2011) in its fast form (Haghighat & Razian 2014).

Every ``w x w`` window of the source and fused feature images is min-max normalised and read as a probability
vector (column-major, as MATLAB's ``x(:)``). The joint pdf of a source/fused pair interpolates between the product
of the marginals and the Frechet bound (upper bound for positive correlation, lower bound for negative), with
the weight chosen to reproduce the vectors' Pearson correlation. The window score is the normalised MI
``2 I / (H_a + H_f)``, averaged over both sources; FMI is the mean over all windows.

Vectorisation: the Frechet bound puts mass only on the "staircase" of the merged CDF breakpoints (at most
``2l - 1`` cells of the ``l x l`` table), so the joint entropy is the closed-form entropy of the product part plus
a correction on those cells; the merge is one sort of ``2l`` keys per window. A negative correlation is handled
as a positive one against the source's reversed pdf (the lower bound is the upper bound of the reversed order).
Sums that decide exact ties are accumulated in MATLAB's left-to-right order.
"""

from __future__ import annotations

import numpy as np
from scipy import fft as sp_fft

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.metrics._filters import as_float_image, check_same_shape
from rgbt_toolkit.metrics.wavelet import dwt2_dmey

FEATURES = ("wavelet", "dct", "edge", "gradient", "none")
_CHUNK = 32768  # windows per vectorised block (bounds memory at a few tens of MB)


def _rerange(x: np.ndarray) -> np.ndarray:
    hi, lo = x.max(), x.min()
    return np.ones_like(x) if hi == lo else (x - lo) / (hi - lo)


def _matlab_sobel_edge(image: np.ndarray) -> np.ndarray:
    """Binary edges as MATLAB's ``edge(I)`` (Sobel, threshold sqrt(4 * mean |g|^2), directional thinning)."""
    p = np.pad(image, 1, mode="edge")
    dx = p[:, 2:] - p[:, :-2]
    bx = np.abs(dx[:-2] + 2.0 * dx[1:-1] + dx[2:]) / 8.0
    dy = p[2:] - p[:-2]
    by = np.abs(dy[:, :-2] + 2.0 * dy[:, 1:-1] + dy[:, 2:]) / 8.0
    b = bx * bx + by * by
    cutoff = 4.0 * b.mean()
    left = np.hstack([b[:, :1], b[:, :-1]])
    right = np.hstack([b[:, 1:], b[:, -1:]])
    up = np.vstack([b[:1], b[:-1]])
    down = np.vstack([b[1:], b[-1:]])
    tol = np.finfo(np.float64).eps * 100.0
    horizontal = (bx >= by - tol) & (left <= b) & (right < b)
    vertical = (by >= bx - tol) & (up <= b) & (down < b)
    return ((b > cutoff) & (horizontal | vertical)).astype(np.float64)


def fmi_features(image: np.ndarray, feature: str) -> np.ndarray:
    """Feature image used by FMI: 'wavelet' (dmey dwt2 tiled [cA cH; cV cD], rescaled to [0, 1]), 'dct' (orthonormal
    2-D DCT), 'edge' (MATLAB Sobel edge map), 'gradient' (MATLAB ``gradient`` x-component) or 'none' (pixels)."""
    x = as_float_image(image, "image")
    if feature == "wavelet":
        ca, ch, cv, cd = dwt2_dmey(x)
        return _rerange(np.block([[ca, ch], [cv, cd]]))
    if feature == "dct":
        return sp_fft.dctn(x, norm="ortho")
    if feature == "edge":
        return _matlab_sobel_edge(x)
    if feature == "gradient":
        return np.gradient(x, axis=1)
    if feature == "none":
        return x
    raise InputError(f"unknown FMI feature {feature!r}; choose one of {', '.join(FEATURES)}")


def _windows(feat: np.ndarray, w: int, rows: slice) -> np.ndarray:
    """(n_windows, w*w) matrix of the windows whose top rows are in ``rows``, column-major inside each window."""
    width = feat.shape[1] - w + 1
    block = feat[rows.start : rows.stop + w - 1]
    height = block.shape[0] - w + 1
    cols = [block[r : r + height, c : c + width].ravel() for c in range(w) for r in range(w)]
    return np.stack(cols, axis=1)


def _seqsum(x: np.ndarray) -> np.ndarray:
    """Left-to-right sum over the last axis (MATLAB's order for short vectors)."""
    total = x[:, 0].copy()
    for k in range(1, x.shape[1]):
        total += x[:, k]
    return total


def _normalise(win: np.ndarray) -> np.ndarray:
    hi, lo = win.max(axis=1, keepdims=True), win.min(axis=1, keepdims=True)
    flat = (hi == lo)[:, 0]
    out = (win - lo) / np.where(hi == lo, 1.0, hi - lo)
    out[flat] = 1.0
    return out


def _pdf(norm: np.ndarray, w: int) -> np.ndarray:
    col_sums = [_seqsum(norm[:, c * w : (c + 1) * w]) for c in range(w)]  # MATLAB sum(sum(x))
    total = col_sums[0]
    for s in col_sums[1:]:
        total = total + s
    return norm / total[:, None]


def _xlog2x(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(log2 p with 0 where p == 0, p * log2 p)."""
    logp = np.log2(np.where(p > 0, p, 1.0))
    return logp, p * logp


def _pair_fmi(a_pdf, a_log, f_pdf, f_log, f_h, f_sd, f_cdf, l: int) -> np.ndarray:
    """Normalised MI of each window for one source/fused pair (windows where the raw patches differ)."""
    idx = np.arange(1, l + 1, dtype=np.float64)
    mean_a = _seqsum(a_pdf) / l
    mean_f = _seqsum(f_pdf) / l
    ta, tf = a_pdf - mean_a[:, None], f_pdf - mean_f[:, None]
    num = _seqsum(ta * tf)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.where(num == 0, 0.0, num / np.sqrt(_seqsum(ta * ta) * _seqsum(tf * tf)))
    c = np.nan_to_num(c)
    e_a = _seqsum(a_pdf * idx)
    a_sd = np.sqrt(np.maximum(_seqsum(a_pdf * idx * idx) - e_a * e_a, 0.0))
    # negative correlation: use the reversed source pdf, for which the lower Frechet bound is the upper one
    neg = c < 0
    a_eff = np.where(neg[:, None], a_pdf[:, ::-1], a_pdf)
    a_log_eff = np.where(neg[:, None], a_log[:, ::-1], a_log)
    a_cdf = np.cumsum(a_eff, axis=1)
    c_eff = np.abs(c)
    # merge the two CDFs: sort 2l keys per window; the index rides in the low 5 mantissa bits
    n = a_pdf.shape[0]
    vals = np.concatenate([f_cdf, a_cdf], axis=1)
    keys = (vals.view(np.int64) & ~np.int64(31)) | np.arange(2 * l, dtype=np.int64)
    keys.sort(axis=1)
    order = keys & 31
    s = np.take_along_axis(vals, order, axis=1)
    is_f = order < l
    pos = np.arange(2 * l)
    f_before = np.cumsum(is_f, axis=1) - is_f
    a_before = pos - f_before
    other_after = l - np.where(is_f, a_before, f_before)
    sum_min = np.sum(s * other_after, axis=1)
    cov_up = sum_min - _seqsum(f_cdf) * _seqsum(a_cdf)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr_up = cov_up / (f_sd * a_sd)
        phi = np.where((c_eff == 0) | (a_sd == 0) | (f_sd == 0), 0.0, c_eff / corr_up)
    phi = np.nan_to_num(phi)
    q = 1.0 - phi
    # entropy of the product part over all l*l cells, in closed form
    s_f, s_a = _seqsum(f_pdf), _seqsum(a_eff)
    log_q = np.log2(np.where(q != 0, np.abs(q), 1.0))
    joint = np.where(q != 0, -q * (s_f * s_a * log_q + s_a * f_h + s_f * np.sum(a_eff * a_log_eff, axis=1)), 0.0)
    # correction on the staircase cells that carry Frechet mass
    mass = np.diff(s, axis=1, prepend=0.0)
    i_k = np.minimum(np.where(is_f, order, f_before), l - 1)
    j_k = np.minimum(np.where(is_f, a_before, order - l), l - 1)
    fi = np.take_along_axis(f_pdf, i_k, axis=1)
    aj = np.take_along_axis(a_eff, j_k, axis=1)
    prod = q[:, None] * fi * aj
    log_prod = log_q[:, None] + np.take_along_axis(f_log, i_k, axis=1) + np.take_along_axis(a_log_eff, j_k, axis=1)
    h_prod = np.where(prod != 0, -prod * log_prod, 0.0)
    cell = phi[:, None] * mass + prod
    h_cell = -cell * np.log2(np.where(cell != 0, np.abs(cell), 1.0))
    joint += np.sum(np.where(mass > 0, h_cell - h_prod, 0.0), axis=1)
    h_a = -np.sum(a_pdf * a_log, axis=1)
    mi = h_a + (-f_h) - joint
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(mi == 0, 0.0, 2.0 * mi / (h_a - f_h))
    return np.nan_to_num(out)


def fmi(
    a: np.ndarray, b: np.ndarray, f: np.ndarray, *, feature: str = "wavelet", window: int = 3
) -> float:
    """FMI of fused image ``f`` against sources ``a`` and ``b``.

    Parameters
    ----------
    a, b, f : ndarray
        2-D images of equal size (any scale; features are normalised per window).
    feature : str
        'wavelet' gives FMI_w as in the JMMAC/DenseFuse table; also 'dct', 'edge', 'gradient', 'none' (FMI_pixel).
    window : int
        Odd window side (3 in the published tables).

    Returns
    -------
    float
        1 when ``a``, ``b`` and ``f`` are identical.
    """
    check_same_shape(visible=a, infrared=b, fused=f)
    if window < 1 or window % 2 == 0:
        raise InputError(f"FMI window must be a positive odd size, got {window}")
    fa, fb, ff = (fmi_features(x, feature) for x in (a, b, f))
    return fmi_of_features(fa, fb, ff, window)


def fmi_of_features(fa: np.ndarray, fb: np.ndarray, ff: np.ndarray, window: int = 3) -> float:
    """FMI from precomputed feature images (see :func:`fmi_features`); the mean window score."""
    if min(ff.shape) < window:
        raise InputError(f"image too small for a {window}x{window} FMI window")
    l = window * window
    idx = np.arange(1, l + 1, dtype=np.float64)
    out_rows = ff.shape[0] - window + 1
    step = max(1, _CHUNK // (ff.shape[1] - window + 1))
    total = 0.0
    count = 0
    for start in range(0, out_rows, step):
        rows = slice(start, min(out_rows, start + step))
        wa, wb, wf = (_windows(x, window, rows) for x in (fa, fb, ff))
        eq_a = np.all(wa == wf, axis=1)
        f_norm = _normalise(wf)
        # MATLAB compares bSub with fSub after the A branch may have normalised fSub in place
        eq_b = np.where(eq_a, np.all(wb == wf, axis=1), np.all(wb == f_norm, axis=1))
        f_pdf = _pdf(f_norm, window)
        f_log, f_xlog = _xlog2x(f_pdf)
        f_h = np.sum(f_xlog, axis=1)  # = -H_f
        e_f = _seqsum(f_pdf * idx)
        f_sd = np.sqrt(np.maximum(_seqsum(f_pdf * idx * idx) - e_f * e_f, 0.0))
        f_cdf = np.cumsum(f_pdf, axis=1)
        scores = []
        for wsrc, eq in ((wa, eq_a), (wb, eq_b)):
            a_pdf = _pdf(_normalise(wsrc), window)
            a_log, _ = _xlog2x(a_pdf)
            pair = _pair_fmi(a_pdf, a_log, f_pdf, f_log, f_h, f_sd, f_cdf, l)
            scores.append(np.where(eq, 1.0, pair))
        total += float(np.sum((scores[0] + scores[1]) / 2.0))
        count += wf.shape[0]
    return total / count
