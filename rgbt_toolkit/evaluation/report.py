"""The evaluation report (:class:`EvaluationReport`, what ``evaluate`` returns) and its renderings as JSON-ready
dicts, text tables and CSV (strings; the library never prints).

Precision and success scores are in percent as RGB-T papers print them, and so are Anti-UAV's SA and SA-P (as the
Anti-UAV410 paper prints SA); VOT's EAO, A and R stay in [0, 1] as the VOT reports print them.
"""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass, field

from rgbt_toolkit.evaluation.anti_uav import AntiUavScores
from rgbt_toolkit.evaluation.benchmarks import Benchmark
from rgbt_toolkit.evaluation.ope import TrackerScores
from rgbt_toolkit.evaluation.vot_runs import VotScores

DECIMALS = 4


@dataclass
class EvaluationReport:
    """Scores of one or more trackers on one benchmark, plus every warning raised on the way (one line each)."""

    benchmark: Benchmark
    trackers: dict[str, TrackerScores | VotScores | AntiUavScores]
    warnings: list[str] = field(default_factory=list)

    def __str__(self) -> str:
        """The score table ``rgbt eval`` prints."""
        return to_table(self)

    def to_dict(self) -> dict:
        """The scores as plain data (what ``rgbt eval --format json`` prints)."""
        return to_dict(self)

    def all_warnings(self) -> list[str]:
        """Ground-truth warnings, then each tracker's, prefixed with the tracker name."""
        out = list(self.warnings)
        for name, scores in self.trackers.items():
            out.extend(f"{name}: {w}" for w in scores.warnings)
        return out


def _r(value: float) -> float:
    return round(float(value), DECIMALS)


def _clean(scores: dict) -> dict:
    return {k: (int(v) if k == "sequences" else _r(v)) for k, v in scores.items()}


def columns(report: EvaluationReport) -> list[str]:
    """The benchmark's metrics, then further summary values the trackers report (VOT's failures, Anti-UAV's RGB)."""
    out = list(report.benchmark.metric_names)
    for scores in report.trackers.values():
        out += [k for k in scores.summary if k not in out]
    return out


def ranked(report: EvaluationReport) -> list[str]:
    """Tracker names, best first by the benchmark's first metric."""
    first = report.benchmark.metric_names[0]
    return sorted(report.trackers, key=lambda n: -report.trackers[n].summary[first])


def to_dict(report: EvaluationReport) -> dict:
    """``{"benchmark", "trackers": {NAME: {metrics..., "per_sequence", "attributes"}}, "warnings"}``."""
    trackers = {}
    for name in ranked(report):
        scores = report.trackers[name]
        entry = {k: _r(v) for k, v in scores.summary.items()}
        if isinstance(scores, VotScores):
            entry["eao_interval"] = list(scores.interval)
            entry["frames"] = scores.frames
        entry["per_sequence"] = {seq: _clean(v) for seq, v in scores.per_sequence().items()}
        entry["attributes"] = {attr: _clean(v) for attr, v in scores.attribute_scores().items()}
        trackers[name] = entry
    return {"benchmark": report.benchmark.title, "trackers": trackers, "warnings": report.all_warnings()}


def to_json(report: EvaluationReport) -> str:
    return json.dumps(to_dict(report), indent=2) + "\n"


def _grid(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    fmt = lambda cells: "  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(cells, widths)))
    return "\n".join([fmt(header), fmt(["-" * w for w in widths]), *map(fmt, rows)])


def _fmt(value: float, vot: bool) -> str:
    return f"{value:.4f}" if vot else f"{value:.2f}"


def to_table(report: EvaluationReport) -> str:
    """Summary table (trackers x metrics), then one attribute table per metric when the benchmark has attributes."""
    bench = report.benchmark
    names = ranked(report)
    is_vot = bench.kind == "vot"
    metrics = columns(report)
    n_seq = max(len(report.trackers[n].sequences) for n in names)
    summaries = {n: report.trackers[n].summary for n in names}
    rows = [[n] + [_fmt(summaries[n][m], is_vot) if m in summaries[n] else "-" for m in metrics] for n in names]
    parts = [f"{bench.title}: {n_seq} sequences", _grid(["tracker", *metrics], rows)]
    attrs = {n: report.trackers[n].attribute_scores() for n in names}
    attr_names = sorted({a for table in attrs.values() for a in table})
    for metric in bench.metric_names if attr_names else ():
        rows = [[a] + [_fmt(attrs[n][a][metric], False) if a in attrs[n] else "-" for n in names] for a in attr_names]
        parts.append(f"\n{metric} by attribute")
        parts.append(_grid(["attribute", *names], rows))
    return "\n".join(parts) + "\n"


def to_csv(report: EvaluationReport) -> str:
    """One row per tracker and scope (``all``, ``attribute:<A>``, ``sequence:<S>``), one column per metric."""
    metrics = columns(report)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["tracker", "scope", *metrics])
    for name in ranked(report):
        scores = report.trackers[name]
        summary = scores.summary
        writer.writerow([name, "all", *(_r(summary[m]) if m in summary else "" for m in metrics)])
        for attr, values in scores.attribute_scores().items():
            writer.writerow([name, f"attribute:{attr}", *(_r(values[m]) if m in values else "" for m in metrics)])
        for seq, values in scores.per_sequence().items():
            writer.writerow([name, f"sequence:{seq}", *(_r(values[m]) if m in values else "" for m in metrics)])
    return out.getvalue()


FORMATTERS = {"table": to_table, "csv": to_csv, "json": to_json}


def render(report: EvaluationReport, fmt: str) -> str:
    """The report in ``fmt`` (``table``, ``csv`` or ``json``)."""
    if fmt not in FORMATTERS:
        raise ValueError(f"unknown format '{fmt}'; choose table, csv or json")
    return FORMATTERS[fmt](report)
