"""The runner: resuming after an interruption, retrying and reporting failures, refusing to overwrite."""

from __future__ import annotations

import batch_helpers
import numpy as np
import pytest
from batch_helpers import count_calls

from rgbt_toolkit.batch.executors import InProcessExecutor
from rgbt_toolkit.batch.manifest import MANIFEST_NAME, Manifest
from rgbt_toolkit.batch.runner import FAILED, run_job, summary_table
from rgbt_toolkit.batch.tasks import plan_track, track_item
from rgbt_toolkit.errors import InputError, RgbtError
from rgbt_toolkit.io.boxes import read_boxes

TEMPLATE = "batch_helpers:template_tracker,batch_helpers:video_tracker"


def _run(dataset, out, tracker=TEMPLATE, preset="full", **kwargs):
    job, found = plan_track(dataset, out, tracker, preset)
    with InProcessExecutor() as executor:
        return run_job(track_item, job, list(found.items), executor, **kwargs)


def test_results_are_benchmark_result_files(dataset, tmp_path):
    report = _run(dataset, tmp_path / "out")
    assert report.ok and report.count("done") == 5
    boxes = read_boxes(tmp_path / "out" / "seq1.txt")
    expected = batch_helpers.template_tracker(dataset / "seq1")
    np.testing.assert_allclose(boxes, expected, atol=1e-4)
    assert (tmp_path / "out" / "vid" / "boxes_rgb.txt").is_file()


def test_interrupted_run_resumes_with_only_the_missing_items(dataset, tmp_path):
    out = tmp_path / "out"
    stop = dataset.parent / "interrupt_after"
    stop.write_text("2")
    with pytest.raises(KeyboardInterrupt):
        _run(dataset, out)
    stop.unlink()
    finished = Manifest(out / MANIFEST_NAME)
    assert len(finished) == 2  # two items finished before the Ctrl-C on the third
    assert sorted(p.name for p in out.glob("*.txt")) == ["seq0.txt", "seq1.txt"]  # nothing half-written
    before = count_calls(dataset)
    report = _run(dataset, out)
    after = count_calls(dataset)
    recomputed = {key for key in after if after[key] != before.get(key, 0)}
    assert recomputed == {"seq2", "seq3", "vid"}
    assert all(n == 1 for key, n in after.items() if key in recomputed)
    assert [r.status for r in report.items] == ["skipped", "skipped", "done", "done", "done"]
    assert "3 done, 2 skipped" in summary_table(report)
    # a third run has nothing left to do
    assert _run(dataset, out).count("skipped") == 5 and count_calls(dataset) == after


def test_corrupt_item_is_reported_without_a_retry_and_the_rest_finish(dataset, tmp_path):
    bad = dataset / "seq1b"
    (dataset / "seq1").rename(bad)
    (bad / "visible.txt").write_text("12,30,40,50\nthis line is corrupt\n")
    report = _run(dataset, tmp_path / "out")
    by_key = {r.key: r for r in report.items}
    assert by_key["seq1b"].status == FAILED and by_key["seq1b"].attempts == 1  # a corrupt file stays corrupt
    assert "visible.txt, line 2" in by_key["seq1b"].error
    assert [r.key for r in report.items if r.status == "done"] == ["seq0", "seq2", "seq3", "vid"]
    table = summary_table(report)
    assert "seq1b" in table and "failed" in table and "4 done, 0 skipped (finished before), 1 failed" in table
    log = report.extra["error_log"].read_text()
    assert "== seq1b (1 try)" in log and "Traceback" in log
    assert not (tmp_path / "out" / "seq1b.txt").exists()
    # fixed later: a re-run does only that item
    (bad / "visible.txt").write_text((dataset / "seq0" / "visible.txt").read_text())
    again = _run(dataset, tmp_path / "out")
    assert [r.key for r in again.items if r.status == "done"] == ["seq1b"] and again.ok


def test_transient_failure_succeeds_on_the_retry(dataset, tmp_path):
    (dataset / "seq2").rename(dataset / "seq2flaky")
    report = _run(dataset, tmp_path / "out", "batch_helpers:flaky_tracker,batch_helpers:video_tracker")
    flaky = next(r for r in report.items if r.key == "seq2flaky")
    assert report.ok and flaky.status == "done" and flaky.attempts == 2
    assert count_calls(dataset)["seq2flaky"] == 2


def test_no_retry_when_retries_is_zero(dataset, tmp_path):
    (dataset / "seq2").rename(dataset / "seq2flaky")
    report = _run(dataset, tmp_path / "out", "batch_helpers:flaky_tracker,batch_helpers:video_tracker", retries=0)
    assert [r.key for r in report.failed] == ["seq2flaky"] and report.failed[0].attempts == 1
    assert "RuntimeError: transient failure" in report.failed[0].error


def test_outputs_of_another_job_are_not_overwritten(dataset, tmp_path):
    out = tmp_path / "out"
    _run(dataset, out)
    with pytest.raises(InputError, match="already exist and were not written by this job.*--overwrite"):
        _run(dataset, out, preset="shifted")
    report = _run(dataset, out, preset="shifted", overwrite=True)
    assert report.count("done") == 5  # a different preset redoes everything
    np.testing.assert_allclose(read_boxes(out / "seq0.txt")[1:, :2],
                               batch_helpers.template_tracker(dataset / "seq0")[1:, :2] + 1.5, atol=1e-4)


def test_foreign_results_in_a_fresh_folder_are_not_overwritten(dataset, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "seq3.txt").write_text("someone else's results\n")
    with pytest.raises(InputError, match="seq3.txt already exist"):
        _run(dataset, out)


def test_outputs_left_by_this_jobs_interrupted_item_are_redone(dataset, tmp_path):
    out = tmp_path / "out"
    job, _ = plan_track(dataset, out, TEMPLATE, "full")
    Manifest(out / MANIFEST_NAME).record_start(job.signature())  # the job started here, then died inside 'vid'
    (out / "vid").mkdir(parents=True)
    (out / "vid" / "boxes_rgb.txt").write_text("half a tracker's output\n")
    report = _run(dataset, out)
    assert report.ok and report.count("done") == 5
    assert "half" not in (out / "vid" / "boxes_rgb.txt").read_text()


def test_tracker_and_preset_are_checked_before_starting(dataset, tmp_path):
    with pytest.raises(InputError, match="unknown tracker 'nope'"):
        plan_track(dataset, tmp_path, "nope")
    with pytest.raises(InputError, match="cannot track video pairs"):
        plan_track(dataset, tmp_path, "batch_helpers:template_tracker")
    with pytest.raises(RgbtError, match="no_such_module is not available"):
        plan_track(dataset / "seq0", tmp_path, "no_such_module:track")


def test_wrong_box_shape_from_a_tracker_is_an_item_error(dataset, tmp_path):
    job, found = plan_track(dataset / "seq0", tmp_path, "batch_helpers:wrong_shape_tracker")
    with pytest.raises(RgbtError, match=r"returned boxes of shape \(12,\), expected \(N, 4\)"):
        track_item(found.items[0], job)


def test_csrt_baseline_follows_a_plain_scene(dataset, tmp_path):
    from rgbt_toolkit.batch.baselines import csrt_sequence
    from rgbt_toolkit.io.sequences import read_sequence

    boxes = csrt_sequence(dataset / "seq0")
    gt = read_sequence(dataset / "seq0").gt_rgb
    assert boxes.shape == gt.shape
    np.testing.assert_allclose(boxes[0], gt[0])
    centre_error = np.hypot(*((boxes[:, :2] + boxes[:, 2:] / 2) - (gt[:, :2] + gt[:, 2:] / 2)).T)
    assert centre_error.max() < 10
    with pytest.raises(InputError, match="unknown preset 'full'; choose one of rgb, t"):
        plan_track(dataset / "seq0", tmp_path, "csrt", "full")


def test_jmmac_entry_points_take_what_the_batch_passes():
    """The registry names the JMMAC API; its functions must accept (folder, preset) and (rgb, t, out, preset)."""
    import inspect

    from rgbt_toolkit.batch.tasks import TRACKERS, resolve

    pytest.importorskip("rgbt_toolkit.jmmac.api")
    spec = TRACKERS["jmmac"]
    for target, n_positional in ((spec.sequence_fn, 2), (spec.video_fn, 4)):
        params = list(inspect.signature(resolve(target)).parameters.values())[:n_positional]
        assert len(params) == n_positional and all(
            p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params), target
    assert {"full", "default"} <= set(resolve(spec.presets)) and spec.default_preset == "default"
