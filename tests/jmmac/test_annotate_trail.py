"""The annotated video's trail: the last second only, and moved with the camera so shake does not scribble."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.jmmac.annotate import Annotator, tail_length
from rgbt_toolkit.jmmac.frame_steps import _shift_in_t


def _frames(n: int = 3):
    return np.zeros((120, 160, 3), np.uint8), np.zeros((90, 120), np.uint8)


def test_trail_covers_the_last_second_of_frames():
    assert tail_length(10.0) == 10 and tail_length(29.97) == 30
    assert tail_length(None) == 30 and tail_length(float("nan"), fallback=12) == 12
    annotator = Annotator(tail_length(10.0))
    rgb, thermal = _frames()
    for k in range(25):
        box = np.array([10.0 + 2 * k, 40.0, 10.0, 10.0])
        annotator.draw(rgb, thermal, box, box, "appearance")
    trail = annotator.trail(annotator.tail_rgb)
    assert len(trail) == 10 and len(annotator.tail_t) == 10
    np.testing.assert_allclose(trail[:, 0], 10 + 2 * np.arange(15, 25) + 5)  # the last ten centres, oldest first


def test_trail_is_drawn_in_the_current_frame_under_camera_motion():
    """A target still in the scene while the camera pans 4 px/frame: compensated, the tail stays on the target."""
    rgb, thermal = _frames()
    shaken, compensated = Annotator(10), Annotator(10)
    scene_centre = np.array([80.0, 60.0])
    previous = last_shift = None
    for k in range(8):
        shift = np.array([4.0 * k, -1.0 * k])  # accumulated camera shift: stable = image + shift
        centre = scene_centre - shift  # where the still target appears in frame k
        box = np.r_[centre - 5, 10.0, 10.0]
        box_t = np.r_[(scene_centre - shift) / 2 - 2.5, 5.0, 5.0]  # a thermal camera at half the resolution
        shaken.draw(rgb, thermal, box, box_t, "appearance")
        compensated.draw(rgb, thermal, box, box_t, "appearance", shift=shift, shift_t=shift / 2)
        trail = compensated.trail(compensated.tail_rgb, shift)
        if k:
            np.testing.assert_allclose(trail[:-1], previous - (shift - last_shift))  # old points move with the camera
        previous, last_shift = trail, shift
    np.testing.assert_allclose(trail, np.tile(centre, (8, 1)))  # all on the target now: no scribble
    assert np.ptp(shaken.trail(shaken.tail_rgb)[:, 0]) == 28.0  # uncompensated: the pan drawn as a 28 px streak
    np.testing.assert_allclose(compensated.trail(compensated.tail_t, shift / 2),  # thermal tail: its own shift
                               np.tile((scene_centre - shift) / 2, (8, 1)))


def test_camera_shift_is_carried_into_thermal_pixels():
    half = np.diag([0.5, 0.5, 1.0])
    np.testing.assert_allclose(_shift_in_t(half, np.array([40.0, 30.0]), np.array([8.0, -2.0])), [4.0, -1.0])


def test_the_label_grows_with_the_panel_and_reads_on_a_bright_sky():
    """A 1080p run's panel is 568 px high: its label is drawn larger than a 240-px panel's, on a darkened band, so it
    reads on a white sky in a video played at screen size."""
    from rgbt_toolkit.jmmac.annotate import label_scale

    assert label_scale(240) == 0.45 and label_scale(568) > 0.7 and label_scale(4000) == 1.2
    sizes = {}
    for height in (240, 568):
        sky = np.full((height, height * 2), 250, np.uint8)
        panel = Annotator().draw(sky, sky, np.array([10.0, 100, 30, 30]), np.array([10.0, 100, 30, 30]),
                                 "appearance", "#150 q=344")
        corner = panel[: height // 8, : height]
        assert corner.min() < 40  # the outline and the band are dark on the bright sky
        dark_rows = np.where((panel[:, : height, :] < 150).all(axis=2).any(axis=1))[0]
        sizes[height] = dark_rows[dark_rows < height // 4].max()  # bottom of the label band
    assert sizes[568] > 1.25 * sizes[240]


def test_a_large_thermal_view_gets_its_box_drawn_at_the_panels_scale():
    """A 1920x1080 thermal camera beside a 454-px working frame: the thermal view is shrunk to the panel first and its
    box drawn there, two panel pixels thick at the scaled place, as on the RGB view (drawn at the thermal camera's
    size and then shrunk, the box was a faint 0.8-px line)."""
    rgb = np.zeros((120, 160, 3), np.uint8)
    thermal = np.full((480, 640), 40, np.uint8)  # 4x the panel's height
    box_t = np.array([200.0, 120.0, 160.0, 120.0])  # -> x 50..89, y 30..59 in the thermal view of the panel
    panel = Annotator().draw(rgb, thermal, np.array([20.0, 30, 40, 30]), box_t, "appearance")
    assert panel.shape == (120, 160 + 160, 3)
    green = (panel[:, :, 1] > 150) & (panel[:, :, 0] < 120)
    right = green[:, 160:]
    assert right[35:55, 50].all() and right[35:55, 51].all()  # the left edge, two pixels wide
    assert right[30, 55:85].all() and right[59, 55:85].all()  # top and bottom edges where the scaled box puts them
    assert not right[35:55, 55:85].any()  # inside: the thermal picture, unmarked
    assert (panel[35:55, 160 + 60, 0] == 40).all()  # the thermal view is the shrunk frame itself, in grey
    assert green[35:55, 20].all() and green[35:55, 21].all()  # the RGB view's box, as before


def test_the_default_video_scale_keeps_the_panel_at_most_1280_px_wide():
    """The panel's width is predicted from the two frame sizes before any frame is drawn (the thermal view at the RGB
    view's height), and the default video scale shrinks only panels wider than PANEL_MAX_WIDTH."""
    from rgbt_toolkit.jmmac.annotate import PANEL_MAX_WIDTH, default_video_scale, panel_width

    for rgb_size, t_size in (((160, 120), (640, 480)), ((807, 454), (1920, 1080)), ((333, 250), (640, 512))):
        rgb = np.zeros(rgb_size[::-1] + (3,), np.uint8)
        panel = Annotator().draw(rgb, np.zeros(t_size[::-1], np.uint8), np.array([10.0, 10, 20, 20]),
                                 np.array([10.0, 10, 20, 20]), "appearance")
        assert panel.shape[1] == panel_width(rgb_size, t_size)
    assert PANEL_MAX_WIDTH == 1280
    assert default_video_scale((640, 512), (640, 512)) == 1.0  # a 640x512 rig: drawn as tracked
    assert default_video_scale((807, 454), (1920, 1080)) == pytest.approx(1280 / 1614)
    assert default_video_scale((807, 454), (640, 512)) == pytest.approx(1280 / (807 + 568))
