"""load_backbone: names, user weights, and one-line errors for weights that do not fit."""

from __future__ import annotations

import pytest
import torch

from rgbt_toolkit.backbones import available, load_backbone
from rgbt_toolkit.backbones.vggm import VGGM
from rgbt_toolkit.errors import InputError, MissingFileError, WeightsError


def test_available_names():
    assert {"efficientnet-lite0", "vggm"} <= set(available())


def test_unknown_name():
    with pytest.raises(InputError, match="unknown backbone 'resnet'"):
        load_backbone("resnet")


def test_missing_weight_file(tmp_path):
    with pytest.raises(MissingFileError, match="weight file not found"):
        load_backbone("efficientnet-lite0", weights=tmp_path / "nope.pth")


def test_unreadable_weight_file(tmp_path):
    bad = tmp_path / "bad.pth"
    bad.write_bytes(b"not a torch file")
    with pytest.raises(WeightsError, match="not a readable torch state dict"):
        load_backbone("efficientnet-lite0", weights=bad)


def test_user_weights_with_a_missing_key(tmp_path):
    from rgbt_toolkit.backbones.efficientnet_lite import EfficientNetLite0

    state = EfficientNetLite0().state_dict()
    del state["head.conv.weight"]
    path = tmp_path / "partial.pt"
    torch.save(state, path)
    with pytest.raises(WeightsError, match="1 missing.*head.conv.weight"):
        load_backbone("efficientnet-lite0", weights=path, cache=False)


def test_user_weights_with_a_wrong_shape(tmp_path):
    from rgbt_toolkit.backbones.efficientnet_lite import EfficientNetLite0

    state = EfficientNetLite0().state_dict()
    state["classifier.bias"] = torch.zeros(10)
    path = tmp_path / "shape.pt"
    torch.save(state, path)
    with pytest.raises(WeightsError, match=r"shape of 'classifier.bias' is \(10,\)"):
        load_backbone("efficientnet-lite0", weights=path, cache=False)


def test_vggm_without_weights_says_how_to_fix():
    with pytest.raises(WeightsError, match="vggm ships no weights"):
        load_backbone("vggm")


def test_vggm_with_user_state_dict(tmp_path):
    path = tmp_path / "vggm.pt"
    torch.save(VGGM().state_dict(), path)
    net = load_backbone("vggm", weights=path)
    feats = net.extract(torch.rand(1, 3, 107, 107))
    assert feats["shallow"].shape[1] == 96 and feats["deep"].shape[1] == 512
    assert net.strides == {"shallow": 2, "conv4": 16, "deep": 16}


def test_vggm_matconvnet_names_are_converted():
    ref = VGGM().state_dict()
    mcn = {}
    for i in range(1, 6):
        mcn[f"conv{i}f"] = ref[f"conv{i}.weight"].permute(2, 3, 1, 0)
        mcn[f"conv{i}b"] = ref[f"conv{i}.bias"][:, None]
    mapped = VGGM.map_keys(mcn)
    assert all(torch.equal(mapped[k], ref[k]) for k in ref)


@pytest.mark.parametrize(
    "bad,match",
    [
        (torch.rand(3, 32, 32), r"must be \[B,3,H,W\]"),
        (torch.zeros(1, 3, 32, 32, dtype=torch.uint8), "divide uint8 by 255"),
        (torch.rand(1, 1, 32, 32), "RGB"),
        (torch.rand(1, 3, 4, 4), "too small"),
    ],
)
def test_bad_input_is_rejected(bad, match):
    with pytest.raises(InputError, match=match):
        load_backbone("efficientnet-lite0").extract(bad)


def test_unknown_layer_is_rejected():
    with pytest.raises(InputError, match="no layer 'conv9'"):
        load_backbone("efficientnet-lite0").extract(torch.rand(1, 3, 32, 32), layers=("conv9",))
