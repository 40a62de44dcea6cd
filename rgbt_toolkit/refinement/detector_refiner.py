"""Box refinement by a class-agnostic detector, with the authors' acceptance rules (public JMMAC code).

On frame 1 the detector must find the target confidently (conf > 0.83 with IoU > 0.73, or conf > 0.95) and the target
must not be over-bright; otherwise refinement stays off for the whole sequence. On later frames the detector runs in
a square region the size of the ECO sample around the tracker's box (1.2x larger when occluded), and the most
confident box that contains the region centre and passes the sanity limits replaces the tracker's box.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rgbt_toolkit.refinement.boxes import as_box, centres, iou
from rgbt_toolkit.refinement.detector import Detections, Detector
from rgbt_toolkit.refinement.regressor import as_rgb, patch_brightness
from rgbt_toolkit.refinement.sanity import SanityLimits, check_correction


@dataclass(frozen=True)
class DetectorRefinerSettings:
    """Acceptance rules; all values from the authors' public code unless noted."""

    min_conf: float = 0.615  # per frame: detections below this confidence are ignored
    search_scale: float = 4.0  # region side = 4 x sqrt(w h): ECO's square search area (search_area_scale 4.0)
    occluded_scale: float = 1.2  # region grown 1.2x while the target is occluded
    init_conf: float = 0.83  # frame 1: enable when conf > 0.83 and IoU > 0.73 ...
    init_iou: float = 0.73
    init_conf_alone: float = 0.95  # ... or conf > 0.95 whatever the IoU
    require_initial_detection: bool = True  # ours: False skips the frame-1 test (e.g. a detector trained on the target)
    max_brightness: float = 185.0  # frame 1: disable when the 2x patch's mean grey is >= 185
    limits: SanityLimits = field(default_factory=SanityLimits)


def search_region(box: np.ndarray, scale: float) -> np.ndarray:
    """Square region of side ``scale * sqrt(w h)`` centred on ``box``."""
    side = scale * float(np.sqrt(box[2] * box[3]))
    return np.concatenate([centres(box) - (side - 1) / 2, [side, side]])


def contains_point(boxes: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Which ``(N, 4)`` boxes cover ``point`` (continuous extents, pixel-centre coordinates)."""
    boxes = np.atleast_2d(boxes)
    lo, hi = boxes[:, :2] - 0.5, boxes[:, :2] + boxes[:, 2:] - 0.5
    return np.all((lo <= point) & (point <= hi), axis=1)


class DetectorRefiner:
    """:class:`~rgbt_toolkit.jmmac.parts.BoxRefiner` that snaps the tracker's box to a confident detection.

    Parameters
    ----------
    detector : Detector
        Any object with ``detect(image, region) -> Detections``, e.g. :class:`OnnxYoloDetector`.
    settings : DetectorRefinerSettings

    Attributes
    ----------
    enabled : bool
        Whether frame 1 allowed refinement; ``disabled_reason`` says why not.
    last_reason : str or None
        Why the last :meth:`refine` returned None.
    last_detections : Detections or None
        What the detector returned on the last call (for overlays and debugging).
    """

    def __init__(self, detector: Detector, settings: DetectorRefinerSettings = DetectorRefinerSettings()):
        self.detector, self.settings = detector, settings
        self.enabled = False
        self.disabled_reason: str | None = "not initialised"
        self.last_reason: str | None = None
        self.last_detections: Detections | None = None

    def initialize(self, rgb: np.ndarray, box: np.ndarray) -> None:
        """Decide on frame 1 whether the detector sees the target well enough to be trusted."""
        s = self.settings
        image, box = as_rgb(rgb), as_box(box, "initial box")
        self.enabled, self.disabled_reason = False, None
        brightness = patch_brightness(image, box)
        if not brightness < s.max_brightness:
            self.disabled_reason = f"target over-bright (mean grey {brightness:.0f} >= {s.max_brightness})"
            return
        if s.require_initial_detection:
            det = self.detector.detect(image, search_region(box, s.search_scale))
            self.last_detections = det
            if not len(det):
                self.disabled_reason = "the detector finds nothing around the target on frame 1"
                return
            overlap = iou(det.boxes, box)
            ok = ((det.scores > s.init_conf) & (overlap > s.init_iou)) | (det.scores > s.init_conf_alone)
            if not ok.any():
                best = int(np.argmax(overlap))
                self.disabled_reason = (f"the detector is not confident on the target on frame 1 (best match conf "
                                        f"{det.scores[best]:.2f}, IoU {overlap[best]:.2f})")
                return
        self.enabled = True

    def refine(self, rgb: np.ndarray, box: np.ndarray, occluded: bool = False) -> np.ndarray | None:
        """The most confident acceptable detection around ``box``, or None."""
        s = self.settings
        self.last_reason, self.last_detections = None, None
        if not self.enabled:
            self.last_reason = f"disabled: {self.disabled_reason}"
            return None
        image, box = as_rgb(rgb), as_box(box)
        scale = s.search_scale * (s.occluded_scale if occluded else 1.0)
        region = search_region(box, scale)
        det = self.detector.detect(image, region)
        self.last_detections = det
        candidates = np.flatnonzero((det.scores > s.min_conf) & contains_point(det.boxes, centres(region)))
        if not len(candidates):
            self.last_reason = "no confident detection on the target"
            return None
        reasons = []
        for i in candidates[np.argsort(-det.scores[candidates], kind="stable")]:
            why = check_correction(box, det.boxes[i], s.limits, occluded)
            if why is None:
                return det.boxes[i].astype(float).copy()
            reasons.append(why)
        self.last_reason = f"detections rejected: {reasons[0]}"
        return None
