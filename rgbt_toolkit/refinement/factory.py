"""Build a box refiner by name, for the pipeline's assembly code and the CLI."""

from __future__ import annotations

from pathlib import Path

from rgbt_toolkit.errors import InputError

# name -> what it is (choices for the CLI are taken from here)
REFINER_KINDS: dict[str, str] = {
    "regressor": "box regressor trained on frame 1 on backbone features (default; no third-party weights)",
    "detector": "a user-supplied YOLO-family ONNX detector (e.g. FastestDet) with the authors' acceptance rules",
}


def make_refiner(kind: str = "regressor", model_path: str | Path | None = None, seed: int = 0):
    """A :class:`~rgbt_toolkit.jmmac.parts.BoxRefiner` of the given kind.

    Parameters
    ----------
    kind : str
        ``"regressor"`` (:class:`RegressionRefiner`) or ``"detector"`` (:class:`DetectorRefiner` around an
        :class:`OnnxYoloDetector`).
    model_path : str or Path, optional
        The ``.onnx`` detector; required for ``"detector"``, not accepted for ``"regressor"``.
    seed : int
        Seed of the regressor's frame-1 samples.

    Raises
    ------
    InputError
        Unknown kind, or a model path missing / given where it has no use.
    WeightsError, MissingDependencyError
        From :class:`OnnxYoloDetector` (unreadable model, onnxruntime not installed).
    """
    if kind == "regressor":
        if model_path is not None:
            raise InputError("the regressor refiner takes no model file; use kind='detector' for an ONNX detector")
        from rgbt_toolkit.refinement.regressor import RegressionRefiner

        return RegressionRefiner(seed=seed)
    if kind == "detector":
        if model_path is None:
            raise InputError("the detector refiner needs model_path=PATH to a YOLO-family .onnx file (e.g. FastestDet)")
        from rgbt_toolkit.refinement.detector import OnnxYoloDetector
        from rgbt_toolkit.refinement.detector_refiner import DetectorRefiner

        return DetectorRefiner(OnnxYoloDetector(model_path))
    raise InputError(f"unknown refiner {kind!r}; choose one of {', '.join(REFINER_KINDS)}")
