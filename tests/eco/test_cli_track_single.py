"""``rgbt track-single`` on a tiny generated frame folder."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.images import write_image
from rgbt_toolkit.io.video import CorruptFrameWarning


def _folder(tmp_path, n=4):
    rng = np.random.default_rng(0)
    bg = (rng.random((96, 128, 3)) * 255).astype(np.uint8)
    obj = (rng.random((20, 16, 3)) * 255).astype(np.uint8)
    folder = tmp_path / "frames"
    folder.mkdir()
    for k in range(n):
        f = bg.copy()
        f[30 : 50, 40 + 2 * k : 56 + 2 * k] = obj
        write_image(folder / f"{k:04d}.png", f)
    return folder


def test_track_single_writes_one_box_per_frame(tmp_path):
    folder = _folder(tmp_path)
    out = tmp_path / "boxes.txt"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out)])
    assert res.exit_code == 0, res.output
    rows = np.loadtxt(out, delimiter=",")
    assert rows.shape == (4, 4)
    np.testing.assert_allclose(rows[0], [40, 30, 16, 20])
    assert abs(rows[-1, 0] - 46) < 2.0  # followed the 2 px/frame motion
    assert "frames/s" in res.output
    assert "with ECO hc+cnn" in res.output  # the default: the preset that wins on the 116 real clips (D50)
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out), "--force",
                                    "--features", "hc"])
    assert res.exit_code == 0 and "with ECO hc " in res.output, res.output


def test_track_single_rejects_a_zero_size_box(tmp_path):
    folder = _folder(tmp_path, n=2)
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,0,20", "-o", str(tmp_path / "b")])
    assert res.exit_code == 1
    assert "zero or negative size" in res.output
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30", "-o", str(tmp_path / "b")])
    assert res.exit_code == 1 and "four numbers" in res.output


def test_track_single_refuses_a_box_outside_the_frame_and_an_existing_output(tmp_path):
    folder = _folder(tmp_path, n=2)
    out = tmp_path / "b.txt"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "500,30,16,20", "-o", str(out)])
    assert res.exit_code == 1 and "lies outside the 128x96 frame" in res.output and not out.exists()
    out.write_text("keep")
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out)])
    assert res.exit_code == 1 and "--force" in res.output and out.read_text() == "keep"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out), "--force"])
    assert res.exit_code == 0 and len(out.read_text().splitlines()) == 2


def test_track_single_on_a_paired_sequence_names_a_modality_folder(tmp_path):
    seq = tmp_path / "seq"
    (seq / "visible").mkdir(parents=True)
    (seq / "infrared").mkdir()
    res = CliRunner().invoke(main, ["track-single", str(seq), "--init", "40,30,16,20", "-o", str(tmp_path / "b")])
    assert res.exit_code == 1 and str(seq / "visible") in res.output and "Traceback" not in res.output


def test_track_single_refuses_to_write_over_its_own_input(tmp_path):
    from rgbt_toolkit.io.video import write_video

    folder = _folder(tmp_path, n=2)
    frame = folder / "0001.png"
    before = frame.read_bytes()
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(frame), "--force"])
    assert res.exit_code == 1 and "would overwrite an input recording" in res.output and "Traceback" not in res.output
    assert frame.read_bytes() == before
    video = tmp_path / "v.mp4"
    write_video(video, [np.zeros((48, 64, 3), np.uint8)] * 3, fps=10)
    before = video.read_bytes()
    res = CliRunner().invoke(main, ["track-single", str(video), "--init", "4,4,16,20", "-o", str(video), "--force"])
    assert res.exit_code == 1 and "would overwrite an input recording" in res.output and video.read_bytes() == before
    res = CliRunner().invoke(main, ["track-single", str(video), "--init", "4,4,16,20", "-o", str(tmp_path / "b.txt"),
                                    "--anti-uav", str(video), "--force"])
    assert res.exit_code == 1 and "Anti-UAV result file would overwrite an input recording" in res.output
    assert video.read_bytes() == before


def test_track_single_keeps_a_row_for_an_unreadable_frame(tmp_path):
    """docs/eco.md: one row per frame. Junk and truncated frames used to drop their rows."""
    folder = _folder(tmp_path, n=8)
    (folder / "0002.png").write_text("junk")
    (folder / "0004.png").write_bytes(bytes(range(256)))  # (an empty file too, but imageio leaks its handle then)
    (folder / "0006.png").write_bytes((folder / "0005.png").read_bytes()[:200])
    out = tmp_path / "boxes.txt"
    with pytest.warns(CorruptFrameWarning) as caught:
        res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "3 unreadable" in res.output and len(caught) == 3
    rows = np.loadtxt(out, delimiter=",")
    assert rows.shape == (8, 4)
    for k in (2, 4, 6):
        np.testing.assert_allclose(rows[k], rows[k - 1])
    assert abs(rows[7, 0] - 54) < 2.0  # row 7 is frame 7 (x = 40 + 2 * 7), not frame 10


def test_track_single_on_one_frame_reports_no_rate(tmp_path):
    folder = _folder(tmp_path, n=3)
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "--max-frames", "1",
                                    "-o", str(tmp_path / "b.txt")])
    assert res.exit_code == 0 and "tracked 1 frame ->" in res.output and "nan" not in res.output


def test_track_single_refuses_frames_of_another_size(tmp_path):
    folder = _folder(tmp_path, n=4)
    write_image(folder / "0002.png", np.zeros((60, 100, 3), np.uint8))
    out = tmp_path / "b.txt"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out)])
    assert res.exit_code == 1 and "0002.png: 100x60, the other frames are 128x96" in res.output
    assert "Traceback" not in res.output and not out.exists()


def test_ctrl_c_keeps_the_rows_tracked_so_far(tmp_path, monkeypatch):
    """As `rgbt track` does: a Ctrl-C writes the boxes of the frames tracked before it and exits 130."""
    from rgbt_toolkit.eco.tracker import EcoTracker

    folder = _folder(tmp_path, n=6)
    out = tmp_path / "boxes.txt"
    calls = {"n": 0}
    real_predict = EcoTracker.predict

    def predict_then_stop(self, frame, center=None):
        calls["n"] += 1
        # call 1 is initialize's search on the first frame (the scale bias); the user presses Ctrl-C while frame 3
        # is tracked
        if calls["n"] == 4:
            raise KeyboardInterrupt
        return real_predict(self, frame, center)

    monkeypatch.setattr(EcoTracker, "predict", predict_then_stop)
    video = tmp_path / "run.mp4"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out),
                                    "--video", str(video)])
    assert res.exit_code == 130, res.output
    assert "interrupted after 3 frames" in res.output
    assert np.loadtxt(out, delimiter=",").shape == (3, 4)  # frames 0-2; frame 3 was cut short
    from rgbt_toolkit.io.frames import open_frames

    assert len(open_frames(video)) == 3  # the annotated video keeps the same frames, as `rgbt track` does


def _absent_folder(tmp_path):
    """The re-acquisition test scene (target out of view on frames 20..31) as a frame folder, with its truth."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from test_reacquire import cut_sequence

    frames, truth = cut_sequence(n=40, cut=40, absent=(20, 32))
    folder = tmp_path / "absent"
    folder.mkdir()
    for k, f in enumerate(frames):
        write_image(folder / f"{k:04d}.png", f)
    return folder, truth


def test_track_single_reports_an_absent_target_in_both_formats(tmp_path):
    import json

    folder, truth = _absent_folder(tmp_path)
    out, res_json = tmp_path / "b.txt", tmp_path / "seq_IR.txt"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,60,16,20", "-o", str(out),
                                    "--absent", "zeros", "--anti-uav", str(res_json)])
    assert res.exit_code == 0, res.output
    assert "target judged absent on" in res.output
    rows = np.loadtxt(out, delimiter=",")
    zero = ~rows.any(axis=1)
    assert zero[24:32].all() and not zero[:20].any() and not zero[34:].any()
    entries = json.loads(res_json.read_text())["res"]
    assert len(entries) == 40 and entries[26] == [] and len(entries[5]) == 4
    held = tmp_path / "held.txt"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,60,16,20", "-o", str(held)])
    assert res.exit_code == 0 and np.loadtxt(held, delimiter=",").all()  # default: the last box is held


def test_track_single_without_reacquisition_never_says_absent(tmp_path):
    folder, _ = _absent_folder(tmp_path)
    out = tmp_path / "b.txt"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,60,16,20", "-o", str(out),
                                    "--absent", "zeros", "--no-reacquire"])
    assert res.exit_code == 0 and "absent" not in res.output
    assert np.loadtxt(out, delimiter=",").all()


@pytest.mark.parametrize("option, message", [("--anti-uav", "names the boxes file itself"),
                                             ("--plot", "--plot names another output file"),
                                             ("--video", "--video names another output file")])
def test_track_single_extra_outputs_must_differ_from_the_boxes_file(tmp_path, option, message):
    folder = _folder(tmp_path, n=2)
    out = tmp_path / "b.txt"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out),
                                    option, str(out)])
    assert res.exit_code == 1 and message in res.output and not out.exists()


def _box_edge_colour(image: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Median colour along the left edge of ``box`` as drawn (a 2-px line on the box's first column)."""
    x, y, w, h = np.round(box).astype(int)
    return np.median(image[y + 2: y + h - 2, x].reshape(-1, 3), axis=0)


def test_track_single_video_draws_every_frame_green_while_tracked_orange_while_lost(tmp_path):
    from rgbt_toolkit.io.frames import open_frames

    folder, _ = _absent_folder(tmp_path)
    out, video = tmp_path / "b.txt", tmp_path / "run.mp4"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,60,16,20", "-o", str(out),
                                    "--video", str(video)])
    assert res.exit_code == 0, res.output
    rows = np.loadtxt(out, delimiter=",")
    frames = [f for f, _ in open_frames(video)]
    assert len(frames) == len(rows) == 40
    green = _box_edge_colour(frames[10], rows[10])
    assert green[1] > 150 and green[0] < 120 and green[2] < 120
    orange = _box_edge_colour(frames[27], rows[27])  # frames 24-31: the target counts as lost, its box is held
    assert orange[0] > 150 and 100 < orange[1] < 220 and orange[2] < 100
    assert not list(tmp_path.glob(".*partial*"))


def test_track_single_video_must_be_a_new_output(tmp_path):
    folder = _folder(tmp_path, n=2)
    out = tmp_path / "b.txt"
    video = tmp_path / "v.mp4"
    video.write_text("keep")
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out),
                                    "--video", str(video)])
    assert res.exit_code == 1 and "--force" in res.output and video.read_text() == "keep" and not out.exists()
    frame = folder / "0000.png"
    res = CliRunner().invoke(main, ["track-single", str(frame), "--init", "40,30,16,20", "-o", str(out),
                                    "--video", str(frame), "--force"])
    assert res.exit_code == 1 and "would overwrite an input recording" in res.output


def test_cli_feature_choices_follow_the_presets():
    from rgbt_cli.options import ECO_FEATURES
    from rgbt_toolkit.eco.params import PRESETS

    assert set(ECO_FEATURES) == set(PRESETS)
