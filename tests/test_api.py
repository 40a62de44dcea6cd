"""The public API at the package root (docs/api.md): it agrees with itself and the CLI's files (the page's examples
run in tests/test_docs_examples.py).

Tracking comparisons use the single-tracker preset B-T, whose boxes repeat exactly from run to run (the two-tracker
presets currently differ by up to ~0.01 px between runs in one process, so they cannot be compared exactly).
"""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest

import rgbt_toolkit
from rgbt_toolkit.errors import InputError, MissingFileError, RgbtError

FRAMES = 6


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """A written sequence folder and the same frames read back into memory."""
    from rgbt_toolkit.io.images import read_image
    from rgbt_toolkit.runtime import set_threads
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_sequence

    set_threads(1)
    folder = write_scene_sequence(SceneRenderer(SceneConfig.aligned(rgb_size=(160, 120), duration=FRAMES / 15)),
                                  tmp_path_factory.mktemp("api") / "walker")
    rgb = [read_image(p) for p in sorted((folder / "visible").iterdir())]
    thermal = [read_image(p) for p in sorted((folder / "infrared").iterdir())]
    return folder, rgb, thermal


@pytest.fixture(scope="module")
def tracked(scene):
    return rgbt_toolkit.track(scene[0], preset="B-T")


def test_numpy_frames_track_like_the_sequence_folder(scene, tracked):
    folder, rgb, thermal = scene
    from_memory = rgbt_toolkit.track(iter(rgb), (f for f in thermal), init=tracked.boxes_rgb[0], preset="B-T",
                                     assume_aligned=True)  # a benchmark sequence: registered already
    assert tracked.boxes_rgb.shape == (FRAMES, 4)
    np.testing.assert_array_equal(from_memory.boxes_rgb, tracked.boxes_rgb)
    np.testing.assert_array_equal(from_memory.boxes_t, tracked.boxes_t)
    assert [f.mode for f in from_memory.frames] == [f.mode for f in tracked.frames]
    assert not np.allclose(tracked.boxes_rgb[-1], tracked.boxes_rgb[0])  # the target moved: a real comparison


def test_saved_files_hold_the_boxes(tracked, tmp_path):
    import json

    from rgbt_toolkit.io.boxes import read_boxes

    tracked.save(tmp_path / "out")
    np.testing.assert_allclose(read_boxes(tmp_path / "out" / "boxes_rgb.txt"), tracked.boxes_rgb, atol=0.006)
    frames = json.loads((tmp_path / "out" / "track.json").read_text())["frames"]
    assert [f["mode"] for f in frames] == [f.mode for f in tracked.frames]
    with pytest.raises(InputError, match="holds results of an earlier run"):
        tracked.save(tmp_path / "out")


def test_streaming_tracker_gives_the_boxes_of_track(scene, tracked):
    folder, rgb, thermal = scene
    tracker = rgbt_toolkit.Tracker(preset="B-T", assume_aligned=True)
    steps = [tracker.initialize(rgb[0], thermal[0], tracked.boxes_rgb[0])]
    steps += [tracker.track(a, b) for a, b in zip(rgb[1:], thermal[1:])]
    np.testing.assert_array_equal(np.array([s.box_rgb for s in steps]), tracked.boxes_rgb)
    np.testing.assert_array_equal(np.array([s.box_t for s in steps]), tracked.boxes_t)
    assert [s.mode for s in steps] == [f.mode for f in tracked.frames]


def test_two_trackers_do_not_share_state(scene, tracked):
    """One object per target: a second tracker on another box leaves the first one's boxes unchanged."""
    folder, rgb, thermal = scene
    first, other = (rgbt_toolkit.Tracker(preset="B-T", assume_aligned=True),
                    rgbt_toolkit.Tracker(preset="B-T", assume_aligned=True))
    boxes = [first.initialize(rgb[0], thermal[0], tracked.boxes_rgb[0]).box_rgb]
    other.initialize(rgb[0], thermal[0], (10, 10, 20, 20))
    for a, b in zip(rgb[1:], thermal[1:]):
        other.track(a, b)
        boxes.append(first.track(a, b).box_rgb)
    np.testing.assert_array_equal(np.array(boxes), tracked.boxes_rgb)


def test_import_is_light_and_loads_the_api_on_first_use():
    code = ("import sys, time; t = time.perf_counter(); import rgbt_toolkit; t = time.perf_counter() - t; "
            "heavy = sorted(m for m in ('torch', 'cv2', 'av', 'scipy', 'rgbt_toolkit.jmmac', 'rgbt_toolkit.fusion') "
            "if m in sys.modules); print(repr((t, heavy)))")
    seconds, heavy = eval(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                         check=True).stdout)
    assert heavy == [] and seconds < 0.5, (seconds, heavy)
    assert callable(rgbt_toolkit.track) and set(rgbt_toolkit.__all__) >= {
        "track", "Tracker", "register", "load_calibration", "fuse", "fusion_metrics", "evaluate"}
    with pytest.raises(AttributeError, match="no attribute 'trak'"):
        rgbt_toolkit.trak


@pytest.mark.parametrize("call, error, message", [
    (lambda s: rgbt_toolkit.track(s[0] / "missing"), RgbtError, "missing"),
    (lambda s: rgbt_toolkit.track(s[1], s[2], preset="best", assume_aligned=True), InputError,
     "unknown preset 'best'"),
    (lambda s: rgbt_toolkit.track(s[1], None), InputError, "need their thermal partners"),
    (lambda s: rgbt_toolkit.track(s[1][0], s[2][0]), InputError, "give an iterable of frames"),
    (lambda s: rgbt_toolkit.track(s[1], s[2][:1] + [np.zeros((5, 5))] * 5, init=(60, 40, 10, 30),
                                  assume_aligned=True), InputError,
     "thermal frame 1: 5x5, the first frame is 160x120"),
    (lambda s: rgbt_toolkit.track(s[1], s[2], init=(0, 0, 10)), InputError, "4 numbers"),
    (lambda s: rgbt_toolkit.track(s[1], s[2], init=(500, 500, 10, 10), assume_aligned=True), InputError,
     "box [500.0, 500.0, 10.0, 10.0] lies outside the 160x120 frame"),
    (lambda s: rgbt_toolkit.Tracker(preset="B-T").track(s[1][0], s[2][0]), InputError, "before initialize"),
    (lambda s: rgbt_toolkit.Tracker(mfnet_weights="nope.pt"), MissingFileError, "nope.pt"),
    (lambda s: rgbt_toolkit.load_calibration(s[0] / "none.json"), MissingFileError, "none.json"),
    (lambda s: rgbt_toolkit.register(s[1], s[2], sync=True, offset=0.1), InputError, "not both"),
    (lambda s: rgbt_toolkit.fuse(s[1][0], s[2][0][:50], weights=None), InputError,
     "visible is 160x120 but infrared is 160x50; pass --registered"),
    (lambda s: rgbt_toolkit.fusion_metrics(s[1][0], s[2][0], s[2][0], convention="nope"), InputError, "nope"),
    (lambda s: rgbt_toolkit.evaluate("rgbt234", s[0].parent, {}), InputError, "at least one results folder"),
])
def test_bad_input_raises_the_projects_error_with_a_clear_message(scene, call, error, message):
    with pytest.raises(error, match=re.escape(message)):
        call(scene)
