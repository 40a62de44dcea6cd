"""Frame-folder JPEGs: ``decode_jpeg`` (simplejpeg) against OpenCV's decoder, to the bit, in every mode
``read_frame`` asks for."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image

from rgbt_toolkit.errors import FileFormatError
from rgbt_toolkit.io.images import read_frame, rgb_to_grey
from rgbt_toolkit.io.jpeg import decode_jpeg

SHARED = Path(__file__).resolve().parents[3] / "shared" / "data"
_REDUCED = {1: (cv2.IMREAD_UNCHANGED, cv2.IMREAD_GRAYSCALE),
            2: (cv2.IMREAD_REDUCED_COLOR_2, cv2.IMREAD_REDUCED_GRAYSCALE_2),
            4: (cv2.IMREAD_REDUCED_COLOR_4, cv2.IMREAD_REDUCED_GRAYSCALE_4),
            8: (cv2.IMREAD_REDUCED_COLOR_8, cv2.IMREAD_REDUCED_GRAYSCALE_8)}


def opencv_decode(data: bytes, *, luma: bool, reduce: int) -> np.ndarray:
    image = cv2.imdecode(np.frombuffer(data, np.uint8), _REDUCED[reduce][luma] | cv2.IMREAD_IGNORE_ORIENTATION)
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB) if image.ndim == 3 else image


def textured(width: int, height: int, seed: int) -> np.ndarray:
    """Smooth colour gradients under noise and sharp edges: every DCT band and both chroma planes carry signal."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:height, 0:width]
    base = np.stack([x * 255 / width, y * 255 / height, (x + y) % 97 * 2.6], axis=-1)
    base[(x // 23 + y // 17) % 2 == 0] *= 0.4
    return np.clip(base + rng.normal(0, 18, base.shape), 0, 255).astype(np.uint8)


ENCODINGS = {
    "420": [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_420],
    "422": [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_422],
    "444": [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_444],
    "411": [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_411],
    "progressive": [cv2.IMWRITE_JPEG_PROGRESSIVE, 1, cv2.IMWRITE_JPEG_QUALITY, 70],
    "restart markers": [cv2.IMWRITE_JPEG_RST_INTERVAL, 4, cv2.IMWRITE_JPEG_QUALITY, 97],
}


@pytest.mark.parametrize("encoding", list(ENCODINGS))
@pytest.mark.parametrize("size", [(333, 217), (640, 512)])
def test_colour_jpegs_decode_to_opencvs_pixels(encoding, size):
    ok, buffer = cv2.imencode(".jpg", textured(*size, seed=len(encoding)), ENCODINGS[encoding])
    data = buffer.tobytes()
    for reduce in (1, 2, 4, 8):
        for luma in (False, True):
            ours = decode_jpeg(data, luma=luma, reduce=reduce)
            np.testing.assert_array_equal(ours, opencv_decode(data, luma=luma, reduce=reduce),
                                          err_msg=f"{encoding} {size} 1/{reduce} luma={luma}")


def test_grey_jpegs_decode_as_opencv_does_flat_whole_and_colour_reduced():
    ok, buffer = cv2.imencode(".jpg", textured(301, 199, seed=3)[..., 1])
    data = buffer.tobytes()
    assert decode_jpeg(data).ndim == 2
    assert decode_jpeg(data, reduce=2).shape == (100, 151, 3)
    for reduce in (1, 2, 4, 8):
        for luma in (False, True):
            np.testing.assert_array_equal(decode_jpeg(data, luma=luma, reduce=reduce),
                                          opencv_decode(data, luma=luma, reduce=reduce))


def test_files_it_does_not_take_are_left_to_opencv_and_named_in_errors(tmp_path):
    cmyk = tmp_path / "cmyk.jpg"
    Image.fromarray(textured(64, 48, seed=5)).convert("CMYK").save(cmyk)
    assert decode_jpeg(cmyk.read_bytes()) is None
    assert read_frame(cmyk).shape == (48, 64, 3)  # OpenCV converts it, as before
    assert decode_jpeg(b"not a jpeg at all") is None
    ok, buffer = cv2.imencode(".jpg", textured(64, 48, seed=6))
    broken = bytearray(buffer.tobytes())
    broken[400:460] = b"\0" * 60  # entropy-coded data zeroed: header and end marker intact
    (tmp_path / "broken.jpg").write_bytes(bytes(broken))
    assert decode_jpeg(bytes(broken)) is None
    with pytest.raises(FileFormatError, match="broken.jpg"):
        read_frame(tmp_path / "broken.jpg")


def test_streams_libjpeg_only_warns_about_decode_as_opencv_decodes_them():
    ok, buffer = cv2.imencode(".jpg", textured(160, 120, seed=8))
    good = buffer.tobytes()
    extraneous = good[:-2] + b"\x00\x00\x00" + good[-2:]  # bytes before the end-of-image marker
    scan = good.index(b"\xff\xda")
    damaged = bytearray(good)
    damaged[scan + 400:scan + 420] = bytes(range(17, 37))  # garbage inside the entropy-coded data
    for data in (extraneous, bytes(damaged)):
        for reduce in (1, 2):
            ours = decode_jpeg(data, reduce=reduce)
            assert ours is not None
            np.testing.assert_array_equal(ours, opencv_decode(data, luma=False, reduce=reduce))


def test_read_frame_greys_a_colour_jpeg_as_before(tmp_path):
    path = tmp_path / "frame.jpg"
    cv2.imwrite(str(path), textured(160, 120, seed=7))
    for reduce in (1, 2):
        expected = rgb_to_grey(opencv_decode(path.read_bytes(), luma=False, reduce=reduce))
        np.testing.assert_array_equal(read_frame(path, grey=True, reduce=reduce), expected)


@pytest.mark.skipif(not SHARED.is_dir(), reason="needs ../shared/data")
def test_real_jpegs_decode_to_opencvs_pixels():
    files = sorted(SHARED.glob("fusion/roadscene/*/*.jpg"))[:20] + sorted(SHARED.glob("fusion/vifb/*/*.jpg"))[:10]
    files += sorted(SHARED.glob("tracking/sequences/*/img/*.jpg"))[:5]
    if not files:
        pytest.skip("no JPEGs in ../shared/data")
    for path in files:
        data = path.read_bytes()
        for reduce in (1, 2):
            for luma in (False, True):
                np.testing.assert_array_equal(decode_jpeg(data, luma=luma, reduce=reduce),
                                              opencv_decode(data, luma=luma, reduce=reduce), err_msg=str(path))
