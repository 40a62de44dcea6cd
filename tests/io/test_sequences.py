"""Benchmark sequence layouts: detection, paired frames and per-modality ground truth."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.images import write_image
from rgbt_toolkit.io.sequences import LAYOUT_NAMES, detect_layout, list_sequences, read_sequence
from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_sequence

FRAME = np.zeros((8, 8, 3), np.uint8)


def _make(root, rgb_dir, t_dir, n, files: dict[str, str], rgb_name="{i:05d}v.jpg", t_name="{i:05d}i.jpg"):
    for i in range(1, n + 1):
        write_image(root / rgb_dir / rgb_name.format(i=i), FRAME)
        write_image(root / t_dir / t_name.format(i=i), FRAME[:, :, 0])
    for name, text in files.items():
        (root / name).write_text(text)
    return root


def test_gtot_corner_boxes_convert_without_plus_one(tmp_path):
    seq = _make(tmp_path / "BlackCar", "v", "i", 2,
                {"groundTruth_v.txt": "10 20 30 60\n11 21 31 61\n", "groundTruth_i.txt": "12 20 32 60\n12 20 32 60\n",
                 "init.txt": "10 20 20 40\n"}, "{i:05d}v.png", "{i:05d}i.png")
    s = read_sequence(seq)
    assert s.layout == "gtot" and len(s) == 2
    np.testing.assert_allclose(s.gt_rgb[0], [10, 20, 20, 40])
    np.testing.assert_allclose(s.gt_t[1], [12, 20, 20, 40])
    np.testing.assert_allclose(s.init_box, [10, 20, 20, 40])


def test_rgbt234_lasher_vtuav_and_vot_layouts(tmp_path):
    rgbt234 = _make(tmp_path / "a", "visible", "infrared", 3,
                    {"visible.txt": "1,2,3,4\n" * 3, "infrared.txt": "5,6,7,8\n" * 3, "init.txt": "1,2,3,4\n"})
    lasher = _make(tmp_path / "b", "visible", "infrared", 3, {"init.txt": "1,2,3,4\n2,2,3,4\n3,2,3,4\n"})
    vtuav = _make(tmp_path / "c", "rgb", "ir", 12, {"rgb.txt": "1 2 3 4\n9 9 9 9\n", "ir.txt": "1 2 3 4\n8 8 8 8\n"})
    vot = _make(tmp_path / "d", "color", "ir", 2,
                {"groundtruth.txt": "1,1,11,1,11,21,1,21\n2,1,12,1,12,21,2,21\n"})
    assert [detect_layout(p).name for p in (rgbt234, lasher, vtuav, vot)] == ["rgbt234", "lasher", "vtuav",
                                                                              "vot-rgbt"]
    np.testing.assert_allclose(read_sequence(rgbt234).gt_t[2], [5, 6, 7, 8])
    lasher_seq = read_sequence(lasher)
    np.testing.assert_allclose(lasher_seq.gt_rgb, lasher_seq.gt_t)
    dense = read_sequence(vtuav).gt_rgb
    assert dense.shape == (12, 4) and np.isnan(dense[1]).all()
    np.testing.assert_allclose(dense[10], [9, 9, 9, 9])
    np.testing.assert_allclose(read_sequence(vot).gt_rgb[1], [2, 1, 10, 20])
    assert list_sequences(tmp_path) == [rgbt234, lasher, vtuav, vot]
    assert set(LAYOUT_NAMES) >= {"gtot", "rgbt234", "lasher", "vtuav", "vot-rgbt"}


def test_mismatched_frame_counts_and_unknown_layout_are_clear_errors(tmp_path):
    seq = _make(tmp_path / "s", "visible", "infrared", 3, {"visible.txt": "1,2,3,4\n", "infrared.txt": "1,2,3,4\n"})
    (seq / "infrared" / "00003i.jpg").unlink()
    with pytest.raises(InputError, match="3 frames but infrared/ has 2"):
        read_sequence(seq)
    (tmp_path / "odd").mkdir()
    with pytest.raises(InputError, match="unknown sequence layout"):
        read_sequence(tmp_path / "odd")


def test_generated_sequence_reads_back_with_its_truth(tmp_path):
    renderer = SceneRenderer(SceneConfig(duration=0.4, seed=1, challenges=frozenset({"camera_motion"})))
    folder = write_scene_sequence(renderer, tmp_path / "gen")
    s = read_sequence(folder)
    assert s.layout == "rgbt234" and len(s) == 6
    truth = renderer.render(0.2, "t", 3).box
    np.testing.assert_allclose(s.gt_t[3], truth, atol=1e-3)
    np.testing.assert_allclose(s.init_box, s.gt_rgb[0])


def test_sequence_given_as_the_current_folder_keeps_its_name(tmp_path, monkeypatch):
    """`rgbt track .` from inside a sequence wrote to `track_` (the name of "." is empty)."""
    from pathlib import Path

    renderer = SceneRenderer(SceneConfig(duration=0.2, seed=1))
    folder = write_scene_sequence(renderer, tmp_path / "gen")
    monkeypatch.chdir(folder)
    assert read_sequence(Path(".")).name == folder.name


def test_empty_ground_truth_without_init_file_is_named(tmp_path):
    """No init.txt and an empty visible.txt: the first box comes from nowhere (was an IndexError)."""
    seq = _make(tmp_path / "s", "visible", "infrared", 2, {"visible.txt": "", "infrared.txt": "1,2,3,4\n1,2,3,4\n"})
    with pytest.raises(InputError, match="visible.txt: empty; it needs the first frame's box"):
        read_sequence(seq)
