"""OPE scoring on tiny constructed benchmarks whose scores are worked out by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError, MissingFileError
from rgbt_toolkit.evaluation.api import evaluate
from rgbt_toolkit.evaluation.benchmarks import GTOT, LASHER, RGBT234, get_benchmark
from rgbt_toolkit.evaluation.groundtruth import GroundTruth, SequenceTruth, load_groundtruth
from rgbt_toolkit.evaluation.ope import score_boxes, score_run, score_sequence
from rgbt_toolkit.evaluation.results import match_sequence
from rgbt_toolkit.io.boxes import write_boxes

BOX = np.array([10.0, 10.0, 20.0, 20.0])


def _truth(bench, **seqs) -> GroundTruth:
    return GroundTruth(bench, {n: SequenceTruth(n, tuple(b)) for n, b in seqs.items()})


def make_rgbt234(root: Path, seqs: dict[str, tuple[np.ndarray, np.ndarray]], attrs: dict[str, list[int]] = None):
    """An RGBT234-layout ground-truth folder: rgbt234_gt/<seq>/{visible,infrared}.txt and attr_txt/."""
    for name, (vis, ir) in seqs.items():
        write_boxes(root / "rgbt234_gt" / name / "visible.txt", vis, precision=0)
        write_boxes(root / "rgbt234_gt" / name / "infrared.txt", ir, precision=0)
    (root / "attr_txt").mkdir(parents=True, exist_ok=True)
    (root / "attr_txt" / "SequencesName.txt").write_text("\n".join(seqs) + "\n")
    for attr, flags in (attrs or {}).items():
        (root / "attr_txt" / f"{attr}.txt").write_text("\n".join(map(str, flags)) + "\n")
    return root


def test_max_over_modalities_and_per_sequence_average():
    gt_v = np.tile(BOX, (4, 1))
    gt_i = gt_v + [30, 0, 0, 0]  # the infrared truth is 30 px to the right
    boxes = np.vstack([gt_v[:2], gt_i[2:3], gt_v[3:] + [100, 0, 0, 0]])  # hit V, hit V, hit I, miss both
    truth = _truth(RGBT234, a=(gt_v, gt_i), b=(gt_v, gt_i))
    scores = score_run({"a": boxes, "b": gt_v}, truth)
    assert scores.per_sequence()["a"]["MPR"] == pytest.approx(75.0)
    assert scores.per_sequence()["b"]["MPR"] == pytest.approx(100.0)
    assert scores.summary["MPR"] == pytest.approx(87.5)  # mean of the sequences, not pooled frames
    # success: sequence a has IoU 1 on three frames, 0 on one: 20 of 21 thresholds (t = 1 excluded) see 3/4
    assert scores.per_sequence()["a"]["MSR"] == pytest.approx(100 * 20 / 21 * 0.75)


def test_gtot_pools_frames_and_counts_strictly_below_5px():
    gt = np.tile(BOX, (3, 1))
    long_gt = np.tile(BOX, (1, 1))
    truth = _truth(GTOT, a=(gt, gt), b=(long_gt, long_gt))
    shifted = gt + [[0, 0, 0, 0], [5, 0, 0, 0], [4, 0, 0, 0]]  # errors 0, 5 (not < 5), 4
    scores = score_run({"a": shifted, "b": long_gt + [10, 0, 0, 0]}, truth)
    assert scores.summary["MPR"] == pytest.approx(100 * 2 / 4)  # pooled: 2 hits in 4 frames
    assert scores.per_sequence()["a"]["MPR"] == pytest.approx(100 * 2 / 3)


def test_gtot_success_is_the_trapezoid_area():
    gt = np.tile(BOX, (1, 1))
    truth = _truth(GTOT, a=(gt, gt))
    scores = score_run({"a": gt}, truth)
    # IoU 1 passes every t < 1: curve 1 up to t = 0.98, 0 at t = 1 -> area 1 - 0.02 / 2
    assert scores.summary["MSR"] == pytest.approx(99.0)


def test_short_long_nan_and_zero_size_results_warn_with_the_sequence_name():
    gt = np.tile(BOX, (4, 1))
    truth = _truth(RGBT234, short=(gt, gt), nan=(gt, gt), zero=(gt, gt), long=(gt, gt), empty=(gt, gt))
    boxes = {
        "short": gt[:3],
        "nan": np.vstack([gt[:3], [np.nan] * 4]),
        "zero": np.vstack([gt[:3], [10, 10, 0, 0]]),
        "long": np.vstack([gt, gt[:2] + 100]),
        "empty": np.zeros((0, 4)),
    }
    scores = score_run(boxes, truth)
    text = "\n".join(scores.warnings)
    assert "short: result has 3 frames, ground truth 4 (shorter)" in text
    assert "long: result has 6 frames, ground truth 4 (longer)" in text
    assert "nan: 1 result box(es) are NaN" in text
    assert "zero: 1 result box(es) have zero or negative size" in text
    assert "empty: empty result; scored as failed in every frame" in text
    per = scores.per_sequence()
    assert per["short"]["MPR"] == pytest.approx(100.0)  # scored on the common 3 frames
    assert per["long"]["MPR"] == pytest.approx(100.0)
    assert per["nan"]["MPR"] == pytest.approx(75.0)
    assert per["zero"]["MSR"] == pytest.approx(100 * 20 / 21 * 0.75)
    assert per["empty"]["MPR"] == 0.0 and scores.sequences["empty"].n_frames == 4


def test_missing_sequences_fail_or_skip():
    gt = np.tile(BOX, (2, 1))
    truth = _truth(RGBT234, a=(gt, gt), b=(gt, gt))
    skipped = score_run({"a": gt}, truth)
    assert list(skipped.sequences) == ["a"] and not skipped.warnings
    failed = score_run({"a": gt}, truth, missing="fail")
    assert failed.summary["MPR"] == pytest.approx(50.0)
    assert failed.warnings == ["b: no result for this sequence; scored as failed in every frame"]
    with pytest.raises(InputError, match="no RGBT234 ground truth for sequence"):
        score_run({"zzz": gt}, truth)


def test_lasher_rules_first_frame_carry_and_invalid_truth():
    gt = np.tile(BOX, (4, 1))
    gt[3] = [0, 0, 0, 0]  # an invalid (absent-target) frame: precision hit, success miss
    boxes = np.vstack([BOX + 100, BOX, [10, 10, 0, 5], BOX + 100])
    score, warnings = score_sequence(boxes, SequenceTruth("s", (gt,)), LASHER)
    # frame 1 replaced by the truth, frame 3 (zero width) replaced by frame 2 -> frames 1-3 hit; frame 4 is -1
    assert score.hits["PR"][20] == 4
    assert score.hits["NPR"][20] == 4
    assert score.hits["SR"][0] == 3
    assert any("replaced by the previous box" in w for w in warnings)


def test_result_file_matching_rule():
    seqs = {"car", "blackcar", "ab_bike", "bike"}
    assert match_sequence("JMMAC_blackcar", seqs) == "blackcar"
    assert match_sequence("T_ab_bike", seqs) == "ab_bike"
    assert match_sequence("bike", seqs) == "bike"
    assert match_sequence("JMMAC_234_final_car", seqs) == "car"
    assert match_sequence("carx", seqs) is None
    assert match_sequence("X-car", seqs, prefix="X-") == "car"
    assert match_sequence("JMMAC_car", seqs, prefix="X-") is None


def test_folder_evaluation_equals_in_memory_scoring(tmp_path):
    rng = np.random.default_rng(3)
    gts = {f"seq{i}": np.column_stack([rng.uniform(0, 200, (30, 2)), rng.uniform(10, 60, (30, 2))]).round()
           for i in range(3)}
    make_rgbt234(tmp_path / "gt", {n: (g, g + 2) for n, g in gts.items()}, attrs={"LI": [1, 0, 1]})
    runs = {n: g + rng.normal(0, 6, g.shape) for n, g in gts.items()}
    for n, b in runs.items():
        write_boxes(tmp_path / "Mine" / f"Mine_{n}.txt", b, delimiter="\t", precision=0)
    report = evaluate("rgbt234", tmp_path / "gt", [tmp_path / "Mine"])
    truth = load_groundtruth(tmp_path / "gt", RGBT234)
    memory = score_run({n: np.round(b) for n, b in runs.items()}, truth, tracker="Mine")
    assert report.trackers["Mine"].summary == pytest.approx(memory.summary)
    assert set(report.trackers["Mine"].attribute_scores()) == {"LI"}
    assert report.trackers["Mine"].attribute_scores()["LI"]["sequences"] == 2


def test_empty_wrong_or_absent_folders_are_clear_errors(tmp_path):
    gt = np.tile(BOX, (2, 1))
    make_rgbt234(tmp_path / "gt", {"a": (gt, gt)})
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no result file for any of the 1 sequences"):
        evaluate("rgbt234", tmp_path / "gt", [tmp_path / "empty"])
    with pytest.raises(MissingFileError, match="no such results folder"):
        evaluate("rgbt234", tmp_path / "gt", [tmp_path / "absent"])
    with pytest.raises(InputError, match="no GTOT ground truth found"):
        evaluate("gtot", tmp_path / "gt", [tmp_path / "empty"])
    with pytest.raises(InputError, match="unknown benchmark"):
        get_benchmark("otb100")


def test_score_boxes_for_one_sequence_outside_a_benchmark():
    gt_rgb = np.tile(BOX, (4, 1))
    gt_t = gt_rgb + [3, 0, 0, 0]
    boxes = gt_t.copy()
    boxes[3] += 50
    summary, warnings = score_boxes(boxes, gt_rgb, gt_t, benchmark="rgbt234")
    assert summary["MPR"] == pytest.approx(75.0) and warnings == []
    summary, _ = score_boxes(boxes, gt_rgb, benchmark="lasher")
    assert set(summary) == {"PR", "SR", "NPR"}
    with pytest.raises(InputError, match="not a one-pass benchmark"):
        score_boxes(boxes, gt_rgb, benchmark="vot-rgbt")
