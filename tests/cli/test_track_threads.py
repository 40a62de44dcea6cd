"""`rgbt track --threads N`: N is the whole run's CPU budget (one core for the reader and writer threads, two tracker
threads when two or more cores are left, libraries half of those each), and every setting gives the same boxes (the
trackers are independent until fusion)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.registration.calib import Calibration, save_calibration
from rgbt_toolkit.runtime import split_tracker_threads

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


def test_split(monkeypatch):
    assert split_tracker_threads(1) == (1, False)
    assert split_tracker_threads(2) == (1, True)
    assert split_tracker_threads(5) == (2, True)
    monkeypatch.delenv("RGBT_THREADS", raising=False)
    assert split_tracker_threads() == (1, True)
    monkeypatch.setenv("RGBT_THREADS", "1")
    assert split_tracker_threads() == (1, False)
    # with a reader and a writer thread (rgbt track's default) one core is theirs
    assert split_tracker_threads(1, io_threads=True) == (1, False)
    assert split_tracker_threads(2, io_threads=True) == (1, False)
    assert split_tracker_threads(3, io_threads=True) == (1, True)
    assert split_tracker_threads(5, io_threads=True) == (2, True)
    monkeypatch.setenv("RGBT_THREADS", "two")
    with pytest.raises(InputError, match="RGBT_THREADS='two'"):
        split_tracker_threads()


def test_one_and_two_threads_track_the_sample_identically(tmp_path):
    scene = json.loads((SAMPLES / "demo_scene.json").read_text())
    calib = tmp_path / "calib.json"
    cfg = scene["config"]
    save_calibration(calib, Calibration(matrix=np.array(scene["h_rgb_to_t"]), model="homography",
                                        rgb_size=tuple(cfg["rgb_size"]), thermal_size=tuple(cfg["t_size"])))
    boxes = {}
    # (threads, extra options, whether the RGB and thermal trackers run side by side)
    for threads, extra, parallel in (("1", [], False), ("2", [], False), ("3", [], True),
                                     ("2", ["--no-io-threads"], True)):
        out = tmp_path / f"t{threads}{len(extra)}"
        result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                           "--calib", str(calib), "--max-frames", "12", "--no-video", "--no-plot",
                                           "--threads", threads, "-o", str(out), *extra])
        assert result.exit_code == 0, result.output
        boxes[threads, parallel] = read_boxes(out / "boxes_rgb.txt")
        assert json.loads((out / "track.json").read_text())["config"]["parallel_trackers"] == parallel
    first = boxes["1", False]
    assert len(first) == 12
    for other in boxes.values():
        np.testing.assert_allclose(other, first, atol=0.05)
