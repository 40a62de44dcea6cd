"""Pixel values of fusion and tracking inputs: any decoded image -> uint8 grey or RGB, never silently saturated.

Fusion blends 8-bit intensities and the trackers' features expect them, so every input is brought to uint8 first:

- uint8 passes through; a boolean (1-bit) image becomes 0 / 255;
- floats already in [0, 1] are scaled by 255 (the usual convention for float images);
- anything else (16-bit, 32-bit integers, floats outside [0, 1] such as a radiometric thermal frame in degrees C or
  floats on 0..255) is *stretched*: the used range, the 0.5 and 99.5 percentiles of the finite pixels, maps to
  0..255, as registration does (``registration.features``). Dividing a 16-bit thermal frame by 257 instead leaves a
  sensor that uses 7000..9000 counts as a flat grey, and clipping a degrees-C frame at 1.0 leaves it white.
- non-finite pixels (dead pixels of a radiometric frame) become the darkest value; an image with no finite pixel is
  refused.

A video is mapped with one range for all its frames (:class:`FixedRange`), so a warming scene does not flicker.

Channels: grey ``[H,W]``, ``[H,W,1]``, grey + alpha ``[H,W,2]``, RGB ``[H,W,3]`` and RGBA ``[H,W,4]`` are accepted
(alpha dropped); colour is stretched with one range for all channels so its hue is kept.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import InputError

STRETCH_PERCENTILES = (0.5, 99.5)  # same as registration.features._stretch


def drop_alpha(image: np.ndarray, name: str) -> np.ndarray:
    """Grey ``[H,W]`` or colour ``[H,W,3]`` from 1-4 channel images (alpha dropped), or :class:`InputError`."""
    image = np.asarray(image)
    if image.ndim == 3 and image.shape[2] in (1, 2):
        image = image[:, :, 0]
    elif image.ndim == 3 and image.shape[2] == 4:
        image = image[:, :, :3]
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3) or image.size == 0:
        raise InputError(f"{name}: expected a grey, grey+alpha, RGB or RGBA image, got array shape {image.shape}")
    return image


def as_uint8(image: np.ndarray, name: str = "image", value_range: tuple[float, float] | None = None) -> np.ndarray:
    """``image`` as uint8 grey ``[H,W]`` or RGB ``[H,W,3]`` (see the module docstring for the value rules).

    Parameters
    ----------
    image : np.ndarray
        Decoded image of any numeric dtype, 1-4 channels.
    name : str
        What to call the image in error messages (a file name).
    value_range : (low, high), optional
        Map this range to 0..255 instead of the image's own used range (non-uint8 images only).

    Raises
    ------
    InputError
        Unsupported channel count or dtype (complex, object), or no finite pixel.
    """
    image = drop_alpha(image, name)
    if image.dtype == np.uint8:
        return image
    if image.dtype == np.bool_:
        return image.astype(np.uint8) * 255
    if not (np.issubdtype(image.dtype, np.integer) or np.issubdtype(image.dtype, np.floating)):
        raise InputError(f"{name}: unsupported pixel type {image.dtype}; use 8- or 16-bit integer or float images")
    values = image.astype(np.float32)
    finite = np.isfinite(values)
    if not finite.any():
        raise InputError(f"{name}: no finite pixel value (all NaN or infinite)")
    if value_range is not None:
        return _mapped(values, *value_range)
    used = values[finite] if not finite.all() else values
    lo, hi = float(used.min()), float(used.max())
    if np.issubdtype(image.dtype, np.floating) and lo >= 0.0 and hi <= 1.0:
        return _mapped(values, 0.0, 1.0)
    lo, hi = used_range(used)
    if hi <= lo:  # constant image: mid-grey rather than a division by zero
        return np.full(values.shape, 128, np.uint8)
    return _mapped(values, lo, hi)


def _mapped(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """float32 ``values`` with ``lo..hi`` mapped to 0..255 (rounded, clipped); non-finite pixels become 0."""
    scaled = (values - np.float32(lo)) * np.float32(255.0 / max(hi - lo, 1e-12)) + np.float32(0.5)
    scaled[~np.isfinite(values)] = 0.0
    return np.clip(scaled, 0, 255).astype(np.uint8)


def used_range(image: np.ndarray) -> tuple[float, float]:
    """The 0.5-99.5 percentile range of the finite pixels of a non-uint8 image (what :func:`as_uint8` stretches)."""
    values = np.asarray(image, dtype=np.float32)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return 0.0, 1.0
    lo, hi = (float(v) for v in np.percentile(values, STRETCH_PERCENTILES))
    # almost all pixels equal: the full range, so the few others still show
    return (lo, hi) if hi > lo else (float(values.min()), float(values.max()))


class FixedRange:
    """Map every frame of one stream to uint8 with one range, set by its first frame with contrast (plus headroom).

    A radiometric thermal video (16-bit counts, or degrees C) stretched frame by frame would change brightness
    whenever something hot enters the view, which the trackers would take for appearance change; one range keeps
    the same temperature at the same grey level. The range only ever widens: when more than ``MAX_CLIPPED`` of a
    frame's pixels fall outside it (sensor drift, an offset jump after a flat-field correction, a hot object), it
    grows to take them in, rather than saturating them. A frame without contrast (a shutter frame) maps to mid-grey
    and sets nothing; one without a finite pixel maps to black. 8-bit frames pass through untouched.
    """

    HEADROOM = 0.1  # of the range on either side, for a scene that warms or cools later
    MAX_CLIPPED = 0.01

    def __init__(self, name: str):
        self.name = name
        self.value_range: tuple[float, float] | None = None

    def __call__(self, frame: np.ndarray, name: str | None = None) -> np.ndarray:
        """``frame`` as uint8 (``name``: the frame's file, for error messages; default the stream's name)."""
        frame = drop_alpha(frame, name or self.name)
        if frame.dtype == np.uint8:
            return frame
        values = np.asarray(frame, dtype=np.float32)
        finite = values[np.isfinite(values)]
        if finite.size == 0:
            return np.zeros(frame.shape, np.uint8)
        lo, hi = float(finite.min()), float(finite.max())
        if self.value_range is None:
            if np.issubdtype(frame.dtype, np.floating) and lo >= 0.0 and hi <= 1.0:
                self.value_range = (0.0, 1.0)  # floats in [0, 1]: the usual convention, no stretch
            elif hi > lo:
                self.value_range = self._padded(*used_range(finite))
            else:
                return np.full(frame.shape, 128, np.uint8)
        low, high = self.value_range
        if np.count_nonzero((finite < low) | (finite > high)) > self.MAX_CLIPPED * finite.size:
            f_lo, f_hi = used_range(finite)
            self.value_range = self._padded(min(low, f_lo), max(high, f_hi))
        return _mapped(values, *self.value_range)  # values: already float32, checked above

    def _padded(self, lo: float, hi: float) -> tuple[float, float]:
        pad = self.HEADROOM * (hi - lo)
        return lo - pad, hi + pad
