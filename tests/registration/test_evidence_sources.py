"""Calibration from points, boxes and a heated board (issue #20 part B): fits, residuals, the JSON, bad input.

Geometry comes from the synthetic rig (``SceneConfig`` defaults: 320x240 RGB -> 256x192 thermal, 1.1x zoom, 1.5 deg
roll, a shift and 3 % keystone), so each recovered transform is checked against the homography that rendered it.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.registration import corner_error, load_calibration
from rgbt_toolkit.registration.board import BoardSpec, calibrate_from_board, detect_board
from rgbt_toolkit.registration.calib import Calibration, save_calibration
from rgbt_toolkit.registration.fit import fit_points
from rgbt_toolkit.registration.from_boxes import best_shift, calibrate_from_boxes
from rgbt_toolkit.registration.transforms import project
from rgbt_toolkit.synth import SceneConfig, SceneRenderer

RGB_SIZE, T_SIZE = (320, 240), (256, 192)
SIZES = ["--rgb-size", "320x240", "--thermal-size", "256x192"]


@pytest.fixture(scope="module")
def rig() -> np.ndarray:
    return SceneRenderer(SceneConfig(duration=0.2)).h_rgb_to_t


def _points_file(path, rgb, thermal, header=True):
    rows = ["x_rgb,y_rgb,x_t,y_t"] if header else []
    rows += [f"{a:.3f},{b:.3f},{c:.3f},{d:.3f}" for (a, b), (c, d) in zip(rgb, thermal)]
    path.write_text("\n".join(rows) + "\n")
    return path


def _picked(rig, n=10, seed=0, noise=0.3):
    rng = np.random.default_rng(seed)
    rgb = rng.uniform([40, 30], [280, 210], (n, 2))
    return rgb, project(rig, rgb) + rng.normal(0, noise, (n, 2))


# ----- the robust fit ------------------------------------------------------------------------------------------------
def test_fit_names_a_misclicked_point_and_recovers_the_rig(rig):
    rgb, thermal = _picked(rig, 12)
    thermal[4] += (25, -10)  # one point clicked on the wrong feature
    fit = fit_points(rgb, thermal, "homography")
    assert list(fit.outliers) == [4]
    assert fit.residuals[4] > 20 and fit.rms < 0.6
    assert corner_error(fit.matrix, rig, RGB_SIZE) < 1.5


def test_two_points_fix_a_similarity_exactly():
    truth = np.array([[0.8, -0.05, 12.0], [0.05, 0.8, -3.0], [0, 0, 1.0]])
    rgb = np.array([[10.0, 20.0], [200.0, 150.0]])
    fit = fit_points(rgb, project(truth, rgb), "similarity")
    np.testing.assert_allclose(fit.matrix, truth, atol=1e-9)


@pytest.mark.parametrize("rgb, model, message", [
    ([[1, 1], [50, 60], [90, 10]], "homography", "3 correspondence\\(s\\); a homography needs at least 4"),
    ([[1, 1]], "similarity", "a similarity needs at least 2"),
    ([[0, 0], [10, 5], [20, 10], [30, 15], [40, 20]], "homography", "RGB points lie on one line"),
    ([[5, 5], [5, 5], [5.2, 5], [5, 5.1]], "homography", "all lie at one place"),
])
def test_degenerate_points_are_refused(rgb, model, message):
    rgb = np.asarray(rgb, float)
    with pytest.raises(InputError, match=message):
        fit_points(rgb, rgb * 0.8 + 3, model)


def test_points_that_fit_no_transform_are_refused(rig):
    rgb, _ = _picked(rig, 10)
    thermal = np.random.default_rng(1).uniform(0, 200, (10, 2))  # rows that do not pair the same features
    with pytest.raises(RegistrationError, match="agree within|residuals too large|scatter by|follow no one"):
        fit_points(rgb, thermal, "homography")


# ----- the calibration file ------------------------------------------------------------------------------------------
def test_residuals_and_source_round_trip_and_old_files_still_load(tmp_path):
    cal = Calibration(np.eye(3), "similarity", RGB_SIZE, T_SIZE, source="boxes", residuals=(0.5, 1.5, 30.0),
                      outliers=(2,))
    save_calibration(tmp_path / "c.json", cal)
    data = json.loads((tmp_path / "c.json").read_text())
    assert data["source"] == "boxes" and data["residuals"]["outliers"] == [2]
    assert data["residuals"]["rms"] == pytest.approx(np.sqrt((0.25 + 2.25) / 2), abs=1e-4)  # outlier left out
    again = load_calibration(tmp_path / "c.json")
    assert again.residuals == (0.5, 1.5, 30.0) and again.outliers == (2,) and again.residual_max == 1.5
    for key in ("source", "residuals"):
        del data[key]
    (tmp_path / "old.json").write_text(json.dumps(data))
    old = load_calibration(tmp_path / "old.json")
    assert old.source == "images" and old.residuals == () and np.isnan(old.residual_rms)
    data["residuals"] = {"per_point": [1.0], "outliers": [3]}
    (tmp_path / "bad.json").write_text(json.dumps(data))
    with pytest.raises(InputError, match="bad.json: 'residuals.outliers' must list indices"):
        load_calibration(tmp_path / "bad.json")


# ----- --points ------------------------------------------------------------------------------------------------------
def test_imprecise_points_are_refused_as_residuals_too_large(tmp_path, rig):
    rgb, thermal = _picked(rig, 12, noise=1.0)
    pts = _points_file(tmp_path / "pts.csv", rgb, thermal)
    result = CliRunner().invoke(main, ["register", "--points", str(pts), *SIZES, "--max-residual", "0.5",
                                       "-o", str(tmp_path / "c.json")])
    assert result.exit_code == 1 and "residuals too large (RMS" in result.output, result.output
    assert "accepted up to 0.5 px RMS" in result.output and not (tmp_path / "c.json").exists()


def test_register_points_writes_the_fit_and_its_residuals(tmp_path, rig):
    rgb, thermal = _picked(rig, 8)
    thermal[6] += (0, 30)
    pts = _points_file(tmp_path / "pts.csv", rgb, thermal)
    # 7 good points: too few for the default to take a homography (it would be a similarity), so it is asked for
    result = CliRunner().invoke(main, ["register", "--points", str(pts), *SIZES, "--model", "homography",
                                       "-o", str(tmp_path / "c.json")])
    assert result.exit_code == 0, result.output
    assert "from points" in result.output and "residuals: RMS" in result.output
    assert "outliers left out (1): line 8" in result.output  # row 7 of the data is line 8 (after the header)
    cal = load_calibration(tmp_path / "c.json")
    assert cal.source == "points" and cal.outliers == (6,) and cal.residual_rms < 0.6
    assert corner_error(cal.matrix, rig, RGB_SIZE) < 1.5


@pytest.mark.parametrize("rows, extra, message", [
    ("1,2,3,4\n10,20,30,40\n50,9,40,7\n", ["--model", "homography"],
     "3 correspondence\\(s\\); a homography needs at least 4"),
    ("1,2,3,4\n10,20,30,40\n50,9,40,7\n", [], "only 2 of 3 correspondences agree"),  # 2 fix a similarity exactly
    ("0,0,0,0\n10,10,8,8\n20,20,16,16\n30,30,24,24\n", ["--model", "homography"], "lie on one line"),
    ("1,2,3,4\nx,2,3,4\n", [], "line 2: 'x,2,3,4' is not four numbers"),
    ("1,2,3\n", [], "line 1: expected four numbers"),
    ("400,20,30,40\n10,20,30,40\n", ["--model", "similarity"], "line 1: point \\(400, 20\\) lies outside the 320x240"),
    ("10,10,200,10\n300,10,10,10\n10,200,190,180\n300,200,20,150\n150,120,90,60\n", [],
     "agree within|too large|mirrors|scatter by"),
])
def test_bad_points_files_are_one_line_and_write_nothing(tmp_path, rows, extra, message):
    (tmp_path / "p.csv").write_text(rows)
    result = CliRunner().invoke(main, ["register", "--points", str(tmp_path / "p.csv"), *SIZES, *extra,
                                       "-o", str(tmp_path / "c.json")])
    assert result.exit_code == 1, result.output
    assert len(result.output.strip().splitlines()) == 1
    assert __import__("re").search(message, result.output), result.output
    assert not (tmp_path / "c.json").exists()


@pytest.mark.parametrize("args, message", [
    (["-o", "c.json"], "nothing to calibrate from"),
    (["--points", "p.csv", "-o", "c.json"], "give --rgb-size WxH and --thermal-size WxH"),
    (["--points", "p.csv", "--from-boxes", "p.csv", "p.csv", *SIZES, "-o", "c.json"], "give one source"),
    (["--points", "p.csv", *SIZES, "--preview", "x.png", "-o", "c.json"], "give the RGB and THERMAL recordings"),
])
def test_register_without_usable_evidence_says_what_to_give(tmp_path, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.csv").write_text("1,2,3,4\n")
    result = CliRunner().invoke(main, ["register", *args])
    assert result.exit_code != 0 and message in result.output, result.output
    assert not (tmp_path / "c.json").exists()


# ----- --from-boxes --------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def walker_boxes(tmp_path_factory):
    """Both cameras' truth boxes of a 3 s scene whose thermal clock lags 0.2 s (thermal frame i shows RGB i+3)."""
    from rgbt_toolkit.io.boxes import write_boxes

    config = SceneConfig(duration=3.0, t_offset=0.2)
    renderer = SceneRenderer(config)
    folder = tmp_path_factory.mktemp("boxes")
    times = np.arange(config.rgb_frame_count) / config.rgb_fps
    rgb = np.array([renderer.render(t, "rgb").box for t in times])
    thermal = np.array([renderer.render(t + config.t_offset, "t").box for t in times])
    write_boxes(folder / "rgb.txt", rgb)
    write_boxes(folder / "t.txt", thermal)
    return folder, renderer.h_rgb_to_t, rgb, thermal


def test_boxes_give_the_rig_and_the_clock_offset(walker_boxes):
    folder, rig, rgb, _ = walker_boxes
    fitted = calibrate_from_boxes(folder / "rgb.txt", folder / "t.txt", RGB_SIZE, T_SIZE, fps=15.0)
    cal = fitted.calibration
    assert cal.source == "boxes" and cal.time_offset == pytest.approx(-0.2)
    # where the target went the mapping is sub-pixel; the frame corners are extrapolated from its path
    centres = rgb[:, :2] + rgb[:, 2:] / 2
    assert np.linalg.norm(project(cal.matrix, centres) - project(rig, centres), axis=1).max() < 1.0
    assert corner_error(cal.matrix, rig, RGB_SIZE) < 8.0
    assert any("clock offset -0.200 s" in note for note in fitted.notes)


def test_shift_search_keeps_zero_for_a_target_standing_still():
    still = np.tile([[100.0, 80.0]], (30, 1)) + np.random.default_rng(0).normal(0, 0.2, (30, 2))
    assert best_shift(still, still * 0.8, 10) == 0


def _write(path, boxes):
    from rgbt_toolkit.io.boxes import write_boxes

    write_boxes(path, np.asarray(boxes, float))
    return str(path)


def test_bad_box_files_are_one_line_and_write_nothing(tmp_path, walker_boxes):
    _, rig, rgb, thermal = walker_boxes
    line = np.c_[np.linspace(20, 280, 30), np.linspace(30, 200, 30), np.full(30, 10), np.full(30, 20)]
    line_t = np.c_[project(rig, line[:, :2] + 5) - 4, np.full((30, 2), 8)]
    half = np.where(np.arange(45)[:, None] < 22, rgb, 0.0)  # RGB boxes in the first half only ...
    other = np.where(np.arange(45)[:, None] >= 40, thermal, 0.0)  # ... thermal ones only at the end
    cases = [
        ((_write(tmp_path / "a.txt", rgb), _write(tmp_path / "b.txt", thermal[:40])), [],
         "45 RGB boxes but 40 thermal boxes"),
        ((_write(tmp_path / "c.txt", half), _write(tmp_path / "d.txt", other)), ["--max-offset", "0.1"],
         "no frame has a box in both files"),
        ((_write(tmp_path / "e.txt", line), _write(tmp_path / "f.txt", line_t)), ["--model", "homography"],
         "points lie on one line, so a homography cannot be fitted"),
    ]
    for (a, b), extra, message in cases:
        out = tmp_path / "c.json"
        result = CliRunner().invoke(main, ["register", "--from-boxes", a, b, *SIZES, *extra, "-o", str(out)])
        assert result.exit_code == 1 and message in result.output, result.output
        assert len(result.output.strip().splitlines()) == 1
        assert not out.exists()


# ----- --board -------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("pattern", ["chessboard", "circles"])
def test_board_in_both_cameras_recovers_the_rig(tmp_path, rig, pattern):
    from rgbt_toolkit.synth.board import write_board_pair

    written = write_board_pair(tmp_path, SceneConfig(duration=0.2), 7, 5, views=4, pattern=pattern)
    fitted = calibrate_from_board(written["rgb"], written["t"], BoardSpec.parse("7x5", pattern))
    truth = np.array(json.loads(written["truth"].read_text())["h_rgb_to_t"])
    np.testing.assert_allclose(truth, rig / rig[2, 2], atol=1e-9)  # the board's rig is the scene's rig
    assert fitted.calibration.source == "board" and fitted.calibration.pairs_used == 4
    assert len(fitted.fit.residuals) == 4 * 35 and fitted.fit.rms < 0.5
    assert corner_error(fitted.calibration.matrix, rig, RGB_SIZE) < 1.0


def test_board_detection_needs_the_whole_board():
    from rgbt_toolkit.synth.board import render_board_pair

    rgb, thermal, _ = render_board_pair(SceneConfig(duration=0.2), 7, 5, views=1)
    assert detect_board(thermal[0], BoardSpec(7, 5)) is not None  # found in reverse polarity
    assert detect_board(rgb[0], BoardSpec(8, 5)) is None  # a wrong corner count never matches


def test_board_not_found_is_one_line_and_writes_nothing(tmp_path):
    from rgbt_toolkit.io.images import write_image

    for name in ("rgb", "t"):
        (tmp_path / name).mkdir()
        write_image(tmp_path / name / "0.png", np.full((96, 128), 90, np.uint8))
    result = CliRunner().invoke(main, ["register", "--board", "7x5", str(tmp_path / "rgb"), str(tmp_path / "t"),
                                       "-o", str(tmp_path / "c.json")])
    assert result.exit_code == 1 and "no 7x5 chessboard board found in any of the 1 RGB frames" in result.output
    assert len(result.output.strip().splitlines()) == 1 and not (tmp_path / "c.json").exists()
    bad = CliRunner().invoke(main, ["register", "--board", "7by5", str(tmp_path / "rgb"), str(tmp_path / "t"),
                                    "-o", str(tmp_path / "c.json")])
    assert bad.exit_code == 1 and "give COLSxROWS" in bad.output


def test_synth_board_refuses_scene_options_and_writes_the_rig(tmp_path):
    refused = CliRunner().invoke(main, ["synth", str(tmp_path / "a"), "--board", "7x5", "-c", "occlusion"])
    assert refused.exit_code == 1 and "--challenges applies to scenes" in refused.output
    assert not (tmp_path / "a").exists()
    made = CliRunner().invoke(main, ["synth", str(tmp_path / "b"), "--board", "6x4", "--board-views", "2",
                                     "--rgb-size", "160x120", "--t-size", "128x96"])
    assert made.exit_code == 0, made.output
    truth = json.loads((tmp_path / "b" / "board.json").read_text())
    assert truth["board"] == "6x4" and truth["views"] == 2 and truth["thermal_size"] == [128, 96]
    assert len(list((tmp_path / "b" / "board_t").iterdir())) == 2
