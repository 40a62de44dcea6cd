"""What a calibration's evidence supports: the model it can determine, and how far to trust the fit over the frame.

Correspondences from hand labels or hand clicks rarely cover the frame: a gimbal keeps a followed drone near the
centre, so its boxes fill a small patch. A homography fitted there reproduces the patch and bends the rest of the
frame at will (on a real pair 45 px off at two corners), while a similarity, with no perspective terms to bend,
extrapolates sanely. :func:`choose_model` therefore takes a homography only when the kept points span enough of the
RGB frame in both directions, and says why. :func:`bootstrap_uncertainty` refits the model to resampled evidence and
reports how far the thermal frame's centre and corners move between the refits: small where the evidence lies,
larger where the fit extrapolates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.registration.fit import (
    MIN_POINTS, SCALE_FACTOR, THRESHOLD_CEILING, THRESHOLD_FLOOR, PointFit, fit_points, least_squares, line_spread,
    usable_matrix,
)
from rgbt_toolkit.registration.transforms import check_model, normalize, project

HOMOGRAPHY_SPAN = 0.5  # a homography when the kept RGB points span half the frame's width and half its height
# and at least this many: 4 fix it exactly, and through fewer than 10 clicked points (0.5 px noise) it bends to
# fit their noise, 7 px off at a good point left out (generated 8-point sets of the calibration benchmark)
HOMOGRAPHY_MIN_POINTS = 10
NEAR_LINE_SHARE = 0.15  # points whose spread across their main line is below this share of the spread along it
SPAN_PERCENTILES = (2.0, 98.0)  # the span between these percentiles: one stray label does not widen it
BOOTSTRAP_ROUNDS = 200  # resampled refits behind the uncertainty figures
PLACES = ("centre", "top_left", "top_right", "bottom_left", "bottom_right")


@dataclass(frozen=True)
class ModelChoice:
    """The model a fit uses and the sentence that says why."""

    model: str
    reason: str


def evidence_span(rgb: np.ndarray, rgb_size: tuple[int, int]) -> tuple[float, float]:
    """Share of the RGB frame's width and height that the points span (between the 2nd and 98th percentiles)."""
    low, high = np.percentile(np.asarray(rgb, dtype=float), SPAN_PERCENTILES, axis=0)
    return float((high[0] - low[0]) / rgb_size[0]), float((high[1] - low[1]) / rgb_size[1])


def choose_model(rgb: np.ndarray, rgb_size: tuple[int, int]) -> ModelChoice:
    """A homography when the points ``rgb`` (those a first fit kept) constrain its perspective terms, else a
    similarity: see the module docstring."""
    span_x, span_y = evidence_span(rgb, rgb_size)
    spans = f"the kept points span {span_x:.0%} x {span_y:.0%} of the RGB frame"
    if len(rgb) < HOMOGRAPHY_MIN_POINTS:
        return ModelChoice("similarity", f"similarity: {len(rgb)} kept points; a homography needs "
                                         f"{HOMOGRAPHY_MIN_POINTS} spread over the frame")
    along, across = line_spread(rgb)
    if across < NEAR_LINE_SHARE * along:
        return ModelChoice("similarity", f"similarity: the kept points lie near one line ({across:.1f} px across, "
                                         f"{along:.1f} px along), which leaves a homography's perspective free")
    if min(span_x, span_y) >= HOMOGRAPHY_SPAN:
        return ModelChoice("homography", f"homography: {spans} (at least {HOMOGRAPHY_SPAN:.0%} each way)")
    return ModelChoice("similarity", f"similarity: {spans}; a homography needs {HOMOGRAPHY_SPAN:.0%} each way, "
                                     "else its perspective is unconstrained away from them (--model homography "
                                     "forces it)")


def frame_places(thermal_size: tuple[int, int]) -> np.ndarray:
    """The thermal frame's centre and four corner pixels (5, 2), in the order of ``PLACES``."""
    w, h = thermal_size
    return np.array([[(w - 1) / 2, (h - 1) / 2], [0, 0], [w - 1, 0], [0, h - 1], [w - 1, h - 1]], dtype=float)


def bootstrap_uncertainty(matrix: np.ndarray, rgb: np.ndarray, thermal: np.ndarray, model: str,
                          thermal_size: tuple[int, int], *, groups: np.ndarray | None = None,
                          rounds: int = BOOTSTRAP_ROUNDS, seed: int = 0) -> dict[str, float]:
    """How far the fit's image of each place in ``PLACES`` moves when the evidence is resampled (thermal px, RMS).

    The RGB points that ``matrix`` maps to the thermal frame's centre and corners are mapped again by ``rounds``
    least-squares refits, each to the kept correspondences ``rgb`` -> ``thermal`` drawn with replacement; the
    figure is the RMS distance of those images from the fit's own. ``groups`` (one id per correspondence) resamples
    whole groups, e.g. a frame's box centre and corners together, since they share one label's error.
    """
    groups = np.arange(len(rgb)) if groups is None else np.asarray(groups)
    ids, members = np.unique(groups, return_inverse=True)
    rows = [np.flatnonzero(members == k) for k in range(len(ids))]
    places = frame_places(thermal_size)
    anchors = project(np.linalg.inv(matrix), places)
    rng = np.random.default_rng(seed)
    moved = []
    for _ in range(rounds):
        pick = np.concatenate([rows[k] for k in rng.integers(0, len(rows), len(rows))])
        if len(pick) < MIN_POINTS[model] or np.ptp(rgb[pick], axis=0).max() < 1.0:
            continue
        refit = least_squares(rgb[pick], thermal[pick], model)
        if usable_matrix(refit):
            moved.append(project(normalize(refit), anchors) - places)
    if not moved:
        return {name: float("nan") for name in PLACES}
    spread = np.sqrt(np.mean(np.sum(np.square(moved), axis=2), axis=0))
    return {name: round(float(v), 3) for name, v in zip(PLACES, spread)}


def uncertainty_line(uncertainty: dict[str, float], rounds: int = BOOTSTRAP_ROUNDS) -> str:
    """The printed summary of :func:`bootstrap_uncertainty`."""
    corners = " / ".join(f"{uncertainty[name]:.1f}" for name in PLACES[1:])
    return (f"uncertainty (thermal px, RMS over {rounds} resampled fits): centre {uncertainty['centre']:.1f}, "
            f"corners {corners} (top-left / top-right / bottom-left / bottom-right)")


@dataclass(frozen=True)
class WeighedFit:
    """A point fit with the model choice behind it and its bootstrap uncertainty."""

    fit: PointFit
    choice: ModelChoice
    uncertainty: dict[str, float]

    def evidence(self) -> dict:
        """The calibration JSON's ``evidence`` entry: how the fit was accepted, its model and its uncertainty."""
        return {"residual_scale": round(self.fit.scale, 4), "threshold": round(self.fit.threshold, 4),
                "threshold_rule": f"{SCALE_FACTOR:g} x residual scale, {THRESHOLD_FLOOR:g}-{THRESHOLD_CEILING:g} px"
                if self.fit.adaptive else "given (--threshold)",
                "model_choice": self.choice.reason,
                "uncertainty": {"units": "thermal px", "method": f"bootstrap, {BOOTSTRAP_ROUNDS} resampled fits",
                                **{k: v if np.isfinite(v) else None for k, v in self.uncertainty.items()}}}

    def lines(self) -> list[str]:
        """What ``rgbt register`` prints about it, after the residuals."""
        fit = self.fit
        rule = (f"{SCALE_FACTOR:g} x the residual scale {fit.scale:.2f} px" if fit.adaptive
                else f"given; residual scale {fit.scale:.2f} px")
        return [f"accepted within {fit.threshold:.2f} px ({rule})", f"model: {self.choice.reason}",
                uncertainty_line(self.uncertainty)]


def fit_weighed(rgb: np.ndarray, thermal: np.ndarray, model: str, rgb_size: tuple[int, int],
                thermal_size: tuple[int, int], *, threshold: float | None = None, max_rms: float | None = None,
                what: str = "correspondences", groups: np.ndarray | None = None,
                spread_check: bool = True) -> WeighedFit:
    """Fit the correspondences with ``model``, or with ``"auto"`` the model their spread supports
    (:func:`choose_model`: a robust similarity first, a homography when its kept points span the frame); then the
    bootstrap uncertainty of the result. ``threshold`` / ``max_rms`` / ``spread_check``: as :func:`fit_points`;
    ``groups``: as :func:`bootstrap_uncertainty`. Raises what :func:`fit_points` raises."""
    rgb, thermal = (np.asarray(p, dtype=float).reshape(-1, 2) for p in (rgb, thermal))
    if model == "auto":
        first = fit_points(rgb, thermal, "similarity", threshold=threshold, max_rms=max_rms, what=what,
                           spread_check=spread_check)
        choice = choose_model(rgb[first.inliers], rgb_size)
        fit = first if choice.model == "similarity" else fit_points(
            rgb, thermal, choice.model, threshold=threshold, max_rms=max_rms, what=what, spread_check=spread_check)
    else:
        check_model(model)
        fit = fit_points(rgb, thermal, model, threshold=threshold, max_rms=max_rms, what=what,
                         spread_check=spread_check)
        choice = ModelChoice(model, f"{model} (as asked with --model)")
    kept = fit.inliers
    uncertainty = bootstrap_uncertainty(fit.matrix, rgb[kept], thermal[kept], fit.model, thermal_size,
                                        groups=None if groups is None else np.asarray(groups)[kept])
    return WeighedFit(fit, choice, uncertainty)
