"""The OpenCV chart helpers behind the run pictures: round ticks, data-to-pixel mapping, lines that break at NaN,
shaded spans at their opacity, atomic PNG writes."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rgbt_toolkit.raster_chart import COLOURS, Axes, Canvas, nice_ticks, padded_limits, tick_label


@pytest.mark.parametrize("low, high, expected", [
    (0, 300, [0, 100, 200, 300]),
    (-0.02, 1.02, [0.0, 0.25, 0.5, 0.75, 1.0]),
    (233, 352, [250, 275, 300, 325, 350]),
    (-14.9, 313.9, [0, 100, 200, 300]),
])
def test_ticks_are_round_values_inside_the_range(low, high, expected):
    ticks = nice_ticks(low, high)
    assert np.allclose(ticks, expected)
    assert [tick_label(v, ticks) for v in ticks[:2]] == [tick_label(expected[0], np.array(expected)),
                                                         tick_label(expected[1], np.array(expected))]


def test_tick_labels_carry_the_decimals_the_step_needs():
    assert [tick_label(v, np.array([0, 0.25, 0.5])) for v in (0, 0.25, 0.5)] == ["0.00", "0.25", "0.50"]
    assert [tick_label(v, np.array([0, 50, 100])) for v in (0, 50)] == ["0", "50"]
    assert tick_label(0.5, np.array([0.0, 0.5, 1.0])) == "0.5"


def test_limits_pad_the_finite_range_and_fall_back_when_there_is_none():
    assert padded_limits(np.array([0.0, np.nan, 10.0])) == pytest.approx((-0.5, 10.5))
    assert padded_limits(np.array([np.nan])) == (0.0, 1.0)
    assert padded_limits(np.array([3.0, 3.0])) == (2.5, 3.5)


def test_points_map_to_pixels_with_y_up_or_down():
    canvas = Canvas(200, 100)
    up = Axes(canvas, (10, 10, 110, 60), (0, 10), (0, 5))
    u, v = up.px([0, 10, 5], [0, 5, 2.5])
    assert np.allclose(u, [10, 110, 60]) and np.allclose(v, [60, 10, 35])
    down = Axes(canvas, (10, 10, 110, 60), (0, 10), (0, 5), invert_y=True)
    assert np.allclose(down.px([0], [0])[1], [10])  # image rows: y = 0 at the top


def test_a_line_is_drawn_where_its_points_are_and_breaks_at_nan():
    canvas = Canvas(120, 60)
    ax = Axes(canvas, (0, 0, 119, 59), (0, 119), (0, 59), invert_y=True)
    ax.line([0, 40, np.nan, 80, 119], [30, 30, np.nan, 30, 30], COLOURS["black"])
    row = canvas.image[30, :, 0]
    assert row[5:35].max() < 60 and row[85:115].max() < 60  # drawn along both finite runs
    assert row[50:70].min() == 255  # not across the gap
    assert canvas.image[5:20].min() == 255  # and nowhere else


def test_a_span_blends_its_colour_at_its_opacity_over_white():
    canvas = Canvas(100, 50)
    ax = Axes(canvas, (0, 0, 100, 50), (0, 10), (0, 1))
    ax.vspan(2, 4, COLOURS["tab:red"], 0.2)
    inside, outside = canvas.image[25, 30], canvas.image[25, 60]
    assert np.allclose(inside, np.round(255 + 0.2 * (np.array(COLOURS["tab:red"]) - 255)), atol=1)
    assert (outside == 255).all()


def test_vertical_text_reads_upwards_and_stays_on_the_canvas():
    canvas = Canvas(60, 120)
    canvas.text(30, 60, "label", vertical=True, align="centre")
    dark = np.argwhere(canvas.image[..., 0] < 128)
    assert dark.size and np.ptp(dark[:, 0]) > np.ptp(dark[:, 1])  # taller than wide
    canvas.text(-50, -50, "off the canvas")  # clipped, not an error


def test_save_writes_a_png_of_the_canvas(tmp_path):
    canvas = Canvas(64, 32)
    canvas.blend_rect(0, 0, 32, 32, COLOURS["tab:green"], 1.0)
    canvas.save(tmp_path / "c.png")
    back = cv2.cvtColor(cv2.imread(str(tmp_path / "c.png")), cv2.COLOR_BGR2RGB)
    assert (back == canvas.image).all() and tuple(back[5, 5]) == COLOURS["tab:green"]
    assert [p.name for p in tmp_path.iterdir()] == ["c.png"]
