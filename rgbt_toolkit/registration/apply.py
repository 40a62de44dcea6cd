"""Use a calibration: warp frames between the two cameras' geometries, map boxes, draw a check image.

A tracker reports one box per modality; ``map_boxes`` carries a box from one camera to the other by warping its four
corners and taking the axis-aligned box around the warped quadrilateral (exact for similarity transforms, a slight
enlargement under rotation or perspective). Boxes are float [x, y, w, h] with (x, y) the top-left corner, in the
same pixel coordinates as the transform.
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.registration.calib import Calibration
from rgbt_toolkit.registration.transforms import project

TARGETS = ("thermal", "rgb")


def _matrix_to(calibration: Calibration, to: str) -> tuple[np.ndarray, tuple[int, int]]:
    if to == "thermal":
        return calibration.matrix, calibration.thermal_size
    if to == "rgb":
        return calibration.inverse, calibration.rgb_size
    raise InputError(f"unknown target geometry '{to}'; choose 'thermal' or 'rgb'")


def warp_frame(frame: np.ndarray, calibration: Calibration, to: str = "thermal", *,
               border_value: float = 0) -> np.ndarray:
    """Resample ``frame`` (from the other camera) into the pixel grid of camera ``to``.

    ``to="thermal"`` takes an RGB frame and returns it as the thermal camera would see it (thermal frame size);
    ``to="rgb"`` does the reverse. Areas the source camera does not see are filled with ``border_value``.
    """
    matrix, size = _matrix_to(calibration, to)
    source_size = calibration.rgb_size if to == "thermal" else calibration.thermal_size
    h, w = frame.shape[:2]
    if (w, h) != tuple(source_size):
        raise InputError(
            f"frame is {w}x{h} but the calibration expects {source_size[0]}x{source_size[1]} for the "
            f"{'RGB' if to == 'thermal' else 'thermal'} camera"
        )
    return cv2.warpPerspective(frame, matrix, tuple(size), flags=cv2.INTER_LINEAR,
                               borderMode=cv2.BORDER_CONSTANT, borderValue=border_value)


def map_boxes(boxes: np.ndarray, calibration: Calibration, to: str = "thermal") -> np.ndarray:
    """Carry [x, y, w, h] boxes (one per row, or a single box) into camera ``to``'s coordinates.

    Each box's corners are warped and the axis-aligned box around them returned; NaN boxes (target lost) stay NaN.
    """
    matrix, _ = _matrix_to(calibration, to)
    arr = np.asarray(boxes, float)
    single = arr.ndim == 1
    arr = np.atleast_2d(arr)
    if arr.shape[1] != 4:
        raise InputError(f"boxes must be [x, y, w, h] rows, got shape {np.shape(boxes)}")
    x, y, w, h = arr.T
    pts = np.stack([np.c_[x, y], np.c_[x + w, y], np.c_[x + w, y + h], np.c_[x, y + h]], axis=1)  # (N, 4, 2)
    warped = project(matrix, pts.reshape(-1, 2)).reshape(-1, 4, 2)
    lo, hi = warped.min(axis=1), warped.max(axis=1)
    out = np.c_[lo, hi - lo]
    return out[0] if single else out


def _as_rgb8(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.dtype != np.uint8:
        lo, hi = np.percentile(image, [0.5, 99.5])
        image = np.clip((image.astype(np.float32) - lo) / max(hi - lo, 1e-6) * 255, 0, 255).astype(np.uint8)
    if image.ndim == 2:
        image = np.repeat(image[:, :, None], 3, axis=2)
    return image[:, :, :3]


def preview(rgb: np.ndarray, thermal: np.ndarray, calibration: Calibration, *, mode: str = "checkerboard",
            tiles: int = 8) -> np.ndarray:
    """A check image in the thermal geometry: RGB warped by the calibration next to thermal.

    ``mode="checkerboard"`` alternates tiles of warped RGB and thermal (edges continue across tile borders when the
    registration is right); ``mode="overlay"`` puts the warped RGB edges in red on the thermal frame.
    """
    warped = _as_rgb8(warp_frame(_as_rgb8(rgb), calibration, "thermal"))
    therm = _as_rgb8(thermal)
    if therm.shape[:2] != warped.shape[:2]:
        raise InputError("thermal frame size does not match the calibration's thermal size")
    h, w = therm.shape[:2]
    if mode == "checkerboard":
        cell = max(8, int(np.ceil(max(h, w) / max(tiles, 1))))
        yy, xx = np.mgrid[0:h, 0:w]
        mask = ((yy // cell + xx // cell) % 2 == 0)[:, :, None]
        return np.where(mask, warped, therm)
    if mode == "overlay":
        grey = cv2.cvtColor(warped, cv2.COLOR_RGB2GRAY)
        edges = cv2.Canny(grey, 50, 150) > 0
        out = therm.copy()
        out[edges] = (255, 0, 0)
        return out
    raise InputError(f"unknown preview mode '{mode}'; choose 'checkerboard' or 'overlay'")
