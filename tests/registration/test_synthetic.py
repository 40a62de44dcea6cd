"""Warped test pairs: the crop and the matching box of the unwarped image."""

import numpy as np

from rgbt_toolkit.registration.synthetic import random_similarity, same_content_box, warp_and_crop
from rgbt_toolkit.registration.transforms import project


def test_crop_holds_only_warped_pixels_and_truth_maps_into_it():
    rng = np.random.default_rng(3)
    image = rng.integers(1, 255, (240, 320), dtype=np.uint8)  # no zeros: a zero in the crop is a border pixel
    truth_warp = random_similarity(rng, (320, 240))
    crop, truth = warp_and_crop(image, truth_warp)
    assert crop.min() > 0
    assert crop.shape[0] * crop.shape[1] > 0.3 * image.size
    # every crop pixel is the source sampled where the inverse truth sends it (bilinear, as warpPerspective does)
    import cv2

    ys, xs = np.mgrid[0:crop.shape[0]:17, 0:crop.shape[1]:17]
    points = np.stack([xs.ravel(), ys.ravel()], 1).astype(float)
    source = project(np.linalg.inv(truth), points).astype(np.float32)
    sampled = cv2.remap(image, source[:, 0].reshape(1, -1), source[:, 1].reshape(1, -1), cv2.INTER_LINEAR)[0]
    assert np.abs(sampled.astype(int) - crop[ys.ravel(), xs.ravel()].astype(int)).max() <= 1


def test_same_content_box_sees_what_the_crop_sees():
    rng = np.random.default_rng(4)
    image = rng.integers(1, 255, (240, 320), dtype=np.uint8)
    for _ in range(5):
        crop, truth = warp_and_crop(image, random_similarity(rng, (320, 240)))
        x0, y0, x1, y1 = same_content_box(truth, image.shape, crop.shape)
        assert 0 <= x0 < x1 <= 320 and 0 <= y0 < y1 <= 240
        corners = np.array([[x0, y0], [x1 - 1, y0], [x1 - 1, y1 - 1], [x0, y1 - 1]], float)
        inside = project(truth, corners)
        h, w = crop.shape
        assert np.all(inside >= -1.0) and np.all(inside[:, 0] <= w) and np.all(inside[:, 1] <= h)
        # and it is not a token box: at least half of what the crop shows
        assert (x1 - x0) * (y1 - y0) > 0.5 * w * h / abs(np.linalg.det(truth[:2, :2]))


def test_pure_shift_gives_the_shifted_window():
    image = np.full((100, 200), 7, np.uint8)
    shift = np.array([[1, 0, 20.0], [0, 1, 10.0], [0, 0, 1]])
    crop, truth = warp_and_crop(image, shift)
    x0, y0, x1, y1 = same_content_box(truth, image.shape, crop.shape)
    # the crop shows source x in [0, 180), y in [0, 90) at most; the box lies within and is nearly that large
    assert x0 >= 0 and y0 >= 0 and x1 <= 181 and y1 <= 91
    assert (x1 - x0) >= 0.85 * crop.shape[1] and (y1 - y0) >= 0.85 * crop.shape[0]
