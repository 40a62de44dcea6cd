"""What a lost frame costs (issue #41): the whole-frame search on a shrunk frame, and verifications reused while the
target stays lost and the place they looked at is unchanged."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rgbt_toolkit.eco import reacquire
from rgbt_toolkit.eco.reacquire import ReacquireParams, Reacquirer, shrink_factor, to_full
from rgbt_toolkit.io.images import block_mean
from rgbt_toolkit.errors import InputError


def textured(h: int, w: int, seed: int = 0) -> np.ndarray:
    """A smooth grey background with some structure (no candidate stands out by chance)."""
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.integers(0, 255, (h, w), dtype=np.uint8), (0, 0), 3)


def lost(frame: np.ndarray, params: ReacquireParams | None = None) -> Reacquirer:
    """A watchdog started on ``frame`` (a 14x12 px target) whose usual peak is 1.0 and which has just lost it."""
    watchdog = Reacquirer(params)
    watchdog.start(frame, np.array([20.0, 30.0, 14.0, 12.0]))
    for _ in range(10):
        watchdog.observe(1.0)
    while not watchdog.observe(0.1):
        pass
    return watchdog


class Scripted:
    """A ``verify`` answering at the candidate itself with a peak per candidate x, counting its calls."""

    def __init__(self, peaks: dict[float, float]) -> None:
        self.peaks, self.calls = peaks, []

    def __call__(self, centre):
        self.calls.append(float(centre[0]))
        return self.peaks[float(centre[0])], np.asarray(centre, float), float(centre[0])


def search_after_a_cut(watchdog: Reacquirer, monkeypatch, shape, size_hw, before_yx, after_yx):
    """Start ``watchdog`` on a textured frame of ``shape`` with a ``size_hw`` target at ``before_yx`` (top left), then
    look for it on a frame where it sits at ``after_yx``: ``(pixels of each frame matched, candidates, frame)``."""
    background = textured(*shape)
    target = textured(*size_hw, seed=1)
    (h, w), (y0, x0), (y1, x1) = size_hw, before_yx, after_yx
    first, later = background.copy(), background.copy()
    first[y0:y0 + h, x0:x0 + w] = target
    later[y1:y1 + h, x1:x1 + w] = target  # the target elsewhere after a cut
    watchdog.start(first, np.array([x0, y0, w, h], dtype=float))
    searched = []
    match = cv2.matchTemplate
    monkeypatch.setattr(reacquire.cv2, "matchTemplate", lambda image, *a: searched.append(image.size) or match(
        image, *a))
    return searched, watchdog.candidates(np.dstack([later] * 3)), later


def test_block_mean_is_the_mean_of_whole_blocks_and_to_full_their_centres():
    image = np.arange(7 * 9, dtype=np.float32).reshape(7, 9)
    small = block_mean(image, 3)
    assert small.shape == (2, 3)  # the last row and column that do not fill a block are dropped
    np.testing.assert_allclose(small, image[:6, :9].reshape(2, 3, 3, 3).mean(axis=(1, 3)), rtol=1e-6)
    np.testing.assert_allclose(to_full([0, 1], 3), [1.0, 4.0])  # block (row 1, col 0) covers pixels 3..5 x 0..2
    assert block_mean(image, 1) is image
    assert shrink_factor((40, 100), 16) == 2 and shrink_factor((15, 100), 16) == 1


def test_the_whole_frame_search_runs_on_a_shrunk_frame_and_still_lands_on_the_target(monkeypatch):
    """A 48x64 px template on a 480x640 frame is matched at a third of the size (a ninth of the pixels; the full
    frame before), and the best match still lands within a block of the target's centre."""
    searched, candidates, later = search_after_a_cut(Reacquirer(), monkeypatch, (480, 640), (48, 64), (100, 80),
                                                     (300, 450))
    assert searched and max(searched) <= later.size / 9
    assert np.hypot(*(candidates[0] - [450 + 31.5, 300 + 23.5])) <= 3


def test_an_unchanged_place_is_verified_once_and_a_changed_one_again():
    frame = textured(120, 160)
    watchdog = lost(frame, ReacquireParams(reuse_frames=4))
    cands = [np.array([40.0, 40.0]), np.array([120.0, 80.0])]
    verify = Scripted({40.0: 0.2, 120.0: 0.25})
    for _ in range(3):
        watchdog.candidates(frame)
        assert watchdog.search(cands, verify, 14.0) is None
    assert verify.calls == [40.0, 120.0]  # the two places once, then their answers reused
    changed = frame.copy()
    changed[74:86, 113:127] = 255  # something appears at the second place
    watchdog.candidates(changed)
    watchdog.search(cands, verify, 14.0)
    assert verify.calls[2:] == [120.0]
    for _ in range(4):  # no answer is older than reuse_frames searches
        watchdog.candidates(changed)
        watchdog.search(cands, verify, 14.0)
    assert verify.calls.count(40.0) == 2


def test_an_answer_that_could_be_taken_and_a_moving_candidate_are_verified_every_time():
    """0.55 of the usual peak may be taken once its rivals fall away, and a candidate one pixel from where it was
    (a target drifting slowly against the sky, svan_ir_bird_003) may be the target with a rising answer."""
    frame = textured(120, 160)
    watchdog = lost(frame)
    promising, hopeless = np.array([40.0, 40.0]), np.array([120.0, 80.0])
    verify = Scripted({40.0: 0.55, 120.0: 0.3, 121.0: 0.3})
    for _ in range(3):
        watchdog.candidates(frame)
        assert watchdog.search([promising, hopeless], verify, 14.0) is None
    assert verify.calls == [40.0, 120.0, 40.0, 40.0]
    watchdog.candidates(frame)
    watchdog.search([hopeless + [1.0, 0.0]], verify, 14.0)
    assert verify.calls[-1] == 121.0


def test_a_fresh_answer_is_taken_and_the_remembered_ones_are_forgotten():
    frame = textured(120, 160)
    watchdog = lost(frame)
    a = np.array([40.0, 40.0])
    verify = Scripted({40.0: 0.2})
    watchdog.candidates(frame)
    watchdog.search([a], verify, 14.0)
    verify.peaks[40.0] = 0.9
    changed = frame.copy()
    changed[34:46, 33:47] = 0
    watchdog.candidates(changed)
    assert watchdog.search([a], verify, 14.0) == 40.0 and not watchdog.lost
    assert watchdog.verified == 2 and not watchdog._memo


def test_reuse_settings_are_checked():
    with pytest.raises(InputError, match="match_side"):
        ReacquireParams(match_side=2)
    with pytest.raises(InputError, match="reuse_frames"):
        ReacquireParams(reuse_change=-1)


def test_rgbt_tracks_watchdog_matches_a_24_px_template_at_half_size_and_lands_on_it(monkeypatch):
    """`rgbt track`'s watchdog (JmmacConfig.reacquire_match_side 12) matches a 28x24 px template, the size of
    svan_v_bird_013's bird, on a frame shrunk by 2 (a quarter of the pixels; ECO alone, match_side 16, matches it at
    full size), and the best match still lands within a block of the target's centre."""
    from rgbt_toolkit.jmmac.api import build_tracker
    from rgbt_toolkit.jmmac.config import preset

    watchdog = build_tracker(preset("default", fusion="average")).watchdog
    assert watchdog.params.match_side == 12 and ReacquireParams().match_side == 16
    searched, candidates, later = search_after_a_cut(watchdog, monkeypatch, (512, 640), (24, 28), (300, 80),
                                                     (100, 500))
    assert searched and max(searched) <= later.size / 4
    assert np.hypot(*(candidates[0] - [500 + 13.5, 100 + 11.5])) <= 2
