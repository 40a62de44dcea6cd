"""``rgbt batch``: run a command over a whole dataset or folder, on this machine or a Dask cluster.

Every subcommand shares the executor options (``--workers``, ``--in-process``, ``--scheduler``, ``--dask-local``),
the resumable manifest, the single progress bar and the summary table with a non-zero exit when an item failed.
"""

from __future__ import annotations

import sys

import click

from rgbt_cli.options import apply_options, fusion_metric_options, output_format_option
from rgbt_cli.progress import progress_bar

EXIT_FAILED_ITEMS = 1
EXIT_INTERRUPTED = 130


def executor_options(fn):
    """The options choosing where items run, shared by every ``rgbt batch`` subcommand."""
    options = [
        click.option("--workers", "-j", type=click.IntRange(min=1), default=None,
                     help="Local worker processes (default: one per CPU core); threads per worker = cores / N."),
        click.option("--in-process", is_flag=True,
                     help="Run items one by one in this process (debugging; tracebacks stay readable)."),
        click.option("--scheduler", metavar="tcp://HOST:PORT", default=None,
                     help="Run on a Dask cluster through this scheduler (needs rgbt-toolkit[dask]; all machines "
                          "must see the same paths)."),
        click.option("--dask-local", type=click.IntRange(min=1), default=None, metavar="N",
                     help="Start a local Dask cluster of N worker processes and run on it."),
        click.option("--threads", type=click.IntRange(min=1), default=None,
                     help="torch, OpenCV and BLAS threads per worker (default: CPU cores / workers)."),
        click.option("--retries", type=click.IntRange(min=0), default=1, show_default=True,
                     help="Times a failed item is run again before it is reported."),
        click.option("--manifest", type=click.Path(dir_okay=False), default=None,
                     help="Record of finished items (default: OUT/.rgbt-batch.jsonl); re-running skips them."),
        click.option("--overwrite", is_flag=True,
                     help="Allow writing over results in OUT that an earlier run of this job did not make."),
    ]
    for option in reversed(options):
        fn = option(fn)
    return fn


def run_with_progress(task_fn, job, found, opts: dict):
    """Make the executor and run the job under one progress bar; exit 130 on Ctrl-C. Returns the batch report."""
    from rgbt_toolkit.batch.executors import make_executor
    from rgbt_toolkit.batch.runner import FAILED, check_outputs, remove_stale_temporaries, run_job

    for path in found.unpaired:
        click.echo(f"warning: {path}: no partner found; ignored", err=True)
    for line in found.notes:
        click.echo(f"warning: {line}", err=True)
    check_outputs(job, list(found.items), opts["manifest"], opts["overwrite"])  # before starting any worker
    bar = progress_bar(total=len(found.items), unit="item", desc="batch")

    def on_item(report) -> None:
        bar.update(1)
        for line in report.warnings:
            bar.write(f"warning: {report.key}: {line}", file=sys.stderr)
        if report.status == FAILED:
            bar.write(f"failed: {report.key}: {report.error}", file=sys.stderr)

    try:
        with make_executor(opts["workers"], opts["in_process"], opts["scheduler"], opts["dask_local"],
                           opts["threads"]) as executor:
            report = run_job(task_fn, job, list(found.items), executor, opts["manifest"], opts["overwrite"],
                             opts["retries"], on_item)
    except KeyboardInterrupt:  # the executor has stopped its workers: their half-written files can go
        bar.close()
        remove_stale_temporaries(job, list(found.items))
        click.echo("interrupted: finished items are recorded; run the same command again to do the rest",
                   err=True)
        sys.exit(EXIT_INTERRUPTED)
    finally:
        bar.close()
    return report


def finish(report, to_stderr: bool = False, extra_failures: int = 0, table: str | None = None) -> None:
    """Print the summary table (``table``, else the generic one); exit non-zero when an item failed (or
    ``extra_failures`` problems were found)."""
    from rgbt_toolkit.batch.runner import summary_table

    click.echo(table if table is not None else summary_table(report), err=to_stderr)
    if not report.ok:
        log = report.extra.get("error_log")
        click.echo(f"{len(report.failed)} item(s) failed" + (f"; tracebacks in {log}" if log else ""), err=True)
    if not report.ok or extra_failures:
        sys.exit(EXIT_FAILED_ITEMS)


@click.group(name="batch")
def command() -> None:
    """Run track, fuse or fusion-metrics over every item of a dataset or folder, resumably, in parallel.

    Finished items are recorded in a manifest and skipped when the same command runs again; a failed item is
    retried once, the others always finish, and the exit status is non-zero when any item failed.
    """


@command.command(name="track")
@click.argument("dataset_dir", type=click.Path(file_okay=False))
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Results folder: <seq>.txt per sequence (scored by 'rgbt eval --results'), <stem>/ per video pair.")
@click.option("--tracker", default="jmmac", show_default=True,
              help="Tracker name (jmmac, csrt), or MODULE:FN[,MODULE:VIDEO_FN]: FN(sequence_folder, preset) -> "
                   "(N, 4) boxes, VIDEO_FN(rgb, t, out_dir, preset) -> {name: path}.")
@click.option("--preset", default=None,
              help="Tracker preset: JMMAC's are default and the paper's ablation variants (full, +TMP, ...); CSRT's are rgb "
                   "(default) or t.")
@click.option("--assume-aligned", is_flag=True,
              help="Video pairs are registered already (only the resolution differs): no registration estimate. "
                   "Without it a pair whose registration fails is reported as a failed item.")
@click.option("--plot", is_flag=True,
              help="Also draw the whole batch's precision and success plots (OUT/batch_plots.png); needs ground "
                   "truth (sequence annotations, or <stem>_rgb.boxes.txt beside a video pair).")
@executor_options
def track(dataset_dir, out_dir, tracker, preset, assume_aligned, plot=False, **opts):
    """Track every sequence folder (GTOT, RGBT234, LasHeR, VTUAV, VOT-RGBT layouts) and video pair in DATASET_DIR.

    Video pairs are matched by name: x_rgb.mp4 with x_t.mp4 (also _visible/_vis and _ir/_thermal/_infrared).
    Ends with a table per item (status, frames, frames/s and, with ground truth, success and precision; a mean
    row), also written as OUT/batch_summary.csv and .json.
    """
    from rgbt_toolkit.batch.tasks import plan_track, track_item
    from rgbt_toolkit.batch.track_summary import (check_plottable_items, plot_track_summary, render_track_table,
                                                  summarise_track, tracker_label, write_track_summary)

    from pathlib import Path

    job, found = plan_track(dataset_dir, out_dir, tracker, preset, assume_aligned=assume_aligned)
    if plot:
        check_plottable_items(found.items)
    report = run_with_progress(track_item, job, found, opts)
    summary = summarise_track(job, list(found.items), report, label=tracker_label(tracker, job.preset))
    written = write_track_summary(summary, out_dir)
    if plot and summary.scores is not None:
        written.append(plot_track_summary(summary, out_dir, Path(dataset_dir).resolve().name))
    for note in summary.notes:
        click.echo(f"note: {note}", err=True)
    click.echo("summary: " + ", ".join(str(p) for p in written), err=True)
    finish(report, table=render_track_table(summary, report))


@command.command(name="fuse")
@click.argument("vis", type=click.Path(file_okay=False))
@click.argument("ir", type=click.Path(file_okay=False), required=False)
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for the fused images, named after each pair's stem.")
@click.option("--weights", type=click.Path(dir_okay=False, exists=True), default=None,
              help="MFNet heads file (default: the shipped weights).")
@click.option("--save-weights", is_flag=True, help="Also write each W_F as <stem>_weights.png.")
@click.option("--ext", type=click.Choice(["png", "jpg", "bmp", "tif"]), default="png", show_default=True,
              help="Format of the fused images.")
@executor_options
def fuse(vis, ir, out_dir, weights, save_weights, ext, **opts):
    """Fuse every registered image pair: VIS and IR folders paired by stem, or one folder of x_vis / x_ir files."""
    from rgbt_toolkit.batch.tasks import fuse_item, plan_fuse

    job, found = plan_fuse(vis, ir, out_dir, weights, ext, save_weights)
    finish(run_with_progress(fuse_item, job, found, opts))


_SUFFIX = {"table": ".txt", "csv": ".csv", "json": ".json"}


@command.command(name="fusion-metrics")
@click.option("--vis", required=True, type=click.Path(exists=True), help="Visible image folder.")
@click.option("--ir", required=True, type=click.Path(exists=True), help="Infrared image folder.")
@click.option("--fused", required=True, type=click.Path(exists=True),
              help="Fused image folder; files pair by stem as <stem>.<ext> or <stem>_<method>.<ext>.")
@click.option("-o", "--output", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for per-image scores (scores/*.json) and the table (fusion_metrics.txt/.csv/.json).")
@apply_options(fusion_metric_options)
@output_format_option
@executor_options
def fusion_metrics(vis, ir, fused, out_dir, convention, metrics, output_format, **opts):
    """Score every fused image against its sources, as 'rgbt fusion-metrics' does, in parallel and resumably.

    The table (one row per image, a mean per method) goes to stdout and to OUT/fusion_metrics.<ext>; the batch
    summary goes to stderr.
    """
    from pathlib import Path

    from rgbt_toolkit._atomic import write_text_atomic
    from rgbt_toolkit.batch.scoring import collect_scores, plan_scores, score_item
    from rgbt_toolkit.metrics.report import render

    names = [m.strip() for m in metrics.split(",") if m.strip()] if metrics else None
    job, found, problems = plan_scores(vis, ir, fused, out_dir, convention, names)
    report = run_with_progress(score_item, job, found, opts)
    failed = {r.key: r.error for r in report.failed}
    table = collect_scores(job, list(found.items), failed, problems)
    text = render(table, output_format)
    write_text_atomic(Path(out_dir) / f"fusion_metrics{_SUFFIX[output_format]}", text)
    click.echo(text, nl=False)
    for line in problems:
        click.echo(f"error: {line}", err=True)
    finish(report, to_stderr=True, extra_failures=len(problems))
