"""Motion cues of JMMAC: camera motion estimation (CME) and target motion prediction (TMP).

* :mod:`~rgbt_toolkit.motion.trigger`: the frame-difference test that decides when to estimate camera motion.
* :mod:`~rgbt_toolkit.motion.camera_motion`: SIFT + MSAC transform between thermal frames, compensation, shift sum.
* :mod:`~rgbt_toolkit.motion.kalman`: the constant-velocity Kalman filter (the motion tracker).
* :mod:`~rgbt_toolkit.motion.quality`: PSR and MAX-PSR reliability of a response map.
* :mod:`~rgbt_toolkit.motion.ddis`: Deformable Diversity Similarity for the template-matching scores s_A, s_M.
* :mod:`~rgbt_toolkit.motion.switcher`: Algorithm 1 (appearance vs motion tracker) and the model-updating rules.
* :mod:`~rgbt_toolkit.motion.calibration`: our raw q and DDIS values mapped onto the paper's scales.
* :mod:`~rgbt_toolkit.motion.parts`: the parts in the forms ``JmmacTracker`` takes (``build_motion_parts``).
"""

from rgbt_toolkit.motion.camera_motion import (
    FAST_CAMERA_MOTION,
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
from rgbt_toolkit.motion.calibration import CalibrationSettings, ScoreCalibrator, geometry_q_scale, jitter_boxes
from rgbt_toolkit.motion.parts import DdisTemplateScorer, PaperScaleQuality, backbone_features, build_motion_parts
from rgbt_toolkit.motion.switcher import (
    APPEARANCE,
    MOTION,
    PAPER_THRESHOLDS,
    Algorithm1Switch,
    SwitchDecision,
    SwitchThresholds,
    TrackerSwitcher,
    use_appearance,
)
from rgbt_toolkit.motion.trigger import CameraMotionTrigger, TriggerResult, TriggerSettings

__all__ = [
    "APPEARANCE",
    "Algorithm1Switch",
    "CalibrationSettings",
    "CameraMotion",
    "CameraMotionCompensation",
    "CameraMotionEstimator",
    "CameraMotionSettings",
    "CameraMotionStep",
    "CameraMotionTrigger",
    "CameraShiftAccumulator",
    "ConstantVelocityKalman",
    "DdisTemplateScorer",
    "FAST_CAMERA_MOTION",
    "KalmanSettings",
    "MOTION",
    "MOTION_MODELS",
    "PAPER_THRESHOLDS",
    "PaperScaleQuality",
    "ScoreCalibrator",
    "SwitchDecision",
    "SwitchThresholds",
    "TemplateMatcher",
    "TrackerSwitcher",
    "TriggerResult",
    "TriggerSettings",
    "apply_transform",
    "backbone_features",
    "box_centre",
    "build_motion_parts",
    "colour_patch_features",
    "compensate_box",
    "compensate_position",
    "crop_window",
    "ddis_score",
    "geometry_q_scale",
    "ideal_max_psr",
    "jitter_boxes",
    "max_psr",
    "psr",
    "use_appearance",
]
