"""Re-acquisition after loss (``eco.reacquire``) on generated scenes with the visibility challenges: the target
leaves the view and comes back (``leave_view``), the camera re-centres in one frame (``gimbal_jump``), a vehicle hides
the target for 1-2 s (``long_occlusion``). Single-camera ECO (``hc``) on the RGB frames, with and without the module.

Measured on seeds 0-4 at 4 s (60 frames, 320x240, target 22x60 px; "back" = frames after the event until the centre
error is below half the target's width and stays there):

=============== ====================================== ================================ ===========================
scenario        with re-acquisition                    without                          absent frames flagged
=============== ====================================== ================================ ===========================
leave_view      back after 0-3 frames (all seeds)      never back (stays off, ~100 px)  19-20 of 20 (0 of 20 without)
gimbal_jump     back after 2 frames on seeds 0,1,3,4;  never back (seed 0: back only    (no absent frames; present
                seed 2: NOT found, see below           when the 2nd jump returns it)    stays true)
long_occlusion  back after 2 frames (all seeds)        back after 1 frame on seeds      22-25 of 23-25, but seed 4:
                                                       0,1,4; seeds 2,3 stay 50-100 px  18 of 25 (0 without)
                                                       off
=============== ====================================== ================================ ===========================

Known failure (not tested here, reported): ``gimbal_jump`` seed 2 (jump of 95 px at frame 20) - with and without
the module the box stays 40-70 px beside the target for 19 frames, every frame ``present``: the peak never drops
below ``lost_ratio`` so the watchdog never fires; only the second jump (frame 39) puts the target back under the box.

(Measured with the JMMAC code's 200^2..250^2 sample patch; the ``hc`` preset samples ECO-HC's
150^2..200^2, on which the same bounds hold, and ECO alone may pass over the returning target once before it is
lost again.) Bounds below are the worst measured value + 5 frames; the seeds are ones where ECO alone does not recover, so each
test fails with the module off.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from rgbt_toolkit.eco.params import preset
from rgbt_toolkit.eco.reacquire import ReacquireParams
from rgbt_toolkit.eco.run import track_frames
from rgbt_toolkit.evaluation.metrics import centre_error


@lru_cache(maxsize=None)
def scene(challenge: str, seed: int, duration: float = 4.0):
    """RGB frames, truth boxes (0,0,0,0 out of view), ``absent`` and ``gimbal_jump`` flags of one generated scene."""
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    cfg = SceneConfig.aligned(rgb_size=(320, 240), challenges=frozenset({challenge}), seed=seed, duration=duration)
    renderer = SceneRenderer(cfg)
    rendered = [renderer.render(i / cfg.rgb_fps, "rgb", i) for i in range(cfg.rgb_frame_count)]
    return ([f.image for f in rendered], np.array([f.box for f in rendered]), np.array([f.absent for f in rendered]),
            np.array([f.flags.get("gimbal_jump", False) for f in rendered]))


def half_size(truth: np.ndarray, absent: np.ndarray) -> float:
    """Half the target's smaller side (11 px here): the 'on the target' bound for the centre error."""
    return 0.5 * float(np.median(truth[~absent][:, 2:].min(axis=1)))


def frames_until_back(err: np.ndarray, bound: float) -> int | None:
    """Frames from the start of ``err`` until it is below ``bound`` for good (None: never)."""
    on = err < bound
    return next((k for k in range(len(on)) if on[k:].all()), None)


def run(challenge: str, seed: int, reacquire: bool):
    frames, truth, absent, jumps = scene(challenge, seed)
    result = track_frames(frames, truth[0], preset("hc"), reacquire=ReacquireParams() if reacquire else None)
    return result, truth, absent, jumps


def test_leave_view_flags_the_target_absent_and_finds_it_when_back():
    # seed 2: out of view on frames 16-35, back from frame 36; measured: 20/20 absent frames flagged, back after 3
    # frames; ECO alone stays where the target left (~100 px off) for the rest of the clip
    watched, truth, absent, _ = run("leave_view", 2, reacquire=True)
    out = np.nonzero(absent)[0]
    assert len(out) >= 15 and out[-1] < len(truth) - 15  # the scene still leaves and comes back as measured
    back_at = out[-1] + 1
    present = np.asarray(watched.present)
    bound = half_size(truth, absent)
    assert np.mean(~present[absent]) >= 0.9, present[absent]  # measured 0.95-1.0 over seeds 0-4
    assert present[:out[0]].all()
    err = centre_error(watched.boxes, truth)
    assert np.all(err[:out[0]] < bound)
    back = frames_until_back(err[back_at:], bound)
    assert back is not None and back <= 8, err[back_at:]  # measured 0-3 over seeds 0-4
    assert present[back_at + back:].all()

    plain, _, _, _ = run("leave_view", 2, reacquire=False)
    assert np.asarray(plain.present).all()  # without the module nothing is ever flagged
    plain_err = centre_error(plain.boxes[back_at:], truth[back_at:])
    # never back on the target for good (ECO alone may pass over it once as it comes back into view)
    assert frames_until_back(plain_err, bound) is None and np.median(plain_err) > 2 * bound, plain_err


def test_gimbal_jump_target_found_again_after_the_jump():
    # seed 4: one jump of 116 px at frame 23; measured: back after 2 frames with the module, never without
    watched, truth, absent, jumps = run("gimbal_jump", 4, reacquire=True)
    (jump,) = np.nonzero(jumps)[0]
    bound = half_size(truth, absent)
    err = centre_error(watched.boxes, truth)
    assert np.all(err[:jump] < bound)
    back = frames_until_back(err[jump:], bound)
    assert back is not None and back <= 7, err[jump:]  # measured 2 on every jump of seeds 0, 1, 3, 4
    assert np.asarray(watched.present)[jump + back:].all()

    plain, _, _, _ = run("gimbal_jump", 4, reacquire=False)
    assert np.all(centre_error(plain.boxes[jump:], truth[jump:]) > 2 * bound)  # ECO alone stays on the background


def test_long_occlusion_is_flagged_and_the_target_found_after_it():
    # seed 3: fully hidden on frames 19-41; measured: 23/23 hidden frames flagged, back 2 frames after it emerges;
    # ECO alone follows the vehicle and stays ~55 px off (on seeds 0, 1, 4 ECO alone also recovers, so not those)
    watched, truth, absent, _ = run("long_occlusion", 3, reacquire=True)
    hidden = np.nonzero(absent)[0]
    assert len(hidden) >= 15
    emerged = hidden[-1] + 1
    present = np.asarray(watched.present)
    bound = half_size(truth, absent)
    assert np.mean(~present[absent]) >= 0.8, present[absent]  # measured 1.0 here (0.72-1.0 over seeds 0-4)
    assert present[:hidden[0] - 2].all()  # flags may go false a frame or two early, while mostly covered
    err = centre_error(watched.boxes, truth)
    back = frames_until_back(err[emerged:], bound)
    assert back is not None and back <= 7, err[emerged:]  # measured 2 on seeds 0-4
    assert present[emerged + back:].all()

    plain, _, _, _ = run("long_occlusion", 3, reacquire=False)
    assert np.median(centre_error(plain.boxes[emerged:], truth[emerged:])) > 2 * bound
