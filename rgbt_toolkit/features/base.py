"""Feature extractor interface for the ECO tracker.

A feature takes a batch of square image patches (one per scale) and returns one or more feature *blocks*, each a
``(S, n, n, D)`` float32 array at its own stride. The tracker handles normalisation, projection and the Fourier
domain; a feature only maps pixels to channels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError


@dataclass(frozen=True)
class BlockSpec:
    """One block a feature returns: its name, stride (patch pixels per cell), channels, and compressed channels."""

    name: str
    stride: int
    dim: int
    compressed_dim: int


@runtime_checkable
class Feature(Protocol):
    """What the tracker needs of a feature extractor."""

    blocks: tuple[BlockSpec, ...]

    def compute(self, patches: np.ndarray) -> list[np.ndarray]:
        """Map ``(S, P, P, 3)`` RGB or ``(S, P, P)`` grey uint8 patches to one ``(S, P//stride, P//stride, dim)`` array
        per block (float32)."""
        ...


def check_patches(patches: np.ndarray, stride: int) -> np.ndarray:
    """Validate a patch batch ``(S, P, P)`` or ``(S, P, P, 3)`` (side a multiple of ``stride``) and return it."""
    patches = np.asarray(patches)
    if patches.ndim not in (3, 4) or (patches.ndim == 4 and patches.shape[-1] != 3):
        raise InputError(f"patches must be (S, P, P) grey or (S, P, P, 3) RGB, got shape {patches.shape}")
    if patches.shape[1] % stride or patches.shape[2] % stride:
        raise InputError(f"patch size {patches.shape[1:3]} is not a multiple of the cell size {stride}")
    return patches


def to_grey(patches: np.ndarray) -> np.ndarray:
    """Luminance (ITU-R BT.601, as MATLAB's rgb2gray) as float32; grey input passes through."""
    if patches.ndim == 3:
        return patches.astype(np.float32)
    p = patches.astype(np.float32)
    return 0.2989 * p[..., 0] + 0.5870 * p[..., 1] + 0.1140 * p[..., 2]


def average_cells(x: np.ndarray, cell: int) -> np.ndarray:
    """Mean over non-overlapping ``cell`` x ``cell`` squares of ``(S, H, W, D)`` float32 (ECO's cell pooling).

    OpenCV's area resize computes exactly these means and is ~8x faster than a numpy reshape-mean here.
    """
    s, h, w, d = x.shape
    out = np.empty((s, h // cell, w // cell, d), np.float32)
    for i in range(s):
        out[i] = cv2.resize(x[i], (w // cell, h // cell), interpolation=cv2.INTER_AREA).reshape(h // cell, w // cell, d)
    return out
