"""`rgbt track --threads N`: N is the whole run's CPU budget (two tracker threads from 2 on, libraries N // 2 each),
and the two settings give identical results (the trackers are independent until fusion)."""

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
    for threads in ("1", "2"):
        out = tmp_path / f"t{threads}"
        result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                           "--calib", str(calib), "--max-frames", "12", "--no-video", "--no-plot",
                                           "--threads", threads, "-o", str(out)])
        assert result.exit_code == 0, result.output
        boxes[threads] = read_boxes(out / "boxes_rgb.txt")
        assert json.loads((out / "track.json").read_text())["config"]["parallel_trackers"] == (threads == "2")
    assert len(boxes["1"]) == 12
    np.testing.assert_allclose(boxes["1"], boxes["2"], atol=0.05)
