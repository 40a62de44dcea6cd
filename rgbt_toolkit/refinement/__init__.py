"""Bounding-box refinement on the visible frame (JMMAC Sec. III-C), behind the pipeline's ``BoxRefiner`` protocol.

>>> from rgbt_toolkit.refinement import make_refiner
>>> refiner = make_refiner()                       # frame-1 box regressor, no third-party weights
>>> refiner.initialize(rgb0, box0)                 # HxWx3 uint8 RGB, [x, y, w, h]
>>> refiner.refine(rgb, box)                       # tighter box, or None (disabled / no acceptable correction)
>>> make_refiner("detector", "FastestDet.onnx")    # a user-supplied YOLO-family ONNX detector instead
"""

from rgbt_toolkit.refinement.detector import Detections, Detector, MissingDependencyError, OnnxYoloDetector
from rgbt_toolkit.refinement.detector_refiner import DetectorRefiner, DetectorRefinerSettings
from rgbt_toolkit.refinement.factory import REFINER_KINDS, make_refiner
from rgbt_toolkit.refinement.regressor import RegressionRefiner, RegressorSettings
from rgbt_toolkit.refinement.sanity import SanityLimits, check_correction

__all__ = [
    "REFINER_KINDS",
    "Detections",
    "Detector",
    "DetectorRefiner",
    "DetectorRefinerSettings",
    "MissingDependencyError",
    "OnnxYoloDetector",
    "RegressionRefiner",
    "RegressorSettings",
    "SanityLimits",
    "check_correction",
    "make_refiner",
]
