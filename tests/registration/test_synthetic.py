"""Warped test pairs: the crop and the matching box of the unwarped image."""

import numpy as np
import pytest

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


def test_rig_homography_is_a_pure_rotation_of_the_camera():
    # K R K^-1 for yaw only: the principal row stays on its line (y unchanged at the centre row), points move right
    # by f tan(yaw) at the centre, and the perspective term is -sin(yaw) / (f cos(yaw) + cx sin(yaw)) (normalised so
    # that h22 = 1) in x and zero in y
    from rgbt_toolkit.registration.synthetic import rig_homography

    w, h = 640, 480
    matrix = rig_homography((w, h), hfov_deg=60.0, yaw_deg=1.5, pitch_deg=0.0)
    f = (w / 2) / np.tan(np.deg2rad(30.0))
    centre = np.array([[(w - 1) / 2, (h - 1) / 2]])
    moved = project(matrix, centre)[0]
    assert moved[0] - centre[0, 0] == pytest.approx(f * np.tan(np.deg2rad(1.5)), rel=1e-6)
    assert moved[1] == pytest.approx(centre[0, 1], abs=1e-9)
    yaw = np.deg2rad(1.5)
    assert matrix[2, 0] == pytest.approx(-np.sin(yaw) / (f * np.cos(yaw) + (w - 1) / 2 * np.sin(yaw)), rel=1e-9)
    assert matrix[2, 1] == pytest.approx(0.0, abs=1e-15)
    assert np.allclose(rig_homography((w, h), hfov_deg=60.0, yaw_deg=0.0, pitch_deg=0.0), np.eye(3))


def test_random_rig_warps_have_the_issue_s_perspective_range():
    from rgbt_toolkit.registration.synthetic import random_rig_warp

    rng = np.random.default_rng(0)
    terms = np.array([random_rig_warp(rng, (1280, 1024))[2, :2] for _ in range(200)])
    # +-1.5 deg through a 50-70 deg HFOV at 1280 px: |h20|, |h21| up to tan(1.5 deg) / f, f = 914-1373 px
    assert np.abs(terms).max() <= np.tan(np.deg2rad(1.5)) / 914 * 1.05
    assert np.abs(terms).max() > 1.5e-5  # and not all tiny: the keystone the benchmark is about


def test_narrower_view_crops_the_centre_and_resamples_it():
    from rgbt_toolkit.registration.synthetic import narrower_view

    image = np.zeros((400, 600), np.uint8)
    image[190:210, 290:310] = 255  # a bright square at the centre
    out, matrix = narrower_view(image, np.eye(3), fov_fraction=0.5, size=(160, 128))
    assert out.shape == (128, 160)
    # the centre maps to the centre, and 300 source pixels of width to 160 output pixels
    assert np.allclose(project(matrix, [[299.5, 199.5]]), [[79.5, 63.5]])
    assert matrix[0, 0] == pytest.approx(160 / 300)
    ys, xs = np.nonzero(out > 128)
    assert abs(xs.mean() - 79.5) < 1 and abs(ys.mean() - 63.5) < 1


def test_rig_view_crop_is_the_unwarped_part_a_rig_warp_shows():
    from rgbt_toolkit.registration.synthetic import random_rig_warp, rig_view_crop

    image = np.random.default_rng(1).integers(0, 255, (480, 640), dtype=np.uint8)
    for seed in range(4):
        crop, truth = rig_view_crop(image, np.random.default_rng(seed))
        # the same draw, warped: the crop is the box of the unwarped image that shows what the warped crop shows
        warped, warp_truth = warp_and_crop(image, random_rig_warp(np.random.default_rng(seed), (640, 480)))
        x0, y0, x1, y1 = same_content_box(warp_truth, image.shape, warped.shape[:2])
        assert np.array_equal(truth, [[1, 0, -x0], [0, 1, -y0], [0, 0, 1]])
        assert np.array_equal(crop, image[y0:y1, x0:x1])
        # a real part of the view is lost (as in a rig warp), but most of it stays
        assert 0.3 * image.size < crop.size < 0.95 * image.size
