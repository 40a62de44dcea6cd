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


def test_bad_thread_setting_is_one_line_not_a_traceback(tmp_path):
    img = tmp_path / "a.png"
    from rgbt_toolkit.io.images import write_image

    write_image(img, np.zeros((8, 8), np.uint8))
    for value, says in (("abc", "RGBT_THREADS='abc' is not a whole number"), ("0", "at least 1")):
        result = CliRunner().invoke(main, ["fusion-metrics", "--vis", str(img), "--ir", str(img), "--fused", str(img)],
                                    env={"RGBT_THREADS": value})
        assert result.exit_code == 1 and says in result.output and "Traceback" not in result.output


def test_output_under_a_file_is_one_line_naming_the_path_given(tmp_path):
    blocker = tmp_path / "afile"
    blocker.write_text("x")
    result = CliRunner().invoke(main, ["synth", str(blocker / "sub"), "--duration", "0.1"])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert str(blocker) in result.output and len(result.output.strip().splitlines()) == 1


def test_atomic_write_errors_name_the_target_not_the_temporary_file(tmp_path, monkeypatch):
    import errno
    import os

    import pytest

    from rgbt_toolkit import _atomic

    def refuse(src, dst):
        raise OSError(errno.EROFS, "Read-only file system", str(src))

    monkeypatch.setattr(_atomic.os, "replace", refuse)
    target = tmp_path / "out.json"
    with pytest.raises(OSError) as info:
        _atomic.write_text_atomic(target, "{}")
    assert info.value.filename == str(target) and info.value.errno == errno.EROFS
    assert os.listdir(tmp_path) == []  # and the temporary file is gone


def test_atomic_write_to_a_special_file_writes_through(tmp_path):
    """`-o /dev/null` once replaced the device with a plain file (rename onto it); a FIFO stands in for it here."""
    import os
    import stat
    import threading

    from rgbt_toolkit._atomic import write_text_atomic

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    received = []

    def read():
        with open(fifo) as fh:
            received.append(fh.read())

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    write_text_atomic(fifo, "hello")
    reader.join(timeout=10)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and received == ["hello"]


def test_up_front_output_check_lets_special_files_through(tmp_path):
    import os

    from rgbt_toolkit._atomic import check_writable

    os.mkfifo(tmp_path / "pipe")
    assert check_writable(tmp_path / "pipe", "boxes file") == tmp_path / "pipe"  # like -o /dev/null
