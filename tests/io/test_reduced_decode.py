"""Frame folders decoded no larger than the tracker needs (:meth:`FrameSource.deliver_at`): JPEGs at 1/2, 1/4, 1/8
size by libjpeg, other files shrunk after decoding; the same picture and pixel geometry as shrinking the whole frame,
files read ahead on two threads in order, and errors still naming the file."""

from __future__ import annotations

import threading
import warnings

import cv2
import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.frames import CorruptFrameWarning, open_frames
from rgbt_toolkit.io.images import block_mean, decode_reduction, read_frame, shrink_to


def _scene(height: int = 240, width: int = 320, seed: int = 0) -> np.ndarray:
    yy, xx = np.mgrid[:height, :width]
    base = 128 + 90 * np.sin(xx / 9.0 + seed) * np.cos(yy / 7.0)
    return np.stack([base, 255 - base, np.roll(base, 5, axis=1)], axis=-1).clip(0, 255).astype(np.uint8)


def _folder(tmp_path, count: int = 8, suffix: str = ".jpg", grey: bool = False):
    folder = tmp_path / ("grey" if grey else "rgb")
    folder.mkdir()
    frames = []
    for k in range(count):
        image = _scene(seed=k)
        if grey:
            image = np.repeat(image[..., :1], 3, axis=2)  # a grey picture stored as colour, as thermal cameras do
        cv2.imwrite(str(folder / f"{k:04d}{suffix}"), image[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 95])
        frames.append(image)
    return folder, frames


def test_reduction_factors_keep_the_frame_at_least_the_target_and_divide_its_sides():
    assert decode_reduction((1920, 1080), (807, 454)) == 2
    assert decode_reduction((1920, 1080), (400, 200)) == 4
    assert decode_reduction((1920, 1080), (200, 120)) == 8
    assert decode_reduction((1920, 1080), (1000, 454)) == 1
    assert decode_reduction((1922, 1080), (400, 200)) == 2  # 1922 / 4 is not whole: the block geometry would slip


@pytest.mark.parametrize("reduce", [2, 4, 8])
def test_a_reduced_jpeg_is_the_block_mean_of_the_whole_frame(tmp_path, reduce):
    folder, _ = _folder(tmp_path, 1)
    path = next(folder.iterdir())
    whole = read_frame(path)
    small = read_frame(path, reduce=reduce)
    assert small.shape == (240 // reduce, 320 // reduce, 3) and small.dtype == np.uint8
    # libjpeg's DCT scaling and a block mean of the decoded pixels see the same picture (JPEG rounding apart)
    assert np.abs(small.astype(float) - block_mean(whole, reduce)).mean() < 2.0
    grey = read_frame(path, luma=True, reduce=reduce)
    assert grey.shape == (240 // reduce, 320 // reduce)


def test_other_formats_are_shrunk_after_decoding_and_bad_factors_refused(tmp_path):
    folder, frames = _folder(tmp_path, 1, suffix=".png")
    path = next(folder.iterdir())
    np.testing.assert_array_equal(read_frame(path, reduce=2), block_mean(frames[0], 2))
    with pytest.raises(ValueError, match="reduce must be"):
        read_frame(path, reduce=3)


def test_a_folder_delivered_at_a_working_size(tmp_path):
    folder, frames = _folder(tmp_path)
    source = open_frames(folder, fixed_size=True)
    iterator = iter(source)
    first, _ = next(iterator)  # read before the size was asked for: as decoded
    assert first.shape == (240, 320, 3)
    source.deliver_at((150, 112))
    rest = [frame for frame, _ in iterator]
    assert len(rest) == len(frames) - 1
    for frame, truth in zip(rest, frames[1:]):
        assert frame.shape == (112, 150, 3)
        assert np.abs(frame.astype(float) - shrink_to(truth, (150, 112))).mean() < 2.5
    with pytest.raises(ValueError, match="cannot be delivered at 400x200"):
        source.deliver_at((400, 200))


def test_a_grey_folder_stays_grey_when_reduced(tmp_path):
    folder, frames = _folder(tmp_path, grey=True)
    source = open_frames(folder, auto_grey=True)
    source.deliver_at((160, 120))
    out = [frame for frame, _ in source]
    assert all(frame.shape == (120, 160) for frame in out)
    assert np.abs(out[3].astype(float) - shrink_to(frames[3][..., 0], (160, 120))).mean() < 2.0


def test_a_frame_of_another_size_is_named_at_reduced_size_too(tmp_path):
    folder, _ = _folder(tmp_path, 6)
    cv2.imwrite(str(folder / "0004.jpg"), _scene(200, 320)[..., ::-1])
    source = open_frames(folder, fixed_size=True)
    source.deliver_at((160, 120))
    with pytest.raises(InputError, match=r"0004.jpg: 160x100 at 1/2 size, the other frames are 320x240"):
        list(source)


def test_read_ahead_keeps_order_skips_a_corrupt_file_and_leaves_no_thread(tmp_path):
    folder, frames = _folder(tmp_path, 10)
    (folder / "0005.jpg").write_bytes(b"\xff\xd8not a jpeg\xff\xd9")
    source = open_frames(folder, keep_gaps=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = list(source)
    assert any(issubclass(w.category, CorruptFrameWarning) and "0005.jpg" in str(w.message) for w in caught)
    assert [frame is None for frame, _ in out] == [k == 5 for k in range(10)]
    for k, (frame, t) in enumerate(out):
        assert t == pytest.approx(k / source.fps)
        if frame is not None:
            assert np.abs(frame.astype(float) - frames[k]).mean() < 2.0
    # a consumer that stops early closes the generator: its workers end with it
    iterator = iter(open_frames(folder))
    next(iterator), next(iterator)
    iterator.close()
    assert not [t for t in threading.enumerate() if t.name.startswith("rgbt-frame-read")]
