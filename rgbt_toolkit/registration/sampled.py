"""A frame folder read by time: only the frames a registration estimate pairs are decoded, JPEG at reduced size.

A registration estimate uses a few frame pairs (4 by default). The streaming path decodes every file of a folder
to learn its frames' times and keep one per time chunk: on a 101-frame 1920x1080 JPEG pair that was 4.6 s of the
8 s estimate inside `rgbt track` (docs/registration.md). Here a folder's times come from its file list (file ``i``
at ``i / fps``, as :class:`~rgbt_toolkit.io.frames.FrameSource` stamps it) and only the chosen files are decoded.
The estimate works on copies whose longer side is at most ``SpatialSettings.analysis_size``, so a JPEG is decoded
straight to the smallest power-of-two reduction (libjpeg's DCT scaling) that keeps it at least that large, as grey.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.images import list_images, read_image

JPEG_SUFFIXES = (".jpg", ".jpeg")
# OpenCV's grey JPEG decodes at 1/1, 1/2, 1/4, 1/8 of the size; EXIF orientation ignored, as read_image ignores it
_REDUCED_GREY = {1: cv2.IMREAD_GRAYSCALE, 2: cv2.IMREAD_REDUCED_GRAYSCALE_2, 4: cv2.IMREAD_REDUCED_GRAYSCALE_4,
                 8: cv2.IMREAD_REDUCED_GRAYSCALE_8}


def reduction_for(size: tuple[int, int], longer: int) -> int:
    """The largest JPEG reduction (1, 2, 4 or 8) that keeps the longer side of a ``size`` (w, h) frame at least
    ``longer`` pixels: the estimate's analysis copy is then resampled from the reduced frame, never enlarged."""
    factor = 1
    while factor < 8 and max(size) / (2 * factor) >= longer:
        factor *= 2
    return factor


def image_size(path: str | os.PathLike) -> tuple[int, int]:
    """(width, height) of an image file from its header, without decoding its pixels."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            return image.size
    except (OSError, UnidentifiedImageError) as exc:
        from rgbt_toolkit.errors import FileFormatError

        raise FileFormatError(f"{path}: cannot read image header ({exc.__class__.__name__})") from None


class SampledFolder:
    """A frame folder whose frames are fetched by time (``times`` from the file list, no decoding).

    ``longer`` is the longest side the estimate analyses (``SpatialSettings.analysis_size``): JPEG frames are decoded
    reduced towards it. ``on_frame`` is called per decoded file (progress). :attr:`size` is the full (width, height) of the frames, which the estimate's matrix refers
    to; a chosen file of another size is an :class:`InputError` naming it.
    """

    def __init__(self, path: str | os.PathLike, fps: float, longer: int, on_frame: Callable[[], None] | None = None):
        self.path, self._on_frame = Path(path), on_frame
        self.files = list_images(self.path)
        if not self.files:
            raise InputError(f"{self.path}: folder holds no images")
        self.times = np.arange(len(self.files)) / float(fps)
        self.size = image_size(self.files[0])
        self.reduction = reduction_for(self.size, longer)

    def decode_cost(self, times: np.ndarray) -> np.ndarray:
        """Frames decoded to fetch the frame at each time: every file stands alone."""
        return np.ones(len(times), int)

    def frames_at(self, times: np.ndarray) -> dict[float, np.ndarray]:
        """{t: grey frame} for times taken from :attr:`times`; an unreadable file is left out with a warning (as
        the streaming path skips it)."""
        found = {}
        for t in times:
            index = int(np.argmin(np.abs(self.times - t)))
            frame = self._read(self.files[index])
            if self._on_frame is not None:
                self._on_frame()
            if frame is not None:
                found[float(self.times[index])] = frame
        return found

    def _read(self, file: Path) -> np.ndarray | None:
        """One file as grey, JPEG reduced by :attr:`reduction`; None (warned) when it does not decode."""
        from rgbt_toolkit.errors import FileFormatError
        from rgbt_toolkit.io.video import CorruptFrameWarning

        try:
            size = image_size(file)
            if size != self.size:
                raise InputError(f"{file}: {size[0]}x{size[1]}, the other frames are {self.size[0]}x{self.size[1]}")
            if file.suffix.lower() in JPEG_SUFFIXES:
                frame = cv2.imread(str(file), _REDUCED_GREY[self.reduction] | cv2.IMREAD_IGNORE_ORIENTATION)
                if frame is None:
                    raise FileFormatError(f"{file}: cannot decode image")
                return frame
            return read_image(file, grey=True)  # PNG / TIFF (16-bit thermal kept) / BMP: no reduced decode
        except FileFormatError as exc:
            warnings.warn(f"{exc}; frame skipped", CorruptFrameWarning, stacklevel=3)
            return None
