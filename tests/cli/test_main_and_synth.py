"""The command group and ``rgbt synth`` through click's runner."""

from __future__ import annotations

import json

import numpy as np
from click.testing import CliRunner

import rgbt_toolkit
from rgbt_cli.main import main
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.sequences import read_sequence
from rgbt_toolkit.io.video import VideoReader


def test_version_and_help_list_the_discovered_commands():
    runner = CliRunner()
    assert runner.invoke(main, ["--version"]).output.strip().endswith(rgbt_toolkit.__version__)
    result = runner.invoke(main, ["--help"])
    assert result.exit_code == 0 and "synth" in result.output


def test_synth_videos_with_different_rates_and_offset(tmp_path):
    result = CliRunner().invoke(main, ["synth", str(tmp_path), "-c", "camera_motion,occlusion", "--duration", "1",
                                       "--rgb-fps", "10", "--t-fps", "8", "--t-offset", "0.25", "--name", "x"])
    assert result.exit_code == 0, result.output
    rgb, t = VideoReader(tmp_path / "x_rgb.mp4"), VideoReader(tmp_path / "x_t.mp4")
    assert (rgb.frame_count, t.frame_count) == (10, 8) and (rgb.size, t.size) == ((320, 240), (256, 192))
    truth = json.loads((tmp_path / "x_scene.json").read_text())
    assert truth["t"]["offset_seconds"] == 0.25 and truth["config"]["challenges"] == ["camera_motion", "occlusion"]
    assert truth["t"]["frames"][1]["time"] == 0.125 + 0.25
    boxes = read_boxes(tmp_path / "x_t.boxes.txt")
    assert boxes.shape == (8, 4)
    np.testing.assert_allclose(boxes[2], truth["t"]["frames"][2]["box"], atol=1e-3)
    np.testing.assert_allclose(read_boxes(tmp_path / "x_rgb.init.txt")[0], truth["rgb"]["frames"][0]["box"], atol=1e-3)


def test_synth_sequence_layout_is_readable_by_the_benchmark_reader(tmp_path):
    result = CliRunner().invoke(main, ["synth", str(tmp_path), "--layout", "rgbt234", "--duration", "0.5"])
    assert result.exit_code == 0, result.output
    sequence = read_sequence(tmp_path / "scene")
    assert sequence.layout == "rgbt234" and len(sequence) == 8 and sequence.gt_t.shape == (8, 4)


def test_bad_options_are_one_line_errors(tmp_path):
    result = CliRunner().invoke(main, ["synth", str(tmp_path), "-c", "teleport"])
    assert result.exit_code != 0 and "unknown challenge" in result.output and "Traceback" not in result.output
    assert not any(tmp_path.iterdir())


def test_synth_help_names_every_challenge():
    """The epilog is written out by hand (the CLI imports no library code at start-up); it must not fall behind."""
    from click.testing import CliRunner

    from rgbt_cli.main import main
    from rgbt_toolkit.synth import CHALLENGES

    text = " ".join(CliRunner().invoke(main, ["synth", "--help"]).output.split())
    assert [name for name in CHALLENGES if name not in text] == []
