"""The per-frame steps of ``rgbt track``'s loop (:func:`~rgbt_toolkit.jmmac.run.run_tracking`): prepare a frame pair,
track it, draw its panel, write it; and what the run counts on the way (tallies, wall time per stage).

Why apart from the loop: one method per step, so the loop reads on one screen, and a step can be changed (made
faster, moved to another thread) without touching the others or the loop's clean-up.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.images import shrink_to
from rgbt_toolkit.jmmac.annotate import Annotator
from rgbt_toolkit.jmmac.outputs import TrackOutputs
from rgbt_toolkit.jmmac.pipeline import FrameResult, JmmacTracker, box_centre
from rgbt_toolkit.jmmac.track_inputs import Paired, TrackInputs
from rgbt_toolkit.jmmac.working_scale import scale_box, shrink, working_size
from rgbt_toolkit.registration.transforms import project



class Prepared(NamedTuple):
    """One frame pair made ready for the tracker and the video (on the reader thread with ``io_threads``); None
    frames: the pair was unreadable."""

    rgb_work: np.ndarray | None  # RGB at the working scale
    thermal_aligned: np.ndarray | None  # thermal warped into it
    rgb_video: np.ndarray | None  # RGB for the video
    thermal: np.ndarray | None  # thermal as read
    stamp: float  # time (s)
    camera: object | None = None  # the tracker's camera-motion measurement of the pair (None: measured when tracked)


class StageClock:
    """The loop's wall time per stage (read, prepare, track, annotate, write), charged lap by lap."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._mark = time.perf_counter()

    def lap(self, stage: str) -> None:
        """Charge the time since the last lap (or restart) to ``stage``."""
        now = time.perf_counter()
        self.seconds[stage] = self.seconds.get(stage, 0.0) + now - self._mark
        self._mark = now

    def restart(self) -> None:
        """Start the next lap now: the time since the last one counts in no stage."""
        self._mark = time.perf_counter()


@dataclass
class RunTally:
    """What the run summary counts over the written frames."""

    frames: int = 0
    absent: int = 0  # frames with present: false (the re-acquisition module judged the target lost)
    modes: dict[str, int] = field(default_factory=dict)
    tracker_seconds: dict[str, float] = field(default_factory=dict)  # the tracker's own timings, per module

    def count(self, result: FrameResult) -> None:
        for name, seconds in result.timings.items():
            self.tracker_seconds[name] = self.tracker_seconds.get(name, 0.0) + seconds
        self.modes[result.mode] = self.modes.get(result.mode, 0) + 1
        self.absent += not result.present
        self.frames += 1


class FrameSteps:
    """One frame's work, a method per step, for a run writing to ``outputs``; the counts go to :attr:`tally`.

    ``tracker`` is the tracker as the loop calls it (wrapped in a ``ScaledTracker`` below full resolution),
    ``scale`` its working scale and ``video_scale`` the annotated video's further shrink. ``progress`` and
    ``on_result`` are :func:`~rgbt_toolkit.jmmac.run.run_tracking`'s callbacks.
    """

    def __init__(self, inputs: TrackInputs, tracker: JmmacTracker, outputs: TrackOutputs, annotator: Annotator, *,
                 scale: float, video_scale: float, video: bool, plot: bool,
                 progress: Callable[[int], None] | None = None,
                 on_result: Callable[[FrameResult, np.ndarray, float], None] | None = None):
        self.inputs, self.tracker, self.outputs, self.annotator = inputs, tracker, outputs, annotator
        self.scale, self.video_scale = scale, video_scale
        self.draw_scale = scale * video_scale  # full-resolution RGB pixels -> annotated-video pixels
        self.work_size = working_size(inputs.rgb_size, scale)  # (w, h) of the frames the tracker sees
        self.video, self.plot = video, plot
        self.progress, self.on_result = progress, on_result
        self.tally = RunTally()
        self.first_rgb: np.ndarray | None = None  # the faint background of track.png
        self.last_panel: LazyPanel | None = None  # shown again for an unreadable frame
        self._prepared = 0  # readable pairs prepared so far (the first starts the camera-motion measurements)

    def prepare(self, pair: Paired) -> Prepared:
        """The frames the tracker and the video need; runs on the reader thread with ``io_threads``."""
        rgb, thermal, stamp = pair
        if rgb is None or thermal is None:
            return Prepared(None, None, None, thermal, stamp)
        rgb_work = shrink_to(rgb, self.work_size)  # the frame the tracker sees (rgb itself at scale 1)
        rgb_video = shrink(rgb_work, self.video_scale) if self.video else None  # the frame the video shows
        thermal_aligned = self.inputs.thermal_in_rgb(thermal, self.scale)
        camera = None
        measure = getattr(self.tracker, "measure_camera_motion", None)  # stand-in trackers (tests) may lack it
        if measure is not None:  # the box-free part of camera motion, here: ahead of the tracker (D44)
            camera = measure(rgb_work, thermal_aligned, first=self._prepared == 0)
        self._prepared += 1
        return Prepared(rgb_work, thermal_aligned, rgb_video, thermal, stamp, camera)

    def skip(self, index: int, stamp: float) -> None:
        """An unreadable frame pair: keep the count, repeat the last box (and the last panel)."""
        if index == 0:
            raise InputError("the first frame pair is unreadable; the target cannot be initialised there")
        result = FrameResult(index, self.tracker.box.copy(), "skipped")
        self.write(result, self.inputs.box_in_t(result.box), stamp, self.last_panel)

    def track(self, index: int, rgb_work: np.ndarray, thermal_aligned: np.ndarray,
              camera: object | None = None) -> FrameResult:
        """The tracker's result for frame ``index`` (the first one initialises it on the starting box); ``camera``:
        the pair's camera-motion measurement from :meth:`prepare`, if it made one."""
        extra = {} if camera is None else {"camera": camera}
        if index == 0:
            self.first_rgb = rgb_work.copy() if self.plot else None
            return self.tracker.initialize(rgb_work, thermal_aligned, self.inputs.init_box, **extra)
        result = self.tracker.track(rgb_work, thermal_aligned, **extra)
        result.index = index  # the tracker counts the frames it saw; skipped frames count here too
        return result

    def thermal_box(self, index: int, result: FrameResult) -> np.ndarray:
        """The result's box in the thermal camera's pixels."""
        if index == 0 and self.inputs.init_box_t is not None:  # a round trip through the RGB camera is not exact
            return self.inputs.init_box_t.copy()
        return self.inputs.box_in_t(result.box)

    def panel(self, index: int, result: FrameResult, rgb_video: np.ndarray | None, thermal: np.ndarray,
              box_t: np.ndarray) -> LazyPanel | None:
        """The frame's annotated panel, drawn when the video writer asks for it; None without a video."""
        if not self.video:
            return None
        side = 2.0 * np.sqrt(result.box[2] * result.box[3])
        centre = box_centre(result.box)
        shift = _camera_shift(self.tracker)
        shift_t = None if shift is None else _shift_in_t(self.inputs.h_rgb_to_t, centre, shift)
        drawn = scale_box(result.box, self.draw_scale)  # drawn on the (working, video-scaled) frame
        region = scale_box(np.array([centre[0] - side / 2, centre[1] - side / 2, side, side]), self.draw_scale)
        return LazyPanel(self.annotator.draw, rgb_video, thermal, drawn, box_t, result.mode, _label(index, result),
                         result.w_f, region, shift=None if shift is None else shift * self.draw_scale, shift_t=shift_t,
                         thermal_size=self.inputs.t_size)

    def write(self, result: FrameResult, box_t: np.ndarray, stamp: float, panel: LazyPanel | None) -> None:
        """Hand the frame to the outputs and the caller's callbacks, and count it."""
        self.outputs.add(self.outputs.frame_record(result, result.box, box_t, stamp), result.box, box_t, panel)
        self.last_panel = panel
        if self.on_result:
            self.on_result(result, box_t, stamp)
        self.tally.count(result)
        if self.progress:
            self.progress(1)


def _label(index: int, result: FrameResult) -> str:
    """The panel's caption: frame number, MAX-PSR, MFNet's RGB weight, CM when camera motion was compensated."""
    return f"#{index}" + (f" q={result.q:.0f}" if np.isfinite(result.q) else "") + \
        (f" wG={result.w_g:.2f}" if np.isfinite(result.w_g) else "") + (" CM" if result.camera_motion else "")


class LazyPanel:
    """One frame's annotated panel, drawn when the video writer first asks for it and kept after that.

    Why: with ``io_threads`` the writer thread then draws it (about 3 ms at a 741x417 working scale), off the tracking
    thread. The frames are drawn in order, so the annotator's trails come out as if drawn in the loop; an unreadable
    frame hands the same object over again and so repeats the picture without drawing it twice.
    """

    def __init__(self, draw: Callable[..., np.ndarray], *args, **kwargs):
        self._call: tuple | None = (draw, args, kwargs)
        self._image: np.ndarray | None = None

    def __call__(self) -> np.ndarray:
        if self._call is not None:
            draw, args, kwargs = self._call
            self._image, self._call = draw(*args, **kwargs), None  # the frames it was drawn from can go
        return self._image


def _camera_shift(tracker: JmmacTracker) -> np.ndarray | None:
    """The tracker's accumulated camera shift in RGB pixels (stable = image + shift); None without camera motion."""
    if not tracker.config.camera_motion or tracker.camera_motion is None:
        return None
    shift = getattr(tracker, "camera_shift", None)  # a stand-in tracker (tests, batch fakes) may not have one
    return None if shift is None else np.array(shift, dtype=float)


def _shift_in_t(h_rgb_to_t: np.ndarray, centre: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """``shift`` (RGB pixels, at ``centre``) in thermal pixels, through the RGB->T homography near the target."""
    ends = project(h_rgb_to_t, np.array([centre, centre + shift], dtype=float))
    return ends[1] - ends[0]
