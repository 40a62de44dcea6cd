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
from rgbt_toolkit.metrics.fmi_fast import WindowStats, Workspace, pair_scores
from rgbt_toolkit.metrics.wavelet import dwt2_dmey

FEATURES = ("wavelet", "dct", "edge", "gradient", "none")
_CHUNK = 8192  # windows per vectorised block (bounds memory at a few tens of MB)


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


def _windows(feat: np.ndarray, w: int, rows: slice, ws: Workspace | None = None, name: str = "") -> np.ndarray:
    """(w*w, n_windows) stack of the windows whose top rows are in ``rows``; row k is window element k in
    MATLAB's column-major order (``x(:)``). Element-major rows keep every per-window step a contiguous vector op.
    With a workspace the stack is written into its buffer ``name`` (no fresh allocation per chunk)."""
    width = feat.shape[1] - w + 1
    block = feat[rows.start : rows.stop + w - 1]
    height = block.shape[0] - w + 1
    if ws is None:
        return np.stack([block[r : r + height, c : c + width].ravel() for c in range(w) for r in range(w)])
    out = ws.get(name, w * w, height * width)
    for c in range(w):
        for r in range(w):
            out[c * w + r].reshape(height, width)[...] = block[r : r + height, c : c + width]
    return out


def _seqsum(x: np.ndarray) -> np.ndarray:
    """Left-to-right sum over the first axis (MATLAB's order for short vectors; it decides exact ties)."""
    total = x[0].copy()
    for row in x[1:]:
        total += row
    return total


def _normalise(win: np.ndarray) -> np.ndarray:
    """Per-window min-max to [0, 1]; a constant window becomes ones (MATLAB's ``ones(2w+1)``)."""
    hi, lo = np.maximum.reduce(win), np.minimum.reduce(win)
    span = hi - lo
    flat = span == 0
    out = (win - lo) / np.where(flat, 1.0, span)
    out[:, flat] = 1.0
    return out


def _pdf(norm: np.ndarray, w: int) -> np.ndarray:
    """Window values over their sum, the sum taken as MATLAB's ``sum(sum(x))`` (columns, then their sums)."""
    total = _seqsum(norm[0:w])
    for c in range(1, w):
        total = total + _seqsum(norm[c * w : (c + 1) * w])
    return norm / total


def _cumsum_rows(x: np.ndarray) -> np.ndarray:
    out = np.empty_like(x)
    out[0] = x[0]
    for k in range(1, x.shape[0]):
        np.add(out[k - 1], x[k], out=out[k])
    return out


_TINY = 1e-300


def _xlog2x(x: np.ndarray) -> np.ndarray:
    """``x * log2|x|`` with 0 for x == 0 (MATLAB skips zero cells and keeps ``real()`` for negative ones)."""
    return x * np.log2(np.maximum(np.abs(x), _TINY))


class _FusedWindows:
    """Per-window quantities of the fused feature that both source pairs share."""

    def __init__(self, wf: np.ndarray, w: int):
        l = w * w
        self.norm = _normalise(wf)
        self.pdf = _pdf(self.norm, w)
        self.entropy = -np.sum(_xlog2x(self.pdf), axis=0)
        self.centred = self.pdf - _seqsum(self.pdf) / l
        self.centred_sq = _seqsum(self.centred * self.centred)
        self.sd = _index_sd(self.pdf)
        self.cdf = _cumsum_rows(self.pdf)
        self.pdf_t = np.ascontiguousarray(self.pdf.T)
        self.cdf_t = np.ascontiguousarray(self.cdf.T)


def _index_sd(pdf: np.ndarray) -> np.ndarray:
    """Standard deviation of the element index (1..l) under each window's pdf."""
    idx = np.arange(1, pdf.shape[0] + 1, dtype=np.float64)[:, None]
    e = _seqsum(pdf * idx)
    return np.sqrt(np.maximum(_seqsum(pdf * (idx * idx)) - e * e, 0.0))


def _pair_fmi(a_pdf: np.ndarray, fw: _FusedWindows) -> np.ndarray:
    """Normalised MI of each window for one source/fused pair (windows where the raw patches differ)."""
    l = a_pdf.shape[0]
    ta = a_pdf - _seqsum(a_pdf) / l
    num = _seqsum(ta * fw.centred)
    den = np.sqrt(_seqsum(ta * ta) * fw.centred_sq)
    c = np.divide(num, den, out=np.zeros_like(num), where=(num != 0) & (den > 0))
    a_sd = _index_sd(a_pdf)
    a_entropy = -np.sum(_xlog2x(a_pdf), axis=0)
    # negative correlation: use the reversed source pdf, for which the lower Frechet bound is the upper one
    neg = c < 0
    a_eff = a_pdf.copy()
    a_eff[:, neg] = a_pdf[::-1, neg]
    a_cdf = _cumsum_rows(a_eff)
    c_eff = np.abs(c)
    # Merge the two CDFs. Both last breakpoints are 1 (up to rounding), so only the first l - 1 of each are
    # sorted; everything above the largest of them is one final segment in cell (l - 1, l - 1). One sort of
    # 2(l - 1) keys per window, the element index riding in the low mantissa bits.
    m = l - 1
    n = a_pdf.shape[1]
    vals = np.empty((n, 2 * m))
    vals[:, :m] = fw.cdf_t[:, :m]
    vals[:, m:] = a_cdf[:m].T
    mask = np.int64((1 << (2 * m - 1).bit_length()) - 1)  # 4 bits for 3x3 windows
    keys = vals.view(np.int64)
    keys &= ~mask
    keys |= np.arange(2 * m, dtype=np.int64)
    keys.sort(axis=1)
    order = keys & mask
    keys &= ~mask
    s = vals  # the merged breakpoints (to 2^-48 relative for 3x3), sorted in place through ``keys``
    # F breakpoints before each merged position: an F element's own index, or position - index for an A element
    pos = np.arange(2 * m, dtype=np.int64)
    is_a = order >= m
    f_before = order + is_a * (pos + m - 2 * order)
    a_before = pos - f_before
    flat_s = s.ravel()
    mass = np.empty_like(s)
    flat_mass = mass.ravel()
    np.subtract(flat_s[1:], flat_s[:-1], out=flat_mass[1:])  # contiguous; row starts fixed below
    mass[:, 0] = s[:, 0]
    np.maximum(mass, 0.0, out=mass)  # truncated keys can leave -1e-15 "masses"
    last_mass = np.maximum(np.minimum(fw.cdf[m], a_cdf[m]) - s[:, -1], 0.0)
    ones = np.ones(2 * m)
    # sum_ij min(F_i, A_j) by the layer-cake formula: each segment counts the F's and A's at or above it
    sum_min = (mass * ((l - f_before) * (l - a_before))) @ ones + last_mass
    cov_up = sum_min - _seqsum(fw.cdf) * _seqsum(a_cdf)
    # phi = c / corr_up with corr_up = cov_up / (sd_f sd_a); 0 where c or either sd is 0 (MATLAB's branch)
    scale = fw.sd * a_sd
    phi = np.divide(c_eff * scale, cov_up, out=np.zeros_like(c_eff), where=(c_eff != 0) & (scale != 0) & (cov_up != 0))
    q = 1.0 - phi
    # entropy of the product part q * f_i * a_j over all l*l cells, in closed form
    s_f, s_a = _seqsum(fw.pdf), _seqsum(a_eff)
    log_q = np.log2(np.maximum(np.abs(q), _TINY))
    joint = np.where(q != 0, q * (s_a * fw.entropy + s_f * a_entropy - s_f * s_a * log_q), 0.0)
    # correction on the staircase cells carrying Frechet mass: segment k lies in cell (f_before_k, a_before_k)
    base = (np.arange(n, dtype=np.int64) * l)[:, None]
    flat_i = f_before + base
    flat_j = a_before + base
    prod = fw.pdf_t.ravel().take(flat_i)
    prod *= np.ascontiguousarray(a_eff.T).ravel().take(flat_j)
    prod *= q[:, None]
    cell = mass
    cell *= phi[:, None]
    cell += prod  # equals prod exactly where the segment is empty
    last_prod = q * fw.pdf[m] * a_eff[m]
    last_cell = phi * last_mass + last_prod
    # x log2 x on every cell; rows with phi > 1 have negative cells and take MATLAB's real(log) on |x| instead
    with np.errstate(invalid="ignore"):
        correction = (prod * np.log2(np.maximum(prod, _TINY)) - cell * np.log2(np.maximum(cell, _TINY))) @ ones
    negative = np.flatnonzero(q < 0)
    if negative.size:
        correction[negative] = (_xlog2x(prod[negative]) - _xlog2x(cell[negative])) @ ones
    joint += correction + _xlog2x(last_prod) - _xlog2x(last_cell)
    mi = a_entropy + fw.entropy - joint
    h_sum = a_entropy + fw.entropy
    return np.divide(2.0 * mi, h_sum, out=np.zeros_like(mi), where=(mi != 0) & (h_sum != 0))


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
    if window < 3 or window % 2 == 0:
        raise InputError(f"FMI window must be an odd size of at least 3, got {window}")
    fa, fb, ff = (fmi_features(x, feature) for x in (a, b, f))
    return fmi_of_features(fa, fb, ff, window)


def fmi_of_features(fa: np.ndarray, fb: np.ndarray, ff: np.ndarray, window: int = 3) -> float:
    """FMI from precomputed feature images (see :func:`fmi_features`); the mean window score."""
    if window < 3 or window % 2 == 0:
        raise InputError(f"FMI window must be an odd size of at least 3, got {window}")
    if min(ff.shape) < window:
        raise InputError(f"image too small for a {window}x{window} FMI window")
    out_rows = ff.shape[0] - window + 1
    step = max(1, _CHUNK // (ff.shape[1] - window + 1))
    total = 0.0
    count = 0
    ws = Workspace(step * (ff.shape[1] - window + 1))
    for start in range(0, out_rows, step):
        rows = slice(start, min(out_rows, start + step))
        wa, wb, wf = (_windows(x, window, rows, ws, name) for x, name in ((fa, "wa"), (fb, "wb"), (ff, "wf")))
        score = _fast_scores(wa, wb, wf, ws) if window == 3 else _exact_scores(wa, wb, wf, window)
        total += float(np.sum(score))
        count += wf.shape[1]
    return total / count


def _exact_scores(wa: np.ndarray, wb: np.ndarray, wf: np.ndarray, window: int) -> np.ndarray:
    """Window scores ``(fmi_AF + fmi_BF) / 2`` by the generic path, with every branch of the published code."""
    eq_a = np.all(wa == wf, axis=0)
    fw = _FusedWindows(wf, window)
    # MATLAB compares bSub with fSub after the A branch may have normalised fSub in place
    eq_b = np.where(eq_a, np.all(wb == wf, axis=0), np.all(wb == fw.norm, axis=0))
    score = np.zeros(wf.shape[1])
    for wsrc, eq in ((wa, eq_a), (wb, eq_b)):
        pair = _pair_fmi(_pdf(_normalise(wsrc), window), fw)
        score += np.where(eq, 1.0, pair)
    return score / 2.0


def _fast_scores(wa: np.ndarray, wb: np.ndarray, wf: np.ndarray, ws: Workspace) -> np.ndarray:
    """3x3 windows: the whole-array path of :mod:`fmi_fast`, special windows re-scored by :func:`_exact_scores`."""
    with np.errstate(all="ignore"):
        sa, sb, sf = WindowStats(wa, True, ws, "a"), WindowStats(wb, True, ws, "b"), WindowStats(wf, False, ws, "f")
        score = pair_scores(sa, sf, ws)
        score += pair_scores(sb, sf, ws)
        score /= 2.0
    special = sa.flat | sb.flat | sf.flat | np.all(wa == wf, axis=0)
    # B is compared with F's normalised window when A differs from F: possible only where B's minimum is 0
    maybe = np.flatnonzero((sb.lo == 0) & ~special)
    if maybe.size:
        special[maybe[np.all(wb[:, maybe] == _normalise(wf[:, maybe]), axis=0)]] = True
    idx = np.flatnonzero(special)
    if idx.size:
        score[idx] = _exact_scores(wa[:, idx], wb[:, idx], wf[:, idx], 3)
    return score
