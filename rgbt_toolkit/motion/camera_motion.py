"""Camera motion estimation (CME, paper Sec. III-B-2) on the thermal stream, and compensation of the target position.

Keypoints of the previous and the current thermal frame are found with SIFT, matched with VLFeat's ratio test
(``vl_ubcmatch`` with threshold 1.7 on *squared* descriptor distances: a match is kept when
``1.7 * d_best^2 < d_second^2``), and a transform is fitted with MSAC: OpenCV's USAC with MSAC scoring for the
affine (the paper's default) and projective models, our own vectorised MSAC for translation and similarity (OpenCV
offers only plain RANSAC for those). The authors' toolbox runs at least 300 iterations with noise sigma 1 and a
chi-square inlier probability 1 - 1e-4 on the symmetric transfer error (4 degrees of freedom): a squared symmetric
error below 23.5 sigma^2, i.e. a one-way error below ``sigma * sqrt(23.5 / 2) = 3.43`` px, which is the threshold
used here. The box centre's displacement under the transform decides whether the camera moved (>= 5 px).

With ``CameraMotionSettings.points="flow"`` (the tracker's fast default) the matches come from pyramidal
Lucas-Kanade flow of corners between the two frames instead, kept only when tracking them back lands within
``flow_check_px`` of where they started; the same MSAC fit follows. Between consecutive frames of a moving camera that
gives the same transform as SIFT for a tenth of its cost (SIFT's first step doubles the frame, and its scale space is
the bulk of the work). When the flow cannot be trusted (too few corners come back, or too few of them fit one
transform: a jump larger than the pyramid reaches, a frame with little texture) the estimate falls back to SIFT, so
large jumps are found as before.

Conventions: a transform maps previous-frame pixel coordinates to current-frame coordinates (3x3, homogeneous);
boxes are ``[x, y, w, h]`` float arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion._robust import fit_opencv, fit_similarity, fit_translation
from rgbt_toolkit.motion.trigger import CameraMotionTrigger, TriggerResult, TriggerSettings, to_grey_uint8
from rgbt_toolkit.registration.overlays import OverlayMask, feature_mask
from rgbt_toolkit.registration.transforms import project

MOTION_MODELS = ("translation", "similarity", "affine", "projective")
POINT_SOURCES = ("sift", "flow")  # where the point matches come from (see the module docstring)
_MINIMAL_SAMPLE = {"translation": 1, "similarity": 2, "affine": 3, "projective": 4}


@lru_cache(maxsize=16)
def _chi2_quantile(p: float, dof: int) -> float:
    """``scipy.stats.chi2.ppf(p, dof)`` for an even ``dof``, by bisection on the closed-form CDF
    ``1 - exp(-x/2) sum_{k < dof/2} (x/2)^k / k!`` (importing scipy.stats cost 1-2 s of every `rgbt track`).
    Cached: every motion fit asks for the same threshold, and 100 bisection steps in Python cost 0.2 ms."""
    if dof % 2 or not 0 < p < 1:
        raise InputError(f"chi-square quantile needs an even dof and 0 < p < 1, got dof={dof}, p={p}")

    def cdf(x: float) -> float:
        half = x / 2
        return 1.0 - math.exp(-half) * sum(half**k / math.factorial(k) for k in range(dof // 2))

    lo, hi = 0.0, 1.0
    while cdf(hi) < p:
        hi *= 2
    for _ in range(100):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if cdf(mid) < p else (lo, mid)
    return (lo + hi) / 2


@dataclass(frozen=True)
class CameraMotionSettings:
    """Parameters of the estimator; defaults from the authors' ``FeatureMatching.m`` unless noted."""

    model: str = "affine"  # paper: "the affine transformation with six parameters is adopted in default"
    ratio: float = 1.7  # vl_ubcmatch threshold, on squared distances
    iterations: int = 300  # RANSAC toolbox min_iters
    confidence: float = 1.0  # 1.0 makes OpenCV run all `iterations` (the toolbox's minimum) instead of stopping early
    inlier_sigma: float = 1.0  # toolbox options.sigma
    inlier_probability: float = 1.0 - 1e-4  # toolbox options.P_inlier
    motion_threshold_px: float = 5.0  # isMotion when the box centre moves at least 5 px
    min_inliers: int = 6  # ours: fewer inliers than this is no reliable estimate
    max_keypoints: int = 1000  # ours: strongest SIFT keypoints kept (0 = all, as vl_sift); 640x480 thermal has
    # 1-3 thousand, and matching is quadratic in their number
    downscale: float = 1.0  # ours: SIFT on the frame resized by this factor (< 1 is faster); points mapped back
    seed: int = 1  # toolbox fix_seed = true (seed 1)
    points: str = "sift"  # ours: "sift" (the paper), or "flow": corners followed by Lucas-Kanade, SIFT when it fails
    flow_corners: int = 300  # ours: strongest corners followed (300 gave the same shifts as 500 on a real 1080p
    # street pair at 57 % of the time: benchmarks/bench_motion.py)
    flow_check_px: float = 0.5  # ours: forward-backward flow error (px at ``downscale``) up to which a corner counts
    flow_min_fraction: float = 0.5  # ours: the flow is trusted when at least this fraction of corners fit the motion
    overlay_refresh: int = 15  # ours: burned-in overlays (registration/overlays.py) are looked for every this many
    # frames and no point is taken on them (they stay put while the camera moves); 0 = never look

    def __post_init__(self) -> None:
        if self.model not in MOTION_MODELS:
            raise InputError(f"unknown camera motion model {self.model!r}; choose one of {', '.join(MOTION_MODELS)}")
        if self.points not in POINT_SOURCES:
            raise InputError(f"unknown camera motion points {self.points!r}; choose one of {', '.join(POINT_SOURCES)}")
        if self.iterations < 1 or self.ratio < 1.0 or not 0.1 <= self.downscale <= 1.0 or self.flow_corners < 8 \
                or self.overlay_refresh < 0:
            raise InputError("camera motion settings: iterations must be >= 1, ratio >= 1, downscale in [0.1, 1], "
                             "flow_corners >= 8, overlay_refresh >= 0")

    @property
    def threshold_px(self) -> float:
        """One-way transfer-error threshold equivalent to the toolbox's chi-square test on the symmetric error."""
        return float(self.inlier_sigma * np.sqrt(_chi2_quantile(self.inlier_probability, 4) / 2.0))


# For real-time use on two cores: matches from corner flow on the half-size frame (500 corners), SIFT there (500
# keypoints) when the flow fails. Accuracy against the exact settings: docs/benchmarks_motion.md.
FAST_CAMERA_MOTION = CameraMotionSettings(downscale=0.5, max_keypoints=500, points="flow")


@dataclass(frozen=True)
class CameraMotion:
    """Result of one estimate between the previous and the current thermal frame.

    Attributes
    ----------
    matrix : ndarray
        3x3 homogeneous transform from previous-frame to current-frame pixels (identity when not ``valid``).
    model : str
        The motion model that was fitted.
    n_matches, n_inliers : int
        Ratio-test matches and MSAC inliers among them.
    shift : ndarray
        ``T(c) - c`` for the reference point ``c`` (the previous box centre): how far the camera moved it.
    is_motion : bool
        ``valid`` and ``|shift| >= motion_threshold_px``: the position should be compensated.
    valid : bool
        Enough matches and inliers were found for a trustworthy transform.
    """

    matrix: np.ndarray
    model: str
    n_matches: int
    n_inliers: int
    shift: np.ndarray
    is_motion: bool
    valid: bool

    def at(self, centre: np.ndarray, threshold_px: float) -> "CameraMotion":
        """The same fit with ``shift`` and ``is_motion`` measured at ``centre`` (the fit itself does not depend on
        where the target is, which lets the fit run ahead of the tracker: :meth:`CameraMotionCompensation.measure`)."""
        if not self.valid:
            return self
        shift = apply_transform(self.matrix, np.asarray(centre, dtype=np.float64)) - centre
        return CameraMotion(self.matrix, self.model, self.n_matches, self.n_inliers, shift,
                            bool(np.hypot(*shift) >= threshold_px), True)


@dataclass(frozen=True)
class Keypoints:
    """SIFT keypoint positions (N, 2) as float64 ``x, y`` and their descriptors (N, 128) float32."""

    points: np.ndarray
    descriptors: np.ndarray


def apply_transform(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map points (N, 2) or one point (2,) through a 3x3 homogeneous transform."""
    mapped = project(matrix, points)
    return mapped[0] if np.ndim(points) == 1 else mapped


def box_centre(box: np.ndarray) -> np.ndarray:
    """Centre ``xy + (wh - 1) / 2`` of an ``[x, y, w, h]`` box covering pixels ``x .. x + w - 1``.

    OpenCV (SIFT keypoints, warps) puts pixel ``i``'s centre at coordinate ``i``; this is the same convention as ECO's
    and :func:`rgbt_toolkit.jmmac.pipeline.box_centre`.
    """
    box = np.asarray(box, dtype=np.float64)
    return box[:2] + (box[2:4] - 1.0) / 2.0


def compensate_position(matrix: np.ndarray, position: np.ndarray) -> np.ndarray:
    """Where a previous-frame point ``(x, y)`` lies in the current frame after the camera moved."""
    return apply_transform(matrix, np.asarray(position, dtype=np.float64))


def compensate_box(matrix: np.ndarray, box: np.ndarray, keep_size: bool = True) -> np.ndarray:
    """Move a previous-frame box into the current frame: its centre goes through the transform.

    With ``keep_size`` (the authors' behaviour: only the position is shifted) the width and height are unchanged;
    otherwise they are scaled by the transform's local area scale ``sqrt(|det J|)`` at the centre.
    """
    box = np.asarray(box, dtype=np.float64)
    centre = box_centre(box)
    new_centre = apply_transform(matrix, centre)
    size = box[2:4].copy()
    if not keep_size:
        eps = 0.5
        jac = np.stack(
            [
                (apply_transform(matrix, centre + [eps, 0]) - apply_transform(matrix, centre - [eps, 0])) / (2 * eps),
                (apply_transform(matrix, centre + [0, eps]) - apply_transform(matrix, centre - [0, eps])) / (2 * eps),
            ],
            axis=1,
        )
        size = size * np.sqrt(abs(np.linalg.det(jac)))
    return np.concatenate([new_centre - (size - 1.0) / 2.0, size])


@dataclass
class CameraShiftAccumulator:
    """Running sum of the camera's displacements, to move between image and camera-compensated coordinates.

    The authors' Kalman filter runs in coordinates where camera motion is removed: its measurement is the position
    plus ``d_total``, the sum of the per-event shifts ``T^-1(c) - c``, i.e. minus the camera's displacement. Here
    ``total`` is the sum of the displacements ``T(c) - c`` themselves, so ``stable = image - total`` and
    ``image = stable + total``.
    """

    total: np.ndarray = field(default_factory=lambda: np.zeros(2))

    def add(self, shift: np.ndarray) -> None:
        """Record one camera displacement ``T(c) - c`` (pixels)."""
        self.total = self.total + np.asarray(shift, dtype=np.float64)

    def to_stable(self, position: np.ndarray) -> np.ndarray:
        """Image position -> camera-compensated position (what the Kalman filter sees)."""
        return np.asarray(position, dtype=np.float64) - self.total

    def to_image(self, position: np.ndarray) -> np.ndarray:
        """Camera-compensated position -> current image position."""
        return np.asarray(position, dtype=np.float64) + self.total

    def reset(self) -> None:
        """Back to no accumulated motion."""
        self.total = np.zeros(2)


class CameraMotionEstimator:
    """SIFT + ratio test + MSAC between two thermal frames (no state besides the OpenCV objects)."""

    def __init__(self, settings: CameraMotionSettings = CameraMotionSettings()) -> None:
        self.settings = settings
        self._sift = cv2.SIFT_create(nfeatures=settings.max_keypoints)
        self._matcher = cv2.BFMatcher(cv2.NORM_L2)

    def small_grey(self, image: np.ndarray) -> np.ndarray:
        """The grey frame at ``downscale``: what both point sources look at."""
        grey = to_grey_uint8(image, "thermal frame")
        d = self.settings.downscale
        return cv2.resize(grey, None, fx=d, fy=d, interpolation=cv2.INTER_AREA) if d < 1.0 else grey

    def flow_matches(self, previous: np.ndarray, current: np.ndarray,
                     allowed: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Corners of ``previous`` and where Lucas-Kanade flow puts them in ``current`` (both grey at ``downscale``),
        in full-frame coordinates; only corners whose backward flow returns within ``flow_check_px``, and only where
        ``allowed`` (uint8, non-zero; at ``downscale``) lets corners be found."""
        s = self.settings
        corners = cv2.goodFeaturesToTrack(previous, maxCorners=s.flow_corners, qualityLevel=0.01,
                                          minDistance=7, blockSize=7, mask=allowed)
        if corners is None or len(corners) < _MINIMAL_SAMPLE[s.model] + 1:
            return np.zeros((0, 2)), np.zeros((0, 2))
        criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 20, 0.03)
        flow = dict(winSize=(15, 15), maxLevel=3, criteria=criteria)
        ahead, found, _ = cv2.calcOpticalFlowPyrLK(previous, current, corners, None, **flow)
        back, returned, _ = cv2.calcOpticalFlowPyrLK(current, previous, ahead, None, **flow)
        error = np.linalg.norm((back - corners).reshape(-1, 2), axis=1)
        keep = (found.ravel() == 1) & (returned.ravel() == 1) & (error < s.flow_check_px)
        src, dst = corners.reshape(-1, 2)[keep].astype(np.float64), ahead.reshape(-1, 2)[keep].astype(np.float64)
        if s.downscale < 1.0:  # pixel centres of the small frame back to full-frame coordinates
            src, dst = (src + 0.5) / s.downscale - 0.5, (dst + 0.5) / s.downscale - 0.5
        return src, dst

    def estimate_flow(self, previous: np.ndarray, current: np.ndarray, box: np.ndarray | None,
                      frame_shape: tuple[int, int], allowed: np.ndarray | None = None) -> CameraMotion | None:
        """The camera motion from corner flow between two grey frames at ``downscale``, or None when the flow cannot
        be trusted: fewer than ``min_inliers`` corners come back, or fewer than ``flow_min_fraction`` of those
        corners that did come back fit one transform. ``allowed``: see :meth:`flow_matches`."""
        src, dst = self.flow_matches(previous, current, allowed)
        motion = self._motion(src, dst, box, frame_shape)
        if not motion.valid or motion.n_inliers < self.settings.flow_min_fraction * len(src):
            return None
        return motion

    def keypoints(self, image: np.ndarray, allowed: np.ndarray | None = None) -> Keypoints:
        """SIFT keypoints of a frame (grey or colour uint8), in full-frame pixel coordinates; only where ``allowed``
        (uint8 at ``downscale``, non-zero) lets them be found."""
        d = self.settings.downscale
        kps, desc = self._sift.detectAndCompute(self.small_grey(image), allowed)
        if desc is None:
            desc = np.zeros((0, 128), np.float32)
        points = np.array([kp.pt for kp in kps], dtype=np.float64).reshape(-1, 2)
        if d < 1.0:
            points = (points + 0.5) / d - 0.5  # pixel centres of the small frame back to full-frame coordinates
        return Keypoints(points, desc)

    def match(self, previous: Keypoints, current: Keypoints) -> tuple[np.ndarray, np.ndarray]:
        """Ratio-test matches: previous-frame points and their current-frame partners, both (M, 2)."""
        if len(previous.points) == 0 or len(current.points) < 2:
            return np.zeros((0, 2)), np.zeros((0, 2))
        pairs = self._matcher.knnMatch(previous.descriptors, current.descriptors, k=2)
        ratio = self.settings.ratio
        keep = [
            (m[0].queryIdx, m[0].trainIdx)
            for m in pairs
            if len(m) == 2 and ratio * m[0].distance ** 2 < m[1].distance ** 2
        ]
        if not keep:
            return np.zeros((0, 2)), np.zeros((0, 2))
        idx = np.array(keep)
        return previous.points[idx[:, 0]], current.points[idx[:, 1]]

    def fit(self, src: np.ndarray, dst: np.ndarray) -> tuple[np.ndarray | None, np.ndarray]:
        """Robust fit of the configured model to matches; returns ``(matrix or None, inlier mask)``."""
        s = self.settings
        if len(src) < _MINIMAL_SAMPLE[s.model] + 1:
            return None, np.zeros(len(src), dtype=bool)
        rng = np.random.default_rng(s.seed)
        if s.model == "translation":
            return fit_translation(src, dst, s.threshold_px, s.iterations, rng)
        if s.model == "similarity":
            return fit_similarity(src, dst, s.threshold_px, s.iterations, rng)
        return fit_opencv(s.model, src, dst, s.threshold_px, s.iterations, s.confidence, s.seed)

    def estimate(self, previous: np.ndarray, current: np.ndarray, box: np.ndarray | None = None) -> CameraMotion:
        """Estimate the camera motion from ``previous`` to ``current`` (thermal frames, uint8).

        Parameters
        ----------
        previous, current : ndarray
            Consecutive thermal frames of the same size.
        box : ndarray, optional
            The previous frame's target box ``[x, y, w, h]``; its centre measures the motion. Default: image centre.

        Returns
        -------
        CameraMotion
            ``valid`` is False (identity matrix, no motion) when too few matches or inliers were found.
        """
        previous, current = np.asarray(previous), np.asarray(current)
        if previous.shape[:2] != current.shape[:2]:
            raise InputError(f"thermal frames differ in size: {previous.shape[:2]} vs {current.shape[:2]}")
        if self.settings.points == "flow":
            motion = self.estimate_flow(self.small_grey(previous), self.small_grey(current), box, previous.shape[:2])
            if motion is not None:
                return motion
        return self.estimate_keypoints(self.keypoints(previous), self.keypoints(current), box, previous.shape[:2])

    def estimate_keypoints(
        self, previous: Keypoints, current: Keypoints, box: np.ndarray | None, frame_shape: tuple[int, int]
    ) -> CameraMotion:
        """:meth:`estimate` from already computed keypoints (reuse the previous frame's on consecutive frames)."""
        src, dst = self.match(previous, current)
        return self._motion(src, dst, box, frame_shape)

    def _motion(self, src: np.ndarray, dst: np.ndarray, box: np.ndarray | None,
                frame_shape: tuple[int, int]) -> CameraMotion:
        """The robust fit to matches ``src -> dst`` and the shift it gives the box centre."""
        matrix, inliers = self.fit(src, dst)
        n_inliers = int(inliers.sum())
        centre = box_centre(box) if box is not None else np.array([frame_shape[1], frame_shape[0]]) / 2.0
        if matrix is None or n_inliers < max(self.settings.min_inliers, _MINIMAL_SAMPLE[self.settings.model] + 1):
            return CameraMotion(np.eye(3), self.settings.model, len(src), n_inliers, np.zeros(2), False, False)
        return CameraMotion(matrix, self.settings.model, len(src), n_inliers, np.zeros(2), False, True).at(
            centre, self.settings.motion_threshold_px)


@dataclass(frozen=True)
class CameraMotionMeasurement:
    """What :meth:`CameraMotionCompensation.measure` found for one frame pair, before any target box is known: the
    trigger's figures and, when it fired, the fitted motion (its shift measured at the frame centre)."""

    trigger: TriggerResult
    motion: CameraMotion | None
    first: bool = False  # the sequence's first frame pair: nothing to compare with yet


@dataclass(frozen=True)
class CameraMotionStep:
    """What :meth:`CameraMotionCompensation.step` found for one frame."""

    trigger: TriggerResult
    motion: CameraMotion | None  # None when the trigger did not fire (no estimate was run)
    box: np.ndarray  # the previous box moved into the current frame (unchanged without camera motion)
    total_shift: np.ndarray  # accumulated camera displacement so far

    @property
    def camera_motion(self) -> bool:
        """True when the trigger fired and the estimate shows a compensable motion (the paper's CM flag)."""
        return self.motion is not None and self.motion.is_motion


class CameraMotionCompensation:
    """Per-frame CME as the authors run it: trigger, then (only when triggered) estimate, compensate, accumulate.

    Call :meth:`initialize` with the first frame pair, then :meth:`step` for every following pair with the previous
    frame's final box. A copy of the previous thermal frame is kept here (callers may reuse their frame buffer), and
    its SIFT keypoints when they were computed, so consecutive motion frames run SIFT once per frame.
    """

    def __init__(
        self,
        settings: CameraMotionSettings = CameraMotionSettings(),
        trigger_settings: TriggerSettings = TriggerSettings(),
    ) -> None:
        self.trigger = CameraMotionTrigger(trigger_settings)
        self.estimator = CameraMotionEstimator(settings)
        self.accumulator = CameraShiftAccumulator()
        self._previous_t: np.ndarray | None = None
        self._previous_kps: Keypoints | None = None
        self._previous_small: np.ndarray | None = None  # the previous frame as the flow sees it (flow only)
        self.sift_frames = 0  # frames whose estimate needed SIFT (with points="flow": the flow's failures)
        self._overlays: OverlayMask | None = None  # burned-in overlays of the thermal stream, looked for now and then
        self._allowed: np.ndarray | None = None  # where points may be found (at ``downscale``; None: anywhere)
        self._frames_seen = 0

    def initialize(self, rgb: np.ndarray, thermal: np.ndarray) -> None:
        """Start a sequence with its first frame pair."""
        self.accumulator.reset()
        self._start(rgb, thermal)

    def _start(self, rgb: np.ndarray, thermal: np.ndarray) -> None:
        """Forget the last sequence's frames and take this pair as the first of a new one."""
        self.trigger.reset()
        self.trigger.update(rgb, thermal)
        self._previous_t = np.array(thermal, copy=True)
        self._previous_kps = None
        self._previous_small = None
        self.sift_frames = 0
        self._overlays, self._allowed, self._frames_seen = None, None, 0
        self._look_for_overlays(self._previous_t)

    def _look_for_overlays(self, thermal: np.ndarray) -> None:
        """Every ``overlay_refresh`` frames: feed the overlay finder and renew the mask of where points may lie.

        An on-screen display stays put while the camera moves, so corners on it say "no motion"; over a
        featureless sky they are most of the corners there are. Looking every few frames is enough (an overlay
        does not move) and keeps the cost (about 1 ms at 640x512) off most frames."""
        refresh = self.estimator.settings.overlay_refresh
        if not refresh or self._frames_seen % refresh:
            self._frames_seen += 1
            return
        self._frames_seen += 1
        if self._overlays is None:
            self._overlays = OverlayMask()
        self._overlays.update(thermal)
        d = self.estimator.settings.downscale
        h, w = thermal.shape[:2]
        small = (max(1, int(round(h * d))), max(1, int(round(w * d)))) if d < 1.0 else (h, w)
        mask = self._overlays.mask(small)
        self._allowed = feature_mask(mask, small) if mask is not None and mask.any() else None

    def step(self, rgb: np.ndarray, thermal: np.ndarray, previous_box: np.ndarray) -> CameraMotionStep:
        """Process one new frame pair; ``previous_box`` is the previous frame's result ``[x, y, w, h]``."""
        if self._previous_t is None:
            raise InputError("CameraMotionCompensation.step called before initialize(first frame pair)")
        return self.apply(self.measure(rgb, thermal), previous_box)

    def measure(self, rgb: np.ndarray, thermal: np.ndarray, *, restart: bool = False) -> CameraMotionMeasurement:
        """The part of :meth:`step` that needs no target box: the trigger, and when it fires the motion fit. With
        ``restart`` (or on the very first call) the pair starts a new sequence instead, as :meth:`initialize` does.

        Why apart: this is nearly all of the module's cost (about 7 ms a frame on a 1080p pair at the working
        scale), and as it does not depend on the tracker's result it can run on the thread that reads the frames,
        ahead of the tracker (``rgbt track``'s reader thread), instead of on the tracker's critical path. Calls
        must come in frame order; :meth:`apply` then uses each measurement in the same order."""
        if restart or self._previous_t is None:
            self._start(rgb, thermal)
            return CameraMotionMeasurement(TriggerResult(0.0, 0.0, 0.0, False), None, first=True)
        thermal = np.asarray(thermal)
        if thermal.shape[:2] != self._previous_t.shape[:2]:
            raise InputError(f"thermal frame size changed from {self._previous_t.shape[:2]} to {thermal.shape[:2]}")
        trig = self.trigger.update(rgb, thermal)
        self._look_for_overlays(thermal)
        motion, current_kps, current_small = None, None, None
        if trig.triggered:
            estimator, allowed = self.estimator, self._allowed
            if estimator.settings.points == "flow":
                previous_small = self._previous_small
                if previous_small is None:
                    previous_small = estimator.small_grey(self._previous_t)
                current_small = estimator.small_grey(thermal)
                motion = estimator.estimate_flow(previous_small, current_small, None, thermal.shape[:2], allowed)
            if motion is None:  # SIFT: the paper's way, and the fallback of the flow
                previous_kps = self._previous_kps
                if previous_kps is None:
                    previous_kps = estimator.keypoints(self._previous_t, allowed)
                current_kps = estimator.keypoints(thermal, allowed)
                motion = estimator.estimate_keypoints(previous_kps, current_kps, None, thermal.shape[:2])
                self.sift_frames += 1
        self._previous_t = np.array(thermal, copy=True)
        self._previous_kps = current_kps
        self._previous_small = current_small
        return CameraMotionMeasurement(trig, motion)

    def apply(self, measured: CameraMotionMeasurement, previous_box: np.ndarray) -> CameraMotionStep:
        """The part of :meth:`step` that needs the previous frame's box: the motion's shift at its centre, the
        accumulated shift, and the box moved with the camera. A first-frame measurement starts the accumulation."""
        box = np.asarray(previous_box, dtype=np.float64)
        if measured.first:
            self.accumulator.reset()
            return CameraMotionStep(measured.trigger, None, box, self.accumulator.total.copy())
        motion = measured.motion
        if motion is not None:
            motion = motion.at(box_centre(box), self.estimator.settings.motion_threshold_px)
            if motion.is_motion:
                self.accumulator.add(motion.shift)
                box = compensate_box(motion.matrix, box, keep_size=True)
        return CameraMotionStep(measured.trigger, motion, box, self.accumulator.total.copy())


__all__ = [
    "FAST_CAMERA_MOTION",
    "MOTION_MODELS",
    "POINT_SOURCES",
    "CameraMotion",
    "CameraMotionCompensation",
    "CameraMotionEstimator",
    "CameraMotionMeasurement",
    "CameraMotionSettings",
    "CameraMotionStep",
    "CameraMotionTrigger",
    "CameraShiftAccumulator",
    "Keypoints",
    "TriggerResult",
    "TriggerSettings",
    "apply_transform",
    "box_centre",
    "compensate_box",
    "compensate_position",
]
