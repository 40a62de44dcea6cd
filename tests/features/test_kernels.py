"""The compiled feature loops (rgbt_toolkit/features/_kernels.c) against their numpy definitions."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rgbt_toolkit.features import _kernels
from rgbt_toolkit.features.fhog import _gradients, fhog_from_histograms, orientation_votes
from rgbt_toolkit.features.pooling import cell_centres, cells_at_scales, pixel_prefilter, sample_map, tent_cells
from tests.features import numpy_reference as ref


def _textured_patch(size: int, seed: int) -> np.ndarray:
    """A smooth blob scene with flat areas (ties between colour channels) and noise: every branch of the loops."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[:size, :size].astype(np.float32)
    base = 120 + 80 * np.sin(xx / 9.0) * np.cos(yy / 13.0)
    patch = np.stack([base, base, 255 - base], axis=-1) + rng.normal(0, 6, (size, size, 3))
    patch[: size // 4, : size // 4] = 128  # flat: all three channels tie
    return np.clip(patch, 0, 255).astype(np.uint8)


@pytest.mark.parametrize("map_stride", [1, 4])
def test_cell_reads_are_bit_identical_to_numpy(map_stride):
    rng = np.random.default_rng(1)
    fmap = rng.random((67, 61, 13), dtype=np.float32)
    ratios = np.array([0.94, 1.0, 1.062])
    rows = np.stack([cell_centres(63, 4, 252, r, 268) for r in ratios])
    cols = rows[:, :50] - 7.3  # other columns, some left of the map (clamped)
    got = sample_map(fmap, map_stride, rows, cols)
    want = ref.sample_map(fmap, map_stride, rows, cols)
    assert got.shape == (3, 63, 50, 13)
    np.testing.assert_array_equal(got, want)


def test_tent_blur_at_the_reads_equals_blurring_the_whole_map_first():
    rng = np.random.default_rng(2)
    fmap = rng.random((67, 61, 13), dtype=np.float32)
    rows = np.stack([cell_centres(63, 4, 252, r, 268) for r in (0.94, 1.0)]) / 4 + 0.3  # fractional, both borders
    cols = rows[:, :50] - 7.3  # other columns, some left of the map (clamped)
    want = sample_map(pixel_prefilter(fmap), 1, rows, cols)
    got = tent_cells(fmap, rows, cols)
    assert got.shape == (2, 63, 50, 13)
    np.testing.assert_allclose(got, want, rtol=2e-6, atol=1e-7)  # the same sums in another order
    # a one-scale cell map of the ECO path takes this route, several scales the whole-map blur; both agree
    one = cells_at_scales(fmap, 1, 4, 60, np.array([1.0]), 61)
    np.testing.assert_allclose(one, cells_at_scales(fmap, 1, 4, 60, np.array([1.0, 1.01]), 61)[:1], rtol=2e-6,
                               atol=1e-7)
    with pytest.raises(ValueError, match="fmap"):
        _kernels.tent_cells(fmap, 68, 61, 13, rows, cols, 2, 63, 50, np.empty_like(got))


def test_orientation_votes_are_bit_identical_to_numpy():
    patch = _textured_patch(96, 2)
    gx = cv2.Sobel(patch, cv2.CV_32F, 1, 0, ksize=1, scale=0.5)
    gy = cv2.Sobel(patch, cv2.CV_32F, 0, 1, ksize=1, scale=0.5)
    want_gx, want_gy = ref.strongest_gradient(gx, gy)
    mag, theta = _gradients(patch[None])
    want_mag, want_theta = cv2.cartToPolar(want_gx, want_gy)
    np.testing.assert_array_equal(mag[0], want_mag)
    np.testing.assert_array_equal(theta[0], want_theta)
    votes = orientation_votes(patch)
    np.testing.assert_array_equal(votes, ref.orientation_votes(mag[0], theta[0]))
    assert np.count_nonzero(votes, axis=-1).max() == 2  # each pixel votes into two neighbouring bins


def test_grey_patch_votes_match_numpy():
    patch = _textured_patch(64, 3)[..., 0]
    mag, theta = _gradients(patch[None])
    np.testing.assert_array_equal(orientation_votes(patch), ref.orientation_votes(mag[0], theta[0]))


def test_fhog_matches_numpy():
    patch = _textured_patch(128, 4)
    centres = np.stack([cell_centres(32, 4, 128, r, 128) for r in (1.0, 1.03)])
    hist = sample_map(pixel_prefilter(orientation_votes(patch)), 1, centres)
    got, want = fhog_from_histograms(hist), ref.fhog_from_histograms(hist)
    np.testing.assert_array_equal(got[..., :27], want[..., :27])  # same operations in the same order
    np.testing.assert_allclose(got[..., 27:], want[..., 27:], rtol=1e-6, atol=1e-7)  # numpy summed these by BLAS
    assert got[..., :27].max() <= 0.2 * 2 + 1e-6 and (got[..., :18] > 0).mean() > 0.5


def test_kernels_refuse_buffers_that_do_not_fit_the_shape():
    fmap = np.zeros((4, 4, 2), np.float32)
    pos = np.zeros((1, 3))
    out = np.empty((1, 3, 3, 2), np.float32)
    with pytest.raises(ValueError, match="fmap"):
        _kernels.bilinear_cells(fmap, 5, 4, 2, pos, pos, 1, 3, 3, out)
    with pytest.raises(ValueError, match="out"):
        _kernels.bilinear_cells(fmap, 4, 4, 2, pos, pos, 1, 3, 3, np.empty(5, np.float32))
    with pytest.raises(ValueError, match="18-bin"):
        fhog_from_histograms(np.zeros((1, 3, 3, 9), np.float32))


def test_an_unbuilt_compiled_module_is_one_clear_error(monkeypatch):
    import importlib
    import sys

    from rgbt_toolkit.errors import MissingDependencyError

    import rgbt_toolkit.features

    monkeypatch.setitem(sys.modules, "rgbt_toolkit.features._kernels", None)  # as if the .so were absent
    monkeypatch.delattr(rgbt_toolkit.features, "_kernels")
    monkeypatch.delitem(sys.modules, "rgbt_toolkit.features.native")
    with pytest.raises(MissingDependencyError, match="not built.*pip install"):
        importlib.import_module("rgbt_toolkit.features.native")


def test_votes_of_impossible_angles_stay_inside_their_row():
    # cv2.cartToPolar never returns these; the kernel must still not write outside a pixel's 18 bins
    theta = np.array([np.nan, -1.0, 100.0, 2 * np.pi], np.float32)
    out = np.full((6, 18), 7.0, np.float32)
    _kernels.orientation_votes(np.ones(4, np.float32), theta, 4, out[1:5])
    np.testing.assert_array_equal(out[[0, 5]], 7.0)  # neighbours untouched
    np.testing.assert_allclose(out[1:5].sum(axis=1), 1.0)
