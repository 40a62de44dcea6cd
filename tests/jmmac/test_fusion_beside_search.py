"""With two tracker threads MFNet's weights are computed while the two ECO searches run (issue #21): the region it
needs is known before searching, so the overlap changes the speed, not the result."""

from __future__ import annotations

import threading

import numpy as np

from rgbt_toolkit.eco import preset as eco_preset
from rgbt_toolkit.jmmac.config import preset
from rgbt_toolkit.jmmac.eco_part import EcoAppearance, grid_region
from rgbt_toolkit.jmmac.pipeline import JmmacTracker

from .fakes import ScriptedTracker


def _frame(seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    frame = rng.integers(60, 90, (120, 160), dtype=np.uint8)
    frame[50:70, 70:90] = 220
    return frame


def test_search_grid_is_the_region_the_search_then_reports():
    tracker = EcoAppearance(eco_preset("hc"))
    frame = _frame()
    tracker.initialize(frame, np.array([70.0, 50.0, 20.0, 20.0]))
    for centre in (np.array([81.0, 61.5]), np.array([-30.0, 400.0])):  # the second is clipped into the frame
        region, grid = tracker.search_grid(centre)
        estimate = tracker.predict(_frame(1), centre)
        np.testing.assert_allclose(region, grid_region(estimate.context))
        assert grid == estimate.response.shape


def _square_grid(centre, side: float = 31.0):
    """A fake tracker's search region: a ``side``-pixel square around ``centre`` on a 31 x 31 grid."""
    return np.array([centre[0] - side / 2, centre[1] - side / 2, side, side]), (31, 31)


class _WaitingTracker(ScriptedTracker):
    """Its search does not return before the fusion net has been called (or ``patience`` seconds have passed)."""

    def __init__(self, truth, fusion_called: threading.Event, patience: float):
        super().__init__(truth)
        self.fusion_called, self.patience = fusion_called, patience
        self.saw_fusion_during_search: list[bool] = []

    def predict(self, frame, centre, search_scales=True):
        self.saw_fusion_during_search.append(self.fusion_called.wait(timeout=self.patience))
        return super().predict(frame, centre)

    def search_grid(self, centre):
        return _square_grid(centre)


class _SignallingFusion:
    def __init__(self, event: threading.Event):
        self.event = event
        self.regions: list[np.ndarray] = []

    def __call__(self, rgb, thermal, region, grid_shape):
        self.regions.append(np.asarray(region, float))
        self.event.set()
        return 0.5, np.ones(grid_shape)


def _run(parallel: bool):
    truth = [np.array([50.0, 50.0])] * 3
    event = threading.Event()
    patience = 5.0 if parallel else 0.1  # sequential: each search waits in vain for a fusion still to come
    rgb, t = _WaitingTracker(truth, event, patience), _WaitingTracker(truth, event, patience)
    fusion = _SignallingFusion(event)
    tracker = JmmacTracker(preset("+MF", parallel_trackers=parallel), rgb, t, fusion=fusion)
    frame = np.zeros((100, 100), np.uint8)
    tracker.initialize(frame, frame, np.array([45.0, 41.0, 11.0, 19.0]))
    event.clear()
    result = tracker.track(frame, frame)
    return rgb.saw_fusion_during_search + t.saw_fusion_during_search, fusion.regions, result


def test_with_two_threads_the_fusion_runs_while_the_trackers_search():
    seen, regions, result = _run(parallel=True)
    assert seen == [True, True]
    np.testing.assert_allclose(regions[0], [50.0 - 15.5, 50.0 - 15.5, 31.0, 31.0])
    assert result.w_g == 0.5


def test_with_one_thread_the_fusion_follows_the_searches():
    seen, regions, _ = _run(parallel=False)
    assert seen == [False, False]
    assert len(regions) == 1


def test_real_trackers_give_the_same_boxes_with_and_without_the_overlap():
    from rgbt_toolkit.jmmac.api import build_tracker
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    renderer = SceneRenderer(SceneConfig.aligned(rgb_size=(320, 240), seed=2, challenges=frozenset({"occlusion"})))
    frames = [(renderer.render(k / 15, "rgb", k), renderer.render(k / 15, "t", k)) for k in range(8)]
    runs = []
    for parallel in (False, True):
        tracker = build_tracker(preset("default", parallel_trackers=parallel))
        tracker.initialize(frames[0][0].image, frames[0][1].image, frames[0][0].box)
        runs.append([tracker.track(rgb.image, t.image) for rgb, t in frames[1:]])
    for a, b in zip(*runs):
        np.testing.assert_array_equal(a.box, b.box)
        assert a.w_g == b.w_g


class _ThreadRecordingTracker(ScriptedTracker):
    """Records the thread of each search and whether it searched scales; a scale search waits (up to ``patience``
    seconds) for the fusion net, so it can only see it when the two ran at once."""

    def __init__(self, truth, fusion_called: threading.Event, patience: float = 5.0):
        super().__init__(truth)
        self.fusion_called, self.patience = fusion_called, patience
        self.searches: list[tuple[bool, bool, bool]] = []  # (on the calling thread, all scales, saw the fusion)

    def predict(self, frame, centre, search_scales=True):
        saw = self.fusion_called.wait(timeout=self.patience) if search_scales else self.fusion_called.is_set()
        self.searches.append((threading.current_thread() is threading.main_thread(), search_scales, saw))
        return super().predict(frame, centre)

    def search_grid(self, centre):
        return _square_grid(centre)


class _SignallingConstantFusion(_SignallingFusion):
    def __init__(self, event: threading.Event, w_g: float):
        super().__init__(event)
        self.w_g = w_g

    def __call__(self, rgb, thermal, region, grid_shape):
        super().__call__(rgb, thermal, region, grid_shape)
        return self.w_g, np.ones(grid_shape)


def test_the_tracker_without_the_scale_search_runs_on_the_calling_thread_before_the_fusion():
    """Three threads on two cores slowed the 7-scale search, the longest job of a frame; the other tracker's
    one-scale search runs here before MFNet instead, while the scale search has a pool thread to itself."""
    truth = [np.array([50.0, 50.0])] * 4
    event = threading.Event()
    rgb, t = _ThreadRecordingTracker(truth, event), _ThreadRecordingTracker(truth, event)
    tracker = JmmacTracker(preset("+MF", parallel_trackers=True), rgb, t,
                           fusion=_SignallingConstantFusion(event, 0.8))  # RGB trusted: RGB searches scales
    frame = np.zeros((100, 100), np.uint8)
    tracker.initialize(frame, frame, np.array([45.0, 41.0, 11.0, 19.0]))
    for _ in range(3):
        event.clear()
        tracker.track(frame, frame)
    # frame 1: no weight yet (w_G 0.5), both search scales on the pool; then RGB alone, beside the fusion
    assert rgb.searches == [(False, True, True)] * 3
    assert t.searches[0] == (False, True, True)
    assert t.searches[1:] == [(True, False, False)] * 2  # here, before the fusion was called
