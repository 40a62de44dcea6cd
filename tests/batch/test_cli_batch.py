"""``rgbt batch track`` end to end: results ``rgbt eval`` scores, resuming after a kill, failures and exit codes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from batch_helpers import count_calls
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.batch.manifest import MANIFEST_NAME, Manifest

TEMPLATE = "batch_helpers:template_tracker,batch_helpers:video_tracker"
HELPERS = Path(__file__).resolve().parent


def _track(dataset, out, *extra, tracker=TEMPLATE):
    return CliRunner().invoke(main, ["batch", "track", str(dataset), "-o", str(out), "--tracker", tracker, *extra])


def test_track_writes_results_that_rgbt_eval_scores(dataset, tmp_path):
    out = tmp_path / "mytracker"
    result = _track(dataset, out, "--in-process")  # the pool and Dask paths are compared in test_executors
    assert result.exit_code == 0, result.output
    assert "5 done, 0 skipped (finished before), 0 failed" in result.stdout
    assert "on in-process" in result.stdout
    scored = CliRunner().invoke(main, ["eval", "-b", "rgbt234", "--gt", str(dataset), "--results", str(out),
                                       "--format", "json"])
    assert scored.exit_code == 0, scored.output
    report = json.loads(scored.stdout)["trackers"]["mytracker"]
    assert sorted(report["per_sequence"]) == ["seq0", "seq1", "seq2", "seq3"]
    assert report["MPR"] > 90  # the template tracker follows these plain scenes
    again = _track(dataset, out, "--workers", "2")
    assert again.exit_code == 0 and "0 done, 5 skipped" in again.stdout and "process pool (2 workers)" in again.stdout


def test_failed_item_gives_summary_and_nonzero_exit(dataset, tmp_path):
    (dataset / "seq2" / "visible.txt").write_text("1,2,3\n")
    result = _track(dataset, tmp_path / "out", "--in-process")
    assert result.exit_code == 1
    assert "seq2  failed       1" in result.stdout and "FileFormatError" in result.stdout
    assert "4 done, 0 skipped (finished before), 1 failed" in result.stdout
    assert "1 item(s) failed; tracebacks in" in result.stderr
    assert sorted(p.name for p in (tmp_path / "out").glob("*.txt")) == ["seq0.txt", "seq1.txt", "seq3.txt"]
    assert "seq2" in (tmp_path / "out" / ".rgbt-batch.errors.log").read_text()


def test_ctrl_c_exits_130_and_keeps_finished_items(dataset, tmp_path):
    (dataset.parent / "interrupt_after").write_text("1")
    result = _track(dataset, tmp_path / "out", "--in-process")
    assert result.exit_code == 130 and "run the same command again" in result.stderr
    assert len(Manifest(tmp_path / "out" / MANIFEST_NAME)) == 1


def test_killed_run_redoes_only_what_was_missing(dataset, tmp_path):
    out = tmp_path / "out"
    tracker = "batch_helpers:slow_tracker,batch_helpers:video_tracker"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HELPERS), os.environ.get("PYTHONPATH", "")])}
    process = subprocess.Popen([sys.executable, "-m", "rgbt_cli.main", "batch", "track", str(dataset), "-o", str(out),
                                "--tracker", tracker, "--in-process"], env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    manifest_path = out / MANIFEST_NAME
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and process.poll() is None:
        if manifest_path.is_file() and len(Manifest(manifest_path)) >= 2:  # two items recorded
            break
        time.sleep(0.05)
    process.send_signal(signal.SIGKILL)
    process.wait()
    finished = {key for key in ("seq0", "seq1", "seq2", "seq3", "vid") if key in Manifest(manifest_path)}
    assert 2 <= len(finished) < 5
    before = count_calls(dataset)
    result = _track(dataset, out, "--in-process", tracker=tracker)
    assert result.exit_code == 0, result.output
    after = count_calls(dataset)
    assert {k for k in after if after[k] != before.get(k, 0)} == {"seq0", "seq1", "seq2", "seq3", "vid"} - finished
    assert f"{5 - len(finished)} done, {len(finished)} skipped" in result.stdout
    assert not [p for p in out.iterdir() if p.name.startswith(".seq")]  # no temporary files left under final names


def test_bad_options_are_one_line_errors(dataset, tmp_path):
    result = _track(dataset, tmp_path / "out", "--in-process", "--dask-local", "2")
    assert result.exit_code == 1 and "cannot be combined" in result.stderr
    result = _track(dataset, tmp_path / "out", tracker="nope")
    assert result.exit_code == 1 and "unknown tracker 'nope'" in result.stderr
    result = _track(tmp_path / "absent", tmp_path / "out")
    assert result.exit_code == 1 and "no such dataset folder" in result.stderr


def test_help_lists_the_subcommands():
    result = CliRunner().invoke(main, ["batch", "--help"])
    assert result.exit_code == 0 and "track" in result.stdout and "fuse" in result.stdout


@pytest.mark.filterwarnings("always")  # as outside pytest, where a warning is not an error
def test_worker_warnings_are_one_plain_line_and_folders_without_boxes_are_reported(dataset, tmp_path):
    import shutil

    shutil.copytree(dataset / "seq1", dataset / "seq1warn")
    shutil.copytree(dataset / "seq2", dataset / "noinit")
    for name in ("visible.txt", "infrared.txt", "init.txt"):
        (dataset / "noinit" / name).unlink()
    result = _track(dataset, tmp_path / "out", "--in-process",
                    tracker="batch_helpers:warning_tracker,batch_helpers:video_tracker")
    assert result.exit_code == 0, result.output
    assert f"warning: {dataset / 'noinit'}: no init.txt/groundTruth; skipped" in result.stderr
    warned = [line for line in result.stderr.splitlines() if "frame 2 skipped" in line]
    assert warned == [f"warning: seq1warn: {dataset / 'seq1warn'}: frame 2 skipped"]
    assert "second line" not in result.stderr and "warnings.warn" not in result.stderr
    assert "6 done" in result.stdout


def test_temporary_files_of_killed_workers_are_removed(dataset, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    stale = [out / ".seq0.k3x_9abc.txt", out / ".seq3.00000000.txt"]  # as atomic_path names them
    kept = [out / ".seq0.txt", out / ".seq0.toolongname.txt", out / "notes.seq1.abcdefgh.txt"]
    for path in stale + kept:
        path.write_text("half")
    (dataset.parent / "interrupt_after").write_text("1")
    result = _track(dataset, out, "--in-process")
    assert result.exit_code == 130
    assert not any(p.exists() for p in stale) and all(p.exists() for p in kept)
    stale[0].write_text("half")  # left by a worker killed in the interrupted run: the next run removes it
    (dataset.parent / "interrupt_after").unlink()
    assert _track(dataset, out, "--in-process").exit_code == 0 and not stale[0].exists()
