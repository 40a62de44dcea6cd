"""Our raw ``q`` (MAX-PSR) and DDIS values put on the paper's scales, so Algorithm 1's thresholds keep their meaning.

Why a calibration is needed (details in ``docs/motion.md``):

* ``q = PSR_var * max`` is free of the response's amplitude but grows with (map area) / (peak area), so it depends on
  the response grid, the label width, the features and the fusion; our ECO and MFNet are not the authors'.
* Our DDIS is on a 0-100 scale (100 = the template itself) with our features, not the authors' VGG-19.

Methods:

* ``q`` ``"running"`` (default): per sequence, ``q_scale = q_reference / median(raw q of the frames seen so far)``
  during the first ``warmup_frames`` frames after initialisation, then frozen. The target is assumed well tracked
  right after initialisation, and that level is mapped onto ``q_reference`` (350, above the skip level 250); the
  thresholds then act as relative drops: q_skip 250 = 71 %, q_hi 210 = 60 %, q_low 135 = 39 % of the early level.
* ``q`` ``"geometry"``: ``q_scale`` from :func:`geometry_q_scale`, the ratio of the ideal MAX-PSR of the paper's ECO
  response geometry (search side / label sigma = 48) to ours. No statistics, but ignores feature/fusion differences.
* ``s`` ``"jitter"`` (default): at initialisation, the first-frame template is scored against the first frame's own
  windows jittered like tracking noise (+-4 % shifts, +-5 % scale); ``s_scale = s_reference / median`` maps that
  level onto ``s_reference`` (48, about what the default deep features give unscaled, so on average nothing
  changes while per-sequence differences in how distinctive the target is are evened out).
* ``"fixed"``: the given ``q_scale`` / ``s_scale`` (e.g. fitted offline on labelled sequences).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.quality import ideal_max_psr

# ECO's response geometry in the paper: square search area 4x the target side, label sigma = side / 12
# (output_sigma_factor 1/12), hence map side / sigma = 48 whatever the feature cell size.
PAPER_MAP_SIDE_OVER_SIGMA = 48.0

Q_METHODS = ("running", "geometry", "fixed")
S_METHODS = ("jitter", "fixed")


@dataclass(frozen=True)
class CalibrationSettings:
    """How raw values are mapped onto the paper's scales; the reference levels are ours (the paper gives none)."""

    q_method: str = "running"
    s_method: str = "jitter"
    warmup_frames: int = 10  # frames after the first whose q sets the running scale
    q_reference: float = 350.0  # paper-scale q of the first frames (skip 250 = 71 %, q_hi = 60 %, q_low = 39 %)
    s_reference: float = 48.0  # paper-scale DDIS of correctly placed (jittered) first-frame windows
    q_scale: float = 1.0  # for "geometry" (computed by the caller with geometry_q_scale) and "fixed"
    s_scale: float = 1.0  # for "fixed"
    jitter_shift: float = 0.04  # jitter windows: shift as a fraction of the box size
    jitter_scale: float = 0.05  # ... and relative size change
    scale_limits: tuple[float, float] = (0.02, 50.0)  # measured scales are clipped to this range

    def __post_init__(self) -> None:
        if self.q_method not in Q_METHODS:
            raise InputError(f"unknown q calibration {self.q_method!r}; choose {', '.join(Q_METHODS)}")
        if self.s_method not in S_METHODS:
            raise InputError(f"unknown s calibration {self.s_method!r}; choose {', '.join(S_METHODS)}")
        if self.warmup_frames < 1 or self.q_scale <= 0 or self.s_scale <= 0:
            raise InputError("calibration: warmup_frames must be >= 1 and the scales > 0")


def geometry_q_scale(response_shape: tuple[int, int], label_sigma: float) -> float:
    """Factor taking our variance-form ``q`` to the paper's scale from the two response geometries.

    Parameters
    ----------
    response_shape : (int, int)
        Our response grid.
    label_sigma : float
        Standard deviation of our tracker's Gaussian label, in grid cells.
    """
    side = float(np.sqrt(response_shape[0] * response_shape[1]))
    n = max(int(round(side)), 8)
    paper = ideal_max_psr((n, n), n / PAPER_MAP_SIDE_OVER_SIGMA)
    ours = ideal_max_psr((int(response_shape[0]), int(response_shape[1])), label_sigma)
    return paper / ours


def jitter_boxes(box: np.ndarray, shift: float = 0.04, scale: float = 0.05) -> np.ndarray:
    """Six boxes around ``box``: shifted by ``+-shift`` of its size along x and y, and resized by ``1 +- scale``."""
    box = np.asarray(box, dtype=np.float64)
    x, y, w, h = box
    cx, cy = x + (w - 1) / 2, y + (h - 1) / 2
    out = [box + [dx * w, dy * h, 0, 0] for dx, dy in ((shift, 0), (-shift, 0), (0, shift), (0, -shift))]
    for f in (1 + scale, 1 - scale):
        out.append(np.array([cx - (w * f - 1) / 2, cy - (h * f - 1) / 2, w * f, h * f]))
    return np.stack(out)


def _robust_scale(samples: Sequence[float], reference: float, limits: tuple[float, float]) -> float:
    values = np.asarray([v for v in samples if np.isfinite(v)], dtype=np.float64)
    level = float(np.median(values)) if values.size else 0.0
    return float(np.clip(reference / level, *limits)) if level > 0 else 1.0


class ScoreCalibrator:
    """Per-sequence state of the calibration, shared by the quality measure and the template scorer."""

    def __init__(self, settings: CalibrationSettings = CalibrationSettings()) -> None:
        self.settings = settings
        self._q_samples: list[float] = []
        self._q_scale_frozen: float | None = None  # the running scale once the warm-up is over (it no longer moves)
        self._s_scale: float | None = None

    def reset(self) -> None:
        """A new sequence."""
        self._q_samples.clear()
        self._q_scale_frozen = None
        self._s_scale = None

    @property
    def q_scale(self) -> float:
        """The current factor raw q -> paper q."""
        s = self.settings
        if s.q_method != "running":
            return s.q_scale
        if self._q_scale_frozen is not None:  # a median of the warm-up per frame cost 0.6 ms of the tracking thread
            return self._q_scale_frozen
        scale = _robust_scale(self._q_samples, s.q_reference, s.scale_limits) if self._q_samples else 1.0
        if self.q_frozen:
            self._q_scale_frozen = scale
        return scale

    @property
    def s_scale(self) -> float:
        """The factor raw DDIS -> paper DDIS (1 until :meth:`set_template_baseline` when ``s_method="jitter"``)."""
        if self.settings.s_method == "fixed":
            return self.settings.s_scale
        return self._s_scale if self._s_scale is not None else 1.0

    @property
    def q_frozen(self) -> bool:
        """True once the running q scale no longer changes."""
        return self.settings.q_method != "running" or len(self._q_samples) >= self.settings.warmup_frames

    def paper_q(self, q_raw: float, observe: bool = True) -> float:
        """Raw q on the paper's scale; during the warm-up ``observe`` adds it to the running statistics first."""
        if observe and not self.q_frozen and np.isfinite(q_raw):
            self._q_samples.append(float(q_raw))
        return float(q_raw) * self.q_scale

    def set_template_baseline(self, scores: Sequence[float]) -> float:
        """Fix ``s_scale`` from DDIS scores of correctly placed (jittered) first-frame windows; returns it."""
        s = self.settings
        self._s_scale = _robust_scale(scores, s.s_reference, s.scale_limits)
        return self._s_scale

    def paper_s(self, s_raw: float) -> float:
        """Raw DDIS on the paper's scale."""
        return float(s_raw) * self.s_scale

    def calibrate_template(self, score_window: Callable[[np.ndarray], float], box: np.ndarray) -> float:
        """Score the jittered first-frame windows with ``score_window(box) -> raw DDIS`` and set ``s_scale``."""
        s = self.settings
        scores = [score_window(b) for b in jitter_boxes(box, s.jitter_shift, s.jitter_scale)]
        return self.set_template_baseline(scores)
