"""Modality-robust image features for RGB-to-thermal registration.

Visible and thermal cameras see the same edges (object outlines, windows, road markings) with unrelated intensities:
an edge can be dark-to-bright in one and bright-to-dark in the other, strong in one and faint in the other. The
feature used throughout is therefore the *doubled-angle gradient orientation* field

    Z = (gx + i gy)^2 / (|g|^2 + s^2),

whose angle is twice the gradient angle (so a contrast flip, angle + pi, gives the same Z) and whose magnitude
saturates at 1 for any edge well above the image's typical gradient ``s`` (so edge strength matters little). Averaging
Z over a small window is the orientation part of the structure tensor. Two channels, Re Z and Im Z, are compared by
normalised correlation (see ``refine.py``).
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError

# Below this RMS gradient (grey levels in [0, 1] per pixel, after the 1-px pre-blur) a frame holds no usable
# structure: a lens cap, a uniform wall or a saturated frame. Natural images measured here lie above 0.02.
BLANK_GRADIENT_RMS = 2e-3


def to_grey(image: np.ndarray) -> np.ndarray:
    """Float32 grey image in [0, 1] from uint8/uint16/float input, colour converted with BT.601 luminance weights."""
    image = np.asarray(image)
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[..., 0]
    if image.ndim == 3 and image.shape[2] in (3, 4):
        dtype = image.dtype
        image = image[..., :3].astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)
        if dtype == np.uint8:
            return image / 255.0
        if dtype == np.uint16:
            return _stretch(image)
    if image.ndim != 2 or image.size == 0:
        raise InputError(f"expected a 2-D grey or H x W x 3 colour frame, got shape {np.shape(image)}")
    return _to_unit(image)


def _to_unit(image: np.ndarray) -> np.ndarray:
    if image.dtype == np.uint8:
        return image.astype(np.float32) / 255.0
    if image.dtype == np.uint16:
        # 16-bit thermal frames rarely span the full range: stretch the used range instead of dividing by 65535
        return _stretch(image.astype(np.float32))
    image = image.astype(np.float32)
    finite = np.isfinite(image)
    if not finite.all():  # dead pixels of a radiometric frame: the median, so they neither set the range nor edges
        image = np.where(finite, image, np.float32(np.median(image[finite])) if finite.any() else np.float32(0))
    if image.max(initial=0.0) > 1.0 + 1e-3:
        return _stretch(image) if image.max() > 255.0 + 1e-3 else image / 255.0
    return image


def _stretch(image: np.ndarray) -> np.ndarray:
    """Map the used range (0.5-99.5 percentiles) to [0, 1] as float32 (percentiles come back as float64)."""
    lo, hi = (np.float32(v) for v in np.percentile(image, [0.5, 99.5]))
    if not np.isfinite(lo) or not np.isfinite(hi) or hi <= lo:
        return np.zeros(image.shape, np.float32)
    return np.clip((image - lo) / (hi - lo), 0.0, 1.0).astype(np.float32, copy=False)


def equalised(grey: np.ndarray, *, clip: float = 2.0, tiles: int = 8) -> np.ndarray:
    """Locally contrast-equalised copy (CLAHE) of a float32 grey image in [0, 1].

    At night a few street lamps set the image's typical gradient, so the orientation field's softness hides the faint
    but real edges of the dark scene around them; after local equalisation those edges count too. Registration gives a
    pair refused for weak evidence a second look with this copy scored beside the plain frame (``spatial.py``).
    """
    clahe = cv2.createCLAHE(clipLimit=clip, tileGridSize=(tiles, tiles))
    return clahe.apply(np.round(np.clip(grey, 0.0, 1.0) * 255).astype(np.uint8)).astype(np.float32) / 255.0


def resize_to(grey: np.ndarray, factor: float) -> np.ndarray:
    """Resize by ``factor`` (area averaging when shrinking); returns the input itself when ``factor`` is 1."""
    if abs(factor - 1.0) < 1e-9:
        return grey
    h, w = grey.shape
    size = (max(1, round(w * factor)), max(1, round(h * factor)))
    return cv2.resize(grey, size, interpolation=cv2.INTER_AREA if factor < 1 else cv2.INTER_LINEAR)


def gradient_rms(grey: np.ndarray) -> float:
    """Root-mean-square gradient magnitude after a 1-px Gaussian blur: how much structure a frame holds."""
    g = cv2.GaussianBlur(grey, (0, 0), 1.0)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=1 / 8)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=1 / 8)
    return float(np.sqrt(np.mean(gx * gx + gy * gy)))


def orientation_field(grey: np.ndarray, *, smooth: float = 1.0, softness: float = 0.5) -> np.ndarray:
    """Doubled-angle orientation field of a grey image as an (H, W, 2) float32 array (Re Z, Im Z).

    Parameters
    ----------
    grey : float32 image in [0, 1].
    smooth : Gaussian sigma (pixels) for averaging Z: widens the capture range and suppresses noise.
    softness : ``s^2`` as a fraction of the mean squared gradient; edges well above it get magnitude near 1, so
        strong and weak edges count alike, while flat noisy areas stay near 0.
    """
    g = cv2.GaussianBlur(grey, (0, 0), 1.0)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=1 / 8)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=1 / 8)
    m2 = gx * gx + gy * gy
    s2 = softness * float(m2.mean()) + 1e-12
    denom = m2 + s2
    field = np.empty(grey.shape + (2,), np.float32)
    field[..., 0] = (gx * gx - gy * gy) / denom
    field[..., 1] = 2.0 * gx * gy / denom
    if smooth > 0:
        field = cv2.GaussianBlur(field, (0, 0), smooth)
    return field
