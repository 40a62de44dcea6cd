"""Single-modality tracking loop over a frame stream (the harness of ``rgbt track-single``).

The loop owns I/O-free orchestration only: initialise on the first frame, ``track`` the rest, collect boxes and
per-stage timings. Reading frames and writing files stay with the caller.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Iterable

import numpy as np

from rgbt_toolkit.eco.params import EcoParams
from rgbt_toolkit.eco.reacquire import Reacquirer, ReacquireParams
from rgbt_toolkit.eco.tracker import EcoTracker, check_box
from rgbt_toolkit.errors import InputError


@dataclass
class SingleTrackRun:
    """Boxes ``(N, 4)`` (x, y, w, h; row 0 is the initial box), peak/PSR per frame and summed stage timings.

    ``present`` is False on frames where the target counted as lost (with re-acquisition on) and the box is the last
    reliable one held; always True without re-acquisition.
    """

    boxes: np.ndarray
    peaks: np.ndarray
    psrs: np.ndarray
    present: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    seconds: dict = field(default_factory=dict)
    frames: int = 0
    skipped: int = 0  # unreadable frames, whose rows repeat the previous box
    interrupted: bool = False  # stopped by Ctrl-C: the rows so far are complete, the rest missing

    @property
    def fps(self) -> float:
        """Frames per second over the tracked frames (initialisation excluded)."""
        spent = sum(v for k, v in self.seconds.items() if k != "initialize")
        tracked = self.frames - 1 - self.skipped
        return tracked / spent if tracked > 0 and spent > 0 else float("nan")


def track_frames(frames: Iterable[np.ndarray | None], init_box, params: EcoParams, *, max_frames: int | None = None,
                 progress: Callable[[int], None] | None = None,
                 reacquire: ReacquireParams | None = None,
                 on_frame: Callable[[np.ndarray | None, np.ndarray, bool], None] | None = None) -> SingleTrackRun:
    """Track one target through ``frames`` (uint8 RGB or grey arrays) from ``init_box`` in the first frame.

    A ``None`` frame (unreadable) gets the previous box again, so row N of the boxes is always frame N. With
    ``reacquire`` a lost target is searched for over the whole frame (``eco.reacquire``); while lost the model is
    not updated and the last reliable box is held. ``on_frame(frame, box, present)`` is called after every frame
    with its row (an annotated video is drawn there while the frame is still at hand).
    """
    box = check_box(init_box, "--init box")
    tracker = EcoTracker(params)
    watchdog = Reacquirer(reacquire) if reacquire is not None else None
    present: list[bool] = []
    boxes, peaks, psrs = [], [], []
    seconds = {"initialize": 0.0, "features": 0.0, "detection": 0.0, "update": 0.0}
    n = skipped = 0
    interrupted = False
    stream = iter(frames)
    while max_frames is None or n < max_frames:
        try:  # a Ctrl-C ends the run with the rows so far (written by the caller), as `rgbt track` does
            frame = next(stream, _END)
            if frame is _END:
                break
            unreadable = _step(tracker, frame, n, box, boxes, peaks, psrs, seconds, watchdog, present)
            if on_frame is not None:
                on_frame(frame, boxes[-1], present[-1])
        except KeyboardInterrupt:
            interrupted = True
            del boxes[n:], peaks[n:], psrs[n:], present[n:]  # a frame cut short leaves no partial row
            break
        skipped += unreadable
        n += 1
        if progress is not None:
            progress(1)
    return SingleTrackRun(np.array(boxes).reshape(-1, 4), np.array(peaks), np.array(psrs), np.array(present, bool),
                          seconds, n, skipped, interrupted)


_END = object()


def _step(tracker: EcoTracker, frame, n: int, box, boxes: list, peaks: list, psrs: list, seconds: dict,
          watchdog: Reacquirer | None, present: list) -> int:
    """Track frame ``n`` (initialise on frame 0), appending its row; returns 1 for an unreadable frame, else 0."""
    if frame is None:
        if n == 0:
            raise InputError("the first frame is unreadable; the target cannot be initialised there")
        boxes.append(boxes[-1])
        peaks.append(np.nan)
        psrs.append(np.nan)
        present.append(present[-1])
        return 1
    if n == 0:
        check_box(box, "--init box", np.shape(frame))
        t0 = time.perf_counter()
        tracker.initialize(frame, box)
        if watchdog is not None:
            watchdog.start(frame, box)
        seconds["initialize"] = time.perf_counter() - t0
        boxes.append(box)
        peaks.append(np.nan)
        psrs.append(np.nan)
        present.append(True)
        return 0
    if watchdog is None:
        res = tracker.track(frame)
        found = True
    else:
        res, found = _watched_step(tracker, watchdog, frame, seconds)
    if res is not None:
        for k, v in res.timings.items():
            seconds[k] = seconds.get(k, 0.0) + v
    boxes.append(res.box if found else boxes[-1])
    peaks.append(res.peak if res is not None else np.nan)
    psrs.append(res.psr if res is not None else np.nan)
    present.append(found)
    return 0


def _watched_step(tracker: EcoTracker, watchdog: Reacquirer, frame, seconds: dict):
    """One frame under the watchdog: ``(result or None, target found)``; the model learns only from found frames."""
    if not watchdog.lost:
        res = tracker.predict(frame)
        if not watchdog.observe(res.peak):
            res.timings.update(tracker.update(frame, res.box))
            return res, True
    t0 = time.perf_counter()
    res = watchdog.search_eco(tracker, frame)
    seconds["reacquire"] = seconds.get("reacquire", 0.0) + time.perf_counter() - t0
    if res is None:
        return None, False
    res.timings = tracker.update(frame, res.box)
    return res, True
