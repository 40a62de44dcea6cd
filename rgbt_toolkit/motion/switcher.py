"""The tracker switcher of target motion prediction (TMP, paper Algorithm 1) as a pure state machine.

Per frame, the appearance tracker's result is kept when

    (q > q_hi and s_A > s_hi) or (q > q_low and s_A > s_low and s_A - s_M > t_diff) or max(s_A, s_M) < t_disable

and the motion tracker's (Kalman) prediction is used otherwise. Around it, the paper's model-updating scheme:
in motion mode the appearance model (ECO) is not updated and the Kalman filter is not corrected (it only predicts);
in appearance mode both happen. Template matching is skipped when ``q > 250`` (appearance is then used), and TMP is
suspended while drastic camera motion is detected (appearance, with the camera-compensated search region).

The thresholds are on the paper's scales; :class:`ScoreCalibration` maps our raw ``q`` and DDIS values onto them
(see ``docs/motion.md`` for the reasoning). Inputs here are raw numbers; no arrays, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.quality import ideal_max_psr

APPEARANCE = "appearance"
MOTION = "motion"

# ECO's response geometry in the paper: search area 4x the target side, label sigma = target side / 12
# (output_sigma_factor 1/12), hence map side / sigma = 48 whatever the cell size.
PAPER_MAP_SIDE_OVER_SIGMA = 48.0


@dataclass(frozen=True)
class SwitchThresholds:
    """Algorithm 1's thresholds on the paper's scales (paper Sec. III-C, Implementation Details)."""

    q_hi: float = 210.0
    s_hi: float = 15.0
    q_low: float = 135.0
    s_low: float = 17.0
    t_diff: float = 3.0
    t_disable: float = 2.0  # not given in the paper; ours: both windows below 2 % DDIS = template matching is blind
    q_skip: float = 250.0  # "If q is higher than 250 ... we suspend the template matching"


PAPER_THRESHOLDS = SwitchThresholds()

CALIBRATION_METHODS = ("ratio", "geometry", "fixed")


@dataclass(frozen=True)
class CalibrationSettings:
    """How raw ``q`` and DDIS values are put on the paper's scales.

    ``ratio`` (default): per sequence, the median of the first ``warmup_frames`` appearance-mode values is mapped onto
    ``q_reference`` / ``s_reference``, the paper-scale levels of a reliably tracked target; the thresholds then act
    as relative drops (q_hi = 70 %, q_low = 45 %, q_skip = 83 % of the early level; s_hi = 60 %, s_low = 68 %).
    ``geometry``: ``q`` is scaled by the ratio of ideal MAX-PSR of the paper's response geometry to ours
    (``q_scale``, from :func:`geometry_q_scale`) and DDIS by ``s_scale``; no warm-up statistics.
    ``fixed``: both scales as given.
    """

    method: str = "ratio"
    warmup_frames: int = 5  # frames after the first in which appearance is trusted and statistics are collected
    q_reference: float = 300.0  # ours: typical paper-scale q of a confident frame (above q_skip = 250)
    s_reference: float = 25.0  # ours: typical paper-scale s_A of a confident frame (above s_low = 17)
    q_scale: float = 1.0  # used by "geometry" and "fixed"
    s_scale: float = 1.0  # used by "geometry" and "fixed"
    scale_limits: tuple[float, float] = (0.02, 50.0)  # ratio scales are clipped to this range

    def __post_init__(self) -> None:
        if self.method not in CALIBRATION_METHODS:
            raise InputError(f"unknown calibration method {self.method!r}; choose {', '.join(CALIBRATION_METHODS)}")
        if self.warmup_frames < 0 or self.q_scale <= 0 or self.s_scale <= 0:
            raise InputError("calibration: warmup_frames must be >= 0 and the scales > 0")


def geometry_q_scale(response_shape: tuple[int, int], label_sigma: float) -> float:
    """Factor taking our variance-form ``q`` to the paper's scale from the two trackers' response geometries.

    ``q`` is amplitude-free and grows with (map area) / (peak area); the ideal value of a map of ``response_shape``
    with a Gaussian label of std ``label_sigma`` cells is compared with the paper's ECO geometry (side / sigma = 48).
    """
    side = float(np.sqrt(response_shape[0] * response_shape[1]))
    n = max(int(round(side)), 8)
    paper = ideal_max_psr((n, n), n / PAPER_MAP_SIDE_OVER_SIGMA)
    ours = ideal_max_psr(tuple(int(v) for v in response_shape), label_sigma)
    return paper / ours


def ratio_scales(
    q_samples: list[float], s_samples: list[float], settings: CalibrationSettings = CalibrationSettings()
) -> tuple[float, float]:
    """``(q_scale, s_scale)`` that map the samples' medians onto the reference levels (the ``ratio`` method)."""
    lo, hi = settings.scale_limits

    def scale(samples: list[float], reference: float) -> float:
        values = np.asarray([v for v in samples if v is not None and np.isfinite(v)], dtype=np.float64)
        level = float(np.median(values)) if values.size else 0.0
        return float(np.clip(reference / level, lo, hi)) if level > 0 else 1.0

    return scale(q_samples, settings.q_reference), scale(s_samples, settings.s_reference)


def use_appearance(q: float, s_a: float, s_m: float, th: SwitchThresholds = PAPER_THRESHOLDS) -> tuple[bool, str]:
    """Algorithm 1's test on paper-scale values; returns ``(appearance?, branch name)``."""
    if q > th.q_hi and s_a > th.s_hi:
        return True, "high"
    if q > th.q_low and s_a > th.s_low and (s_a - s_m) > th.t_diff:
        return True, "low_diff"
    if max(s_a, s_m) < th.t_disable:
        return True, "disabled"
    return False, "motion"


@dataclass(frozen=True)
class SwitchDecision:
    """The switcher's verdict for one frame.

    ``mode`` is ``"appearance"`` or ``"motion"``; ``update_appearance``: update ECO this frame; ``correct_kalman``:
    correct the Kalman filter with the appearance result (otherwise it only predicts); ``reason``: the branch taken
    (``no_kalman``, ``warmup``, ``camera_motion``, ``q_skip``, ``high``, ``low_diff``, ``disabled``, ``motion``);
    ``q``, ``s_a``, ``s_m``: the values on the paper's scales (``None`` where template matching was skipped).
    """

    mode: str
    update_appearance: bool
    correct_kalman: bool
    reason: str
    q: float
    s_a: float | None = None
    s_m: float | None = None


@dataclass
class TrackerSwitcher:
    """Algorithm 1 with calibration state. Call :meth:`needs_template_matching`, then :meth:`decide`, every frame.

    The first frame (initialisation) is not passed in. During the first ``warmup_frames`` frames the appearance
    result is always used while raw ``q`` and ``s_A`` are collected for the ``ratio`` calibration.
    """

    thresholds: SwitchThresholds = PAPER_THRESHOLDS
    calibration: CalibrationSettings = field(default_factory=CalibrationSettings)
    _q_samples: list[float] = field(default_factory=list, init=False)
    _s_samples: list[float] = field(default_factory=list, init=False)
    _scales: tuple[float, float] | None = field(default=None, init=False)

    def __post_init__(self) -> None:
        if self.calibration.method != "ratio" or self.calibration.warmup_frames == 0:
            self._scales = (self.calibration.q_scale, self.calibration.s_scale)

    def reset(self) -> None:
        """Forget the calibration (a new sequence)."""
        self._q_samples.clear()
        self._s_samples.clear()
        self._scales = None
        self.__post_init__()

    @property
    def calibrated(self) -> bool:
        """True once the scales are known (after the warm-up with the ``ratio`` method)."""
        return self._scales is not None

    @property
    def scales(self) -> tuple[float, float]:
        """``(q_scale, s_scale)`` in use (1, 1 during warm-up)."""
        return self._scales if self._scales is not None else (1.0, 1.0)

    def paper_q(self, q_raw: float) -> float:
        """Raw ``q`` on the paper's scale."""
        return float(q_raw) * self.scales[0]

    def paper_s(self, s_raw: float | None) -> float | None:
        """Raw DDIS on the paper's scale."""
        return None if s_raw is None else float(s_raw) * self.scales[1]

    def needs_template_matching(self, q_raw: float, camera_motion: bool = False) -> bool:
        """Whether ``s_A`` and ``s_M`` must be computed this frame (False when ``q > q_skip`` or camera motion)."""
        if camera_motion:
            return False
        if not self.calibrated:
            return True
        return self.paper_q(q_raw) <= self.thresholds.q_skip

    def decide(
        self,
        q_raw: float,
        s_a_raw: float | None = None,
        s_m_raw: float | None = None,
        *,
        camera_motion: bool = False,
        kalman_ready: bool = True,
    ) -> SwitchDecision:
        """Choose the tracker for this frame.

        Parameters
        ----------
        q_raw : float
            MAX-PSR of the (fused) response map, our scale.
        s_a_raw, s_m_raw : float, optional
            DDIS of the appearance and the motion windows against the first template, our scale; required when
            :meth:`needs_template_matching` said so.
        camera_motion : bool
            Drastic camera motion was detected and compensated this frame (TMP suspended).
        kalman_ready : bool
            The Kalman filter has been initialised (it is from frame 2 on, as in the authors' code).
        """
        if not np.isfinite(q_raw):
            raise InputError(f"q must be finite, got {q_raw}")
        if not kalman_ready:
            return SwitchDecision(APPEARANCE, True, False, "no_kalman", self.paper_q(q_raw))
        if camera_motion:
            return SwitchDecision(APPEARANCE, True, True, "camera_motion", self.paper_q(q_raw))
        if not self.calibrated:
            self._q_samples.append(float(q_raw))
            if s_a_raw is not None:
                self._s_samples.append(float(s_a_raw))
            decision = SwitchDecision(APPEARANCE, True, True, "warmup", q_raw, s_a_raw, s_m_raw)
            if len(self._q_samples) >= self.calibration.warmup_frames:
                self._scales = ratio_scales(self._q_samples, self._s_samples, self.calibration)
            return decision
        q = self.paper_q(q_raw)
        if q > self.thresholds.q_skip:
            return SwitchDecision(APPEARANCE, True, True, "q_skip", q)
        if s_a_raw is None or s_m_raw is None:
            raise InputError("s_A and s_M are needed when q <= q_skip; call needs_template_matching() first")
        s_a, s_m = self.paper_s(s_a_raw), self.paper_s(s_m_raw)
        appearance, reason = use_appearance(q, s_a, s_m, self.thresholds)
        if appearance:
            return SwitchDecision(APPEARANCE, True, True, reason, q, s_a, s_m)
        return SwitchDecision(MOTION, False, False, reason, q, s_a, s_m)
