"""``rgbt register`` through click's CliRunner on tiny generated inputs."""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.images import write_image
from rgbt_toolkit.registration import corner_error, load_calibration


@pytest.fixture(scope="module")
def images(tmp_path_factory, make_pair):
    folder = tmp_path_factory.mktemp("register")
    visible, thermal, truth = make_pair(5)
    write_image(folder / "rgb.png", visible)
    write_image(folder / "t.png", thermal)
    write_image(folder / "blank.png", np.zeros_like(thermal))
    return folder, truth, (visible.shape[1], visible.shape[0])


def test_register_images_writes_calibration_and_preview(images):
    folder, truth, size = images
    out, prev = folder / "calib.json", folder / "check.png"
    result = CliRunner().invoke(main, ["register", str(folder / "rgb.png"), str(folder / "t.png"), "-o", str(out),
                                       "--preview", str(prev)])
    assert result.exit_code == 0, result.output
    assert "RGB -> thermal homography" in result.output and "quality" in result.output
    assert "time offset +0.000 s" in result.output
    evidence = float(result.output.split("evidence ")[1].split()[0])  # the reason it was trusted is printed too
    assert evidence >= 1.5 and "second look" not in result.output
    # 1.62 px since the homography is pulled towards the similarity fit (stiffness 0.05, docs/registration.md): the
    # price on a true keystone for steadier homographies on real, non-planar scenes
    assert corner_error(load_calibration(out).matrix, truth, size) < 2.0
    assert prev.is_file() and prev.stat().st_size > 0
    again = CliRunner().invoke(main, ["register", str(folder / "rgb.png"), str(folder / "t.png"), "-o", str(out)])
    assert again.exit_code == 1 and "already exists; pass --force" in again.output


def test_register_reports_a_given_offset(images):
    """--offset is written to the calibration and printed as given (it once printed +0.000 s, "not estimated")."""
    folder, _, _ = images
    out = folder / "given.json"
    result = CliRunner().invoke(main, ["register", str(folder / "rgb.png"), str(folder / "t.png"), "-o", str(out),
                                       "--offset", "0.5", "--model", "similarity"])
    assert result.exit_code == 0, result.output
    assert "time offset +0.500 s (given" in result.output
    assert load_calibration(out).time_offset == 0.5


def test_preview_mode_without_preview_is_refused(images):
    folder, _, _ = images
    out = folder / "mode.json"
    result = CliRunner().invoke(main, ["register", str(folder / "rgb.png"), str(folder / "t.png"), "-o", str(out),
                                       "--preview-mode", "overlay"])
    assert result.exit_code == 1 and "--preview-mode needs --preview" in result.output
    assert not out.exists()


def test_register_json_and_similarity(images):
    folder, truth, size = images
    out = folder / "sim.json"
    result = CliRunner().invoke(main, ["register", str(folder / "rgb.png"), str(folder / "t.png"), "-o", str(out),
                                       "--model", "similarity", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    assert data["model"] == "similarity" and data["rgb_to_thermal"][2] == [0.0, 0.0, 1.0]


def test_blank_thermal_is_one_line_error(images):
    folder, _, _ = images
    result = CliRunner().invoke(main, ["register", str(folder / "rgb.png"), str(folder / "blank.png"), "-o",
                                       str(folder / "never.json")])
    assert result.exit_code == 1
    assert "blank" in result.output and "Traceback" not in result.output
    assert str(folder / "blank.png") in result.output  # names the recording at fault
    assert len(result.output.strip().splitlines()) == 1
    assert not (folder / "never.json").exists()


def test_single_frame_video_cannot_sync(tmp_path, make_pair):
    from rgbt_toolkit.io.video import write_video

    visible, thermal, _ = make_pair(6)
    write_video(tmp_path / "rgb.mp4", [visible[: visible.shape[0] // 2 * 2, : visible.shape[1] // 2 * 2]], fps=25)
    write_video(tmp_path / "t.mp4", [np.repeat(thermal[..., None], 3, axis=2)], fps=25)
    result = CliRunner().invoke(main, ["register", str(tmp_path / "rgb.mp4"), str(tmp_path / "t.mp4"), "-o",
                                       str(tmp_path / "c.json"), "--sync"])
    assert result.exit_code == 1 and "single frame carries no motion" in result.output


def test_evidence_line_says_how_the_estimate_was_trusted():
    from rgbt_toolkit.registration.report import evidence_line

    assert evidence_line({"evidence": 2.345}).startswith("evidence 2.35 ")
    weak = evidence_line({"evidence": 1.3, "blocks_agreeing": 6, "blocks_textured": 14, "second_look": True})
    assert "6 of 14 blocks agree" in weak and "second look" in weak
    assert evidence_line({}) == "evidence: not recorded"
    refused_look = evidence_line({"evidence": 1.6, "second_look": {"evidence": 0.9}})  # a refusal's record, not a find
    assert "second look" not in refused_look


def _register(*args):
    return CliRunner().invoke(main, ["register", *map(str, args)])


def test_output_paths_are_checked_before_registering(images, tmp_path):
    folder, _, _ = images
    rgb, t = folder / "rgb.png", folder / "t.png"
    before = t.read_bytes()
    (tmp_path / "a_file").write_text("x")
    cases = [  # arguments, message, the path it must name
        ((rgb, t, "-o", tmp_path / "c.json", "--preview", tmp_path / "p.txt"), "the preview is an image",
         tmp_path / "p.txt"),
        ((rgb, t, "-o", tmp_path / "same.png", "--preview", tmp_path / "same.png"), "cannot be the same file",
         tmp_path / "same.png"),
        ((rgb, t, "-o", t, "--force"), "would overwrite an input recording", t),
        ((rgb, t, "-o", tmp_path / "c.json", "--preview", t, "--force"), "would overwrite an input recording", t),
        ((rgb, t, "-o", tmp_path / "a_file" / "sub" / "c.json"), "is a file, not a folder",
         tmp_path / "a_file" / "sub" / "c.json"),
    ]
    for args, message, named in cases:
        result = _register(*args)
        assert result.exit_code == 1 and message in result.output, (args, result.output)
        assert len(result.output.strip().splitlines()) == 1 and f"Error: {named}:" in result.output
    assert t.read_bytes() == before and not (tmp_path / "c.json").exists()


def test_failing_preview_leaves_no_calibration(images, tmp_path, monkeypatch):
    import rgbt_toolkit.registration.report as report
    from rgbt_toolkit.errors import RegistrationError

    def broken(*args, **kwargs):
        raise RegistrationError("no frames to draw the preview from")

    monkeypatch.setattr(report, "write_preview", broken)
    folder, _, _ = images
    out = tmp_path / "c.json"
    result = _register(folder / "rgb.png", folder / "t.png", "-o", out, "--preview", tmp_path / "p.png")
    assert result.exit_code == 1 and "preview" in result.output
    assert not out.exists()


def test_too_many_pairs_is_a_usage_error(images, tmp_path):
    folder, _, _ = images
    result = _register(folder / "rgb.png", folder / "t.png", "-o", tmp_path / "c.json", "--pairs", 500)
    assert result.exit_code == 2 and "1<=x<=32" in result.output


def test_cli_pair_limit_matches_the_library():
    from rgbt_cli import cmd_register
    from rgbt_toolkit.registration.pipeline import MAX_PAIRS

    assert cmd_register.MAX_PAIRS == MAX_PAIRS


@pytest.fixture(scope="module")
def scene_videos(tmp_path_factory):
    """A 5-s moving-camera scene (RGB 320x240 at 30 fps, thermal 256x192 at 25 fps, thermal clock 0.45 s behind)."""
    synth = pytest.importorskip("rgbt_toolkit.synth")
    cfg = synth.SceneConfig(challenges=frozenset({"camera_motion"}), seed=9, duration=5.0, rgb_fps=30.0, t_fps=25.0,
                            t_offset=0.45)
    renderer = synth.SceneRenderer(cfg)
    return synth.write_scene_videos(renderer, tmp_path_factory.mktemp("scene")), renderer


def test_sync_with_max_offset_beyond_the_clip_does_not_crash(scene_videos, tmp_path):
    paths, renderer = scene_videos
    out, prev = tmp_path / "c.json", tmp_path / "p.png"
    result = _register(paths["rgb"], paths["t"], "-o", out, "--sync", "--max-offset", 100, "--preview", prev)
    assert result.exit_code == 0, result.output
    assert load_calibration(out).time_offset == pytest.approx(-0.45, abs=1 / 25)
    # camera shake between exposures a fraction of a frame apart costs ~2 px here (see test_pipeline.py)
    assert corner_error(load_calibration(out).matrix, renderer.h_rgb_to_t, (320, 240)) < 3.0
    assert prev.is_file()


def test_known_offset_and_sync_exclude_each_other(scene_videos, tmp_path):
    paths, _ = scene_videos
    result = _register(paths["rgb"], paths["t"], "-o", tmp_path / "c.json", "--sync", "--offset", 0.5)
    assert result.exit_code == 1 and "not both" in result.output
    result = _register(paths["rgb"], paths["t"], "-o", tmp_path / "c.json", "--offset", -0.45, "--json")
    assert result.exit_code == 0, result.output
    assert json.loads(result.output)["time_offset_s"] == -0.45


def test_a_featureless_pair_is_refused_in_one_line(tmp_path):
    """Uniform grey with one small moving square in each camera: nothing to register; once a traceback
    (ZeroDivisionError on the coarse search's margin), now one line and no calibration file."""
    import numpy as np

    from rgbt_toolkit.io.video import write_video

    def frames(offset):
        for k in range(15):
            image = np.full((120, 160, 3), 128, np.uint8)
            image[40 + k:48 + k, 30 + 4 * k + offset:38 + 4 * k + offset] = 250
            yield image

    write_video(tmp_path / "z_rgb.mp4", frames(0), 10.0)
    write_video(tmp_path / "z_t.mp4", frames(3), 10.0)
    out = tmp_path / "z.json"
    result = CliRunner().invoke(main, ["register", str(tmp_path / "z_rgb.mp4"), str(tmp_path / "z_t.mp4"), "-o",
                                       str(out)])
    assert result.exit_code != 0 and not out.exists()
    assert "Traceback" not in result.output and result.exception is None or isinstance(result.exception, SystemExit)
    assert len(result.output.strip().splitlines()) == 1, result.output
