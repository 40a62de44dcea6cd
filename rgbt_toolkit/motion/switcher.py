"""The tracker switcher of target motion prediction (TMP, paper Algorithm 1) as a pure state machine.

Per frame, the appearance tracker's result is kept when

    (q > q_hi and s_A > s_hi) or (q > q_low and s_A > s_low and s_A - s_M > t_diff) or max(s_A, s_M) < t_disable

and the motion tracker's (Kalman) prediction is used otherwise. Ours, before those clauses: the appearance result is
also kept when it agrees with the motion prediction (centres within half a target size, or within one standard
deviation of the Kalman prediction's own spread) and q has not collapsed (``SwitchThresholds.agree_offset``,
``agree_sigmas``, ``q_collapse``; docs/motion.md, "Agreeing candidates keep appearance").
Around it, the paper's model-updating scheme (Sec. III-C): in motion mode the appearance model (ECO) is not updated
and the Kalman filter is not corrected (it only predicts); in appearance mode both happen. Template matching is
skipped when ``q > 250`` (appearance is then used: "the appearance tracker is much more reliable"), and TMP is
suspended while drastic camera motion is detected (appearance, with the camera-compensated search region; the
authors' code still corrects the Kalman filter then).

All values here are on the paper's scales; :mod:`rgbt_toolkit.motion.calibration` maps our raw ``q`` and DDIS values
onto them (see ``docs/motion.md``). Inputs are plain numbers; no arrays, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.evaluation.metrics import centre_error

APPEARANCE = "appearance"
MOTION = "motion"


@dataclass(frozen=True)
class SwitchThresholds:
    """Algorithm 1's thresholds on the paper's scales (paper Sec. III-C, Implementation Details)."""

    q_hi: float = 210.0
    s_hi: float = 15.0
    q_low: float = 135.0
    s_low: float = 17.0
    t_diff: float = 3.0
    t_disable: float = 0.0  # not given in the paper; 0 turns the clause off (a flat occluder scores 0 too; docs)
    q_skip: float = 250.0  # "If q is higher than 250 ... we suspend the template matching processing"
    # ours (real footage, docs/motion.md "Agreeing candidates"): the appearance result is kept whenever its centre lies
    # within agree_offset x the target size (sqrt(w h)) of the motion prediction's and q has not collapsed (above
    # q_collapse, about 25 % of a sequence's early level, where a fully hidden target falls). Two windows that
    # overlap score alike, so Algorithm 1's s_A - s_M test cannot pick appearance there, and on real footage s_A
    # sits below s_low as the target's look drifts from frame 1: every such frame went to motion mode, where no
    # model learns, and the box drifted. agree_offset = 0 and agree_sigmas = 0 give the paper's Algorithm 1.
    agree_offset: float = 0.5
    q_collapse: float = 90.0
    # ours (real footage, small targets): the candidates also agree when their distance is within agree_sigmas x the
    # Kalman prediction's spread (ConstantVelocityKalman.spread, ~10.5 px with the paper's Q and R). The motion model
    # cannot place a target more finely than that, and half the size of a 9x6 px drone (3.7 px) is less than a
    # turning drone leaves its constant-velocity path in one frame. 0 turns it off.
    agree_sigmas: float = 1.0


PAPER_THRESHOLDS = SwitchThresholds()  # the paper's values, with our agreement clauses on (both 0: the paper's)


def use_appearance(q: float, s_a: float, s_m: float, th: SwitchThresholds = PAPER_THRESHOLDS,
                   offset: float | None = None, spread_offset: float | None = None) -> tuple[bool, str]:
    """Algorithm 1's test on paper-scale values; returns ``(keep the appearance result?, branch name)``.

    ``offset``: the distance between the appearance and the motion boxes' centres in units of the target size
    (:func:`candidate_offset`), when known; ``spread_offset``: the same distance in units of the Kalman prediction's
    spread (:meth:`~rgbt_toolkit.motion.kalman.ConstantVelocityKalman.spread`), when known. Branches: ``"agree"``
    (the two candidates agree by either measure and q has not collapsed; ours), ``"high"`` (q and s_A both high),
    ``"low_diff"`` (moderate q, s_A clearly above s_M), ``"disabled"`` (both similarities too low for template
    matching to mean anything), ``"motion"`` (none holds).
    """
    near = (offset is not None and th.agree_offset > 0 and offset <= th.agree_offset) or (
        spread_offset is not None and th.agree_sigmas > 0 and spread_offset <= th.agree_sigmas)
    if near and q > th.q_collapse:
        return True, "agree"
    if q > th.q_hi and s_a > th.s_hi:
        return True, "high"
    if q > th.q_low and s_a > th.s_low and (s_a - s_m) > th.t_diff:
        return True, "low_diff"
    if max(s_a, s_m) < th.t_disable:
        return True, "disabled"
    return False, "motion"


class Algorithm1Switch:
    """Callable ``(q, s_A, s_M, offset, spread_offset) -> bool`` (True keeps the appearance result), the form
    ``JmmacTracker`` takes."""

    def __init__(self, thresholds: SwitchThresholds = PAPER_THRESHOLDS) -> None:
        self.thresholds = thresholds

    def __call__(self, q: float, s_a: float, s_m: float, offset: float | None = None,
                 spread_offset: float | None = None) -> bool:
        return use_appearance(q, s_a, s_m, self.thresholds, offset, spread_offset)[0]


def candidate_offset(box_appearance, box_motion) -> float:
    """Distance between the two candidate boxes' centres (``[x, y, w, h]``) over the appearance box's size
    ``sqrt(w h)``: 0 when they coincide, 1 when they are one target size apart."""
    a, m = np.asarray(box_appearance, dtype=float), np.asarray(box_motion, dtype=float)
    return float(centre_error(a[None], m[None])[0] / np.sqrt(max(a[2] * a[3], 1e-12)))


@dataclass(frozen=True)
class SwitchDecision:
    """The switcher's verdict for one frame.

    Attributes
    ----------
    mode : str
        ``"appearance"`` or ``"motion"``: whose box is the frame's result.
    update_appearance : bool
        Update the appearance model (ECO) with this frame.
    correct_kalman : bool
        Correct the Kalman filter with the appearance result (otherwise it only predicts).
    reason : str
        The branch taken: ``no_kalman``, ``camera_motion``, ``q_skip``, ``agree``, ``high``, ``low_diff``,
        ``disabled``, ``motion``.
    template_matching : bool
        Whether s_A and s_M took part (False when they were not needed).
    """

    mode: str
    update_appearance: bool
    correct_kalman: bool
    reason: str
    template_matching: bool


class TrackerSwitcher:
    """Algorithm 1 with the model-updating rules. Per frame: :meth:`needs_template_matching`, then :meth:`decide`.

    The only state is bookkeeping for the harness: the number of consecutive frames in the current mode.
    """

    def __init__(self, thresholds: SwitchThresholds = PAPER_THRESHOLDS) -> None:
        self.thresholds = thresholds
        self.mode = APPEARANCE
        self.run_length = 0

    def reset(self) -> None:
        """A new sequence."""
        self.mode, self.run_length = APPEARANCE, 0

    def needs_template_matching(self, q: float, camera_motion: bool = False, kalman_ready: bool = True) -> bool:
        """Whether s_A and s_M must be computed this frame (not when q > q_skip, under camera motion, or before the
        Kalman filter exists)."""
        return kalman_ready and not camera_motion and q <= self.thresholds.q_skip

    def decide(
        self,
        q: float,
        s_a: float | None = None,
        s_m: float | None = None,
        *,
        camera_motion: bool = False,
        kalman_ready: bool = True,
        offset: float | None = None,
        spread_offset: float | None = None,
    ) -> SwitchDecision:
        """Choose the tracker for this frame from paper-scale values.

        Parameters
        ----------
        q : float
            MAX-PSR of the fused response.
        s_a, s_m : float, optional
            DDIS of the appearance and the motion windows against the first template; required when
            :meth:`needs_template_matching` is True.
        camera_motion : bool
            Drastic camera motion was detected and compensated this frame (TMP suspended).
        kalman_ready : bool
            The Kalman filter has been initialised (from frame 2 on, as in the authors' code).
        offset : float, optional
            :func:`candidate_offset` of the appearance and the motion boxes (enables the ``agree`` branch).
        spread_offset : float, optional
            Their centre distance over the Kalman prediction's spread (enables the ``agree`` branch too).
        """
        if not np.isfinite(q):
            raise InputError(f"q must be a finite number, got {q}")
        if not kalman_ready:
            decision = SwitchDecision(APPEARANCE, True, False, "no_kalman", False)
        elif camera_motion:
            decision = SwitchDecision(APPEARANCE, True, True, "camera_motion", False)
        elif q > self.thresholds.q_skip:
            decision = SwitchDecision(APPEARANCE, True, True, "q_skip", False)
        else:
            if s_a is None or s_m is None or not (np.isfinite(s_a) and np.isfinite(s_m)):
                raise InputError("s_A and s_M are needed when q <= q_skip; ask needs_template_matching() first")
            appearance, reason = use_appearance(q, s_a, s_m, self.thresholds, offset, spread_offset)
            decision = SwitchDecision(
                APPEARANCE if appearance else MOTION, appearance, appearance, reason, True
            )
        self.run_length = self.run_length + 1 if decision.mode == self.mode else 1
        self.mode = decision.mode
        return decision
