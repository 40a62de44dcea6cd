"""Box files: every layout and separator, round trips, VOT markers, malformed lines named by file and line."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.io.boxes import (
    corners_to_xywh,
    polygon_to_xywh,
    read_boxes,
    read_vot_groundtruth,
    read_vot_regions,
    read_vot_results,
    write_boxes,
    write_vot_results,
    xywh_to_polygon,
    xywh_to_xyxy,
    xyxy_to_xywh,
)

BOXES = np.array([[10.0, 20.0, 30.0, 40.0], [11.5, 19.25, 29.0, 41.0], [0.0, 0.0, 5.0, 6.0]])


@pytest.mark.parametrize("sep", [",", " ", "\t", ", ", " \t "])
def test_read_xywh_each_separator(tmp_path, sep):
    path = tmp_path / "b.txt"
    path.write_text("\n".join(sep.join(str(v) for v in row) for row in BOXES) + "\n")
    np.testing.assert_array_equal(read_boxes(path), BOXES)


def test_windows_line_endings_and_no_final_newline(tmp_path):
    path = tmp_path / "crlf.txt"
    path.write_bytes(b"1,2,3,4\r\n5,6,7,8")
    np.testing.assert_array_equal(read_boxes(path), [[1, 2, 3, 4], [5, 6, 7, 8]])


@pytest.mark.parametrize("fmt", ["xywh", "xyxy", "corners", "polygon"])
@pytest.mark.parametrize("delimiter", [",", " ", "\t"])
def test_write_read_round_trip(tmp_path, fmt, delimiter):
    path = tmp_path / f"b_{fmt}.txt"
    write_boxes(path, BOXES, fmt=fmt, delimiter=delimiter, precision=4)
    read_fmt = "xyxy" if fmt == "xyxy" else "auto"
    np.testing.assert_allclose(read_boxes(path, fmt=read_fmt), BOXES)
    assert not list(tmp_path.glob(".*")), "atomic write left a temporary file"


def test_gtot_xyxy_convention_has_no_plus_one(tmp_path):
    path = tmp_path / "groundTruth_v.txt"
    path.write_text("209 155 309 218\n")  # GTOT BlackCar frame 1; its init.txt says 209 155 100 63
    np.testing.assert_array_equal(read_boxes(path, fmt="xyxy"), [[209, 155, 100, 63]])


def test_corner_rows_follow_the_benchmark_convention(tmp_path):
    path = tmp_path / "r.txt"
    path.write_text("148,53,172,53,172,98,148,98\n")  # x1,y1,x2,y1,x2,y2,x1,y2
    np.testing.assert_array_equal(read_boxes(path), [[148, 53, 24, 45]])
    np.testing.assert_array_equal(read_boxes(path, fmt="corners"), [[148, 53, 24, 45]])


def test_rotated_polygon_gives_its_bounding_box():
    poly = np.array([[5.0, 0.0, 10.0, 5.0, 5.0, 10.0, 0.0, 5.0]])  # a diamond
    np.testing.assert_array_equal(polygon_to_xywh(poly), [[0, 0, 10, 10]])


def test_conversions_are_vectorised_inverses():
    np.testing.assert_allclose(xyxy_to_xywh(xywh_to_xyxy(BOXES)), BOXES)
    np.testing.assert_allclose(polygon_to_xywh(xywh_to_polygon(BOXES)), BOXES)
    np.testing.assert_allclose(corners_to_xywh(xywh_to_polygon(BOXES)), BOXES)
    assert xywh_to_polygon(BOXES[None]).shape == (1, 3, 8)


def test_nan_rows_keep_frame_indices(tmp_path):
    path = tmp_path / "n.txt"
    path.write_text("1,2,3,4\nnan\nNaN,NaN,NaN,NaN\n5,6,7,8\n\n")
    boxes = read_boxes(path)
    assert boxes.shape == (4, 4)
    assert np.isnan(boxes[1]).all() and np.isnan(boxes[2]).all()
    np.testing.assert_array_equal(boxes[3], [5, 6, 7, 8])
    write_boxes(tmp_path / "w.txt", boxes, precision=0)
    assert (tmp_path / "w.txt").read_text().splitlines()[1] == "nan,nan,nan,nan"


@pytest.mark.parametrize(
    "text, line, fmt",
    [
        ("1,2,3,4\n1,2,x,4\n", 2, "auto"),
        ("1,2,3,4\n\n1,2,3\n", 3, "auto"),
        ("1,2,3,4,5\n", 1, "auto"),
        ("1,2,3,4\n", 1, "corners"),
        ("1,2,3,4\n1,2,3,4,5,6,7,8\n", 2, "xywh"),
        ("1,2,inf,4\n", 1, "auto"),
    ],
)
def test_malformed_line_names_file_and_line(tmp_path, text, line, fmt):
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=rf"bad\.txt, line {line}:"):
        read_boxes(path, fmt=fmt)


def test_missing_file_and_unknown_format(tmp_path):
    with pytest.raises(MissingFileError, match="no such box file"):
        read_boxes(tmp_path / "absent.txt")
    (tmp_path / "b.txt").write_text("1,2,3,4\n")
    with pytest.raises(InputError, match="unknown box format"):
        read_boxes(tmp_path / "b.txt", fmt="ltrb")
    with pytest.raises(InputError, match=r"\(N, 4\)"):
        write_boxes(tmp_path / "o.txt", np.zeros((3, 5)))


def test_binary_file_is_a_format_error(tmp_path):
    path = tmp_path / "img.txt"
    path.write_bytes(b"\xff\xd8\xff\xe0\x00\x10JFIF")
    with pytest.raises(FileFormatError, match="img.txt"):
        read_boxes(path)


def test_vot_markers_and_polygons(tmp_path):
    path = tmp_path / "seq_001.txt"
    path.write_text("1\n148,53,172,53,172,98,148,98\n2\n0\n0\n1\n10,20,30,40\n")
    raw = read_vot_regions(path)
    assert raw[0] == 1 and raw[2] == 2 and raw[3] == 0 and raw[5] == 1
    assert raw[1].shape == (8,)
    results = read_vot_results(path)
    np.testing.assert_array_equal(results[1], [148, 53, 24, 45])
    np.testing.assert_array_equal(results[6], [10, 20, 30, 40])
    write_vot_results(tmp_path / "out_001.txt", raw)
    again = read_vot_regions(tmp_path / "out_001.txt")
    assert [e if isinstance(e, int) else tuple(e) for e in again] == [
        e if isinstance(e, int) else tuple(e) for e in raw
    ]


def test_vot_groundtruth_rejects_markers_and_returns_boxes(tmp_path):
    gt = tmp_path / "groundtruth.txt"
    gt.write_text("5,0,10,5,5,10,0,5\n1,2,3,4\n")
    boxes = np.asarray(read_vot_groundtruth(gt), dtype=float)
    np.testing.assert_array_equal(boxes, [[0, 0, 10, 10], [1, 2, 3, 4]])
    gt.write_text("1,2,3,4\n2\n")
    with pytest.raises(FileFormatError, match=r"groundtruth\.txt, line 2:"):
        read_vot_groundtruth(gt)
    gt.write_text("1,2,3,4\n7\n")
    with pytest.raises(FileFormatError, match="line 2"):
        read_vot_results(gt)
