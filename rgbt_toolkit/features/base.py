"""Feature extractor interface for the ECO tracker.

A feature takes a batch of square image patches (one per scale) and returns one or more feature *blocks*, each a
``(S, n, n, D)`` float32 array at its own stride. The tracker handles normalisation, projection and the Fourier
domain; a feature only maps pixels to channels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

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
    """What the tracker needs of a feature extractor.

    ``maps(patch)`` turns one patch into raw maps, one per block, each with the stride it was computed at (1 for
    per-pixel channels); :mod:`rgbt_toolkit.features.pooling` samples those at the cells of each scale; ``finish``
    turns the sampled cells into the block's final channels (fHOG's block normalisation, for instance).
    """

    blocks: tuple[BlockSpec, ...]

    def maps(self, patch: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """``(P, P)`` grey or ``(P, P, 3)`` RGB uint8 -> ``[(map (H, W, D) float32, map stride)]`` per block."""
        ...

    def finish(self, cells: list[np.ndarray]) -> list[np.ndarray]:
        """Sampled cells ``(S, n, n, D)`` per block -> final ``(S, n, n, dim)`` per block."""
        ...


def compute(feature: Feature, patches: np.ndarray) -> list[np.ndarray]:
    """Cell maps ``(S, P/stride, P/stride, dim)`` per block for a batch of patches at their own scale."""
    from rgbt_toolkit.features.pooling import cells_at_scales

    strides = [b.stride for b in feature.blocks]
    patches = check_patches(patches, max(strides))
    size = patches.shape[1]
    per_block: list[list[np.ndarray]] = [[] for _ in strides]
    for patch in patches:
        for k, ((fmap, ms), st) in enumerate(zip(feature.maps(patch), strides)):
            per_block[k].append(cells_at_scales(fmap, ms, st, size, np.array([1.0]), size)[0])
    return feature.finish([np.stack(c) for c in per_block])


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
