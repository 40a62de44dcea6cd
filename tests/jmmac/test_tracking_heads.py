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


def test_tracker_feeds_mfnet_the_configured_patch_side():
    """`rgbt track` runs MFNet on 80 px crops (issue #21: the generated benchmarks' accuracy of 128 px at 60 % of the
    cost); the side is a setting, checked against the backbone's stride."""
    import pytest

    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.jmmac.api import build_tracker
    from rgbt_toolkit.jmmac.config import JmmacConfig

    class Recorder:
        def patch_weights(self, rgb, thermal, grid):
            self.shapes = (rgb.shape, thermal.shape)
            return 0.5, np.full(grid, 0.5)

    for side in (80, 128):
        net = Recorder()
        fusion = build_tracker(JmmacConfig(fusion_patch=side), mfnet=net).fusion
        fusion(np.zeros((240, 320, 3), np.uint8), np.zeros((240, 320), np.uint8), np.array([100.0, 80, 60, 60]),
               (25, 25))
        assert net.shapes == ((side, side, 3), (side, side))
    assert JmmacConfig().fusion_patch == 80
    for bad in (72, 16):
        with pytest.raises(InputError, match="multiple of 16"):
            JmmacConfig(fusion_patch=bad)
