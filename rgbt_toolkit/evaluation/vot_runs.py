"""VOT folders and runs: read a VOT ground-truth folder and a tracker's ``baseline`` results, score A / R / EAO.

Ground truth: ``GT_DIR/<seq>/groundtruth.txt`` (rectangles or polygons), sequences from ``GT_DIR/list.txt`` or the
sub-folders; the first image of ``<seq>/ir/`` (else ``color/``) gives the image size that bounds overlaps.
Results: ``DIR/baseline/<seq>/<seq>_NNN.txt`` (or ``DIR/<seq>/<seq>_NNN.txt``), one file per repetition.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from rgbt_toolkit.errors import InputError, MissingFileError
from rgbt_toolkit.evaluation import vot
from rgbt_toolkit.evaluation.benchmarks import VotBenchmark
from rgbt_toolkit.evaluation.results import check_no_gaps
from rgbt_toolkit.io.boxes import VOT_INIT, VotEntry, read_vot_regions
from rgbt_toolkit.io.images import list_images, natural_key


@dataclass(frozen=True)
class VotSequenceScore:
    """One sequence: frame count, failures (mean over repetitions) and accuracy overlaps (NaN = not counted)."""

    name: str
    n_frames: int
    failures: float
    overlaps: np.ndarray

    @property
    def accuracy(self) -> float:
        valid = self.overlaps[~np.isnan(self.overlaps)]
        return float(valid.mean()) if len(valid) else 0.0


@dataclass
class VotScores:
    """A tracker's VOT baseline scores; ``summary`` gives EAO, A, R as the VOT report prints them (0..1)."""

    tracker: str
    benchmark: VotBenchmark
    sequences: dict[str, VotSequenceScore]
    curve: np.ndarray  # expected overlap per sequence length 1..L
    interval: tuple[int, int]
    warnings: list[str] = field(default_factory=list)
    attributes: dict[str, tuple[str, ...]] = field(default_factory=dict)

    @property
    def failures(self) -> float:
        return float(sum(s.failures for s in self.sequences.values()))

    @property
    def frames(self) -> int:
        return int(sum(s.n_frames for s in self.sequences.values()))

    @property
    def summary(self) -> dict[str, float]:
        overlaps = np.concatenate([s.overlaps for s in self.sequences.values()])
        valid = overlaps[~np.isnan(overlaps)]
        return {
            "EAO": vot.eao_score(self.curve, *self.interval),
            "A": float(valid.mean()) if len(valid) else 0.0,
            "R": vot.reliability(self.failures, self.frames, self.benchmark.reliability_frames),
            "failures": self.failures,
        }

    def per_sequence(self) -> dict[str, dict[str, float]]:
        s_frames = self.benchmark.reliability_frames
        return {
            name: {"A": s.accuracy, "R": vot.reliability(s.failures, s.n_frames, s_frames), "failures": s.failures}
            for name, s in self.sequences.items()
        }

    def attribute_scores(self) -> dict[str, dict[str, float]]:
        return {}


def score_vot_run(
    trajectories: Mapping[str, Sequence[Sequence[VotEntry]]],
    groundtruth: Mapping[str, Sequence[VotEntry]],
    bench: VotBenchmark,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    tracker: str = "tracker",
    interval: tuple[int, int] | None = None,
) -> VotScores:
    """Score VOT trajectories held in memory: sequence -> list of repetitions, each a list of entries.

    ``interval`` overrides the EAO length interval, which is otherwise estimated from the ground-truth lengths of
    all sequences in ``groundtruth`` (the whole dataset, as VOT does).
    """
    bounds = bounds or {}
    warnings: list[str] = []
    lengths = {name: len(gt) for name, gt in groundtruth.items()}
    if not lengths:
        raise InputError("no VOT ground truth to score against")
    max_len = max(lengths.values())
    scores: dict[str, VotSequenceScore] = {}
    all_frags, all_weights = [], []
    for name, gt in groundtruth.items():
        runs = trajectories.get(name) or []
        if not runs:
            warnings.append(f"{name}: no result for this sequence; left out of A, R and EAO")
            continue
        acc, fails = [], []
        for rep, traj in enumerate(runs, start=1):
            if len(traj) != len(gt):
                warnings.append(f"{name}: repetition {rep} has {len(traj)} frames, ground truth {len(gt)}; "
                                f"scoring the common {min(len(traj), len(gt))} frames")
            if not traj or not (isinstance(traj[0], int) and traj[0] == VOT_INIT):
                warnings.append(f"{name}: repetition {rep} does not start with the initialisation marker 1")
            n_nan = sum(1 for e in traj if not isinstance(e, int) and np.isnan(e).any())
            if n_nan:
                warnings.append(f"{name}: repetition {rep} has {n_nan} NaN region(s); left out of accuracy, zero "
                                f"overlap in EAO")
            box = bounds.get(name)
            raw = vot.region_overlaps(traj, gt, box)
            overlaps = np.full(len(gt), np.nan)
            overlaps[: len(raw)] = vot.mask_burnin(raw, traj, bench.burnin)
            acc.append(overlaps)
            failed = vot.failure_frames(traj)
            fails.append(len(failed))
            all_frags.append(vot.fragments(raw, failed, bench.skip_initialize, max_len))
            all_weights.append(np.full(len(all_frags[-1]), 1.0 / len(runs)))
        with np.errstate(all="ignore"):
            stacked = np.array(acc)
            counts = (~np.isnan(stacked)).sum(axis=0)
            mean_overlaps = np.where(counts > 0, np.nansum(stacked, axis=0) / np.maximum(counts, 1), np.nan)
        scores[name] = VotSequenceScore(name, len(gt), float(np.mean(fails)), mean_overlaps)
    if not scores:
        raise InputError("no VOT results to score")
    curve = vot.expected_overlap_curve(np.concatenate(all_frags), np.concatenate(all_weights))
    if interval is None:
        low, high, _ = vot.eao_interval(list(lengths.values()), bench.eao_density)
        interval = (low, high)
    return VotScores(tracker, bench, scores, curve, interval, warnings)


def load_vot_groundtruth(
    gt_dir: str | os.PathLike, bench: VotBenchmark
) -> tuple[dict[str, list[VotEntry]], dict[str, tuple[float, float]]]:
    """Ground-truth regions and image bounds of every sequence in a VOT folder."""
    gt_dir = Path(gt_dir)
    if not gt_dir.is_dir():
        raise MissingFileError(f"{gt_dir}: no such ground-truth folder")
    list_file = gt_dir / bench.sequence_list
    if list_file.is_file():
        names = [n.strip() for n in list_file.read_text(encoding="utf-8").splitlines() if n.strip()]
    else:
        names = sorted((p.name for p in gt_dir.iterdir() if (p / bench.groundtruth_file).is_file()), key=natural_key)
    if not names:
        raise InputError(f"{gt_dir}: no VOT sequences (expected <seq>/{bench.groundtruth_file} folders or "
                         f"{bench.sequence_list}); is this the right folder and --benchmark?")
    truth, bounds = {}, {}
    for name in names:
        path = gt_dir / name / bench.groundtruth_file
        if not path.is_file():
            raise MissingFileError(f"{path}: listed sequence has no ground truth")
        check_no_gaps(path)
        truth[name] = read_vot_regions(path, allow_markers=False)
        for folder in bench.image_folders:
            if (gt_dir / name / folder).is_dir():
                images = list_images(gt_dir / name / folder)
                if images:
                    bounds[name] = _image_size(images[0])
                    break
    return truth, bounds


def _image_size(path: Path) -> tuple[float, float]:
    from PIL import Image  # header only, no decode

    with Image.open(path) as im:
        return float(im.width), float(im.height)


def load_vot_results(folder: str | os.PathLike, sequences: Sequence[str], bench: VotBenchmark) -> dict[str, list]:
    """Every repetition file of every sequence: sequence -> list of trajectories (missing sequences absent)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise MissingFileError(f"{folder}: no such results folder")
    base = folder / bench.experiment if (folder / bench.experiment).is_dir() else folder
    runs: dict[str, list] = {}
    for name in sequences:
        files = sorted((base / name).glob(f"{name}_[0-9][0-9][0-9].txt")) if (base / name).is_dir() else []
        if files:
            for path in files:
                check_no_gaps(path)
            runs[name] = [read_vot_regions(p) for p in files]
    if not runs:
        raise InputError(f"{folder}: no VOT result files (expected [{bench.experiment}/]<seq>/<seq>_001.txt for "
                         f"sequences such as {', '.join(list(sequences)[:3])}); is this the right folder?")
    return runs
