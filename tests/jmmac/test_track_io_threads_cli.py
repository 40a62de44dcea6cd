"""`rgbt track` with and without I/O threads (`--no-io-threads`), `--video-scale`, a writer failure as one line, and
a real Ctrl-C (SIGINT) delivered to the command mid-run."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io import video as video_module
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.video import VideoReader
from rgbt_toolkit.registration.calib import Calibration, save_calibration

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
PAIR = [str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4")]


@pytest.fixture(scope="module")
def calib(tmp_path_factory) -> Path:
    scene = json.loads((SAMPLES / "demo_scene.json").read_text())
    path = tmp_path_factory.mktemp("calib") / "calib.json"
    cfg = scene["config"]
    save_calibration(path, Calibration(matrix=np.array(scene["h_rgb_to_t"]), model="homography",
                                       rgb_size=tuple(cfg["rgb_size"]), thermal_size=tuple(cfg["t_size"])))
    return path


def test_the_real_tracker_gives_the_same_boxes_with_and_without_io_threads(calib, tmp_path):
    boxes = {}
    for flag in ("--no-io-threads", None):
        out = tmp_path / (flag or "threads")
        args = ["track", *PAIR, "--calib", str(calib), "--max-frames", "12", "--no-plot", "--threads", "1",
                "--video-scale", "0.5", "-o", str(out)] + ([flag] if flag else [])
        result = CliRunner().invoke(main, args)
        assert result.exit_code == 0, result.output
        boxes[flag] = read_boxes(out / "boxes_rgb.txt")
        assert json.loads((out / "track.json").read_text())["summary"]["io_threads"] is (flag is None)
        assert VideoReader(out / "annotated.mp4").size[1] == 120  # 240-px frames drawn at half size
    assert len(boxes[None]) == 12
    # as test_track_threads: the tracker itself is not bit-reproducible from run to run (float reductions)
    np.testing.assert_allclose(boxes[None], boxes["--no-io-threads"], atol=0.05)


def test_video_scale_needs_the_video(tmp_path):
    result = CliRunner().invoke(main, ["track", *PAIR, "--assume-aligned", "--no-video", "--video-scale", "0.5",
                                       "-o", str(tmp_path / "o")])
    assert result.exit_code != 0 and "--video-scale sets how annotated.mp4 is written" in result.output
    assert not (tmp_path / "o").exists()
    result = CliRunner().invoke(main, ["track", *PAIR, "--video-scale", "0", "-o", str(tmp_path / "o")])
    assert result.exit_code == 2 and "--video-scale" in result.output


def test_a_full_disk_while_encoding_is_one_line_and_the_box_files_stand(calib, tmp_path, monkeypatch):
    original = video_module.VideoWriter.write

    def write(self, frame):
        if self.frames_written == 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        original(self, frame)

    monkeypatch.setattr(video_module.VideoWriter, "write", write)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["track", *PAIR, "--calib", str(calib), "--max-frames", "20", "--threads", "1",
                                       "-o", str(out)])
    assert result.exit_code == 1
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert lines[-1] == f"Error: {out / 'annotated.mp4'}: cannot write the video (No space left on device)"
    assert "Traceback" not in result.output
    assert (out / "boxes_rgb.txt").is_file() and not (out / "annotated.mp4").exists()
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]


@pytest.mark.slow
def test_sigint_mid_run_leaves_complete_files_and_no_temporaries(calib, tmp_path):
    out = tmp_path / "out"
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    # a suite started as a background job of a non-interactive shell inherits SIGINT ignored, and Python then never
    # turns it into KeyboardInterrupt: give the child the default disposition, as a terminal's Ctrl-C finds it
    process = subprocess.Popen([sys.executable, "-m", "rgbt_cli.main", "track", *PAIR, "--calib", str(calib),
                                "--threads", "1", "-o", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               env=env, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    partial = out / ".track.json.partial"
    deadline = time.monotonic() + 120
    # track.json is flushed in 8 KB blocks: a non-empty partial file means about a dozen frames are tracked
    while time.monotonic() < deadline and process.poll() is None and \
            not (partial.is_file() and partial.stat().st_size > 0):
        time.sleep(0.05)
    assert process.poll() is None, "the run ended before it could be interrupted"
    process.send_signal(signal.SIGINT)
    try:
        _, stderr = process.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        process.kill()
        pytest.fail("rgbt track did not stop within 60 s of SIGINT")
    assert process.returncode == 130, stderr.decode()
    track = json.loads((out / "track.json").read_text())
    frames = len(track["frames"])
    assert track["summary"]["interrupted"] is True and 0 < frames < 75
    assert read_boxes(out / "boxes_rgb.txt").shape == (frames, 4)
    assert VideoReader(out / "annotated.mp4").frame_count == frames
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]
