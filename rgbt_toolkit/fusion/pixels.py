"""Pixel values of ``rgbt fuse`` inputs: any decoded image -> uint8 grey or RGB, never silently saturated.

Fusion blends 8-bit intensities, so every input is brought to uint8 first:

- uint8 passes through; a boolean (1-bit) image becomes 0 / 255;
- floats already in [0, 1] are scaled by 255 (the usual convention for float images);
- anything else (16-bit, 32-bit integers, floats outside [0, 1] such as a radiometric thermal frame in degrees C or
  floats on 0..255) is *stretched*: the used range, the 0.5 and 99.5 percentiles of the finite pixels, maps to
  0..255, as registration does (``registration.features``). Dividing a 16-bit thermal frame by 257 instead leaves a
  sensor that uses 7000..9000 counts as a flat grey, and clipping a degrees-C frame at 1.0 leaves it white.
- non-finite pixels (dead pixels of a radiometric frame) become the darkest value; an image with no finite pixel is
  refused.

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


def as_uint8(image: np.ndarray, name: str = "image") -> np.ndarray:
    """``image`` as uint8 grey ``[H,W]`` or RGB ``[H,W,3]`` (see the module docstring for the value rules).

    Parameters
    ----------
    image : np.ndarray
        Decoded image of any numeric dtype, 1-4 channels.
    name : str
        What to call the image in error messages (a file name).

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
    if not finite.all():
        if not finite.any():
            raise InputError(f"{name}: no finite pixel value (all NaN or infinite)")
        values = np.where(finite, values, np.nan)
    used = values[finite] if not finite.all() else values
    lo, hi = float(used.min()), float(used.max())
    if np.issubdtype(image.dtype, np.floating) and lo >= 0.0 and hi <= 1.0:
        scaled = values * 255.0
    else:
        p_lo, p_hi = (float(v) for v in np.percentile(used, STRETCH_PERCENTILES))
        if p_hi > p_lo:
            lo, hi = p_lo, p_hi  # else: almost all pixels equal; stretch the full range so the few others show
        if hi <= lo:  # constant image: mid-grey rather than a division by zero
            scaled = np.full(values.shape, 128.0, np.float32)
        else:
            scaled = (values - lo) * (255.0 / (hi - lo))
    return np.clip(np.nan_to_num(scaled, nan=0.0) + 0.5, 0, 255).astype(np.uint8)
