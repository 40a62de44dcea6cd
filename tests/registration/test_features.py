import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.registration.features import BLANK_GRADIENT_RMS, gradient_rms, orientation_field, to_grey


def test_to_grey_ranges():
    rgb = np.full((8, 9, 3), 255, np.uint8)
    assert to_grey(rgb).shape == (8, 9) and to_grey(rgb).max() == pytest.approx(1.0, abs=1e-5)
    raw = np.linspace(1000, 3000, 64, dtype=np.uint16).reshape(8, 8)  # 16-bit thermal: its used range is stretched
    g = to_grey(raw)
    assert g.min() == pytest.approx(0.0, abs=0.01) and g.max() == pytest.approx(1.0, abs=0.01)
    with pytest.raises(InputError, match="expected a 2-D grey"):
        to_grey(np.zeros((4, 4, 2)))


def test_orientation_field_ignores_contrast_reversal_and_gain(pair):
    visible = to_grey(pair[0])
    a = orientation_field(visible)
    b = orientation_field(1.0 - 0.3 * visible)  # inverted and with a quarter of the contrast
    assert a.shape == visible.shape + (2,)
    assert np.abs(a - b).max() < 1e-4


def test_blank_frames_have_no_gradient(pair):
    assert gradient_rms(np.full((50, 60), 0.4, np.float32)) < BLANK_GRADIENT_RMS
    assert gradient_rms(to_grey(pair[0])) > 10 * BLANK_GRADIENT_RMS
