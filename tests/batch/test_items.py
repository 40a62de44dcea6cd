"""Discovery of batch items: sequence folders of any layout, video pairs and image pairs matched by name."""

from __future__ import annotations

import pytest

from rgbt_toolkit.batch.items import VIDEO_EXTS, image_pair_items, pair_by_tag, track_items
from rgbt_toolkit.errors import InputError, MissingFileError


def _touch(folder, *names):
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        (folder / name).touch()


def test_track_items_finds_sequences_and_video_pairs(dataset):
    found = track_items(dataset)
    assert [(i.key, i.kind) for i in found.items] == [
        ("seq0", "sequence"), ("seq1", "sequence"), ("seq2", "sequence"), ("seq3", "sequence"), ("vid", "video_pair")]
    assert found.items[-1].paths == (dataset / "vid_rgb.mp4", dataset / "vid_t.mp4")
    assert found.unpaired == ()


def test_one_sequence_folder_is_a_dataset_of_one(dataset):
    found = track_items(dataset / "seq2")
    assert [i.key for i in found.items] == ["seq2"]


def test_video_pairs_matched_by_tag(tmp_path):
    _touch(tmp_path, "a_rgb.mp4", "a_t.mp4", "b-visible.avi", "b-thermal.avi", "c_vis.MP4", "c_IR.mp4",
           "day_2_color.mkv", "day_2_infrared.mkv", "lonely_rgb.mp4", "notes_rgb.txt", "untagged.mp4",
           "dup_rgb.mp4", "dup_vis.mp4", "dup_t.mp4")
    found = pair_by_tag(tmp_path, VIDEO_EXTS, "video_pair")
    pairs = {i.key: tuple(p.name for p in i.paths) for i in found.items}
    assert pairs == {"a": ("a_rgb.mp4", "a_t.mp4"), "b": ("b-visible.avi", "b-thermal.avi"),
                     "c": ("c_vis.MP4", "c_IR.mp4"), "day_2": ("day_2_color.mkv", "day_2_infrared.mkv")}
    # a missing partner, no tag, or two RGB candidates for one stem: reported, not guessed
    assert {p.name for p in found.unpaired} == {"lonely_rgb.mp4", "untagged.mp4", "dup_rgb.mp4", "dup_vis.mp4",
                                                "dup_t.mp4"}


def test_nothing_to_track_is_a_clear_error(tmp_path):
    _touch(tmp_path / "empty", "readme.txt")
    with pytest.raises(InputError, match="no sequence folders .* no video pairs"):
        track_items(tmp_path / "empty")
    with pytest.raises(MissingFileError, match="no such dataset folder"):
        track_items(tmp_path / "absent")


def test_result_name_collision_is_refused(dataset):
    _touch(dataset, "seq1_rgb.mp4", "seq1_t.mp4")
    with pytest.raises(InputError, match="'seq1' is both a sequence and a video pair"):
        track_items(dataset)


def test_image_pairs_from_two_folders_by_stem(tmp_path):
    _touch(tmp_path / "vis", "01.png", "02.png", "03.jpg", "only_vis.png")
    _touch(tmp_path / "ir", "01.png", "02.bmp", "03.jpg", "only_ir.png")
    found = image_pair_items(tmp_path / "vis", tmp_path / "ir")
    assert [(i.key, i.paths[1].name) for i in found.items] == [("01", "01.png"), ("02", "02.bmp"), ("03", "03.jpg")]
    assert sorted(p.name for p in found.unpaired) == ["only_ir.png", "only_vis.png"]


def test_image_pairs_from_one_folder_by_tag(tmp_path):
    _touch(tmp_path, "x_vis.png", "x_ir.png", "y_rgb.jpg", "y_t.jpg")
    found = image_pair_items(tmp_path)
    assert [i.key for i in found.items] == ["x", "y"]
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no image pairs found"):
        image_pair_items(tmp_path / "empty")
