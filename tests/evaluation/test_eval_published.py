"""The authors' raw JMMAC results scored with each benchmark's conventions give the published numbers.

Reference values: ``../shared/reference/jmmac_official_code_notes.md`` ("Published raw results"): GTOT MPR 90.17 /
MSR 73.18 and RGBT234 MPR 79.02 / MSR 57.34 (the paper prints 90.1 / 73.2 and 79.0 / 57.3); the paper's VOT19-RGBT
table prints R = 0.8235 for JMMAC.
"""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.evaluation.api import evaluate
from rgbt_toolkit.evaluation.benchmarks import RGBT234
from rgbt_toolkit.evaluation.groundtruth import load_groundtruth
from rgbt_toolkit.io.boxes import read_boxes, write_boxes

pytestmark = pytest.mark.shared


def test_gtot_jmmac_reproduces_published_numbers(shared_dir):
    data = shared_dir / "data" / "tracking"
    report = evaluate("gtot", data / "gt" / "GTOT", [data / "results" / "JMMAC" / "GTOT"])
    scores = report.trackers["GTOT"]
    assert round(scores.summary["MPR"], 2) == 90.17
    assert round(scores.summary["MSR"], 2) == 73.18
    assert sum(s.n_frames for s in scores.sequences.values()) == 7850
    assert report.all_warnings() == []


def test_rgbt234_jmmac_reproduces_published_numbers(shared_dir):
    data = shared_dir / "data" / "tracking"
    report = evaluate("rgbt234", data / "gt" / "RGBT234", [data / "results" / "JMMAC" / "RGBT234"])
    scores = report.trackers["RGBT234"]
    assert len(scores.sequences) == 234
    assert round(scores.summary["MPR"], 2) == 79.02
    assert round(scores.summary["MSR"], 2) == 57.34
    # orangeman1 is one line short: truncated, and said so
    assert report.all_warnings() == [
        "RGBT234: orangeman1: result has 920 frames, ground truth 921 (shorter); scoring the common 920 frames"
    ]
    attributes = scores.attribute_scores()
    assert len(attributes) == 12 and sum(a["sequences"] for a in attributes.values()) > 234
    # the benchmark root or its rgbt234_gt sub-folder: the same sequences, in the same order, with attributes
    sub = load_groundtruth(data / "gt" / "RGBT234" / "rgbt234_gt", RGBT234)
    assert list(sub.sequences) == list(scores.sequences) and set(sub.attributes) == set(attributes)


def test_vot19_rgbt_jmmac_failures_give_the_published_robustness(shared_dir, tmp_path):
    """R needs only the failure markers; A and EAO here use a stand-in truth (the VOT truth is not in shared)."""
    data = shared_dir / "data" / "tracking"
    raw = data / "results" / "JMMAC" / "VOT19-RGBT"
    stand_in = tmp_path / "vot"
    for seq in sorted(p.name for p in (raw / "baseline").iterdir()):
        boxes = read_boxes(data / "gt" / "RGBT234" / "rgbt234_gt" / seq / "infrared.txt")
        write_boxes(stand_in / seq / "groundtruth.txt", boxes, fmt="polygon", precision=0)
    scores = evaluate("vot-rgbt", stand_in, [raw]).trackers["VOT19-RGBT"]
    assert len(scores.sequences) == 60 and scores.frames == 20083
    assert scores.failures == 39
    assert round(scores.summary["R"], 4) == 0.8235
    assert 0.55 < scores.summary["A"] < 0.75 and 0.35 < scores.summary["EAO"] < 0.6


def test_lasher_rules_on_its_own_truth(shared_dir):
    """The 40 LasHeR files scored against themselves: invalid (absent-target) frames count for PR, not for SR."""
    gt = shared_dir / "data" / "tracking" / "gt" / "LasHeR"
    report = evaluate("lasher", gt, [gt / "lasher_gt"])
    scores = report.trackers["lasher_gt"]
    assert len(scores.sequences) == 40
    assert scores.summary["PR"] == pytest.approx(100.0) and scores.summary["NPR"] == pytest.approx(100.0)
    invalid = np.mean([np.mean((read_boxes(gt / "lasher_gt" / f"{s}.txt") <= 0).any(axis=1))
                       for s in scores.sequences])
    assert scores.summary["SR"] == pytest.approx(100 * 20 / 21 * (1 - invalid))
    assert any("205 listed sequence(s) have no ground truth" in w for w in report.warnings)
    assert "NO" in scores.attribute_scores()
