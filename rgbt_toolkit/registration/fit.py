"""Robust fit of an RGB->T transform to point correspondences, shared by the points, boxes and board sources.

A correspondence is one point seen by both cameras (a hand-picked feature, a target's box centre in one frame, a
board corner). RANSAC (OpenCV's ``estimateAffinePartial2D`` / ``estimateAffine2D`` / ``findHomography``) finds the
transform most points agree with; the agreeing points are refitted by least squares, and every point gets its
residual (distance in thermal pixels between where the fit sends its RGB point and its thermal point). Points that
cannot determine the model (too few, all on one line) and fits whose residuals are too large are refused with one
line that says what to change, so no calibration is written from them.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.registration.calib import Calibration
from rgbt_toolkit.registration.transforms import check_model, decompose, normalize, project

MIN_POINTS = {"similarity": 2, "affine": 3, "homography": 4}
COLLINEAR_RATIO = 0.01  # spread across the points' main line / spread along it, below which they count as a line


@dataclass(frozen=True)
class PointFit:
    """A transform fitted to correspondences, with each one's residual and whether the fit kept it."""

    matrix: np.ndarray  # 3x3 RGB pixels -> thermal pixels
    model: str
    residuals: np.ndarray  # (N,) thermal pixels, every correspondence
    inliers: np.ndarray  # (N,) bool

    @property
    def outliers(self) -> np.ndarray:
        """Indices of the correspondences the fit left out."""
        return np.flatnonzero(~self.inliers)

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals[self.inliers] ** 2)))

    @property
    def max(self) -> float:
        return float(self.residuals[self.inliers].max())


def line_spread(points: np.ndarray) -> tuple[float, float]:
    """Standard deviation of ``points`` along and across their main direction (pixels)."""
    centred = points - points.mean(axis=0)
    singular = np.linalg.svd(centred, compute_uv=False) / np.sqrt(len(points))
    return float(singular[0]), float(singular[-1]) if len(singular) > 1 else 0.0


def check_correspondences(rgb: np.ndarray, thermal: np.ndarray, model: str, what: str) -> None:
    """Refuse correspondences that cannot determine ``model``: too few, repeated, or all on one line.

    ``what`` names the evidence in the message (e.g. the points file).
    """
    check_model(model)
    need = MIN_POINTS[model]
    if len(rgb) < need:
        raise InputError(f"{what}: {len(rgb)} correspondence(s); a {model} needs at least {need}"
                         + (" (or use --model similarity, which needs 2)" if model != "similarity" else ""))
    for points, camera in ((rgb, "RGB"), (thermal, "thermal")):
        along, across = line_spread(points)
        if along < 1.0:
            raise InputError(f"{what}: the {camera} points all lie at one place; pick points spread over the view")
        if model != "similarity" and across < COLLINEAR_RATIO * along:
            raise InputError(f"{what}: the {camera} points lie on one line, so a {model} cannot be fitted (it needs "
                             "points off that line); add points off the line, or use --model similarity")


def _ransac(rgb: np.ndarray, thermal: np.ndarray, model: str, threshold: float, seed: int) -> np.ndarray | None:
    src, dst = rgb.astype(np.float64), thermal.astype(np.float64)
    cv2.setRNGSeed(seed)  # OpenCV's RANSAC draws from its global generator: fix it so a fit repeats exactly
    if model == "homography":
        matrix, _ = cv2.findHomography(src, dst, cv2.RANSAC, threshold, maxIters=5000, confidence=0.999)
        return matrix
    estimate = cv2.estimateAffinePartial2D if model == "similarity" else cv2.estimateAffine2D
    matrix, _ = estimate(src, dst, method=cv2.RANSAC, ransacReprojThreshold=threshold, maxIters=5000,
                         confidence=0.999, refineIters=10)
    return None if matrix is None else np.vstack([matrix, [0.0, 0.0, 1.0]])


def _least_squares(rgb: np.ndarray, thermal: np.ndarray, model: str) -> np.ndarray | None:
    """Least-squares ``model`` through all given points (they all count as inliers)."""
    if model == "homography":
        matrix, _ = cv2.findHomography(rgb.astype(np.float64), thermal.astype(np.float64), 0)
        return matrix
    return _linear(rgb, thermal, model)


def _linear(src: np.ndarray, dst: np.ndarray, model: str) -> np.ndarray:
    n = len(src)
    if model == "similarity":  # x' = a x - b y + tx, y' = b x + a y + ty
        design = np.zeros((2 * n, 4))
        design[0::2] = np.c_[src[:, 0], -src[:, 1], np.ones(n), np.zeros(n)]
        design[1::2] = np.c_[src[:, 1], src[:, 0], np.zeros(n), np.ones(n)]
        a, b, tx, ty = np.linalg.lstsq(design, dst.ravel(), rcond=None)[0]
        return np.array([[a, -b, tx], [b, a, ty], [0, 0, 1.0]])
    design = np.zeros((2 * n, 6))
    design[0::2, 0:2], design[0::2, 2] = src, 1
    design[1::2, 3:5], design[1::2, 5] = src, 1
    p = np.linalg.lstsq(design, dst.ravel(), rcond=None)[0]
    return np.array([[p[0], p[1], p[2]], [p[3], p[4], p[5]], [0, 0, 1.0]])


def fit_points(rgb, thermal, model: str = "homography", *, threshold: float = 4.0, max_rms: float = 2.0,
               min_inlier_fraction: float = 0.5, what: str = "correspondences", seed: int = 0) -> PointFit:
    """Fit ``model`` (RGB -> thermal) robustly to (N, 2) point pairs; refuse degenerate input and poor fits.

    Parameters
    ----------
    rgb, thermal : array-like (N, 2)
        The same N points in RGB and in thermal pixels.
    model : {"homography", "affine", "similarity"}
    threshold : float
        Thermal pixels within which a point agrees with a RANSAC hypothesis; farther points are outliers.
    max_rms : float
        Largest accepted RMS residual of the kept points (thermal pixels), below ``threshold``: above it the points
        disagree with any single planar transform (imprecise clicks, a scene far from planar) and the fit is
        refused.
    min_inlier_fraction : float
        At least this share of the points must agree, else the "outliers" are the majority and the fit is refused.
    what : str
        Names the evidence in messages (e.g. the points file).
    seed : int
        RANSAC's random seed (OpenCV's generator is global; it is set here so results repeat).

    Raises
    ------
    InputError
        Too few points, all at one place or on one line (for affine/homography).
    RegistrationError
        No transform found, a mirrored or folded one, too few points agree, or residuals above ``max_rms``.
    """
    rgb, thermal = (np.asarray(p, dtype=float).reshape(-1, 2) for p in (rgb, thermal))
    if len(rgb) != len(thermal):
        raise InputError(f"{what}: {len(rgb)} RGB points but {len(thermal)} thermal points")
    if not (np.isfinite(rgb).all() and np.isfinite(thermal).all()):
        raise InputError(f"{what}: points must be finite numbers")
    check_correspondences(rgb, thermal, model, what)
    matrix = _ransac(rgb, thermal, model, threshold, seed) if len(rgb) > MIN_POINTS[model] else None
    if matrix is None:
        matrix = _least_squares(rgb, thermal, model)
    if matrix is None or not np.isfinite(matrix).all() or abs(matrix[2, 2]) < 1e-12:
        raise RegistrationError(f"{what}: no {model} fits these points; check that each row pairs the same point "
                                "in both cameras")
    inliers = np.linalg.norm(project(normalize(matrix), rgb) - thermal, axis=1) <= threshold
    if inliers.sum() >= MIN_POINTS[model]:  # refit on the agreeing points: the final estimate uses all of them
        try:
            check_correspondences(rgb[inliers], thermal[inliers], model, what)
            refit = _least_squares(rgb[inliers], thermal[inliers], model)
            if refit is not None and np.isfinite(refit).all() and abs(refit[2, 2]) > 1e-12:
                matrix = refit
        except InputError:
            pass  # the agreeing subset alone is degenerate: keep the RANSAC estimate from all points
    matrix = normalize(matrix)
    residuals = np.linalg.norm(project(matrix, rgb) - thermal, axis=1)
    inliers = residuals <= threshold
    fit = PointFit(matrix, model, residuals, inliers)
    if inliers.sum() < max(MIN_POINTS[model], int(np.ceil(min_inlier_fraction * len(rgb)))):
        raise RegistrationError(f"{what}: only {int(inliers.sum())} of {len(rgb)} correspondences agree within "
                                f"{threshold:g} px (median residual {np.median(residuals):.1f} px); check the "
                                "pairs, or raise --threshold")
    if fit.rms > max_rms:
        raise RegistrationError(f"{what}: residuals too large (RMS {fit.rms:.2f} px, max {fit.max:.2f} px, "
                                f"accepted up to {max_rms:g} px RMS); check the pairs or try another --model")
    if decompose(matrix)["mirrored"]:
        raise RegistrationError(f"{what}: the fitted {model} mirrors the image; check that the RGB and thermal "
                                "columns are not swapped or flipped")
    return fit


@dataclass(frozen=True)
class SourceFit:
    """A calibration fitted to one source of evidence, with names for its correspondences (for the report)."""

    calibration: Calibration
    fit: PointFit
    labels: tuple[str, ...]  # one per correspondence: "line 7", "frame 12", "view 3 corner 5"
    notes: tuple[str, ...] = ()  # further findings worth a line (the boxes' time shift, board views found)


def calibration_from_fit(fit: PointFit, source: str, rgb_size: tuple[int, int], thermal_size: tuple[int, int], *,
                         time_offset: float = 0.0, pairs_used: int = 0) -> Calibration:
    """The calibration JSON's record of a point fit: matrix, source, residuals and outliers."""
    return Calibration(fit.matrix, fit.model, tuple(int(v) for v in rgb_size), tuple(int(v) for v in thermal_size),
                       time_offset=float(time_offset), pairs_used=int(pairs_used), source=source,
                       residuals=tuple(float(v) for v in fit.residuals),
                       outliers=tuple(int(i) for i in fit.outliers))


def fit_summary_lines(result: SourceFit, worst: int = 5) -> list[str]:
    """What ``rgbt register`` prints for a fitted source: the matrix, residuals, the worst points, outliers."""
    cal, fit = result.calibration, result.fit
    parts = decompose(cal.matrix)
    rows = [f"RGB -> thermal {cal.model} (from {cal.source}):"]
    rows += ["  [" + "  ".join(f"{v:12.6g}" for v in row) + " ]" for row in cal.matrix]
    rows.append(f"  scale {parts['scale']:.4f}, rotation {parts['rotation_deg']:+.2f} deg, shift "
                f"({parts['shift_x']:+.1f}, {parts['shift_y']:+.1f}) px; RGB {cal.rgb_size[0]}x{cal.rgb_size[1]} -> "
                f"thermal {cal.thermal_size[0]}x{cal.thermal_size[1]}")
    kept = int(fit.inliers.sum())
    rows.append(f"residuals: RMS {fit.rms:.2f} px, max {fit.max:.2f} px (thermal pixels) over {kept} of "
                f"{len(fit.residuals)} correspondences")
    order = np.argsort(-np.where(fit.inliers, fit.residuals, -1.0))[:worst]
    shown = [f"{result.labels[i]} {fit.residuals[i]:.2f}" for i in order if fit.inliers[i]]
    if shown:
        rows.append("  largest kept: " + ", ".join(shown))
    if len(fit.outliers):
        named = ", ".join(f"{result.labels[i]} ({fit.residuals[i]:.1f} px)" for i in fit.outliers[:20])
        more = f" and {len(fit.outliers) - 20} more" if len(fit.outliers) > 20 else ""
        rows.append(f"outliers left out ({len(fit.outliers)}): {named}{more}")
    else:
        rows.append("outliers: none")
    rows += list(result.notes)
    return rows
