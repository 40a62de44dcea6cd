"""VOT accuracy / robustness / EAO on a constructed case worked out by hand, and the VOT folder layout."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rgbt_toolkit.errors import FileFormatError, InputError
from rgbt_toolkit.evaluation import vot
from rgbt_toolkit.evaluation.api import evaluate
from rgbt_toolkit.evaluation.benchmarks import VOT_RGBT
from rgbt_toolkit.evaluation.plots import plot_report
from rgbt_toolkit.evaluation.polygons import polygon_iou
from rgbt_toolkit.evaluation.vot_runs import score_vot_run
from rgbt_toolkit.io.boxes import write_boxes, write_vot_results

FULL = np.array([0.0, 0.0, 10.0, 10.0])
HALF_SHIFT = np.array([5.0, 0.0, 10.0, 10.0])  # overlap 50 / 150
HALF_HEIGHT = np.array([0.0, 0.0, 10.0, 5.0])  # overlap 0.5

# burn-in 2 and re-initialisation 2 frames after a failure keep the hand computation short
BENCH = dataclasses.replace(VOT_RGBT, burnin=2, skip_initialize=2)

SEQ_A = [1, FULL, HALF_SHIFT, 2, 0, 1, FULL, HALF_HEIGHT, FULL, FULL]  # fails at frame 3, re-init at 5
SEQ_B = [1, FULL, FULL, FULL, FULL, FULL]


def _gt(n):
    return [FULL.copy() for _ in range(n)]


def test_accuracy_ignores_markers_and_burn_in():
    overlaps = vot.accuracy_overlaps(SEQ_A, _gt(10), burnin=2)
    valid = overlaps[~np.isnan(overlaps)]
    np.testing.assert_allclose(valid, [1 / 3, 0.5, 1.0, 1.0])
    assert np.flatnonzero(~np.isnan(overlaps)).tolist() == [2, 7, 8, 9]


def test_hand_computed_accuracy_robustness_and_eao():
    scores = score_vot_run({"a": [SEQ_A], "b": [SEQ_B]}, {"a": _gt(10), "b": _gt(6)}, BENCH, interval=(2, 3))
    summary = scores.summary
    assert summary["A"] == pytest.approx((1 / 3 + 0.5 + 1 + 1 + 4) / 8)  # pooled over the 8 valid frames
    assert summary["failures"] == 1
    assert summary["R"] == pytest.approx(math.exp(-100 * 1 / 16))
    # fragments: a1 = [., 1, 1/3, 0, 0, 0 | zero padded], a2 = [., 1, .5, 1, 1 | NaN], b = [., 1, 1, 1, 1, 1 | NaN]
    curve = scores.curve
    assert curve[0] == 1.0
    assert curve[1] == pytest.approx(1.0)
    assert curve[2] == pytest.approx(((1 + 1 / 3) / 2 + 0.75 + 1) / 3)
    assert curve[4] == pytest.approx(((4 / 3) / 4 + 3.5 / 4 + 1) / 3)
    assert curve[5] == pytest.approx(((4 / 3) / 5 + 1) / 2)  # a2 is too short for length 6
    assert curve[8] == pytest.approx((4 / 3) / 8)  # only the failed fragment reaches length 9
    assert summary["EAO"] == pytest.approx((curve[1] + curve[2]) / 2)
    assert scores.per_sequence()["a"]["failures"] == 1


def test_repetitions_average_failures_and_weigh_fragments():
    scores = score_vot_run({"a": [SEQ_A, SEQ_A[:1] + [FULL] * 9]}, {"a": _gt(10)}, BENCH, interval=(2, 2))
    assert scores.summary["failures"] == pytest.approx(0.5)


def test_eao_interval_holds_the_requested_density():
    lengths = [123, 659, 333, 212, 300, 280, 150, 990, 410, 260]
    low, high, peak = vot.eao_interval(lengths, density=0.5)
    assert 1 <= low <= peak <= high <= max(lengths)
    wider = vot.eao_interval(lengths, density=0.8)
    assert wider[0] <= low and wider[1] >= high


def test_rotated_polygon_overlap_is_exact():
    square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], dtype=float)
    diamond = np.array([[1, -1], [3, 1], [1, 3], [-1, 1]], dtype=float)  # area 8, contains the whole square
    assert polygon_iou(square, diamond) == pytest.approx(4 / 8)
    shifted = square + [1, 0]
    assert polygon_iou(square, shifted) == pytest.approx(2 / 6)
    entries = [np.array([1, -1, 3, 1, 1, 3, -1, 1.0])]
    overlaps = vot.region_overlaps(entries, [np.array([0, 0, 2, 2.0])])
    assert overlaps[0] == pytest.approx(0.5)


def test_vot_folder_layout_through_evaluate(tmp_path):
    gt_dir = tmp_path / "vot"
    for name, n in (("a", 10), ("b", 6)):
        write_boxes(gt_dir / name / "groundtruth.txt", np.tile(FULL, (n, 1)), fmt="polygon", precision=1)
    write_vot_results(tmp_path / "T" / "baseline" / "a" / "a_001.txt", SEQ_A)
    write_vot_results(tmp_path / "T" / "baseline" / "b" / "b_001.txt", SEQ_B)
    report = evaluate("vot-rgbt", gt_dir, [tmp_path / "T"])
    scores = report.trackers["T"]
    assert scores.summary["failures"] == 1
    # the default burn-in of 10 leaves only frames >= 10 of each run: none here
    assert scores.summary["A"] == 0.0
    assert list(evaluate("vot-rgbt", gt_dir, [tmp_path / "T" / "baseline"]).trackers) == ["T"]
    plot_report(report, tmp_path / "eao.png")
    assert (tmp_path / "eao.png").read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(InputError, match="no VOT result files"):
        evaluate("vot-rgbt", gt_dir, [gt_dir])
    with pytest.raises(InputError, match="no VOT sequences"):
        evaluate("vot-rgbt", tmp_path / "T", [tmp_path / "T"])


def test_overlaps_are_bounded_by_the_image_found_in_the_sequence_folder(tmp_path):
    from rgbt_toolkit.evaluation.vot_runs import load_vot_groundtruth
    from rgbt_toolkit.io.images import write_image

    write_boxes(tmp_path / "s" / "groundtruth.txt", np.array([[0.0, 0.0, 10.0, 10.0]] * 2), precision=0)
    write_image(tmp_path / "s" / "ir" / "00000001.png", np.zeros((8, 20), dtype=np.uint8))  # 20 wide, 8 high
    truth, bounds = load_vot_groundtruth(tmp_path, VOT_RGBT)
    assert bounds == {"s": (20.0, 8.0)}
    # inside the 20 x 8 image both boxes are 10 x 8; unbounded they are 10 x 10 and 10 x 12
    overlap = vot.region_overlaps([np.array([0.0, -2.0, 10.0, 12.0])], truth["s"][:1], bounds["s"])
    assert overlap[0] == pytest.approx(1.0)
    assert vot.region_overlaps([np.array([0.0, -2.0, 10.0, 12.0])], truth["s"][:1])[0] == pytest.approx(100 / 120)
    with pytest.raises(InputError, match="--prefix applies to one-pass"):
        evaluate("vot-rgbt", tmp_path, [tmp_path], prefix="x_")


def test_vot_empty_lines_are_errors_and_nan_regions_warned(tmp_path):
    gt_dir = tmp_path / "vot"
    write_boxes(gt_dir / "a" / "groundtruth.txt", np.tile(FULL, (10, 1)), fmt="polygon", precision=1)
    result = tmp_path / "T" / "baseline" / "a" / "a_001.txt"
    write_vot_results(result, SEQ_A)
    lines = result.read_text().splitlines()
    lines[7] = "nan"
    result.write_text("\n".join(lines) + "\n")
    report = evaluate("vot-rgbt", gt_dir, [tmp_path / "T"])
    assert any("a: repetition 1 has 1 NaN region(s)" in w for w in report.all_warnings())
    gt = gt_dir / "a" / "groundtruth.txt"
    lines = gt.read_text().splitlines()
    lines[2] = " "
    gt.write_text("\n".join(lines) + "\n")
    with pytest.raises(FileFormatError, match="groundtruth.txt, line 3: empty line"):
        evaluate("vot-rgbt", gt_dir, [tmp_path / "T"])
