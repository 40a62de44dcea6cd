"""The shipped tracking heads load into MFNet and give weights in (0, 1)."""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.fusion.model import MFNet
from rgbt_toolkit.jmmac.api import TRACKING_HEADS
from rgbt_toolkit.jmmac.fusion_part import MfnetWeighting


def test_tracking_heads_are_shipped_small_and_fit_the_backbone():
    assert TRACKING_HEADS.is_file() and TRACKING_HEADS.stat().st_size < 5 * 2**20
    weighting = MfnetWeighting(MFNet.from_file(TRACKING_HEADS))
    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)
    thermal = rng.integers(0, 255, (120, 160), dtype=np.uint8)
    w_g, w_l = weighting(rgb, thermal, np.array([40.0, 20.0, 60.0, 60.0]), (25, 25))
    assert 0.0 < w_g < 1.0 and w_l.shape == (25, 25) and np.all((w_l > 0) & (w_l < 1))
