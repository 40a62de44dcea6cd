"""Algorithm 1 and the model-updating rules, driven by scripted per-frame inputs covering every branch."""

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.switcher import (
    APPEARANCE,
    MOTION,
    PAPER_THRESHOLDS,
    Algorithm1Switch,
    SwitchThresholds,
    TrackerSwitcher,
    candidate_offset,
    use_appearance,
)


def test_paper_values():
    t = PAPER_THRESHOLDS
    assert (t.q_hi, t.s_hi, t.q_low, t.s_low, t.t_diff, t.q_skip) == (210, 15, 135, 17, 3, 250)
    with pytest.raises(AttributeError):
        t.q_hi = 1.0  # frozen


@pytest.mark.parametrize(
    "q, s_a, s_m, expected",
    [
        (220, 16, 30, (True, "high")),  # q > q_hi and s_A > s_hi, whatever s_M
        (210, 18, 0, (True, "low_diff")),  # q = q_hi is not > q_hi; the second clause holds
        (150, 20, 16.9, (True, "low_diff")),  # q > q_low, s_A > s_low, s_A - s_M = 3.1 > 3
        (150, 20, 17, (False, "motion")),  # difference exactly 3 is not > 3
        (150, 17, 0, (False, "motion")),  # s_A = s_low is not > s_low
        (135, 40, 0, (False, "motion")),  # q = q_low is not > q_low
        (100, 0.0, 0.0, (False, "motion")),  # t_disable = 0 by default: the clause never fires
        (220, 15, 5, (False, "motion")),  # s_A = s_hi fails clause 1, s_A < s_low fails clause 2
    ],
)
def test_algorithm1_branches(q, s_a, s_m, expected):
    assert use_appearance(q, s_a, s_m) == expected
    assert Algorithm1Switch()(q, s_a, s_m) is expected[0]


def test_disable_clause_when_given_a_level():
    th = SwitchThresholds(t_disable=1.0)
    assert use_appearance(100, 0.5, 0.9, th) == (True, "disabled")  # both similarities blind: keep appearance
    assert use_appearance(100, 0.5, 1.0, th) == (False, "motion")  # max = t_disable is not < t_disable


def test_scripted_occlusion_sequence():
    """Frame by frame: start, confident tracking, occlusion (motion mode), recovery, camera motion."""
    sw = TrackerSwitcher()
    script = [
        # (q, s_A, s_M, camera_motion, kalman_ready) -> (mode, update ECO, correct Kalman, reason, matched)
        ((300, None, None, False, False), (APPEARANCE, True, False, "no_kalman", False)),
        ((290, None, None, False, True), (APPEARANCE, True, True, "q_skip", False)),
        ((230, 25, 24, False, True), (APPEARANCE, True, True, "high", True)),
        ((180, 12, 14, False, True), (MOTION, False, False, "motion", True)),  # occluder: low q, low s_A
        ((120, 8, 10, False, True), (MOTION, False, False, "motion", True)),
        ((160, 22, 12, False, True), (APPEARANCE, True, True, "low_diff", True)),  # target re-appears
        ((90, 5, 6, True, True), (APPEARANCE, True, True, "camera_motion", False)),  # TMP suspended
    ]
    for (q, s_a, s_m, cm, ready), expected in script:
        needed = sw.needs_template_matching(q, camera_motion=cm, kalman_ready=ready)
        assert needed == expected[4]
        d = sw.decide(q, s_a if needed else None, s_m if needed else None, camera_motion=cm, kalman_ready=ready)
        assert (d.mode, d.update_appearance, d.correct_kalman, d.reason, d.template_matching) == expected
    assert sw.mode == APPEARANCE and sw.run_length == 2


def test_run_length_counts_motion_frames():
    sw = TrackerSwitcher()
    for _ in range(3):
        sw.decide(100, 5, 9)
    assert sw.mode == MOTION and sw.run_length == 3
    sw.reset()
    assert sw.mode == APPEARANCE and sw.run_length == 0


def test_custom_thresholds_and_errors():
    sw = TrackerSwitcher(SwitchThresholds(q_skip=1000.0))
    assert sw.needs_template_matching(400.0)
    with pytest.raises(InputError, match="s_A and s_M are needed"):
        sw.decide(400.0)
    with pytest.raises(InputError, match="finite"):
        sw.decide(float("nan"))


@pytest.mark.parametrize(
    "q, offset, expected",
    [
        (150, 0.0, (True, "agree")),  # boxes on one another: s_A = s_M, which Algorithm 1 alone sends to motion
        (150, 0.5, (True, "agree")),  # half a target size apart still agrees
        (150, 0.51, (False, "motion")),  # further apart: Algorithm 1 decides
        (90, 0.0, (False, "motion")),  # q at the collapse level (a hidden target): Algorithm 1 decides
        (91, 0.2, (True, "agree")),
        (150, None, (False, "motion")),  # no offset given: the paper's Algorithm 1
    ],
)
def test_agreeing_candidates_keep_appearance(q, offset, expected):
    assert use_appearance(q, 12.0, 12.0, PAPER_THRESHOLDS, offset) == expected
    assert Algorithm1Switch()(q, 12.0, 12.0, offset) is expected[0]
    decision = TrackerSwitcher().decide(q, 12.0, 12.0, offset=offset)
    assert decision.reason == expected[1] and decision.update_appearance is expected[0]


def test_agreement_off_is_the_papers_algorithm():
    paper = SwitchThresholds(agree_offset=0.0, agree_sigmas=0.0)
    assert use_appearance(150, 12.0, 12.0, paper, 0.1, 0.1) == (False, "motion")
    assert use_appearance(150, 12.0, 12.0, paper, 0.0, 0.0) == (False, "motion")


@pytest.mark.parametrize(
    "q, offset, spread_offset, expected",
    [
        (150, 0.9, 0.8, (True, "agree")),  # a tiny target: a size away, but within the prediction's spread
        (150, 0.9, 1.2, (False, "motion")),  # beyond both
        (150, None, 1.0, (True, "agree")),  # at the spread's limit
        (85, 0.9, 0.1, (False, "motion")),  # q collapsed: Algorithm 1 decides
        (150, 0.9, None, (False, "motion")),  # no spread given: the size rule alone
    ],
)
def test_candidates_within_the_motion_models_spread_agree(q, offset, spread_offset, expected):
    assert use_appearance(q, 12.0, 12.0, PAPER_THRESHOLDS, offset, spread_offset) == expected
    assert Algorithm1Switch()(q, 12.0, 12.0, offset, spread_offset) is expected[0]
    decision = TrackerSwitcher().decide(q, 12.0, 12.0, offset=offset, spread_offset=spread_offset)
    assert decision.reason == expected[1]
    size_only = SwitchThresholds(agree_sigmas=0.0)
    assert use_appearance(q, 12.0, 12.0, size_only, offset, spread_offset)[1] != "agree"


def test_candidate_offset_in_target_sizes():
    assert candidate_offset([10, 20, 8, 2], [10, 20, 8, 2]) == 0.0
    assert candidate_offset([10, 20, 8, 2], [14, 23, 8, 2]) == pytest.approx(5 / 4)  # 5 px over sqrt(16) px
    assert candidate_offset([0, 0, 4, 4], [0, 2, 6, 4]) == pytest.approx(np.hypot(1, 2) / 4)  # centres, not corners
