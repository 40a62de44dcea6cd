"""The numpy definitions of the feature loops that rgbt_toolkit/features/_kernels.c compiles.

They were the library's own code until the loops moved to C; kept here as the second implementation the compiled
kernels are checked against (tests/features/test_kernels.py).
"""

from __future__ import annotations

import numpy as np

N_ORIENT = 18
CLIP = 0.2
_EPS = 1e-4


def bilinear_rows(pos: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    pos = np.clip(pos, 0, size - 1)
    i0 = np.floor(pos).astype(np.int64)
    i1 = np.minimum(i0 + 1, size - 1)
    return i0, i1, (pos - i0).astype(np.float32)[:, None]


def sample_map(fmap: np.ndarray, map_stride: int, centres: np.ndarray, centres_x: np.ndarray | None = None
               ) -> np.ndarray:
    """Bilinear read of ``fmap`` (H, W, D) at base-pixel ``centres`` ``(S, n)`` -> ``(S, n, n, D)``."""
    centres = np.atleast_2d(centres)
    h, w, d = fmap.shape
    flat = fmap.reshape(h * w, d)
    cx = centres if centres_x is None else np.atleast_2d(centres_x)
    u = (centres - (map_stride - 1) / 2) / map_stride
    v = (cx - (map_stride - 1) / 2) / map_stride
    ny, nx = u.shape[1], v.shape[1]
    out = np.empty((u.shape[0], ny, nx, d), np.float32)
    for k, (uk, vk) in enumerate(zip(u, v)):
        y0, y1, wy1 = bilinear_rows(uk, h)
        x0, x1, fx = bilinear_rows(vk, w)
        wx1 = fx.reshape(1, -1, 1)

        def read(rows, cols):
            return np.take(flat, (rows[:, None] * w + cols[None, :]).ravel(), axis=0).reshape(ny, nx, d)

        top = read(y0, x0) * (1 - wx1) + read(y0, x1) * wx1
        bot = read(y1, x0) * (1 - wx1) + read(y1, x1) * wx1
        out[k] = top * (1 - wy1)[:, :, None] + bot * wy1[:, :, None]
    return out


def strongest_gradient(gx: np.ndarray, gy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(H, W, 3)`` per-channel gradients -> the gradient of the channel with the largest squared magnitude."""
    gx, gy = np.moveaxis(gx, -1, 0), np.moveaxis(gy, -1, 0)
    m = [a * a + b * b for a, b in zip(gx, gy)]
    first = m[0] >= m[1]
    m01 = np.where(first, m[0], m[1])
    third = m[2] > m01
    return (np.where(third, gx[2], np.where(first, gx[0], gx[1])),
            np.where(third, gy[2], np.where(first, gy[0], gy[1])))


def orientation_votes(mag: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Per-pixel magnitude ``(H, W)`` split between the two nearest of 18 orientation bins -> ``(H, W, 18)``."""
    h, w = mag.shape
    b = theta.ravel() * (N_ORIENT / (2 * np.pi))
    b0f = np.floor(b)
    fo = b - b0f
    b0 = b0f.astype(np.int64)
    b0[b0 >= N_ORIENT] -= N_ORIENT
    b1 = b0 + 1
    b1[b1 == N_ORIENT] = 0
    m = mag.ravel()
    votes = np.zeros((h * w, N_ORIENT), np.float32)
    rows = np.arange(h * w)
    votes[rows, b0] = m * (1 - fo)
    votes[rows, b1] += m * fo
    return votes.reshape(h, w, N_ORIENT)


def fhog_from_histograms(hist: np.ndarray) -> np.ndarray:
    """Normalise and truncate 18-bin cell histograms ``(S, n, m, 18)`` into the 31 fHOG channels."""
    s, ny, nx, _ = hist.shape
    insens = hist[..., :9] + hist[..., 9:]
    energy = np.sum(insens * insens, axis=-1)
    e = np.pad(energy, ((0, 0), (1, 1), (1, 1)), mode="edge")
    blocks = e[:, :-1, :-1] + e[:, 1:, :-1] + e[:, :-1, 1:] + e[:, 1:, 1:]
    inv_norm = (1.0 / np.sqrt(blocks + _EPS)).astype(np.float32)
    out = np.empty((s, ny, nx, 31), np.float32)
    ones = np.ones(N_ORIENT, np.float32)
    clipped, clipped_ins = np.empty((ny, nx, N_ORIENT), np.float32), np.empty((ny, nx, 9), np.float32)
    sens, ins = np.empty_like(clipped), np.empty_like(clipped_ins)
    for i in range(s):
        for k, (dy, dx) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
            norm = inv_norm[i, dy : dy + ny, dx : dx + nx, None]
            np.minimum(np.multiply(hist[i], norm, out=clipped), CLIP, out=clipped)
            np.minimum(np.multiply(insens[i], norm, out=clipped_ins), CLIP, out=clipped_ins)
            out[i, :, :, 27 + k] = (clipped.reshape(-1, N_ORIENT) @ ones).reshape(ny, nx)
            if k == 0:
                sens[...], ins[...] = clipped, clipped_ins
            else:
                sens += clipped
                ins += clipped_ins
        np.multiply(sens, 0.5, out=out[i, :, :, :N_ORIENT])
        np.multiply(ins, 0.5, out=out[i, :, :, N_ORIENT:27])
    out[..., 27:] *= 0.2357
    return out
