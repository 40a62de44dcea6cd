"""Drawing for the annotated output videos: RGB and thermal side by side with box, mode and trajectory tail
(``rgbt track``), or one camera with its box and tail (``SingleAnnotator``, ``rgbt track-single --video``).

This is the harness's job, not the algorithm's: the tracker returns numbers and this module turns them into pixels.
The tail covers the last second only, and when the camera's accumulated shift is given the past centres are moved
with it, so under camera shake the tail shows the target's own motion in the current frame, not a scribble.
"""

from __future__ import annotations

from collections import deque

import cv2
import numpy as np

MODE_COLOURS = {"init": (255, 255, 255), "appearance": (60, 220, 60), "motion": (255, 170, 0)}
# annotated.mp4's default width at most (px): two views side by side as a 720p-wide player shows them. A wider panel
# only costs encoding (x264 ultrafast: 3.0 against 1.8 ms a frame for a 1614x454 and a 1210x340 panel of a real
# street pair), and players shrink it on most laptop screens anyway
PANEL_MAX_WIDTH = 1280


def _thermal_view_width(thermal_size: tuple[int, int], height: int) -> int:
    """Width of the thermal view of a ``(w, h)`` thermal frame drawn ``height`` px high (the RGB view's height)."""
    return max(1, int(round(thermal_size[0] * height / thermal_size[1])))


def panel_width(rgb_size: tuple[int, int], thermal_size: tuple[int, int]) -> int:
    """Width of :meth:`Annotator.draw`'s panel for an RGB view of ``rgb_size`` and a thermal frame of ``thermal_size``
    (both ``(w, h)``): the thermal view is drawn at the RGB view's height."""
    return int(rgb_size[0]) + _thermal_view_width(thermal_size, rgb_size[1])


def default_video_scale(rgb_size: tuple[int, int], thermal_size: tuple[int, int],
                        max_width: int = PANEL_MAX_WIDTH) -> float:
    """The video scale (at most 1) at which the panel of an RGB view of ``rgb_size`` (the working frame) beside a
    thermal frame of ``thermal_size`` is at most ``max_width`` px wide."""
    return min(1.0, max_width / panel_width(rgb_size, thermal_size))


def _to_rgb(image: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(image, cv2.COLOR_GRAY2RGB) if image.ndim == 2 else image.copy()


def _paint(view: np.ndarray, image: np.ndarray) -> None:
    """Copy a grey or RGB ``image`` into ``view`` (H, W, 3 uint8, a part of the panel) as RGB."""
    if image.ndim == 2:
        out = cv2.cvtColor(np.ascontiguousarray(image, dtype=np.uint8), cv2.COLOR_GRAY2RGB, dst=view)
        if out is not view:  # OpenCV wrote a new array instead (a view it cannot take as its output)
            view[:] = out
    else:
        view[:] = image[:, :, :3]


def _draw_box(image: np.ndarray, box: np.ndarray, colour, thickness: int = 2) -> None:
    if not np.all(np.isfinite(box)):
        return
    x, y, w, h = box
    cv2.rectangle(image, (int(round(x)), int(round(y))), (int(round(x + w - 1)), int(round(y + h - 1))), colour,
                  thickness, cv2.LINE_AA)


def _draw_trail(image: np.ndarray, points: np.ndarray) -> None:
    """The centre path: a thin polyline through ``points`` (N, 2), when there are two or more."""
    if len(points) > 1:
        cv2.polylines(image, [np.round(points).astype(np.int32)], False, (255, 230, 0), 1, cv2.LINE_AA)


def label_scale(height: int) -> float:
    """OpenCV font scale for a label on an image ``height`` px high: 0.45 up to 360 px, growing with the image (a
    568-px panel of a 1080p run gets 0.71) so the label stays readable in a video played at screen size."""
    return float(np.clip(height / 800.0, 0.45, 1.2))


def _draw_label(image: np.ndarray, text: str, colour) -> None:
    """``text`` in the top-left corner on a dark band, outlined in black, so it reads on any background."""
    scale = label_scale(image.shape[0])
    thick = max(1, int(round(scale * 2)))
    (width, height), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
    margin = max(4, int(round(6 * scale)))
    band = image[: height + base + 2 * margin, : width + 2 * margin]
    band[:] = (band * 0.45).astype(np.uint8)  # darkened, not hidden: the scene stays visible behind the text
    origin = (margin, margin + height)
    cv2.putText(image, text, origin, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), thick + 2, cv2.LINE_AA)
    cv2.putText(image, text, origin, cv2.FONT_HERSHEY_SIMPLEX, scale, colour, thick, cv2.LINE_AA)


def overlay_weight(image: np.ndarray, w_f: np.ndarray, region: np.ndarray) -> np.ndarray:
    """Blend the fusion weight map (red = RGB trusted, blue = thermal trusted) over the search region."""
    x, y, w, h = np.round(region).astype(int)
    H, W = image.shape[:2]
    x0, y0, x1, y1 = max(x, 0), max(y, 0), min(x + w, W), min(y + h, H)
    if x1 <= x0 or y1 <= y0:
        return image
    heat = cv2.resize(np.clip(w_f, 0, 1).astype(np.float32), (w, h), interpolation=cv2.INTER_LINEAR)
    heat = heat[y0 - y: y1 - y, x0 - x: x1 - x, None]
    tint = heat * np.array([255, 40, 40]) + (1 - heat) * np.array([40, 40, 255])
    out = image.copy()
    out[y0:y1, x0:x1] = (0.6 * out[y0:y1, x0:x1] + 0.4 * tint).astype(np.uint8)
    return out


def tail_length(fps: float | None, fallback: int = 30) -> int:
    """Frames in one second of video (the tail's length); ``fallback`` frames when the rate is unknown."""
    if fps is None or not np.isfinite(fps) or fps <= 0:
        return fallback
    return max(2, int(round(fps)))


class Annotator:
    """Keeps the trajectory tail (the last ``tail`` frames) between frames and draws one side-by-side panel per frame.

    Past centres are stored in camera-stable coordinates (image + accumulated camera shift, the tracker's
    convention) and drawn at stable - current shift, i.e. where those points of the scene are in the current frame.
    """

    def __init__(self, tail: int = 30, show_weights: bool = False):
        self.tail_rgb: deque[np.ndarray] = deque(maxlen=tail)
        self.tail_t: deque[np.ndarray] = deque(maxlen=tail)
        self.show_weights = show_weights

    def draw(self, rgb: np.ndarray, thermal: np.ndarray, box_rgb: np.ndarray, box_t: np.ndarray, mode: str,
             text: str = "", w_f: np.ndarray | None = None, region: np.ndarray | None = None,
             shift: np.ndarray | None = None, shift_t: np.ndarray | None = None,
             thermal_size: tuple[int, int] | None = None) -> np.ndarray:
        """Return the annotated panel (RGB uint8); both images keep their own geometry, scaled to one height.

        ``shift`` / ``shift_t``: the accumulated camera shift in RGB / thermal pixels (stable = image + shift), or
        None without camera-motion estimation (the tail is then drawn as tracked). ``thermal_size``: the thermal
        camera's ``(w, h)``, the pixels ``box_t`` and ``shift_t`` are in, when ``thermal`` was decoded smaller (a
        JPEG folder read at 1/2, 1/4 or 1/8 size); default: the frame's own size.

        The thermal view is scaled to the panel first and its box and tail drawn there, so both views' lines are as
        thick as the panel's own pixels make them (a 1920x1080 thermal frame drawn at full size and then shrunk to a
        454-px panel showed a 0.8-px box) and only the panel's pixels are converted and copied.
        """
        height, width = rgb.shape[:2]
        t_width = _thermal_view_width((thermal.shape[1], thermal.shape[0]), height)
        panel = np.empty((height, width + t_width, 3), np.uint8)
        left, right = panel[:, :width], panel[:, width:]
        _paint(left, rgb)
        _paint(right, thermal if thermal.shape[:2] == (height, t_width) else
               cv2.resize(thermal, (t_width, height), interpolation=cv2.INTER_LINEAR))
        if self.show_weights and w_f is not None and region is not None:
            left[:] = overlay_weight(left, w_f, region)
        colour = MODE_COLOURS.get(mode, (255, 255, 255))
        t_w, t_h = thermal_size if thermal_size is not None else (thermal.shape[1], thermal.shape[0])
        t_zoom = np.array([t_width / t_w, height / t_h])  # thermal camera pixels -> panel, per axis
        for image, box, tail, offset, scale in ((left, box_rgb, self.tail_rgb, shift, np.ones(2)),
                                                (right, box_t, self.tail_t, shift_t, t_zoom)):
            offset = np.zeros(2) if offset is None else np.asarray(offset, float)
            box = np.asarray(box, float)
            if np.all(np.isfinite(box)):
                tail.append(np.array([box[0] + box[2] / 2, box[1] + box[3] / 2]) + offset)
            # pixel centres p of the view sit at (p + 0.5) * scale - 0.5 in the panel; box edges at p * scale
            _draw_trail(image, (self.trail(tail, offset) + 0.5) * scale - 0.5)
            _draw_box(image, box * np.tile(scale, 2), colour)
        _draw_label(panel, f"{mode}  {text}".strip(), colour)
        return panel

    @staticmethod
    def trail(tail: deque, shift: np.ndarray | None = None) -> np.ndarray:
        """The tail's centres ``(N, 2)`` in the current frame's pixels, given the current accumulated shift."""
        points = np.array(tail, float).reshape(-1, 2)
        return points - (np.zeros(2) if shift is None else np.asarray(shift, float))


LOST_COLOUR = (255, 170, 0)  # the held box of a frame where the target counts as lost


class SingleAnnotator:
    """One camera's annotated frames for ``rgbt track-single``: the box (green while tracked, orange while the
    target counts as lost and the last reliable box is held), the last ``tail`` centres and the frame number.

    An unreadable frame repeats the last drawn panel, so the video keeps one frame per box row.
    """

    def __init__(self, tail: int = 30) -> None:
        self.tail: deque[np.ndarray] = deque(maxlen=tail)
        self.index = 0
        self.last: np.ndarray | None = None

    def draw(self, frame: np.ndarray | None, box: np.ndarray, present: bool) -> np.ndarray:
        """The annotated frame (RGB uint8) for ``frame`` with its box row; ``frame=None``: the last one again."""
        self.index += 1
        if frame is None:
            if self.last is None:
                raise ValueError("the first frame must be readable")
            return self.last
        image = _to_rgb(frame)
        colour = MODE_COLOURS["appearance"] if present else LOST_COLOUR
        if present and np.all(np.isfinite(box)):
            self.tail.append(np.array([box[0] + box[2] / 2, box[1] + box[3] / 2]))
        _draw_trail(image, Annotator.trail(self.tail))
        _draw_box(image, np.asarray(box, float), colour)
        _draw_label(image, f"{self.index}" + ("" if present else "  lost"), colour)
        self.last = image
        return image
