"""The fixed fold split of the real clips and the report's aggregation (benchmarks/real_folds.py), on clip names and
made-up scores; one test checks the split on the clips in ../shared."""

from __future__ import annotations

import importlib.util
import json
import random
from collections import Counter
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "real_folds.py"
_spec = importlib.util.spec_from_file_location("real_folds", _PATH)
rf = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(rf)

# the 116 clip names of data/tracking/real/ and real_more/ (their README.md tables), by class and number
NUMBERS = {
    "antiuav_ir": ["04", "05", "07", "09"],
    "svan_ir_drone": [f"{i:03d}" for i in range(1, 27)],
    "svan_ir_bird": ["002", "003", "005", "006", *(f"{i:03d}" for i in range(9, 15))],
    "svan_ir_airplane": [f"{i:03d}" for i in range(1, 11)],
    "svan_ir_helicopter": [f"{i:03d}" for i in range(1, 11)],
    "svan_v_drone": [f"{i:03d}" for i in range(1, 27)],
    "svan_v_bird": ["001", "002", "004", "007", "013", "027", "028", "029", "030", "031"],
    "svan_v_airplane": [f"{i:03d}" for i in range(1, 11)],
    "svan_v_helicopter": [f"{i:03d}" for i in range(1, 11)],
}
REAL_NAMES = [f"{cls}_{n}" for cls, nums in NUMBERS.items() for n in nums]


def test_clip_class_strips_the_number_only():
    assert rf.clip_class("svan_ir_bird_005") == "svan_ir_bird"
    assert rf.clip_class("antiuav_ir_09") == "antiuav_ir"
    assert rf.clip_class("svan_v_helicopter_010") == "svan_v_helicopter"


def test_split_pinned_on_the_real_names():
    """The split is written down here: if the rule changes, these clips change folds and the test fails."""
    got = rf.folds(REAL_NAMES)
    assert [got[f"antiuav_ir_{n}"] for n in NUMBERS["antiuav_ir"]] == [2, 3, 0, 1]
    assert [got[f"svan_ir_bird_{n}"] for n in NUMBERS["svan_ir_bird"]] == [1, 2, 3, 0, 1, 2, 3, 0, 1, 2]
    assert [got[f"svan_v_helicopter_{n}"] for n in ("001", "002", "003", "010")] == [0, 1, 2, 1]
    assert [got[f"svan_v_drone_{n}"] for n in ("001", "002", "026")] == [3, 0, 0]
    assert Counter(got.values()) == {0: 29, 1: 29, 2: 29, 3: 29}


def test_every_clip_in_exactly_one_fold():
    got = rf.folds(REAL_NAMES)
    assert set(got) == set(REAL_NAMES)
    assert set(got.values()) == {0, 1, 2, 3}


def test_split_does_not_depend_on_the_order_of_the_names():
    shuffled = REAL_NAMES[:]
    random.Random(3).shuffle(shuffled)
    assert rf.folds(shuffled) == rf.folds(REAL_NAMES)


def test_split_is_stratified_by_class():
    got = rf.folds(REAL_NAMES)
    for cls in NUMBERS:
        per_fold = Counter(f for n, f in got.items() if rf.clip_class(n) == cls)
        sizes = [per_fold.get(k, 0) for k in range(rf.N_FOLDS)]
        assert max(sizes) - min(sizes) <= 1, (cls, sizes)


def test_adding_a_clip_moves_no_other_class_and_no_earlier_clip():
    before = rf.folds(REAL_NAMES)
    after = rf.folds([*REAL_NAMES, "svan_v_bird_099", "svan_ir_fox_001"])
    assert {n: after[n] for n in REAL_NAMES} == before


def test_split_refuses_repeated_names():
    with pytest.raises(ValueError, match="must be unique"):
        rf.folds(["svan_v_bird_001", "svan_v_bird_001"])


def test_parse_folds():
    assert rf.parse_folds("2,0, 2") == [0, 2]
    assert rf.parse_folds(None) == [] and rf.parse_folds("") == []
    with pytest.raises(ValueError, match="fold 4 does not exist"):
        rf.parse_folds("1,4")


# --- aggregation on made-up scores -----------------------------------------------------------------------------------
TRACKERS = ["ECO-hc", "ECO-deep", "CSRT", "Nano"]
PEERS = ["CSRT", "Nano"]
# clip -> success of ECO-hc, ECO-deep, CSRT, Nano
FAKE = {
    "x_ir_bird_001": (20.0, 80.0, 40.0, 30.0),   # hc 0.25 x deep: collapse
    "x_ir_bird_002": (29.9, 50.0, 40.0, 30.0),   # just below 0.6 x 50: collapse
    "x_ir_bird_003": (30.0, 50.0, 40.0, 30.0),   # exactly 0.6 x deep: no collapse
    "x_ir_bird_004": (0.0, 49.9, 40.0, 30.0),    # deep below the floor: no collapse
    "x_v_heli_001": (60.0, 60.0, 50.0, 70.0),
    "x_v_heli_002": (60.0, 60.0, 50.0, 80.0),
}


def fake_results() -> dict:
    return {(s, t): {"success": v, "precision": 0.0, "size": 0.0}
            for s, vals in FAKE.items() for t, v in zip(TRACKERS, vals)}


def test_collapses_at_the_boundaries_worst_first():
    assert rf.collapses(fake_results(), list(FAKE)) == ["x_ir_bird_001", "x_ir_bird_002"]


def test_groups_give_all_tuned_other_each_fold_and_each_folder():
    seqs = list(FAKE)
    fold_of = {s: i % 4 for i, s in enumerate(seqs)}
    sets = {s: "real" if "bird" in s else "real_more" for s in seqs}
    rows = dict(rf.groups(seqs, fold_of, sets, tuned=[0, 1], aside=("x_ir_bird_003",)))
    assert rows["all (6)"] == seqs
    assert rows["tuned on, folds 0,1 (4)"] == ["x_ir_bird_001", "x_ir_bird_002", "x_v_heli_001", "x_v_heli_002"]
    assert rows["not tuned on (2)"] == ["x_ir_bird_003", "x_ir_bird_004"]
    assert rows["fold 0 (tuned on) (2)"] == ["x_ir_bird_001", "x_v_heli_001"]
    assert rows["fold 3 (1)"] == ["x_ir_bird_004"]
    assert rows["real/ (4)"] == seqs[:4] and rows["real_more/ (2)"] == seqs[4:]
    assert rows["real/ held aside (1)"] == ["x_ir_bird_003"]
    assert len(rows) == 10


def test_group_table_means_and_margins():
    lines = rf.group_table(fake_results(), TRACKERS, [("birds", list(FAKE)[:4]), ("helis", list(FAKE)[4:])], PEERS)
    assert lines[0] == ("| clips | ECO-hc | ECO-deep | CSRT | Nano | ECO-hc − CSRT | ECO-deep − CSRT | "
                        "ECO-hc − best peer | ECO-deep − best peer |")
    # birds: hc (20 + 29.9 + 30 + 0) / 4 = 19.975, deep 57.475, CSRT 40 (the best peer), Nano 30
    assert lines[2] == "| birds | 20.0 | 57.5 | 40.0 | 30.0 | -20.0 | +17.5 | -20.0 (CSRT) | +17.5 (CSRT) |"
    # helis: Nano 75 is the best peer
    assert lines[3] == "| helis | 60.0 | 60.0 | 50.0 | 75.0 | +10.0 | +10.0 | -15.0 (Nano) | -15.0 (Nano) |"


def test_class_table_marks_more_than_five_below_the_best_peer():
    lines = rf.class_table(fake_results(), TRACKERS, list(FAKE), PEERS)
    assert lines[2] == "| x_ir_bird | 4 | 20.0 | 57.5 | 40.0 | 30.0 | CSRT 40.0 | **-20.0** | +17.5 |"
    assert lines[3] == "| x_v_heli | 2 | 60.0 | 60.0 | 50.0 | 75.0 | Nano 75.0 | **-15.0** | **-15.0** |"


def test_collapse_table_rows():
    seqs = list(FAKE)
    lines = rf.collapse_table(fake_results(), seqs, {s: 2 for s in seqs}, PEERS)
    assert lines[2:] == ["| x_ir_bird_001 | 2 | 20.0 | 80.0 | 0.25 | CSRT 40.0 |",
                         "| x_ir_bird_002 | 2 | 29.9 | 50.0 | 0.60 | CSRT 40.0 |"]



def test_collapse_table_says_none_when_nothing_collapses():
    seqs = ["x_v_heli_001", "x_v_heli_002"]
    assert rf.collapse_table(fake_results(), seqs, {s: 0 for s in seqs}, PEERS)[2:] == ["| none | | | | | |"]


@pytest.mark.shared
def test_the_116_real_clips_are_found_and_classes_match_their_meta(shared_dir):
    root = shared_dir / "data/tracking"
    if not (root / "real_more").is_dir():
        pytest.skip("../shared/data/tracking/real_more is absent")
    found = sorted(p for s in ("real", "real_more") for p in (root / s).iterdir() if (p / "groundtruth.txt").is_file())
    assert sorted(p.name for p in found) == sorted(REAL_NAMES)
    for p in found:
        meta = json.loads((p / "meta.json").read_text())
        source, modality, *kind = rf.clip_class(p.name).split("_")
        assert meta["modality"] == {"ir": "thermal", "v": "visible"}[modality], p.name
        assert meta["class"] == (kind[0] if kind else "drone"), p.name
