"""rgbt fuse and rgbt train-mfnet through click's CliRunner on tiny generated inputs."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.images import read_image, write_image


@pytest.fixture()
def pair_folders(tmp_path, make_scene):
    for k in range(2):
        rgb, t = make_scene(96, 128, 20 + k)
        write_image(tmp_path / "vi" / f"{k:02d}.png", rgb)
        write_image(tmp_path / "ir" / f"{k:02d}.png", t)
    return tmp_path / "vi", tmp_path / "ir"


def test_fuse_folders_with_weight_maps(tmp_path, pair_folders, heads_file):
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["fuse", *map(str, pair_folders), "-o", str(out), "--weights", str(heads_file),
                                    "--save-weights", "--json"])
    assert res.exit_code == 0, res.output
    lines = [json.loads(x) for x in res.output.strip().splitlines()]
    assert len(lines) == 2 and 0 < lines[0]["w_g"] < 1 and "network" in lines[0]["ms"]
    for k in range(2):
        fused = read_image(out / f"{k:02d}.png")
        assert fused.shape == (96, 128, 3)
        assert read_image(out / f"{k:02d}_weights.png").shape == (96, 128, 3)


def test_fuse_single_pair_with_calibration_and_no_silent_overwrite(tmp_path, pair_folders, heads_file):
    vis, ir = pair_folders
    calib = tmp_path / "calib.json"
    calib.write_text(json.dumps({"H": [[1, 0, 2], [0, 1, 1], [0, 0, 1]]}))
    out = tmp_path / "f.png"
    args = ["fuse", str(vis / "00.png"), str(ir / "00.png"), "-o", str(out), "--weights", str(heads_file),
            "--calib", str(calib)]
    assert CliRunner().invoke(main, args).exit_code == 0
    assert read_image(out).shape == (96, 128, 3)
    again = CliRunner().invoke(main, args)
    assert again.exit_code == 1 and "exists; pass --force" in again.output
    assert CliRunner().invoke(main, args + ["--force"]).exit_code == 0


def test_fuse_bad_weights_is_one_line(tmp_path, pair_folders):
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"junk")
    res = CliRunner().invoke(main, ["fuse", *map(str, pair_folders), "-o", str(tmp_path / "o"), "--weights", str(bad)])
    assert res.exit_code == 1 and "not a readable torch file" in res.output and "Traceback" not in res.output


def test_train_mfnet_tiny_run(tmp_path, make_scene):
    for k in range(3):
        rgb, t = make_scene(280, 300, 30 + k)
        write_image(tmp_path / "d" / "vi" / f"{k}.png", rgb)
        write_image(tmp_path / "d" / "ir" / f"{k}.png", t)
    out = tmp_path / "w.pt"
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(tmp_path / "d"), "-o", str(out), "--samples", "8",
                                    "--val-samples", "8", "--epochs", "1,1,0", "--lr", "1e-4,5e-4,5e-5",
                                    "--local-init", "0", "--kinds", "clean,rgb_dark"])
    assert res.exit_code == 0, res.output
    from rgbt_toolkit.fusion.weights_io import load_heads, read_meta

    load_heads(out)
    meta = read_meta(out)
    assert [h["stage"] for h in meta["history"]] == ["global", "local"]
    # the earlier image heads' recipe (DCF, W_L starting at 0.5) is reachable from the command line
    assert [s["lr"] for s in meta["settings"]["stages"]] == [1e-4, 5e-4, 5e-5]
    assert meta["settings"]["local_init"] == 0.0
    # --kinds restricts the sample conditions (training and held-out pairs alike)
    assert list(meta["settings"]["sample"]["kinds"]) == ["clean", "rgb_dark"]
    assert {k[4:] for k in meta["validation"]["mfnet"] if k.startswith("hit_")} == {"clean", "rgb_dark"}
    assert meta["response_source"] == "DcfResponseSource"
    bad = CliRunner().invoke(main, ["train-mfnet", "--data", str(tmp_path / "d"), "-o", str(out)])
    assert bad.exit_code == 1 and "exists" in bad.output


def test_train_mfnet_unknown_kind_is_one_line(tmp_path, make_scene):
    rgb, t = make_scene(280, 300, 30)
    write_image(tmp_path / "d" / "vi" / "0.png", rgb)
    write_image(tmp_path / "d" / "ir" / "0.png", t)
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(tmp_path / "d"), "-o", str(tmp_path / "w.pt"),
                                    "--kinds", "clean,fog"])
    assert res.exit_code == 1 and "fog" in res.output and "rgb_glare" in res.output and "Traceback" not in res.output


def test_train_mfnet_bad_epochs(tmp_path):
    (tmp_path / "d").mkdir()
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(tmp_path / "d"), "-o", str(tmp_path / "w.pt"),
                                    "--epochs", "1,2"])
    assert res.exit_code == 1 and "three non-negative integers" in res.output
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(tmp_path / "d"), "-o", str(tmp_path / "w.pt"),
                                    "--epochs", "0,0,0"])
    assert res.exit_code == 1 and "--epochs '0,0,0': no stage would train" in res.output
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(tmp_path / "d"), "-o", str(tmp_path / "w.pt"),
                                    "--lr", "1e-4,0,1e-5"])
    assert res.exit_code == 1 and "--lr '1e-4,0,1e-5': learning rates must be finite numbers > 0" in res.output
