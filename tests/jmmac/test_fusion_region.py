"""MFNet sees the region the response grid covers, so W_F lands on the cells it was computed for."""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.eco.tracker import TrackResult
from rgbt_toolkit.jmmac.config import preset
from rgbt_toolkit.jmmac.eco_part import grid_region
from rgbt_toolkit.jmmac.fusion_part import crop_resized
from rgbt_toolkit.jmmac.pipeline import JmmacTracker

from .fakes import ScriptedTracker


def test_grid_region_puts_cell_centres_on_the_grid_points():
    pred = TrackResult(box=np.zeros(4), center=np.zeros(2), scale=1.0, scale_index=0,
                       response=np.zeros((5, 5), np.float32), grid_origin=np.array([10.0, 20.0]), grid_step=2.0,
                       search_center=np.array([14.0, 24.0]), peak=1.0, psr=1.0)
    x, y, side, _ = grid_region(pred)
    cells = (np.arange(5) + 0.5) * side / 5
    np.testing.assert_allclose(x + cells, [pred.grid_to_image(0, j)[0] for j in range(5)])
    np.testing.assert_allclose(y + cells, [pred.grid_to_image(i, 0)[1] for i in range(5)])


def test_crop_of_a_pixel_aligned_region_is_the_pixels():
    image = np.random.default_rng(0).integers(0, 255, (80, 90, 3), dtype=np.uint8)
    # pixels 20..59 (centres at 20..59, edges at 19.5 and 59.5)
    np.testing.assert_array_equal(crop_resized(image, np.array([19.5, 29.5, 40.0, 40.0]), 40), image[30:70, 20:60])


class _RecordingFusion:
    def __init__(self):
        self.regions = []

    def __call__(self, rgb, thermal, region, grid_shape):
        self.regions.append(np.asarray(region, float))
        return 0.5, np.ones(grid_shape)


class _RegionTracker(ScriptedTracker):
    def predict(self, frame, centre, search_scales=True):
        estimate = super().predict(frame, centre)
        estimate.region = np.array([1.0, 2.0, 3.0, 3.0])
        return estimate


def _run(tracker_class):
    truth = [np.array([50.0, 50.0])] * 3
    fusion = _RecordingFusion()
    tracker = JmmacTracker(preset("+MF"), tracker_class(truth), tracker_class(truth), fusion=fusion)
    frame = np.zeros((100, 100), np.uint8)
    tracker.initialize(frame, frame, np.array([45.0, 41.0, 11.0, 19.0]))
    tracker.track(frame, frame)
    return fusion.regions[0]


def test_pipeline_hands_the_reported_region_to_the_fusion_net():
    np.testing.assert_allclose(_run(_RegionTracker), [1.0, 2.0, 3.0, 3.0])


def test_without_a_reported_region_the_net_sees_eco_search_area():
    x, y, side, _ = _run(ScriptedTracker)
    np.testing.assert_allclose(side, 4 * np.sqrt(11 * 19))  # ECO search_area_scale 4
    np.testing.assert_allclose([x + side / 2, y + side / 2], [50.0, 50.0])  # centred on the last box
