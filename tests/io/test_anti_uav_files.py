"""Anti-UAV label and result files: every accepted frame form, the writer's round trip, malformed files named."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.io.anti_uav import read_anti_uav_label, read_anti_uav_result, write_anti_uav_result

NAN = [np.nan] * 4


def test_label_accepts_both_no_box_forms(tmp_path):
    path = tmp_path / "IR_label.json"
    path.write_text(json.dumps({"exist": [1, 0, 0, True], "gt_rect": [[1, 2, 3, 4], [], [0, 0, 0, 0], [5, 6, 7, 8]]}))
    label = read_anti_uav_label(path)
    assert label.present.tolist() == [True, False, False, True]
    np.testing.assert_array_equal(label.boxes, [[1, 2, 3, 4], NAN, NAN, [5, 6, 7, 8]])


def test_label_keeps_a_box_on_an_absent_frame_and_drops_none_on_present(tmp_path):
    path = tmp_path / "IR_label.json"
    path.write_text(json.dumps({"exist": [0, 1], "gt_rect": [[1, 2, 3, 4], []]}))
    label = read_anti_uav_label(path)
    np.testing.assert_array_equal(label.boxes, [[1, 2, 3, 4], NAN])
    assert label.present.tolist() == [False, True]  # the scorer leaves frame 2 out, the reader keeps the flag


def test_result_text_rows_every_line_is_a_frame(tmp_path):
    path = tmp_path / "s_IR.txt"
    path.write_text("1,2,3,4\n\n[]\n0\n5 6\t7;8\n[9, 10, 11, 12]\nnan\n0,0,0,0\n")
    track = read_anti_uav_result(path)
    assert track.present.tolist() == [True, False, False, False, True, True, False, True]
    np.testing.assert_array_equal(track.boxes[[0, 4, 5, 7]], [[1, 2, 3, 4], [5, 6, 7, 8], [9, 10, 11, 12], [0] * 4])
    assert np.isnan(track.boxes[[1, 2, 3, 6]]).all()


def test_result_json_in_any_extension(tmp_path):
    for name in ("a.json", "a_IR.txt"):
        (tmp_path / name).write_text(json.dumps({"res": [[1.5, 2, 3, 4], [], [0], [0, 0, 0, 0]]}))
        track = read_anti_uav_result(tmp_path / name)
        assert track.present.tolist() == [True, False, False, True]
        np.testing.assert_array_equal(track.boxes[0], [1.5, 2, 3, 4])


def test_final_newline_adds_no_frame_but_a_blank_last_line_does(tmp_path):
    path = tmp_path / "r.txt"
    path.write_text("1,2,3,4\n")
    assert len(read_anti_uav_result(path)) == 1
    path.write_text("1,2,3,4\n\n")
    assert read_anti_uav_result(path).present.tolist() == [True, False]


def test_writer_round_trip_with_absent_frames(tmp_path):
    boxes = np.array([[1.23456, 2, 3, 4], [np.nan] * 4, [5, 6, 7, 8], [9, 9, 9, 9]])
    path = tmp_path / "out" / "seq_IR.txt"
    write_anti_uav_result(path, boxes, present=[True, False, True, False])
    assert json.loads(path.read_text()) == {"res": [[1.2346, 2.0, 3.0, 4.0], [], [5.0, 6.0, 7.0, 8.0], []]}
    track = read_anti_uav_result(path)
    assert track.present.tolist() == [True, False, True, False]
    assert [p.name for p in path.parent.iterdir()] == ["seq_IR.txt"]  # no temporary file left behind


def test_writer_default_presence_follows_nan_rows(tmp_path):
    path = tmp_path / "seq_IR.json"
    write_anti_uav_result(path, np.array([[1, 2, 3, 4], [np.nan] * 4]))
    assert json.loads(path.read_text())["res"] == [[1.0, 2.0, 3.0, 4.0], []]


@pytest.mark.parametrize("boxes, present, message", [
    (np.zeros((2, 3)), None, r"boxes must be an \(N, 4\) array"),
    (np.zeros((2, 4)), [True], "present has 1 flags for 2 boxes"),
    (np.array([[1, 2, 3, 4], [np.nan] * 4]), [True, True], "frame 2 is marked present but its box is not finite"),
])
def test_writer_refuses_bad_input(tmp_path, boxes, present, message):
    with pytest.raises(InputError, match=message):
        write_anti_uav_result(tmp_path / "x.json", boxes, present)
    assert not (tmp_path / "x.json").exists()


@pytest.mark.parametrize("text, message", [
    ('{"res": [[1, 2, 3, 4]', "malformed JSON"),
    ('{"res": [[1, 2, true, 4]]}', "frame 1: expected"),
    ('{"res": [[7]]}', "frame 1: a single value 7 is neither a box nor the absent mark 0"),
    ('{"res": [[1, 2, 3, NaN]]}', "frame 1: box .* is not four finite numbers"),
    ("1,2,3\n", "line 1: expected 4 values"),
])
def test_malformed_results_name_file_and_frame(tmp_path, text, message):
    path = tmp_path / "r.txt"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=message) as info:
        read_anti_uav_result(path)
    assert str(path) in str(info.value)


def test_missing_files(tmp_path):
    with pytest.raises(MissingFileError, match="no such label file"):
        read_anti_uav_label(tmp_path / "IR_label.json")
    with pytest.raises(MissingFileError, match="no such result file"):
        read_anti_uav_result(tmp_path / "s_IR.txt")
