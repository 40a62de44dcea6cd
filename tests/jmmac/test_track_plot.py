"""``track.png`` from the ``rgbt track`` frame loop: drawn from track.json's records, complete or absent."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from rgbt_toolkit.jmmac import JmmacTracker, preset
from rgbt_toolkit.jmmac.frame_steps import _camera_shift
from rgbt_toolkit.jmmac.inputs import resolve_inputs
from rgbt_toolkit.jmmac.pipeline import box_centre
from rgbt_toolkit.jmmac.run import run_tracking
from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_videos

from .fakes import ScriptedTracker

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    out = tmp_path_factory.mktemp("scene")
    renderer = SceneRenderer(SceneConfig(duration=1.0, rgb_fps=10, t_fps=10, seed=2))
    return renderer, write_scene_videos(renderer, out, "s")


def _oracle(renderer, fps=10.0):
    truth = [box_centre(renderer.render(k / fps, "rgb", k).box) for k in range(40)]
    return JmmacTracker(preset("B-RGB"), ScriptedTracker(truth), None)


def _inputs(scene):
    renderer, paths = scene
    return resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t)


def test_track_png_is_written_beside_track_json(scene, tmp_path):
    summary = run_tracking(_inputs(scene), _oracle(scene[0]), tmp_path / "out", video=False)
    png = tmp_path / "out" / "track.png"
    assert summary["outputs"]["plot"] == str(png) and png.read_bytes()[:8] == PNG_SIGNATURE
    assert png.stat().st_size > 20_000
    assert len(json.loads((tmp_path / "out" / "track.json").read_text())["frames"]) == 10
    run_tracking(_inputs(scene), _oracle(scene[0]), tmp_path / "off", video=False, plot=False)
    assert not (tmp_path / "off" / "track.png").exists() and (tmp_path / "off" / "track.json").exists()


def test_an_interrupted_run_still_draws_the_frames_it_tracked(scene, tmp_path):
    def stop_at_frame_4(result, box_t, time_s):
        if result.index == 4:
            raise KeyboardInterrupt

    summary = run_tracking(_inputs(scene), _oracle(scene[0]), tmp_path / "out", video=False,
                           on_result=stop_at_frame_4)
    assert summary["interrupted"] and summary["frames"] == 4
    assert (tmp_path / "out" / "track.png").read_bytes()[:8] == PNG_SIGNATURE


def test_ctrl_c_while_drawing_leaves_no_picture_and_the_other_files_complete(scene, tmp_path, monkeypatch):
    import rgbt_toolkit.raster_chart as chart

    def interrupted(path, data):
        with open(path, "wb") as handle:
            handle.write(PNG_SIGNATURE)
        raise KeyboardInterrupt

    monkeypatch.setattr(chart, "write_bytes", interrupted)
    summary = run_tracking(_inputs(scene), _oracle(scene[0]), tmp_path / "out", video=False)
    assert summary["interrupted"] and "plot" not in summary["outputs"]
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == ["boxes_rgb.txt", "boxes_t.txt", "track.json"]  # no track.png, no temporary file
    assert json.loads((tmp_path / "out" / "track.json").read_text())["summary"]["frames_written"] == 10


def test_camera_shift_is_read_only_with_camera_motion_estimation():
    """The annotator's compensation reads JmmacTracker's accumulated shift (stable = image + shift)."""
    on = SimpleNamespace(config=SimpleNamespace(camera_motion=True), camera_motion=object(), camera_shift=np.array([3.0, 4]))
    np.testing.assert_allclose(_camera_shift(on), [3.0, 4.0])
    off = SimpleNamespace(config=SimpleNamespace(camera_motion=False), camera_motion=None, _shift=np.zeros(2))
    assert _camera_shift(off) is None
    tracker = JmmacTracker(preset("B-RGB"), ScriptedTracker([np.zeros(2)]), None)
    assert np.shape(tracker._shift) == (2,)  # the attribute _camera_shift relies on
