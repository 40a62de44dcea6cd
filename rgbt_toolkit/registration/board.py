"""Calibration from a heated calibration board (chessboard or circle grid) seen by both cameras.

A board whose squares (or dots) differ in temperature shows the same pattern to the RGB and the thermal camera.
OpenCV's detectors find its inner corners (``findChessboardCornersSB``) or dot centres (``findCirclesGrid``) in each
camera; every frame pair in which both cameras see the whole board gives ``cols x rows`` correspondences, and the
views of several poses are combined into one robust fit whose residuals are the reprojection error.

Thermal images are stretched to 8 bits (percentiles) before detection and tried in both polarities: a heated square
may look bright in thermal where it is dark in RGB. A chessboard's corner order can then start from another corner
(the pattern's symmetry); of the orders the grid allows, the one whose per-view transform rolls the least is kept,
which assumes the two cameras are mounted within 45 degrees of the same roll (90 degrees for a non-square grid).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.registration.fit import SourceFit, calibration_from_fit, fit_points
from rgbt_toolkit.registration.transforms import decompose

PATTERNS = ("chessboard", "circles")


@dataclass(frozen=True)
class BoardSpec:
    """A board's pattern and grid: ``cols x rows`` inner corners (chessboard) or dots (circle grid)."""

    cols: int
    rows: int
    pattern: str = "chessboard"

    @classmethod
    def parse(cls, text: str, pattern: str = "chessboard") -> "BoardSpec":
        """``"9x6"`` -> BoardSpec(9, 6); a one-line error for anything else."""
        match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", str(text))
        if match is None:
            raise InputError(f"board '{text}': give COLSxROWS, e.g. 9x6 (inner corners of a chessboard, dots of a "
                             "circle grid)")
        cols, rows = int(match.group(1)), int(match.group(2))
        if min(cols, rows) < 2 or (pattern == "chessboard" and min(cols, rows) < 3):
            raise InputError(f"board '{text}': a grid needs at least 3x3 inner corners (2x2 dots)")
        if pattern not in PATTERNS:
            raise InputError(f"unknown board pattern '{pattern}'; choose {' or '.join(PATTERNS)}")
        return cls(cols, rows, pattern)

    @property
    def count(self) -> int:
        return self.cols * self.rows

    def __str__(self) -> str:
        return f"{self.cols}x{self.rows} {self.pattern}"


def to_8bit(frame: np.ndarray) -> np.ndarray:
    """A grey uint8 image stretched between the 0.5 and 99.5 percentiles (16-bit or float thermal included)."""
    image = np.asarray(frame)
    if image.ndim == 3:
        image = cv2.cvtColor(image[:, :, :3].astype(np.float32), cv2.COLOR_RGB2GRAY)
    image = image.astype(np.float32)
    lo, hi = np.percentile(image, [0.5, 99.5])
    return np.clip((image - lo) * (255.0 / max(hi - lo, 1e-6)), 0, 255).astype(np.uint8)


def detect_board(frame: np.ndarray, spec: BoardSpec) -> np.ndarray | None:
    """The board's ``cols x rows`` points (N, 2) in OpenCV's order, or None when the whole board is not found."""
    grey = to_8bit(frame)
    size = (spec.cols, spec.rows)
    for image in (grey, 255 - grey):  # heated squares or dots may be the bright ones
        if spec.pattern == "chessboard":
            found, points = cv2.findChessboardCornersSB(
                image, size, flags=cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY)
        else:
            found, points = cv2.findCirclesGrid(image, size, flags=cv2.CALIB_CB_SYMMETRIC_GRID)
        if found and points is not None and len(points) == spec.count:
            return points.reshape(-1, 2).astype(float)
    return None


def _orders(spec: BoardSpec) -> list[np.ndarray]:
    """Index permutations of the grid that the pattern cannot tell apart (rotations; never mirror images)."""
    grid = np.arange(spec.count).reshape(spec.rows, spec.cols)
    orders = [grid, np.rot90(grid, 2)]
    if spec.cols == spec.rows:
        orders += [np.rot90(grid, 1), np.rot90(grid, 3)]
    return [o.ravel() for o in orders]


def match_views(rgb_points: np.ndarray, t_points: np.ndarray, spec: BoardSpec) -> np.ndarray:
    """``t_points`` reordered to correspond to ``rgb_points`` point for point (see the module note on order)."""
    best, best_roll = t_points, np.inf
    for order in _orders(spec):
        candidate = t_points[order]
        matrix, _ = cv2.findHomography(rgb_points, candidate, 0)
        if matrix is None:
            continue
        parts = decompose(matrix)
        if parts["mirrored"]:
            continue
        if abs(parts["rotation_deg"]) < best_roll:
            best, best_roll = candidate, abs(parts["rotation_deg"])
    return best


def sample_pairs(rgb_path, thermal_path, views: int, *, fps: float | None = None) -> list[tuple[int, np.ndarray,
                                                                                                  np.ndarray]]:
    """Up to ``views`` (RGB frame index, RGB frame, thermal frame nearest in time) spread over the recordings."""
    from rgbt_toolkit.io.frames import open_frames

    rgb_source = open_frames(rgb_path, fps=fps, grey=True)
    t_source = open_frames(thermal_path, fps=fps, grey=True)
    count = max(rgb_source.frame_count, 1)
    wanted = set(np.unique(np.linspace(0, count - 1, min(views, count)).round().astype(int)).tolist())
    chosen = [(k, frame, t) for k, (frame, t) in enumerate(rgb_source) if k in wanted]
    if not chosen:
        raise InputError(f"{rgb_path}: no readable frames")
    times = np.array([t for _, _, t in chosen])
    partners: list = [None] * len(chosen)
    gaps = np.full(len(chosen), np.inf)
    for frame, t in t_source:
        gap = np.abs(times - t)
        better = gap < gaps
        for i in np.flatnonzero(better):
            partners[i], gaps[i] = frame, gap[i]
        if t > times[-1] + 1.0:
            break
    return [(k, rgb, partners[i]) for i, (k, rgb, _) in enumerate(chosen) if partners[i] is not None]


def calibrate_from_board(rgb_path: str | os.PathLike, thermal_path: str | os.PathLike, spec: BoardSpec, *,
                         model: str = "homography", views: int = 20, fps: float | None = None,
                         threshold: float = 2.0, max_rms: float = 1.0) -> SourceFit:
    """Fit the RGB->T transform to a heated board seen in both recordings (images, frame folders or videos).

    Up to ``views`` frame pairs spread over the recordings are searched; every pair where both cameras see the
    whole board adds its points. ``threshold`` / ``max_rms`` (thermal pixels) are as in ``fit_points``; board corners
    are located to a fraction of a pixel, so the defaults are tighter than for hand-picked points.

    Raises
    ------
    RegistrationError
        The board is found in no frame of one camera, or in no pair by both; or the fit is refused.
    """
    from rgbt_toolkit.io.frames import open_frames

    pairs = sample_pairs(rgb_path, thermal_path, views, fps=fps)
    rgb_size = open_frames(rgb_path, fps=fps).size
    thermal_size = open_frames(thermal_path, fps=fps).size
    found_rgb = found_t = 0
    rgb_pts, t_pts, labels = [], [], []
    for k, rgb, thermal in pairs:
        a, b = detect_board(rgb, spec), detect_board(thermal, spec)
        found_rgb, found_t = found_rgb + (a is not None), found_t + (b is not None)
        if a is None or b is None:
            continue
        rgb_pts.append(a)
        t_pts.append(match_views(a, b, spec))
        labels += [f"frame {k} point {m}" for m in range(spec.count)]
    if not found_rgb or not found_t:
        camera, path = ("RGB", rgb_path) if not found_rgb else ("thermal", thermal_path)
        raise RegistrationError(f"{path}: no {spec} board found in any of the {len(pairs)} {camera} frames searched "
                                f"(COLSxROWS counts the inner corners of a chessboard, the dots of a circle grid; "
                                "the whole board must be in view)")
    if not rgb_pts:
        raise RegistrationError(f"{rgb_path} / {thermal_path}: the {spec} board is found in {found_rgb} RGB and "
                                f"{found_t} thermal frames but never in both at once; record both cameras together")
    fit = fit_points(np.concatenate(rgb_pts), np.concatenate(t_pts), model, threshold=threshold, max_rms=max_rms,
                     what=f"{rgb_path} / {thermal_path} ({spec} board)")
    notes = (f"board {spec}: found in {len(rgb_pts)} of {len(pairs)} frame pairs ({found_rgb} RGB, {found_t} "
             f"thermal); reprojection error RMS {fit.rms:.3f} px",)
    calibration = calibration_from_fit(fit, "board", rgb_size, thermal_size, pairs_used=len(rgb_pts))
    return SourceFit(calibration, fit, tuple(labels), notes)
