"""One-pass evaluation (OPE): score a tracker's boxes against a benchmark's ground truth, the benchmark's own way.

Per frame the centre error (and normalised centre error) against each modality's ground truth keeps the smaller
value and the overlap keeps the larger (MPR / MSR); with one ground truth these are plain PR / SR. Per sequence the
frames are counted under every threshold; the benchmark record then says whether counts are pooled over all frames
(GTOT) or turned into per-sequence curves that are averaged (RGBT234, RGBT210, LasHeR).

Problems the official toolkits tolerate are tolerated here the same way and reported in ``warnings`` (one line naming
the sequence): result files longer or shorter than the ground truth are scored on the common length, NaN boxes are
failed frames, zero-size boxes score zero overlap (or are replaced by the previous box where the benchmark does so),
and a sequence without a result file is scored as failed in every frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Mapping

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.evaluation import metrics
from rgbt_toolkit.evaluation.benchmarks import Curve, OpeBenchmark
from rgbt_toolkit.evaluation.groundtruth import GroundTruth, SequenceTruth


@dataclass(frozen=True)
class SequenceScore:
    """Threshold counts of one sequence: ``hits[curve name][i]`` frames pass threshold ``i`` out of ``n_frames``."""

    name: str
    n_frames: int
    hits: dict[str, np.ndarray]
    missing: bool = False


@dataclass
class TrackerScores:
    """All sequence scores of one tracker on one benchmark, with the aggregation rules of that benchmark."""

    tracker: str
    benchmark: OpeBenchmark
    sequences: dict[str, SequenceScore]
    attributes: dict[str, tuple[str, ...]] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)

    def curve(self, name: str, sequences: Iterable[str] | None = None) -> np.ndarray:
        """Aggregated curve (fractions in [0, 1]) of metric ``name`` over ``sequences`` (default: all)."""
        chosen = [self.sequences[s] for s in (sequences if sequences is not None else self.sequences)]
        if not chosen:
            raise InputError("no sequences to aggregate")
        hits = np.array([s.hits[name] for s in chosen], dtype=float)
        frames = np.array([s.n_frames for s in chosen], dtype=float)
        if self.benchmark.pooled:
            return hits.sum(axis=0) / frames.sum()
        return (hits / frames[:, None]).mean(axis=0)

    def score(self, name: str, sequences: Iterable[str] | None = None) -> float:
        """Score of metric ``name`` in percent, as papers print it."""
        spec = _curve_spec(self.benchmark, name)
        return 100.0 * curve_score(spec, self.curve(name, sequences))

    @property
    def summary(self) -> dict[str, float]:
        """Every metric of the benchmark over all sequences, in percent."""
        return {name: self.score(name) for name in self.benchmark.metric_names}

    def per_sequence(self) -> dict[str, dict[str, float]]:
        """Metric -> percent for each sequence on its own (pooled and averaged agree for one sequence)."""
        return {seq: {name: self.score(name, [seq]) for name in self.benchmark.metric_names} for seq in self.sequences}

    def attribute_scores(self) -> dict[str, dict[str, float]]:
        """Metric -> percent over the sequences of each challenge attribute, plus their count."""
        out = {}
        for attr, seqs in self.attributes.items():
            present = [s for s in seqs if s in self.sequences]
            if present:
                out[attr] = {name: self.score(name, present) for name in self.benchmark.metric_names}
                out[attr]["sequences"] = len(present)
        return out


def _curve_spec(bench: OpeBenchmark, name: str) -> Curve:
    for c in bench.curves:
        if c.name == name:
            return c
    raise InputError(f"{bench.title} has no metric '{name}'; it reports {', '.join(bench.metric_names)}")


def curve_score(spec: Curve, curve: np.ndarray) -> float:
    """The reported number of a curve: its value at the score threshold, or its area for success curves."""
    if spec.kind == "overlap":
        return metrics.area_under_curve(curve, spec.thresholds, spec.area)
    return float(curve[spec.score_index])


def matlab_round(values: np.ndarray) -> np.ndarray:
    """Round half away from zero, as MATLAB's ``round`` (NumPy rounds halves to even)."""
    v = np.asarray(values, dtype=float)
    return np.sign(v) * np.floor(np.abs(v) + 0.5)


def _carry_previous(boxes: np.ndarray, bad: np.ndarray) -> np.ndarray:
    """Replace each bad row by the last good row before it (frame 0 is never replaced)."""
    idx = np.arange(len(boxes))
    bad = bad.copy()
    bad[0] = False
    idx[bad] = 0
    return boxes[np.maximum.accumulate(idx)]


def score_sequence(
    boxes: np.ndarray | None, truth: SequenceTruth, bench: OpeBenchmark
) -> tuple[SequenceScore, list[str]]:
    """Score one sequence's result boxes (``None``: no result, every frame failed); return score and warnings."""
    name, warnings = truth.name, []
    n_gt = truth.n_frames
    missing = boxes is None
    r = np.full((n_gt, 4), np.nan) if missing else np.asarray(boxes, dtype=float)
    if r.ndim != 2 or r.shape[1] != 4:
        raise InputError(f"{name}: result boxes must be an (N, 4) x, y, w, h array, got shape {r.shape}")
    if not missing and len(r) == 0:
        warnings.append(f"{name}: empty result; scored as failed in every frame")
        r, missing = np.full((n_gt, 4), np.nan), True
    elif len(r) != n_gt:
        side = "shorter" if len(r) < n_gt else "longer"
        warnings.append(f"{name}: result has {len(r)} frames, ground truth {n_gt} ({side}); "
                        f"scoring the common {min(len(r), n_gt)} frames")
    n = min(len(r), n_gt)
    r = r[:n].copy()
    gts = [g[:n] for g in truth.boxes]
    if not missing:
        n_nan = int(np.isnan(r).any(axis=1).sum())
        if n_nan:
            warnings.append(f"{name}: {n_nan} result box(es) are NaN; scored as failed frames")
    if bench.round_results:
        r = matlab_round(r)
    if bench.first_frame_from_gt and n:
        r[0] = gts[0][0]
    degenerate = (r[:, 2] <= 0) | (r[:, 3] <= 0)
    if degenerate.any():
        how = "replaced by the previous box" if bench.carry_degenerate else "scored with zero overlap"
        warnings.append(f"{name}: {int(degenerate.sum())} result box(es) have zero or negative size; {how}")
        if bench.carry_degenerate:
            r = _carry_previous(r, degenerate)
    hits: dict[str, np.ndarray] = {}
    per_kind = {}
    for curve in bench.curves:
        if curve.kind not in per_kind:
            per_kind[curve.kind] = _frame_values(curve.kind, r, gts, bench)
        values = per_kind[curve.kind]
        if curve.kind == "overlap":
            hits[curve.name] = metrics.hits_above(values, curve.thresholds)
        else:
            hits[curve.name] = metrics.hits_below(values, curve.thresholds, strict=curve.strict)
    return SequenceScore(name, n, hits, missing), warnings


def _frame_values(kind: str, r: np.ndarray, gts: list[np.ndarray], bench: OpeBenchmark) -> np.ndarray:
    """Per-frame value of one curve kind, combined over modalities (best of them, NaN-ignoring as MATLAB)."""
    if kind == "overlap":
        per_gt = [metrics.iou_inclusive(r, g) for g in gts]
        values = per_gt[0] if len(per_gt) == 1 else np.fmax.reduce(per_gt)
    else:
        fn = metrics.centre_error if kind == "error" else metrics.normalised_centre_error
        per_gt = [fn(r, g) for g in gts]
        values = per_gt[0] if len(per_gt) == 1 else np.fmin.reduce(per_gt)
    if bench.invalid_gt_nonpositive:
        invalid = (gts[0] <= 0).any(axis=1)
        values = np.where(invalid, -1.0, values)  # -1: a hit for precision, a miss for success (LasHeR toolkit)
    return values


def score_run(
    boxes: Mapping[str, np.ndarray],
    truth: GroundTruth,
    tracker: str = "tracker",
    missing: str = "skip",
) -> TrackerScores:
    """Score a tracker run held in memory: sequence name -> (N, 4) ``x, y, w, h`` boxes.

    This is the path ``rgbt eval`` takes after reading the files, so a run scored here gives the numbers the
    command gives for the same boxes written to disk.

    Parameters
    ----------
    missing : {"skip", "fail"}
        Benchmark sequences absent from ``boxes``: left out of the averages (``skip``, for a run on a subset) or
        scored as failed in every frame with a warning (``fail``, as a results folder is scored).
    """
    if missing not in ("skip", "fail"):
        raise InputError(f"missing must be 'skip' or 'fail', got '{missing}'")
    unknown = sorted(set(boxes) - set(truth.sequences))
    if unknown:
        raise InputError(f"no {truth.benchmark.title} ground truth for sequence(s): {', '.join(unknown[:5])}")
    scores: dict[str, SequenceScore] = {}
    warnings: list[str] = []
    for name, seq in truth.sequences.items():
        if name not in boxes:
            if missing == "skip":
                continue
            warnings.append(f"{name}: no result for this sequence; scored as failed in every frame")
        score, notes = score_sequence(boxes.get(name), seq, truth.benchmark)
        scores[name] = score
        warnings.extend(notes)
    if not scores:
        raise InputError(f"no {truth.benchmark.title} sequence to score")
    return TrackerScores(tracker, truth.benchmark, scores, dict(truth.attributes), warnings)


def score_boxes(boxes: np.ndarray, *truths: np.ndarray, benchmark: str | OpeBenchmark = "rgbt234",
                name: str = "sequence") -> tuple[dict[str, float], list[str]]:
    """Metrics (percent) of one sequence's boxes against one or two ground truths (visible, infrared).

    For a run outside a benchmark folder (a synthetic sequence, a single clip): the benchmark's conventions apply
    as if the sequence were part of it. Returns the metrics and the warnings.
    """
    from rgbt_toolkit.evaluation.benchmarks import get_benchmark

    bench = get_benchmark(benchmark) if isinstance(benchmark, str) else benchmark
    if not isinstance(bench, OpeBenchmark):
        raise InputError(f"{bench.title} is not a one-pass benchmark; use evaluation.vot_runs.score_vot_run")
    if not truths:
        raise InputError("give at least one ground-truth array")
    truth = SequenceTruth(name, tuple(np.asarray(t, dtype=float).reshape(-1, 4) for t in truths))
    score, warnings = score_sequence(boxes, truth, bench)
    scores = TrackerScores("tracker", bench, {name: score})
    return scores.summary, warnings
