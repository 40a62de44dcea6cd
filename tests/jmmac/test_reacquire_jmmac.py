"""Re-acquisition as a JMMAC module: the `default` preset finds a target again after a shot cut, `+TMP` (the same
without the module) does not, and lost frames are flagged `present: false`."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "eco"))
from test_reacquire import centre_error, cut_sequence  # noqa: E402

from rgbt_toolkit.jmmac.api import build_tracker  # noqa: E402
from rgbt_toolkit.jmmac.config import preset  # noqa: E402


def run(name: str, rgb: list, thermal: list, box) -> tuple[np.ndarray, list]:
    tracker = build_tracker(preset(name))
    results = [tracker.initialize(rgb[0], thermal[0], box)]
    results += [tracker.track(r, t) for r, t in zip(rgb[1:], thermal[1:])]
    return np.array([r.box for r in results]), results


@pytest.fixture(scope="module")
def cut_pair():
    rgb, truth = cut_sequence(n=36, cut=18)
    thermal, _ = cut_sequence(n=36, cut=18, grey=True)
    return rgb, thermal, truth


def test_default_finds_the_target_after_a_cut_and_tmp_alone_does_not(cut_pair):
    rgb, thermal, truth = cut_pair
    boxes, results = run("default", rgb, thermal, truth[0])
    err = centre_error(boxes, truth)
    assert np.all(err[:18] < 4)
    assert np.all(err[26:] < 4), err[18:]
    assert any(r.reacquired for r in results)
    without, _ = run("+TMP", rgb, thermal, truth[0])
    assert np.median(centre_error(without[26:], truth[26:])) > 50


def test_absent_target_is_flagged_and_nothing_learns():
    rgb, truth = cut_sequence(n=40, cut=40, absent=(18, 30))
    thermal, _ = cut_sequence(n=40, cut=40, absent=(18, 30), grey=True)
    boxes, results = run("default", rgb, thermal, truth[0])
    present = np.array([r.present for r in results])
    assert not present[22:30].any() and present[:18].all()
    assert present[34:].all() and np.all(centre_error(boxes[34:], truth[34:]) < 4)


def test_the_module_is_a_switch():
    assert preset("default").reacquire and preset("+RA").reacquire
    assert not preset("+TMP").reacquire and not preset("full").reacquire


def test_real_clip_cut_between_shots(shared_dir):
    """A real visible clip joined from two shots (svan_v_bird_001, cut at frame 54), given to JMMAC as both cameras
    (its grey copy as the thermal one; the real set has no RGB-T pairs): `default` is back on the bird after the
    cut, `+TMP` keeps tracking the empty sky where it was."""
    import cv2

    from tests.real_clips import real_clip

    rgb, truth = real_clip(shared_dir, "svan_v_bird_001", 114)
    thermal = [cv2.cvtColor(f, cv2.COLOR_RGB2GRAY) for f in rgb]
    boxes, results = run("default", rgb, thermal, truth[0])
    assert [r.index for r in results if r.reacquired][0] <= 60
    assert np.median(centre_error(boxes[84:], truth[84:])) < 5
    without, _ = run("+TMP", rgb, thermal, truth[0])
    assert np.median(centre_error(without[84:], truth[84:])) > 50


def test_a_lost_frame_verifies_at_most_the_budget(cut_pair):
    """Each verification is a full appearance step of both trackers: while lost, at most `reacquire_budget` per
    frame (all 8 candidates cost 190 ms/frame at 640x480), and the target is still found after the cut."""
    rgb, thermal, truth = cut_pair
    tracker = build_tracker(preset("default"))
    calls, original = [], tracker._verify
    tracker._verify = lambda *a: calls.append(tracker.index) or original(*a)
    tracker.initialize(rgb[0], thermal[0], truth[0])
    boxes = [tracker.track(r, t).box for r, t in zip(rgb[1:], thermal[1:])]
    per_frame = np.bincount(calls) if calls else np.zeros(1)
    assert calls and per_frame.max() <= tracker.config.reacquire_budget
    assert np.all(centre_error(np.array(boxes[25:]), truth[26:]) < 4)


@pytest.mark.parametrize("all_scales", [False, True])
def test_verification_looks_at_the_current_scale_unless_told(cut_pair, all_scales):
    """`verify_all_scales` False (the default) verifies each candidate at the current scale only (one feature scale
    instead of 7); both settings find the target after the cut."""
    rgb, thermal, truth = cut_pair
    # both trackers search scales on tracked frames (with "lead" the RGB tracker may not), so every search that is
    # not a verification looks at 7
    tracker = build_tracker(preset("default", verify_all_scales=all_scales, scale_search="both"))
    scales_seen = []
    eco = tracker.rgb_tracker.eco
    original = eco.predict

    def predict(frame, center=None, search_scales=True):
        pred = original(frame, center, search_scales)
        scales_seen.append((tracker.index, search_scales, len(eco._last_peaks)))
        return pred

    eco.predict = predict
    original_verify = tracker._verify
    verifying = []
    tracker._verify = lambda *a: verifying.append(len(scales_seen)) or original_verify(*a)
    tracker.initialize(rgb[0], thermal[0], truth[0])
    boxes = [tracker.track(r, t).box for r, t in zip(rgb[1:], thermal[1:])]
    assert verifying
    verified = [scales_seen[k] for k in verifying]  # the predict call each verification made
    assert all(n == (7 if all_scales else 1) for _, _, n in verified)
    assert all(n == 7 for k, (_, _, n) in enumerate(scales_seen) if k not in verifying)
    assert np.all(centre_error(np.array(boxes[25:]), truth[26:]) < 4)
