"""Drawing for the annotated output video: RGB and thermal side by side, box, mode and trajectory tail.

This is the harness's job, not the algorithm's: the tracker returns numbers and this module turns them into pixels.
"""

from __future__ import annotations

from collections import deque

import cv2
import numpy as np

MODE_COLOURS = {"init": (255, 255, 255), "appearance": (60, 220, 60), "motion": (255, 170, 0)}


def _to_rgb(image: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(image, cv2.COLOR_GRAY2RGB) if image.ndim == 2 else image.copy()


def _draw_box(image: np.ndarray, box: np.ndarray, colour, thickness: int = 2) -> None:
    if not np.all(np.isfinite(box)):
        return
    x, y, w, h = box
    cv2.rectangle(image, (int(round(x)), int(round(y))), (int(round(x + w - 1)), int(round(y + h - 1))), colour,
                  thickness, cv2.LINE_AA)


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


class Annotator:
    """Keeps the trajectory tail between frames and draws one side-by-side panel per frame."""

    def __init__(self, tail: int = 30, show_weights: bool = False):
        self.tail_rgb: deque[tuple[int, int]] = deque(maxlen=tail)
        self.tail_t: deque[tuple[int, int]] = deque(maxlen=tail)
        self.show_weights = show_weights

    def draw(self, rgb: np.ndarray, thermal: np.ndarray, box_rgb: np.ndarray, box_t: np.ndarray, mode: str,
             text: str = "", w_f: np.ndarray | None = None, region: np.ndarray | None = None) -> np.ndarray:
        """Return the annotated panel (RGB uint8); both images keep their own geometry, scaled to one height."""
        left, right = _to_rgb(rgb), _to_rgb(thermal)
        if self.show_weights and w_f is not None and region is not None:
            left = overlay_weight(left, w_f, region)
        colour = MODE_COLOURS.get(mode, (255, 255, 255))
        for image, box, tail in ((left, box_rgb, self.tail_rgb), (right, box_t, self.tail_t)):
            if np.all(np.isfinite(box)):
                tail.append((int(round(box[0] + box[2] / 2)), int(round(box[1] + box[3] / 2))))
            if len(tail) > 1:
                cv2.polylines(image, [np.array(tail, np.int32)], False, (255, 230, 0), 1, cv2.LINE_AA)
            _draw_box(image, box, colour)
        height = left.shape[0]
        if right.shape[0] != height:
            scale = height / right.shape[0]
            right = cv2.resize(right, (int(round(right.shape[1] * scale)), height), interpolation=cv2.INTER_LINEAR)
        panel = np.concatenate([left, right], axis=1)
        label = f"{mode}  {text}".strip()
        cv2.putText(panel, label, (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(panel, label, (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, colour, 1, cv2.LINE_AA)
        return panel
