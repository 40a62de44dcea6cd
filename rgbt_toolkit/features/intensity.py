"""Intensity features for grey / thermal images.

ECO pairs fHOG with ColorNames on colour input and with an intensity-channel lookup table on grey input (the authors'
JMMAC code runs it on thermal frames). The project's own version: the normalised intensity plus a soft histogram of
intensity (triangular votes into ``bins`` levels), averaged over cells. The soft histogram lets a linear filter
respond to "how many pixels of this brightness are here", which a single intensity channel cannot express.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.features.base import BlockSpec, compute, to_grey


def intensity_channels(grey: np.ndarray, bins: int) -> np.ndarray:
    """Per-pixel channels ``(..., 1 + bins)``: intensity scaled to [-0.5, 0.5] and triangular bin memberships."""
    v = grey.astype(np.float32) / 255.0
    centres = np.linspace(0.0, 1.0, bins, dtype=np.float32)
    width = 1.0 / (bins - 1)
    member = np.maximum(0.0, 1.0 - np.abs(v[..., None] - centres) / width)
    return np.concatenate([(v - 0.5)[..., None], member], axis=-1)


class Intensity:
    """Intensity and soft intensity-histogram channels at ``cell`` pixels (for thermal / grey frames)."""

    def __init__(self, cell: int = 4, compressed_dim: int = 3, bins: int = 6) -> None:
        self.cell = cell
        self.bins = bins
        self.blocks = (BlockSpec("intensity", cell, 1 + bins, compressed_dim),)
        self._table = intensity_channels(np.arange(256, dtype=np.uint8), bins)

    def maps(self, patch: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """Per-pixel channels ``(P, P, 1 + bins)`` (colour is converted to luminance).

        A grey uint8 patch has 256 possible values, so its channels are read from a table of
        :func:`intensity_channels` of 0..255 (the same numbers, 3x faster than computing them per pixel).
        """
        if patch.ndim == 2 and patch.dtype == np.uint8:
            return [(np.take(self._table, patch, axis=0), 1)]
        return [(intensity_channels(to_grey(patch[None])[0], self.bins), 1)]

    def finish(self, cells: list[np.ndarray]) -> list[np.ndarray]:
        """Pooled channels are the feature."""
        return cells

    def compute(self, patches: np.ndarray) -> list[np.ndarray]:
        """``(S, P, P[, 3])`` uint8 -> ``[(S, P/cell, P/cell, 1 + bins)]`` pooled bilinearly over cells."""
        return compute(self, patches)
