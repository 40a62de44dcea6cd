"""FMI window scores for 3x3 windows with whole-array operations only (no sort, no gather, no fancy indexing).

The generic path in :mod:`rgbt_toolkit.metrics.feature_mi` merges the two CDFs of a window pair with a row sort and
gathers the cell probabilities; both are slow numpy calls. For 3x3 windows each CDF has 8 breakpoints below the
top, so the merge is a bitonic merge of 8 + 8 keys: 4 stages of element-wise min/max over ``(8, n)`` slices. The
source of each merged key rides in its lowest mantissa bit (keys are shifted to [1, 2], one exponent, so that
bit is one ulp = 2.2e-16 and no key is subnormal). The probability of the F (or A) interval holding each merged
segment is the next F breakpoint minus the previous one: a reversed running min minus a running max.

Every ``(rows, n)`` array lives in a :class:`Workspace` reused across chunks: fresh megabyte-sized arrays are
mapped and page-faulted by the allocator on every call, which cost more than the arithmetic.

Windows where the published algorithm takes a special branch (a flat window, a window equal to F's, a source
window that could equal F's normalised window) are scored by the exact generic path instead; on the others this
path agrees with the literal algorithm to about 1e-13 per window (summation order and the 2.2e-16 key
quantisation are the only differences).
"""

from __future__ import annotations

import numpy as np

_TINY = 1e-300
_L = 9  # window elements
_M = 8  # breakpoints below the top
_K = np.arange(1, _L + 1, dtype=np.float64)
_K2 = _K * _K
_SEGMENT_WEIGHT = (2 * _L - np.arange(2 * _M, dtype=np.float64))[:, None]  # 18 - k for merged segment k


class Workspace:
    """Named ``(rows, capacity)`` buffers; :meth:`get` returns the first ``n`` columns."""

    def __init__(self, capacity: int):
        self.capacity = capacity
        self._buffers: dict[str, np.ndarray] = {}

    def get(self, name: str, rows: int, n: int, dtype=np.float64) -> np.ndarray:
        buf = self._buffers.get(name)
        if buf is None:
            buf = self._buffers[name] = np.empty((rows, self.capacity), dtype)
        return buf[:, :n]


def _scan(op: np.ufunc, x: np.ndarray, out: np.ndarray, reverse: bool = False) -> np.ndarray:
    """Running ``op`` over the rows of ``x`` (``op.accumulate(x, axis=0)`` runs element by element down each
    column; a row at a time keeps every call a contiguous vector op). ``out`` may be ``x``."""
    rows = range(x.shape[0] - 1, -1, -1) if reverse else range(x.shape[0])
    prev = None
    for k in rows:
        if prev is None:
            if out is not x:
                out[k] = x[k]
        else:
            op(out[prev], x[k], out=out[k])
        prev = k
    return out


_INV_LN2 = 1.0 / np.log(2.0)


def _xlog2x_sum(x: np.ndarray, scratch: np.ndarray, nonnegative: bool = False) -> np.ndarray:
    """Sum over the first axis of ``x log2 |x|`` (0 for 0; MATLAB's real part for negative cells).

    Natural log (a little faster than ``log2`` in numpy), the sum rescaled by 1/ln 2.
    """
    if nonnegative:
        np.maximum(x, _TINY, out=scratch)
    else:
        np.abs(x, out=scratch)
        scratch += _TINY
    np.log(scratch, out=scratch)
    scratch *= x
    total = scratch.sum(axis=0)
    total *= _INV_LN2
    return total


def _xlog2x(x: np.ndarray) -> np.ndarray:
    return x * np.log2(np.abs(x) + _TINY)


def _set_low_bit(keys: np.ndarray, bit: int) -> None:
    bits = keys.view(np.int64)
    if bit:
        np.bitwise_or(bits, 1, out=bits)
    else:
        np.bitwise_and(bits, ~np.int64(1), out=bits)


class WindowStats:
    """Per-window pdf, CDF keys, entropy, index spread and centred pdf of one feature image (3x3 windows).

    ``win`` is the ``(9, n)`` element-major stack (rows in MATLAB's column-major window order); ``slot`` names
    this image's buffers in ``ws``.
    """

    def __init__(self, win: np.ndarray, source: bool, ws: Workspace, slot: str):
        n = win.shape[1]
        self.lo = lo = np.minimum.reduce(win)
        pdf = np.subtract(win, lo, out=ws.get(slot + "pdf", _L, n))
        total = pdf.sum(axis=0)
        self.flat = total == 0  # exactly flat: every element equals the minimum
        total[self.flat] = 1.0
        pdf /= total
        self.pdf = pdf
        self.pdf_sum = pdf.sum(axis=0)
        scratch = ws.get("stats_scratch", _L, n)
        self.entropy = -_xlog2x_sum(pdf, scratch)
        e1 = _K @ pdf
        self.sd = np.sqrt(np.maximum(_K2 @ pdf - e1 * e1, 0.0))
        self.centred = np.subtract(pdf, self.pdf_sum / _L, out=ws.get(slot + "centred", _L, n))
        np.multiply(self.centred, self.centred, out=scratch)
        self.centred_sq = scratch.sum(axis=0)
        cdf = _scan(np.add, pdf, scratch)
        self.top = cdf[_M].copy()
        self.cdf_sum = cdf.sum(axis=0)
        if source:  # keys descending (the second half of a bitonic sequence), low bit set; also for the reversed pdf
            self.keys = np.add(cdf[_M - 1 :: -1], 1.0, out=ws.get(slot + "keys", _M, n))
            _set_low_bit(self.keys, 1)
            # the reversed pdf's CDF is top - cdf[7 - k] below its top (equal to top), so its keys descend as
            # (top + 1) - cdf[0..7] and its CDF sums to 10 top - sum(cdf)
            rev_keys = np.subtract(self.top + 1.0, cdf[:_M], out=ws.get(slot + "rev_keys", _M, n))
            _set_low_bit(rev_keys, 1)
            self.rev_top = self.top
            self.rev_cdf_sum = 10.0 * self.top - self.cdf_sum
            self.rev_step = np.subtract(rev_keys, self.keys, out=rev_keys)  # exact: both on [1, 2]
        else:
            self.keys = np.add(cdf[:_M], 1.0, out=ws.get(slot + "keys", _M, n))
            _set_low_bit(self.keys, 0)


def _bitonic_merge(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Sort each column of ``x`` (16 rows: ascending 8, then descending 8) by a bitonic merge; ``y`` is scratch.
    Returns ``x`` (four stages ping-pong back to it)."""
    n = x.shape[1]
    src, dst = x, y
    for half in (8, 4, 2, 1):
        s4 = src.reshape(16 // (2 * half), 2, half, n)
        d4 = dst.reshape(16 // (2 * half), 2, half, n)
        np.minimum(s4[:, 0], s4[:, 1], out=d4[:, 0])
        np.maximum(s4[:, 0], s4[:, 1], out=d4[:, 1])
        src, dst = dst, src
    return src


def pair_scores(a: WindowStats, f: WindowStats, ws: Workspace) -> np.ndarray:
    """Normalised MI ``2 I / (H_a + H_f)`` of every window pair (flat and equal windows to be overwritten)."""
    n = f.pdf.shape[1]
    rows = 2 * _M
    s, t, u, v = (ws.get(name, rows, n) for name in ("pair_s", "pair_t", "pair_u", "pair_v"))
    bits = ws.get("pair_bits", rows, n, np.int64)
    np.multiply(a.centred, f.centred, out=t[:_L])
    num = t[:_L].sum(axis=0)
    den = np.sqrt(a.centred_sq * f.centred_sq)
    c = np.divide(num, den, out=np.zeros(n), where=(num != 0) & (den > 0))
    neg = c < 0
    s[:_M] = f.keys
    # keys + 1 * (rev_keys - keys) is rev_keys exactly (the difference of two keys on [1, 2] is exact)
    np.multiply(a.rev_step, neg, out=s[_M:])
    s[_M:] += a.keys
    a_top = np.where(neg, a.rev_top, a.top)
    a_cdf_sum = np.where(neg, a.rev_cdf_sum, a.cdf_sum)
    a_last = np.where(neg, a.pdf[0], a.pdf[_M])
    _bitonic_merge(s, t)
    np.bitwise_and(s.view(np.int64), 1, out=bits)
    is_a = t
    np.copyto(is_a, bits, casting="unsafe")
    s -= 1.0  # exact (Sterbenz): the merged breakpoints on [0, 1]
    mass = u
    mass[0] = s[0]
    np.subtract(s[1:], s[:-1], out=mass[1:])
    last_mass = np.maximum(np.minimum(f.top, a_top) - s[-1], 0.0)
    # layer cake: sum_ij min(F_i, A_j) = sum_k mass_k c_F c_A with c_F = 9 - #F before k = 18 - k - c_A and
    # c_A = 9 - #A before k, a count-down over the rows
    a_count = v
    a_count[0] = _L
    for k in range(1, rows):
        np.subtract(a_count[k - 1], is_a[k - 1], out=a_count[k])
    w = np.subtract(_SEGMENT_WEIGHT, a_count, out=ws.get("pair_w", rows, n))
    w *= a_count
    w *= mass
    sum_min = w.sum(axis=0) + last_mass
    cov_up = sum_min - f.cdf_sum * a_cdf_sum
    c_eff = np.abs(c)
    spread = f.sd * a.sd
    phi = np.divide(c_eff * spread, cov_up, out=np.zeros(n), where=(c_eff != 0) & (spread != 0) & (cov_up != 0))
    q = 1.0 - phi
    # probability of the F interval holding segment k: next F breakpoint at or after k minus the last one before
    is_f = np.subtract(1.0, is_a, out=w)
    f_only = np.multiply(s, is_f, out=v)
    prev = _scan(np.maximum, f_only, ws.get("pair_prev", rows, n))
    np.multiply(is_a, f.top, out=bits.view(np.float64))
    f_only += bits.view(np.float64)
    f_cell = _scan(np.minimum, f_only, f_only, reverse=True)
    f_cell[1:] -= prev[:-1]
    a_only = np.multiply(s, is_a, out=t)
    _scan(np.maximum, a_only, prev)
    is_f *= a_top
    a_only += is_f
    a_cell = _scan(np.minimum, a_only, a_only, reverse=True)
    a_cell[1:] -= prev[:-1]
    prod = f_cell
    prod *= a_cell
    prod *= q
    cell = np.multiply(mass, phi, out=mass)
    cell += prod
    # cells are negative only where q < 0 (phi > 1); those windows take |x| (MATLAB's real part of the log)
    correction = _xlog2x_sum(prod, a_cell, nonnegative=True)
    correction -= _xlog2x_sum(cell, s, nonnegative=True)
    negative = np.flatnonzero(q < 0)
    if negative.size:
        correction[negative] = _xlog2x_sum(prod[:, negative], prod[:, negative].copy())
        correction[negative] -= _xlog2x_sum(cell[:, negative], cell[:, negative].copy())
    last_prod = q * f.pdf[_M] * a_last
    last_cell = last_prod + phi * last_mass
    correction += _xlog2x(last_prod) - _xlog2x(last_cell)
    log_q = np.log2(np.abs(q) + _TINY)
    joint = q * (a.pdf_sum * f.entropy + f.pdf_sum * a.entropy - f.pdf_sum * a.pdf_sum * log_q)
    joint += correction
    h_sum = a.entropy + f.entropy
    mi = h_sum - joint
    return np.divide(2.0 * mi, h_sum, out=np.zeros(n), where=(mi != 0) & (h_sum != 0))
