"""rgbt fuse on folders with bad pairs, output-name rules, --registered, --calib sizes (acceptance review, issue 7)."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.images import read_image, write_image


@pytest.fixture()
def folders(tmp_path, make_scene):
    """vi/ir folders: 00 good, 01 truncated visible JPEG, 02 sizes differ, 03 good, plus a visible-only file."""
    vi, ir = tmp_path / "vi", tmp_path / "ir"
    for k in range(4):
        rgb, t = make_scene(64, 80, 40 + k)
        write_image(vi / f"{k:02d}.jpg", rgb)
        write_image(ir / f"{k:02d}.png", t if k != 2 else t[:, :70])
    (vi / "01.jpg").write_bytes((vi / "01.jpg").read_bytes()[:300])
    write_image(vi / "only_vis.png", rgb)
    (ir / "notes.txt").write_text("not an image")
    return vi, ir


def _fuse(*args):
    return CliRunner().invoke(main, ["fuse", *map(str, args)])


def test_folder_run_fuses_the_good_pairs_and_lists_every_failure(tmp_path, folders, heads_file):
    vi, ir = folders
    out = tmp_path / "out"
    res = _fuse(vi, ir, "-o", out, "--weights", heads_file)
    assert res.exit_code == 1
    assert sorted(p.name for p in out.iterdir()) == ["00.png", "03.png"]
    assert "fused 2 of 4 pair(s); 2 failed" in res.stderr
    assert f"{vi / '01.jpg'}: cannot decode image" in res.stderr
    assert f"{vi / '02.jpg'} is 80x64 but {ir / '02.png'} is 70x64; pass --registered" in res.stderr
    assert "1 visible image(s) without a partner of the same stem, not fused: only_vis.png" in res.stderr
    assert "Traceback" not in res.stderr + res.stdout


def test_rerun_refuses_existing_outputs_unless_skip_existing_or_force(tmp_path, folders, heads_file):
    vi, ir = folders
    out = tmp_path / "out"
    _fuse(vi, ir, "-o", out, "--weights", heads_file)
    again = _fuse(vi, ir, "-o", out, "--weights", heads_file)
    assert again.exit_code == 1 and "00.png and 1 more output(s) exist; pass --force" in again.stderr
    write_image(vi / "01.jpg", read_image(vi / "00.jpg"))  # the user repairs the broken file
    write_image(ir / "02.png", read_image(ir / "00.png"))
    before = (out / "00.png").stat().st_mtime_ns
    res = _fuse(vi, ir, "-o", out, "--weights", heads_file, "--skip-existing", "--json")
    assert res.exit_code == 0, res.stderr
    records = [json.loads(x) for x in res.stdout.splitlines()]
    assert sum(r.get("skipped", False) for r in records) == 2 and sum("w_g" in r for r in records) == 2
    assert (out / "00.png").stat().st_mtime_ns == before and (out / "01.png").is_file()
    assert _fuse(vi, ir, "-o", out, "--weights", heads_file, "--force").exit_code == 0
    both = _fuse(vi, ir, "-o", out, "--weights", heads_file, "--force", "--skip-existing")
    assert both.exit_code == 1 and "exclude each other" in both.output


def test_json_records_failures_without_nan(tmp_path, folders, heads_file):
    vi, ir = folders
    res = _fuse(vi, ir, "-o", tmp_path / "o", "--weights", heads_file, "--json")
    records = [json.loads(x) for x in res.stdout.splitlines()]
    assert [r["out"][-6:] for r in records if "error" in r] == ["01.png", "02.png"]
    assert "NaN" not in res.stdout


def test_registered_resizes_infrared_onto_the_visible_grid(tmp_path, make_scene, heads_file):
    rgb, t = make_scene(96, 128, 7)
    write_image(tmp_path / "v.png", rgb)
    write_image(tmp_path / "t.png", cv2.resize(t, (64, 48), interpolation=cv2.INTER_AREA))
    refused = _fuse(tmp_path / "v.png", tmp_path / "t.png", "-o", tmp_path / "f.png", "--weights", heads_file)
    assert refused.exit_code == 1 and "v.png is 128x96 but" in refused.stderr and "t.png is 64x48" in refused.stderr
    assert refused.stderr.startswith("Error: ") and len(refused.stderr.strip().splitlines()) == 1
    res = _fuse(tmp_path / "v.png", tmp_path / "t.png", "-o", tmp_path / "f.png", "--weights", heads_file,
                "--registered")
    assert res.exit_code == 0, res.stderr
    assert read_image(tmp_path / "f.png").shape == (96, 128, 3)
    both = _fuse(tmp_path / "v.png", tmp_path / "t.png", "-o", tmp_path / "g.png", "--registered", "--calib",
                 tmp_path / "c.json")
    assert both.exit_code != 0 and "exclude each other" in both.stderr


def test_registered_refuses_a_pair_of_other_aspect_ratios(tmp_path, make_scene, heads_file):
    rgb, t = make_scene(96, 128, 7)
    write_image(tmp_path / "v.png", rgb)
    write_image(tmp_path / "t.png", cv2.resize(t, (120, 96), interpolation=cv2.INTER_AREA))  # 5:4 against 4:3
    res = _fuse(tmp_path / "v.png", tmp_path / "t.png", "-o", tmp_path / "f.png", "--weights", heads_file,
                "--registered")
    assert res.exit_code == 1 and "one aspect ratio" in res.stderr and "t.png is 120x96" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and not (tmp_path / "f.png").exists()
    write_image(tmp_path / "t.png", cv2.resize(t, (127, 96), interpolation=cv2.INTER_AREA))  # rounding: accepted
    assert _fuse(tmp_path / "v.png", tmp_path / "t.png", "-o", tmp_path / "f.png", "--weights", heads_file,
                 "--registered").exit_code == 0


def test_calibration_made_for_other_sizes_is_refused(tmp_path, make_scene, heads_file):
    from rgbt_toolkit.registration.calib import Calibration, save_calibration

    rgb, t = make_scene(96, 128, 8)
    write_image(tmp_path / "v.png", rgb)
    write_image(tmp_path / "t.png", t)
    calib = tmp_path / "calib.json"
    save_calibration(calib, Calibration(np.eye(3), "homography", (640, 480), (640, 512)))
    res = _fuse(tmp_path / "v.png", tmp_path / "t.png", "-o", tmp_path / "f.png", "--weights", heads_file,
                "--calib", calib)
    assert res.exit_code == 1
    assert (f"{calib}: calibration made for RGB 640x480 and thermal 640x512, but {tmp_path / 'v.png'} is 128x96 "
            f"and {tmp_path / 't.png'} is 128x96") in res.stderr
    save_calibration(calib, Calibration(np.eye(3), "homography", (128, 96), (128, 96)))
    assert _fuse(tmp_path / "v.png", tmp_path / "t.png", "-o", tmp_path / "f.png", "--weights", heads_file,
                 "--calib", calib).exit_code == 0


@pytest.mark.parametrize("name", ["o.txt", "o.webp"])
def test_output_with_a_non_image_suffix_is_an_error_not_a_folder(tmp_path, folders, name):
    vi, ir = folders
    res = _fuse(vi / "00.jpg", ir / "00.png", "-o", tmp_path / name)
    assert res.exit_code == 1 and "cannot write a" in res.stderr and not (tmp_path / name).exists()


def test_folder_input_always_writes_a_folder(tmp_path, make_scene, heads_file):
    rgb, t = make_scene(64, 80, 9)
    write_image(tmp_path / "vi" / "a.png", rgb)
    write_image(tmp_path / "ir" / "a.png", t)
    res = _fuse(tmp_path / "vi", tmp_path / "ir", "-o", tmp_path / "out.png", "--weights", heads_file)
    assert res.exit_code == 0, res.stderr
    assert (tmp_path / "out.png" / "a.png").is_file()
    (tmp_path / "file.png").write_bytes(b"x")
    res = _fuse(tmp_path / "vi", tmp_path / "ir", "-o", tmp_path / "file.png", "--weights", heads_file)
    assert res.exit_code == 1 and "exists and is not a folder" in res.stderr
    # an existing folder named like an image receives <stem>.png for a single pair too
    res = _fuse(tmp_path / "vi" / "a.png", tmp_path / "ir" / "a.png", "-o", tmp_path / "out.png", "--weights",
                heads_file, "--force")
    assert res.exit_code == 0 and (tmp_path / "out.png" / "a.png").is_file()


def test_weight_map_names_are_checked_up_front(tmp_path, make_scene, heads_file):
    rgb, t = make_scene(64, 80, 10)
    for stem in ("a", "a_weights"):
        write_image(tmp_path / "vi" / f"{stem}.png", rgb)
        write_image(tmp_path / "ir" / f"{stem}.png", t)
    out = tmp_path / "out"
    res = _fuse(tmp_path / "vi", tmp_path / "ir", "-o", out, "--weights", heads_file, "--save-weights")
    assert res.exit_code == 1 and "would be both the weight map of" in res.stderr
    assert "and the fused image of" in res.stderr
    assert not out.exists()
    one = [tmp_path / "vi" / "a.png", tmp_path / "ir" / "a.png", "-o", tmp_path / "f.png", "--weights", heads_file]
    (tmp_path / "f_weights.png").write_bytes(b"keep")
    res = _fuse(*one, "--save-weights")
    assert res.exit_code == 1 and "f_weights.png exists; pass --force" in res.stderr
    assert (tmp_path / "f_weights.png").read_bytes() == b"keep" and not (tmp_path / "f.png").exists()


def test_output_never_overwrites_an_input(tmp_path, make_scene, heads_file):
    rgb, t = make_scene(64, 80, 11)
    write_image(tmp_path / "vi" / "a.png", rgb)
    write_image(tmp_path / "ir" / "a.png", t)
    res = _fuse(tmp_path / "vi", tmp_path / "ir", "-o", tmp_path / "vi", "--weights", heads_file, "--force")
    assert res.exit_code == 1 and "would overwrite an input image" in res.stderr


def test_heads_for_another_backbone_name_the_file_and_the_option(tmp_path, folders):
    from rgbt_toolkit.fusion.network import HeadConfig, MFNetHeads
    from rgbt_toolkit.fusion.weights_io import save_heads

    vi, ir = folders
    vgg, wide = tmp_path / "vgg.pt", tmp_path / "wide.pt"
    save_heads(vgg, MFNetHeads(HeadConfig(backbone="vggm", layer="conv5", in_channels=1024)))
    save_heads(wide, MFNetHeads(HeadConfig(in_channels=100)))
    res = _fuse(vi / "00.jpg", ir / "00.png", "-o", tmp_path / "f.png", "--weights", vgg)
    assert res.exit_code == 1 and f"{vgg}: heads trained on backbone 'vggm'" in res.stderr
    assert "--backbone-weights" in res.stderr
    res = _fuse(vi / "00.jpg", ir / "00.png", "-o", tmp_path / "f.png", "--weights", wide)
    assert res.exit_code == 1 and f"{wide}: MFNet heads expect 100 channels" in res.stderr


def test_grey_alpha_and_sixteen_bit_inputs_fuse(tmp_path, make_scene, heads_file):
    rgb, t = make_scene(64, 80, 12)
    grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    write_image(tmp_path / "la.png", np.stack([grey, np.full_like(grey, 255)], axis=2))
    write_image(tmp_path / "t16.png", (t.astype(np.uint16) * 8 + 7000))  # counts 7000..9040, like a raw sensor
    res = _fuse(tmp_path / "la.png", tmp_path / "t16.png", "-o", tmp_path / "f.png", "--weights", heads_file)
    assert res.exit_code == 0, res.stderr
    fused = read_image(tmp_path / "f.png")
    assert fused.shape == (64, 80) and fused.std() > 20  # /257 would give a flat thermal image of ~30
