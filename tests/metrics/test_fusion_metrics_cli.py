"""``rgbt fusion-metrics`` through click's runner on tiny generated images, and the stem pairing rules."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.images import write_image
from rgbt_toolkit.metrics.scoring import pair_by_stem, score_folders


def _img(seed, shape=(48, 56), colour=False):
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[: shape[0], : shape[1]]
    base = 100 + 60 * np.sin(xx / (5.0 + seed)) + 30 * np.cos(yy / 7.0) + rng.normal(0, 5, shape)
    grey = np.clip(np.round(base), 0, 255).astype(np.uint8)
    return np.stack([grey, grey // 2 + 40, 255 - grey], axis=2) if colour else grey


@pytest.fixture()
def folders(tmp_path):
    vis, ir, fused = tmp_path / "vi", tmp_path / "ir", tmp_path / "fused"
    for d in (vis, ir, fused):
        d.mkdir()
    for stem, seed in (("a", 1), ("b", 2), ("c_x", 3)):
        write_image(vis / f"{stem}.png", _img(seed, colour=True))
        write_image(ir / f"{stem}.png", _img(seed + 10))
    write_image(fused / "a_M1.png", _img(21))
    write_image(fused / "a_HMSD_GF.bmp", _img(22, colour=True))
    write_image(fused / "b_M1.png", _img(23))
    write_image(fused / "b_HMSD_GF.png", _img(24)[:40])  # wrong size
    write_image(fused / "c_x_M1.png", _img(25))  # the source stem itself has an underscore
    write_image(fused / "zzz_M1.png", _img(26))  # no sources
    (fused / "broken_M1.png").write_bytes(b"not an image")  # unreadable and no sources
    (fused / "a_BAD.png").write_bytes(b"not an image")  # unreadable, sources present
    return vis, ir, fused


def test_pairing_by_stem_with_underscored_methods_and_stems(folders):
    vis, ir, fused = folders
    triples, problems = pair_by_stem(vis, ir, fused)
    found = {(t.image, t.method) for t in triples}
    assert found == {("a", "M1"), ("a", "HMSD_GF"), ("a", "BAD"), ("b", "M1"), ("b", "HMSD_GF"), ("c_x", "M1")}
    assert len(problems) == 2 and any("zzz_M1.png" in p for p in problems) and any("broken_M1" in p for p in problems)


def test_folder_mode_scores_the_rest_and_lists_problems(folders, tmp_path):
    vis, ir, fused = folders
    out = tmp_path / "scores.csv"
    result = CliRunner().invoke(main, ["fusion-metrics", "--vis", str(vis), "--ir", str(ir), "--fused", str(fused),
                                       "--metrics", "EN,MI,SSIM", "--format", "csv", "-o", str(out)])
    assert result.exit_code == 1
    assert f"4 image(s) could not be scored; {out} holds the 4 scored" in result.output
    assert "b_HMSD_GF.png" in result.output and "sizes differ" in result.output and "zzz_M1.png" in result.output
    assert "a_BAD.png: cannot decode image" in result.output
    assert result.output.count("a_BAD.png") == 1  # named once, not "path: path: cannot decode"
    rows = list(csv.DictReader(io.StringIO(out.read_text())))
    assert [r["image"] for r in rows] == ["a", "a", "b", "c_x", "mean", "mean"]
    assert {r["method"] for r in rows if r["image"] == "mean"} == {"M1", "HMSD_GF"}
    for r in rows:
        assert float(r["MI"]) == pytest.approx(2 * float(r["EN"]))  # paper convention's MI quirk
    m1 = [float(r["EN"]) for r in rows if r["method"] == "M1" and r["image"] != "mean"]
    mean_m1 = next(float(r["EN"]) for r in rows if r["image"] == "mean" and r["method"] == "M1")
    assert mean_m1 == pytest.approx(np.mean(m1))
    assert not list(tmp_path.glob(".scores*"))  # atomic write left no temporary file


def test_single_triple_json_and_table(folders):
    vis, ir, fused = folders
    args = ["fusion-metrics", "--vis", str(vis / "a.png"), "--ir", str(ir / "a.png"), "--fused",
            str(fused / "a_M1.png"), "--convention", "vifb", "--metrics", "EN,SF,Qabf"]
    result = CliRunner().invoke(main, [*args, "--format", "json"])
    assert result.exit_code == 0, result.output
    payload = json.loads(result.output)
    assert payload["convention"] == "vifb" and payload["metrics"] == ["EN", "SF", "Qabf"]
    assert payload["rows"][0]["image"] == "a" and payload["rows"][0]["method"] == "M1" and not payload["errors"]
    table = CliRunner().invoke(main, args)
    assert table.exit_code == 0 and "mean" in table.output and "Qabf" in table.output


def test_bad_metric_name_is_one_line_error(folders):
    vis, ir, fused = folders
    result = CliRunner().invoke(main, ["fusion-metrics", "--vis", str(vis), "--ir", str(ir), "--fused", str(fused),
                                       "--metrics", "EN,Bogus"])
    assert result.exit_code == 1 and "unknown metric 'Bogus'" in result.output
    assert "Traceback" not in result.output


def test_score_folders_default_paper_set(folders):
    vis, ir, fused = folders
    table = score_folders(vis, ir, fused / "c_x_M1.png")
    assert table.metrics == ["EN", "MI", "Qabf", "FMI_w", "Nabf", "SSIM", "MS_SSIM"]
    (row,) = table.rows
    assert row["image"] == "c_x" and 0 < row["FMI_w"] < 1 and 0 < row["MS_SSIM"] <= 1 and row["Nabf"] >= 0


def test_cli_choices_follow_the_library_tables():
    from rgbt_cli.cmd_fusion_metrics import command
    from rgbt_cli.options import FUSION_CONVENTIONS as _CONVENTIONS
    from rgbt_toolkit.metrics import CONVENTIONS

    assert set(_CONVENTIONS) == set(CONVENTIONS)
    listed = command.epilog.split("Metrics:")[1].split(". See")[0]
    assert {m.strip() for m in listed.split(",")} == set(CONVENTIONS["standard"].available())


def test_empty_fused_folder_is_an_error_not_an_empty_table(folders, tmp_path):
    vis, ir, _ = folders
    (tmp_path / "empty").mkdir()
    result = CliRunner().invoke(main, ["fusion-metrics", "--vis", str(vis), "--ir", str(ir),
                                       "--fused", str(tmp_path / "empty")])
    assert result.exit_code == 1 and "empty: no images found" in result.output


def test_float_tiffs_in_0_1_score_as_their_8_bit_images(tmp_path):
    import imageio.v3 as iio

    vis, ir, fused = _img(1, colour=True), _img(11), _img(21)
    for name, image in (("vis", vis), ("ir", ir), ("fused", fused)):
        write_image(tmp_path / f"{name}.png", image)
        iio.imwrite(tmp_path / f"{name}.tif", (image / 255.0).astype(np.float32))
    names = ["EN", "Qabf", "Nabf", "SSIM"]
    eight = score_folders(tmp_path / "vis.png", tmp_path / "ir.png", tmp_path / "fused.png", "vifb", names)
    floats = score_folders(tmp_path / "vis.png", tmp_path / "ir.tif", tmp_path / "fused.tif", "vifb", names)
    assert not floats.errors and eight.rows[0]["EN"] > 5
    for name in names:
        assert floats.rows[0][name] == pytest.approx(eight.rows[0][name], abs=1e-9), name


@pytest.mark.parametrize("shape", [(1, 40), (40, 1)])
def test_one_pixel_wide_images_are_one_line_errors(tmp_path, shape):
    for name, seed in (("a", 1), ("b", 2), ("c", 3)):
        write_image(tmp_path / f"{name}.png", _img(seed, shape))
    for convention in ("standard", "vifb"):
        result = CliRunner().invoke(main, ["fusion-metrics", "--vis", str(tmp_path / "a.png"), "--ir",
                                           str(tmp_path / "b.png"), "--fused", str(tmp_path / "c.png"),
                                           "--convention", convention, "--metrics", "EN,AG"])
        assert result.exit_code == 1 and "AG needs images of at least 2x2 pixels" in result.output
        assert "Traceback" not in result.output and isinstance(result.exception, SystemExit)


def test_output_under_a_file_or_with_nothing_scored_is_not_written(folders, tmp_path):
    vis, ir, fused = folders
    (tmp_path / "afile").write_text("x")
    args = ["fusion-metrics", "--vis", str(vis), "--ir", str(ir), "--metrics", "EN"]
    result = CliRunner().invoke(main, [*args, "--fused", str(fused), "-o", str(tmp_path / "afile" / "x.csv")])
    assert result.exit_code == 1 and "afile is a file, not a folder" in result.output
    (tmp_path / "none").mkdir()
    write_image(tmp_path / "none" / "zzz_M1.png", _img(26))  # no sources: nothing can be scored
    out = tmp_path / "x.csv"
    result = CliRunner().invoke(main, [*args, "--fused", str(tmp_path / "none"), "-o", str(out), "--format", "csv"])
    assert result.exit_code == 1 and f"{out} not written" in result.stderr and not out.exists()
