"""Calibration JSON round trip and errors; warping frames and mapping boxes between the cameras."""


import numpy as np
import pytest

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.registration import Calibration, load_calibration, map_boxes, preview, save_calibration, warp_frame
from rgbt_toolkit.registration.transforms import similarity


@pytest.fixture()
def calib():
    matrix = similarity(0.5, 0.0, (0, 0), (10, 5))  # thermal = RGB / 2 + (10, 5)
    return Calibration(matrix, "similarity", rgb_size=(200, 100), thermal_size=(120, 60), time_offset=0.25,
                       quality=0.4, peak_ratio=2.0, overlap=0.9, pairs_used=3, offset_correlation=0.8)


def test_round_trip(tmp_path, calib):
    path = tmp_path / "calib.json"
    save_calibration(path, calib)
    back = load_calibration(path)
    assert np.allclose(back.matrix, calib.matrix)
    assert (back.model, back.rgb_size, back.thermal_size) == ("similarity", (200, 100), (120, 60))
    assert back.time_offset == 0.25
    assert back.offset_correlation == pytest.approx(0.8) and back.pairs_used == 3
    assert np.allclose(back.inverse @ back.matrix, np.eye(3))


@pytest.mark.parametrize("content, message", [
    ("{not json", "not valid JSON"),
    ('{"format": "something"}', "not an rgbt calibration"),
    ('{"format": "rgbt-calibration", "version": 1, "model": "homography", "rgb_to_thermal": [[1, 0], [0, 1]]}',
     "3x3 list of numbers"),
    ('{"format": "rgbt-calibration", "version": 1, "model": "rigid", "rgb_to_thermal": [[1,0,0],[0,1,0],[0,0,1]]}',
     "'model' must be one of"),
    ('{"format": "rgbt-calibration", "version": 1, "model": "affine", "rgb_to_thermal": [[1,0,0],[0,1,0],[0,0,1]], '
     '"rgb_size": [10, 0], "thermal_size": [5, 5]}', "'rgb_size' must be"),
])
def test_bad_files_name_the_problem(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(FileFormatError, match=message):
        load_calibration(path)


@pytest.mark.parametrize("field, value, message", [
    ("quality", "high", "'quality' must be a finite number or null, got 'high'"),
    ("pairs_used", "four", "'pairs_used' must be a whole number"),
    ("pairs_used", True, "'pairs_used' must be a whole number"),
    ("rgb_size", [True, True], r"'rgb_size' must be \[width, height\] with positive integers"),
    ("time_offset_s", True, "'time_offset_s' must be a number of seconds"),  # JSON true is no number of seconds
    ("time_offset_s", 1e300, "'time_offset_s' must be a number of seconds within"),
    ("time_offset_s", "0.2", "'time_offset_s' must be a number"),
    ("offset_correlation", False, "'offset_correlation' must be a finite number or null"),
    ("rgb_to_thermal", [[True, 0, 0], [0, 1, 0], [0, 0, 1]], "'rgb_to_thermal' must be a 3x3 list of numbers"),
])
def test_wrong_field_types_name_the_file_and_field(tmp_path, calib, field, value, message):
    import json

    path = tmp_path / "calib.json"
    save_calibration(path, calib)
    data = json.loads(path.read_text())
    data[field] = value
    path.write_text(json.dumps(data))
    with pytest.raises(FileFormatError, match=message) as info:
        load_calibration(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)


def test_byte_order_mark_is_accepted(tmp_path, calib):
    path = tmp_path / "calib.json"
    save_calibration(path, calib)
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    assert load_calibration(path).pairs_used == 3


def test_missing_file(tmp_path):
    with pytest.raises(MissingFileError, match="no such calibration file"):
        load_calibration(tmp_path / "absent.json")


def test_map_boxes_both_ways(calib):
    boxes = np.array([[20.0, 10.0, 40.0, 30.0], [np.nan] * 4])
    in_thermal = map_boxes(boxes, calib, "thermal")
    assert np.allclose(in_thermal[0], [20.0, 10.0, 20.0, 15.0])
    assert np.isnan(in_thermal[1]).all()
    assert np.allclose(map_boxes(in_thermal[0], calib, "rgb"), boxes[0])  # single box in, single box out
    with pytest.raises(InputError, match="x, y, w, h"):
        map_boxes(np.zeros((2, 3)), calib)


def test_rotated_box_grows_to_enclose_the_warped_quadrilateral():
    cal = Calibration(similarity(1.0, np.deg2rad(45), (0, 0), (0, 0)), "similarity", (100, 100), (100, 100))
    box = map_boxes([0.0, 0.0, 10.0, 10.0], cal)
    assert box[2] == pytest.approx(10 * np.sqrt(2)) and box[3] == pytest.approx(10 * np.sqrt(2))


def test_warp_frame_and_preview(calib):
    rgb = np.zeros((100, 200, 3), np.uint8)
    rgb[40:60, 80:120] = 255  # a bright block, centre (99.5, 49.5) -> thermal (59.75, 29.75)
    warped = warp_frame(rgb, calib, "thermal")
    assert warped.shape == (60, 120, 3)
    ys, xs = np.nonzero(warped[..., 0] > 128)
    assert xs.mean() == pytest.approx(59.75, abs=0.6) and ys.mean() == pytest.approx(29.75, abs=0.6)
    assert warp_frame(warped, calib, "rgb").shape == (100, 200, 3)
    with pytest.raises(InputError, match="calibration expects 200x100"):
        warp_frame(warped, calib, "thermal")
    thermal = np.full((60, 120), 50, np.uint8)
    for mode in ("checkerboard", "overlay"):
        image = preview(rgb, thermal, calib, mode=mode)
        assert image.shape == (60, 120, 3) and image.dtype == np.uint8
