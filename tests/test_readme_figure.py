"""scripts/readme_figure.py: how it lays out the README picture (the whole run is the script's own job), and the
picture it made is the one README.md and the docs' home page show."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("readme_figure", ROOT / "scripts" / "readme_figure.py")
figure = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(figure)


def _frame(h=4, w=3):
    """An annotated frame: the RGB view filled with 10, the thermal view with 20."""
    return np.concatenate([np.full((h, w, 3), 10, np.uint8), np.full((h, w, 3), 20, np.uint8)], axis=1)


def test_the_frame_column_stacks_the_rgb_view_above_the_thermal_view():
    column = figure.frame_column(_frame())
    assert column.shape == (8, 3, 3)
    assert (column[:4] == 10).all() and (column[4:] == 20).all()


def test_compose_centres_both_on_the_taller_one_with_a_white_gap():
    plot = np.full((12, 5, 4), 30, np.uint8)  # RGBA, as PNGs may be read
    out = figure.compose(_frame(), plot, gap=2)
    assert out.shape == (12, 3 + 2 + 5, 3) and out.dtype == np.uint8
    assert (out[:2, :3] == 255).all() and (out[10:, :3] == 255).all()      # column centred: 2 white rows each side
    assert (out[2:6, :3] == 10).all() and (out[6:10, :3] == 20).all()
    assert (out[:, 3:5] == 255).all() and (out[:, 5:] == 30).all()


def test_compose_when_the_frame_is_the_taller():
    out = figure.compose(_frame(h=10), np.full((6, 4, 3), 30, np.uint8), gap=1)
    assert out.shape == (20, 8, 3)
    assert (out[:7, 4:] == 255).all() and (out[7:13, 4:] == 30).all() and (out[13:, 4:] == 255).all()


def test_a_frame_that_is_not_two_views_is_refused():
    with pytest.raises(ValueError, match="two camera views side by side"):
        figure.compose(np.zeros((4, 5, 3), np.uint8), np.zeros((4, 4, 3), np.uint8))


def test_the_picture_is_committed_small_and_shown():
    png = ROOT / "docs" / "img" / "readme_track.png"
    assert png.stat().st_size < 300_000
    assert "](docs/img/readme_track.png)" in (ROOT / "README.md").read_text(encoding="utf-8")
    assert "](img/readme_track.png)" in (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
