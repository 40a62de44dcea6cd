"""A class-agnostic detector interface and a runner for user-supplied YOLO-family ONNX models.

The paper refines the tracker's box with a COCO-trained YOLOv2 run in a small region around the target, ignoring
the class label. No JMMAC detector weights are published, so the toolkit runs whatever YOLO-family ONNX model the
user supplies (tested with FastestDet); :mod:`rgbt_toolkit.refinement.yolo` decodes the output layouts.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError, MissingDependencyError, WeightsError
from rgbt_toolkit.refinement.boxes import as_box, centres
from rgbt_toolkit.refinement.yolo import DECODERS, LAYOUTS, guess_layout, nms


__all__ = ["Detections", "Detector", "MissingDependencyError", "OnnxYoloDetector"]


@dataclass(frozen=True)
class Detections:
    """Detected boxes in frame pixels: ``boxes`` ``(N, 4)`` as ``x, y, w, h``, ``scores`` ``(N,)``, ``labels``."""

    boxes: np.ndarray
    scores: np.ndarray
    labels: np.ndarray

    def __len__(self) -> int:
        return len(self.scores)


class Detector(Protocol):
    def detect(self, image: np.ndarray, region: np.ndarray) -> Detections:
        """Objects of any class inside ``region`` (``x, y, w, h``) of the ``HxWx3`` uint8 RGB ``image``."""
        ...


def _import_onnxruntime():
    try:
        import onnxruntime
    except ImportError:
        raise MissingDependencyError(
            "ONNX detectors need onnxruntime, which is not installed: pip install rgbt-toolkit[onnx]") from None
    return onnxruntime


class OnnxYoloDetector:
    """Run a YOLO-family ONNX model on a region of a frame.

    Parameters
    ----------
    model_path : str or Path
        The ``.onnx`` file (e.g. FastestDet, or a YOLOv5/v8 export).
    layout : str
        ``"auto"`` (guess from the output shape) or one of ``fastestdet``, ``yolov5``, ``yolov8``.
    conf_threshold : float
        Detections scoring below this are dropped before suppression.
    nms_iou : float
        Class-agnostic suppression threshold.
    bgr : bool, optional
        Feed the network BGR instead of RGB; default: BGR for FastestDet (trained on OpenCV-read images), RGB
        otherwise.
    input_size : int
        Input side used when the model's input size is dynamic.
    threads : int, optional
        onnxruntime intra-op threads (default: torch's thread count, which :func:`rgbt_toolkit.runtime.set_threads`
        sets).

    Raises
    ------
    WeightsError
        The file is missing, is not a readable ONNX model, or its input/output do not fit a YOLO-family layout.
    MissingDependencyError
        onnxruntime is not installed.
    """

    def __init__(self, model_path: str | Path, layout: str = "auto", conf_threshold: float = 0.3,
                 nms_iou: float = 0.45, bgr: bool | None = None, input_size: int = 640, threads: int | None = None):
        path = Path(model_path)
        if not path.is_file():
            raise WeightsError(f"{path}: detector model not found; pass the path of a YOLO-family .onnx file")
        if layout != "auto" and layout not in LAYOUTS:
            raise InputError(f"unknown detector layout {layout!r}; choose auto or one of {', '.join(LAYOUTS)}")
        ort = _import_onnxruntime()
        if threads is None:
            import torch

            threads = torch.get_num_threads()
        options = ort.SessionOptions()
        options.intra_op_num_threads = int(threads)
        options.inter_op_num_threads = 1
        options.log_severity_level = 3
        try:
            self.session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
        except Exception as exc:  # onnxruntime raises its own exception types for unreadable / invalid models
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise WeightsError(f"{path}: not a readable ONNX model ({first[:200]})") from None
        inputs, outputs = self.session.get_inputs(), self.session.get_outputs()
        shape = list(inputs[0].shape)
        if len(inputs) != 1 or len(shape) != 4 or shape[1] not in (3, "3"):
            raise WeightsError(f"{path}: expected one image input [1,3,H,W], got {shape}; not a YOLO-family model")
        h = shape[2] if isinstance(shape[2], int) else input_size
        w = shape[3] if isinstance(shape[3], int) else input_size
        self.input_name, self.input_size = inputs[0].name, (int(w), int(h))
        if layout == "auto":
            out_shape = outputs[0].shape
            if not all(isinstance(v, int) for v in out_shape):  # dynamic axes: run once to see the real shape
                out_shape = self._run(np.zeros((1, 3, self.input_size[1], self.input_size[0]), np.float32)).shape
            layout = guess_layout(tuple(out_shape))
        self.path, self.layout = path, layout
        self.bgr = (layout == "fastestdet") if bgr is None else bool(bgr)
        self.conf_threshold, self.nms_iou = float(conf_threshold), float(nms_iou)

    def _run(self, blob: np.ndarray) -> np.ndarray:
        return np.asarray(self.session.run(None, {self.input_name: blob})[0])

    def _transform(self, region: np.ndarray) -> tuple[float, np.ndarray]:
        """Letterbox scale and the 2x3 affine taking frame pixels to network-input pixels (region centred)."""
        iw, ih = self.input_size
        s = min(iw / region[2], ih / region[3])
        c = centres(region)
        return s, np.array([[s, 0.0, (iw - 1) / 2 - s * c[0]], [0.0, s, (ih - 1) / 2 - s * c[1]]])

    def detect(self, image: np.ndarray, region: np.ndarray | None = None) -> Detections:
        """Detections inside ``region`` (default: the whole frame), in frame pixels, best first.

        The region is letterboxed into the network input (grey padding, as YOLO letterboxing; parts outside the
        frame are grey too), the output decoded, thresholded and suppressed without regard to class.
        """
        image = np.asarray(image)
        if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
            raise InputError(f"detector needs an HxWx3 uint8 RGB image, got {image.dtype} {image.shape}")
        region = as_box([0, 0, image.shape[1], image.shape[0]] if region is None else region, "detector region")
        s, m = self._transform(region)
        patch = cv2.warpAffine(image, m, self.input_size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                               borderValue=(114, 114, 114))
        if self.bgr:
            patch = patch[:, :, ::-1]
        blob = np.ascontiguousarray(patch.transpose(2, 0, 1)[None], dtype=np.float32) / 255.0
        xyxy, scores, labels = DECODERS[self.layout](self._run(blob), self.input_size)
        ok = scores > self.conf_threshold
        xyxy, scores, labels = xyxy[ok], scores[ok], labels[ok]
        keep = nms(xyxy, scores, self.nms_iou)
        xyxy, scores, labels = xyxy[keep], scores[keep], labels[keep]
        # input edge coordinate e = p + 0.5 with p = s (x - c) + (size - 1) / 2  ->  frame x = (p - t) / s
        x0 = (xyxy[:, 0] - 0.5 - m[0, 2]) / s
        y0 = (xyxy[:, 1] - 0.5 - m[1, 2]) / s
        w = (xyxy[:, 2] - xyxy[:, 0]) / s
        h = (xyxy[:, 3] - xyxy[:, 1]) / s
        boxes = np.stack([x0 + 0.5, y0 + 0.5, w, h], axis=1) if len(keep) else np.zeros((0, 4))
        return Detections(boxes, scores.astype(float), labels.astype(int))
