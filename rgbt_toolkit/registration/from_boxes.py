"""Calibration from a target's boxes in both cameras over time (two label files, or two ``rgbt track-single`` runs).

Where the two images share no texture (a drone against the sky) the target itself is the shared evidence: its box
centre in frame i of the RGB camera and in the thermal camera is one correspondence, and a target that crosses the
view gives many. Frames pair by index; when the two tracks are shifted in time (the cameras' clocks differ) the
integer frame shift whose pairs agree best with one transform is searched and reported as the clock offset. Box
sizes join the fit (as the boxes' corners) only where their ratio between the cameras is steady, since two trackers'
or annotators' boxes may fit the target differently tightly.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.registration.fit import (
    MIN_POINTS, SourceFit, calibration_from_fit, check_correspondences, fit_points, line_spread,
)
from rgbt_toolkit.registration.transforms import project

SIZE_RATIO_SPREAD = 0.08  # box-size ratios (thermal / RGB) steadier than this (relative MAD) count as agreeing
NEAR_LINE_RATIO = 0.15  # a path whose spread across its main line is below this share of the spread along it


def read_track_boxes(path: str | os.PathLike) -> np.ndarray:
    """(N, 4) ``x, y, w, h`` per frame from any box file ``rgbt`` reads; NaN rows where the target has no box.

    Text box files (one box per line: ``rgbt track-single -o``, benchmark ground truth), Anti-UAV labels
    (``{"exist", "gt_rect"}``) and results (``{"res"}``). Rows of zero size (``0,0,0,0``: absent) become NaN.
    """
    from rgbt_toolkit.io.anti_uav import read_anti_uav_label, read_anti_uav_result
    from rgbt_toolkit.io.boxes import read_boxes, read_text_file

    path = Path(path)
    if path.suffix.lower() == ".json":
        text = read_text_file(path, "box file")
        frames = read_anti_uav_label(path) if '"gt_rect"' in text else read_anti_uav_result(path)
        boxes = np.where(frames.present[:, None], frames.boxes, np.nan)
    else:
        boxes = np.array(read_boxes(path), dtype=float)
    boxes[~((boxes[:, 2] > 0) & (boxes[:, 3] > 0))] = np.nan
    return boxes


def _centres(boxes: np.ndarray) -> np.ndarray:
    return boxes[:, :2] + boxes[:, 2:] / 2


def _pairs_at(valid_a: np.ndarray, valid_b: np.ndarray, shift: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices (i, i + shift) of frames where both tracks have a box."""
    n = len(valid_a)
    i = np.arange(max(0, -shift), min(n, n - shift))
    keep = valid_a[i] & valid_b[i + shift]
    return i[keep], i[keep] + shift


def _shift_score(a: np.ndarray, b: np.ndarray, threshold: float) -> float:
    """Median residual of a robust similarity through the centre pairs (inf when it cannot be fitted)."""
    if len(a) < 3 or np.ptp(a, axis=0).max() < 1.0:
        return np.inf
    cv2.setRNGSeed(0)
    matrix, _ = cv2.estimateAffinePartial2D(a, b, method=cv2.RANSAC, ransacReprojThreshold=threshold)
    if matrix is None:
        return np.inf
    return float(np.median(np.linalg.norm(project(np.vstack([matrix, [0, 0, 1]]), a) - b, axis=1)))


def best_shift(rgb_centres: np.ndarray, t_centres: np.ndarray, max_shift: int, threshold: float = 3.0,
               min_pairs: int = 3) -> int:
    """The frame shift s (RGB frame i shows what thermal frame i + s shows) whose pairs fit one transform best.

    Near-ties (within 2 % or 0.05 px of the best median residual: a target standing still, any shift fits) go to
    the smallest |s|, so a static target never invents a clock offset.
    """
    valid_a, valid_b = ~np.isnan(rgb_centres[:, 0]), ~np.isnan(t_centres[:, 0])
    scores = {}
    for shift in range(-max_shift, max_shift + 1):
        i, j = _pairs_at(valid_a, valid_b, shift)
        if len(i) >= min_pairs:
            scores[shift] = _shift_score(rgb_centres[i], t_centres[j], threshold)
    finite = {s: v for s, v in scores.items() if np.isfinite(v)}
    if not finite:
        return 0
    best = min(finite.values())
    return min((s for s, v in finite.items() if v <= best * 1.02 + 0.05), key=lambda s: (abs(s), s))


def calibrate_from_boxes(rgb_boxes: str | os.PathLike, t_boxes: str | os.PathLike, rgb_size: tuple[int, int],
                         thermal_size: tuple[int, int], *, model: str = "homography", fps: float = 30.0,
                         max_offset: float = 2.0, threshold: float = 4.0, max_rms: float = 2.0) -> SourceFit:
    """Fit the RGB->T transform (and the clock offset) to a target's boxes in both cameras.

    Parameters
    ----------
    rgb_boxes, t_boxes : path
        One box per frame in each camera's pixels (see :func:`read_track_boxes`), the same frames in both files.
    rgb_size, thermal_size : (w, h)
        The cameras' frame sizes, recorded in the calibration.
    model : {"homography", "affine", "similarity"}
    fps : float
        Frame rate of the tracks, to report the frame shift in seconds.
    max_offset : float
        Largest clock offset searched, seconds (0: frames pair by index only).
    threshold, max_rms : float
        As :func:`~rgbt_toolkit.registration.fit.fit_points`.

    Raises
    ------
    InputError
        Files of different lengths, no frame with a box in both, too few frames, or centres on one line (for a
        model beyond similarity).
    RegistrationError
        The pairs do not fit one transform (see ``fit_points``).
    """
    if not (fps > 0 and np.isfinite(fps)):
        raise InputError(f"fps must be a positive number of frames per second, got {fps}")
    a, b = read_track_boxes(rgb_boxes), read_track_boxes(t_boxes)
    what = f"{rgb_boxes} / {t_boxes}"
    if len(a) != len(b):
        raise InputError(f"{what}: {len(a)} RGB boxes but {len(b)} thermal boxes; the two files must hold the same "
                         "frames (one box per frame, 0,0,0,0 where the target is not seen)")
    ca, cb = _centres(a), _centres(b)
    max_shift = int(round(max_offset * fps))
    shift = best_shift(ca, cb, min(max_shift, max(len(a) - 3, 0)), threshold)
    i, j = _pairs_at(~np.isnan(ca[:, 0]), ~np.isnan(cb[:, 0]), shift)
    if len(i) == 0:
        raise InputError(f"{what}: no frame has a box in both files; they must track the same target over the "
                         "same frames")
    what_centres = f"{what} (box centres of {len(i)} common frames)"
    check_correspondences(ca[i], cb[j], model, what_centres)
    rgb_pts, t_pts = [ca[i]], [cb[j]]
    labels = [f"frame {k}" for k in i]
    notes = []
    along, across = line_spread(ca[i])
    if across < NEAR_LINE_RATIO * along:
        notes.append(f"warning: the target's path is nearly a line ({across:.1f} px across, {along:.1f} px along): "
                     "rotation and perspective off that line are poorly determined; a path across the view is better")
    ratios = b[j, 2:] / a[i, 2:]
    median = np.median(ratios, axis=0)
    spread = np.median(np.abs(ratios - median), axis=0) / median
    if len(i) >= MIN_POINTS[model] and (spread < SIZE_RATIO_SPREAD).all():
        for corner, sign in (("top-left", -0.5), ("bottom-right", 0.5)):
            rgb_pts.append(ca[i] + sign * a[i, 2:])
            t_pts.append(cb[j] + sign * b[j, 2:])
            labels += [f"frame {k} {corner}" for k in i]
        notes.append(f"box sizes agree (size ratio spread {spread.max():.1%}): box corners used with the centres")
    else:
        notes.append(f"box sizes disagree between the cameras (size ratio spread {spread.max():.1%}): centres only")
    fit = fit_points(np.concatenate(rgb_pts), np.concatenate(t_pts), model, threshold=threshold, max_rms=max_rms,
                     what=what_centres)
    offset = shift / fps
    if shift:
        notes.append(f"time shift: RGB frame i pairs with thermal frame i{shift:+d}, clock offset {offset:+.3f} s at "
                     f"{fps:g} fps (thermal = RGB + offset)")
    else:
        notes.append(f"time shift: none found within ±{max_offset:g} s (frames pair by index)")
    calibration = calibration_from_fit(fit, "boxes", rgb_size, thermal_size, time_offset=offset, pairs_used=len(i))
    return SourceFit(calibration, fit, tuple(labels), tuple(notes))
