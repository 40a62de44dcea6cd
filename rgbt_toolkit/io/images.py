"""Single images: read as numpy arrays, write atomically.

Images are returned as decoded (uint8 or uint16), in RGB channel order for colour images and 2-D for grey ones.
JPEG decoding goes through imageio/Pillow (libjpeg-turbo), which reproduces the published fusion metric values.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import cv2
import imageio.v3 as iio
import numpy as np

from rgbt_toolkit._atomic import atomic_path
from rgbt_toolkit.errors import FileFormatError, MissingFileError
from rgbt_toolkit.io.jpeg import decode_jpeg

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


def natural_key(name: str) -> list:
    """Sort key that orders ``2.jpg`` before ``10.jpg``."""
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", name)]


def list_images(folder: str | os.PathLike) -> list[Path]:
    """Image files directly inside ``folder``, naturally sorted."""
    folder = Path(folder)
    if not folder.is_dir():
        raise MissingFileError(f"{folder}: no such folder")
    files = [p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES]
    return sorted(files, key=lambda p: natural_key(p.name))


def read_image(path: str | os.PathLike, *, grey: bool = False) -> np.ndarray:
    """Read one image; ``grey=True`` converts colour to luminance (ITU-R BT.601, as MATLAB's rgb2gray) in uint8."""
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: no such file")
    if path.stat().st_size == 0:  # imageio would fail too, leaving its file handle open
        raise FileFormatError(f"{path}: empty file, not an image")
    try:
        image = iio.imread(path)
    except Exception as exc:  # imageio raises many types for corrupt files
        raise FileFormatError(f"{path}: cannot decode image ({exc.__class__.__name__})") from None
    if image.ndim == 3 and image.shape[2] == 4 and path.suffix.lower() in (".jpg", ".jpeg"):
        image = iio.imread(path, mode="RGB")  # JPEG has no alpha: four channels are CMYK, which Pillow converts
    elif image.ndim == 3 and image.shape[2] == 4:
        image = image[:, :, :3]
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.ndim not in (2, 3) or image.size == 0:
        raise FileFormatError(f"{path}: not a 2-D grey or colour image (shape {image.shape})")
    if grey and image.ndim == 3:
        image = rgb_to_grey(image)
    return image


def is_grey_picture(image: np.ndarray) -> bool:
    """Whether an H x W x 3 frame shows a grey picture (all three channels equal everywhere), as a thermal camera's
    8-bit output stored as colour does; any coloured pixel (a palette, a coloured overlay) makes it a colour frame."""
    return image.ndim == 3 and bool(np.array_equal(image[..., 0], image[..., 1])
                                    and np.array_equal(image[..., 0], image[..., 2]))


def block_mean(image: np.ndarray, k: int) -> np.ndarray:
    """``image`` shrunk by the whole factor ``k``: the means of its k x k blocks (rows and columns left over at the
    bottom and right edge dropped). The sides are exact multiples of ``k`` so that OpenCV takes its block-mean fast
    path, several times faster than its general area resize."""
    if k == 1:
        return image
    h, w = image.shape[0] // k * k, image.shape[1] // k * k
    return cv2.resize(image[:h, :w], (w // k, h // k), interpolation=cv2.INTER_AREA)


def shrink_to(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """``image`` resized down to ``size`` (w, h) by area averaging, or itself when it has that size already.

    Area averaging by a whole factor ``1/k`` has a fast path in OpenCV (plain k x k block means) that the general
    path lacks: 1920x1080 -> 741x417 took 9.3 ms directly (one thread). So the largest whole factor that divides both
    sides goes first, and a remaining factor of at least 1/2 is bilinear: after the block mean the image holds no
    detail finer than that factor can show, and OpenCV's bilinear resize is 7x faster than its general area resize
    (960x540 -> 741x417, RGB: 0.6 against 4.2 ms). A factor between 1/2 and 1 with no block mean before it is
    bilinear too: each output pixel then blends the 2 x 2 input pixels around it, which at such a mild reduction
    differs from the area mean by a fraction of a grey level (0.25 on average on a real 1080p street frame shrunk to
    0.53), while OpenCV's general area path costs 11 ms on that frame against 1.9 ms. Pixel centres map as
    ``(p + 0.5) * factor - 0.5`` either way (cv2.resize's geometry).
    """
    h, w = image.shape[:2]
    size = (int(size[0]), int(size[1]))
    if (w, h) == size:
        return image
    factor = size[0] / w
    k = next((k for k in range(int(1.0 / factor + 1e-9), 1, -1) if w % k == 0 and h % k == 0), 1)
    if k > 1:
        image = cv2.resize(image, (w // k, h // k), interpolation=cv2.INTER_AREA)
        if image.shape[1::-1] == size:
            return image
    remaining = size[0] / image.shape[1]
    return cv2.resize(image, size, interpolation=cv2.INTER_LINEAR if remaining >= 0.5 else cv2.INTER_AREA)


def decode_reduction(size: tuple[int, int], target: tuple[int, int]) -> int:
    """The largest factor k of 2, 4, 8 by which a JPEG decoder can shrink frames of ``size`` (w, h) while they stay
    at least ``target`` on both sides (1: none): libjpeg's DCT scaling decodes 1/k of the pixels for a fraction of
    the time (a 1920x1080 frame at 1/2: 6.6 ms against 14 ms here). Only factors that divide both sides, so that
    the reduced frame keeps the block-mean geometry of :func:`block_mean` exactly."""
    return next((k for k in (8, 4, 2) if size[0] % k == 0 and size[1] % k == 0
                 and size[0] // k >= target[0] and size[1] // k >= target[1]), 1)


def _ends_with_eoi(data: bytes) -> bool:
    """Whether a JPEG file's bytes end with its end-of-image marker (``FF D9``, padding zeros allowed after it)."""
    return data[-64:].rstrip(b"\0").endswith(b"\xff\xd9")


_REDUCED = {2: (cv2.IMREAD_REDUCED_COLOR_2, cv2.IMREAD_REDUCED_GRAYSCALE_2),
            4: (cv2.IMREAD_REDUCED_COLOR_4, cv2.IMREAD_REDUCED_GRAYSCALE_4),
            8: (cv2.IMREAD_REDUCED_COLOR_8, cv2.IMREAD_REDUCED_GRAYSCALE_8)}


def read_frame(path: str | os.PathLike, *, grey: bool = False, luma: bool = False, reduce: int = 1) -> np.ndarray:
    """One frame of a frame folder: :func:`read_image`'s result, decoded by libjpeg-turbo directly when the file is a
    JPEG (:func:`rgbt_toolkit.io.jpeg.decode_jpeg`, else OpenCV's decoder).

    Why: a 1920x1080 JPEG takes imageio/Pillow about four times as long as OpenCV's decoder and OpenCV twice as long
    as ``simplejpeg`` (the same libjpeg-turbo pixels, compared to the bit on real frames), which on folders of
    full-HD frames is most of a tracker's time per frame. ``luma`` (a grey picture stored as colour, see
    :func:`is_grey_picture`) decodes only the JPEG's luma component, which equals every
    channel of such a picture. A JPEG that does not end with its end-of-image marker (a truncated file) and anything
    but 8-bit grey or RGB goes through :func:`read_image`, whose errors name the file.

    ``reduce`` (2, 4 or 8; :func:`decode_reduction`): the frame shrunk by that whole factor, decoded at that size by
    libjpeg's DCT scaling (a colour JPEG comes out as RGB even if it held one component), other files decoded whole
    and shrunk by :func:`block_mean`.
    """
    path = Path(path)
    if reduce not in (1, *_REDUCED):
        raise ValueError(f"reduce must be 1, 2, 4 or 8, got {reduce}")
    data = path.read_bytes() if path.suffix.lower() in (".jpg", ".jpeg") and path.is_file() else None
    if data is None or not _ends_with_eoi(data):
        return block_mean(read_image(path, grey=grey or luma), reduce)
    image = decode_jpeg(data, luma=luma, reduce=reduce)
    if image is not None:
        return rgb_to_grey(image) if grey and image.ndim == 3 else image
    if reduce > 1:
        flags = _REDUCED[reduce][1 if luma else 0] | cv2.IMREAD_IGNORE_ORIENTATION
    else:  # (no EXIF turn)
        flags = cv2.IMREAD_GRAYSCALE | cv2.IMREAD_IGNORE_ORIENTATION if luma else cv2.IMREAD_UNCHANGED
    image = cv2.imdecode(np.frombuffer(data, np.uint8), flags)
    if image is None or image.dtype != np.uint8 or (image.ndim == 3 and image.shape[2] != 3):
        return block_mean(read_image(path, grey=grey or luma), reduce)
    if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
        if grey:
            image = rgb_to_grey(image)
    return image


_GREY_WEIGHTS = np.array([[0.298936021293775, 0.587043074451121, 0.114020904255103]])  # MATLAB rgb2gray


def rgb_to_grey(image: np.ndarray) -> np.ndarray:
    """MATLAB ``rgb2gray``: 0.2989 R + 0.5870 G + 0.1140 B, rounded, same dtype as the input."""
    rgb = np.ascontiguousarray(image[..., :3], dtype=np.float64)
    if rgb.ndim == 3:
        # OpenCV's weighted sum of an image's channels gives the float64 sum `rgb @ weights` gives (tested to the
        # bit on random frames) 3x faster: the camera-motion trigger converts a frame pair on every tracked frame
        grey = cv2.transform(rgb, _GREY_WEIGHTS).reshape(rgb.shape[:2])
    else:
        grey = rgb @ _GREY_WEIGHTS[0]
    if np.issubdtype(image.dtype, np.integer):
        info = np.iinfo(image.dtype)
        return np.clip(np.round(grey), info.min, info.max).astype(image.dtype)
    return grey.astype(image.dtype)


def write_image(path: str | os.PathLike, image: np.ndarray) -> None:
    """Write ``image`` (RGB order for colour) atomically; the format comes from the suffix."""
    with atomic_path(path) as tmp:
        iio.imwrite(tmp, np.ascontiguousarray(image), extension=Path(path).suffix.lower())
