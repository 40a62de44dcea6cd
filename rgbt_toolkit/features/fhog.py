"""Felzenszwalb HOG (fHOG), 31 channels per cell, vectorised over a batch of patches.

Channels (Felzenszwalb et al., PAMI 2010, as in Piotr Dollar's ``fhog`` used by ECO): 18 contrast-sensitive
orientations, 9 contrast-insensitive orientations, each normalised by the four 2x2-cell block energies around the cell
and clipped at 0.2, plus 4 texture channels (the summed clipped energies per block). Gradients are central differences
on the colour channel with the largest magnitude; votes are interpolated linearly in orientation and bilinearly in
space (each pixel feeds the 2x2 nearest cell centres; done by :mod:`rgbt_toolkit.features.pooling`).
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.features.base import BlockSpec, compute

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
            # squared magnitudes in numpy: cv2.magnitude's last bit varies from call to call (OpenCV 5.1), and on
            # grey areas, where the channels tie, that flipped the chosen channel and made runs non-repeatable
            m = [a * a + b * b for a, b in zip(gx, gy)]
            first = m[0] >= m[1]
            m01 = np.where(first, m[0], m[1])
            third = m[2] > m01
            gx = np.where(third, gx[2], np.where(first, gx[0], gx[1]))
            gy = np.where(third, gy[2], np.where(first, gy[0], gy[1]))
        gxs[i], gys[i] = gx, gy
    mag, theta = cv2.cartToPolar(gxs.reshape(-1, w), gys.reshape(-1, w))
    return mag.reshape(s, h, w), theta.reshape(s, h, w)


def orientation_votes(patch: np.ndarray) -> np.ndarray:
    """Per-pixel gradient votes ``(H, W, 18)`` float32: the magnitude split linearly between the two nearest of 18
    orientation bins over [0, 2pi). Pooling these over cells (bilinearly) gives the HOG cell histograms."""
    mag, theta = _gradients(patch[None])
    h, w = mag.shape[1:]
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
    """Normalise and truncate 18-bin cell histograms ``(S, n, m, 18)`` into the 31 fHOG channels.

    Each cell is normalised by each of its four 2x2-block energies in turn and clipped; one patch and one block
    corner at a time, so the working arrays stay in cache (about twice as fast as the all-at-once version on 7 x 63 x 63
    cells, the ECO search's size).
    """
    s, ny, nx, _ = hist.shape
    insens = hist[..., :9] + hist[..., 9:]
    energy = np.sum(insens * insens, axis=-1)
    e = np.pad(energy, ((0, 0), (1, 1), (1, 1)), mode="edge")
    blocks = e[:, :-1, :-1] + e[:, 1:, :-1] + e[:, :-1, 1:] + e[:, 1:, 1:]
    inv_norm = (1.0 / np.sqrt(blocks + _EPS)).astype(np.float32)  # (S, n + 1, m + 1)
    out = np.empty((s, ny, nx, 31), np.float32)
    ones = np.ones(N_ORIENT, np.float32)
    clipped, clipped_ins = np.empty((ny, nx, N_ORIENT), np.float32), np.empty((ny, nx, 9), np.float32)
    sens, ins = np.empty_like(clipped), np.empty_like(clipped_ins)
    for i in range(s):
        for k, (dy, dx) in enumerate(((0, 0), (0, 1), (1, 0), (1, 1))):
            norm = inv_norm[i, dy : dy + ny, dx : dx + nx, None]
            np.minimum(np.multiply(hist[i], norm, out=clipped), CLIP, out=clipped)
            np.minimum(np.multiply(insens[i], norm, out=clipped_ins), CLIP, out=clipped_ins)
            out[i, :, :, 27 + k] = (clipped.reshape(-1, N_ORIENT) @ ones).reshape(ny, nx)  # texture
            if k == 0:
                sens[...], ins[...] = clipped, clipped_ins
            else:
                sens += clipped
                ins += clipped_ins
        np.multiply(sens, 0.5, out=out[i, :, :, :N_ORIENT])
        np.multiply(ins, 0.5, out=out[i, :, :, N_ORIENT:27])
    out[..., 27:] *= 0.2357
    return out


class FHog:
    """fHOG feature block (31 channels at ``cell`` pixels, compressed to ``compressed_dim`` by the tracker)."""

    def __init__(self, cell: int = 4, compressed_dim: int = 10) -> None:
        self.cell = cell
        self.blocks = (BlockSpec("fhog", cell, 31, compressed_dim),)

    def maps(self, patch: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """Per-pixel orientation votes (pooled into cell histograms by the caller)."""
        return [(orientation_votes(patch), 1)]

    def finish(self, cells: list[np.ndarray]) -> list[np.ndarray]:
        """Cell histograms ``(S, n, n, 18)`` -> normalised 31-channel fHOG."""
        return [fhog_from_histograms(cells[0])]

    def compute(self, patches: np.ndarray) -> list[np.ndarray]:
        """``(S, P, P[, 3])`` uint8 -> ``[(S, P/cell, P/cell, 31)]``."""
        return compute(self, patches)
