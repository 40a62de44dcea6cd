"""MFNet heads: weight ranges, W_F = w_G * W_L, ablations, response fusion."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from rgbt_toolkit.backbones import load_backbone
from rgbt_toolkit.fusion.model import MFNet, to_tensor
from rgbt_toolkit.fusion.network import HeadConfig, MFNetHeads, fuse_responses


@pytest.fixture(scope="module")
def net(make_heads):
    return MFNet(make_heads(), load_backbone("efficientnet-lite0"))


def test_weights_are_in_open_unit_interval_and_product(net, make_scene):
    rgb, t = make_scene(200, 200, 1)
    w_g, w_l, w_f = net.weights(to_tensor(rgb), to_tensor(t), (50, 50))
    assert w_g.shape == (1,) and w_l.shape == (1, 50, 50) and w_f.shape == (1, 50, 50)
    for w in (w_g, w_l, w_f):
        assert float(w.min()) > 0.0 and float(w.max()) < 1.0
    assert torch.allclose(w_f, w_g[:, None, None] * w_l, atol=0, rtol=0)
    assert float(w_l.std()) > 1e-4  # a real map, not a constant


def test_fresh_heads_start_at_the_average_without_local_correction():
    heads = MFNetHeads(HeadConfig(in_channels=8, hidden=4))
    f = torch.randn(2, 4, 13, 13) * 10
    w_g, w_l, w_f = heads(f, f.flip(0), (50, 50))
    assert torch.allclose(w_g, torch.full_like(w_g, 0.5), atol=0.02)
    # W_L starts at sigmoid(3) = 0.953, so W_F starts at (nearly) the global weight, not half of it
    assert torch.allclose(w_l, torch.full_like(w_l, 0.9526), atol=0.01)
    assert torch.allclose(w_f, 0.9526 * w_g[:, None, None].expand_as(w_f), atol=0.01)


def test_local_init_sets_the_starting_local_weight():
    f = torch.randn(1, 4, 9, 9) * 10
    for logit, expect in ((0.0, 0.5), (2.0, 0.8808)):
        _, w_l, _ = MFNetHeads(HeadConfig(in_channels=8, hidden=4, local_init=logit))(f, f, (20, 20))
        assert torch.allclose(w_l, torch.full_like(w_l, expect), atol=0.01), logit


@pytest.mark.parametrize("use_global,use_local", [(True, False), (False, True)])
def test_ablation_replaces_a_head_by_one(use_global, use_local, make_heads):
    heads = make_heads(cfg=HeadConfig(in_channels=8, hidden=4))
    f = torch.randn(1, 4, 9, 11)
    w_g, w_l, w_f = heads(f, -f, (36, 44), use_global, use_local)
    if not use_global:
        assert torch.equal(w_g, torch.ones(1)) and torch.equal(w_f, w_l)
    if not use_local:
        assert torch.equal(w_l, torch.ones(1, 36, 44)) and torch.allclose(w_f, w_g.expand(1, 36, 44)[0])


def test_local_map_is_resized_to_the_response_size():
    heads = MFNetHeads(HeadConfig(in_channels=8, hidden=4))
    f = torch.randn(3, 4, 13, 13)
    _, w_l, w_f = heads(f, f, (31, 47))
    assert w_l.shape == w_f.shape == (3, 31, 47)


def test_feature_shape_mismatch():
    heads = MFNetHeads(HeadConfig(in_channels=8, hidden=4))
    with pytest.raises(ValueError, match="differ in shape"):
        heads(torch.randn(1, 4, 13, 13), torch.randn(1, 4, 12, 13), (50, 50))


def test_fuse_responses_formula_and_identity():
    rng = np.random.default_rng(0)
    w, a, b = rng.random((3, 5, 5))
    assert np.allclose(fuse_responses(w, a, b), w * a + (1 - w) * b)
    assert np.allclose(fuse_responses(w, a, a), a)  # identical responses fuse to themselves
    assert np.allclose(fuse_responses(np.ones((5, 5)), a, b), a)


def test_heads_for_another_backbone_are_refused():
    from rgbt_toolkit.errors import InputError

    heads = MFNetHeads(HeadConfig(in_channels=1024, layer="deep"))
    with pytest.raises(InputError, match="expect 1024 channels"):
        MFNet(heads, load_backbone("efficientnet-lite0"))
