"""The box size must not drift: on small, noisy targets the in-filter scale search used to shrink or grow the box
frame after frame while its centre stayed on the target (docs/eco.md, "Scale on real footage")."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.eco.params import preset
from rgbt_toolkit.eco.run import track_frames
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.evaluation.metrics import centre_error
from tests.real_clips import real_clip


def size_error(boxes: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """``|log(area_est / area_true)|`` per frame (frames with an absent target, ``0,0,0,0``, left out)."""
    keep = np.any(truth != 0, axis=1)
    b, t = boxes[keep], truth[keep]
    return np.abs(np.log(b[:, 2] * b[:, 3] / (t[:, 2] * t[:, 3])))


def generated(challenges: tuple[str, ...], target_size: tuple[float, float], modality: str = "rgb",
              duration: float = 6):
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    cfg = SceneConfig(challenges=frozenset(challenges), seed=1, target_size=target_size, duration=duration)
    renderer = SceneRenderer(cfg)
    n, fps = (cfg.rgb_frame_count, cfg.rgb_fps) if modality == "rgb" else (cfg.t_frame_count, cfg.t_fps)
    rendered = [renderer.render(i / fps, modality, i) for i in range(n)]
    return [f.image for f in rendered], np.array([f.box for f in rendered])


def test_small_noisy_generated_target_keeps_its_size():
    # a 12x14 px target under sensor noise and JPEG artefacts: the unpenalised search shrank the box to 65 % of the
    # target's area (median |log| error 0.44); with the hysteresis it stays within a few per cent
    frames, truth = generated(("degradation",), (0.05, 0.06))
    boxes = track_frames(frames, truth[0], preset("hc")).boxes
    assert np.median(size_error(boxes[1:], truth[1:])) < 0.1
    assert np.median(centre_error(boxes[1:], truth[1:])) < 3
    drifting = track_frames(frames, truth[0], preset("hc").with_(scale_penalty=1.0)).boxes
    assert np.median(size_error(drifting[1:], truth[1:])) > 0.2  # the failure this guards against


def test_a_real_scale_change_is_still_followed():
    # the target approaches and recedes (about 2x): a fixed-size box would be ~0.3 off in log area on average
    frames, truth = generated(("scale_change",), (0.09, 0.25))
    boxes = track_frames(frames, truth[0], preset("hc")).boxes
    fixed = track_frames(frames, truth[0], preset("hc").with_(n_scales=1)).boxes
    assert np.median(size_error(boxes[1:], truth[1:])) < 0.12
    assert np.median(size_error(boxes[1:], truth[1:])) < 0.5 * np.median(size_error(fixed[1:], truth[1:]))


def test_a_tilt_towards_one_side_is_not_a_size_change():
    from rgbt_toolkit.eco.tracker import _scale_choice

    # peaks rising towards the smaller scales (2.4 % for the first step, less for the next two), highest at the edge
    # of the search, as on svan_v_drone_003: the penalised maximum is one step off the centre; such steps were the
    # drift on real footage
    tilt = np.array([1.05, 1.037, 1.024, 1.0, 0.98, 0.975, 0.975])
    assert _scale_choice(tilt, 0.98, step_to_peak=False) == 2
    assert _scale_choice(tilt, 0.98, step_to_peak=True) == 3
    # a target 2 % larger: its peak is one step out and the step goes there
    peaked = np.array([0.9, 0.95, 0.98, 1.0, 1.03, 1.01, 0.97])
    assert _scale_choice(peaked, 0.98, step_to_peak=True) == 4
    # a fast change beyond the search: the highest peak at the edge wins by more than the penalty of three steps
    edge = np.array([0.93, 0.95, 0.97, 1.0, 1.03, 1.06, 1.09])
    assert _scale_choice(edge, 0.98, step_to_peak=True) == 6
    # too little evidence for any step
    assert _scale_choice(np.array([0.99, 1.0, 1.0, 1.0, 1.01, 1.015, 1.02]), 0.98, step_to_peak=True) == 3


def test_small_far_target_on_a_real_sensor_keeps_its_size():
    # the generator's lessons from real footage (a 12x14 px target, fixed-pattern stripes, dead pixels, codec
    # blocking, a burned-in timestamp): stepping to the penalised maximum moved the box size by 10 % in log area, the
    # drift seen on the real visible drones; stepping only to the peak keeps the first size
    frames, truth = generated(("far_target", "real_sensor"), (0.05, 0.06), duration=10)
    kept = np.median(size_error(track_frames(frames, truth[0], preset("hc")).boxes[1:], truth[1:]))
    drifting = track_frames(frames, truth[0], preset("hc").with_(scale_step_to_peak=False)).boxes
    drift = np.median(size_error(drifting[1:], truth[1:]))
    # one scale step is 0.02 in log area; where the run ends depends on float rounding (BLAS threads): 0-2 steps
    # kept, 5 steps drifted
    assert kept < 0.05 and drift > 0.07 and drift > 2 * kept, (kept, drift)


@pytest.mark.parametrize("field, value", [("scale_penalty", 0.0), ("scale_penalty", 1.5)])
def test_bad_scale_settings_are_clear_errors(field, value):
    with pytest.raises(InputError, match=field):
        preset("hc").with_(**{field: value})


@pytest.mark.parametrize("name, frames", [("svan_v_helicopter_002", 150), ("antiuav_ir_07", 200)])
def test_real_sequence_box_size_does_not_drift(shared_dir, name, frames):
    """Real clips where the old search drifted (visible helicopter shrinking, Anti-UAV drone growing)."""
    images, truth = real_clip(shared_dir, name, frames)
    boxes = track_frames(images, truth[0], preset("hc")).boxes
    err = size_error(boxes[1:], truth[1:])
    assert np.median(err) < 0.2, np.median(err)
    assert np.median(centre_error(boxes[1:], truth[1:])) < 6


def _aligned_scale_change(seed: int = 0):
    """The generated scale_change scene of ``benchmarks/bench_jmmac.py`` (320x240, 4 s): grows 1.6x, then recedes."""
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    cfg = SceneConfig.aligned(rgb_size=(320, 240), challenges=frozenset({"scale_change"}), seed=seed, duration=4.0)
    renderer = SceneRenderer(cfg)
    rendered = [renderer.render(i / cfg.rgb_fps, "rgb", i) for i in range(cfg.rgb_frame_count)]
    return [f.image for f in rendered], np.array([f.box for f in rendered])


def test_first_frame_scale_bias_lets_the_hysteresis_follow_a_fast_scale_change():
    # with the 2 %-per-step hysteresis alone the search mistook the filter's own preference for a zoomed sample for a
    # size change and lagged behind the real one (median |log area| error 0.15-0.27: that run drifts, and where it
    # ends depends on float rounding, e.g. the BLAS thread count); dividing by the first frame's per-scale peaks
    # (where the true scale is 1) leaves the evidence of a change: 0.06
    frames, truth = _aligned_scale_change()
    calibrated = track_frames(frames, truth[0], preset("hc")).boxes
    uncalibrated = track_frames(frames, truth[0], preset("hc").with_(scale_bias_calibration=False)).boxes
    calibrated_error = np.median(size_error(calibrated[1:], truth[1:]))
    assert calibrated_error < 0.1
    assert np.median(size_error(uncalibrated[1:], truth[1:])) > 2 * calibrated_error


def test_scale_bias_is_measured_on_the_first_frame():
    from rgbt_toolkit.eco.tracker import EcoTracker

    frames, truth = _aligned_scale_change()
    tracker = EcoTracker(preset("hc"))
    tracker.initialize(frames[0], truth[0])
    bias = tracker.scale_bias
    assert bias.shape == (preset("hc").n_scales,) and bias[len(bias) // 2] == 1.0
    assert np.ptp(bias) > 1e-3  # the peaks on the training frame itself do differ between scales
    # on that frame every scale's evidence is then equal, so the hysteresis keeps the trained size
    assert tracker.predict(frames[0]).scale_index == len(bias) // 2
    off = EcoTracker(preset("hc").with_(scale_bias_calibration=False))
    off.initialize(frames[0], truth[0])
    assert np.all(off.scale_bias == 1.0)


def test_real_visible_drone_box_keeps_the_labels_size(shared_dir):
    """svan_v_drone_003 (313 frames, a visible drone whose labels keep their size within 7 %; its image shrinks over
    the first 100 frames, then holds): stepping to the penalised maximum, the hc box kept shrinking step by step, to
    73 % of the labels' area by the end (benchmarks/bench_real.py: median size error 0.233, success 80.7); stepping
    only to the peak it keeps its size (0.024, success 93.1)."""
    images, truth = real_clip(shared_dir, "svan_v_drone_003")
    present = np.any(truth[1:] != 0, axis=1)
    boxes = track_frames(images, truth[0], preset("hc")).boxes
    assert np.median(size_error(boxes[1:][present], truth[1:][present])) < 0.08
    final = np.sqrt(boxes[-1, 2] * boxes[-1, 3] / (truth[-1, 2] * truth[-1, 3]))
    assert 0.9 < final < 1.1, final
    drifting = track_frames(images, truth[0], preset("hc").with_(scale_step_to_peak=False)).boxes
    assert np.median(size_error(drifting[1:][present], truth[1:][present])) > 0.15


def test_real_drone_keeps_its_size_over_the_whole_clip(shared_dir):
    """antiuav_ir_07 (751 frames, a 17x10 px thermal drone whose labels keep their size): on the JMMAC code's
    200^2..250^2 sample patch the hc box shrank to 14x8 px by the end (median size error 0.253 over the clip); on
    ECO-HC's 150^2..200^2 patch, the hc preset's (docs/decisions.md, D6), it keeps its size (0.040)."""
    images, truth = real_clip(shared_dir, "antiuav_ir_07")
    boxes = track_frames(images, truth[0], preset("hc")).boxes
    present = np.any(truth[1:] != 0, axis=1)
    err = size_error(boxes[1:][present], truth[1:][present])
    assert np.median(err) < 0.1, np.median(err)
    assert np.median(centre_error(boxes[1:][present], truth[1:][present])) < 3
    final = np.sqrt(boxes[-1, 2] * boxes[-1, 3]) / np.sqrt(truth[0, 2] * truth[0, 3])
    assert 0.85 < final < 1.15, final
