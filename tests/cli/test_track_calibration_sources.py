"""Issue #20 part B end to end: every calibration source into ``rgbt track``, and no silent registration fallback.

One generated rig (320x240 RGB -> 256x192 thermal, 1.1x zoom, 1.5 deg roll, a shift, 3 % keystone; the thermal clock
0.2 s behind) is calibrated from hand-picked points, from the target's boxes, and from a heated board; each
calibration then drives ``rgbt track``, whose thermal boxes must be the RGB boxes carried by the true rig geometry.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.jmmac.inputs import map_box
from rgbt_toolkit.registration.transforms import project

T_OFFSET = 0.2
SIZES = ["--rgb-size", "320x240", "--thermal-size", "256x192"]
TRACK = ["--preset", "B-T", "--no-video", "--no-plot", "--max-frames", "4"]


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """The scene videos, their box files and truth, and a board recorded by the same rig."""
    folder = tmp_path_factory.mktemp("rig")
    runner = CliRunner()
    scene = runner.invoke(main, ["synth", str(folder), "--duration", "3", "--t-offset", str(T_OFFSET)])
    assert scene.exit_code == 0, scene.output
    board = runner.invoke(main, ["synth", str(folder), "--board", "7x5", "--board-views", "4"])
    assert board.exit_code == 0, board.output
    truth = np.array(json.loads((folder / "scene_scene.json").read_text())["h_rgb_to_t"])
    return folder, truth / truth[2, 2]


def _evidence(source: str, folder, truth) -> list[str]:
    if source == "points":
        rng = np.random.default_rng(3)
        rgb = rng.uniform([30, 30], [290, 210], (9, 2))
        thermal = project(truth, rgb) + rng.normal(0, 0.4, rgb.shape)  # clicks are good to about half a pixel
        rows = [f"{a:.2f},{b:.2f},{c:.2f},{d:.2f}" for (a, b), (c, d) in zip(rgb, thermal)]
        (folder / "points.csv").write_text("x_rgb,y_rgb,x_t,y_t\n" + "\n".join(rows) + "\n")
        return ["--points", str(folder / "points.csv"), *SIZES]
    if source == "boxes":
        return ["--from-boxes", str(folder / "scene_rgb.boxes.txt"), str(folder / "scene_t.boxes.txt"), "--fps", "15",
                *SIZES]
    return ["--board", "7x5", str(folder / "board_rgb"), str(folder / "board_t")]


@pytest.mark.parametrize("source", ["points", "boxes", "board"])
def test_each_calibration_source_drives_track_with_the_rig_geometry(rig, source, tmp_path):
    folder, truth = rig
    calib = tmp_path / f"{source}.json"
    made = CliRunner().invoke(main, ["register", *_evidence(source, folder, truth), "-o", str(calib)])
    assert made.exit_code == 0, made.output
    assert "residuals: RMS" in made.output and f"(from {source})" in made.output
    stored = json.loads(calib.read_text())
    assert stored["source"] == source and stored["residuals"]["rms"] < 1.0
    if source == "boxes":  # the box tracks are 3 frames apart: the clock offset comes with the geometry
        assert stored["time_offset_s"] == pytest.approx(-T_OFFSET)
    offset = [] if source == "boxes" else ["--offset", str(-T_OFFSET)]
    out = tmp_path / "out"
    tracked = CliRunner().invoke(main, ["track", str(folder / "scene_rgb.mp4"), str(folder / "scene_t.mp4"),
                                        "--calib", str(calib), *offset, *TRACK, "-o", str(out)])
    assert tracked.exit_code == 0, tracked.output
    boxes_rgb, boxes_t = read_boxes(out / "boxes_rgb.txt"), read_boxes(out / "boxes_t.txt")
    assert boxes_rgb.shape == boxes_t.shape == (4, 4)
    expected = np.array([map_box(truth, box) for box in boxes_rgb])
    np.testing.assert_allclose(boxes_t, expected, atol=1.5)  # thermal boxes where the true rig puts them
    scaled = np.array([map_box(np.diag([0.8, 0.8, 1.0]), box) for box in boxes_rgb])
    assert np.abs(scaled - expected).max() > 8  # the old resolution-only guess would have missed by this much


@pytest.fixture(scope="module")
def night_pair(tmp_path_factory):
    """A night pair: the RGB camera sees nothing (black sky), the thermal one a warm drone crossing a cold sky."""
    from rgbt_toolkit.io.video import write_video

    folder = tmp_path_factory.mktemp("night")
    rng = np.random.default_rng(0)
    rgb, thermal = [], []
    for k in range(10):
        rgb.append(np.full((240, 320, 3), 6, np.uint8))
        sky = np.full((192, 256), 40.0) + rng.normal(0, 0.8, (192, 256))
        sky[90:98, 40 + 6 * k:52 + 6 * k] = 210
        thermal.append(np.repeat(sky.clip(0, 255).astype(np.uint8)[:, :, None], 3, axis=2))
    write_video(folder / "night_rgb.mp4", rgb, fps=15)
    write_video(folder / "night_t.mp4", thermal, fps=15)
    return folder


def test_unregistrable_pair_stops_before_tracking_with_the_remedies(night_pair):
    out = night_pair / "out"
    result = CliRunner().invoke(main, ["track", str(night_pair / "night_rgb.mp4"), str(night_pair / "night_t.mp4"),
                                       *TRACK, "-o", str(out)])
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert len(lines) == 1, result.output
    assert "no RGB->T transform (registration failed:" in lines[0] and "blank" in lines[0]
    for remedy in ("--calib FILE", "--assume-aligned", "--points FILE", "--from-boxes", "--board COLSxROWS"):
        assert remedy in lines[0]
    assert not out.exists()  # nothing written, not even the folder


def test_assume_aligned_tracks_with_the_resolution_scaling_it_asked_for(night_pair):
    out = night_pair / "aligned"
    result = CliRunner().invoke(main, ["track", str(night_pair / "night_rgb.mp4"), str(night_pair / "night_t.mp4"),
                                       "--assume-aligned", "--init", "50,112,15,10", *TRACK, "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "--assume-aligned: the views are taken as registered" in result.output
    first_rgb, first_t = read_boxes(out / "boxes_rgb.txt")[0], read_boxes(out / "boxes_t.txt")[0]
    np.testing.assert_allclose(first_t, first_rgb * 0.8, atol=1e-2)  # 320x240 -> 256x192: the scaling, nothing else
    from rgbt_toolkit.registration.calib import Calibration, save_calibration

    save_calibration(night_pair / "c.json", Calibration(np.diag([0.8, 0.8, 1.0]), "similarity", (320, 240), (256, 192)))
    both = CliRunner().invoke(main, ["track", str(night_pair / "night_rgb.mp4"), str(night_pair / "night_t.mp4"),
                                     "--assume-aligned", "--calib", str(night_pair / "c.json"), *TRACK])
    assert both.exit_code == 1 and "either --calib" in both.output and "not both" in both.output


def test_api_without_calibration_or_assume_aligned_raises(night_pair):
    import rgbt_toolkit
    from rgbt_toolkit.errors import RegistrationError

    rgb = [np.full((48, 64, 3), 6, np.uint8)] * 3
    thermal = [np.full((40, 50), 40, np.uint8)] * 3
    with pytest.raises(RegistrationError, match="assume_aligned=True"):
        rgbt_toolkit.track(rgb, thermal, init=(10, 10, 8, 8), preset="B-T")
    with pytest.raises(RegistrationError, match="no RGB->T transform"):
        rgbt_toolkit.Tracker(preset="B-T").initialize(rgb[0], thermal[0], (10, 10, 8, 8))
    with pytest.raises(RegistrationError, match="--assume-aligned"):
        rgbt_toolkit.track(night_pair / "night_rgb.mp4", night_pair / "night_t.mp4", preset="B-T", max_frames=2)
    result = rgbt_toolkit.track(rgb, thermal, init=(10, 10, 8, 8), preset="B-T", assume_aligned=True)
    np.testing.assert_allclose(result.boxes_t[0], [10 * 50 / 64, 10 * 40 / 48, 8 * 50 / 64, 8 * 40 / 48], atol=1e-6)
