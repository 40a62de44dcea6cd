"""Image fusion I_F = W_F I_RGB + (1 - W_F) I_T: identities, colour handling, errors."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.backbones import load_backbone
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.fusion.image_fusion import FuseSettings, fuse_images, net_size, weight_heatmap
from rgbt_toolkit.fusion.model import MFNet


@pytest.fixture(scope="module")
def net(make_heads):
    return MFNet(make_heads(), load_backbone("efficientnet-lite0"))


def test_identical_grey_inputs_fuse_to_themselves(net, make_scene):
    _, t = make_scene(120, 160, 2)
    res = fuse_images(t, t.copy(), net)
    assert np.array_equal(res.fused, t)


def test_colour_visible_keeps_its_chroma_and_fuses_to_itself_with_its_own_luminance(net, make_scene):
    import cv2

    rgb, _ = make_scene(96, 128, 3)
    y = cv2.cvtColor(rgb, cv2.COLOR_RGB2YCrCb)[:, :, 0]
    res = fuse_images(rgb, y, net)
    assert res.fused.shape == rgb.shape
    assert np.abs(res.fused.astype(int) - rgb).max() <= 2  # YCrCb round trip only


def test_fused_is_the_weighted_blend(net, make_scene):
    rgb, t = make_scene(120, 160, 4)
    grey = rgb[:, :, 0]
    res = fuse_images(grey, t, net)
    expect = res.w_f * grey + (1 - res.w_f) * t
    assert np.abs(res.fused - expect).max() <= 0.51
    assert res.w_f.shape == grey.shape and 0 < res.w_f.min() and res.w_f.max() < 1
    assert set(res.timings) == {"prepare", "backbone", "heads", "blend"}


def test_three_channel_infrared_is_used_as_grey(net, make_scene):
    rgb, t = make_scene(64, 64, 5)
    a = fuse_images(rgb, t, net).fused
    b = fuse_images(rgb, np.dstack([t, t, t]), net).fused
    assert np.array_equal(a, b)


def test_global_only_gives_a_constant_weight(net, make_scene):
    rgb, t = make_scene(64, 96, 6)
    res = fuse_images(rgb, t, net, FuseSettings(use_local=False))
    assert np.ptp(res.w_f) < 1e-6 and abs(res.w_f[0, 0] - res.w_g) < 1e-6


def test_size_mismatch_says_register_first(net):
    with pytest.raises(InputError, match="register them first"):
        fuse_images(np.zeros((50, 60), np.uint8), np.zeros((50, 61), np.uint8), net)


def test_network_size_never_upsamples_and_keeps_aspect():
    assert net_size((480, 640), 192) == (144, 192)
    assert net_size((100, 120), 192) == (100, 120)


def test_heatmap_is_rgb_uint8():
    hm = weight_heatmap(np.linspace(0, 1, 20, dtype=np.float32).reshape(4, 5))
    assert hm.shape == (4, 5, 3) and hm.dtype == np.uint8
    assert not np.array_equal(hm[0, 0], hm[-1, -1])


def test_sixteen_bit_and_celsius_thermal_fuse_like_their_stretched_8_bit_image(net, make_scene):
    rgb, t = make_scene(64, 96, 9)
    counts = t.astype(np.uint16) * 8 + 7000  # a raw sensor: /257 would make it a flat grey of ~30
    celsius = counts.astype(np.float32) / 100.0 - 50.0  # the same frame in degrees C: clipping at 1 made it white
    ref = fuse_images(rgb, counts, net).fused
    assert np.abs(fuse_images(rgb, celsius, net).fused.astype(int) - ref.astype(int)).max() <= 1
    wrong = fuse_images(rgb, np.full_like(t, 30), net).fused  # what dividing by 257 gave, roughly
    assert np.abs(ref.astype(int) - wrong.astype(int)).mean() > 10
