"""Input pixels of fusion and tracking: non-8-bit images are stretched by their used range, never divided by 257 or
clipped; a recording is mapped with one range (FixedRange) that only widens."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.pixels import FixedRange, as_uint8, used_range


def _ramp(lo: float, hi: float, dtype) -> np.ndarray:
    return np.linspace(lo, hi, 200 * 50).reshape(50, 200).astype(dtype)


def test_sixteen_bit_thermal_is_stretched_by_its_used_range():
    # a radiometric sensor using counts 7000..9000: /257 would give a flat grey 27..35
    out = as_uint8(_ramp(7000, 9000, np.uint16), "ir16.png")
    assert out.dtype == np.uint8 and out.min() == 0 and out.max() == 255
    assert np.all(np.diff(out[:, ::20].ravel().astype(int)) >= 0)  # monotone: order of temperatures kept


def test_float_celsius_and_float_0_255_are_stretched_not_saturated():
    celsius = as_uint8(_ramp(15.0, 40.0, np.float32), "ir.tif")
    assert celsius.min() == 0 and celsius.max() == 255 and 100 < celsius.mean() < 155  # was all 255 (clipped)
    on_255 = as_uint8(_ramp(0.0, 255.0, np.float32), "v.tif")
    assert on_255.min() == 0 and on_255.max() == 255 and 100 < on_255.mean() < 155
    # the same scene in counts, in degrees and in integers gives the same 8-bit image
    assert np.abs(celsius.astype(int) - as_uint8(_ramp(7000, 9000, np.uint16), "x").astype(int)).max() <= 1


def test_float_in_unit_range_is_scaled_by_255_and_8_bit_passes_through():
    assert as_uint8(np.full((4, 4), 0.5, np.float32), "x").max() == 128
    u8 = np.arange(16, dtype=np.uint8).reshape(4, 4)
    assert as_uint8(u8, "x") is u8


def test_outliers_do_not_decide_the_range():
    img = _ramp(7000, 9000, np.uint16)
    img[0, :5] = 65535  # five hot pixels: 0.05 % of the image
    out = as_uint8(img, "x")
    assert 100 < out[1:].mean() < 155


def test_dead_pixels_become_dark_and_all_nan_is_refused():
    img = _ramp(15.0, 40.0, np.float32)
    img[10, 10] = np.nan
    img[11, 11] = np.inf
    out = as_uint8(img, "x")
    assert out[10, 10] == 0 and out[11, 11] == 0 and out.max() == 255
    with pytest.raises(InputError, match="a.tif: no finite pixel"):
        as_uint8(np.full((4, 4), np.nan, np.float32), "a.tif")


def test_channels_alpha_dropped_and_bool_and_int32():
    grey_alpha = np.stack([np.full((4, 4), 77, np.uint8), np.full((4, 4), 255, np.uint8)], axis=2)
    assert as_uint8(grey_alpha, "la.png").shape == (4, 4) and as_uint8(grey_alpha, "x").max() == 77
    assert as_uint8(np.zeros((4, 4, 4), np.uint8), "x").shape == (4, 4, 3)
    assert set(np.unique(as_uint8(np.eye(4, dtype=bool), "x"))) == {0, 255}
    assert as_uint8(_ramp(0, 25500, np.int32), "x").max() == 255
    assert as_uint8(np.full((4, 4), 9000, np.uint16), "x").max() == 128  # constant: mid-grey, no division by 0
    with pytest.raises(InputError, match="v.png: expected a grey, grey\\+alpha, RGB or RGBA image"):
        as_uint8(np.zeros((4, 4, 5), np.uint8), "v.png")
    with pytest.raises(InputError, match="c.npy: unsupported pixel type complex64"):
        as_uint8(np.zeros((4, 4), np.complex64), "c.npy")


def test_colour_is_stretched_with_one_range_for_all_channels():
    rgb = np.stack([_ramp(1000, 3000, np.uint16), _ramp(2000, 4000, np.uint16), _ramp(3000, 5000, np.uint16)], 2)
    out = as_uint8(rgb, "x").astype(int)
    assert (out[..., 2] >= out[..., 0]).all() and out[..., 2].mean() - out[..., 0].mean() > 100


def test_a_given_range_replaces_the_images_own():
    counts = _ramp(7000, 8000, np.uint16)
    out = as_uint8(counts, "x", value_range=(6000.0, 10000.0))
    assert abs(int(out.min()) - 64) <= 1 and abs(int(out.max()) - 128) <= 1  # (7000-6000)/4000 * 255 = 63.75
    assert used_range(counts) == pytest.approx((7005, 7995), abs=1)


def test_one_range_for_a_recording_set_by_its_first_frame_with_contrast():
    to_8bit = FixedRange("t.mkv")
    shutter = np.full((50, 200), 7000, np.uint16)
    assert to_8bit(shutter).max() == 128 and to_8bit.value_range is None  # no contrast: sets nothing
    first = to_8bit(_ramp(7000, 9000, np.uint16))
    assert 15 <= first.min() < first.max() <= 240  # 10 % headroom on either side
    warmer = to_8bit(_ramp(7100, 9100, np.uint16))
    assert np.median(warmer.astype(int) - first.astype(int)) == pytest.approx(10.6, abs=1.5)  # not re-stretched


def test_the_range_widens_for_drift_instead_of_saturating():
    to_8bit = FixedRange("t.mkv")
    to_8bit(_ramp(7000, 9000, np.uint16))
    drifted = to_8bit(_ramp(7800, 9800, np.uint16))  # an offset jump after a flat-field correction: 30 % above
    assert np.mean(drifted == 255) < 0.01
    low, high = to_8bit.value_range
    assert low <= 7000 and high >= 9800


def test_frames_without_finite_pixels_alpha_and_inf_dead_pixels():
    to_8bit = FixedRange("t")
    with np.errstate(all="raise"):  # no warning either
        assert to_8bit(np.full((4, 4), np.nan, np.float32)).max() == 0 and to_8bit.value_range is None
    grey_alpha = np.stack([_ramp(7000, 9000, np.uint16), np.full((50, 200), 65535, np.uint16)], axis=2)
    out = FixedRange("t")(grey_alpha)
    assert out.shape == (50, 200) and out.max() - out.min() > 180  # the alpha channel sets no range
    half = _ramp(0.0, 0.5, np.float32)
    half[0, 0] = -np.inf  # a dead pixel: floats in [0, 1] are still scaled by 255, as as_uint8 does
    assert FixedRange("t")(half).max() == as_uint8(half).max() == 128
