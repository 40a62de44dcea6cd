"""Anti-UAV state accuracy on 4-frame sequences worked out by hand, the folder layout, and the refused inputs.

The rules checked are those of the official code (ZhaoJ9014/Anti-UAV ``Eval/test.py`` and
``anti_uav_jittor/anti_uav410_jit/Evaluation_for_SA.py``, Anti-UAV/baseline ``test.py``, the 3rd challenge's
scoring program): SA = mean over frames of IoU (target there) or [reported absent] (target absent); SA-P = SA -
0.2 * (missed / present frames) ** 0.3, a present target being missed unless a box overlaps it with IoU > 1e-5.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.evaluation.anti_uav import frame_states, state_accuracy
from rgbt_toolkit.evaluation.api import evaluate
from rgbt_toolkit.evaluation.benchmarks import ANTI_UAV, get_benchmark
from rgbt_toolkit.io.anti_uav import TargetFrames

BOX = [0, 0, 10, 10]
HALF = [0, 0, 10, 5]  # IoU 0.5 with BOX
THIRD = [5, 0, 10, 10]  # IoU 50 / 150 with BOX
AWAY = [20, 20, 5, 5]  # no overlap


def _frames(entries) -> TargetFrames:
    """Result entries as the files hold them: [x, y, w, h] or [] (absent)."""
    present = np.array([len(e) == 4 for e in entries])
    boxes = np.array([e if len(e) == 4 else [np.nan] * 4 for e in entries], dtype=float).reshape(-1, 4)
    return TargetFrames(present, boxes)


def _label(exist, rects) -> TargetFrames:
    boxes = np.array([r if len(r) == 4 and any(r) else [np.nan] * 4 for r in rects], dtype=float).reshape(-1, 4)
    return TargetFrames(np.array(exist, dtype=bool), boxes)


def _write_label(folder, exist, rects, modality="IR"):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{modality}_label.json").write_text(json.dumps({"exist": exist, "gt_rect": rects}))


# --------------------------------------------------------------------------------------------- hand-computed scores
def test_absent_frames_score_one_only_when_reported_absent():
    truth = _label([1, 1, 0, 0], [BOX, BOX, [], [0, 0, 0, 0]])
    score = state_accuracy(_frames([BOX, THIRD, [], [1, 1, 2, 2]]), truth)
    # frame scores 1, 1/3, 1 (absent, reported absent), 0 (absent, a box reported)
    assert score.sa == pytest.approx((1 + 1 / 3 + 1 + 0) / 4)
    assert score.miss_rate == 0.0 and score.sa_p == pytest.approx(score.sa)  # both present frames are overlapped


def test_penalty_counts_absent_marks_and_boxes_that_miss_the_target():
    truth = _label([1, 1, 1, 0], [BOX, BOX, BOX, []])
    score = state_accuracy(_frames([[], AWAY, HALF, []]), truth)
    assert score.sa == pytest.approx((0 + 0 + 0.5 + 1) / 4)
    # missed: frame 1 reported absent, frame 2 boxed elsewhere (IoU 0 <= 1e-5); frame 3 overlaps
    assert score.miss_rate == pytest.approx(2 / 3)
    assert score.sa_p == pytest.approx(0.375 - 0.2 * (2 / 3) ** 0.3)


def test_all_present_targets_missed_costs_the_full_penalty():
    truth = _label([0, 1, 1, 0], [[], BOX, BOX, []])
    score = state_accuracy(_frames([[], [], AWAY, []]), truth)
    assert score.sa == pytest.approx(0.5)
    assert score.sa_p == pytest.approx(0.5 - 0.2)  # (2 / 2) ** 0.3 = 1


def test_no_present_frame_means_no_penalty():
    truth = _label([0, 0, 0, 0], [[]] * 4)
    score = state_accuracy(_frames([[], [], BOX, []]), truth)
    assert score.sa == pytest.approx(0.75) and score.sa_p == pytest.approx(0.75)


def test_zero_size_box_is_a_box_not_an_absent_mark():
    truth = _label([0, 0, 1, 1], [[], [], BOX, BOX])
    states = frame_states(_frames([[0, 0, 0, 0], [], [0, 0, 0, 0], BOX]), truth)
    np.testing.assert_allclose(states.accuracy, [0, 1, 0, 1])
    assert states.missed.tolist() == [False, False, True, False]


def test_present_frames_without_a_box_are_left_out():
    truth = _label([1, 1, 0, 1], [BOX, [], [], [0, 0, 0, 0]])  # frames 2 and 4: exist = 1 but no box
    score = state_accuracy(_frames([BOX, [], [], []]), truth)
    assert score.n_frames == 2
    assert score.sa == pytest.approx(1.0) and score.sa_p == pytest.approx(1.0)


def test_first_frame_counts_like_any_other():
    truth = _label([1, 1, 1, 1], [BOX] * 4)
    score = state_accuracy(_frames([AWAY, BOX, BOX, BOX]), truth)
    assert score.sa == pytest.approx(0.75)
    assert score.sa_p == pytest.approx(0.75 - 0.2 * 0.25 ** 0.3)


def test_lengths_must_agree_in_memory():
    with pytest.raises(InputError, match="result has 3 frames, label 4"):
        state_accuracy(_frames([BOX] * 3), _label([1] * 4, [BOX] * 4))


def test_benchmark_table_entry():
    assert get_benchmark("Anti_UAV") is ANTI_UAV and get_benchmark("antiuav") is ANTI_UAV
    assert ANTI_UAV.metric_names == ("SA", "SA-P")
    assert (ANTI_UAV.miss_iou, ANTI_UAV.penalty_weight, ANTI_UAV.penalty_power) == (1e-5, 0.2, 0.3)


# ------------------------------------------------------------------------------------------------------- folders
@pytest.fixture()
def folders(tmp_path):
    """Two IR sequences (a: 4 frames, b: 2 frames) and results in each accepted file form."""
    gt = tmp_path / "gt"
    _write_label(gt / "a", [1, 1, 1, 0], [BOX, BOX, BOX, []])
    _write_label(gt / "b", [1, 0], [BOX, [0, 0, 0, 0]])
    return tmp_path, gt


SEQ_A = (0.375, 0.375 - 0.2 * (2 / 3) ** 0.3)  # test_penalty_counts_absent_marks_and_boxes_that_miss_the_target
SEQ_B = (1.0, 1.0)


def _expected(*seqs):
    return [100 * float(np.mean([s[i] for s in seqs])) for i in (0, 1)]


@pytest.mark.parametrize("form", ["json", "json_in_txt", "text_rows", "bare_names"])
def test_every_result_form_scores_the_same(folders, form):
    root, gt = folders
    out = root / "T"
    out.mkdir()
    a, b = [[], AWAY, HALF, []], [BOX, []]
    if form == "json":
        (out / "a_IR.json").write_text(json.dumps({"res": a}))
        (out / "b_IR.json").write_text(json.dumps({"res": b}))
    elif form == "json_in_txt":  # as the official baselines write them
        (out / "a_IR.txt").write_text(json.dumps({"res": a}))
        (out / "b_IR.txt").write_text(json.dumps({"res": b}))
    elif form == "text_rows":  # an empty line or [] is a frame with the target reported absent
        (out / "a_IR.txt").write_text("\n20,20,5,5\n0 0 10 5\n[]\n")
        (out / "b_IR.txt").write_text("[0, 0, 10, 10]\n\n")
    else:
        (out / "a.txt").write_text("\n20,20,5,5\n0,0,10,5\n\n")
        (out / "b.json").write_text(json.dumps({"res": b}))
    report = evaluate("anti-uav", gt, [out])
    scores = report.trackers["T"]
    assert [scores.summary["SA"], scores.summary["SA-P"]] == pytest.approx(_expected(SEQ_A, SEQ_B))
    assert scores.per_sequence()["a"] == pytest.approx({"SA": 100 * SEQ_A[0], "SA-P": 100 * SEQ_A[1]})
    assert report.all_warnings() == []


def test_sequences_are_averaged_not_pooled(folders):
    root, gt = folders
    out = root / "T"
    out.mkdir()
    (out / "a_IR.json").write_text(json.dumps({"res": [[], AWAY, HALF, []]}))
    (out / "b_IR.json").write_text(json.dumps({"res": [BOX, []]}))
    sa = evaluate("anti-uav", gt, [out]).trackers["T"].summary["SA"]
    assert sa == pytest.approx(100 * (0.375 + 1.0) / 2)
    assert sa != pytest.approx(100 * (1.5 + 2) / 6)  # pooled frames would give 58.33


def test_missing_sequence_scores_zero_with_full_penalty_and_a_warning(folders):
    root, gt = folders
    out = root / "T"
    out.mkdir()
    (out / "b_IR.json").write_text(json.dumps({"res": [BOX, []]}))
    report = evaluate("anti-uav", gt, [out])
    per = report.trackers["T"].per_sequence()
    assert per["a"] == pytest.approx({"SA": 0.0, "SA-P": -20.0})
    assert "T: a: no IR result for this sequence; scored 0 in every frame" in report.all_warnings()


def test_rgb_results_are_scored_against_rgb_labels(folders):
    root, gt = folders
    _write_label(gt / "a", [0, 0, 1, 1], [[], [], BOX, BOX], modality="RGB")
    out = root / "T"
    out.mkdir()
    (out / "a_IR.json").write_text(json.dumps({"res": [[], AWAY, HALF, []]}))
    (out / "b_IR.json").write_text(json.dumps({"res": [BOX, []]}))
    (out / "a_RGB.json").write_text(json.dumps({"res": [[], [], THIRD, []]}))
    scores = evaluate("anti-uav", gt, [out]).trackers["T"]
    rgb_sa = (1 + 1 + 1 / 3 + 0) / 4
    assert scores.summary["SA_RGB"] == pytest.approx(100 * rgb_sa)
    assert scores.summary["SA-P_RGB"] == pytest.approx(100 * (rgb_sa - 0.2 * 0.5 ** 0.3))
    assert scores.summary["SA"] == pytest.approx(_expected(SEQ_A, SEQ_B)[0])  # IR unchanged, ranked on it
    assert "SA_RGB" not in scores.per_sequence()["b"]  # b has no RGB label


def test_zero_size_result_boxes_are_warned_about(folders):
    root, gt = folders
    out = root / "T"
    out.mkdir()
    (out / "a_IR.json").write_text(json.dumps({"res": [BOX, BOX, BOX, [0, 0, 0, 0]]}))
    (out / "b_IR.json").write_text(json.dumps({"res": [BOX, []]}))
    report = evaluate("anti-uav", gt, [out])
    assert report.trackers["T"].per_sequence()["a"]["SA"] == pytest.approx(75.0)
    assert any("a: 1 IR box(es) of zero or negative size score as boxes" in w for w in report.all_warnings())


def test_boxless_present_label_frames_are_warned_about(tmp_path):
    _write_label(tmp_path / "gt" / "s", [1, 1, 0], [BOX, [], []])
    (tmp_path / "T").mkdir()
    (tmp_path / "T" / "s_IR.json").write_text(json.dumps({"res": [BOX, [], []]}))
    report = evaluate("anti-uav", tmp_path / "gt", [tmp_path / "T"])
    assert report.trackers["T"].summary["SA"] == pytest.approx(100.0)
    assert report.warnings == ["s: 1 frame(s) of IR_label.json have exist = 1 but no box; left out of the scores "
                               "(as the Anti-UAV410 toolkit does)"]


# ---------------------------------------------------------------------------------------------------- bad inputs
def test_result_length_mismatch_is_an_error_naming_both_files(folders):
    root, gt = folders
    out = root / "T"
    out.mkdir()
    (out / "a_IR.txt").write_text("0,0,10,10\n0,0,10,10\n0,0,10,10\n")  # 3 rows for 4 frames
    with pytest.raises(FileFormatError, match=r"a_IR.txt: 3 frames, but .*a[/\\]IR_label.json has 4"):
        evaluate("anti-uav", gt, [out])


def test_trailing_empty_lines_are_frames_so_they_count_in_the_length(folders):
    root, gt = folders
    out = root / "T"
    out.mkdir()
    (out / "b_IR.txt").write_text("0,0,10,10\n\n\n")  # 3 frames: the label has 2
    with pytest.raises(FileFormatError, match="b_IR.txt: 3 frames, but .* has 2"):
        evaluate("anti-uav", gt, [out])


@pytest.mark.parametrize("text, message", [
    ('{"res": [[1, 2, 3, 4], ', "malformed JSON"),
    ('{"boxes": []}', r'an Anti-UAV JSON result is \{"res"'),
    ('{"res": [[1, 2, 3]]}', r"frame 1: expected \[x, y, w, h\] or \[\]"),
    ('{"res": [[1, 2, 3, 4], "x"]}', r"frame 2: expected \[x, y, w, h\] or \[\]"),
    ("1,2,3,4\n1,2,x,4\n", "line 2: '1,2,x,4' is not x,y,w,h"),
])
def test_malformed_result_files_name_the_file(folders, text, message):
    root, gt = folders
    out = root / "T"
    out.mkdir()
    (out / "a_IR.txt").write_text(text)
    with pytest.raises(FileFormatError, match=message) as info:
        evaluate("anti-uav", gt, [out])
    assert str(out / "a_IR.txt") in str(info.value)


@pytest.mark.parametrize("text, message", [
    ('{"exist": [1, 0], "gt_rect": [[0, 0, 10, 10], []', "malformed JSON"),
    ('{"exist": [1, 0]}', r'an Anti-UAV label is \{"exist"'),
    ('{"exist": [1, 0, 1], "gt_rect": [[0, 0, 10, 10], []]}', "'exist' has 3 frames but 'gt_rect' has 2"),
    ('{"exist": [1, 2], "gt_rect": [[0, 0, 10, 10], []]}', "frame 2: 'exist' must be 0 or 1, got 2"),
    ('{"exist": [], "gt_rect": []}', "empty label"),
])
def test_malformed_labels_name_the_file(folders, text, message):
    root, gt = folders
    (gt / "b" / "IR_label.json").write_text(text)
    (root / "T").mkdir()
    with pytest.raises(FileFormatError, match=message) as info:
        evaluate("anti-uav", gt, [root / "T"])
    assert str(gt / "b" / "IR_label.json") in str(info.value)


def test_rgb_result_without_rgb_label_is_an_error(folders):
    root, gt = folders
    out = root / "T"
    out.mkdir()
    (out / "a_IR.json").write_text(json.dumps({"res": [BOX] * 4}))
    (out / "a_RGB.json").write_text(json.dumps({"res": [BOX] * 4}))
    with pytest.raises(MissingFileError, match=r"a[/\\]RGB_label.json: missing label file, needed to score .*a_RGB"):
        evaluate("anti-uav", gt, [out])


def test_sequence_with_only_an_rgb_label_is_an_error(folders):
    root, gt = folders
    (gt / "b" / "IR_label.json").rename(gt / "b" / "RGB_label.json")
    with pytest.raises(MissingFileError, match=r"b[/\\]IR_label.json: missing label file"):
        evaluate("anti-uav", gt, [root])


def test_two_result_files_for_one_sequence_are_refused(folders):
    root, gt = folders
    out = root / "T"
    out.mkdir()
    (out / "a_IR.txt").write_text(json.dumps({"res": [BOX] * 4}))
    (out / "a.txt").write_text(json.dumps({"res": [BOX] * 4}))
    with pytest.raises(InputError, match=r"several IR results for a \(a_IR.txt, a.txt\); keep one"):
        evaluate("anti-uav", gt, [out])


def test_wrong_folders_and_prefix(folders):
    root, gt = folders
    (root / "empty").mkdir()
    with pytest.raises(InputError, match=r"no result file for any of the 2 sequences \(expected <seq>_IR.json"):
        evaluate("anti-uav", gt, [root / "empty"])
    with pytest.raises(InputError, match="no Anti-UAV ground truth found"):
        evaluate("anti-uav", root / "empty", [root / "empty"])
    with pytest.raises(InputError, match="--prefix applies to one-pass benchmarks"):
        evaluate("anti-uav", gt, [root / "empty"], prefix="T_")
