"""Head weight files: round trip, shipped weights, clear errors on a mismatch."""

from __future__ import annotations

import pytest
import torch

from rgbt_toolkit.errors import MissingFileError, WeightsError
from rgbt_toolkit.fusion.network import HeadConfig, MFNetHeads
from rgbt_toolkit.fusion.weights_io import DEFAULT_WEIGHTS, load_heads, read_meta, save_heads


def _out(heads, seed=0):
    g = torch.Generator().manual_seed(seed)
    f1, f2 = torch.randn(2, 112, 13, 13, generator=g), torch.randn(2, 112, 13, 13, generator=g)
    with torch.no_grad():
        return heads(f1, f2, (50, 50))


def test_round_trip_exact_in_float32(tmp_path, make_heads):
    heads = make_heads(3)
    save_heads(tmp_path / "h.pt", heads, {"a": 1}, half=False)
    back = load_heads(tmp_path / "h.pt")
    for k, v in heads.state_dict().items():
        assert torch.equal(v, back.state_dict()[k])
    assert read_meta(tmp_path / "h.pt") == {"a": 1}
    assert back.cfg == heads.cfg


def test_round_trip_half_precision_keeps_the_weights(tmp_path, make_heads):
    heads = make_heads(4)
    save_heads(tmp_path / "h.pt", heads)
    back = load_heads(tmp_path / "h.pt")
    for a, b in zip(_out(heads), _out(back)):
        assert torch.allclose(a, b, atol=2e-3)


def test_shipped_weights_load_and_are_small():
    assert DEFAULT_WEIGHTS.is_file(), "run the command in docs/fusion.md to produce the shipped weights"
    assert DEFAULT_WEIGHTS.stat().st_size < 5 * 1024 * 1024
    heads = load_heads(expect=HeadConfig())
    meta = read_meta()
    assert meta["response_source"] and meta["history"]
    w_g, w_l, _ = _out(heads)
    assert 0 < float(w_g.min()) and float(w_g.max()) < 1


def test_files_without_local_init_still_load(tmp_path, make_heads):
    """Weight files written before HeadConfig.local_init existed load unchanged (the field only affects training)."""
    heads = make_heads(5)
    save_heads(tmp_path / "h.pt", heads, half=False)
    blob = torch.load(tmp_path / "h.pt", weights_only=True)
    del blob["config"]["local_init"]
    torch.save(blob, tmp_path / "old.pt")
    back = load_heads(tmp_path / "old.pt", expect=HeadConfig())
    for a, b in zip(_out(heads), _out(back)):
        assert torch.equal(a, b)


def test_missing_file(tmp_path):
    with pytest.raises(MissingFileError, match="train one with `rgbt train-mfnet`"):
        load_heads(tmp_path / "none.pt")


def test_not_a_head_file(tmp_path):
    torch.save({"x": torch.zeros(1)}, tmp_path / "other.pt")
    with pytest.raises(WeightsError, match="not an MFNet head file"):
        load_heads(tmp_path / "other.pt")
    (tmp_path / "junk.pt").write_bytes(b"junk")
    with pytest.raises(WeightsError, match="not a readable torch file"):
        load_heads(tmp_path / "junk.pt")


def test_heads_for_another_backbone(tmp_path):
    save_heads(tmp_path / "v.pt", MFNetHeads(HeadConfig(in_channels=1024, backbone="vggm")))
    with pytest.raises(WeightsError, match="trained for backbone='vggm'"):
        load_heads(tmp_path / "v.pt", expect=HeadConfig())


def test_tensor_shape_mismatch(tmp_path, make_heads):
    save_heads(tmp_path / "h.pt", make_heads())
    blob = torch.load(tmp_path / "h.pt", weights_only=True)
    blob["state"]["global_head.conv2.weight"] = torch.zeros(1, 256, 5, 5)
    torch.save(blob, tmp_path / "bad.pt")
    with pytest.raises(WeightsError, match="global_head.conv2.weight.*expected"):
        load_heads(tmp_path / "bad.pt")


def test_missing_tensor(tmp_path, make_heads):
    save_heads(tmp_path / "h.pt", make_heads())
    blob = torch.load(tmp_path / "h.pt", weights_only=True)
    del blob["state"]["local_head.deconv1.bias"]
    torch.save(blob, tmp_path / "bad.pt")
    with pytest.raises(WeightsError, match="1 missing"):
        load_heads(tmp_path / "bad.pt")


def test_shipped_image_heads_record_the_documented_recipe():
    # docs/fusion.md: rgbt train-mfnet --data roadscene --seed 0 --source eco --local-init 3 --lr 1e-4,5e-4,5e-5
    meta = read_meta(DEFAULT_WEIGHTS)
    s = meta["settings"]
    assert meta["response_source"] == "EcoResponseSource"
    assert [str(d).replace("\\", "/").rsplit("/", 1)[-1] for d in meta["data"]] == ["roadscene"]
    assert s["seed"] == 0 and s["local_init"] == 3.0 and s["samples"] == 1200 and s["val_samples"] == 240
    assert [(st["name"], st["epochs"], st["lr"]) for st in s["stages"]] == [
        ("global", 6, 1e-4), ("local", 4, 5e-4), ("joint", 2, 5e-5)]
    assert load_heads().cfg.local_init == 3.0
