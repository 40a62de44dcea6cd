"""The record both input resolvers return (:class:`TrackInputs`), and the checks they share.

Why a module of its own: ``jmmac.inputs`` (files, folders, sequences) hands live sources to ``jmmac.live_inputs``,
and both build the same record with the same box checks and the same "no geometry" message; kept in ``inputs``, the
two modules would import each other.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.eco.tracker import check_box
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.registration.transforms import project

Paired = tuple[np.ndarray | None, np.ndarray | None, float]  # (rgb, thermal in its own geometry, time); None: corrupt


def map_box(homography: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Map an ``[x, y, w, h]`` box through a 3x3 homography: the extent of its mapped corners."""
    x, y, w, h = box
    points = project(homography, [[x, y], [x + w, y], [x + w, y + h], [x, y + h]])
    lo, hi = points.min(axis=0), points.max(axis=0)
    return np.concatenate([lo, hi - lo])


@dataclass
class TrackInputs:
    """Resolved inputs of one tracking run."""

    name: str
    pairs: Iterator[Paired]
    rgb_size: tuple[int, int]
    t_size: tuple[int, int]
    fps: float
    frame_count: int  # best estimate, for the progress bar (0 when unknown)
    h_rgb_to_t: np.ndarray
    init_box: np.ndarray  # RGB camera pixels
    init_source: str
    notes: list[str] = field(default_factory=list)
    description: dict = field(default_factory=dict)
    init_box_t: np.ndarray | None = None  # the first thermal box when given in thermal pixels (--init-modality t)
    live: object | None = None  # io.live.LivePairs of live sources: its readers, dropped count and end notes

    @property
    def h_t_to_rgb(self) -> np.ndarray:
        return np.linalg.inv(self.h_rgb_to_t)

    def thermal_in_rgb(self, thermal: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """Warp a thermal frame into the RGB camera's geometry (identity rigs pass through untouched), or straight
        into that geometry shrunk by ``scale`` (the tracker's working scale: one warp, never a full-size one)."""
        if scale == 1.0 and np.allclose(self.h_rgb_to_t, np.eye(3)) and thermal.shape[1::-1] == self.rgb_size:
            return thermal
        matrix, size = self.h_rgb_to_t, self.rgb_size
        if scale != 1.0:  # working pixel p_w = (p + 0.5) * scale - 0.5 (cv2.resize's geometry)
            shift = 0.5 * scale - 0.5
            to_work = np.array([[scale, 0.0, shift], [0.0, scale, shift], [0.0, 0.0, 1.0]])
            matrix = self.h_rgb_to_t @ np.linalg.inv(to_work)
            size = (max(1, int(round(size[0] * scale))), max(1, int(round(size[1] * scale))))
        return cv2.warpPerspective(thermal, matrix, size, flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                   borderMode=cv2.BORDER_REPLICATE)

    def box_in_t(self, box_rgb: np.ndarray) -> np.ndarray:
        return map_box(self.h_rgb_to_t, box_rgb)


def check_input_box(box: np.ndarray, size: tuple[int, int], what: str) -> np.ndarray:
    """The target box in an input of ``size`` (w, h), or InputError naming the input."""
    return check_box(box, f"{what}: box", (size[1], size[0]))


def first_init_box(path: Path, size: tuple[int, int]) -> np.ndarray:
    """The first box of an init file, checked against the frames (``size`` w, h) of the camera it belongs to."""
    boxes = read_boxes(path)
    if len(boxes) == 0:
        raise InputError(f"{path}: empty; it needs the first frame's box x,y,w,h")
    return check_input_box(boxes[0], size, str(path))


REMEDIES = ("give --calib FILE (a calibration from `rgbt register`), or --assume-aligned if the footage is already "
            "registered (only the resolution differs), or make a calibration with `rgbt register --points FILE`, "
            "`--from-boxes RGB_BOXES T_BOXES` or `--board COLSxROWS RGB T`")


def unregistered_message(rgb, thermal, why: str) -> str:
    """The one line that stops a run whose two views have no known geometry: why, and what to give instead."""
    why = " ".join(str(why).split()).rstrip(".")
    return f"{rgb} / {thermal}: no RGB->T transform ({why}); {REMEDIES}"
