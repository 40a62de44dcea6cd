"""Block agreement: the parts of a right transform's view agree with it on their own; a wrong one's scatter."""

import numpy as np
import pytest

from rgbt_toolkit.registration.features import to_grey
from rgbt_toolkit.registration.verify import block_agreement
from rgbt_toolkit.synth import SceneConfig, SceneRenderer


@pytest.fixture(scope="module")
def scene():
    renderer = SceneRenderer(SceneConfig(seed=2))
    rgb = to_grey(renderer.render(1.0, "rgb").image)
    thermal = to_grey(renderer.render(1.0, "t").image)
    return rgb, thermal, renderer.h_rgb_to_t


def test_true_transform_has_most_textured_blocks_agreeing(scene):
    rgb, thermal, truth = scene
    agreement = block_agreement([rgb], [thermal], truth)
    assert agreement.textured >= 8
    assert agreement.fraction >= 0.6, agreement
    assert np.median(np.abs(agreement.shifts), axis=0).max() <= 1.0  # the typical block peaks at zero shift


def test_transform_off_by_a_shift_is_seen_by_every_block(scene):
    """Off by 4 % of the width: the blocks that find a peak find it at that offset, not at zero."""
    rgb, thermal, truth = scene
    off = truth @ np.array([[1, 0, 0.04 * rgb.shape[1]], [0, 1, 0], [0, 0, 1.0]])
    agreement = block_agreement([rgb], [thermal], off)
    assert agreement.agreeing <= 2, agreement
    # the blocks' own peaks point back to the truth: about -4 % of the level width in x
    level_shift = 0.04 * 320
    assert np.median(agreement.shifts[:, 0]) == pytest.approx(-level_shift, abs=2.0)


def test_unrelated_scenes_do_not_agree(scene):
    rgb, _, truth = scene
    other = SceneRenderer(SceneConfig(seed=7))
    thermal = to_grey(other.render(3.0, "t").image)
    agreement = block_agreement([rgb], [thermal], truth)
    assert agreement.agreeing <= 3, agreement


def test_blank_view_has_no_textured_blocks(scene):
    rgb, thermal, truth = scene
    agreement = block_agreement([np.zeros_like(rgb)], [thermal], truth)
    assert agreement.textured == 0 and agreement.fraction == 0.0


def test_cameras_of_different_resolution_agree(scene):
    """A 3x larger RGB camera: the thermal frame must not be shrunk by the scale twice."""
    import cv2

    from rgbt_toolkit.registration.transforms import pixel_scaling

    rgb, thermal, truth = scene
    big = cv2.resize(rgb, None, fx=3.0, fy=3.0, interpolation=cv2.INTER_CUBIC)
    matrix = truth @ pixel_scaling(1 / 3.0, 1 / 3.0)  # big RGB pixels -> original RGB pixels -> thermal
    agreement = block_agreement([big], [thermal], matrix)
    assert agreement.fraction >= 0.6, agreement


def test_frame_lists_of_different_length_are_refused(scene):
    from rgbt_toolkit.errors import InputError

    rgb, thermal, truth = scene
    with pytest.raises(InputError, match="2 RGB frames but 1 thermal"):
        block_agreement([rgb, rgb], [thermal], truth)
