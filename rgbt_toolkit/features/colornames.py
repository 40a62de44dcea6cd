"""Colour-naming feature: soft membership of each pixel in the 11 basic colour terms.

The ColorNames table of van de Weijer et al. (learned from Google images) is not ours to ship. This module builds the
project's own table instead: each of the 11 basic colour terms of Berlin and Kay (black, blue, brown, grey, green,
orange, pink, purple, red, white, yellow - the order of the original table) is a prototype colour in CIELAB, and a
pixel's membership is a softmax of its negative squared perceptual distance to the prototypes. Like ECO's ``CNnorm``,
the 11 memberships (which sum to one) are projected onto an orthonormal basis of the zero-sum subspace, giving 10
decorrelated channels. A user who has the original table (``CNnorm.mat``, 32768 x 10, index
``r//8 + 32*(g//8) + 1024*(b//8)``) can load it with :func:`load_colour_table` and pass it in.
"""

from __future__ import annotations

import os
import threading
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.errors import FileFormatError, MissingFileError
from rgbt_toolkit.features.base import BlockSpec, compute

TERMS = ("black", "blue", "brown", "grey", "green", "orange", "pink", "purple", "red", "white", "yellow")

# Prototype (focal) colours in sRGB, chosen near the focal colours reported by Berlin & Kay / Sturges & Whitfield
# (1995) for the Munsell array, and the spread (CIELAB distance scale) of each category; achromatic categories are
# narrow in chroma, chromatic ones broad in lightness.
_PROTOTYPES_SRGB = np.array([
    [0, 0, 0],          # black
    [40, 80, 200],      # blue
    [120, 70, 35],      # brown
    [128, 128, 128],    # grey
    [40, 150, 60],      # green
    [245, 130, 20],     # orange
    [245, 160, 190],    # pink
    [120, 50, 150],     # purple
    [200, 25, 35],      # red
    [255, 255, 255],    # white
    [250, 225, 40],     # yellow
], dtype=np.uint8)
_SPREAD = np.array([22.0, 30.0, 22.0, 22.0, 32.0, 25.0, 25.0, 28.0, 28.0, 22.0, 25.0])
# weighting of (L, a, b) in the distance: lightness counts less than hue for the chromatic terms
_LAB_WEIGHT = np.array([0.6, 1.0, 1.0])

TABLE_BINS = 32  # 32 levels per channel (r // 8), as the original table


def _srgb_to_lab(rgb_uint8: np.ndarray) -> np.ndarray:
    """CIELAB (D65) of uint8 sRGB colours ``(N, 3)`` via OpenCV's float conversion (L in 0..100)."""
    f = (rgb_uint8.reshape(-1, 1, 3).astype(np.float32) / 255.0)
    return cv2.cvtColor(f, cv2.COLOR_RGB2Lab).reshape(-1, 3).astype(np.float64)


def zero_sum_basis(n: int) -> np.ndarray:
    """``(n, n-1)`` orthonormal basis of the vectors summing to zero (Helmert contrasts)."""
    basis = np.zeros((n, n - 1))
    for j in range(1, n):
        basis[:j, j - 1] = 1.0 / j
        basis[j, j - 1] = -1.0
        basis[:, j - 1] /= np.linalg.norm(basis[:, j - 1])
    return basis


def membership(rgb_uint8: np.ndarray) -> np.ndarray:
    """Soft membership ``(N, 11)`` of ``(N, 3)`` uint8 sRGB colours in the 11 colour terms (rows sum to 1)."""
    lab = _srgb_to_lab(rgb_uint8)
    proto = _srgb_to_lab(_PROTOTYPES_SRGB)
    d2 = (((lab[:, None, :] - proto[None, :, :]) * _LAB_WEIGHT) ** 2).sum(-1) / (2 * _SPREAD**2)
    d2 -= d2.min(axis=1, keepdims=True)
    p = np.exp(-d2)
    return p / p.sum(axis=1, keepdims=True)


_TABLE_LOCK = threading.Lock()  # one build, however many threads ask for the table at once


def own_table() -> np.ndarray:
    """The project's colour-name table, ``(32768, 10)`` float32, indexed like the original ``CNnorm``."""
    with _TABLE_LOCK:
        return _build_own_table()


def build_table_in_background() -> threading.Thread | None:
    """Start building :func:`own_table` on a daemon thread (returned; None when it is built already); a later call of
    :func:`own_table` waits for that build.

    Why: the first build takes 50-100 ms (OpenCV makes its CIELAB tables on first use), on the first frame of every
    ECO tracker with colour names; a caller that has a core to spare before then (``rgbt track`` while its inputs
    open) takes it off the tracker's start-up.
    """
    if _build_own_table.cache_info().currsize:
        return None
    thread = threading.Thread(target=own_table, name="rgbt-colour-table", daemon=True)
    thread.start()
    return thread


@lru_cache(maxsize=1)
def _build_own_table() -> np.ndarray:
    levels = np.arange(TABLE_BINS) * 8 + 4  # bin centres
    r, g, b = np.meshgrid(levels, levels, levels, indexing="ij")
    # index r//8 + 32 g//8 + 1024 b//8: r varies fastest
    rgb = np.stack([r.transpose(2, 1, 0).ravel(), g.transpose(2, 1, 0).ravel(), b.transpose(2, 1, 0).ravel()], 1)
    probs = membership(rgb.astype(np.uint8))
    return ((probs - 1.0 / len(TERMS)) @ zero_sum_basis(len(TERMS))).astype(np.float32)


def table_index(patches: np.ndarray) -> np.ndarray:
    """Table row of each pixel of uint8 RGB ``(..., 3)``: ``r//8 + 32*(g//8) + 1024*(b//8)``."""
    q = (patches >> 3).astype(np.int32)
    return q[..., 0] + 32 * q[..., 1] + 1024 * q[..., 2]


def load_colour_table(path: str | os.PathLike) -> np.ndarray:
    """Read a user-supplied colour-name table in the original ``.mat`` format (a 32768 x D numeric matrix).

    Raises
    ------
    MissingFileError, FileFormatError
    """
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: no such file")
    from scipy.io import loadmat

    try:
        contents = loadmat(path)
    except Exception as exc:  # scipy raises several unrelated types for a bad file
        raise FileFormatError(f"{path}: not a MATLAB .mat file ({exc})") from None
    for key, value in contents.items():
        if not key.startswith("__") and isinstance(value, np.ndarray) and value.ndim == 2 \
                and value.shape[0] == TABLE_BINS**3 and np.issubdtype(value.dtype, np.number):
            return value.astype(np.float32)
    raise FileFormatError(f"{path}: no 32768-row colour table inside; expected e.g. variable CNnorm (32768 x 10)")


class ColourNames:
    """Colour-name channels averaged over ``cell`` x ``cell`` pixels; ``table`` defaults to :func:`own_table`."""

    def __init__(self, cell: int = 4, compressed_dim: int = 3, table: np.ndarray | None = None) -> None:
        self.cell = cell
        self.table = own_table() if table is None else np.asarray(table, dtype=np.float32)
        self.blocks = (BlockSpec("colornames", cell, self.table.shape[1], compressed_dim),)

    def maps(self, patch: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """Per-pixel table values ``(P, P, D)`` (grey patches are replicated to RGB)."""
        if patch.ndim == 2:
            patch = np.repeat(patch[..., None], 3, axis=-1)
        return [(np.take(self.table, table_index(patch), axis=0), 1)]

    def finish(self, cells: list[np.ndarray]) -> list[np.ndarray]:
        """Pooled values are the feature."""
        return cells

    def compute(self, patches: np.ndarray) -> list[np.ndarray]:
        """``(S, P, P, 3)`` uint8 RGB -> ``[(S, P/cell, P/cell, D)]``: table values pooled bilinearly over cells."""
        return compute(self, patches)
