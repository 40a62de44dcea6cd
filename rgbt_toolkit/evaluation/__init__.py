"""Tracking evaluation that reproduces published benchmark numbers (GTOT, RGBT234, RGBT210, LasHeR, VOT-RGBT,
Anti-UAV).

Entry points: :func:`evaluate` (result folders, what ``rgbt eval`` runs), :func:`score_run` (a run held in memory),
:func:`score_boxes` (one sequence against its own ground truth), :func:`state_accuracy` (one Anti-UAV track against
its label); benchmark conventions live in
:mod:`rgbt_toolkit.evaluation.benchmarks`. See ``docs/evaluation.md``.
"""

import importlib

_EXPORTS = {
    "AntiUavScores": "anti_uav",
    "BENCHMARKS": "benchmarks",
    "EvaluationReport": "report",
    "GroundTruth": "groundtruth",
    "SequenceTruth": "groundtruth",
    "TrackerScores": "ope",
    "evaluate": "api",
    "get_benchmark": "benchmarks",
    "load_groundtruth": "groundtruth",
    "score_boxes": "ope",
    "score_run": "ope",
    "state_accuracy": "anti_uav",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    """Import lazily, so ``rgbt --help`` (which reads the benchmark table) stays fast."""
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
