"""The ``rgbt track`` harness: inputs, time pairing, geometry, init sources, streamed outputs, interruption."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.video import VideoReader
from rgbt_toolkit.jmmac import JmmacTracker, preset
from rgbt_toolkit.io.boxes import parse_box
from rgbt_toolkit.jmmac.inputs import map_box, resolve_inputs
from rgbt_toolkit.jmmac.pipeline import box_centre
from rgbt_toolkit.jmmac.run import run_tracking
from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_sequence, write_scene_videos

from .fakes import ScriptedTracker


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    out = tmp_path_factory.mktemp("scene")
    renderer = SceneRenderer(SceneConfig(duration=1.0, rgb_fps=10, t_fps=5, seed=2))
    paths = write_scene_videos(renderer, out, "s")
    return renderer, paths


def _oracle(renderer, fps=10.0):
    """A tracker that knows where the target is (from the generator), to test the harness alone."""
    truth = [box_centre(renderer.render(k / fps, "rgb", k).box) for k in range(40)]
    return JmmacTracker(preset("B-RGB"), ScriptedTracker(truth), None)


def test_videos_with_different_rates_are_paired_and_boxes_mapped_to_both_cameras(scene, tmp_path):
    renderer, paths = scene
    inputs = resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t)
    assert inputs.init_source.endswith("s_rgb.init.txt") and inputs.t_size == (256, 192)
    assert any("frame rates differ" in note for note in inputs.notes)
    summary = run_tracking(inputs, _oracle(renderer), tmp_path / "out")
    assert summary["frames"] == 10 and not summary["interrupted"]
    boxes_rgb, boxes_t = read_boxes(tmp_path / "out" / "boxes_rgb.txt"), read_boxes(tmp_path / "out" / "boxes_t.txt")
    truth_t = read_boxes(paths["rgb"].with_name("s_t.boxes.txt"))
    # thermal frame k covers scene time k / 5; RGB frame 2k is the same instant
    np.testing.assert_allclose(boxes_t[::2], truth_t[:5], atol=1.5)
    np.testing.assert_allclose(boxes_rgb, read_boxes(paths["rgb"].with_name("s_rgb.boxes.txt")), atol=1.0)
    track = json.loads((tmp_path / "out" / "track.json").read_text())
    assert len(track["frames"]) == 10 and track["frames"][3]["mode"] == "appearance"
    assert track["summary"]["frames_written"] == 10
    video = VideoReader(tmp_path / "out" / "annotated.mp4")
    assert video.frame_count == 10 and video.size[0] > 320  # side by side


def test_init_in_thermal_pixels_and_automatic_init(scene):
    renderer, paths = scene
    truth_t = read_boxes(paths["rgb"].with_name("s_t.boxes.txt"))[0]
    via_t = resolve_inputs(paths["rgb"], paths["t"], init=truth_t, init_modality="t", h_rgb_to_t=renderer.h_rgb_to_t)
    truth_rgb = read_boxes(paths["rgb"].with_name("s_rgb.boxes.txt"))[0]
    np.testing.assert_allclose(box_centre(via_t.init_box), box_centre(truth_rgb), atol=1.5)

    lone = paths["rgb"].parent / "lone"
    lone.mkdir()
    for key in ("rgb", "t"):
        (lone / paths[key].name).write_bytes(paths[key].read_bytes())
    auto = resolve_inputs(lone / paths["rgb"].name, lone / paths["t"].name, h_rgb_to_t=renderer.h_rgb_to_t)
    assert auto.init_source.startswith("automatic")
    np.testing.assert_allclose(box_centre(auto.init_box), box_centre(truth_rgb), atol=3.0)


def test_benchmark_sequence_folder_is_one_input(tmp_path):
    renderer = SceneRenderer(SceneConfig(duration=0.4, seed=3))
    folder = write_scene_sequence(renderer, tmp_path / "seq")
    inputs = resolve_inputs(folder)
    assert inputs.init_source == "rgbt234 ground truth" and inputs.frame_count == 6
    summary = run_tracking(inputs, _oracle(renderer, fps=15), tmp_path / "out", video=False)
    assert summary["frames"] == 6 and not (tmp_path / "out" / "annotated.mp4").exists()


def test_interrupted_run_leaves_complete_files(scene, tmp_path, interrupt_after):
    renderer, paths = scene
    inputs = resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t)

    inputs.pairs = interrupt_after(inputs.pairs, 4)
    summary = run_tracking(inputs, _oracle(renderer), tmp_path / "out")
    assert summary["interrupted"] and summary["frames"] == 4
    assert read_boxes(tmp_path / "out" / "boxes_t.txt").shape == (4, 4)
    assert json.loads((tmp_path / "out" / "track.json").read_text())["summary"]["interrupted"] is True
    assert VideoReader(tmp_path / "out" / "annotated.mp4").frame_count == 4
    assert not list((tmp_path / "out").glob(".*partial*"))


def test_bad_init_boxes_and_inputs(scene, tmp_path):
    renderer, paths = scene
    with pytest.raises(InputError, match="outside the 320x240 frame"):
        resolve_inputs(paths["rgb"], paths["t"], init=np.array([900.0, 5, 10, 10]))
    with pytest.raises(InputError, match="four numbers"):
        parse_box("1,2,3")
    with pytest.raises(InputError, match="two inputs"):
        resolve_inputs(paths["rgb"])


def test_map_box_round_trip():
    h = np.array([[0.8, 0.02, 5.0], [-0.01, 0.8, -3.0], [1e-5, 0, 1.0]])
    box = np.array([50.0, 60.0, 20.0, 40.0])
    there = map_box(h, box)
    back = map_box(np.linalg.inv(h), there)
    assert np.all(back[:2] <= box[:2] + 1e-9) and np.all(back[2:] >= box[2:] - 1e-9)  # bounding boxes only grow
    np.testing.assert_allclose(box_centre(back), box_centre(box), atol=0.5)


def test_corrupt_frame_in_a_sequence_is_skipped_and_the_count_kept(tmp_path):
    from rgbt_toolkit.io.video import CorruptFrameWarning

    renderer = SceneRenderer(SceneConfig(duration=0.4, seed=3))
    folder = write_scene_sequence(renderer, tmp_path / "seq")
    (folder / "infrared" / "00003i.jpg").write_bytes(b"\xff\xd8 not a jpeg")
    inputs = resolve_inputs(folder)
    with pytest.warns(CorruptFrameWarning, match="00003i.jpg"):
        summary = run_tracking(inputs, _oracle(renderer, fps=15), tmp_path / "out")
    boxes = read_boxes(tmp_path / "out" / "boxes_rgb.txt")
    assert summary["frames"] == 6 and summary["modes"]["skipped"] == 1 and len(boxes) == 6
    np.testing.assert_allclose(boxes[2], boxes[1])
    assert VideoReader(tmp_path / "out" / "annotated.mp4").frame_count == 6
    records = json.loads((tmp_path / "out" / "track.json").read_text())["frames"]
    assert [r["frame"] for r in records] == list(range(6))  # was [0, 1, 2, 3, 4, 4]: the skip broke the numbering


def test_batch_entry_point_repeats_the_last_box_over_an_unreadable_frame(tmp_path, monkeypatch):
    """`rgbt batch track` goes through track_sequence_folder: an unreadable frame crashed it (thermal None)."""
    import rgbt_toolkit.jmmac.api as api
    from rgbt_toolkit.io.video import CorruptFrameWarning

    renderer = SceneRenderer(SceneConfig(duration=0.4, seed=3))
    folder = write_scene_sequence(renderer, tmp_path / "seq")
    (folder / "visible" / "00003v.jpg").write_text("not a picture")
    monkeypatch.setattr(api, "build_tracker", lambda config, **options: _oracle(renderer, fps=15))
    with pytest.warns(CorruptFrameWarning, match="00003v.jpg"):
        boxes = api.track_sequence_folder(folder, "B-RGB")
    assert boxes.shape == (6, 4)
    np.testing.assert_allclose(boxes[2], boxes[1])
    assert not np.allclose(boxes[3], boxes[2])


@pytest.mark.parametrize("which", ["rgb", "t"])
def test_empty_or_bad_init_file_beside_a_video_is_named(scene, tmp_path, which):
    import shutil

    renderer, paths = scene
    for key in ("rgb", "t"):
        shutil.copy(paths[key], tmp_path / paths[key].name)
    rgb, thermal = tmp_path / paths["rgb"].name, tmp_path / paths["t"].name
    init = (rgb if which == "rgb" else thermal).with_suffix(".init.txt")
    init.write_text("\n  \n")
    with pytest.raises(InputError, match=f"{init.name}: empty; it needs the first frame's box"):
        resolve_inputs(rgb, thermal, h_rgb_to_t=renderer.h_rgb_to_t)
    init.write_text("900,10,5,5\n")  # outside the camera the file belongs to: name the file, not the RGB video
    size = "320x240" if which == "rgb" else "256x192"
    with pytest.raises(InputError, match=f"{init.name}: box .* outside the {size}"):
        resolve_inputs(rgb, thermal, h_rgb_to_t=renderer.h_rgb_to_t)


def _frame_folders(renderer, root, n=6):
    from rgbt_toolkit.io.images import write_image

    for modality in ("rgb", "t"):
        (root / modality).mkdir(parents=True)
        for k in range(n):
            write_image(root / modality / f"{k}.png", renderer.render(k / 30, modality, k).image)
    return root / "rgb", root / "t"


def test_unreadable_frame_in_a_frame_folder_keeps_its_row(tmp_path):
    """Row N of the box files is frame N: an unreadable RGB frame used to drop its row and shift the rest."""
    from rgbt_toolkit.io.video import CorruptFrameWarning

    renderer = SceneRenderer(SceneConfig(duration=0.4, seed=3))
    rgb_dir, t_dir = _frame_folders(renderer, tmp_path)
    (rgb_dir / "3.png").write_text("not a picture")
    inputs = resolve_inputs(rgb_dir, t_dir, init=renderer.render(0, "rgb").box, h_rgb_to_t=renderer.h_rgb_to_t)
    with pytest.warns(CorruptFrameWarning, match="3.png"):
        summary = run_tracking(inputs, _oracle(renderer, fps=30), tmp_path / "out", video=False)
    boxes = read_boxes(tmp_path / "out" / "boxes_rgb.txt")
    assert len(boxes) == 6 and len(read_boxes(tmp_path / "out" / "boxes_t.txt")) == 6
    np.testing.assert_allclose(boxes[3], boxes[2])
    records = json.loads((tmp_path / "out" / "track.json").read_text())["frames"]
    assert [r["frame"] for r in records] == list(range(6)) and records[3]["mode"] == "skipped"
    assert summary["modes"]["skipped"] == 1


def test_frame_of_another_size_stops_the_run_and_track_json_says_so(tmp_path):
    from rgbt_toolkit.io.images import write_image

    renderer = SceneRenderer(SceneConfig(duration=0.4, seed=3))
    rgb_dir, t_dir = _frame_folders(renderer, tmp_path)
    write_image(t_dir / "4.png", np.zeros((100, 150, 3), np.uint8))
    inputs = resolve_inputs(rgb_dir, t_dir, init=renderer.render(0, "rgb").box, h_rgb_to_t=renderer.h_rgb_to_t)
    with pytest.raises(InputError, match=r"4.png: 150x100, the other frames are 256x192"):
        run_tracking(inputs, _oracle(renderer, fps=30), tmp_path / "out", video=False)
    summary = json.loads((tmp_path / "out" / "track.json").read_text())["summary"]
    assert "150x100" in summary["error"] and summary["interrupted"] is False


def test_frame_of_another_size_in_a_sequence_is_named(tmp_path):
    from rgbt_toolkit.io.images import write_image

    renderer = SceneRenderer(SceneConfig(duration=0.4, seed=3))
    folder = write_scene_sequence(renderer, tmp_path / "seq")
    write_image(folder / "visible" / "00004v.jpg", np.zeros((100, 150, 3), np.uint8))
    with pytest.raises(InputError, match=r"00004v.jpg: 150x100, the other frames are 320x240"):
        run_tracking(resolve_inputs(folder), _oracle(renderer, fps=15), tmp_path / "out", video=False)


def test_no_overlap_in_time_is_an_error_before_any_output(scene, tmp_path):
    renderer, paths = scene
    with pytest.raises(InputError, match=r"no RGB and thermal frames overlap in time \(RGB 0.00-0.90 s, .*offset "
                                         r"\+100.000 s\)"):
        resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t, time_offset=-100.0)
    with pytest.raises(InputError, match="finite"):
        resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t, time_offset=float("nan"))


def test_video_pair_entry_point_passes_ctrl_c_on(scene, tmp_path, monkeypatch):
    """Batch jobs call track_video_pair: a Ctrl-C that run_tracking turned into a shorter, complete run must still
    stop the batch, or the item would be recorded as done with truncated boxes."""
    import rgbt_toolkit.jmmac.run as run
    from rgbt_toolkit.jmmac import api

    _, paths = scene
    monkeypatch.setattr(api, "build_tracker", lambda *args, **kwargs: None)
    monkeypatch.setattr(run, "run_tracking", lambda *args, **kwargs: {"interrupted": True, "outputs": {}})
    with pytest.raises(KeyboardInterrupt):
        api.track_video_pair(paths["rgb"], paths["t"], tmp_path / "out")
