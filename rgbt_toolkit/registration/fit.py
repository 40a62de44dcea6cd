"""Robust fit of an RGB->T transform to point correspondences, shared by the points, boxes and board sources.

A correspondence is one point seen by both cameras (a hand-picked feature, a target's box centre in one frame, a
board corner). RANSAC (OpenCV's ``estimateAffinePartial2D`` / ``estimateAffine2D`` / ``findHomography``) finds the
transform most points agree with; the agreeing points are refitted by least squares, and every point gets its
residual (distance in thermal pixels between where the fit sends its RGB point and its thermal point). Points that
cannot determine the model (too few, all on one line) and fits whose residuals are too large are refused with one
line that says what to change, so no calibration is written from them. Unless a threshold is given, what counts as
agreeing comes from the evidence's own noise (:func:`robust_scale` of the residuals): hand labels that jitter by a
few pixels and clicks precise to a fraction of one are each held to their own precision.
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
SCALE_FACTOR = 3.0  # default acceptance: within 3 robust scales (a 2-D Gaussian keeps 98.9 % of its points there)
THRESHOLD_FLOOR = 1.0  # px: whole-pixel labels scatter by about 0.4 px; a tighter limit drops good points
THRESHOLD_CEILING = 30.0  # px: evidence noisier than 10 px (robust scale) is refused unless --threshold is given
# residual scale above this share of the thermal points' RMS spread: the fit explains less than half their variance
# (rows that pair unrelated points: about 0.7). Boxes are judged on smoothed tracks instead (from_boxes.TRACK_SHARE)
MAX_SCALE_SHARE = 0.5
REWEIGH_ROUNDS = 3  # scale, inliers and refit repeated: the first estimate's scale includes its own error


@dataclass(frozen=True)
class PointFit:
    """A transform fitted to correspondences, with each one's residual and whether the fit kept it."""

    matrix: np.ndarray  # 3x3 RGB pixels -> thermal pixels
    model: str
    residuals: np.ndarray  # (N,) thermal pixels, every correspondence
    inliers: np.ndarray  # (N,) bool
    scale: float = float("nan")  # robust scale of the residual components (see robust_scale), thermal pixels
    threshold: float = float("nan")  # the acceptance the inliers were chosen with, thermal pixels
    adaptive: bool = False  # True: the threshold came from ``scale``; False: it was given

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


def least_squares(rgb: np.ndarray, thermal: np.ndarray, model: str) -> np.ndarray | None:
    """Least-squares ``model`` through all given points (they all count as inliers)."""
    if model == "homography":
        matrix, _ = cv2.findHomography(rgb.astype(np.float64), thermal.astype(np.float64), 0)
        return matrix
    return _linear(rgb, thermal, model)


def similarity_both_noisy(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """The similarity ``dst ~ s R src + t`` when both point sets are noisy, equally in their own pixels.

    Least squares in ``dst`` alone treats ``src`` as exact and shrinks the scale by the share of ``src``'s spread
    that is noise (regression dilution): for hand labels of a target kept near the centre, jitter of 3 px against a
    spread of 15 px, 12 % too small a scale, 25 px off at the thermal frame's corners. Minimising
    ``sum |dst - s R src - t|^2 / (1 + s^2)`` (the maximum-likelihood fit under equal noise on both sides) gives
    ``s`` as the positive root of ``C s^2 + (Sxx - Syy) s - C = 0`` with ``Sxx``, ``Syy`` the centred sums of
    squares and ``C`` the Procrustes correlation; exact points give the exact similarity either way.
    """
    src_mean, dst_mean = src.mean(axis=0), dst.mean(axis=0)
    x, y = src - src_mean, dst - dst_mean
    dot, cross = float(np.sum(x * y)), float(np.sum(x[:, 0] * y[:, 1] - x[:, 1] * y[:, 0]))
    corr = np.hypot(dot, cross)
    if corr < 1e-12:  # no relation between the two sets: no rotation or scale to find
        return np.array([[0.0, 0.0, dst_mean[0]], [0.0, 0.0, dst_mean[1]], [0, 0, 1.0]])
    excess = float(np.sum(x ** 2) - np.sum(y ** 2))
    scale = (-excess + np.sqrt(excess ** 2 + 4 * corr ** 2)) / (2 * corr)
    rotation = scale * np.array([[dot, -cross], [cross, dot]]) / corr
    return np.vstack([np.c_[rotation, dst_mean - rotation @ src_mean], [0, 0, 1.0]])


def _linear(src: np.ndarray, dst: np.ndarray, model: str) -> np.ndarray:
    if model == "similarity":
        return similarity_both_noisy(src, dst)
    n = len(src)
    design = np.zeros((2 * n, 6))
    design[0::2, 0:2], design[0::2, 2] = src, 1
    design[1::2, 3:5], design[1::2, 5] = src, 1
    p = np.linalg.lstsq(design, dst.ravel(), rcond=None)[0]
    return np.array([[p[0], p[1], p[2]], [p[3], p[4], p[5]], [0, 0, 1.0]])


def robust_scale(deltas: np.ndarray) -> float:
    """Robust standard deviation of residual vectors (N, 2): 1.4826 x the median absolute deviation of their x and
    y components, which equals the standard deviation for Gaussian noise and ignores a minority of outliers."""
    components = np.asarray(deltas, dtype=float).ravel()
    return float(1.4826 * np.median(np.abs(components - np.median(components))))


def _lmeds(rgb: np.ndarray, thermal: np.ndarray, model: str, seed: int) -> np.ndarray | None:
    """Least-median-of-squares ``model``: robust to up to half the points being wrong, with no threshold to set."""
    src, dst = rgb.astype(np.float64), thermal.astype(np.float64)
    cv2.setRNGSeed(seed)  # its random samples come from OpenCV's global generator, as RANSAC's
    if model == "homography":
        matrix, _ = cv2.findHomography(src, dst, cv2.LMEDS)
        return matrix
    estimate = cv2.estimateAffinePartial2D if model == "similarity" else cv2.estimateAffine2D
    matrix, _ = estimate(src, dst, method=cv2.LMEDS, refineIters=10)
    return None if matrix is None else np.vstack([matrix, [0.0, 0.0, 1.0]])


def usable_matrix(matrix: np.ndarray | None) -> bool:
    """A finite 3x3 whose projective scale is not zero (OpenCV returns None or NaN where a fit failed)."""
    return matrix is not None and bool(np.isfinite(matrix).all()) and abs(matrix[2, 2]) > 1e-12


def _refit(matrix: np.ndarray, rgb: np.ndarray, thermal: np.ndarray, model: str, inliers: np.ndarray,
           what: str) -> np.ndarray:
    """Least squares on the agreeing points (the final estimate uses all of them); ``matrix`` where they alone are
    too few or degenerate."""
    if inliers.sum() < MIN_POINTS[model]:
        return matrix
    try:
        check_correspondences(rgb[inliers], thermal[inliers], model, what)
    except InputError:
        return matrix
    refit = least_squares(rgb[inliers], thermal[inliers], model)
    return refit if usable_matrix(refit) else matrix


def _scaled_threshold(deltas: np.ndarray, model: str) -> tuple[float, float]:
    """The noise scale of residuals ``deltas`` of a ``model`` fit and the acceptance it sets: ``SCALE_FACTOR``
    scales, within the floor and ceiling.

    The fit took ``2 * MIN_POINTS`` parameters from the ``2 N`` residual components, which are therefore smaller
    than the noise; the robust scale is raised by ``sqrt(2 N / (2 N - parameters))``, as a variance is divided by
    its degrees of freedom (a homography through 8 points would otherwise see a third of the noise and drop good
    points).
    """
    components, parameters = 2 * len(deltas), 2 * MIN_POINTS[model]
    scale = robust_scale(deltas) * np.sqrt(components / max(components - parameters, 1))
    return float(scale), float(np.clip(SCALE_FACTOR * scale, THRESHOLD_FLOOR, THRESHOLD_CEILING))


def fit_points(rgb, thermal, model: str = "homography", *, threshold: float | None = None,
               max_rms: float | None = None, min_inlier_fraction: float = 0.5, what: str = "correspondences",
               seed: int = 0, spread_check: bool = True) -> PointFit:
    """Fit ``model`` (RGB -> thermal) robustly to (N, 2) point pairs; refuse degenerate input and poor fits.

    Parameters
    ----------
    rgb, thermal : array-like (N, 2)
        The same N points in RGB and in thermal pixels.
    model : {"homography", "affine", "similarity"}
    threshold : float, optional
        Thermal pixels within which a point agrees with the fit; farther points are outliers. By default it comes
        from the evidence's own noise: ``SCALE_FACTOR`` (3) times the residuals' robust scale (see
        :func:`robust_scale`), at least ``THRESHOLD_FLOOR`` and at most ``THRESHOLD_CEILING`` px, so hand labels
        that jitter by a few pixels are accepted and precise clicks are held to their precision.
    max_rms : float, optional
        Largest accepted RMS residual of the kept points (thermal pixels); by default none beyond the threshold.
    min_inlier_fraction : float
        At least this share of the points must agree, else the "outliers" are the majority and the fit is refused.
    what : str
        Names the evidence in messages (e.g. the points file).
    seed : int
        RANSAC's random seed (OpenCV's generator is global; it is set here so results repeat).
    spread_check : bool
        With the default threshold, refuse residuals whose scale is over ``MAX_SCALE_SHARE`` of the thermal points'
        RMS spread (the fit explains less than half of it). False where the caller judges that itself: a target's
        boxes, whose jitter can exceed the motion of a followed target, are judged on tracks smoothed in time.

    Raises
    ------
    InputError
        Too few points, all at one place or on one line (for affine/homography).
    RegistrationError
        No transform found, a mirrored or folded one, too few points agree, residuals above ``max_rms``, or (with
        the default threshold) residuals that scatter beyond the ceiling or over a large share of the evidence's
        own spread: pairs of different targets, or of no one planar transform.
    """
    rgb, thermal = (np.asarray(p, dtype=float).reshape(-1, 2) for p in (rgb, thermal))
    if len(rgb) != len(thermal):
        raise InputError(f"{what}: {len(rgb)} RGB points but {len(thermal)} thermal points")
    if not (np.isfinite(rgb).all() and np.isfinite(thermal).all()):
        raise InputError(f"{what}: points must be finite numbers")
    check_correspondences(rgb, thermal, model, what)
    matrix = _initial(rgb, thermal, model, threshold, seed)
    if not usable_matrix(matrix):
        raise RegistrationError(f"{what}: no {model} fits these points; check that each row pairs the same point "
                                "in both cameras")
    for _ in range(1 if threshold is not None else REWEIGH_ROUNDS):
        deltas = project(normalize(matrix), rgb) - thermal
        limit = _scaled_threshold(deltas, model)[1] if threshold is None else threshold
        matrix = _refit(matrix, rgb, thermal, model, np.linalg.norm(deltas, axis=1) <= limit, what)
    matrix = normalize(matrix)
    deltas = project(matrix, rgb) - thermal
    residuals = np.linalg.norm(deltas, axis=1)
    scale, scaled = _scaled_threshold(deltas, model)
    limit = scaled if threshold is None else threshold
    fit = PointFit(matrix, model, residuals, residuals <= limit, scale, limit, threshold is None)
    _check_fit(fit, thermal, max_rms, min_inlier_fraction, what, spread_check)
    return fit


def _initial(rgb: np.ndarray, thermal: np.ndarray, model: str, threshold: float | None,
             seed: int) -> np.ndarray | None:
    """A first robust estimate: RANSAC within a given threshold, least median of squares without one, and plain
    least squares where the points are exactly as many as the model needs."""
    matrix = None
    if len(rgb) > MIN_POINTS[model]:
        matrix = (_ransac(rgb, thermal, model, threshold, seed) if threshold is not None
                  else _lmeds(rgb, thermal, model, seed))
    return matrix if usable_matrix(matrix) else least_squares(rgb, thermal, model)


def rms_spread(points: np.ndarray) -> float:
    """RMS distance of ``points`` (N, 2) from their mean, pixels (0 for fewer than two)."""
    if len(points) < 2:
        return 0.0
    return float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=1))))


def _check_fit(fit: PointFit, thermal: np.ndarray, max_rms: float | None, min_inlier_fraction: float,
               what: str, spread_check: bool = True) -> None:
    """Refuse a fit its own evidence does not support (see :func:`fit_points`)."""
    if abs(np.linalg.det(fit.matrix)) < 1e-12:
        raise RegistrationError(f"{what}: the fitted {fit.model} maps the whole image to a point or a line; the two "
                                "cameras' points are not related (check that each row pairs the same point)")
    n, kept = len(fit.residuals), int(fit.inliers.sum())
    where = (f"{fit.threshold:.1f} px ({SCALE_FACTOR:g} x their residual scale {fit.scale:.2f} px, within "
             f"{THRESHOLD_FLOOR:g}-{THRESHOLD_CEILING:g} px)" if fit.adaptive else f"{fit.threshold:g} px")
    spread = rms_spread(thermal[fit.inliers])
    if spread_check and fit.adaptive and kept >= 2 and fit.scale > MAX_SCALE_SHARE * spread:
        raise RegistrationError(f"{what}: the residuals (robust scale {fit.scale:.2f} px) are {fit.scale / spread:.0%}"
                                f" of how far the thermal points spread ({spread:.1f} px RMS): the pairs follow no one"
                                f" {fit.model} (boxes of different targets, or rows that do not pair the same point); "
                                "check the pairs")
    if fit.adaptive and SCALE_FACTOR * fit.scale > THRESHOLD_CEILING:
        raise RegistrationError(f"{what}: the correspondences scatter by {fit.scale:.2f} px (robust scale of the "
                                "residuals), more than a calibration can use (at most "
                                f"{THRESHOLD_CEILING / SCALE_FACTOR:.1f} px); check the pairs, or give --threshold")
    # an outlier is only named against kept points that over-determine the model (2 beyond the minimum): any
    # MIN_POINTS points fit exactly, so leaving the rest out would prove nothing
    needed = MIN_POINTS[fit.model] + (2 if kept < n else 0)
    if kept < max(needed, int(np.ceil(min_inlier_fraction * n))):
        raise RegistrationError(f"{what}: only {kept} of {n} correspondences agree within {where} (median residual "
                                f"{np.median(fit.residuals):.1f} px); check the pairs, or raise --threshold")
    if max_rms is not None and fit.rms > max_rms:
        raise RegistrationError(f"{what}: residuals too large (RMS {fit.rms:.2f} px, max {fit.max:.2f} px, "
                                f"accepted up to {max_rms:g} px RMS); check the pairs or try another --model")
    if decompose(fit.matrix)["mirrored"]:
        raise RegistrationError(f"{what}: the fitted {fit.model} mirrors the image; check that the RGB and thermal "
                                "columns are not swapped or flipped")


@dataclass(frozen=True)
class SourceFit:
    """A calibration fitted to one source of evidence, with names for its correspondences (for the report)."""

    calibration: Calibration
    fit: PointFit
    labels: tuple[str, ...]  # one per correspondence: "line 7", "frame 12", "view 3 corner 5"
    notes: tuple[str, ...] = ()  # further findings worth a line (the boxes' time shift, board views found)


def calibration_from_fit(fit: PointFit, source: str, rgb_size: tuple[int, int], thermal_size: tuple[int, int], *,
                         time_offset: float = 0.0, pairs_used: int = 0, evidence: dict | None = None) -> Calibration:
    """The calibration JSON's record of a point fit: matrix, source, residuals, outliers and ``evidence`` (see
    :meth:`rgbt_toolkit.registration.weigh.WeighedFit.evidence`)."""
    return Calibration(fit.matrix, fit.model, tuple(int(v) for v in rgb_size), tuple(int(v) for v in thermal_size),
                       time_offset=float(time_offset), pairs_used=int(pairs_used), source=source,
                       residuals=tuple(float(v) for v in fit.residuals),
                       outliers=tuple(int(i) for i in fit.outliers), evidence=evidence)


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
