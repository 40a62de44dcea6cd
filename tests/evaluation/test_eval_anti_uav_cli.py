"""``rgbt eval --benchmark anti-uav`` through click's CliRunner on a tiny generated Anti-UAV folder."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.anti_uav import read_anti_uav_result, write_anti_uav_result

BOX = [0, 0, 10, 10]
HALF = [0, 0, 10, 5]  # IoU 0.5 with BOX


@pytest.fixture()
def bench(tmp_path):
    """Labels for seq1 (IR + RGB) and seq2 (IR); trackers Good (exact), Half (IR only, written by the writer)."""
    gt = tmp_path / "gt"
    labels = {
        "seq1": ([1, 1, 1, 0], [BOX, BOX, BOX, [0, 0, 0, 0]]),
        "seq2": ([0, 1], [[], BOX]),
    }
    for seq, (exist, rects) in labels.items():
        (gt / seq).mkdir(parents=True)
        (gt / seq / "IR_label.json").write_text(json.dumps({"exist": exist, "gt_rect": rects}))
    (gt / "seq1" / "RGB_label.json").write_text(json.dumps({"exist": [1, 1, 1, 0], "gt_rect": [BOX] * 3 + [[]]}))
    good = tmp_path / "Good"
    good.mkdir()
    (good / "seq1_IR.txt").write_text(json.dumps({"res": [BOX, BOX, BOX, []]}))
    (good / "seq2_IR.txt").write_text(json.dumps({"res": [[], BOX]}))
    (good / "seq1_RGB.txt").write_text(json.dumps({"res": [BOX, BOX, BOX, []]}))
    # Half: seq1 frames 1, 0.5, 0 (reported absent), 1; seq2 0 (a box while absent), 1
    write_anti_uav_result(tmp_path / "Half" / "seq1_IR.txt", np.array([BOX, HALF, BOX, BOX], float),
                          present=np.array([True, True, False, False]))
    write_anti_uav_result(tmp_path / "Half" / "seq2_IR.txt", np.array([BOX, BOX], float))
    return tmp_path


HALF_SEQ1 = ((1 + 0.5 + 0 + 1) / 4, (1 + 0.5 + 0 + 1) / 4 - 0.2 * (1 / 3) ** 0.3)
HALF_SEQ2 = (0.5, 0.5)
HALF_SA = 100 * (HALF_SEQ1[0] + HALF_SEQ2[0]) / 2
HALF_SA_P = 100 * (HALF_SEQ1[1] + HALF_SEQ2[1]) / 2


def _run(*args):
    return CliRunner().invoke(main, ["eval", *map(str, args)])


def test_writer_output_reads_back(bench):
    track = read_anti_uav_result(bench / "Half" / "seq1_IR.txt")
    assert track.present.tolist() == [True, True, False, False]


def test_table_ranks_trackers_with_both_scores(bench):
    result = _run("-b", "anti-uav", "--gt", bench / "gt", "-r", bench / "Half", "-r", bench / "Good")
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0] == "Anti-UAV: 2 sequences"
    assert lines[1].split() == ["tracker", "SA", "SA-P", "SA_RGB", "SA-P_RGB"]
    assert lines[3].split() == ["Good", "100.00", "100.00", "100.00", "100.00"]
    assert lines[4].split() == ["Half", f"{HALF_SA:.2f}", f"{HALF_SA_P:.2f}", "-", "-"]
    assert result.stderr == ""


def test_json_and_csv(bench, tmp_path):
    out = tmp_path / "scores.json"
    result = _run("-b", "anti-uav", "--gt", bench / "gt", "-r", bench / "Half", "--format", "json", "-o", out)
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert data["benchmark"] == "Anti-UAV"
    half = data["trackers"]["Half"]
    assert half["SA"] == pytest.approx(HALF_SA, abs=1e-4) and half["SA-P"] == pytest.approx(HALF_SA_P, abs=1e-4)
    assert half["per_sequence"]["seq2"] == {"SA": 50.0, "SA-P": 50.0}
    assert half["attributes"] == {}
    result = _run("-b", "anti-uav", "--gt", bench / "gt", "-r", bench / "Good", "--format", "csv")
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    assert rows[0] == {"tracker": "Good", "scope": "all", "SA": "100.0", "SA-P": "100.0", "SA_RGB": "100.0",
                       "SA-P_RGB": "100.0"}
    assert rows[2]["scope"] == "sequence:seq2" and rows[2]["SA_RGB"] == ""


def test_missing_sequence_warns_on_stderr(bench):
    (bench / "Good" / "seq2_IR.txt").unlink()
    result = _run("-b", "anti-uav", "--gt", bench / "gt", "-r", bench / "Good", "--format", "json")
    assert result.exit_code == 0, result.output
    assert "warning: Good: seq2: no IR result for this sequence; scored 0 in every frame" in result.stderr
    assert json.loads(result.stdout)["trackers"]["Good"]["per_sequence"]["seq2"] == {"SA": 0.0, "SA-P": -20.0}


def test_plot_is_refused_before_anything_is_written(bench, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    result = _run("-b", "anti-uav", "--gt", bench / "gt", "-r", bench / "Good", "--plot", "p.png", "-o", "s.txt")
    assert result.exit_code == 1
    assert "--plot: Anti-UAV reports state accuracy" in result.stderr
    assert len(result.output.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == before


@pytest.mark.parametrize("change, message", [
    ("short", "seq1_IR.txt: 3 frames, but"),
    ("bad_json", "seq1_IR.txt: malformed JSON"),
    ("no_label", "IR_label.json: missing label file"),
    ("prefix", "--prefix applies to one-pass benchmarks"),
])
def test_bad_input_is_one_line_and_exit_1(bench, change, message):
    args = []
    if change == "short":
        (bench / "Good" / "seq1_IR.txt").write_text(json.dumps({"res": [BOX, BOX, BOX]}))
    elif change == "bad_json":
        (bench / "Good" / "seq1_IR.txt").write_text('{"res": [[0, 0, 10, 10]')
    elif change == "no_label":
        (bench / "gt" / "seq1" / "IR_label.json").unlink()
    else:
        args = ["--prefix", "Good_"]
    result = _run("-b", "anti-uav", "--gt", bench / "gt", "-r", bench / "Good", *args)
    assert result.exit_code == 1
    assert message in result.stderr
    assert "Traceback" not in result.output and len(result.output.strip().splitlines()) == 1
