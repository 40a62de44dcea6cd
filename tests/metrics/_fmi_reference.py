"""A literal, loop-by-loop FMI (the published MATLAB algorithm) used only to check the vectorised one on crops."""

from __future__ import annotations

import numpy as np


def _norm(sub):
    hi, lo = sub.max(), sub.min()
    return np.ones_like(sub) if hi == lo else (sub - lo) / (hi - lo)


def _seq(x):
    total = 0.0
    for v in x:
        total += v
    return total


def _entropy(p):
    nz = p[p != 0]
    return float(np.sum(-nz * np.log2(nz)))


def _pair(s_sub, f_sub):
    """Normalised MI of one window pair, straight from the definition (all l*l joint cells)."""
    l = s_sub.size
    sp = s_sub.ravel(order="F") / _seq(_seq(col) for col in s_sub.T)
    fp = f_sub.ravel(order="F") / _seq(_seq(col) for col in f_sub.T)
    sc, fc = np.cumsum(sp), np.cumsum(fp)
    # MATLAB/Octave accumulate these short sums left to right; it decides c for two flat windows
    st, ft = sp - _seq(sp) / l, fp - _seq(fp) / l
    num = _seq(st * ft)
    c = 0.0 if num == 0 else num / np.sqrt(_seq(st * st) * _seq(ft * ft))
    i = np.arange(1, l + 1)
    s_sd = np.sqrt(max(np.sum(i * i * sp) - np.sum(i * sp) ** 2, 0.0))
    f_sd = np.sqrt(max(np.sum(i * i * fp) - np.sum(i * fp) ** 2, 0.0))
    fc0, sc0 = np.r_[0.0, fc], np.r_[0.0, sc]
    if c >= 0:
        bound = lambda u, v: np.minimum(u, v)  # noqa: E731
    else:
        bound = lambda u, v: np.maximum(u + v - 1.0, 0.0)  # noqa: E731
    cov = np.sum(bound(fc[:, None], sc[None, :]) - fc[:, None] * sc[None, :])
    if (c == 0 and c >= 0) or s_sd == 0 or f_sd == 0:
        w = 0.0
    else:
        w = c / (cov / (f_sd * s_sd))
    cdf = bound(fc0[:, None], sc0[None, :])
    jb = cdf[1:, 1:] - cdf[:-1, 1:] - cdf[1:, :-1] + cdf[:-1, :-1]
    jp = w * jb + (1.0 - w) * fp[:, None] * sp[None, :]
    nz = jp[jp != 0]
    joint = float(np.sum(-nz * np.log2(np.abs(nz))))
    hs, hf = _entropy(sp), _entropy(fp)
    mi = hs + hf - joint
    return 0.0 if mi == 0 else 2.0 * mi / (hs + hf)


def fmi_reference(fa, fb, ff, w=3):
    """Mean window score over feature images ``fa``, ``fb``, ``ff``."""
    r = w // 2
    m, n = ff.shape
    scores = []
    for p in range(r, m - r):
        for q in range(r, n - r):
            a = fa[p - r : p + r + 1, q - r : q + r + 1]
            b = fb[p - r : p + r + 1, q - r : q + r + 1]
            f = ff[p - r : p + r + 1, q - r : q + r + 1]
            s_af = 1.0 if np.array_equal(a, f) else _pair(_norm(a), _norm(f))
            f_cmp = f if np.array_equal(a, f) else _norm(f)
            s_bf = 1.0 if np.array_equal(b, f_cmp) else _pair(_norm(b), _norm(f))
            scores.append((s_af + s_bf) / 2.0)
    return float(np.mean(scores))
