"""``rgbt eval`` through click's CliRunner on tiny generated benchmark folders."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.boxes import write_boxes

N = 12


@pytest.fixture()
def bench(tmp_path):
    """An RGBT234-layout truth with 3 sequences and two trackers: Good (exact) and Poor (one sequence missing)."""
    rng = np.random.default_rng(0)
    gt_root = tmp_path / "RGBT234"
    names = ["seqA", "seqB", "car3"]
    for i, name in enumerate(names):
        gt = np.column_stack([rng.integers(0, 300, (N, 2)), rng.integers(10, 50, (N, 2))]).astype(float)
        write_boxes(gt_root / "rgbt234_gt" / name / "visible.txt", gt, precision=0)
        write_boxes(gt_root / "rgbt234_gt" / name / "infrared.txt", gt, precision=0)
        write_boxes(tmp_path / "Good" / f"Good_{name}.txt", gt, precision=0)
        if name != "car3":
            write_boxes(tmp_path / "Poor" / f"{name}.txt", gt + [8, 0, 0, 0], delimiter=" ", precision=0)
    (gt_root / "attr_txt").mkdir()
    (gt_root / "attr_txt" / "SequencesName.txt").write_text("\n".join(names) + "\n")
    (gt_root / "attr_txt" / "LI.txt").write_text("1\n0\n1\n")
    return tmp_path


def _run(*args):
    return CliRunner().invoke(main, ["eval", *map(str, args)])


def test_table_ranks_trackers_and_warns_on_stderr(bench):
    result = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", bench / "Poor", "-r", bench / "Good")
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0] == "RGBT234: 3 sequences"
    assert lines[3].split() == ["Good", "100.00", f"{100 * 20 / 21:.2f}"]
    assert lines[4].split()[0] == "Poor"
    assert "warning: Poor: car3: no result for this sequence" in result.stderr
    assert "MPR by attribute" in result.stdout


def test_json_csv_output_file_and_plot(bench, tmp_path):
    out = tmp_path / "scores.json"
    png = tmp_path / "plots" / "curves.png"
    result = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", bench / "Good", "-r", bench / "Poor",
                  "--format", "json", "-o", out, "--plot", png)
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert data["benchmark"] == "RGBT234"
    assert list(data["trackers"]) == ["Good", "Poor"]
    good = data["trackers"]["Good"]
    assert good["MPR"] == 100.0 and set(good["per_sequence"]) == {"seqA", "seqB", "car3"}
    assert good["attributes"]["LI"]["sequences"] == 2
    assert data["trackers"]["Poor"]["per_sequence"]["car3"]["MPR"] == 0.0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    result = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", bench / "Good", "--format", "csv")
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    assert rows[0] == {"tracker": "Good", "scope": "all", "MPR": "100.0", "MSR": str(round(100 * 20 / 21, 4))}
    assert {r["scope"] for r in rows} >= {"attribute:LI", "sequence:car3"}


def test_prefix_selects_exact_file_names(bench):
    result = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", bench / "Good", "--prefix", "Good_",
                  "--format", "json")
    assert result.exit_code == 0 and json.loads(result.stdout)["trackers"]["Good"]["MPR"] == 100.0
    result = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", bench / "Good", "--prefix", "Other_")
    assert result.exit_code == 1
    assert "no result file for any of the 3 sequences" in result.output


@pytest.mark.parametrize(
    "args, message",
    [
        (["-b", "rgbt234", "--gt", "{b}/RGBT234", "-r", "{b}/empty"], "no result file for any"),
        (["-b", "rgbt234", "--gt", "{b}/RGBT234", "-r", "{b}/absent"], "no such results folder"),
        (["-b", "gtot", "--gt", "{b}/RGBT234", "-r", "{b}/Good"], "no GTOT ground truth found"),
        (["-b", "vot-rgbt", "--gt", "{b}/RGBT234", "-r", "{b}/Good"], "no VOT sequences"),
    ],
)
def test_bad_folders_give_one_line_and_exit_1(bench, args, message):
    (bench / "empty").mkdir()
    result = _run(*[a.format(b=bench) for a in args])
    assert result.exit_code == 1
    assert message in result.output
    assert "Traceback" not in result.output and len(result.output.strip().splitlines()) == 1


def test_trackers_can_be_named_on_the_command_line(bench):
    result = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", f"Ours={bench / 'Good'}", "-r", bench / "Poor")
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[3].split()[0] == "Ours" and "warning: Poor: car3" in result.stderr
    clash = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", f"Poor={bench / 'Good'}", "-r", bench / "Poor")
    assert clash.exit_code == 1 and "share the tracker name 'Poor'" in clash.output


@pytest.mark.parametrize("which", ["result", "groundtruth"])
def test_empty_line_mid_file_is_an_error_not_a_shift(bench, which):
    path = (bench / "Good" / "Good_seqA.txt" if which == "result"
            else bench / "RGBT234" / "rgbt234_gt" / "seqA" / "visible.txt")
    lines = path.read_text().splitlines()
    lines[4] = ""
    path.write_text("\n".join(lines) + "\n\n")  # trailing blank lines stay harmless
    result = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", bench / "Good")
    assert result.exit_code == 1
    assert f"{path}, line 5: empty line" in result.stderr


def test_nan_ground_truth_rows_are_reported(bench):
    path = bench / "RGBT234" / "rgbt234_gt" / "seqB" / "infrared.txt"
    lines = path.read_text().splitlines()
    lines[3] = "nan,nan,nan,nan"
    path.write_text("\n".join(lines) + "\n")
    result = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", bench / "Good")
    assert result.exit_code == 0, result.output
    assert "warning: seqB: 1 ground-truth box(es) are NaN" in result.stderr


@pytest.mark.parametrize("outputs, message", [
    (["--plot", "q.png", "-o", "orig.txt/o.csv"], "orig.txt is a file, not a folder"),
    (["--plot", "p.jpg"], "plots are written as PNG"),
    (["--plot", "p.txt", "-o", "s.txt"], "plots are written as PNG"),
    (["-o", "o.png", "--plot", "o.png"], "given for both -o and --plot"),
])
def test_bad_outputs_are_refused_before_anything_is_written(bench, tmp_path, monkeypatch, outputs, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "orig.txt").write_text("keep\n")
    before = sorted(p.name for p in tmp_path.iterdir())
    result = _run("-b", "rgbt234", "--gt", bench / "RGBT234", "-r", bench / "Good", *outputs)
    assert result.exit_code == 1 and message in result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == before
