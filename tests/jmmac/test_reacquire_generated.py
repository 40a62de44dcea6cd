"""Re-acquisition as a JMMAC module on a generated aligned RGB-T scene where the target leaves the view and comes
back (``leave_view``): the ``default`` preset flags the out-of-view frames ``present: false`` and is back on the
target a few frames after it returns; ``+TMP`` (the same without the module) is not.

Both presets run with ``fusion="average"`` instead of MFNet: MFNet costs ~2 s a frame on CPU (two 60-frame runs would
take minutes), and the module under test sits after the fusion. Measured (seed 2, 4 s, 320x240, target 22x60 px):
default flags 20/20 out-of-view frames and is back (centre error < half the target's width, for good) 3 frames after
the target re-enters (frame 36); +TMP flags none and stays 40-100 px off (median ~99) until the target walks back
under its box on the last frame. Bound: measured + 5 frames.
gimbal_jump and long_occlusion are covered for single-camera ECO in tests/eco/test_reacquire_generated.py (JMMAC runs
of those were not measured within this test's time budget).
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.jmmac.api import build_tracker
from rgbt_toolkit.jmmac.config import preset
from rgbt_toolkit.evaluation.metrics import centre_error


def scene(challenge: str, seed: int, duration: float = 4.0, size: tuple[int, int] = (320, 240)):
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    cfg = SceneConfig.aligned(rgb_size=size, challenges=frozenset({challenge}), seed=seed, duration=duration)
    renderer = SceneRenderer(cfg)
    n, fps = cfg.rgb_frame_count, cfg.rgb_fps
    rgb = [renderer.render(i / fps, "rgb", i) for i in range(n)]
    thermal = [renderer.render(i / fps, "t", i).image for i in range(n)]  # aligned: same geometry as RGB
    return [f.image for f in rgb], thermal, np.array([f.box for f in rgb]), np.array([f.absent for f in rgb])


def run(name: str, rgb: list, thermal: list, box):
    tracker = build_tracker(preset(name, fusion="average"))
    results = [tracker.initialize(rgb[0], thermal[0], box)]
    results += [tracker.track(r, t) for r, t in zip(rgb[1:], thermal[1:])]
    return np.array([r.box for r in results]), results


def test_default_flags_the_target_out_of_view_and_finds_it_back_tmp_does_not():
    rgb, thermal, truth, absent = scene("leave_view", 2)
    out = np.nonzero(absent)[0]
    assert len(out) >= 15 and out[-1] < len(truth) - 15
    back_at = out[-1] + 1
    bound = 0.5 * float(np.median(truth[~absent][:, 2:].min(axis=1)))

    boxes, results = run("default", rgb, thermal, truth[0])
    present = np.array([r.present for r in results])
    err = centre_error(boxes, truth)
    assert np.mean(~present[absent]) >= 0.9, present[absent]  # measured 20/20
    assert present[:out[0]].all()
    assert np.all(err[:out[0] - 1] < bound)  # (the last frame before leaving is half out: clipped truth box)
    on = err[back_at:] < bound
    back = next((k for k in range(len(on)) if on[k:].all()), None)
    assert back is not None and back <= 8, err[back_at:]  # measured 3
    assert present[back_at + back:].all()
    assert any(r.reacquired for r in results)

    without, tmp_results = run("+TMP", rgb, thermal, truth[0])
    assert all(r.present for r in tmp_results)
    assert np.median(centre_error(without[back_at:], truth[back_at:])) > 2 * bound


def test_a_lost_frame_verifies_under_one_candidate_and_the_target_is_found_as_it_returns():
    """Issue #41: a lost frame used to cost three times the verification budget of full appearance steps; while the
    target stays lost nothing learns, so a candidate at an unchanged place keeps its answer. At 640x480 (target
    43x120 px: the whole-frame search also runs on frames shrunk by 2) seed 2 leaves the view on frames 16-35.
    Measured: 14 verifications over the 20 lost frames and the found one (0.67 per frame; 63, 3.15 per frame,
    before), found again on frame 36 as before (bench_lost.py times it); one of them on the frame the target is
    declared lost."""
    rgb, thermal, truth, absent = scene("leave_view", 2, size=(640, 480))
    back_at = np.nonzero(absent)[0][-1] + 1
    tracker = build_tracker(preset("default", fusion="average"))
    verified = []
    original = tracker._verify
    tracker._verify = lambda *a: verified.append(tracker.index) or original(*a)
    results = [tracker.initialize(rgb[0], thermal[0], truth[0])]
    results += [tracker.track(r, t) for r, t in zip(rgb[1:], thermal[1:])]
    searched = sum(not r.present or r.reacquired for r in results)
    assert searched >= 15
    assert len(verified) <= searched, (len(verified), searched)  # measured 14 of 21
    # the frame the target is declared lost ran a tracked frame's appearance step already: one candidate there
    # (reacquire_first_budget; measured 3 with the budget of the frames after it)
    declared = next(r.index for r in results if not r.present or r.reacquired)
    assert verified.count(declared) == 1, verified
    assert [r.index for r in results if r.reacquired][0] <= back_at + 3  # measured back_at (36)
    err = centre_error(np.array([r.box for r in results]), truth)
    assert np.all(err[back_at + 3:] < 0.5 * float(np.median(truth[~absent][:, 2:].min(axis=1))))
