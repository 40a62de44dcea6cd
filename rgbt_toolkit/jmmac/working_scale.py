"""Track large frames at a working scale: the tracker sees frames shrunk so its per-frame cost does not grow with
the frame size.

Why: every per-frame operation that touches whole frames (warping the thermal frame into RGB geometry, the camera
motion trigger and SIFT, the whole-frame search after loss, drawing) costs in proportion to the pixel count, 6.75x
more at 1920x1080 than at 640x480, while ECO itself resamples its search region to at most 250x250 px anyway. Shrinking
a frame no further than that (the search region stays at least ``sample_side`` pixels) loses nothing ECO would have
used, and frames are never shrunk below ``min_width`` (small targets on large frames keep their pixels).

Boxes go in and come out in full-resolution RGB pixels; :class:`ScaledTracker` converts at the boundary.
"""

from __future__ import annotations

import cv2
import numpy as np

MIN_WIDTH = 640  # never track on frames narrower than this (the benchmarks' and the generator's usual width)
SAMPLE_SIDE = 250.0  # the largest sample patch side of the ECO presets (deep: 250^2; hc samples at most 200^2)
SEARCH_SCALE = 4.0  # ECO's search region side = 4 sqrt(w h) (EcoParams.search_area_scale)


def working_scale(rgb_size: tuple[int, int], box: np.ndarray, *, min_width: int = MIN_WIDTH,
                  sample_side: float = SAMPLE_SIDE, search_scale: float = SEARCH_SCALE) -> float:
    """The factor (<= 1) frames of ``rgb_size`` (w, h) are shrunk by for a target of ``box`` (x, y, w, h)."""
    width = float(rgb_size[0])
    if width <= min_width:
        return 1.0
    side = search_scale * float(np.sqrt(max(box[2] * box[3], 1.0)))
    return float(min(1.0, max(sample_side / side, min_width / width)))


def scale_box(box: np.ndarray, factor: float) -> np.ndarray:
    """A box ``[x, y, w, h]`` (first-pixel convention) in pixels of an image resized by ``factor`` (cv2.resize
    geometry: pixel centres map as ``(p + 0.5) * factor - 0.5``)."""
    box = np.asarray(box, dtype=float)
    return np.array([(box[0] + 0.5) * factor - 0.5, (box[1] + 0.5) * factor - 0.5, box[2] * factor, box[3] * factor])


def shrink(image: np.ndarray, factor: float) -> np.ndarray:
    """``image`` resized by ``factor`` (area averaging), or itself when ``factor`` is 1.

    Area averaging by a whole factor ``1/k`` has a fast path in OpenCV (plain k x k block means) that the general
    path lacks: 1920x1080 -> 741x417 took 9.3 ms directly (one thread). So the largest whole factor that divides both
    sides goes first, and a remaining factor of at least 1/2 is bilinear: after the block mean the image holds no
    detail finer than that factor can show, and OpenCV's bilinear resize is 7x faster than its general area resize
    (960x540 -> 741x417, RGB: 0.6 against 4.2 ms). A factor between 1/2 and 1 with no block mean before it is
    bilinear too: each output pixel then blends the 2 x 2 input pixels around it, which at such a mild reduction
    differs from the area mean by a fraction of a grey level (0.25 on average on a real 1080p street frame shrunk to
    0.53), while OpenCV's general area path costs 11 ms on that frame against 1.9 ms. The output size and its pixel
    geometry (:func:`scale_box`: half-pixel centres in both) are the same either way.
    """
    if factor >= 1.0:
        return image
    h, w = image.shape[:2]
    size = (max(1, int(round(w * factor))), max(1, int(round(h * factor))))
    k = next((k for k in range(int(1.0 / factor + 1e-9), 1, -1) if w % k == 0 and h % k == 0), 1)
    if k > 1:
        image = cv2.resize(image, (w // k, h // k), interpolation=cv2.INTER_AREA)
        if image.shape[1::-1] == size:
            return image
    remaining = size[0] / image.shape[1]
    return cv2.resize(image, size, interpolation=cv2.INTER_LINEAR if remaining >= 0.5 else cv2.INTER_AREA)


class ScaledTracker:
    """A :class:`~rgbt_toolkit.jmmac.pipeline.JmmacTracker` fed with frames shrunk by ``scale``; boxes and camera
    shifts in and out are in full-resolution RGB pixels (the frames passed in must already be shrunk)."""

    def __init__(self, tracker, scale: float) -> None:
        self.tracker, self.scale = tracker, float(scale)

    @property
    def config(self):
        return self.tracker.config

    @property
    def box(self) -> np.ndarray | None:
        box = self.tracker.box
        return None if box is None else scale_box(box, 1 / self.scale)

    @property
    def camera_shift(self) -> np.ndarray:
        return np.asarray(self.tracker.camera_shift, dtype=float) / self.scale

    def __getattr__(self, name):  # the tracker's other parts (camera_motion, refiner, ...) as they are
        return getattr(self.tracker, name)

    def _full(self, result):
        result.box = scale_box(result.box, 1 / self.scale)
        return result

    def initialize(self, rgb: np.ndarray, thermal: np.ndarray, box: np.ndarray):
        return self._full(self.tracker.initialize(rgb, thermal, scale_box(box, self.scale)))

    def track(self, rgb: np.ndarray, thermal: np.ndarray):
        return self._full(self.tracker.track(rgb, thermal))
