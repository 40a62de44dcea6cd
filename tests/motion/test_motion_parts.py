"""The motion parts plugged into the JMMAC pipeline: an occlusion handled end to end by Kalman + Algorithm 1."""

import numpy as np
import pytest
from motion_synth import make_texture

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion import (
    Algorithm1Switch,
    CameraMotionCompensation,
    ConstantVelocityKalman,
    DdisTemplateScorer,
    PaperScaleQuality,
    build_motion_parts,
)
from rgbt_toolkit.motion.template import ModalityAwareTemplate

GRID = 41


class _FakeEco:
    """Finds the target where the script says; stuck on a flat, noisy response while it is occluded."""

    def __init__(self, truth, occluded, stuck):
        from rgbt_toolkit.jmmac.parts import AppearanceEstimate

        self.estimate_type = AppearanceEstimate
        self.truth, self.occluded, self.stuck = truth, occluded, stuck
        self.rng = np.random.default_rng(0)
        self.k, self.updates = 0, []

    def initialize(self, frame, box):
        self.size, self.k = np.asarray(box[2:], float), 0

    def predict(self, frame, centre):
        self.k += 1
        occluded = self.k in self.occluded
        peak = self.stuck if occluded else self.truth[self.k]
        offs = np.arange(GRID) - GRID // 2
        gx, gy = np.meshgrid(centre[0] + offs, centre[1] + offs)
        amp, sigma = (0.3, 6.0) if occluded else (1.0, 2.0)
        resp = amp * np.exp(-((gx - peak[0]) ** 2 + (gy - peak[1]) ** 2) / (2 * sigma**2))
        resp = resp + self.rng.random((GRID, GRID)) * 0.05
        box = np.r_[peak - (self.size - 1) / 2, self.size]
        return self.estimate_type(box, resp, 1.0, float(resp.max()), np.asarray(centre, float))

    def locate(self, estimate, response, scale_factor):
        row, col = np.unravel_index(np.argmax(response), response.shape)
        centre = estimate.context + np.array([col, row]) - GRID // 2
        return np.r_[centre - (self.size - 1) / 2, self.size]

    def update(self, frame, box):
        self.updates.append(self.k)


def test_build_motion_parts_kinds():
    parts = build_motion_parts("similarity")
    assert isinstance(parts["camera_motion"], CameraMotionCompensation)
    assert parts["camera_motion"].estimator.settings.model == "similarity"
    assert isinstance(parts["kalman"], ConstantVelocityKalman)
    assert isinstance(parts["quality"], PaperScaleQuality)
    assert isinstance(parts["template"], ModalityAwareTemplate)
    assert isinstance(parts["template"].rgb_scorer, DdisTemplateScorer)
    assert isinstance(parts["switch"], Algorithm1Switch)
    assert parts["quality"].calibrator is parts["template"].rgb_scorer.calibrator
    assert parts["template"].thermal_scorer.calibrator is not parts["quality"].calibrator


def test_template_scorer_calibrates_on_first_frame():
    scene = make_texture(200, 240, 3, channels=3)
    parts = build_motion_parts(features="colour")
    box = np.array([80.0, 60.0, 36.0, 52.0])
    scorer = parts["template"].rgb_scorer
    scorer.initialize(scene, box)
    s_a, s_m = scorer(scene, box, box + [40.0, 0.0, 0.0, 0.0])
    assert s_a == pytest.approx(100.0 * scorer.calibrator.s_scale)  # the template itself
    assert s_m < 15.0 < s_a  # a window 40 px away is below s_hi, the right one far above
    scorer.calibrator.paper_q(10.0)
    scorer.initialize(scene, box)  # a new sequence: the running q statistics start again
    assert scorer.calibrator.q_scale == 1.0 and not scorer.calibrator.q_frozen
    with pytest.raises(InputError, match="DDIS features"):
        DdisTemplateScorer(scorer.calibrator, features="sift")


def test_occlusion_is_bridged_by_the_motion_tracker():
    pytest.importorskip("rgbt_toolkit.jmmac.pipeline")
    from rgbt_toolkit.jmmac.config import preset
    from rgbt_toolkit.jmmac.pipeline import JmmacTracker

    bg_rgb, bg_t = make_texture(240, 320, 1, channels=3), make_texture(240, 320, 2)
    target_rgb, target_t = make_texture(40, 30, 3, channels=3), make_texture(40, 30, 4)
    occluder = make_texture(60, 60, 5, channels=3)
    n, occluded = 24, set(range(13, 18))
    truth = [np.array([80.0 + 3 * k, 120.0]) for k in range(n)]  # centres, 3 px per frame to the right
    eco = _FakeEco(truth, occluded, stuck=truth[12])
    # colour features keep the test fast; the default deep features are exercised by benchmarks/bench_motion.py
    tracker = JmmacTracker(preset("+TMP", fusion="t"), None, eco, **build_motion_parts(features="colour"))
    frames = []
    for k in range(n):
        rgb, t = bg_rgb.copy(), bg_t.copy()
        x0, y0 = (truth[k] - [14.5, 19.5]).astype(int)
        rgb[y0 : y0 + 40, x0 : x0 + 30] = target_rgb
        t[y0 : y0 + 40, x0 : x0 + 30] = target_t
        if k in occluded:
            rgb[90:150, 118:178] = occluder
        frames.append((rgb, t))
    tracker.initialize(*frames[0], np.r_[truth[0] - [14.5, 19.5], 30.0, 40.0])
    modes, errors = [], []
    for k in range(1, n):
        result = tracker.track(*frames[k])
        modes.append(result.mode)
        errors.append(np.hypot(*(result.box[:2] + (result.box[2:] - 1) / 2 - truth[k])))
    assert [k for k, m in enumerate(modes, 1) if m == "motion"] == sorted(occluded)
    assert max(errors) < 1.0  # the Kalman prediction carried the box through the occlusion
    assert not occluded & set(eco.updates)  # no appearance update while the motion tracker was in use


@pytest.mark.slow
def test_deep_backbone_features_for_ddis():
    from rgbt_toolkit.motion.ddis import crop_window, ddis_score
    from rgbt_toolkit.motion.parts import backbone_features

    features = backbone_features("efficientnet-lite0", "shallow")
    scene, box = make_texture(200, 200, 1, channels=3), np.array([60.0, 60.0, 48.0, 48.0])
    template = features(crop_window(scene, box, (48, 48)))
    assert template.shape == (12, 12, 24)  # stride 4

    def score(image, b):
        return ddis_score(template, features(crop_window(image, b, (48, 48))), normalize_features=True)

    assert score(scene, box) == pytest.approx(100.0)
    assert score(scene, box + [3.0, 2.0, 0.0, 0.0]) > 2 * score(make_texture(200, 200, 5, channels=3), box)
