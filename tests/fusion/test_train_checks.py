"""train-mfnet and weight files refuse non-finite values; output and data checked before training (issue 7 review)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.errors import InputError, WeightsError
from rgbt_toolkit.fusion.network import HeadConfig, MFNetHeads, fuse_responses
from rgbt_toolkit.fusion.sources import collect_units
from rgbt_toolkit.fusion.train import Cache, Stage, TrainSettings, train_heads
from rgbt_toolkit.fusion.weights_io import FORMAT, VERSION, load_heads, save_heads
from rgbt_toolkit.io.images import write_image


@pytest.fixture()
def one_pair(tmp_path, make_scene):
    rgb, t = make_scene(280, 300, 30)
    write_image(tmp_path / "d" / "vi" / "0.png", rgb)
    write_image(tmp_path / "d" / "ir" / "0.png", t)
    return tmp_path / "d"


@pytest.mark.parametrize("option", [["--lr", "nan,1e-2,5e-5"], ["--lr", "1e-4,inf,5e-5"], ["--local-init", "nan"],
                                    ["--local-init", "-inf"]])
def test_non_finite_settings_are_refused_in_one_line(tmp_path, one_pair, option):
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(one_pair), "-o", str(tmp_path / "w.pt"), *option])
    assert res.exit_code == 1 and "finite" in res.output and len(res.output.strip().splitlines()) == 1
    assert not (tmp_path / "w.pt").exists()


def test_settings_refuse_non_finite_values_in_the_library():
    with pytest.raises(InputError, match="learning rate of the local stage must be a finite number"):
        TrainSettings(stages=(Stage("global", 1, 1e-4), Stage("local", 1, float("nan")), Stage("joint", 1, 1e-5)))
    with pytest.raises(InputError, match="local_init must be a finite logit"):
        TrainSettings(local_init=float("inf"))


def test_non_finite_heads_are_never_saved_and_never_loaded(tmp_path):
    heads = MFNetHeads(HeadConfig(in_channels=8, hidden=8))
    with torch.no_grad():
        heads.global_head.conv1.weight[0, 0, 0, 0] = float("nan")
    with pytest.raises(WeightsError, match="h.pt: not written, tensor 'global_head.conv1.weight' holds NaN"):
        save_heads(tmp_path / "h.pt", heads)
    assert not (tmp_path / "h.pt").exists()
    # a file written elsewhere with a NaN inside: refused on load, naming the file
    blob = {"format": FORMAT, "version": VERSION, "config": heads.cfg.to_dict(),
            "state": {k: v.clone() for k, v in heads.state_dict().items()}, "meta": {}}
    torch.save(blob, tmp_path / "nan.pt")
    with pytest.raises(WeightsError, match="nan.pt: tensor 'global_head.conv1.weight' holds NaN or infinite"):
        load_heads(tmp_path / "nan.pt")


def test_a_diverging_run_stops_with_an_error():
    g = torch.Generator().manual_seed(0)
    n = 16
    cache = Cache(torch.randn(n, 4, 5, 5, generator=g).half(), torch.randn(n, 4, 5, 5, generator=g).half(),
                  torch.rand(n, 20, 20, generator=g), torch.rand(n, 20, 20, generator=g),
                  torch.rand(n, 20, 20, generator=g), ["clean"] * n)
    settings = TrainSettings(stages=(Stage("global", 3, 1e30), Stage("local", 0, 1e-2), Stage("joint", 0, 1e-5)))
    with pytest.raises(WeightsError, match="training diverged in the global stage"):
        train_heads(cache, settings, cfg=HeadConfig(in_channels=8, hidden=8))


def test_output_is_checked_before_training(tmp_path, one_pair):
    (tmp_path / "afile").write_text("x")
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(one_pair), "-o", str(tmp_path / "afile" / "w.pt")])
    assert res.exit_code == 1 and "afile is a file, not a folder" in res.output


def test_one_pair_warns_that_validation_uses_training_data(tmp_path, one_pair):
    out = tmp_path / "new" / "w.pt"  # a missing parent folder is created
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(one_pair), "--data", str(one_pair) + "/", "-o",
                                    str(out), "--samples", "8", "--val-samples", "8", "--epochs", "1,0,0"])
    assert res.exit_code == 0, res.output
    assert "warning: only 1 image pair or sequence" in res.stderr and "measured on training data" in res.stderr
    report = json.loads(res.stdout)
    assert report["validation_on_training_data"] is True
    assert res.stderr.strip().splitlines()[-1].startswith(f"wrote {out}: training peak hit mfnet ")
    from rgbt_toolkit.fusion.weights_io import read_meta

    assert read_meta(out)["data"] == [str(one_pair)]  # the repeated folder counted once


def test_units_of_repeated_and_nested_folders_count_once(tmp_path, make_scene):
    for k in range(2):
        rgb, t = make_scene(64, 64, k)
        write_image(tmp_path / "p" / "vi" / f"{k}.png", rgb)
        write_image(tmp_path / "p" / "ir" / f"{k}.png", t)
    (tmp_path / "x").mkdir()
    assert len(collect_units([tmp_path / "p", tmp_path / "p", tmp_path / "x" / ".." / "p"])) == 2


def test_fuse_responses_refuses_shapes_that_do_not_fit():
    assert fuse_responses(np.full((3, 3), 0.25), np.ones((3, 3)), np.zeros((3, 3)))[0, 0] == 0.25
    with pytest.raises(InputError, match="weight map \\(1, 10, 10\\) does not fit the responses \\(1, 20, 20\\)"):
        fuse_responses(torch.rand(1, 10, 10), torch.rand(1, 20, 20), torch.rand(1, 20, 20))
    with pytest.raises(InputError, match="differ in shape"):
        fuse_responses(0.5, np.ones((4, 4)), np.ones((4, 5)))
