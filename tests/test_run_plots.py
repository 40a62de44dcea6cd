"""Pictures of one tracking run (``rgbt_toolkit.run_plots``): valid PNGs, the motion stretch shaded, atomic writes."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rgbt_toolkit.run_plots import plot_single_run, plot_track, plot_track_json

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _records(n: int = 60, motion: tuple[int, int] | None = (20, 35)) -> list[dict]:
    """track.json-like records: a target drifting right; ``motion`` frames in motion mode under camera motion."""
    records = []
    for k in range(n):
        in_motion = motion is not None and motion[0] <= k < motion[1]
        records.append({"frame": k, "time": k / 30, "box_rgb": [40 + 2 * k, 50 + 5 * np.sin(k / 8), 16, 20],
                        "box_t": [0, 0, 1, 1], "mode": "init" if k == 0 else "motion" if in_motion else "appearance",
                        "q": None if k == 0 else 12.0 if in_motion else 45.0 + (k % 5),
                        "w_g": None if k == 0 else 0.4 + 0.005 * k, "camera_motion": in_motion, "refined": False})
    return records


def _image(path) -> np.ndarray:
    import matplotlib.image

    assert path.read_bytes()[:8] == PNG_SIGNATURE
    return matplotlib.image.imread(path)


def _orange_pixels(image: np.ndarray) -> int:
    """Pixels of the mode strip's motion colour (tab:orange at alpha 0.85 over white)."""
    rgb = (image[..., :3] * 255).astype(int)
    return int(np.sum((rgb[..., 0] > 230) & (np.abs(rgb[..., 1] - 146) < 20) & (rgb[..., 2] < 80)))


def test_track_png_is_a_picture_of_sensible_size_with_the_motion_stretch_shaded(tmp_path):
    background = np.full((120, 200, 3), 90, np.uint8)
    plot_track(_records(), tmp_path / "track.png", background=background, title="walker")
    image = _image(tmp_path / "track.png")
    assert 900 <= image.shape[1] <= 2000 and 400 <= image.shape[0] <= 1200
    assert image[..., :3].std() > 0.05  # not a blank canvas
    plot_track(_records(motion=None), tmp_path / "plain.png")
    assert _orange_pixels(image) > 500 > _orange_pixels(_image(tmp_path / "plain.png"))


def test_track_png_is_remade_from_track_json_with_missing_values(tmp_path):
    records = _records(20)
    records[5]["box_rgb"] = [None, None, 16, 20]  # as track.json writes a NaN
    (tmp_path / "track.json").write_text(json.dumps({"inputs": "x", "frames": records, "summary": {}}))
    plot_track_json(tmp_path / "track.json", tmp_path / "again.png")
    assert _image(tmp_path / "again.png").shape[1] > 900


def test_single_run_png_shades_the_frames_judged_absent(tmp_path):
    n = 40
    boxes = np.c_[np.arange(n) + 10.0, np.full(n, 30.0), np.full(n, 12.0), np.full(n, 12.0)]
    peaks, psrs = np.r_[np.nan, np.full(n - 1, 0.6)], np.r_[np.nan, np.full(n - 1, 9.0)]
    present = np.ones(n, bool)
    plot_single_run(boxes, peaks, psrs, present, tmp_path / "seen.png")
    present[15:25] = False
    plot_single_run(boxes, peaks, psrs, present, tmp_path / "lost.png")

    def red(image):  # tab:red shading at alpha 0.2 over white, and the red path dots
        rgb = (image[..., :3] * 255).astype(int)
        return int(np.sum((rgb[..., 0] > 230) & (rgb[..., 1] < 215) & (rgb[..., 1] > 190) & (rgb[..., 2] > 190)))

    assert red(_image(tmp_path / "lost.png")) > 1000 > red(_image(tmp_path / "seen.png"))


def test_a_failing_write_leaves_no_partial_picture(tmp_path, monkeypatch):
    import rgbt_toolkit.raster_chart as chart

    def cut_short(error: BaseException):
        def write_bytes(path, data):
            with open(path, "wb") as handle:
                handle.write(data[:8])  # a few bytes, then the failure
            raise error
        return write_bytes

    monkeypatch.setattr(chart, "write_bytes", cut_short(OSError(28, "No space left on device")))
    with pytest.raises(OSError, match="No space left"):
        plot_track(_records(), tmp_path / "track.png")
    monkeypatch.setattr(chart, "write_bytes", cut_short(KeyboardInterrupt()))  # Ctrl-C while writing
    with pytest.raises(KeyboardInterrupt):
        plot_single_run(np.zeros((3, 4)) + 5, np.ones(3), np.ones(3), None, tmp_path / "single.png")
    assert list(tmp_path.iterdir()) == []


def test_track_png_shades_frames_where_the_target_counted_as_lost(tmp_path):
    records = _records(motion=None)
    plot_track(records, tmp_path / "present.png")
    for record in records[30:45]:
        record["present"] = False
    plot_track(records, tmp_path / "lost.png")

    def pink(image):  # tab:red at alpha 0.2 over white
        rgb = (image[..., :3] * 255).astype(int)
        return int(np.sum((rgb[..., 0] > 230) & (np.abs(rgb[..., 1] - 203) < 12) & (np.abs(rgb[..., 2] - 203) < 12)))

    assert pink(_image(tmp_path / "lost.png")) > 1000 > pink(_image(tmp_path / "present.png"))
