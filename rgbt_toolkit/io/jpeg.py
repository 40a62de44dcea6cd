"""Frame-folder JPEGs decoded by libjpeg-turbo through ``simplejpeg``, the pixels OpenCV's decoder gives.

Why not OpenCV: on the 1920x1080 JPEG frames of ``benchmarks/bench_speed_real.py`` OpenCV's ``imread`` takes
9.4 ms whole and 5.2 ms at half size (its conversion to RGB included), ``simplejpeg`` 4.2 and 3.2 ms, and a frame
folder of two cameras decodes two such files per frame. Both run libjpeg-turbo's accurate integer IDCT and its
smooth chroma upsampling, so the pixels are the same to the bit (``tests/io/test_jpeg.py`` compares them on
generated JPEGs of every chroma layout, progressive, grey and damaged ones, and on real frames of ``../shared``); the
GIL is released while a file decodes, so the read-ahead's two workers decode two files at once.
"""

from __future__ import annotations

import numpy as np
import simplejpeg


def decode_jpeg(data: bytes, *, luma: bool = False, reduce: int = 1) -> np.ndarray | None:
    """A JPEG file's bytes as OpenCV's ``imread`` would give them, in RGB order; None when this decoder does not
    take the file (CMYK, a header it cannot read: the caller's OpenCV path then decodes it, and its errors name the
    file).

    Like ``imread``: a colour file gives H x W x 3 (``luma``: its luma component alone, H x W), a grey file H x W at
    full size and H x W x 3 when reduced (``IMREAD_REDUCED_COLOR_k`` converts it); ``reduce`` (1, 2, 4 or 8)
    decodes at ceil(W / k) x ceil(H / k) by libjpeg's DCT scaling, without the EXIF orientation applied.
    """
    try:
        height, width, colourspace, _ = simplejpeg.decode_jpeg_header(data)
    except ValueError:
        return None
    if colourspace not in ("Gray", "YCbCr", "RGB"):
        return None
    out_h, out_w = -(-height // reduce), -(-width // reduce)
    flat = luma or (reduce == 1 and colourspace == "Gray")
    try:
        # strict=False: a stream libjpeg only warns about (extraneous bytes, a damaged scan) decodes as OpenCV decodes
        # it, instead of failing and being decoded twice
        image = simplejpeg.decode_jpeg(data, "GRAY" if flat else "RGB", min_height=out_h, min_width=out_w,
                                       strict=False)
    except ValueError:
        return None
    if image.shape[:2] != (out_h, out_w):  # a scale other than 1/reduce (never seen; OpenCV's size is the contract)
        return None
    return image[..., 0] if flat else image
