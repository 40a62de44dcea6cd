"""What ``rgbt batch track`` reports at the end: per item status, frames, speed and, where there is ground truth,
success and precision; a mean row; the table as CSV/JSON and the whole batch's precision/success plots.

Scores follow the benchmark the sequences come from (``rgbt eval``'s conventions: GTOT's MPR at 5 px and pooled
frames, RGBT234's MPR at 20 px and averaged per-sequence curves, ...), so a batch's mean row is the number
``rgbt eval`` prints for the same results folder when every item finished. Items are read back from their result
files, so items finished by an earlier run (skipped now) are scored too.
"""

from __future__ import annotations

import csv
import io
import json
import os
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rgbt_toolkit._atomic import write_text_atomic
from rgbt_toolkit.batch.items import Item
from rgbt_toolkit.batch.manifest import Manifest
from rgbt_toolkit.batch.runner import FAILED, SKIPPED, BatchReport
from rgbt_toolkit.errors import RgbtError

SUMMARY_NAME = "batch_summary"  # OUT/batch_summary.csv and .json
PLOT_NAME = "batch_plots.png"
_BENCHMARK_OF_LAYOUT = {"gtot": "gtot", "rgbt234": "rgbt234", "rgbt210": "rgbt210", "lasher": "lasher"}
_DEFAULT_BENCHMARK = "rgbt234"  # VTUAV, VOT-RGBT and video pairs: PR at 20 px, SR as the area under the curve


@dataclass
class ItemRow:
    """One line of the table; ``scores`` maps metric name -> percent (empty without ground truth)."""

    item: str
    status: str
    attempts: int | None
    seconds: float | None
    frames: int | None
    fps: float | None
    scores: dict[str, float] = field(default_factory=dict)
    error: str | None = None


@dataclass
class TrackSummary:
    """The table of a tracking batch, and the scores behind its mean row (for the plots)."""

    rows: list[ItemRow]
    benchmark: object  # evaluation.benchmarks.OpeBenchmark whose conventions scored the items
    metrics: tuple[str, ...]
    mean: ItemRow
    scores: object | None  # evaluation.ope.TrackerScores of every scored item; None when none had ground truth
    label: str
    notes: list[str] = field(default_factory=list)

    @property
    def failed(self) -> list[str]:
        return [r.item for r in self.rows if r.status == FAILED]


def _truth(item: Item) -> tuple[tuple[np.ndarray, ...], str | None]:
    """Ground-truth boxes of an item (per modality in the result's geometry) and its sequence layout."""
    from rgbt_toolkit.io.boxes import read_boxes
    from rgbt_toolkit.io.sequences import read_sequence

    if item.kind == "sequence":
        seq = read_sequence(item.paths[0])
        truths = tuple(g for g in (seq.gt_rgb, seq.gt_t) if g is not None and len(g))
        return truths, seq.layout
    beside = Path(item.paths[0]).with_suffix(".boxes.txt")  # <stem>_rgb.boxes.txt, as `rgbt synth` writes it
    return ((read_boxes(beside),) if beside.is_file() else ()), None


def _result(job, item: Item) -> tuple[np.ndarray | None, float | None]:
    """The item's result boxes in RGB pixels, and the frames/s its own run reported (video pairs)."""
    from rgbt_toolkit.io.boxes import read_boxes

    if item.kind == "sequence":
        path = job.out_dir / f"{item.key}.txt"
        return (read_boxes(path) if path.is_file() else None), None
    folder = job.out_dir / item.key
    boxes = read_boxes(folder / "boxes_rgb.txt") if (folder / "boxes_rgb.txt").is_file() else None
    fps = None
    if (folder / "track.json").is_file():
        fps = json.loads((folder / "track.json").read_text(encoding="utf-8")).get("summary", {}).get("fps")
    return boxes, fps


def summarise_track(job, items: list[Item], report: BatchReport, label: str) -> TrackSummary:
    """Build the table of a finished (or partly failed) tracking batch from its result files.

    ``label`` names the tracker/variant in the plots (``jmmac default``). Frames/s is the item's frames over its
    wall time in the worker (model loading included) unless the tracker's own run reported one (video pairs).
    """
    from rgbt_toolkit.evaluation.benchmarks import get_benchmark
    from rgbt_toolkit.evaluation.groundtruth import SequenceTruth
    from rgbt_toolkit.evaluation.ope import TrackerScores, score_sequence

    by_key = {r.key: r for r in report.items}
    manifest = Manifest(report.manifest)
    loaded, layouts, notes = {}, Counter(), []
    for item in items:
        try:
            truths, layout = _truth(item)
        except RgbtError as exc:  # the item itself reports it (it failed); the table just has no score
            truths, layout = (), None
            notes.append(f"{item.key}: no ground truth ({exc})")
        loaded[item.key] = truths
        if layout is not None:
            layouts[layout] += 1
    names = {_BENCHMARK_OF_LAYOUT.get(layout, _DEFAULT_BENCHMARK) for layout in layouts} or {_DEFAULT_BENCHMARK}
    if len(names) > 1:
        notes.append(f"sequences of several benchmarks ({', '.join(sorted(names))}); scored the "
                     f"{_DEFAULT_BENCHMARK} way")
        names = {_DEFAULT_BENCHMARK}
    bench = get_benchmark(names.pop())
    rows, scored = [], {}
    for item in items:
        state = by_key[item.key]
        seconds = state.seconds if state.status != SKIPPED else getattr(manifest.get(item.key), "seconds", None)
        row = ItemRow(item.key, state.status, state.attempts, seconds, None, None, error=state.error)
        if state.status != FAILED:
            boxes, own_fps = _result(job, item)
            if boxes is not None:
                row.frames = len(boxes)
                row.fps = own_fps if own_fps else (len(boxes) / seconds if seconds else None)
                if loaded[item.key]:
                    score, warnings = score_sequence(boxes, SequenceTruth(item.key, loaded[item.key]), bench)
                    scored[item.key] = score
                    notes.extend(warnings)
                    row.scores = TrackerScores(label, bench, {item.key: score}).summary
        rows.append(row)
    scores = TrackerScores(label, bench, scored) if scored else None
    done = [r for r in rows if r.frames]
    frames = sum(r.frames for r in done)
    seconds = sum(r.seconds or 0.0 for r in done)
    mean = ItemRow("mean", f"{len(done)}/{len(rows)} ok", None, seconds or None, frames or None,
                   (frames / seconds) if seconds else None, scores.summary if scores is not None else {})
    return TrackSummary(rows, bench, bench.metric_names, mean, scores, label, notes)


def check_plottable_items(items) -> None:
    """Refuse ``--plot`` before any item runs when no item has ground truth to draw curves from."""
    from rgbt_toolkit.errors import InputError

    if not any(item.kind == "sequence" or Path(item.paths[0]).with_suffix(".boxes.txt").is_file() for item in items):
        raise InputError("--plot: no item has ground truth (sequence annotations, or <stem>_rgb.boxes.txt beside a "
                         "video pair), so there are no precision/success curves to draw; leave out --plot")


def _cell(value, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def render_track_table(summary: TrackSummary, report: BatchReport, width: int = 60) -> str:
    """The plain-text table: one row per item, the mean row (the benchmark's aggregate over scored items), the
    failed items named, then the batch totals line."""
    metrics = summary.metrics
    name_w = max(4, *(len(r.item) for r in summary.rows))
    head = f"{'item':<{name_w}}  {'status':<7}  {'tries':>5}  {'seconds':>8}  {'frames':>6}  {'fps':>7}"
    head += "".join(f"  {m:>6}" for m in metrics) + "  error"
    lines = [head]
    for r in [*summary.rows, summary.mean]:
        tries = "" if r.attempts is None else r.attempts
        seconds = "-" if r.status == SKIPPED and r.seconds is None else _cell(r.seconds, ".2f")
        line = (f"{r.item:<{name_w}}  {r.status:<7}  {tries:>5}  {seconds:>8}  {_cell(r.frames, 'd'):>6}  "
                f"{_cell(r.fps, '.1f'):>7}")
        line += "".join(f"  {_cell(r.scores.get(m), '.1f'):>6}" for m in metrics)
        lines.append((line + f"  {(r.error or '')[:width]}").rstrip())
    if summary.scores is not None:
        lines.append(f"scores: {summary.benchmark.title} conventions ({', '.join(metrics)} in %); the mean row "
                     f"aggregates {len(summary.scores.sequences)} scored item(s) as `rgbt eval` does")
    if summary.failed:
        lines.append(f"failed: {', '.join(summary.failed)}")
    from rgbt_toolkit.batch.runner import summary_table

    lines.append(summary_table(report, all_items=False).splitlines()[-1])  # the totals line
    return "\n".join(lines)


def _record(row: ItemRow, metrics: tuple[str, ...]) -> dict:
    return {"item": row.item, "status": row.status, "tries": row.attempts,
            "seconds": None if row.seconds is None else round(row.seconds, 3), "frames": row.frames,
            "fps": None if row.fps is None else round(row.fps, 2),
            **{m: (None if m not in row.scores else round(row.scores[m], 2)) for m in metrics}, "error": row.error}


def write_track_summary(summary: TrackSummary, out_dir: str | os.PathLike) -> list[Path]:
    """Write ``batch_summary.csv`` and ``batch_summary.json`` into ``out_dir`` (atomically); return their paths."""
    records = [_record(r, summary.metrics) for r in summary.rows]
    mean = _record(summary.mean, summary.metrics)
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=list(mean), lineterminator="\n")
    writer.writeheader()
    writer.writerows([*records, mean])
    out = Path(out_dir)
    csv_path, json_path = out / f"{SUMMARY_NAME}.csv", out / f"{SUMMARY_NAME}.json"
    write_text_atomic(csv_path, text.getvalue())
    document = {"tracker": summary.label, "benchmark": summary.benchmark.key, "metrics": list(summary.metrics),
                "items": records, "mean": mean, "failed": summary.failed, "notes": summary.notes}
    write_text_atomic(json_path, json.dumps(document, indent=1) + "\n")
    return [csv_path, json_path]


def tracker_label(tracker: str, preset: str) -> str:
    """A short curve label: ``jmmac default``; a custom ``module:function[,module:video_fn]`` by its function name."""
    name = tracker.split(",")[0].rpartition(":")[2] if ":" in tracker else tracker
    return f"{name} {preset}"


def plot_track_summary(summary: TrackSummary, out_dir: str | os.PathLike, dataset: str | None = None) -> Path:
    """Precision and success plots of the whole batch (one curve per tracker/variant) as ``batch_plots.png``.

    Raises
    ------
    RgbtError
        No item has ground truth to score (``--plot`` needs it).
    """
    from rgbt_toolkit.evaluation.plots import plot_report
    from rgbt_toolkit.evaluation.report import EvaluationReport

    if summary.scores is None:
        raise RgbtError("--plot: no finished item has ground truth (sequence annotations, or <stem>_rgb.boxes.txt "
                        "beside a video pair), so there are no precision/success curves to draw")
    from dataclasses import replace

    path = Path(out_dir) / PLOT_NAME
    bench = summary.benchmark  # the titles name the batch, scored the way of its benchmark
    titled = replace(bench, title=f"{dataset}, {bench.title} scoring" if dataset else f"{bench.title} scoring")
    scores = replace(summary.scores, benchmark=titled)
    plot_report(EvaluationReport(titled, {summary.label: scores}), path)
    return path
