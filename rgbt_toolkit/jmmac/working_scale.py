"""Track large frames at a working scale: the tracker sees frames shrunk so its per-frame cost does not grow with
the frame size.

Why: every per-frame operation that touches whole frames (warping the thermal frame into RGB geometry, the camera
motion trigger and SIFT, the whole-frame search after loss, drawing) costs in proportion to the pixel count, 6.75x
more at 1920x1080 than at 640x480, while ECO itself resamples its search region to at most 250x250 px anyway. Shrinking
a frame no further than that (the search region stays at least ``sample_side`` pixels: the largest sample patch of
the tracker's ECO preset, :func:`sample_side`) loses nothing ECO would have used, and frames are never shrunk below
``min_width`` (small targets on large frames keep their pixels).

Boxes go in and come out in full-resolution RGB pixels; :class:`ScaledTracker` converts at the boundary.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.io.images import shrink_to

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


def sample_side(tracker) -> float:
    """The largest sample patch side (px) of ``tracker``'s ECO trackers, or :data:`SAMPLE_SIDE` for a tracker without
    ECO parts (stand-ins in tests). Why per tracker: ECO-hc samples at most 200 x 200 px, so shrinking the frame for
    250 px (the deep preset's patch) kept 1.56x the pixels ECO-hc uses on every whole-frame step (decode, thermal
    warp, camera motion, drawing, encoding) for nothing (docs/decisions.md, D43)."""
    sides = []
    for part in (getattr(tracker, "rgb_tracker", None), getattr(tracker, "t_tracker", None)):
        params = getattr(getattr(part, "eco", None), "params", None)
        if params is not None:
            sides.append(float(np.sqrt(params.max_sample_area)))
    return max(sides) if sides else SAMPLE_SIDE


def scale_box(box: np.ndarray, factor: float) -> np.ndarray:
    """A box ``[x, y, w, h]`` (first-pixel convention) in pixels of an image resized by ``factor`` (cv2.resize
    geometry: pixel centres map as ``(p + 0.5) * factor - 0.5``)."""
    box = np.asarray(box, dtype=float)
    return np.array([(box[0] + 0.5) * factor - 0.5, (box[1] + 0.5) * factor - 0.5, box[2] * factor, box[3] * factor])


def shrink(image: np.ndarray, factor: float) -> np.ndarray:
    """``image`` resized by ``factor`` (area averaging), or itself when ``factor`` is 1; the output size is
    ``round(side * factor)`` on each side, and :func:`~rgbt_toolkit.io.images.shrink_to` says how it is resampled."""
    if factor >= 1.0:
        return image
    h, w = image.shape[:2]
    return shrink_to(image, (max(1, int(round(w * factor))), max(1, int(round(h * factor)))))


def working_size(size: tuple[int, int], factor: float) -> tuple[int, int]:
    """The ``(w, h)`` of a frame of ``size`` shrunk by ``factor`` (:func:`shrink`'s output size)."""
    if factor >= 1.0:
        return int(size[0]), int(size[1])
    return max(1, int(round(size[0] * factor))), max(1, int(round(size[1] * factor)))


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

    def initialize(self, rgb: np.ndarray, thermal: np.ndarray, box: np.ndarray, **kwargs):
        return self._full(self.tracker.initialize(rgb, thermal, scale_box(box, self.scale), **kwargs))

    def track(self, rgb: np.ndarray, thermal: np.ndarray, **kwargs):
        return self._full(self.tracker.track(rgb, thermal, **kwargs))
