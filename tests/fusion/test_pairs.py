"""Inputs of rgbt fuse: pairing by stem, output names, calibration files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError, RegistrationError
from rgbt_toolkit.fusion.pairs import output_path, pair_inputs, read_homography, warp_to_visible
from rgbt_toolkit.io.images import write_image


def _touch_images(folder, names):
    folder.mkdir()
    for n in names:
        write_image(folder / n, np.zeros((8, 8), np.uint8))


def test_folders_pair_by_stem_in_natural_order(tmp_path):
    _touch_images(tmp_path / "vi", ["10.png", "2.png", "3.jpg", "only_vis.png"])
    _touch_images(tmp_path / "ir", ["2.jpg", "10.png", "3.png"])
    pairs = pair_inputs(tmp_path / "vi", tmp_path / "ir")
    assert [(v.name, i.name) for v, i in pairs] == [("2.png", "2.jpg"), ("3.jpg", "3.png"), ("10.png", "10.png")]


def test_pairing_errors(tmp_path):
    _touch_images(tmp_path / "vi", ["a.png"])
    _touch_images(tmp_path / "ir", ["b.png"])
    with pytest.raises(InputError, match="no image file stem appears in both"):
        pair_inputs(tmp_path / "vi", tmp_path / "ir")
    with pytest.raises(InputError, match="not one of each"):
        pair_inputs(tmp_path / "vi" / "a.png", tmp_path / "ir")
    with pytest.raises(MissingFileError):
        pair_inputs(tmp_path / "nothing", tmp_path / "ir")


def test_output_names(tmp_path):
    from pathlib import Path

    assert output_path(tmp_path / "f.png", Path("x/01.jpg"), folder=False) == tmp_path / "f.png"
    assert output_path(tmp_path / "out", Path("x/01.jpg"), folder=True) == tmp_path / "out" / "01.png"


def test_homography_file(tmp_path):
    p = tmp_path / "calib.json"
    p.write_text(json.dumps({"H": [[2, 0, 4], [0, 2, 6], [0, 0, 2]]}))
    assert np.allclose(read_homography(p), [[1, 0, 2], [0, 1, 3], [0, 0, 1]])


@pytest.mark.parametrize(
    "text,error,match",
    [
        ("{", FileFormatError, "not valid JSON"),
        ('{"H": [[1, 0], [0, 1]]}', FileFormatError, "3x3 homography"),
        ('{"M": 1}', FileFormatError, "3x3 homography"),
        ('{"H": [[0, 0, 0], [0, 0, 0], [0, 0, 1]]}', RegistrationError, "singular"),
    ],
)
def test_bad_homography_files(tmp_path, text, error, match):
    p = tmp_path / "calib.json"
    p.write_text(text)
    with pytest.raises(error, match=match):
        read_homography(p)


def test_warp_moves_pixels_by_the_translation():
    ir = np.zeros((40, 50), np.uint8)
    ir[10, 20] = 200
    out = warp_to_visible(ir, np.array([[1.0, 0, 5], [0, 1, -3], [0, 0, 1]]), (40, 50))
    assert np.unravel_index(out.argmax(), out.shape) == (7, 25)


def test_calibration_from_rgbt_register_is_read_and_inverted(tmp_path):
    from rgbt_toolkit.registration import Calibration, save_calibration

    rgb_to_t = np.array([[0.9, 0.0, -5.0], [0.0, 0.9, 4.0], [0.0, 0.0, 1.0]])
    path = tmp_path / "calib.json"
    save_calibration(path, Calibration(rgb_to_t, "similarity", (320, 240), (256, 192)))
    assert np.allclose(read_homography(path) @ rgb_to_t, np.eye(3))  # thermal -> visible
