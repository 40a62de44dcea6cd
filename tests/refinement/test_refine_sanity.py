"""The authors' sanity limits, one rule at a time."""

import numpy as np
import pytest

from rgbt_toolkit.refinement.sanity import SanityLimits, check_correction

OLD = np.array([100.0, 100.0, 40.0, 80.0])


def test_small_change_accepted():
    assert check_correction(OLD, OLD + [3, -4, 6, -8]) is None


@pytest.mark.parametrize("new, reason", [
    ([100, 100, 70, 120], "area ratio"),  # area x2.6
    ([100, 100, 40 * 1.45, 80 / 1.45 * 0.7], "aspect change"),  # aspect x3.0
    ([100, 100, 62, 60], "side change"),  # width x1.55
    ([100, 100, 40, 80 / 1.6], "side change"),
    ([138, 100, 40, 80], "offset"),  # 0.95 widths (not occluded: limit 0.9)
    ([100, 100, -1, 80], "degenerate"),
    ([100, 100, np.nan, 80], "degenerate"),
])
def test_absurd_changes_rejected(new, reason):
    assert reason in check_correction(OLD, np.array(new, dtype=float))


def test_occlusion_loosens_offset_and_drops_distance():
    big = np.array([100.0, 100.0, 80.0, 160.0])
    far = big + [45, 0, 0, 0]  # 45 px: > 40 px but only 0.56 widths
    assert "centre moved" in check_correction(big, far)
    assert check_correction(big, far, occluded=True) is None
    shifted = OLD + [44, 0, 0, 0]  # 1.1 widths: over 0.9, under 1.2
    assert check_correction(OLD, shifted, SanityLimits(max_centre_distance=1e9)) is not None
    assert check_correction(OLD, shifted, occluded=True) is None
    assert "offset" in check_correction(OLD, OLD + [50, 0, 0, 0], occluded=True)  # 1.25 widths
