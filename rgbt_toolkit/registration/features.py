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


def orientation_field(grey: np.ndarray, *, smooth: float = 1.0, softness: float = 0.5,
                      ignore_fill: bool = True) -> np.ndarray:
    """Doubled-angle orientation field of a grey image as an (H, W, 2) float32 array (Re Z, Im Z).

    Parameters
    ----------
    grey : float32 image in [0, 1].
    smooth : Gaussian sigma (pixels) for averaging Z: widens the capture range and suppresses noise.
    softness : ``s^2`` as a fraction of the mean squared gradient; edges well above it get magnitude near 1, so
        strong and weak edges count alike, while flat noisy areas stay near 0.
    ignore_fill : zero the field over and around a no-data fill at the frame edge (:func:`fill_mask`), so its
        straight edge, which the other camera does not see, neither pulls the match nor sets ``s``.
    """
    g = cv2.GaussianBlur(grey, (0, 0), 1.0)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=1 / 8)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=1 / 8)
    m2 = gx * gx + gy * gy
    fill = fill_mask(grey) if ignore_fill else None
    if fill is not None:  # the edge of a no-data fill is not scene structure: neither an edge nor in the mean
        fill = cv2.dilate(fill.astype(np.uint8), np.ones((2 * FILL_REACH + 1,) * 2, np.uint8)) > 0
        m2[fill] = 0.0
        s2 = softness * float(m2.sum() / max(1, fill.size - int(fill.sum()))) + 1e-12
    else:
        s2 = softness * float(m2.mean()) + 1e-12
    denom = m2 + s2
    field = np.empty(grey.shape + (2,), np.float32)
    field[..., 0] = (gx * gx - gy * gy) / denom
    field[..., 1] = 2.0 * gx * gy / denom
    if fill is not None:
        field[fill] = 0.0
    if smooth > 0:
        field = cv2.GaussianBlur(field, (0, 0), smooth)
    return field


FILL_REACH = 4  # px around a fill whose gradients its edge reaches (1-px pre-blur, 3x3 Sobel, 1-px smoothing)
FILL_TOLERANCE = 2.0 / 255  # a fill is one value; resampling and mild compression move it by a grey level
MAX_FILL_VERTICES = 12  # a fill's outline is a few straight lines (a pasted, rotated or cropped frame)
MAX_FILL_SPREAD = 0.6 / 255  # standard deviation inside a fill (lossless: 0; JPEG: a fraction of a grey level)
MIN_FILL_AREA = 0.01  # fraction of the frame: smaller patches of one value at the edge (clipped sky) are left alone


def fill_mask(grey: np.ndarray) -> np.ndarray | None:
    """Where a frame holds no picture: one constant value reaching the frame edge, outlined by straight lines.

    Frames warped, rotated, letterboxed or pasted onto a canvas by an earlier step (TNO's infrared images 09 and 10
    carry black bars) have a sharp straight edge along the fill that the other camera does not see, and that would
    draw the registration towards aligning it with some unrelated edge. A clipped cold sky is also one value at the
    frame edge, but its outline (the horizon) is ragged, and real: it is not taken. Limits: a fill must be flat to
    within a grey level, so a JPEG'd fill is found only once shrinking has averaged its compression noise away (VIFB
    labMan's white page: at the 256-px coarse search, not at full size), and a clipped sky over a perfectly straight
    roofline would be taken for one. Returns None when there is no fill.
    """
    rim = np.concatenate([grey[0], grey[-1], grey[1:-1, 0], grey[1:-1, -1]])
    counts = np.bincount(np.clip(np.round(rim * 255), 0, 255).astype(np.intp), minlength=256)  # O(n), no sort
    value = int(np.argmax(counts)) / 255
    if counts.max() < 0.1 * rim.size:
        return None
    same = (np.abs(grey - value) <= FILL_TOLERANCE).astype(np.uint8)
    _, labels, stats, _ = cv2.connectedComponentsWithStats(same, connectivity=4)
    touching = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    large = touching[(touching > 0) & (stats[touching, cv2.CC_STAT_AREA] >= MIN_FILL_AREA * grey.size)]
    mask = np.zeros(grey.shape, bool)
    for label in large:  # a noisy rim can touch hundreds of specks: only large parts get a full-frame mask
        part = labels == label
        inner = cv2.erode(part.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
        if not inner.any() or float(np.std(grey[inner])) > MAX_FILL_SPREAD:
            continue  # a smooth, low-contrast part of the scene, not one value written into the frame
        outlines, _ = cv2.findContours(part.astype(np.uint8), cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
        # specks of noise inside a fill leave tiny holes: only outlines of some length count
        vertices = sum(len(cv2.approxPolyDP(c, 2.5, True)) for c in outlines if len(c) >= 40)
        if vertices <= MAX_FILL_VERTICES:
            mask |= part
    return mask if mask.any() else None
