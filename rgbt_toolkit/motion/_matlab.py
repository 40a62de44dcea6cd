"""The two MATLAB image operations the authors' camera-motion trigger relies on, reproduced exactly.

``medfilt2(I, [9 9])`` pads with zeros (not by replication, as ``cv2.medianBlur`` does), and ``imresize`` shrinks with
an antialiased bicubic kernel (a = -0.5, widened by 1/scale) and symmetric edge padding. The trigger's threshold
(0.1284) was tuned on those exact numbers, so both are reproduced here rather than approximated by OpenCV defaults.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np


def medfilt2_zero(image: np.ndarray, size: int = 9) -> np.ndarray:
    """MATLAB ``medfilt2(image, [size size])`` on a 2-D uint8 image: median over a square window, zero padding.

    ``cv2.medianBlur`` replicates the border; padding with ``size // 2`` zeros first and cropping afterwards makes
    every output pixel's window lie inside the padded image, which gives MATLAB's zero-padded result exactly.
    """
    if image.ndim != 2 or image.dtype != np.uint8:
        raise ValueError("medfilt2_zero expects a 2-D uint8 image")
    if size % 2 != 1 or size < 1:
        raise ValueError(f"median size must be odd and positive, got {size}")
    half = size // 2
    padded = cv2.copyMakeBorder(image, half, half, half, half, cv2.BORDER_CONSTANT, value=0)
    filtered = cv2.medianBlur(padded, size)
    return filtered[half:-half, half:-half] if half else filtered


def _cubic(x: np.ndarray) -> np.ndarray:
    """MATLAB's bicubic kernel (Keys, a = -0.5)."""
    ax = np.abs(x)
    ax2 = ax * ax
    ax3 = ax2 * ax
    inner = (1.5 * ax3 - 2.5 * ax2 + 1.0) * (ax <= 1)
    return inner + (-0.5 * ax3 + 2.5 * ax2 - 4.0 * ax + 2.0) * ((ax > 1) & (ax <= 2))


@lru_cache(maxsize=16)
def imresize_weights(in_length: int, out_length: int) -> np.ndarray:
    """The ``out_length x in_length`` matrix of MATLAB ``imresize`` (bicubic, antialiasing on) along one axis.

    Output sample ``i`` (1-based in MATLAB) sits at input coordinate ``u = i / s + 0.5 (1 - 1 / s)``; when shrinking
    (``s < 1``) the kernel is stretched by ``1 / s`` and scaled by ``s``. Taps beyond the edges are folded back by
    symmetric reflection, and each row is normalised to sum to one, as MATLAB's ``contributions`` does.
    """
    scale = out_length / in_length
    kernel_width = 4.0 / scale if scale < 1 else 4.0
    x = np.arange(1, out_length + 1, dtype=np.float64)
    u = x / scale + 0.5 * (1.0 - 1.0 / scale)
    left = np.floor(u - kernel_width / 2.0)
    taps = int(np.ceil(kernel_width)) + 2
    indices = left[:, None] + np.arange(taps)[None, :]  # 1-based input positions
    distance = u[:, None] - indices
    weights = scale * _cubic(scale * distance) if scale < 1 else _cubic(distance)
    weights = weights / weights.sum(axis=1, keepdims=True)
    mirror = np.concatenate([np.arange(in_length), np.arange(in_length - 1, -1, -1)])
    folded = mirror[np.mod(indices.astype(np.int64) - 1, mirror.size)]
    matrix = np.zeros((out_length, in_length))
    np.add.at(matrix, (np.repeat(np.arange(out_length), taps), folded.ravel()), weights.ravel())
    matrix.flags.writeable = False  # cached (the trigger resizes frames of one size every frame): shared, read-only
    return matrix


def imresize_bicubic(image: np.ndarray, out_shape: tuple[int, int]) -> np.ndarray:
    """MATLAB ``imresize(double(image), out_shape)`` (bicubic, antialiased) of a 2-D array, in float64.

    The resize is separable and linear, so it is one matrix product per axis; MATLAB's order of axes only changes
    rounding in the last bits.
    """
    rows = imresize_weights(image.shape[0], out_shape[0])
    cols = imresize_weights(image.shape[1], out_shape[1])
    return rows @ np.asarray(image, dtype=np.float64) @ cols.T
