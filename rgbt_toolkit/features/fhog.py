"""Felzenszwalb HOG (fHOG), 31 channels per cell, vectorised over a batch of patches.

Channels (Felzenszwalb et al., PAMI 2010, as in Piotr Dollar's ``fhog`` used by ECO): 18 contrast-sensitive
orientations, 9 contrast-insensitive orientations, each normalised by the four 2x2-cell block energies around the cell
and clipped at 0.2, plus 4 texture channels (the summed clipped energies per block). Gradients are central differences
on the colour channel with the largest magnitude; votes are interpolated linearly in orientation and bilinearly in
space (each pixel feeds the 2x2 nearest cell centres).
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

from rgbt_toolkit.features.base import BlockSpec, check_patches

N_ORIENT = 18
CLIP = 0.2
_EPS = 1e-4


def _gradients(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel magnitude and orientation in [0, 2pi); colour patches use the channel of largest magnitude.

    Central differences ``(I[x+1] - I[x-1]) / 2`` (OpenCV's 1x3 Sobel, reflected border), one patch at a time: the
    per-patch OpenCV calls are about 4x faster than the equivalent batched numpy slicing (measured on 7 x 200^2 x 3).
    """
    s, h, w = p.shape[:3]
    gxs = np.empty((s, h, w), np.float32)
    gys = np.empty((s, h, w), np.float32)
    for i in range(s):
        gx = cv2.Sobel(p[i], cv2.CV_32F, 1, 0, ksize=1, scale=0.5)
        gy = cv2.Sobel(p[i], cv2.CV_32F, 0, 1, ksize=1, scale=0.5)
        if p.ndim == 4:
            gx, gy = cv2.split(gx), cv2.split(gy)
            m = [cv2.magnitude(a, b) for a, b in zip(gx, gy)]
            first = m[0] >= m[1]
            m01 = np.where(first, m[0], m[1])
            third = m[2] > m01
            gx = np.where(third, gx[2], np.where(first, gx[0], gx[1]))
            gy = np.where(third, gy[2], np.where(first, gy[0], gy[1]))
        gxs[i], gys[i] = gx, gy
    mag, theta = cv2.cartToPolar(gxs.reshape(-1, w), gys.reshape(-1, w))
    return mag.reshape(s, h, w), theta.reshape(s, h, w)


@lru_cache(maxsize=8)
def _vote_layout(s: int, h: int, w: int, cell: int):
    """Index bases and weights of the vertical cell interpolation, fixed for a patch batch shape."""
    u = (np.arange(h) + 0.5) / cell - 0.5
    c0 = np.floor(u).astype(np.int64)
    fy = (u - c0).astype(np.float32)
    ny = h // cell
    lo, hi = np.clip(c0, 0, ny - 1), np.clip(c0 + 1, 0, ny - 1)
    base = (np.arange(s)[:, None, None] * ny) * (w * N_ORIENT) + np.arange(w)[None, None, :] * N_ORIENT
    base_lo = (base + (lo * (w * N_ORIENT))[None, :, None]).ravel()
    base_hi = (base + (hi * (w * N_ORIENT))[None, :, None]).ravel()
    ux = (np.arange(cell) + 0.5) / cell - 0.5
    fx = (ux - np.floor(ux)).astype(np.float32)  # upper-centre weight of each offset within a cell
    return base_lo, base_hi, fy, fx


def orientation_histograms(patches: np.ndarray, cell: int = 4) -> np.ndarray:
    """18-bin gradient histograms per cell, ``(S, H/cell, W/cell, 18)`` float32.

    Votes are split linearly between the two nearest orientation bins and bilinearly between the 2x2 nearest cell
    centres (clamped at the border). Vertical and orientation interpolation are one weighted ``bincount``; the
    horizontal one uses the fact that the weights depend only on the offset inside a cell.
    """
    mag, theta = _gradients(patches)
    s, h, w = mag.shape
    ny, nx = h // cell, w // cell
    base_lo, base_hi, fy, fxo = _vote_layout(s, h, w, cell)
    b = theta.ravel() * (N_ORIENT / (2 * np.pi))
    b0f = np.floor(b)
    fo = b - b0f
    b0 = b0f.astype(np.int64) % N_ORIENT
    b1 = b0 + 1
    b1[b1 == N_ORIENT] = 0
    m_hi = (mag * fy[None, :, None]).ravel()
    m_lo = mag.ravel() - m_hi
    n = b0.size
    idx = np.empty(4 * n, np.int64)
    wts = np.empty(4 * n, np.float32)
    np.add(base_lo, b0, out=idx[:n])
    np.add(base_lo, b1, out=idx[n : 2 * n])
    np.add(base_hi, b0, out=idx[2 * n : 3 * n])
    np.add(base_hi, b1, out=idx[3 * n :])
    np.multiply(m_lo, 1 - fo, out=wts[:n])
    np.multiply(m_lo, fo, out=wts[n : 2 * n])
    np.multiply(m_hi, 1 - fo, out=wts[2 * n : 3 * n])
    np.multiply(m_hi, fo, out=wts[3 * n :])
    acc = np.bincount(idx, wts, minlength=s * ny * w * N_ORIENT).astype(np.float32)
    acc = acc.reshape(s, ny, nx, cell, N_ORIENT)
    # Horizontal: offset o of cell c votes f_o to the upper centre and 1 - f_o to the lower one; the lower centre is
    # the previous cell for the first half of the cell, the upper centre is the next cell for the second half.
    half = cell // 2
    first, second = acc[:, :, :, :half], acc[:, :, :, half:]
    up_first = np.einsum("syxob,o->syxb", first, fxo[:half])
    down_first = np.einsum("syxob,o->syxb", first, 1 - fxo[:half])
    down_second = np.einsum("syxob,o->syxb", second, 1 - fxo[half:])
    up_second = np.einsum("syxob,o->syxb", second, fxo[half:])
    out = up_first + down_second
    out[:, :, :-1] += down_first[:, :, 1:]
    out[:, :, 0] += down_first[:, :, 0]
    out[:, :, 1:] += up_second[:, :, :-1]
    out[:, :, -1] += up_second[:, :, -1]
    return out


def fhog_from_histograms(hist: np.ndarray) -> np.ndarray:
    """Normalise and truncate 18-bin cell histograms into the 31 fHOG channels."""
    insens = hist[..., :9] + hist[..., 9:]
    energy = np.sum(insens * insens, axis=-1)
    e = np.pad(energy, ((0, 0), (1, 1), (1, 1)), mode="edge")
    # block (2x2 cells) energies at the four corners of each cell
    blocks = e[:, :-1, :-1] + e[:, 1:, :-1] + e[:, :-1, 1:] + e[:, 1:, 1:]
    norms = [1.0 / np.sqrt(blocks[:, dy : dy + hist.shape[1], dx : dx + hist.shape[2]] + _EPS)
             for dy in (0, 1) for dx in (0, 1)]
    sens = np.zeros_like(hist)
    ins = np.zeros_like(insens)
    texture = []
    for n in norms:
        hs = np.minimum(hist * n[..., None], CLIP)
        sens += hs
        ins += np.minimum(insens * n[..., None], CLIP)
        texture.append(0.2357 * hs.sum(axis=-1))
    return np.concatenate([0.5 * sens, 0.5 * ins, np.stack(texture, axis=-1)], axis=-1).astype(np.float32)


class FHog:
    """fHOG feature block (31 channels at ``cell`` pixels, compressed to ``compressed_dim`` by the tracker)."""

    def __init__(self, cell: int = 4, compressed_dim: int = 10) -> None:
        self.cell = cell
        self.blocks = (BlockSpec("fhog", cell, 31, compressed_dim),)

    def compute(self, patches: np.ndarray) -> list[np.ndarray]:
        """``(S, P, P[, 3])`` uint8 -> ``[(S, P/cell, P/cell, 31)]``."""
        patches = check_patches(patches, self.cell)
        return [fhog_from_histograms(orientation_histograms(patches, self.cell))]
