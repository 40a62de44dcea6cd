"""The JMMAC per-frame step with scripted parts: fusion, switching, update rules and suspensions."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.jmmac import JmmacTracker, preset
from rgbt_toolkit.jmmac.pipeline import box_centre
from rgbt_toolkit.motion.switcher import Algorithm1Switch, SwitchThresholds

from .fakes import ConstantFusion, FixedTemplate, RecordingKalman, ScriptedTracker

FRAME = np.full((120, 160, 3), 128, np.uint8)
SIZE = np.array([11.0, 21.0])


def _truth(n=8):
    return [np.array([60.0 + 2 * k, 50.0 + k]) for k in range(n)]


def _box(centre):
    return np.r_[centre - (SIZE - 1) / 2, SIZE]


def _run(tracker, n):
    results = [tracker.initialize(FRAME, FRAME, _box(_truth()[0]))]
    results += [tracker.track(FRAME, FRAME) for _ in range(1, n)]
    return results


def test_fusion_weight_picks_the_reliable_modality():
    truth = _truth()
    decoy = {k: truth[k] + np.array([9.0, 0.0]) for k in range(1, 8)}  # RGB locks onto a distractor
    for w_g, expect_truth in ((0.2, True), (0.8, False)):
        rgb, t = ScriptedTracker(truth, decoy), ScriptedTracker(truth)
        tracker = JmmacTracker(preset("+MF"), rgb, t, fusion=ConstantFusion(w_g))
        results = _run(tracker, 5)
        errors = [np.abs(box_centre(r.box) - truth[r.index]).max() for r in results[1:]]
        assert (max(errors) < 0.5) == expect_truth
        assert results[-1].w_g == pytest.approx(w_g)


def test_single_modality_presets_run_one_tracker_only():
    truth = _truth()
    rgb, t = ScriptedTracker(truth), ScriptedTracker(truth)
    _run(JmmacTracker(preset("B-T"), rgb, t), 4)
    assert rgb.updates == [] and t.updates == [1, 2, 3]


def test_motion_mode_freezes_appearance_updates_and_kalman_corrections():
    truth = _truth()
    rgb, t = ScriptedTracker(truth), ScriptedTracker(truth)
    kalman = RecordingKalman()
    switch_calls = []

    def switch(q, s_a, s_m, offset, spread_offset=None):
        switch_calls.append((q, s_a, s_m))
        return s_a > s_m

    scores = [(20.0, 0.0), (20.0, 0.0), (0.0, 20.0), (20.0, 0.0)]  # frame 4 goes to the motion tracker
    tracker = JmmacTracker(preset("+TMP", camera_motion=False), rgb, t, fusion=ConstantFusion(0.5), kalman=kalman,
                           quality=lambda r: 100.0, template=FixedTemplate(scores), switch=switch)
    results = _run(tracker, 7)
    modes = [r.mode for r in results]
    assert modes[:2] == ["init", "appearance"]
    motion_frames = [r.index for r in results if r.mode == "motion"]
    assert motion_frames == [4]
    assert 4 not in rgb.updates and 4 not in t.updates and 5 in t.updates
    # the Kalman filter starts at frame 1 (the authors' frame 2) and is corrected on every appearance frame but 4
    assert kalman.corrections == len([r for r in results[2:] if r.mode == "appearance"])
    motion = results[4]
    np.testing.assert_allclose(motion.box[2:], SIZE)  # scale frozen in motion mode
    assert np.isfinite(motion.s_a) and np.isfinite(motion.s_m)


@pytest.mark.parametrize("agree_offset, expect_motion", [(0.5, False), (0.0, True)])
def test_agreeing_candidates_keep_learning(agree_offset, expect_motion):
    """A visible target whose look has drifted from frame 1 (q 150, s_A = s_M = 12, below s_low) and whose
    appearance box sits on the Kalman prediction: Algorithm 1 alone sends every such frame to motion mode, where no
    model learns (on real clips the box then drifted off); with the agreement clause the appearance result stays and
    both trackers learn from every frame."""
    _expect_learning_every_frame(RecordingKalman(), SwitchThresholds(agree_offset=agree_offset), expect_motion)


def _expect_learning_every_frame(kalman, thresholds, expect_motion: bool) -> None:
    """q 150 and s_A = s_M = 12 on every frame (a target whose look has drifted, below s_low): whether Algorithm 1
    with ``thresholds`` sends frames to motion mode, and if not, that both trackers learn from every frame."""
    truth = _truth()
    rgb, t = ScriptedTracker(truth), ScriptedTracker(truth)
    tracker = JmmacTracker(preset("+TMP", camera_motion=False), rgb, t, fusion=ConstantFusion(0.5), kalman=kalman,
                           quality=lambda r: 150.0, template=FixedTemplate([(12.0, 12.0)] * 8),
                           switch=Algorithm1Switch(thresholds))
    results = _run(tracker, 7)
    assert bool([r for r in results if r.mode == "motion"]) is expect_motion
    if not expect_motion:
        assert rgb.updates == t.updates == [1, 2, 3, 4, 5, 6]


class _OffPredictingKalman(RecordingKalman):
    """A motion model whose prediction lies 12 px ahead of the last position (the target moves 2 px a frame: the
    prediction misses it by 10 px, as after a turn the filter has not seen yet), and which says its
    prediction spreads 10.5 px (the paper's Kalman at steady state)."""

    def predict(self):
        return self.positions[-1] + np.array([12.0, 0.0])

    def spread(self):
        return 10.5


@pytest.mark.parametrize("agree_sigmas, expect_motion", [(1.0, False), (0.0, True)])
def test_candidates_within_the_motion_models_spread_keep_learning(agree_sigmas, expect_motion):
    """The two candidates 10 px apart: more than half the 15-px target (the size rule does not hold), but within the
    Kalman prediction's own spread, so the motion model has no evidence against the appearance result."""
    _expect_learning_every_frame(_OffPredictingKalman(), SwitchThresholds(agree_sigmas=agree_sigmas), expect_motion)


def test_high_quality_skips_template_matching():
    truth = _truth()
    template = FixedTemplate([])
    tracker = JmmacTracker(preset("+TMP", camera_motion=False), ScriptedTracker(truth), ScriptedTracker(truth),
                           fusion=ConstantFusion(0.5), kalman=RecordingKalman(), quality=lambda r: 300.0,
                           template=template, switch=lambda q, a, m, offset, spread=None: False)
    results = _run(tracker, 5)
    assert template.calls == 0 and all(r.mode != "motion" for r in results)


class _AlwaysMoving:
    """Camera-motion stand-in reporting drastic motion that shifts the scene by +3 px in x per frame."""

    def initialize(self, rgb, t):
        self.total = np.zeros(2)

    def step(self, rgb, t, box):
        self.total = self.total + [3.0, 0.0]

        class Step:
            camera_motion = True
            total_shift = self.total.copy()

        Step.box = np.r_[box[:2] + [3.0, 0.0], box[2:]]
        return Step


def test_drastic_camera_motion_suspends_fusion_and_switching():
    truth = _truth()
    template = FixedTemplate([])
    tracker = JmmacTracker(preset("full", refine=False), ScriptedTracker(truth), ScriptedTracker(truth),
                           fusion=ConstantFusion(0.9), camera_motion=_AlwaysMoving(), kalman=RecordingKalman(),
                           quality=lambda r: 300.0, template=template, switch=lambda q, a, m, offset, spread=None: False)
    results = _run(tracker, 4)
    assert all(r.camera_motion and r.w_g == 0.5 and r.mode == "appearance" for r in results[1:])
    assert template.calls == 0


def test_target_hidden_under_camera_motion_is_carried_by_the_camera():
    """q below q_low while the camera moves: the previous box moved by the camera, and no model learns."""
    truth = _truth()
    kalman, rgb_tracker = RecordingKalman(), ScriptedTracker(truth)
    tracker = JmmacTracker(preset("full", refine=False), rgb_tracker, ScriptedTracker(truth),
                           fusion=ConstantFusion(0.9), camera_motion=_AlwaysMoving(), kalman=kalman,
                           quality=lambda r: 10.0, template=FixedTemplate([]), switch=lambda q, a, m, offset, spread=None: False)
    results = _run(tracker, 4)
    assert all(r.mode == "motion" and r.camera_motion for r in results[1:])
    for k in range(1, 4):  # +3 px per frame from the initial box, whatever the appearance trackers say
        np.testing.assert_allclose(results[k].box, results[0].box + [3.0 * k, 0, 0, 0])
    assert not kalman.initialized and kalman.corrections == 0 and rgb_tracker.updates == []


@pytest.mark.parametrize("box, message", [([10, 10, 0, 5], "zero or negative size"), ([500, 10, 5, 5], "outside"),
                                          ([np.nan, 1, 2, 3], "four finite numbers")])
def test_bad_initial_boxes_are_clear_errors(box, message):
    tracker = JmmacTracker(preset("B-RGB"), ScriptedTracker(_truth()), None)
    with pytest.raises(InputError, match=message):
        tracker.initialize(FRAME, FRAME, np.array(box, float))


def test_missing_parts_are_reported():
    with pytest.raises(InputError, match="needs an MFNet"):
        JmmacTracker(preset("+MF"), ScriptedTracker(_truth()), ScriptedTracker(_truth()))
    with pytest.raises(InputError, match="unknown preset"):
        preset("+XYZ")


class _Zooming(ScriptedTracker):
    """Reports a fixed size change when it searches scales, none when it looks at the current scale only."""

    def __init__(self, truth, factor):
        super().__init__(truth)
        self.factor, self.searched = factor, []

    def predict(self, frame, centre, search_scales=True):
        estimate = super().predict(frame, centre)
        self.searched.append(search_scales)
        estimate.scale_factor = self.factor if search_scales else 1.0
        return estimate

    def locate(self, estimate, response, scale_factor):
        box = super().locate(estimate, response, scale_factor)
        centre, size = box[:2] + (box[2:] - 1) / 2, self.size * scale_factor
        return np.r_[centre - (size - 1) / 2, size]

    def update(self, frame, box):
        super().update(frame, box)
        self.size = np.asarray(box[2:], float)


@pytest.mark.parametrize("w_g, searcher", [(0.8, "rgb"), (0.2, "t"), (0.5, None)])
def test_the_trusted_modality_alone_searches_scales_and_sets_the_size(w_g, searcher):
    truth = _truth()
    rgb, t = _Zooming(truth, 1.10), _Zooming(truth, 0.90)
    results = _run(JmmacTracker(preset("+MF"), rgb, t, fusion=ConstantFusion(w_g)), 4)
    # the first frame after the initial one: no weight yet, both search and their sizes blend
    assert rgb.searched[0] and t.searched[0]
    assert results[1].box[2] == pytest.approx(SIZE[0] * 1.10 ** w_g * 0.90 ** (1 - w_g))
    if searcher is None:  # no modality preferred (w_G = 0.5): always both
        assert all(rgb.searched) and all(t.searched)
        return
    lead, other = (rgb, t) if searcher == "rgb" else (t, rgb)
    assert lead.searched[1:] == [True, True] and other.searched[1:] == [False, False]
    assert results[-1].box[2] == pytest.approx(results[-2].box[2] * lead.factor)


def test_both_trackers_search_scales_when_asked_and_blend_their_sizes():
    truth = _truth()
    rgb, t = _Zooming(truth, 1.10), _Zooming(truth, 0.90)
    results = _run(JmmacTracker(preset("+MF", scale_search="both"), rgb, t, fusion=ConstantFusion(0.75)), 3)
    assert all(rgb.searched) and all(t.searched)
    assert results[-1].box[2] == pytest.approx(results[-2].box[2] * 1.10 ** 0.75 * 0.90 ** 0.25)
    with pytest.raises(InputError, match="scale search"):
        preset("+MF", scale_search="one")


class _LostWatchdog:
    """A re-acquisition watchdog that has lost the target and finds nothing."""

    lost, usual_peak = True, 1.0

    def start(self, frame, box):
        pass

    def candidates(self, frame, thermal=None, executor=None):
        return []

    def search(self, candidates, verify, size):
        return None


def test_no_tracker_searches_scales_while_the_target_is_lost():
    """Nothing learns while the target counts as lost, so a size estimated at the search centre means nothing: both
    trackers look at the current scale only (a fifth of the feature cost of the 7-scale search)."""
    truth = _truth()
    rgb, t = _Zooming(truth, 1.10), _Zooming(truth, 0.90)
    tracker = JmmacTracker(preset("+MF", reacquire=True), rgb, t, fusion=ConstantFusion(0.8))
    tracker.watchdog = _LostWatchdog()
    results = _run(tracker, 4)
    assert not any(rgb.searched) and not any(t.searched)
    assert all(r.box[2] == pytest.approx(SIZE[0]) for r in results) and not any(r.present for r in results[1:])


class _CountingFusion(ConstantFusion):
    """MFNet stand-in that counts the frames it weighs."""

    def __init__(self, w_g):
        super().__init__(w_g)
        self.calls = 0

    def __call__(self, rgb, thermal, region, grid_shape):
        self.calls += 1
        return super().__call__(rgb, thermal, region, grid_shape)


@pytest.mark.parametrize("parallel", [True, False])
def test_a_lost_frame_is_fused_by_the_plain_average_without_mfnet(parallel):
    """While the target is lost the old place's responses only give the fallback box and the whole-frame search
    weighs its candidates by the plain average; the frame itself is weighed so too, and MFNet is not run (D51)."""
    truth = _truth()
    fusion = _CountingFusion(0.8)
    tracker = JmmacTracker(preset("+MF", reacquire=True, parallel_trackers=parallel), ScriptedTracker(truth),
                           ScriptedTracker(truth), fusion=fusion)
    tracker.watchdog = _LostWatchdog()
    results = _run(tracker, 4)
    assert fusion.calls == 0
    assert all(r.w_g == 0.5 for r in results[1:])
    found = JmmacTracker(preset("+MF", parallel_trackers=parallel), ScriptedTracker(truth), ScriptedTracker(truth),
                         fusion=_CountingFusion(0.8))
    assert all(r.w_g == pytest.approx(0.8) for r in _run(found, 4)[1:])  # a tracked frame: MFNet's weight
    assert found.fusion.calls == 3
