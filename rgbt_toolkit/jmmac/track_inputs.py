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
from rgbt_toolkit.io.images import decode_reduction
from rgbt_toolkit.jmmac.working_scale import working_size
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
    sources: tuple | None = None  # (RGB, thermal) io.frames.FrameSource of file inputs: see decode_for

    def decode_for(self, scale: float) -> None:
        """Let frame folders decode the frames still to come no larger than tracking at ``scale`` needs: the RGB
        frames at the working size, the thermal frames reduced by the largest whole factor at which they still have
        a pixel for every working pixel (:meth:`thermal_in_rgb` warps from whatever size they come at). Why: a
        1920x1080 JPEG decoded at half size takes half the time (docs/decisions.md, D45)."""
        if self.sources is None or scale >= 1.0:
            return
        rgb_source, t_source = self.sources
        rgb_source.deliver_at(working_size(self.rgb_size, scale))
        # thermal pixels per working pixel near the RGB frame's centre (the homography's local area ratio)
        centre = np.array(self.rgb_size, dtype=float) / 2.0
        (ax, ay), (bx, by) = project(self.h_rgb_to_t, [centre + [1.0, 0.0], centre + [0.0, 1.0]]) - \
            project(self.h_rgb_to_t, [centre, centre])
        density = np.sqrt(abs(ax * by - ay * bx)) / scale
        needed = (int(np.ceil(self.t_size[0] / density)), int(np.ceil(self.t_size[1] / density)))
        k = decode_reduction(self.t_size, needed)
        if k > 1:
            t_source.deliver_at((self.t_size[0] // k, self.t_size[1] // k))

    @property
    def h_t_to_rgb(self) -> np.ndarray:
        return np.linalg.inv(self.h_rgb_to_t)

    def thermal_in_rgb(self, thermal: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """Warp a thermal frame into the RGB camera's geometry (identity rigs pass through untouched), or straight
        into that geometry shrunk by ``scale`` (the tracker's working scale: one warp, never a full-size one)."""
        if scale == 1.0 and np.allclose(self.h_rgb_to_t, np.eye(3)) and thermal.shape[1::-1] == tuple(self.rgb_size):
            return thermal
        matrix, size = self.h_rgb_to_t, self.rgb_size
        if thermal.shape[1::-1] != tuple(self.t_size):  # decoded reduced (decode_for): thermal p -> (p + 0.5) f - 0.5
            fx, fy = thermal.shape[1] / self.t_size[0], thermal.shape[0] / self.t_size[1]
            matrix = np.array([[fx, 0.0, 0.5 * fx - 0.5], [0.0, fy, 0.5 * fy - 0.5], [0.0, 0.0, 1.0]]) @ matrix
        if scale != 1.0:  # working pixel p_w = (p + 0.5) * scale - 0.5 (cv2.resize's geometry)
            shift = 0.5 * scale - 0.5
            from_work = np.array([[1 / scale, 0.0, -shift / scale], [0.0, 1 / scale, -shift / scale], [0.0, 0.0, 1.0]])
            matrix = matrix @ from_work  # (an affine calibration keeps its last row exactly 0, 0, 1)
            size = (max(1, int(round(size[0] * scale))), max(1, int(round(size[1] * scale))))
        flags = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP
        if np.array_equal(matrix[2], [0.0, 0.0, 1.0]):  # an affine calibration: the same pixels, a third less time
            return cv2.warpAffine(thermal, matrix[:2], size, flags=flags, borderMode=cv2.BORDER_REPLICATE)
        return cv2.warpPerspective(thermal, matrix, size, flags=flags, borderMode=cv2.BORDER_REPLICATE)

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
