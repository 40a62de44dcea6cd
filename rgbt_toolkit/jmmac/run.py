"""The frame loop of ``rgbt track``: feed paired frames to the tracker, stream results to the output folder.

The loop owns I/O, timing and drawing; the tracker only sees frames. An interruption (Ctrl-C) or a failure mid-run
still closes every output as a complete file up to the last frame processed.

With ``io_threads`` (the default) the tracker keeps the calling thread to itself: a reader thread decodes and
prepares the next frame pairs (shrink, thermal warp) a few frames ahead, and a writer thread encodes the annotated
video behind a bounded queue (:class:`~rgbt_toolkit.jmmac.inputs.ReadAhead`,
:class:`~rgbt_toolkit.io.video.ThreadedVideoWriter`). Both run without the GIL for most of their work (PyAV, OpenCV),
so a second core takes them over; the results are the same frame for frame as with ``io_threads=False``, and both
threads are ended and joined before :func:`run_tracking` returns or raises.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rgbt_toolkit import __version__
from rgbt_toolkit.jmmac.annotate import Annotator, tail_length
from rgbt_toolkit.jmmac.inputs import ReadAhead, TrackInputs
from rgbt_toolkit.jmmac.outputs import TrackOutputs
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.jmmac.pipeline import FrameResult, JmmacTracker, box_centre
from rgbt_toolkit.jmmac.working_scale import ScaledTracker, scale_box, shrink, working_scale
from rgbt_toolkit.registration.transforms import project
from rgbt_toolkit.run_plots import plot_track


def run_tracking(inputs: TrackInputs, tracker: JmmacTracker, outdir: str | os.PathLike, *, video: bool = True,
                 show_weights: bool = False, progress: Callable[[int], None] | None = None,
                 max_frames: int | None = None, plot: bool = True, absent_rows: str = "hold", anti_uav: bool = False,
                 on_result: Callable[[FrameResult, np.ndarray, float], None] | None = None,
                 full_resolution: bool = False, io_threads: bool = True, video_scale: float = 1.0,
                 video_preset: str = "ultrafast", video_crf: int = 23) -> dict:
    """Track through ``inputs`` and write ``boxes_rgb.txt``, ``boxes_t.txt``, ``track.json``, ``annotated.mp4`` and
    ``track.png`` (drawn from track.json's records once they are closed; skipped with ``plot=False``).

    ``on_result(result, box_t, time_s)`` sees every frame's full-precision result (the files hold rounded boxes);
    :func:`rgbt_toolkit.track` keeps them in memory through it. Returns the run summary (frames, frames/s, mean time
    per module, modes, paths, whether it was interrupted). ``absent_rows`` / ``anti_uav``: see
    :class:`~rgbt_toolkit.jmmac.outputs.TrackOutputs` (the Anti-UAV files are named after the input).

    Frames wider than 640 px are tracked, and drawn into the annotated video, at a working scale
    (:mod:`rgbt_toolkit.jmmac.working_scale`) unless ``full_resolution``; the box files are in full-resolution pixels.
    ``video_scale`` (0 < F <= 1) shrinks the annotated video further: drawn at F times the working frame's size;
    ``video_preset`` and ``video_crf`` are x264's speed preset and quality for it (see
    :class:`~rgbt_toolkit.jmmac.outputs.TrackOutputs`).

    ``io_threads``: decode ahead on a reader thread (not for live sources, whose reader already keeps only the newest
    pair) and encode the video on a writer thread; False runs everything on the calling thread.
    """
    if not (np.isfinite(video_scale) and 0.0 < video_scale <= 1.0):
        raise InputError(f"the video scale must be in (0, 1], got {video_scale}")
    config = tracker.config
    scale = 1.0 if full_resolution else working_scale(inputs.rgb_size, inputs.init_box)
    if scale < 1.0:
        tracker = ScaledTracker(tracker, scale)
    meta = {
        "tool": f"rgbt-toolkit {__version__}",
        "inputs": inputs.description,
        "init_box_rgb": [round(float(v), 3) for v in inputs.init_box],
        "init_source": inputs.init_source,
        "h_rgb_to_t": np.round(inputs.h_rgb_to_t, 8).tolist(),
        "config": {k: getattr(config, k) for k in config.__dataclass_fields__},
        "notes": inputs.notes,
        "working_scale": round(scale, 6),  # frames were shrunk by this factor for tracking and drawing
        "video_scale": round(float(video_scale), 6),  # annotated.mp4 is drawn at working_scale * video_scale
        "box_convention": "x, y, w, h in each camera's pixels; x, y = first pixel column/row of the target",
    }
    outputs = TrackOutputs(outdir, meta, inputs.fps or 30.0, video=video, keep_records=plot, absent_rows=absent_rows,
                           anti_uav_name=inputs.name if anti_uav else None, threaded_video=io_threads and video,
                           video_preset=video_preset, video_crf=video_crf)
    annotator = Annotator(tail_length(inputs.fps, config.max_tail), show_weights)  # the last second of frames
    first_rgb = None  # the faint background of track.png
    totals: dict[str, float] = {}
    modes: dict[str, int] = {}
    frames, absent, interrupted, error, started = 0, 0, False, None, time.perf_counter()
    panel = None
    stages: dict[str, float] = {}  # where the loop's wall time goes: read, prepare, track, annotate, write

    def lap(name: str, since: float) -> float:
        now = time.perf_counter()
        stages[name] = stages.get(name, 0.0) + now - since
        return now

    def prepare(pair):
        """The frames the tracker and the video need; runs on the reader thread with ``io_threads``."""
        rgb, thermal, stamp = pair
        if rgb is None or thermal is None:
            return None, None, None, thermal, stamp
        rgb_work = shrink(rgb, scale)  # the frame the tracker sees (rgb itself at scale 1)
        rgb_video = shrink(rgb_work, video_scale) if video else None  # the frame the video shows
        return rgb_work, inputs.thermal_in_rgb(thermal, scale), rgb_video, thermal, stamp

    draw_scale = scale * video_scale  # full-resolution RGB pixels -> annotated-video pixels
    # live sources: their reader already drops stale pairs; reading ahead would hand the tracker old ones
    reader = ReadAhead(inputs.pairs, prepare, limit=max_frames) if io_threads and inputs.live is None else None
    mark = time.perf_counter()
    try:
        for index, item in enumerate(reader if reader is not None else inputs.pairs):
            mark = lap("read", mark)
            if max_frames is not None and index >= max_frames:
                break
            if reader is None:
                item = prepare(item)
                mark = lap("prepare", mark)
            rgb_work, thermal_aligned, rgb_video, thermal, stamp = item
            if rgb_work is None:  # unreadable frame: keep the count, repeat the last box
                if index == 0:
                    raise InputError("the first frame pair is unreadable; the target cannot be initialised there")
                result = FrameResult(index, tracker.box.copy(), "skipped")
                outputs.add(outputs.frame_record(result, result.box, inputs.box_in_t(result.box), stamp),
                            result.box, inputs.box_in_t(result.box), panel)  # the last panel again
                if on_result:
                    on_result(result, inputs.box_in_t(result.box), stamp)
                frames += 1
                modes["skipped"] = modes.get("skipped", 0) + 1
                if progress:
                    progress(1)
                mark = time.perf_counter()
                continue
            if index == 0:
                first_rgb = rgb_work.copy() if plot else None
                result = tracker.initialize(rgb_work, thermal_aligned, inputs.init_box)
            else:
                result = tracker.track(rgb_work, thermal_aligned)
                result.index = index  # the tracker counts the frames it saw; skipped frames count here too
            mark = lap("track", mark)
            box_t = inputs.box_in_t(result.box)
            if index == 0 and inputs.init_box_t is not None:  # a round trip through the RGB camera is not exact
                box_t = inputs.init_box_t.copy()
            panel = None
            if video:
                text = f"#{index}" + (f" q={result.q:.0f}" if np.isfinite(result.q) else "") + \
                    (f" wG={result.w_g:.2f}" if np.isfinite(result.w_g) else "") + (" CM" if result.camera_motion else "")
                side = 2.0 * np.sqrt(result.box[2] * result.box[3])
                centre = box_centre(result.box)
                shift = _camera_shift(tracker)
                shift_t = None if shift is None else _shift_in_t(inputs.h_rgb_to_t, centre, shift)
                drawn = scale_box(result.box, draw_scale)  # drawn on the (working, video-scaled) frame
                region = scale_box(np.array([centre[0] - side / 2, centre[1] - side / 2, side, side]), draw_scale)
                panel = LazyPanel(annotator.draw, rgb_video, thermal, drawn, box_t, result.mode, text, result.w_f,
                                  region, shift=None if shift is None else shift * draw_scale, shift_t=shift_t)
            mark = lap("annotate", mark)
            outputs.add(outputs.frame_record(result, result.box, box_t, stamp), result.box, box_t, panel)
            if on_result:
                on_result(result, box_t, stamp)
            for name, seconds in result.timings.items():
                totals[name] = totals.get(name, 0.0) + seconds
            modes[result.mode] = modes.get(result.mode, 0) + 1
            absent += not result.present
            frames += 1
            if progress:
                progress(1)
            mark = lap("write", mark)
    except KeyboardInterrupt:
        interrupted = True
    except Exception as exc:  # the files still close, and track.json says the run did not finish
        error = str(exc) or exc.__class__.__name__
        raise
    finally:
        read_seconds = 0.0
        if reader is not None:  # stop and join the reader thread (it closes the input files)
            try:
                reader.close()
            except KeyboardInterrupt:  # a Ctrl-C during the join: the thread is told to stop already; the files
                interrupted = True  # must still close, so finish the join
                reader.close()
            read_seconds = reader.busy_seconds
        if inputs.live is not None:  # stop the live readers (a run cut short by --max-frames, an error, Ctrl-C)
            inputs.live.close()
        # annotated.mp4 first (the writer's queue encoded, its thread joined), so the summary can say if it failed
        video_error = outputs.finish_video()
        if isinstance(video_error, KeyboardInterrupt):  # Ctrl-C while the encoder finished: the video is dropped
            interrupted, video_error = True, None
        elif video_error is not None and error is None:
            error = str(video_error)
        elapsed = time.perf_counter() - started
        tracked = max(frames - 1, 1)
        summary = {
            "frames": frames,
            "seconds": round(elapsed, 3),
            "fps": round(frames / elapsed, 2) if elapsed > 0 else None,
            "tracker_ms_per_frame": {k: round(1000 * v / tracked, 2) for k, v in totals.items()},
            # the loop's wall time per frame: waiting for decoded frames, shrink + thermal warp, the tracker (first
            # frame included), "annotate" (the panel's drawing call prepared), writing the files (the video's drawing
            # and encoding included when they run on this thread)
            "loop_ms_per_frame": {k: round(1000 * v / max(frames, 1), 2) for k, v in stages.items()},
            # with io_threads, the reader's (decode, shrink, warp) and the writer's (draw, encode) busy time per frame:
            # off the loop above, whose "read" / "write" are then only the waits for them
            "io_threads": bool(io_threads),
            "background_ms_per_frame": {"read_prepare": round(1000 * read_seconds / max(frames, 1), 2),
                                        "encode": round(1000 * outputs.encode_seconds / max(frames, 1), 2)}
            if io_threads else {},
            "modes": modes,
            "absent_frames": absent,  # frames with present: false (the re-acquisition module judged the target lost)
            # live sources with --realtime: pairs replaced by newer ones while the tracker was busy (never tracked)
            "dropped_frames": inputs.live.dropped if inputs.live is not None else 0,
            "source_notes": list(inputs.live.notes) if inputs.live is not None else [],
            "interrupted": interrupted,
            "error": error,
        }
        written = outputs.close(summary)
    if video_error is not None and not interrupted:  # the loop ended cleanly but the video could not be finished
        raise video_error
    if plot and outputs.records:
        try:  # atomic: a Ctrl-C / SIGTERM while drawing leaves no picture, and the other files stand
            plot_track(outputs.records, Path(outdir) / "track.png", background=first_rgb, title=inputs.name,
                       background_scale=scale)
            written["plot"] = Path(outdir) / "track.png"
        except KeyboardInterrupt:
            summary["interrupted"] = True
    summary["outputs"] = {k: str(Path(v)) for k, v in written.items()}
    return summary


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
