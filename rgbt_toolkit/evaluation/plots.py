"""Precision and success plots as the RGB-T benchmarks draw them (and VOT's expected-overlap curve), as PNG.

One panel per curve of the benchmark, one line per tracker, the legend sorted by score with the score in brackets
(``JMMAC [0.902]``), as the GTOT / RGBT234 toolkits label them. Uses matplotlib's Agg backend (no display needed).
"""

from __future__ import annotations

import os

import numpy as np

from rgbt_toolkit._atomic import atomic_path
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.evaluation.benchmarks import Benchmark, OpeBenchmark
from rgbt_toolkit.evaluation.report import EvaluationReport

_LABELS = {
    "error": ("Location error threshold (pixels)", "Precision", "Precision plots of OPE"),
    "normalised": ("Normalised location error threshold", "Normalised precision", "Normalised precision plots"),
    "overlap": ("Overlap threshold", "Success rate", "Success plots of OPE"),
}


PLOTTED_KINDS = ("ope", "vot")  # benchmarks that score through curves; Anti-UAV's state accuracy has none


def check_plottable(bench: Benchmark) -> None:
    """Refuse, before any scoring, a plot of a benchmark whose score is not read off a curve."""
    if bench.kind not in PLOTTED_KINDS:
        raise InputError(f"--plot: {bench.title} reports state accuracy, which has no precision/success or "
                         f"expected-overlap curve to draw; leave out --plot")


def plot_report(report: EvaluationReport, path: str | os.PathLike, dpi: int = 120) -> None:
    """Draw every curve of ``report`` into one PNG at ``path`` (written atomically)."""
    check_plottable(report.benchmark)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure  # no pyplot: no global state, no display

    bench = report.benchmark
    n_panels = len(bench.curves) if isinstance(bench, OpeBenchmark) else 1
    fig = Figure(figsize=(5.2 * n_panels, 4.4) if n_panels > 1 else (6.4, 4.4))
    FigureCanvasAgg(fig)
    if isinstance(bench, OpeBenchmark):
        _plot_ope(report, bench, fig)
    else:
        _plot_vot(report, fig)
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")


def _plot_ope(report: EvaluationReport, bench: OpeBenchmark, fig) -> None:
    curves = bench.curves
    axes = fig.subplots(1, len(curves), squeeze=False)
    for ax, spec in zip(axes[0], curves):
        order = sorted(report.trackers, key=lambda n: -report.trackers[n].summary[spec.name])
        for name in order:
            scores = report.trackers[name]
            value = scores.summary[spec.name] / 100.0
            ax.plot(spec.thresholds, scores.curve(spec.name), linewidth=2, label=f"{name} [{value:.3f}]")
        xlabel, ylabel, title = _LABELS[spec.kind]
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(f"{title} on {bench.title} ({spec.name})")
        ax.set_xlim(spec.start, spec.stop)
        ax.set_ylim(0, 1)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="lower right" if spec.kind != "overlap" else "lower left", fontsize=8)


def _plot_vot(report: EvaluationReport, fig) -> None:
    ax = fig.subplots()
    order = sorted(report.trackers, key=lambda n: -report.trackers[n].summary["EAO"])
    for name in order:
        scores = report.trackers[name]
        lengths = np.arange(1, len(scores.curve) + 1)
        ax.plot(lengths, scores.curve, linewidth=2, label=f"{name} [{scores.summary['EAO']:.3f}]")
    low, high = report.trackers[order[0]].interval
    ax.axvspan(low, high, color="grey", alpha=0.15, label=f"EAO interval [{low}, {high}]")
    ax.set_xlabel("Sequence length")
    ax.set_ylabel("Expected overlap")
    ax.set_title(f"Expected overlap curves on {report.benchmark.title}")
    ax.set_ylim(0, 1)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
