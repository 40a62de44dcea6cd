"""``rgbt eval``: score trackers' result folders on an RGB-T (or Anti-UAV) benchmark with its own conventions."""

from __future__ import annotations

import click

from rgbt_cli.options import output_file_option, output_format_option, threads_option
from rgbt_toolkit.evaluation.benchmarks import BENCHMARKS  # light: numpy only


@click.command(name="eval")
@click.option("--benchmark", "-b", required=True, type=click.Choice(list(BENCHMARKS), case_sensitive=False),
              help="Benchmark whose scoring conventions apply.")
@click.option("--gt", "gt_dir", required=True, type=click.Path(file_okay=False),
              help="Ground-truth folder (e.g. gt/RGBT234 or gt/RGBT234/rgbt234_gt; VOT: <seq>/groundtruth.txt; "
                   "Anti-UAV: <seq>/IR_label.json).")
@click.option("--results", "-r", "results", required=True, multiple=True, type=click.Path(file_okay=False),
              help="Result folder of one tracker (repeatable): DIR (the tracker is named after the folder) or "
                   "NAME=DIR.")
@click.option("--prefix", default=None,
              help="One-pass benchmarks: result files are exactly <PREFIX><seq>.txt (default: <seq>.txt or "
                   "<anything>_<seq>.txt).")
@click.option("--plot", "plot_path", default=None, type=click.Path(dir_okay=False),
              help="Also draw precision/success plots (VOT: expected-overlap curves) into this PNG; not for "
                   "Anti-UAV.")
@output_format_option
@output_file_option
@threads_option
def command(benchmark, gt_dir, results, prefix, plot_path, output_format, output, threads):
    """Score tracker results on GTOT, RGBT234, RGBT210, LasHeR, VOT-RGBT or Anti-UAV, reproducing published numbers.

    Warnings (missing sequences, short files, NaN or zero-size boxes) go to stderr, one line each.
    """
    from rgbt_toolkit._atomic import write_text_atomic
    from rgbt_toolkit.evaluation.api import evaluate
    from rgbt_toolkit.evaluation.report import render
    from rgbt_toolkit.runtime import set_threads

    _check_outputs(output, plot_path, benchmark)  # all of them before any work, so a bad one leaves nothing behind
    set_threads(threads)
    report = evaluate(benchmark, gt_dir, list(results), prefix=prefix)
    for line in report.all_warnings():
        click.echo(f"warning: {line}", err=True)
    text = render(report, output_format)
    if plot_path:
        from rgbt_toolkit.evaluation.plots import plot_report

        plot_report(report, plot_path)
    if output:
        write_text_atomic(output, text)
    else:
        click.echo(text, nl=False)


def _check_outputs(output: str | None, plot_path: str | None, benchmark: str) -> None:
    """Refuse unwritable outputs, a plot name that is not .png or of a benchmark without curves, one file for both."""
    from pathlib import Path

    from rgbt_toolkit._atomic import check_writable
    from rgbt_toolkit.errors import InputError

    if plot_path:
        from rgbt_toolkit.evaluation.benchmarks import get_benchmark
        from rgbt_toolkit.evaluation.plots import check_plottable

        check_plottable(get_benchmark(benchmark))
    if plot_path and Path(plot_path).suffix.lower() != ".png":
        raise InputError(f"--plot {plot_path}: plots are written as PNG; give a file name ending in .png")
    if output and plot_path and Path(output).resolve() == Path(plot_path).resolve():
        raise InputError(f"{output}: given for both -o and --plot; choose two file names")
    for path, what in ((output, "scores"), (plot_path, "plot")):
        if path:
            check_writable(path, what, overwrite=True)
