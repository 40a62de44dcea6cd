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
    assert set(res.timings) == {"prepare", "network", "blend"}


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
    assert net_size((450, 620), 192) == (140, 192)  # 139.4: nearest multiple of the local head's 4-px cells
    assert net_size((5, 300), 192) == (16, 192)


def test_padding_reaches_the_stride_by_reflection_and_leaves_multiples_alone():
    from rgbt_toolkit.fusion.image_fusion import pad_to_stride

    image = np.arange(140 * 100, dtype=np.int32).reshape(140, 100).astype(np.uint8)
    padded = pad_to_stride(image)
    assert padded.shape == (144, 112) and np.array_equal(padded[:140, :100], image)
    assert np.array_equal(padded[140, :100], image[138]) and np.array_equal(padded[:140, 100], image[:, 98])
    same = np.zeros((144, 192, 3), np.uint8)
    assert pad_to_stride(same) is same


@pytest.mark.parametrize("shape", [(101, 157), (37, 250), (144, 192)])
def test_any_size_fuses_and_the_weight_map_covers_the_image(net, make_scene, shape):
    rgb, t = make_scene(*shape, 10)
    res = fuse_images(rgb, t, net)
    assert res.fused.shape == rgb.shape and res.w_f.shape == shape
    assert np.isfinite(res.w_f).all() and 0 < res.w_f.min() and res.w_f.max() < 1


def test_padding_does_not_shift_the_weight_map(net, make_scene):
    """An image whose network input needs padding (164 -> 176 columns) gets the weights of the same place in a wider
    image that needs none: the cropped-back map is aligned. Away from the padded edge the difference is well below
    that of a 4-px misalignment (measured 0.003 vs 0.015; not cropping the padding's cells gives 0.05)."""
    rgb, t = make_scene(128, 176, 11)  # 176 = 11 * 16: no padding
    settings = FuseSettings(net_side=176, use_global=False)
    whole = fuse_images(rgb, t, net, settings).w_f
    part = fuse_images(rgb[:, :164], t[:, :164], net, settings).w_f
    shifted = fuse_images(rgb[:, 4:168], t[:, 4:168], net, settings).w_f
    inner = np.s_[24:-24, 24:132]
    assert np.abs(part[inner] - whole[inner]).mean() < 0.5 * np.abs(shifted[inner] - whole[inner]).mean()


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
