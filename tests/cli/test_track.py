"""``rgbt track`` end to end on the bundled sample and on bad input."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.evaluation.metrics import iou_continuous
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.video import VideoReader, write_video

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


@pytest.mark.slow
def test_full_tracker_on_the_bundled_sample(tmp_path):
    """Through frame 50: the camera shakes (frames 27-42) while the target is hidden (34-41, q 14-30)."""
    out = tmp_path / "demo"
    result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                       "--max-frames", "50", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "tracked 50 frames" in result.output
    for modality in ("rgb", "t"):
        boxes = read_boxes(out / f"boxes_{modality}.txt")
        truth = read_boxes(SAMPLES / f"demo_{modality}.boxes.txt")[:50]
        assert boxes.shape == (50, 4)
        assert iou_continuous(boxes, truth).mean() > 0.6, modality
        centre_error = np.linalg.norm(boxes[:, :2] + boxes[:, 2:] / 2 - truth[:, :2] - truth[:, 2:] / 2, axis=1)
        assert centre_error.max() < 15, (modality, centre_error.round(1))  # was lost (56-146 px off) by frame 42
    track = json.loads((out / "track.json").read_text())
    frame = track["frames"][5]
    assert set(frame) >= {"box_rgb", "box_t", "mode", "q", "s_a", "s_m", "camera_motion", "w_g", "timing_ms"}
    assert 0.0 < frame["w_g"] < 1.0 and track["init_source"].endswith("demo_rgb.init.txt")
    assert VideoReader(out / "annotated.mp4").frame_count == 50


def test_videos_of_different_lengths_and_rates_are_paired_by_time(tmp_path):
    rng = np.random.default_rng(0)
    base = (rng.integers(0, 255, (60, 80)) // 4 * 4).astype(np.uint8)
    frames = [np.roll(np.stack([base] * 3, axis=2), k, axis=1) for k in range(20)]
    write_video(tmp_path / "a_rgb.mp4", frames, fps=10)
    write_video(tmp_path / "a_t.mp4", frames[::2][:7], fps=5)  # half the rate, and shorter
    result = CliRunner().invoke(main, ["track", str(tmp_path / "a_rgb.mp4"), str(tmp_path / "a_t.mp4"),
                                       "--init", "30,20,12,12", "--preset", "B-T", "--no-video",
                                       "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert "frame rates differ" in result.output
    assert "the thermal recording is shorter (2.00 s RGB, 1.40 s thermal)" in result.output
    # thermal ends at 1.2 s; RGB frames up to 1.5 s lie within 1.5 thermal intervals of it, later ones are dropped
    assert len(read_boxes(tmp_path / "out" / "boxes_rgb.txt")) == 16


@pytest.mark.parametrize("args, message", [
    (["--init", "900,10,20,20"], "outside the 320x240 frame"),
    (["--init", "1,2,3"], "four numbers"),
    (["--init", "nan,1,2,3"], "four finite numbers"),
    (["--preset", "+XYZ", "--init", "10,10,20,20"], "unknown preset"),
    (["--init-modality", "t"], "give --init too"),  # was ignored: the init file's RGB box was used
    (["--show-weights", "--no-video"], "cannot go with --no-video"),
    (["--video-preset", "medium", "--no-video"], "--video-preset sets how annotated.mp4 is written"),
    (["--video-crf", "18", "--no-video"], "--video-crf sets how annotated.mp4 is written"),
])
def test_bad_options_are_one_line_errors(tmp_path, args, message):
    result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                       "-o", str(tmp_path / "out"), *args])
    assert result.exit_code == 1 and message in result.output and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


def test_unreadable_video_is_named(tmp_path):
    (tmp_path / "x.mp4").write_bytes(b"")
    result = CliRunner().invoke(main, ["track", str(tmp_path / "x.mp4"), str(SAMPLES / "demo_t.mp4")])
    assert result.exit_code == 1 and "x.mp4: file is empty" in result.output


def test_earlier_results_are_not_overwritten_without_force(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "track.json").write_text("{}")
    args = ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"), "--preset", "B-T", "--no-video",
            "--max-frames", "3", "-o", str(tmp_path / "out")]
    refused = CliRunner().invoke(main, args)
    assert refused.exit_code == 1 and "--force" in refused.output
    assert (tmp_path / "out" / "track.json").read_text() == "{}"
    assert CliRunner().invoke(main, args + ["--force"]).exit_code == 0
    assert len(read_boxes(tmp_path / "out" / "boxes_t.txt")) == 3


def test_output_folder_is_checked_before_the_registration_estimate(tmp_path, monkeypatch):
    """An -o that cannot be used fails at once, not after the registration estimate (seconds on long videos)."""
    from rgbt_toolkit.jmmac import api

    def never(*args, **kwargs):
        raise AssertionError("the registration estimate ran before the output folder was checked")

    monkeypatch.setattr(api, "registration_estimator", lambda: never)
    (tmp_path / "afile").write_text("")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "boxes_t.txt").write_text("")
    locked = tmp_path / "locked"  # a folder the user may not write in (as root, chmod alone would not show it)
    locked.mkdir()
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda path, mode, **kw: Path(path) != locked and real_access(path, mode, **kw))
    for out, message in ((tmp_path / "afile" / "out", "afile is a file, not a folder"),
                         (tmp_path / "out", "holds results of an earlier run"),
                         (locked / "run", f"no permission to write in {locked}")):
        result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                           "--no-video", "-o", str(out)])
        assert result.exit_code == 1 and message in result.output, result.output


def _calibration(path, rgb_size=(320, 240), t_size=(256, 192), offset=0.0):
    from rgbt_toolkit.registration.calib import Calibration, save_calibration

    matrix = np.diag([t_size[0] / rgb_size[0], t_size[1] / rgb_size[1], 1.0])
    save_calibration(path, Calibration(matrix, "similarity", rgb_size, t_size, time_offset=offset))
    return str(path)


def test_offset_option_uses_the_convention_register_prints(tmp_path, monkeypatch):
    """`--offset X` with the X that `rgbt register --sync` printed must pair frames like `--calib` holding X."""
    import rgbt_toolkit.jmmac.inputs as inputs_module

    seen = []

    def capture(*args, **kwargs):
        seen.append(kwargs["time_offset"])
        raise inputs_module.InputError("stop here")

    monkeypatch.setattr(inputs_module, "resolve_inputs", capture)
    base = ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"), "-o", str(tmp_path / "out")]
    CliRunner().invoke(main, base + ["--calib", _calibration(tmp_path / "c.json", offset=0.2)])
    CliRunner().invoke(main, base + ["--calib", _calibration(tmp_path / "z.json"), "--offset", "0.2"])
    assert seen == [pytest.approx(-0.2), pytest.approx(-0.2)]


def _assert_thermal_frames_mapped_to_8_bits(thermal_frames, originals):
    """The frames the tracker gets: 8 bits spread over the used range, the 8-bit originals up to gain and offset."""
    for frame, original in zip(thermal_frames, originals):
        frame = frame if frame.ndim == 2 else frame[:, :, 0]
        assert frame.dtype == np.uint8 and int(frame.max()) - int(frame.min()) > 150
        assert np.corrcoef(frame.ravel(), original.ravel())[0, 1] > 0.99


def test_sixteen_bit_thermal_frames_are_tracked(tmp_path):
    """A radiometric camera's 16-bit PNG frames (counts 7000-9040): the thermal ECO used to refuse them (uint8 only)."""
    from rgbt_toolkit.io.images import write_image
    from rgbt_toolkit.jmmac.inputs import resolve_inputs

    rgb_dir, t_dir = tmp_path / "rgb", tmp_path / "t"
    rgb_dir.mkdir(), t_dir.mkdir()
    pairs = zip(VideoReader(SAMPLES / "demo_rgb.mp4"), VideoReader(SAMPLES / "demo_t.mp4"))
    originals = []
    for k, ((rgb, _), (t, _)) in enumerate(pairs):
        if k == 12:
            break
        write_image(rgb_dir / f"{k:04d}.png", rgb)
        write_image(t_dir / f"{k:04d}.png", t[:, :, 0].astype(np.uint16) * 8 + 7000)
        originals.append(t[:, :, 0])
    truth = read_boxes(SAMPLES / "demo_rgb.boxes.txt")[:12]
    inputs = resolve_inputs(rgb_dir, t_dir, init=truth[0], h_rgb_to_t=np.eye(3))
    _assert_thermal_frames_mapped_to_8_bits([t for _, t, _ in inputs.pairs], originals)
    result = CliRunner().invoke(main, ["track", str(rgb_dir), str(t_dir), "--init", ",".join(map(str, truth[0])),
                                       "--no-video", "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    boxes = read_boxes(tmp_path / "out" / "boxes_rgb.txt")
    centre_error = np.linalg.norm(boxes[:, :2] + boxes[:, 2:] / 2 - truth[:, :2] - truth[:, 2:] / 2, axis=1)
    assert centre_error.max() < 10, centre_error.round(1)


def test_calibration_of_other_cameras_is_refused(tmp_path):
    calib = _calibration(tmp_path / "c.json", rgb_size=(500, 329), t_size=(440, 300))
    result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                       "--calib", calib, "--init", "10,10,20,20", "-o", str(tmp_path / "out")])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert (f"calibration made for RGB 500x329 and thermal 440x300, but {SAMPLES / 'demo_rgb.mp4'} is 320x240 and "
            f"{SAMPLES / 'demo_t.mp4'} is 256x192") in result.output
    assert not (tmp_path / "out").exists()


def test_empty_init_file_of_a_sequence_is_named(tmp_path):
    result = CliRunner().invoke(main, ["synth", str(tmp_path), "--layout", "rgbt234", "--duration", "0.3",
                                       "--name", "seq"])
    assert result.exit_code == 0, result.output
    (tmp_path / "seq" / "init.txt").write_text("")
    result = CliRunner().invoke(main, ["track", str(tmp_path / "seq"), "-o", str(tmp_path / "out"), "--no-video"])
    assert result.exit_code == 1 and "init.txt: empty" in result.output and "Traceback" not in result.output


def test_sequence_with_sixteen_bit_thermal_frames_is_tracked(tmp_path):
    from rgbt_toolkit.io.images import list_images, read_image, write_image

    result = CliRunner().invoke(main, ["synth", str(tmp_path), "--layout", "rgbt234", "--duration", "0.4",
                                       "--name", "seq"])
    assert result.exit_code == 0, result.output
    originals = []
    for path in list_images(tmp_path / "seq" / "infrared"):  # a radiometric camera's counts instead of 8 bits
        grey = read_image(path)
        grey = grey[:, :, 0] if grey.ndim == 3 else grey
        path.unlink()
        write_image(path.with_suffix(".png"), grey.astype(np.uint16) * 8 + 7000)
        originals.append(grey)
    from rgbt_toolkit.jmmac.inputs import resolve_inputs

    _assert_thermal_frames_mapped_to_8_bits([t for _, t, _ in resolve_inputs(tmp_path / "seq", None).pairs],
                                            originals)
    result = CliRunner().invoke(main, ["track", str(tmp_path / "seq"), "--preset", "B-T", "--no-video",
                                       "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    boxes = read_boxes(tmp_path / "out" / "boxes_rgb.txt")
    truth = read_boxes(tmp_path / "seq" / "visible.txt")
    assert iou_continuous(boxes, truth[: len(boxes)]).mean() > 0.5


def test_forced_rerun_without_video_removes_the_earlier_video(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "annotated.mp4").write_bytes(b"old run")
    args = ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"), "--preset", "B-T", "--no-video",
            "--max-frames", "2", "-o", str(out), "--force"]
    assert CliRunner().invoke(main, args).exit_code == 0
    assert not (out / "annotated.mp4").exists() and (out / "boxes_rgb.txt").exists()


def test_init_in_thermal_pixels_is_the_first_thermal_box(tmp_path):
    from rgbt_toolkit.registration.calib import Calibration, save_calibration

    angle = np.deg2rad(5)
    matrix = np.array([[0.8 * np.cos(angle), -0.8 * np.sin(angle), 20], [0.8 * np.sin(angle), 0.8 * np.cos(angle), 5],
                       [0, 0, 1.0]])  # rotated: a box mapped to RGB and back grows
    save_calibration(tmp_path / "c.json", Calibration(matrix, "similarity", (320, 240), (256, 192)))
    result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                       "--calib", str(tmp_path / "c.json"), "--init", "100.5,60.25,20,50",
                                       "--init-modality", "t", "--preset", "B-T", "--no-video", "--max-frames", "2",
                                       "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    np.testing.assert_allclose(read_boxes(tmp_path / "out" / "boxes_t.txt")[0], [100.5, 60.25, 20, 50], atol=0.01)


@pytest.mark.parametrize("offset, code, message", [
    ("100", 1, "no RGB and thermal frames overlap in time"),
    ("nan", 2, "must be a finite number of seconds"),
    ("inf", 2, "must be a finite number of seconds"),
])
def test_offset_without_overlap_or_not_finite_is_refused(tmp_path, offset, code, message):
    """An offset past the end used to 'track' 0 frames into empty box files and exit 0."""
    result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                       "--calib", _calibration(tmp_path / "c.json"), "--offset", offset,
                                       "--no-video", "-o", str(tmp_path / "out")])
    assert result.exit_code == code and message in result.output and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


def test_empty_init_file_beside_the_videos_is_named(tmp_path):
    import shutil

    for name in ("demo_rgb.mp4", "demo_t.mp4"):
        shutil.copy(SAMPLES / name, tmp_path / name)
    (tmp_path / "demo_t.init.txt").write_text("")
    result = CliRunner().invoke(main, ["track", str(tmp_path / "demo_rgb.mp4"), str(tmp_path / "demo_t.mp4"),
                                       "--calib", _calibration(tmp_path / "c.json"), "-o", str(tmp_path / "out")])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert f"{tmp_path / 'demo_t.init.txt'}: empty; it needs the first frame's box" in result.output


def test_unreadable_frame_of_a_frame_folder_keeps_its_row(tmp_path):
    from rgbt_toolkit.io.images import write_image
    from rgbt_toolkit.io.video import CorruptFrameWarning

    for name, key in (("rgb", "demo_rgb.mp4"), ("t", "demo_t.mp4")):
        (tmp_path / name).mkdir()
        for k, (frame, _) in zip(range(6), VideoReader(SAMPLES / key)):
            write_image(tmp_path / name / f"{k}.png", frame)
    (tmp_path / "rgb" / "2.png").write_text("junk")
    with pytest.warns(CorruptFrameWarning, match="2.png"):
        result = CliRunner().invoke(main, ["track", str(tmp_path / "rgb"), str(tmp_path / "t"),
                                           "--init", "123,108,22,60", "--calib", _calibration(tmp_path / "c.json"), "--preset", "B-T",
                                           "--no-video", "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert "tracked 6 frames (1 unreadable: the previous box repeated)" in result.output
    boxes = read_boxes(tmp_path / "out" / "boxes_rgb.txt")
    assert len(boxes) == 6 and np.allclose(boxes[2], boxes[1])


def test_sigterm_stops_like_ctrl_c_with_complete_outputs(tmp_path, monkeypatch):
    """`kill` (or a scheduler's time limit) closes every output as a complete file, like Ctrl-C, and exits 143."""
    import os
    import signal

    from rgbt_toolkit.jmmac.pipeline import JmmacTracker

    calls = {"n": 0}
    real_track = JmmacTracker.track

    def track_then_terminated(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 3:
            os.kill(os.getpid(), signal.SIGTERM)
        return real_track(self, *args, **kwargs)

    monkeypatch.setattr(JmmacTracker, "track", track_then_terminated)
    before = signal.getsignal(signal.SIGTERM)
    result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                       "--preset", "B-T", "--no-video", "--max-frames", "8", "-o",
                                       str(tmp_path / "out")])
    assert result.exit_code == 143, result.output
    assert "interrupted after 3 frames" in result.output
    assert read_boxes(tmp_path / "out" / "boxes_t.txt").shape == (3, 4)
    assert not list((tmp_path / "out").glob(".*partial*"))
    assert signal.getsignal(signal.SIGTERM) == before


@pytest.mark.parametrize("option, name", [("--mfnet-weights", "heads.pt"), ("--mfnet-weights", "heads.onnx"),
                                          ("--detector", "yolo.onnx")])
def test_a_model_file_that_does_not_load_is_one_line_naming_it(tmp_path, monkeypatch, option, name):
    """A user's model file that is no model: exit 1, the file named on one line, no results written, and before
    the registration estimate (seconds on long videos), which a user's files never need to wait for."""
    from rgbt_toolkit.jmmac import api

    def never(*args, **kwargs):
        raise AssertionError("the registration estimate ran before the model file was loaded")

    monkeypatch.setattr(api, "registration_estimator", lambda *args, **kwargs: never)
    bad = tmp_path / name
    bad.write_bytes(np.arange(64, dtype=np.uint8).tobytes())
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                       "--init", "150,110,40,30", option, str(bad), "-o", str(out),
                                       "--max-frames", "2"])
    assert result.exit_code == 1, result.output
    assert str(bad) in result.output and "Traceback" not in result.output
    assert "registration estimate ran" not in result.output
    assert not out.exists() or not any(out.iterdir())
