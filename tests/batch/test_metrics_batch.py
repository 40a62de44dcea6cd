"""``rgbt batch fusion-metrics``: the same table as ``rgbt fusion-metrics``, resumable, with failures listed."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.images import write_image

pytest.importorskip("rgbt_toolkit.metrics.scoring")


@pytest.fixture()
def fusion_folders(tmp_path):
    rng = np.random.default_rng(1)
    for stem in ("01", "02"):
        vis = rng.integers(0, 255, (48, 64), dtype=np.uint8)
        ir = rng.integers(0, 255, (48, 64), dtype=np.uint8)
        write_image(tmp_path / "vis" / f"{stem}.png", vis)
        write_image(tmp_path / "ir" / f"{stem}.png", ir)
        write_image(tmp_path / "fused" / f"{stem}_avg.png", ((vis.astype(int) + ir) // 2).astype(np.uint8))
        write_image(tmp_path / "fused" / f"{stem}_max.png", np.maximum(vis, ir))
    return tmp_path


def _args(root, *extra):
    return ["--vis", str(root / "vis"), "--ir", str(root / "ir"), "--fused", str(root / "fused"), *extra]


def test_batch_table_equals_the_single_command(fusion_folders):
    root = fusion_folders
    single = CliRunner().invoke(main, ["fusion-metrics", *_args(root, "--format", "json")])
    assert single.exit_code == 0, single.output
    batch = CliRunner().invoke(main, ["batch", "fusion-metrics", *_args(root, "-o", str(root / "out"), "--format",
                                                                        "json", "--in-process")])
    assert batch.exit_code == 0, batch.output
    expected, got = json.loads(single.stdout), json.loads(batch.stdout)
    assert got["rows"] == expected["rows"] and got["means"] == expected["means"]
    assert len(got["rows"]) == 4 and "4 done" in batch.stderr
    assert json.loads((root / "out" / "fusion_metrics.json").read_text()) == got
    again = CliRunner().invoke(main, ["batch", "fusion-metrics", *_args(root, "-o", str(root / "out"), "--format",
                                                                        "json", "--in-process")])
    assert again.exit_code == 0 and "0 done, 4 skipped" in again.stderr
    assert json.loads(again.stdout)["rows"] == expected["rows"]


def test_a_bad_fused_image_is_listed_and_the_rest_scored(fusion_folders):
    root = fusion_folders
    write_image(root / "fused" / "02_max.png", np.zeros((10, 10), np.uint8))
    write_image(root / "fused" / "99_avg.png", np.zeros((48, 64), np.uint8))  # no sources with stem 99
    result = CliRunner().invoke(main, ["batch", "fusion-metrics", *_args(root, "-o", str(root / "out"),
                                                                         "--in-process", "--metrics", "EN,SSIM")])
    assert result.exit_code == 1
    assert "02_max.png  failed       1" in result.stderr and "InputError: image sizes differ" in result.stderr
    assert "99_avg.png: no visible/infrared image with a matching stem" in result.stderr
    rows = [line.split()[:2] for line in result.stdout.splitlines()[2:5]]
    assert rows == [["01", "avg"], ["01", "max"], ["02", "avg"]]
    assert "3 done, 0 skipped (finished before), 1 failed" in result.stderr


def test_unknown_metric_fails_before_starting(fusion_folders):
    root = fusion_folders
    result = CliRunner().invoke(main, ["batch", "fusion-metrics", *_args(root, "-o", str(root / "out"),
                                                                         "--metrics", "EN,NOPE")])
    assert result.exit_code == 1 and "NOPE" in result.stderr and not (root / "out").exists()


def test_batch_scores_vifb_fused_images_as_vifb_does(shared_dir, tmp_path):
    """Two VIFB images with all 13 methods' fused results, against VIFB's own values (reference_metrics.csv)."""
    import csv

    vifb = shared_dir / "data" / "fusion" / "vifb"
    fused = tmp_path / "fused"
    fused.mkdir()
    for path in sorted(vifb.glob("fused/*.jpg")):
        if path.name.split("_")[0] in ("carLight", "kettle"):
            (fused / path.name).symlink_to(path)  # a subset, linked, never copied
    result = CliRunner().invoke(main, ["batch", "fusion-metrics", "--vis", str(vifb / "VI"), "--ir", str(vifb / "IR"),
                                       "--fused", str(fused), "-o", str(tmp_path / "out"), "--convention", "vifb",
                                       "--metrics", "EN,SF,AG", "--format", "json", "--in-process"])
    assert result.exit_code == 0, result.output
    rows = {(r["image"], r["method"]): r for r in json.loads(result.stdout)["rows"]}
    assert len(rows) == 26
    with open(vifb / "reference_metrics.csv", newline="") as handle:
        reference = {(r["image"], r["method"]): r for r in csv.DictReader(handle)}
    for key, row in rows.items():
        ref = reference[key]
        for ours, theirs in (("EN", "Entropy"), ("SF", "Spatial_frequency"), ("AG", "Avg_gradient")):
            assert row[ours] == pytest.approx(float(ref[theirs]), rel=1e-3), (key, ours)


def test_a_replaced_fused_image_is_scored_again(fusion_folders):
    root = fusion_folders
    args = ["batch", "fusion-metrics", *_args(root, "-o", str(root / "out"), "--format", "json", "--in-process",
                                              "--metrics", "EN")]
    first = CliRunner().invoke(main, args)
    assert first.exit_code == 0, first.output
    write_image(root / "fused" / "01_max.png", np.full((48, 64), 9, np.uint8))  # a flat image: EN 0
    again = CliRunner().invoke(main, args)
    assert again.exit_code == 0 and "1 done, 3 skipped" in again.stderr
    rows = {(r["image"], r["method"]): r["EN"] for r in json.loads(again.stdout)["rows"]}
    assert rows[("01", "max")] == 0.0 and rows[("01", "avg")] > 5
