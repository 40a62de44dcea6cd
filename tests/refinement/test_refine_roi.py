"""Patch cropping and RoI-align: coordinates checked on maps whose values are their own coordinates."""

import numpy as np
import torch

from rgbt_toolkit.refinement.roi import boxes_to_regions, crop_patch, patch_transform, roi_align


def test_crop_patch_puts_the_centre_mid_patch():
    image = np.zeros((100, 120, 3), np.uint8)
    image[40, 70] = 255  # one bright pixel
    patch = crop_patch(image, np.array([70.0, 40.0]), 1.0, 33)
    assert np.unravel_index(patch[:, :, 0].argmax(), patch.shape[:2]) == (16, 16)
    m = patch_transform(np.array([70.0, 40.0]), 2.0, 33)
    np.testing.assert_allclose(m @ [71.0, 40.0, 1.0], [18.0, 16.0])


def test_roi_align_samples_bin_centres():
    # a stride-4 map whose value at cell (i, j) is the x coordinate of that cell's centre in patch pixels
    stride, hf, wf = 4, 10, 12
    xs = np.arange(wf) * stride + (stride - 1) / 2
    feat = torch.tensor(np.tile(xs, (hf, 1)), dtype=torch.float64)[None, None]
    region = np.array([[8.0 - 0.5, 4.0 - 0.5, 8.0 + 16 - 0.5, 4.0 + 20 - 0.5]])  # the box x=8, y=4, w=16, h=20
    out = roi_align(feat, region, stride, grid=4, points=2)
    assert out.shape == (1, 1, 4, 4)
    # inside the map interior bilinear sampling of a linear ramp is exact: each bin reads its centre's x
    expected = 8.0 - 0.5 + (np.arange(4) + 0.5) * 4
    np.testing.assert_allclose(out[0, 0, 0].numpy(), expected, atol=1e-9)
    np.testing.assert_allclose(out[0, 0, :, 1].numpy(), expected[1], atol=1e-9)


def test_regions_follow_the_patch_transform():
    m = patch_transform(np.array([50.0, 60.0]), 0.5, 49)
    box = np.array([[40.5, 50.5, 20.0, 20.0]])  # centre (50, 60)
    r = boxes_to_regions(box, m, context=1.5)
    np.testing.assert_allclose(r, [[24 - 7.5, 24 - 7.5, 24 + 7.5, 24 + 7.5]])
