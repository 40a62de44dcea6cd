"""The ``overlays`` challenge: each camera's own OSD, a clock that ticks each second, truth unchanged."""

import numpy as np

from rgbt_toolkit.synth.config import SceneConfig
from rgbt_toolkit.synth.osd import osd_lines, osd_pixels
from rgbt_toolkit.synth.render import SceneRenderer


def _scene(overlays: bool) -> SceneRenderer:
    return SceneRenderer(SceneConfig(challenges=frozenset({"overlays"} if overlays else set()), seed=3))


def test_overlay_is_drawn_white_where_the_osd_is_and_nowhere_else():
    plain, osd = _scene(False).render(0.5, "rgb", 7), _scene(True).render(0.5, "rgb", 7)
    where = osd_pixels((320, 240), 0.5, "rgb")
    changed = np.any(plain.image != osd.image, axis=2)
    assert not changed[~where].any()
    assert np.median(osd.image[where].min(axis=1)) > np.median(plain.image[where].min(axis=1)) + 60
    assert np.array_equal(plain.box, osd.box)


def test_each_camera_has_its_own_osd_and_only_rgb_a_reticle():
    rgb, t = osd_pixels((320, 240), 0.0, "rgb"), osd_pixels((320, 240), 0.0, "t")
    assert (rgb != t).mean() > 0.01  # other fonts, sizes and margins
    centre = np.zeros((240, 320), bool)
    centre[60:180, 80:240] = True
    assert rgb[centre].any() and not t[centre].any()  # the reticle's brackets are near the centre


def test_clock_changes_every_second():
    assert osd_lines(0.2, "t")[0] == osd_lines(0.9, "t")[0] != osd_lines(1.1, "t")[0]
    assert not np.array_equal(osd_pixels((256, 192), 0.2, "t"), osd_pixels((256, 192), 1.1, "t"))
