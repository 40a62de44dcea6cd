"""Anti-UAV state accuracy (SA) and the challenges' penalised score (SA-P), as pure functions of per-frame states.

Per frame ``t`` of a sequence, with ``v_t`` the label's ``exist`` flag and ``p_t`` = 1 when the tracker reports the
target absent:

* ``a_t = IoU_t`` when the target exists (0 when the tracker reports it absent), ``a_t = p_t`` when it does not;
* ``SA = mean_t a_t``;
* ``m_t = 1`` when the target exists and no reported box overlaps it with IoU > 1e-5 (reported absent, or a box
  elsewhere); ``SA-P = SA - 0.2 * (mean of m_t over frames with v_t = 1) ** 0.3`` (0 penalty without such frames).

Sequence scores are averaged over sequences (not pooled over frames); reported in percent. The frame conventions
are those of the official code (ZhaoJ9014/Anti-UAV ``Eval/test.py`` and ``anti_uav_jittor/anti_uav410_jit/
Evaluation_for_SA.py``, Anti-UAV/baseline ``test.py``, the 3rd challenge's CodaLab scoring program):

* IoU of continuous ``[x, x + w] x [y, y + h]`` rectangles, no ``+1``; no positive overlap gives 0;
* every frame counts, the first included (trackers write the initial box there);
* "absent" is ``[]`` (or ``[0]``); a zero-size box is a box, so it scores 0 on an absent frame;
* frames whose label says ``exist = 1`` but has no box (``[]`` or ``[0, 0, 0, 0]``) are left out, as the Anti-UAV410
  toolkit does (the challenge code never meets them);
* result and label lengths must agree: the official code silently scores the common length, which drops frames
  (see ``anti_uav_runs``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.evaluation import metrics
from rgbt_toolkit.evaluation.benchmarks import ANTI_UAV, AntiUavBenchmark
from rgbt_toolkit.io.anti_uav import TargetFrames


@dataclass(frozen=True)
class FrameStates:
    """Per-frame terms of one sequence: accuracy ``a_t``, missed flag ``m_t``, and which frames count at all."""

    accuracy: np.ndarray  # (N,) float in [0, 1]
    missed: np.ndarray  # (N,) bool, only ever true where the target exists
    counted: np.ndarray  # (N,) bool
    exist: np.ndarray  # (N,) bool


def frame_states(pred: TargetFrames, truth: TargetFrames, miss_iou: float = ANTI_UAV.miss_iou) -> FrameStates:
    """The per-frame terms of ``pred`` against ``truth`` (same length; see the module notes for the conventions)."""
    if len(pred) != len(truth):
        raise InputError(f"result has {len(pred)} frames, label {len(truth)}; give one entry per frame")
    exist = truth.present
    gt_has_box = ~np.isnan(truth.boxes).any(axis=1)
    counted = ~exist | gt_has_box
    both = exist & gt_has_box & pred.present
    iou = np.zeros(len(truth))
    if both.any():
        iou[both] = metrics.iou_continuous(pred.boxes[both], truth.boxes[both])
    accuracy = np.where(exist, iou, (~pred.present).astype(float))
    missed = exist & ~(pred.present & (iou > miss_iou))
    return FrameStates(accuracy, missed & counted, counted, exist)


@dataclass(frozen=True)
class SequenceStateScore:
    """One sequence of one modality: SA, SA-P (both in [0, 1]), the missed fraction, and the frames counted."""

    name: str
    sa: float
    sa_p: float
    miss_rate: float
    n_frames: int
    missing: bool = False


def sequence_score(name: str, states: FrameStates, bench: AntiUavBenchmark = ANTI_UAV,
                   missing: bool = False) -> SequenceStateScore:
    """SA and SA-P of one sequence from its per-frame terms.

    Raises
    ------
    InputError
        No frame counts (every frame's label says the target exists but gives no box).
    """
    n = int(states.counted.sum())
    if n == 0:
        raise InputError(f"{name}: no frame to score (every labelled frame has exist = 1 but no box)")
    sa = float(states.accuracy[states.counted].mean())
    present = states.exist & states.counted
    miss_rate = float(states.missed[present].mean()) if present.any() else 0.0
    sa_p = sa - bench.penalty_weight * miss_rate ** bench.penalty_power
    return SequenceStateScore(name, sa, sa_p, miss_rate, n, missing)


def state_accuracy(pred: TargetFrames, truth: TargetFrames, bench: AntiUavBenchmark = ANTI_UAV,
                   name: str = "sequence") -> SequenceStateScore:
    """SA and SA-P of one track held in memory against its label (a single clip, a tracker's own check)."""
    return sequence_score(name, frame_states(pred, truth, bench.miss_iou), bench)


def failed_states(truth: TargetFrames) -> FrameStates:
    """The terms of a sequence without a result: accuracy 0 and every present target missed."""
    counted = ~truth.present | ~np.isnan(truth.boxes).any(axis=1)
    return FrameStates(np.zeros(len(truth)), truth.present & counted, counted, truth.present)


def metric_name(metric: str, modality: str, bench: AntiUavBenchmark) -> str:
    """Column name: ``SA`` / ``SA-P`` for the ranked modality, ``SA_RGB`` / ``SA-P_RGB`` for another."""
    return metric if modality == bench.modalities[0] else f"{metric}_{modality}"


@dataclass
class AntiUavScores:
    """A tracker's Anti-UAV scores: modality -> sequence -> score; ``summary`` in percent, averaged over sequences."""

    tracker: str
    benchmark: AntiUavBenchmark
    modalities: dict[str, dict[str, SequenceStateScore]]
    warnings: list[str] = field(default_factory=list)

    @property
    def sequences(self) -> dict[str, SequenceStateScore]:
        """The ranked modality's sequence scores."""
        return self.modalities.get(self.benchmark.modalities[0], {})

    @property
    def summary(self) -> dict[str, float]:
        out = {}
        for modality, scores in self.modalities.items():
            if scores:
                out[metric_name("SA", modality, self.benchmark)] = 100 * float(np.mean([s.sa for s in scores.values()]))
                out[metric_name("SA-P", modality, self.benchmark)] = 100 * float(
                    np.mean([s.sa_p for s in scores.values()]))
        return out

    def per_sequence(self) -> dict[str, dict[str, float]]:
        out: dict[str, dict[str, float]] = {}
        for modality, scores in self.modalities.items():
            for name, s in scores.items():
                row = out.setdefault(name, {})
                row[metric_name("SA", modality, self.benchmark)] = 100 * s.sa
                row[metric_name("SA-P", modality, self.benchmark)] = 100 * s.sa_p
        return out

    def attribute_scores(self) -> dict[str, dict[str, float]]:
        return {}
