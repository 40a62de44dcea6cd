"""Deep ECO features from chosen backbone layers: the backbone stops at the last one asked for; one width per layer."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.eco import EcoParams, preset
from rgbt_toolkit.errors import InputError

torch = pytest.importorskip("torch")


def test_shallow_layer_alone_never_runs_the_deeper_blocks(backbone):
    from rgbt_toolkit.features.deep import DeepFeatures

    ran = []
    hooks = [b.register_forward_hook(lambda m, i, o, k=k: ran.append(k)) for k, b in enumerate(backbone.blocks)]
    try:
        feat = DeepFeatures(layers=("shallow",), compressed_dims=(16,))
        (fmap, stride), = feat.maps(np.zeros((64, 64, 3), np.uint8))
        shallow_only = sorted(set(ran))
        ran.clear()
        DeepFeatures().maps(np.zeros((64, 64, 3), np.uint8))
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
