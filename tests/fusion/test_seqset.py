"""Training on benchmark sequences: frame pairs, patch geometry, data detection, and a tiny CLI run."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.fusion.seqset import SequenceSource, frame_pairs
from rgbt_toolkit.fusion.sources import MixedSource, collect_units, make_source
from rgbt_toolkit.fusion.trainset import PairSource
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.images import write_image
from rgbt_toolkit.io.sequences import read_sequence


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_sequence

    root = tmp_path_factory.mktemp("seqs")
    for s in (1, 2):
        cfg = SceneConfig.aligned(duration=0.6, seed=s, challenges=frozenset({"low_light"}))
        write_scene_sequence(SceneRenderer(cfg), root / f"seq{s}")
    return root


def test_frame_pairs_are_1_to_5_apart_and_skip_unannotated(dataset):
    seq = read_sequence(dataset / "seq1")
    pairs = frame_pairs(seq, 5)
    n = len(seq)
    assert pairs and all(1 <= j - i <= 5 and j < n for i, j in pairs)
    assert len(pairs) == sum(min(5, n - 1 - i) for i in range(n))  # every frame annotated here
    seq.gt_rgb[2] = np.nan
    seq.gt_t[4, 2] = 0.0
    pairs = frame_pairs(seq, 5)
    assert not any(k in (2, 4) for pair in pairs for k in pair) and (1, 3) in pairs


def test_samples_put_the_ground_truth_box_where_the_target_is(dataset):
    src = SequenceSource([dataset / "seq1", dataset / "seq2"])
    seq = src.sequences[0]
    gt = read_boxes(dataset / "seq1" / "visible.txt")
    s = src.sample(seq, 1, 4, np.random.default_rng(0))
    assert s.init_rgb.shape == (200, 200, 3) and s.init_t.shape == (200, 200) and s.kind == "sequence"
    # init box centred in the patch, same aspect; search box moved by the gt motion times the patch scale
    assert np.allclose(s.init_box[:2] + s.init_box[2:] / 2, 100.0)
    scale = s.init_box[2] / gt[1, 2]
    assert np.isclose(s.init_box[3] / gt[1, 3], scale) and 28 * 0.99 <= np.sqrt(np.prod(s.init_box[2:])) <= 56 * 1.01
    assert np.allclose(s.search_box[:2] - s.init_box[:2], (gt[4, :2] - gt[1, :2]) * scale, atol=1e-6)
    # the target is the warm blob of the thermal patch: hotter inside the box than around it
    x, y, w, h = np.round(s.search_box).astype(int)
    inside = s.search_t[y : y + h, x : x + w].astype(float).mean()
    assert inside > s.search_t.astype(float).mean() + 20
    rng = np.random.default_rng(1)
    for k in range(6):
        d = src.draw(k, rng)
        assert np.all(np.isfinite(d.search_box)) and d.search_box[2] > 0


def test_mixed_data_and_bad_folder(tmp_path, dataset, make_scene):
    for k in range(2):
        rgb, t = make_scene(280, 300, 40 + k)
        write_image(tmp_path / "pairs" / "vi" / f"{k}.png", rgb)
        write_image(tmp_path / "pairs" / "ir" / f"{k}.png", t)
    units = collect_units([tmp_path / "pairs", dataset, dataset / "seq1"])
    assert len(units) == 2 + 2  # seq1 is inside the dataset folder too: counted once
    src = make_source(units)
    assert isinstance(src, MixedSource) and [type(p) for p in src.parts] == [PairSource, SequenceSource]
    rng = np.random.default_rng(0)
    kinds = [src.draw(k, rng).kind for k in range(4)]
    assert kinds[1] == kinds[3] == "sequence" and kinds[0] != "sequence"
    (tmp_path / "junk" / "x").mkdir(parents=True)
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(dataset), "--data", str(tmp_path / "junk"),
                                    "-o", str(tmp_path / "w.pt")])
    assert res.exit_code == 1 and str(tmp_path / "junk") in res.output and "neither aligned pairs" in res.output
    assert len(res.output.strip().splitlines()) == 1 and "Traceback" not in res.output


def test_train_mfnet_on_sequences_tiny_run(tmp_path, dataset):
    out = tmp_path / "w.pt"
    res = CliRunner().invoke(main, ["train-mfnet", "--data", str(dataset), "-o", str(out), "--samples", "8",
                                    "--val-samples", "8", "--epochs", "1,1,0"])
    assert res.exit_code == 0, res.output
    from rgbt_toolkit.fusion.weights_io import load_heads, read_meta

    load_heads(out)
    meta = read_meta(out)
    assert meta["train_sequences"] == 1 and meta["val_sequences"] == 1 and meta["train_images"] == 0
    assert [h["stage"] for h in meta["history"]] == ["global", "local"]
    assert "hit_sequence" in meta["validation"]["mfnet"]
