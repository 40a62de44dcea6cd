"""The MATLAB medfilt2 / imresize reproductions the camera-motion trigger depends on."""

import numpy as np
import scipy.ndimage as ndi
from PIL import Image

from rgbt_toolkit.motion._matlab import imresize_bicubic, imresize_weights, medfilt2_zero


def test_medfilt2_pads_with_zeros_like_matlab():
    # scipy's constant-mode median is an independent implementation of MATLAB's default 'zeros' padding
    img = np.random.default_rng(0).integers(0, 256, (61, 83)).astype(np.uint8)
    np.testing.assert_array_equal(medfilt2_zero(img, 9), ndi.median_filter(img, size=9, mode="constant", cval=0))


def test_medfilt2_differs_from_replicated_border():
    img = np.full((20, 20), 200, np.uint8)
    out = medfilt2_zero(img, 9)
    assert out[0, 0] == 0  # corner window: 56 of 81 samples are padding zeros
    assert out[10, 10] == 200


def test_imresize_matches_pillow_antialiased_bicubic_inside():
    # Pillow's BICUBIC (a = -0.5, support widened by the scale) is the same kernel; edges differ (Pillow renormalises,
    # MATLAB reflects), so compare away from the border
    img = np.random.default_rng(1).uniform(0, 255, (480, 640))
    ours = imresize_bicubic(img, (40, 40))
    pil = np.asarray(Image.fromarray(img.astype(np.float32), "F").resize((40, 40), Image.BICUBIC))
    np.testing.assert_allclose(ours[3:-3, 3:-3], pil[3:-3, 3:-3], atol=1e-3)


def test_imresize_weights_are_normalised_and_keep_constants():
    w = imresize_weights(480, 40)
    np.testing.assert_allclose(w.sum(axis=1), 1.0)
    np.testing.assert_allclose(imresize_bicubic(np.full((50, 70), 7.5), (40, 40)), 7.5)
