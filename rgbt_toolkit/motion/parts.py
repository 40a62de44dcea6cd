"""Ready-made motion parts in the forms :class:`rgbt_toolkit.jmmac.pipeline.JmmacTracker` takes.

``build_motion_parts(...)`` returns the ``camera_motion``, ``kalman``, ``quality``, ``template`` and ``switch``
keyword arguments of the tracker, sharing one :class:`~rgbt_toolkit.motion.calibration.ScoreCalibrator` so that ``q``
and ``s_A``, ``s_M`` arrive on the paper's scales.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.calibration import CalibrationSettings, ScoreCalibrator
from rgbt_toolkit.motion.camera_motion import CameraMotionCompensation, CameraMotionSettings
from rgbt_toolkit.motion.ddis import TemplateMatcher, colour_patch_features, crop_window
from rgbt_toolkit.motion.kalman import ConstantVelocityKalman, KalmanSettings
from rgbt_toolkit.motion.quality import max_psr
from rgbt_toolkit.motion.template import ModalityAwareTemplate
from rgbt_toolkit.motion.switcher import PAPER_THRESHOLDS, Algorithm1Switch, SwitchThresholds
from rgbt_toolkit.motion.trigger import TriggerSettings

FeatureFn = Callable[[np.ndarray], np.ndarray]


def backbone_features(backbone: str = "efficientnet-lite0", layer: str = "shallow", weights=None) -> FeatureFn:
    """A ``patch -> H x W x C`` feature function from one layer of a registered backbone (loaded on first use).

    For DDIS on deep features as the paper does (VGG-19 there); use it with ``normalize_features=True`` and a
    template area that gives a grid of 12-24 cells per side at the layer's stride (48x48 px at stride 4: 12x12).
    The network is loaded on first use and shared through :func:`rgbt_toolkit.backbones.load_backbone`'s cache.
    """

    from rgbt_toolkit.fusion.onnx_model import SHIPPED_LAYERS, shipped_layers

    if weights is None and (backbone, (layer,)) in SHIPPED_LAYERS:
        def shipped(patch: np.ndarray) -> np.ndarray:  # the shipped export (loaded on first use): no torch import
            return shipped_layers(backbone, (layer,))(patch)

        return shipped

    def features(patch: np.ndarray) -> np.ndarray:
        import torch

        from rgbt_toolkit.backbones import load_backbone

        net = load_backbone(backbone, weights)
        img = np.repeat(patch[..., None], 3, axis=-1) if patch.ndim == 2 else patch
        x = torch.from_numpy(np.ascontiguousarray(img)).permute(2, 0, 1)[None].float().div_(255.0)
        with torch.no_grad():
            out = net.extract(x, (layer,))[layer]
        return out[0].permute(1, 2, 0).numpy().astype(np.float64)

    return features


class PaperScaleQuality:
    """``response -> q`` on the paper's scale: MAX-PSR (variance form by default), then the calibrator's scale.

    Also keeps the last raw value in ``last_raw`` for logging.
    """

    def __init__(self, calibrator: ScoreCalibrator, form: str = "var") -> None:
        self.calibrator = calibrator
        self.form = form
        self.last_raw = float("nan")

    def __call__(self, response) -> float:
        self.last_raw = max_psr(response, self.form)
        return self.calibrator.paper_q(self.last_raw)


def template_patch_size(box: np.ndarray, area: float) -> tuple[int, int]:
    """``(width, height)`` with the box's aspect ratio and about ``area`` pixels, each side a multiple of 4 (the
    stride of the deep DDIS layer, whose ONNX export needs it) and at least 8."""
    w, h = float(box[2]), float(box[3])
    f = np.sqrt(area / (w * h))
    return max(4 * int(round(w * f / 4)), 8), max(4 * int(round(h * f / 4)), 8)


class DdisTemplateScorer:
    """The ``TemplateScorer`` part: DDIS of the appearance and motion windows against the first-frame RGB template.

    Parameters
    ----------
    calibrator : ScoreCalibrator
        Receives the jittered first-frame baseline (``s_method="jitter"``) and scales the scores.
    features : callable or "deep" or "colour"
        ``patch (h, w, 3) uint8 -> H x W x C`` features. ``"deep"`` (default): EfficientNet-Lite0's stride-4 layer
        (:func:`backbone_features`), deep features as the paper's DDIS (VGG-19 there). ``"colour"``: 3x3 colour cells
        (:func:`colour_patch_features`, the DDIS paper's hand-made features; no network, but on noisy or weakly
        textured targets they separate a visible from an occluded target far less well, see ``docs/motion.md``).
    template_area : float
        Windows are resampled to the first box's aspect ratio with about this many pixels (48x48 by default), which
        fixes the DDIS grid (16x16 cells with the default features).
    normalize_features : bool, optional
        Cosine instead of Euclidean nearest neighbours; default True for ``"deep"``, False otherwise.
    """

    def __init__(
        self,
        calibrator: ScoreCalibrator,
        features: FeatureFn | str = "deep",
        template_area: float = 48.0 * 48.0,
        normalize_features: bool | None = None,
    ) -> None:
        self.calibrator = calibrator
        if features == "deep":
            self.features = backbone_features()
        elif features == "colour":
            self.features = colour_patch_features
        elif callable(features):
            self.features = features
        else:
            raise InputError(f"DDIS features must be 'deep', 'colour' or a function, got {features!r}")
        if normalize_features is None:
            normalize_features = features == "deep"
        self.template_area = template_area
        self.normalize_features = normalize_features
        self._matcher: TemplateMatcher | None = None
        self._size: tuple[int, int] | None = None
        self.last_raw: tuple[float, float] = (float("nan"), float("nan"))

    def _window(self, rgb: np.ndarray, box: np.ndarray) -> np.ndarray:
        return self.features(crop_window(rgb, box, self._size))

    def initialize(self, rgb: np.ndarray, box: np.ndarray) -> None:
        """Store ``T_1``'s features and calibrate the score scale on jittered first-frame windows.

        A new sequence starts here, so the shared calibrator is reset (the running ``q`` scale too).
        """
        box = np.asarray(box, dtype=np.float64)
        self.calibrator.reset()
        self._size = template_patch_size(box, self.template_area)
        self._matcher = TemplateMatcher(self._window(rgb, box), self.normalize_features)
        if self.calibrator.settings.s_method == "jitter":
            self.calibrator.calibrate_template(lambda b: self._matcher.score(self._window(rgb, b)), box)

    def __call__(self, rgb: np.ndarray, box_appearance: np.ndarray, box_motion: np.ndarray) -> tuple[float, float]:
        """``(s_A, s_M)`` on the paper's scale."""
        if self._matcher is None:
            raise InputError("DdisTemplateScorer used before initialize(first RGB frame, box)")
        s_a = self._matcher.score(self._window(rgb, box_appearance))
        s_m = self._matcher.score(self._window(rgb, box_motion))
        self.last_raw = (s_a, s_m)
        return self.calibrator.paper_s(s_a), self.calibrator.paper_s(s_m)


def build_motion_parts(
    motion_model: str = "affine",
    *,
    camera: CameraMotionSettings | None = None,
    trigger: TriggerSettings = TriggerSettings(),
    kalman: KalmanSettings = KalmanSettings(),
    calibration: CalibrationSettings = CalibrationSettings(),
    thresholds: SwitchThresholds = PAPER_THRESHOLDS,
    features: FeatureFn | str = "deep",
    normalize_features: bool | None = None,
    template_area: float = 48.0 * 48.0,
    dark_level: float = 40.0,
) -> dict[str, object]:
    """All motion parts for ``JmmacTracker(config, rgb_tracker, t_tracker, fusion, **parts, refiner=...)``.

    ``motion_model`` selects the CME transform unless a full ``camera`` settings object is given. ``features``,
    ``normalize_features`` and ``template_area`` configure the DDIS scorer (default: EfficientNet-Lite0 stride-4
    features, cosine matching, on a 48x48 window). Template matching runs on RGB, and on the thermal frame while
    the visible patch's mean grey is below ``dark_level`` (:class:`ModalityAwareTemplate`). One tracker run per set
    of parts: the Kalman filter and the calibrators carry per-sequence state.
    """
    calibrator = ScoreCalibrator(calibration)
    return {
        "camera_motion": CameraMotionCompensation(camera or CameraMotionSettings(model=motion_model), trigger),
        "kalman": ConstantVelocityKalman(kalman),
        "quality": PaperScaleQuality(calibrator),
        "template": ModalityAwareTemplate(
            DdisTemplateScorer(calibrator, features, template_area, normalize_features),
            DdisTemplateScorer(ScoreCalibrator(calibration), features, template_area, normalize_features),
            dark_level,
        ),
        "switch": Algorithm1Switch(thresholds),
    }
