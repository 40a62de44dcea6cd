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

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.registration.fit import (
    SCALE_FACTOR, THRESHOLD_FLOOR, SourceFit, calibration_from_fit, check_correspondences,
    least_squares, line_spread, rms_spread, robust_scale, similarity_both_noisy, usable_matrix,
)
from rgbt_toolkit.registration.transforms import project
from rgbt_toolkit.registration.weigh import fit_weighed

SIZE_RATIO_SPREAD = 0.08  # box-size ratios (thermal / RGB) steadier than this (relative MAD) count as agreeing
MIN_SIZE_FRAMES = 4  # frames needed to judge whether the box sizes agree
SMOOTH_FRAMES = 9  # moving average over this many paired frames before judging whether the tracks are one target
# the smoothed tracks' residual scale above this share of the thermal track's RMS spread: not one target. Generated
# labels (30 s, 2-5 px jitter, followed or walking target): one target at most 0.24, two targets at least 0.48
TRACK_SHARE = 0.35
VERTEX_WINDOW = 7  # frames either side of the lowest score fitted by the parabola of _vertex
BOWL_LEVEL = 2.0  # the bottom of the score curve: scores up to this many times the lowest
BOWL_Z = 3.0  # the parabola's curvature must be this many standard errors above zero to establish a shift
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


def _shift_score(a: np.ndarray, b: np.ndarray) -> float:
    """RMS residual of a similarity through the centre pairs, each residual capped at ``SCALE_FACTOR`` robust
    scales (inf when no similarity can be fitted).

    The similarity is a least-median-of-squares start refitted by least squares on the pairs within the cap (as
    :func:`~rgbt_toolkit.registration.fit.fit_points` accepts them). Every pair weighs in, a stray one by no more
    than the cap, so a shift of one frame shows against label jitter of a few pixels.
    """
    if len(a) < 3 or np.ptp(a, axis=0).max() < 1.0:
        return np.inf
    cv2.setRNGSeed(0)
    start, _ = cv2.estimateAffinePartial2D(a, b, method=cv2.LMEDS)
    if start is None:
        return np.inf
    matrix = np.vstack([start, [0, 0, 1]])
    deltas = project(matrix, a) - b
    cap = max(SCALE_FACTOR * robust_scale(deltas), THRESHOLD_FLOOR)
    keep = np.linalg.norm(deltas, axis=1) <= cap
    refit = least_squares(a[keep], b[keep], "similarity") if keep.sum() >= 3 else None
    if usable_matrix(refit):
        matrix = refit
    residuals = np.linalg.norm(project(matrix, a) - b, axis=1)
    # per degree of freedom (2 per pair, 4 taken by the similarity): few pairs fit closely by chance alone
    return float(np.sqrt(np.sum(np.minimum(residuals, cap) ** 2) / (2 * len(a) - 4)))


def _bowl(scores: dict[int, float], best: int) -> np.ndarray:
    """The shifts around ``best`` (at most ``VERTEX_WINDOW`` either side, without a gap) whose score is within
    ``BOWL_LEVEL`` times the lowest: the bottom of the curve, where it is a parabola in the squared score."""
    near = [best]
    for step in (-1, 1):
        shift = best + step
        while (shift in scores and abs(shift - best) <= VERTEX_WINDOW
               and scores[shift] <= BOWL_LEVEL * scores[best]):
            near.append(shift)
            shift += step
    return np.array(sorted(near))


def _vertex(scores: dict[int, float], best: int) -> int:
    """The shift at the bottom of the score curve near its lowest point ``best``.

    Each shift's score is measured on its own pairs, so with label jitter the curve is a bowl (the squared score a
    parabola in the shift) plus noise of a few hundredths of a pixel, and its lowest single score may land a frame
    or two off: the vertex of a parabola through the bottom (:func:`_bowl`) averages that noise out. A bottom of
    fewer than 5 shifts is a bowl far sharper than the noise, and its lowest point is the shift. A parabola whose
    curvature is not ``BOWL_Z`` standard errors above zero shows no bowl (a target standing still, or moving too
    little for its jitter): 0, so a clock offset is not invented.
    """
    near = _bowl(scores, best)
    if len(near) < 5:
        return best
    values = np.array([scores[s] ** 2 for s in near])
    design = np.vander(near.astype(float), 3)  # columns s^2, s, 1
    coefficients = np.linalg.lstsq(design, values, rcond=None)[0]
    curve, slope = coefficients[:2]
    residual = values - design @ coefficients
    variance = float(residual @ residual) / (len(near) - 3)
    error = float(np.sqrt(variance * np.linalg.inv(design.T @ design)[0, 0]))
    if not curve > BOWL_Z * error:
        return 0
    return int(np.clip(np.round(-slope / (2 * curve)), near.min(), near.max()))


def best_shift(rgb_centres: np.ndarray, t_centres: np.ndarray, max_shift: int, min_pairs: int | None = None) -> int:
    """The frame shift s (RGB frame i shows what thermal frame i + s shows) whose pairs fit one transform best.

    Only shifts that pair at least ``min_pairs`` frames are tried (default: half of the frames labelled in the
    camera with fewer, at least 3), so a shift that keeps a handful of frames cannot win by fitting them closely.
    The shift is the bottom of the score curve near its lowest point (:func:`_vertex`); 0 where the curve shows no
    bowl (a target standing still: any shift fits), so a static target never invents a clock offset.
    """
    valid_a, valid_b = ~np.isnan(rgb_centres[:, 0]), ~np.isnan(t_centres[:, 0])
    if min_pairs is None:
        min_pairs = max(3, int(min(valid_a.sum(), valid_b.sum())) // 2)
    scores = {}
    for shift in range(-max_shift, max_shift + 1):
        i, j = _pairs_at(valid_a, valid_b, shift)
        if len(i) >= min_pairs:
            scores[shift] = _shift_score(rgb_centres[i], t_centres[j])
    finite = {s: v for s, v in scores.items() if np.isfinite(v)}
    if not finite:
        return 0
    return _vertex(finite, min(finite, key=lambda s: (finite[s], abs(s))))


def _correspondences(a: np.ndarray, b: np.ndarray, i: np.ndarray,
                     j: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str], np.ndarray, str]:
    """RGB and thermal points of the paired frames ``i`` / ``j`` of boxes ``a`` / ``b``: the box centres, and the
    top-left and bottom-right corners where the boxes' size ratio is steady; a label and the frame of each point,
    and the note that says which were used."""
    ca, cb = _centres(a), _centres(b)
    rgb_pts, t_pts, frames = [ca[i]], [cb[j]], [i]
    labels = [f"frame {k}" for k in i]
    ratios = b[j, 2:] / a[i, 2:]
    median = np.median(ratios, axis=0)
    spread = np.median(np.abs(ratios - median), axis=0) / median
    if len(i) < MIN_SIZE_FRAMES or not (spread < SIZE_RATIO_SPREAD).all():
        note = f"box sizes disagree between the cameras (size ratio spread {spread.max():.1%}): centres only"
        return ca[i], cb[j], labels, i, note
    for corner, sign in (("top-left", -0.5), ("bottom-right", 0.5)):
        rgb_pts.append(ca[i] + sign * a[i, 2:])
        t_pts.append(cb[j] + sign * b[j, 2:])
        labels += [f"frame {k} {corner}" for k in i]
        frames.append(i)
    note = f"box sizes agree (size ratio spread {spread.max():.1%}): box corners used with the centres"
    return np.concatenate(rgb_pts), np.concatenate(t_pts), labels, np.concatenate(frames), note


def smoothed(points: np.ndarray, frames: int = SMOOTH_FRAMES) -> np.ndarray:
    """Moving average of a track (N, 2) over ``frames`` consecutive rows (fewer rows than that: as given)."""
    if len(points) < frames:
        return points
    kernel = np.ones(frames) / frames
    return np.stack([np.convolve(points[:, k], kernel, mode="valid") for k in range(2)], axis=1)


def check_one_target(rgb_centres: np.ndarray, t_centres: np.ndarray, what: str) -> None:
    """Refuse two tracks that no similarity relates: boxes of different targets, or a target that hardly moves.

    Judged on the tracks smoothed in time (:func:`smoothed`): label jitter is independent from frame to frame and
    averages out, while the difference between two targets' paths is smooth and stays. The similarity through the
    smoothed pairs must leave residuals (robust scale) below ``TRACK_SHARE`` of the smoothed thermal track's RMS
    spread.
    """
    rgb, thermal = smoothed(rgb_centres), smoothed(t_centres)
    deltas = project(similarity_both_noisy(rgb, thermal), rgb) - thermal
    scale, spread = robust_scale(deltas), rms_spread(thermal)
    if scale > TRACK_SHARE * spread:
        raise RegistrationError(f"{what}: the two tracks do not follow one similarity: averaged over {SMOOTH_FRAMES} "
                                f"frames, the residuals (robust scale {scale:.2f} px) are {scale / max(spread, 1e-9):.0%}"
                                f" of the thermal track's spread ({spread:.1f} px RMS); are they boxes of one target, "
                                "and does it move?")


def calibrate_from_boxes(rgb_boxes: str | os.PathLike, t_boxes: str | os.PathLike, rgb_size: tuple[int, int],
                         thermal_size: tuple[int, int], *, model: str = "auto", fps: float = 30.0,
                         max_offset: float = 2.0, threshold: float | None = None,
                         max_rms: float | None = None) -> SourceFit:
    """Fit the RGB->T transform (and the clock offset) to a target's boxes in both cameras.

    Parameters
    ----------
    rgb_boxes, t_boxes : path
        One box per frame in each camera's pixels (see :func:`read_track_boxes`), the same frames in both files.
    rgb_size, thermal_size : (w, h)
        The cameras' frame sizes, recorded in the calibration.
    model : {"auto", "homography", "affine", "similarity"}
        ``"auto"``: the model the boxes' spread over the frame supports
        (:func:`~rgbt_toolkit.registration.weigh.choose_model`).
    fps : float
        Frame rate of the tracks, to report the frame shift in seconds.
    max_offset : float
        Largest clock offset searched, seconds (0: frames pair by index only).
    threshold, max_rms : float, optional
        As :func:`~rgbt_toolkit.registration.fit.fit_points`: by default the acceptance comes from the residuals'
        robust scale (labels jitter by a few pixels) and no fixed RMS limit applies.

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
    shift = best_shift(ca, cb, min(max_shift, max(len(a) - 3, 0)))
    i, j = _pairs_at(~np.isnan(ca[:, 0]), ~np.isnan(cb[:, 0]), shift)
    if len(i) == 0:
        raise InputError(f"{what}: no frame has a box in both files; they must track the same target over the "
                         "same frames")
    what_centres = f"{what} (box centres of {len(i)} common frames)"
    check_correspondences(ca[i], cb[j], "similarity" if model == "auto" else model, what_centres)
    notes = []
    along, across = line_spread(ca[i])
    if across < NEAR_LINE_RATIO * along:
        notes.append(f"warning: the target's path is nearly a line ({across:.1f} px across, {along:.1f} px along): "
                     "rotation and perspective off that line are poorly determined; a path across the view is better")
    if threshold is None:
        check_one_target(ca[i], cb[j], what_centres)
    rgb_pts, t_pts, labels, frames, note = _correspondences(a, b, i, j)
    notes.append(note)
    weighed = fit_weighed(rgb_pts, t_pts, model, rgb_size, thermal_size, threshold=threshold, max_rms=max_rms,
                          what=what_centres, groups=frames, spread_check=False)
    offset = shift / fps
    if shift:
        notes.append(f"time shift: RGB frame i pairs with thermal frame i{shift:+d}, clock offset {offset:+.3f} s at "
                     f"{fps:g} fps (thermal = RGB + offset)")
    else:
        notes.append(f"time shift: none found within ±{max_offset:g} s (frames pair by index)")
    calibration = calibration_from_fit(weighed.fit, "boxes", rgb_size, thermal_size, time_offset=offset,
                                       pairs_used=len(i), evidence=weighed.evidence())
    return SourceFit(calibration, weighed.fit, tuple(labels), tuple(weighed.lines() + notes))
