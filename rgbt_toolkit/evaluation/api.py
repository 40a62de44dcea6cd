"""Evaluate trackers' result folders on a benchmark: the library call behind ``rgbt eval``."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.evaluation.anti_uav import AntiUavScores
from rgbt_toolkit.evaluation.anti_uav_runs import evaluate_anti_uav_folder, load_anti_uav_groundtruth
from rgbt_toolkit.evaluation.benchmarks import AntiUavBenchmark, Benchmark, VotBenchmark, get_benchmark
from rgbt_toolkit.evaluation.groundtruth import GroundTruth, load_groundtruth
from rgbt_toolkit.evaluation.ope import TrackerScores, score_run
from rgbt_toolkit.evaluation.report import EvaluationReport  # re-exported: evaluate() returns it
from rgbt_toolkit.evaluation.results import check_no_gaps, find_result_files
from rgbt_toolkit.evaluation.vot_runs import VotScores, load_vot_groundtruth, load_vot_results, score_vot_run
from rgbt_toolkit.io.boxes import read_boxes


def named_results(results: Sequence[str | os.PathLike]) -> tuple[list[str], list[Path]]:
    """``(names, folders)`` from result arguments ``DIR`` or ``NAME=DIR`` (an explicit tracker name).

    Unnamed folders are named by :func:`tracker_names`; ``NAME=DIR`` lets the authors' per-benchmark folders
    (``results/JMMAC/GTOT``) show as ``JMMAC`` instead of ``GTOT``.
    """
    given, folders = [], []
    for result in results:
        text = str(result)
        name, sep, folder = text.partition("=")
        if sep and name and folder and not Path(text).exists():
            given.append(name)
            folders.append(Path(folder))
        else:
            given.append(None)
            folders.append(Path(text))
    derived = tracker_names(folders)
    names = [g if g is not None else d for g, d in zip(given, derived)]
    if len(set(names)) != len(names):
        raise InputError(f"two result folders share the tracker name {_first_repeat(names)!r}; "
                         "name them with NAME=DIR")
    return names, folders


def _first_repeat(names: list[str]) -> str:
    return next(n for n in names if names.count(n) > 1)


def tracker_names(folders: Sequence[str | os.PathLike]) -> list[str]:
    """Tracker names from result folders: the folder name, with its parent added when two names clash.

    A VOT experiment folder (``.../JMMAC/baseline``) is named after its parent.
    """
    paths = [Path(f).resolve() for f in folders]
    paths = [p.parent if p.name == "baseline" else p for p in paths]
    names = [p.name for p in paths]
    for i, p in enumerate(paths):
        if names.count(p.name) > 1:
            names[i] = f"{p.parent.name}/{p.name}"
    if len(set(names)) != len(names):
        raise InputError("the same results folder was given twice")
    return names


def evaluate_ope_folder(truth: GroundTruth, folder: str | os.PathLike, name: str,
                        prefix: str | None = None) -> TrackerScores:
    """Score one tracker's result folder against loaded ground truth (missing sequences fail every frame)."""
    files, notes = find_result_files(folder, list(truth.sequences), prefix)
    for path in files.values():
        check_no_gaps(path)
    boxes = {seq: read_boxes(path, fmt="auto") for seq, path in files.items()}
    scores = score_run(boxes, truth, tracker=name, missing="fail")
    scores.warnings[:0] = notes
    return scores


def evaluate(
    benchmark: str | Benchmark,
    gt_dir: str | os.PathLike,
    results: Sequence[str | os.PathLike],
    prefix: str | None = None,
) -> EvaluationReport:
    """Score every results folder (one tracker each, named after the folder) on ``benchmark``.

    Parameters
    ----------
    benchmark : str or benchmark record
        ``gtot``, ``rgbt234``, ``rgbt210``, ``lasher``, ``vot-rgbt`` or ``anti-uav``.
    gt_dir : path-like
        The benchmark's ground-truth folder (see :mod:`rgbt_toolkit.evaluation.groundtruth`; VOT:
        ``<seq>/groundtruth.txt``; Anti-UAV: ``<seq>/IR_label.json`` [+ ``RGB_label.json``]).
    results : sequence of path-like
        Result folders, each ``DIR`` (named after the folder) or ``NAME=DIR``. OPE: ``<seq>.txt`` or
        ``<anything>_<seq>.txt`` per sequence; VOT: ``[baseline/]<seq>/<seq>_001.txt``; Anti-UAV:
        ``<seq>_IR.json`` / ``<seq>_IR.txt`` (or ``<seq>.json`` / ``<seq>.txt``) [+ ``<seq>_RGB.*``].
    prefix : str, optional
        OPE only: match ``<prefix><seq>.txt`` exactly instead of the suffix rule.
    """
    bench = get_benchmark(benchmark) if isinstance(benchmark, str) else benchmark
    if not results:
        raise InputError("give at least one results folder")
    names, results = named_results(results)
    trackers: dict[str, TrackerScores | VotScores | AntiUavScores] = {}
    if isinstance(bench, AntiUavBenchmark):
        if prefix is not None:
            raise InputError("--prefix applies to one-pass benchmarks; Anti-UAV results are <seq>_IR.json or "
                             "<seq>_IR.txt")
        anti_uav_truth = load_anti_uav_groundtruth(gt_dir, bench)
        for name, folder in zip(names, results):
            trackers[name] = evaluate_anti_uav_folder(anti_uav_truth, folder, name)
        return EvaluationReport(bench, trackers, list(anti_uav_truth.warnings))
    if isinstance(bench, VotBenchmark):
        if prefix is not None:
            raise InputError("--prefix applies to one-pass benchmarks; VOT results are <seq>/<seq>_001.txt")
        truth, bounds = load_vot_groundtruth(gt_dir, bench)
        for name, folder in zip(names, results):
            runs = load_vot_results(folder, list(truth), bench)
            trackers[name] = score_vot_run(runs, truth, bench, bounds, tracker=name)
        return EvaluationReport(bench, trackers)
    truth = load_groundtruth(gt_dir, bench)
    for name, folder in zip(names, results):
        trackers[name] = evaluate_ope_folder(truth, folder, name, prefix)
    return EvaluationReport(bench, trackers, list(truth.warnings))
