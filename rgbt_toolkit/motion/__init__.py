"""Motion cues of JMMAC: camera motion estimation (CME) and target motion prediction (TMP).

* :mod:`~rgbt_toolkit.motion.trigger`: the frame-difference test that decides when to estimate camera motion.
* :mod:`~rgbt_toolkit.motion.camera_motion`: SIFT + MSAC transform between thermal frames, compensation, shift sum.
* :mod:`~rgbt_toolkit.motion.kalman`: the constant-velocity Kalman filter (the motion tracker).
* :mod:`~rgbt_toolkit.motion.quality`: PSR and MAX-PSR reliability of a response map.
* :mod:`~rgbt_toolkit.motion.ddis`: Deformable Diversity Similarity for the template-matching scores s_A, s_M.
* :mod:`~rgbt_toolkit.motion.switcher`: Algorithm 1 (appearance vs motion tracker) with score calibration.
"""

from rgbt_toolkit.motion.camera_motion import (
    MOTION_MODELS,
    CameraMotion,
    CameraMotionCompensation,
    CameraMotionEstimator,
    CameraMotionSettings,
    CameraMotionStep,
    CameraShiftAccumulator,
    apply_transform,
    box_centre,
    compensate_box,
    compensate_position,
)
from rgbt_toolkit.motion.ddis import TemplateMatcher, colour_patch_features, crop_window, ddis_score
from rgbt_toolkit.motion.kalman import ConstantVelocityKalman, KalmanSettings
from rgbt_toolkit.motion.quality import ideal_max_psr, max_psr, psr
from rgbt_toolkit.motion.switcher import (
    APPEARANCE,
    MOTION,
    PAPER_THRESHOLDS,
    CalibrationSettings,
    SwitchDecision,
    SwitchThresholds,
    TrackerSwitcher,
    geometry_q_scale,
    ratio_scales,
    use_appearance,
)
from rgbt_toolkit.motion.trigger import CameraMotionTrigger, TriggerResult, TriggerSettings

__all__ = [
    "APPEARANCE",
    "MOTION",
    "MOTION_MODELS",
    "PAPER_THRESHOLDS",
    "CalibrationSettings",
    "CameraMotion",
    "CameraMotionCompensation",
    "CameraMotionEstimator",
    "CameraMotionSettings",
    "CameraMotionStep",
    "CameraMotionTrigger",
    "CameraShiftAccumulator",
    "ConstantVelocityKalman",
    "KalmanSettings",
    "SwitchDecision",
    "SwitchThresholds",
    "TemplateMatcher",
    "TrackerSwitcher",
    "TriggerResult",
    "TriggerSettings",
    "apply_transform",
    "box_centre",
    "colour_patch_features",
    "compensate_box",
    "compensate_position",
    "crop_window",
    "ddis_score",
    "geometry_q_scale",
    "ideal_max_psr",
    "max_psr",
    "psr",
    "ratio_scales",
    "use_appearance",
]
