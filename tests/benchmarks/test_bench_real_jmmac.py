"""`bench_real.py --jmmac`: the JmmacConfig fields it is given reach the JMMAC tracker it runs (on a generated clip,
so the test needs nothing from ../shared)."""

from __future__ import annotations

import cv2
import numpy as np


def _clip(frames: int = 6) -> tuple[list[np.ndarray], np.ndarray]:
    """A grey textured 320x240 clip with a bright 60x60 px target moving 2 px a frame: large enough that its search
    region (240 px) is wider than hc's smallest patch (150 px), so the patch bounds matter."""
    rng = np.random.default_rng(0)
    background = cv2.GaussianBlur(rng.integers(0, 255, (240, 320)).astype(np.uint8), (5, 5), 0)
    clip = []
    for k in range(frames):
        frame = (background * 0.5).astype(np.uint8)
        x = 100 + 2 * k
        frame[90:150, x:x + 60] = 200 + (background[90:150, 100:160] // 8)
        clip.append(frame)
    return clip, np.array([100.0, 90.0, 60.0, 60.0])


def test_jmmac_config_overrides_reach_the_tracker(load_benchmark):
    bench = load_benchmark("bench_real")
    frames, init = _clip()
    default = bench.run_jmmac("JMMAC", frames, init)
    unchanged = bench.run_jmmac("JMMAC", frames, init, {})
    smaller_patch = bench.run_jmmac("JMMAC", frames, init, {"sample_area": [22500, 22500]})
    assert default.shape == (len(frames), 4)
    np.testing.assert_array_equal(unchanged, default)
    # the same target followed (within 2 px) from a smaller patch: the override changed the tracker, not the task
    assert np.max(np.abs(smaller_patch - default)) > 1e-6
    assert np.max(np.abs(smaller_patch[:, :2] - default[:, :2])) < 2.0
