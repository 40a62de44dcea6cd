"""JMMAC's per-frame step, in the paper's order (Sec. III and the authors' code):

camera-motion test and compensation -> RGB and T appearance trackers -> MFNet fusion of their responses ->
Kalman motion tracker and the Algorithm-1 switcher -> box refinement -> model updates (skipped in motion mode).

Everything runs in one geometry (the RGB camera's, with the thermal frame registered onto it by the caller); the
harness maps boxes to the thermal camera. The algorithm never draws or writes files.
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from rgbt_toolkit.eco.tracker import check_box
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.jmmac.config import JmmacConfig
from rgbt_toolkit.jmmac.parts import AppearanceTracker, BoxRefiner, FusionWeighting, TemplateScorer
from rgbt_toolkit.motion.switcher import candidate_offset
from rgbt_toolkit.motion.template import patch_mean


@dataclass
class FrameResult:
    """What happened in one frame; the harness turns these into box files, ``track.json`` and the video."""

    index: int
    box: np.ndarray
    mode: str  # "init", "appearance" or "motion"
    q: float = float("nan")  # MAX-PSR of the fused response, on the paper's scale
    s_a: float = float("nan")  # template similarity of the appearance result (NaN when matching was skipped)
    s_m: float = float("nan")  # ... of the motion result
    camera_motion: bool = False  # the trigger fired and CME compensated the search region
    w_g: float = float("nan")  # MFNet's global weight of the RGB modality
    refined: bool = False
    w_f: np.ndarray | None = None  # the fusion weight map on the response grid (for overlays)
    present: bool = True  # False while the target counts as lost (re-acquisition on): the box is not a measurement
    reacquired: bool = False  # the box comes from the whole-frame search (the target was found again)
    confidence: float = float("nan")  # fused peak / its usual value on confident frames (re-acquisition on)
    timings: dict[str, float] = field(default_factory=dict)  # seconds per module


def box_centre(box: np.ndarray) -> np.ndarray:
    """Centre of an ``[x, y, w, h]`` box in the benchmark first-pixel convention (as ECO: xy + (wh - 1) / 2)."""
    return box[:2] + (box[2:] - 1) / 2


def box_at(centre: np.ndarray, size: np.ndarray) -> np.ndarray:
    return np.concatenate([centre - (size - 1) / 2, size])


class _Clock:
    """Accumulates wall time per module for one frame."""

    def __init__(self) -> None:
        self.timings: dict[str, float] = {}
        self._start = time.perf_counter()

    def lap(self, name: str) -> None:
        now = time.perf_counter()
        self.timings[name] = self.timings.get(name, 0.0) + now - self._start
        self._start = now


class JmmacTracker:
    """The full tracker, assembled from parts (``None`` for a part whose module is switched off).

    Parameters
    ----------
    config : JmmacConfig
    rgb_tracker, t_tracker : AppearanceTracker
        ECO on each modality, configured with the same search grid.
    fusion : FusionWeighting, optional
        MFNet's ``(w_G, W_L)``; required for the ``global``, ``local`` and ``mfnet`` fusion modes.
    camera_motion : object with ``initialize(rgb, t)`` and ``step(rgb, t, box)``, optional
        :class:`rgbt_toolkit.motion.camera_motion.CameraMotionCompensation`.
    kalman : object with ``initialize(pos)``, ``predict()``, ``correct(pos)``, optional
        The constant-velocity motion tracker, run in camera-compensated coordinates.
    quality : callable ``response -> q``, optional
        MAX-PSR on the paper's scale.
    template : TemplateScorer, optional
        DDIS similarities ``(s_A, s_M)`` on the paper's scale.
    switch : callable ``(q, s_A, s_M, offset, spread_offset) -> bool``, optional
        Algorithm 1: True keeps the appearance result (``offset``: the two candidates' centre distance in target
        sizes, :func:`~rgbt_toolkit.motion.switcher.candidate_offset`; ``spread_offset``: the same distance over the
        Kalman prediction's spread, ``kalman.spread()``, or None when the filter has no such method).
    refiner : BoxRefiner, optional
    """

    def __init__(self, config: JmmacConfig, rgb_tracker: AppearanceTracker | None,
                 t_tracker: AppearanceTracker | None, fusion: FusionWeighting | None = None,
                 camera_motion=None, kalman=None, quality: Callable[[np.ndarray], float] | None = None,
                 template: TemplateScorer | None = None,
                 switch: Callable[[float, float, float, float, float | None], bool] | None = None,
                 refiner: BoxRefiner | None = None):
        if config.uses_rgb and rgb_tracker is None or config.uses_t and t_tracker is None:
            raise InputError(f"fusion mode {config.fusion!r} needs the RGB and/or T tracker it fuses")
        if config.fusion in ("global", "local", "mfnet") and fusion is None:
            raise InputError(f"fusion mode {config.fusion!r} needs an MFNet")
        if config.target_motion and not (kalman and quality and template and switch):
            raise InputError("target motion prediction needs a Kalman filter, a quality measure, a template scorer "
                             "and a switcher")
        self.config = config
        self.rgb_tracker, self.t_tracker = rgb_tracker, t_tracker
        self.fusion, self.camera_motion, self.kalman = fusion, camera_motion, kalman
        self.quality, self.template, self.switch, self.refiner = quality, template, switch, refiner
        self.box: np.ndarray | None = None
        self.index = -1
        self._pool = ThreadPoolExecutor(max_workers=2) if config.parallel_trackers and config.fusion not in (
            "rgb", "t") else None
        self._pending: list = []  # the model updates of the last frame, running on the pool
        self._last_wg = 0.5  # the last frame's global RGB weight: picks the tracker that searches scales
        self._shift = np.zeros(2)  # accumulated camera displacement: stable = image + shift
        self._trusted = True  # the current box may be carried by the camera motion (see track)
        self.watchdog = None
        if config.reacquire:
            from rgbt_toolkit.eco.reacquire import Reacquirer, ReacquireParams

            self.watchdog = Reacquirer(ReacquireParams(verify_budget=config.reacquire_budget,
                                                       first_budget=config.reacquire_first_budget,
                                                       match_side=config.reacquire_match_side))

    # ------------------------------------------------------------------------------------------------------------
    def measure_camera_motion(self, rgb: np.ndarray, thermal: np.ndarray, *, first: bool = False):
        """The camera-motion work on a frame pair that needs no target box (the trigger, the motion fit), or None
        without camera motion. Hand the result to :meth:`initialize` (``first``) or :meth:`track` of the same pair as
        ``camera=``; calls must come in frame order. Why: the caller may run this ahead, on another thread (``rgbt
        track``'s reader), which takes it off the tracker's critical path (docs/decisions.md, D44)."""
        if not (self.config.camera_motion and self.camera_motion is not None):
            return None
        return self.camera_motion.measure(rgb, thermal, restart=first)

    def initialize(self, rgb: np.ndarray, thermal: np.ndarray, box: np.ndarray, *, camera=None) -> FrameResult:
        """Start on the first frame pair with the target's box (RGB geometry); ``camera``: this pair's
        :meth:`measure_camera_motion` (``first=True``), when the caller measured it."""
        box = check_box(box, "initial box", rgb.shape)
        self._finish_updates()  # a tracker reused for the next sequence: no update of the last one still running
        clock = _Clock()
        # the two first-frame trainings (about 1 s each) are independent: side by side, as the per-frame searches
        self._both(lambda tracker, frame: tracker.initialize(frame, box), rgb, thermal)
        clock.lap("appearance")
        if self.config.camera_motion and self.camera_motion is not None:
            if camera is None:
                self.camera_motion.initialize(rgb, thermal)
            else:
                self.camera_motion.apply(camera, box)  # the measurement started the sequence already
        if self.config.target_motion:
            if hasattr(self.kalman, "reset"):  # a tracker may be reused for the next sequence
                self.kalman.reset()
            self.template.initialize(rgb, thermal, box)
        if self.config.refine and self.refiner is not None:
            self.refiner.initialize(rgb, box)
        if self.watchdog is not None:
            self.watchdog.start(rgb if self.config.uses_rgb else thermal, box)
        clock.lap("setup")
        self.box, self.index, self._shift, self._trusted = box, 0, np.zeros(2), True
        self._last_wg = 0.5
        return FrameResult(0, box.copy(), "init", timings=clock.timings)

    def track(self, rgb: np.ndarray, thermal: np.ndarray, *, camera=None) -> FrameResult:
        """Process the next frame pair (thermal already in RGB geometry) and return the frame's result; ``camera``:
        this pair's :meth:`measure_camera_motion`, when the caller measured it (else it is measured here)."""
        if self.box is None:
            raise InputError("JmmacTracker.track called before initialize")
        cfg, clock = self.config, _Clock()
        self.index += 1
        scaler = self._scale_searcher()  # the tracker that estimates the size this frame (None: both)
        previous = self.box

        # 1. camera motion: test, estimate on T, move the search centre with the camera
        drastic = False
        centre = box_centre(previous)
        carried = None  # the previous box moved by the camera motion (drastic frames only)
        if cfg.camera_motion and self.camera_motion is not None:
            step = self.camera_motion.step(rgb, thermal, previous) if camera is None else \
                self.camera_motion.apply(camera, previous)
            drastic = bool(step.camera_motion)
            if drastic:
                carried = np.asarray(step.box, dtype=float)
                centre = box_centre(carried)
            self._shift = -np.asarray(step.total_shift, dtype=float)
        clock.lap("camera_motion")
        self._finish_updates()  # the last frame's model updates ran in the background meanwhile
        clock.lap("update")

        # 2. appearance trackers on the shared grid, and 3. fusion (suspended under drastic camera motion: then the
        # plain average). MFNet looks only at the search region, which an ECO tracker knows before it searches, so
        # with two tracker threads the weights are computed on this thread while the two searches run.
        lost = self.watchdog is not None and self.watchdog.lost
        # while the target is lost the responses at the old place only give the frame's fallback box, and every
        # candidate of the whole-frame search is weighed by the plain average: so is this frame (no MFNet; D51)
        plain = drastic or lost
        known = self._known_search(centre) if self._pool is not None and not plain else None
        search = lambda tr, frame: self._search(tr, frame, centre, scaler, lost)  # noqa: E731
        if known is not None:
            weigh = lambda: self._fusion_weight(rgb, thermal, known[0], known[1], drastic)  # noqa: E731
            # the tracker that does not search scales is light: it runs here, before MFNet, and the scale search
            # has a core to itself instead of sharing two with three threads
            light = None if scaler is None or lost else (self.t_tracker if scaler is self.rgb_tracker
                                                           else self.rgb_tracker)
            (est_rgb, est_t), (w_g, w_f) = self._both(search, rgb, thermal, beside=weigh, here=light)
            clock.lap("appearance")  # the fusion's own time is inside, overlapped
        else:
            est_rgb, est_t = self._both(search, rgb, thermal)
            clock.lap("appearance")
            estimate = est_rgb or est_t
            region = estimate.region if estimate.region is not None else self._search_region(centre, previous)
            w_g, w_f = self._fusion_weight(rgb, thermal, region, estimate.response.shape, plain)
        clock.lap("fusion")
        fused, scale, lead = self._fuse(est_rgb, est_t, w_f, w_g, scaler)
        box_appearance = lead_tracker = None
        lead_tracker = self.rgb_tracker if lead is est_rgb else self.t_tracker
        box_appearance = lead_tracker.locate(lead, fused, scale)
        clock.lap("localisation")

        # 4. target motion prediction (Kalman + Algorithm 1), suspended under drastic camera motion
        self._last_wg = w_g
        result = FrameResult(self.index, box_appearance, "appearance", camera_motion=drastic, w_g=w_g, w_f=w_f)
        use_appearance = True
        if cfg.target_motion:
            result.q = float(self.quality(fused))
            holding = carried is not None and self._trusted and result.q < cfg.q_hold_under_camera_motion
            if holding:  # hidden while the camera moves: see JmmacConfig
                result.box, result.mode = carried, "motion"
                use_appearance = False
            box_motion = self._motion_candidate(previous)
            if box_motion is not None and not drastic and result.q <= cfg.q_skip_matching:
                result.s_a, result.s_m = self.template(rgb, thermal, box_appearance, box_motion)
                offset = candidate_offset(box_appearance, box_motion)
                use_appearance = bool(self.switch(result.q, result.s_a, result.s_m, offset,
                                                  self._spread_offset(offset, box_appearance)))
                if not use_appearance:
                    result.box, result.mode = box_motion, "motion"
            # a carried box is only as good as the box it carries: an appearance result, or one carried from it
            self._trusted = use_appearance or holding
        clock.lap("target_motion")

        # 4b. re-acquisition: a fused peak far below its usual value for a few frames means the target is lost
        if self.watchdog is not None and not drastic:
            use_appearance = self._watch(rgb, thermal, fused, result, previous, use_appearance)
        clock.lap("reacquire")

        # 5. box refinement on the visible frame (not under camera motion, in motion mode or in the dark)
        if cfg.refine and self.refiner is not None and use_appearance and not drastic and self._lit(rgb, result.box):
            refined = self.refiner.refine(rgb, result.box)
            if refined is not None:
                result.box, result.refined = np.asarray(refined, dtype=float), True
        clock.lap("refinement")

        # 6. model updates with the final box, as the authors' code (refinement -> size update -> ECO update);
        # appearance trackers and Kalman learn only from appearance results (Sec. III-C)
        if use_appearance:
            if cfg.target_motion:
                self._kalman_measure(box_centre(result.box))
            self._update_trackers(rgb, thermal, result.box)
        clock.lap("update")

        self.box = result.box.copy()
        result.timings = clock.timings
        return result

    @property
    def camera_shift(self) -> np.ndarray:
        """Accumulated camera displacement in RGB pixels (stable = image + shift), for drawing past positions."""
        return self._shift.copy()

    # ------------------------------------------------------------------------------------------------------------
    def _watch(self, rgb, thermal, fused, result: FrameResult, previous, use_appearance: bool) -> bool:
        """Feed the watchdog; while lost, search the whole frame. Returns whether the models learn from the frame.

        Found: the frame's box is the verified candidate and the Kalman filter restarts there. Not found: the box
        Algorithm 1 chose stays (the motion prediction bridges short gaps), flagged not present, and nothing learns.
        """
        watchdog = self.watchdog
        peak, usual = float(np.max(fused)), watchdog.usual_peak
        result.confidence = peak / usual if np.isfinite(usual) and usual > 0 else 1.0
        if not watchdog.lost and not watchdog.observe(peak):
            return use_appearance
        size = float(np.sqrt(previous[2] * previous[3]))
        frame = rgb if self.config.uses_rgb else thermal
        # the pool's workers are idle between the searches: one finds the warm blobs while this thread matches
        candidates = watchdog.candidates(frame, thermal if self.config.uses_t else None, executor=self._pool)
        found = watchdog.search(candidates, lambda c: self._verify(rgb, thermal, c, previous), size)
        if found is None:
            result.present = False
            return False
        result.box, result.mode, result.reacquired = found, "appearance", True
        if self.config.target_motion and hasattr(self.kalman, "reset"):
            self.kalman.reset()  # a jump: the old velocity means nothing here
        self._trusted = True
        return True

    def _verify(self, rgb, thermal, centre: np.ndarray, previous: np.ndarray):
        """``(peak, centre, box)`` of both appearance trackers looking at ``centre`` (plain average, no model change)."""
        all_scales = self.config.verify_all_scales
        est_rgb, est_t = self._both(lambda tr, frame: tr.predict(frame, centre, all_scales), rgb, thermal)
        fused, _, lead = self._fuse(est_rgb, est_t, 0.5, 0.5)
        tracker = self.rgb_tracker if lead is est_rgb else self.t_tracker
        box = tracker.locate(lead, fused, 1.0)
        return float(np.max(fused)), box_centre(box), box

    def _both(self, work, rgb, thermal, beside: Callable | None = None, here=None):
        """``work(tracker, frame)`` for the RGB and the T tracker (each only if used), on two threads when asked.

        The two ECO trackers are independent until fusion and spend their time in numpy, OpenCV and FFT calls that
        release the GIL, so with ``config.parallel_trackers`` they share two cores without extra processes.
        ``beside()``, if given, runs on this thread meanwhile; then ``(results, beside())`` is returned. ``here``:
        a tracker whose work also runs on this thread (before ``beside``) rather than on the pool.
        """
        jobs = []
        if self.config.uses_rgb:
            jobs.append((self.rgb_tracker, rgb))
        if self.config.uses_t:
            jobs.append((self.t_tracker, thermal))
        extra = None
        if self._pool is not None and len(jobs) == 2:
            futures = [None if tracker is here else self._pool.submit(work, tracker, frame)
                       for tracker, frame in jobs]
            out = [None, None]
            try:
                for k, (tracker, frame) in enumerate(jobs):
                    if tracker is here:
                        out[k] = work(tracker, frame)
                extra = beside() if beside is not None else None
            finally:  # never leave a search running on the pool (an error or Ctrl-C here)
                out = [out[k] if f is None else f.result() for k, f in enumerate(futures)]
        else:
            out = [work(tracker, frame) for tracker, frame in jobs]
            extra = beside() if beside is not None else None
        if len(jobs) == 2:
            pair = out[0], out[1]
        else:
            pair = (out[0], None) if self.config.uses_rgb else (None, out[0])
        return pair if beside is None else (pair, extra)

    def _update_trackers(self, rgb, thermal, box: np.ndarray) -> None:
        """Both trackers learn from ``box``. With two tracker threads, and when neither update reads the frames'
        pixels (ECO reuses its search's sample: the usual case), the updates run on the pool while this frame is
        handed back and the next frame's camera motion is estimated; :meth:`_finish_updates` waits for them before
        the next search. The result is the same: nothing the updates touch is read before then, and the frames'
        buffers may be refilled by the caller meanwhile because the updates do not read them."""
        background = self._pool is not None and self.config.uses_rgb and self.config.uses_t and not any(
            getattr(tracker, "update_reads_frame", lambda *_: True)(frame, box)
            for tracker, frame in ((self.rgb_tracker, rgb), (self.t_tracker, thermal)))
        if background:
            self._pending = [self._pool.submit(tracker.update, frame, box)
                             for tracker, frame in ((self.rgb_tracker, rgb), (self.t_tracker, thermal))]
        else:
            self._both(lambda tr, frame: tr.update(frame, box), rgb, thermal)

    def _finish_updates(self) -> None:
        """Wait for the background model updates (an error in one is raised here)."""
        pending, self._pending = self._pending, []
        for future in pending:
            future.result()

    def _known_search(self, centre: np.ndarray) -> tuple[np.ndarray, tuple[int, int]] | None:
        """``(region, grid_shape)`` the trackers will search around ``centre``, when MFNet is needed and the
        trackers can say so before searching (``search_grid``); else None."""
        if self.config.fusion not in ("global", "local", "mfnet"):
            return None
        tracker = self.rgb_tracker if self.config.uses_rgb else self.t_tracker
        if not hasattr(tracker, "search_grid"):
            return None
        return tracker.search_grid(centre)

    def _fusion_weight(self, rgb, thermal, region: np.ndarray, grid: tuple[int, int],
                       drastic: bool) -> tuple[float, np.ndarray | None]:
        """``(w_G, W_F)`` for the responses on ``grid`` covering the image square ``region``."""
        mode = self.config.fusion
        if mode in ("rgb", "t"):
            return (1.0 if mode == "rgb" else 0.0), None
        if mode == "average" or drastic:
            return 0.5, np.full(grid, 0.5)
        w_g, w_l = self.fusion(rgb, thermal, region, grid)
        if mode == "global":
            w_l = np.ones(grid)
        elif mode == "local":
            w_g = 1.0
        return float(w_g), w_g * np.asarray(w_l, dtype=float)

    @staticmethod
    def _search_region(centre: np.ndarray, previous: np.ndarray) -> np.ndarray:
        """The square search area around the target, for trackers that do not report the region their response
        covers (ECO: search_area_shape 'square', search_area_scale 4: side 4 sqrt(w h))."""
        side = 4.0 * np.sqrt(previous[2] * previous[3])
        return np.array([centre[0] - side / 2, centre[1] - side / 2, side, side])

    def _fuse(self, est_rgb, est_t, w_f, w_g, scaler=None):
        """Fused response, size change and the estimate to localise on. ``scaler``: the tracker that alone searched
        scales this frame (its size change is the box's), or None (both did: blended by ``w_G``)."""
        if est_t is None:
            return est_rgb.response, est_rgb.scale_factor, est_rgb
        if est_rgb is None:
            return est_t.response, est_t.scale_factor, est_t
        fused = w_f * est_rgb.response + (1 - w_f) * est_t.response
        if scaler is not None:
            scale = float((est_rgb if scaler is self.rgb_tracker else est_t).scale_factor)
        else:  # geometric mean
            scale = float(est_rgb.scale_factor ** w_g * est_t.scale_factor ** (1 - w_g))
        return fused, scale, est_rgb

    def _scale_searcher(self):
        """With ``scale_search="lead"`` the tracker of the modality MFNet trusted more on the last frame; None (both
        trackers search scales) with ``"both"``, with one tracker, and when neither modality was preferred (``w_G``
        exactly 0.5: the fixed average, fusion suspended under camera motion, the first frame)."""
        w_g = self._last_wg
        if self.config.scale_search != "lead" or not (self.config.uses_rgb and self.config.uses_t) or not (
                np.isfinite(w_g) and w_g != 0.5):
            return None
        return self.rgb_tracker if w_g > 0.5 else self.t_tracker

    def _search(self, tracker, frame, centre, scaler, lost: bool = False):
        """One tracker's appearance search: all scales when it estimates the size this frame, else the current one.

        While the target counts as lost no model learns, and a size estimated on whatever lies at the search centre
        means nothing: the current scale only (a fifth of the feature cost; the same boxes on the generated scenes).
        """
        if not lost and (scaler is None or tracker is scaler):
            return tracker.predict(frame, centre)
        return tracker.predict(frame, centre, False)

    def _motion_candidate(self, previous: np.ndarray) -> np.ndarray | None:
        """The Kalman prediction as a box of the previous size, in image coordinates; None before it has started."""
        if not getattr(self.kalman, "initialized", False):
            return None
        stable = np.asarray(self.kalman.predict(), dtype=float)
        return box_at(stable - self._shift, previous[2:])

    def _spread_offset(self, offset: float, box_appearance: np.ndarray) -> float | None:
        """``offset`` (the candidates' centre distance in target sizes) in units of the Kalman prediction's spread
        instead; None when the motion tracker has no ``spread``."""
        spread = getattr(self.kalman, "spread", None)
        if spread is None:
            return None
        return offset * float(np.sqrt(box_appearance[2] * box_appearance[3])) / max(float(spread()), 1e-9)

    def _kalman_measure(self, centre_image: np.ndarray) -> None:
        stable = centre_image + self._shift
        if getattr(self.kalman, "initialized", False):
            self.kalman.correct(stable)
        else:  # the authors start the filter at frame 2
            self.kalman.initialize(stable)

    def _lit(self, rgb: np.ndarray, box: np.ndarray) -> bool:
        return patch_mean(rgb, box) >= self.config.dark_level
