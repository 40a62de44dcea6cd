"""The frame loop of ``rgbt track``: feed paired frames to the tracker, stream results to the output folder.

The loop owns I/O, timing and drawing; the tracker only sees frames. An interruption (Ctrl-C) or a failure mid-run
still closes every output as a complete file up to the last frame processed.

With ``io_threads`` (the default) the tracker keeps the calling thread to itself: a reader thread decodes and
prepares the next frame pairs (shrink, thermal warp) a few frames ahead, and a writer thread encodes the annotated
video behind a bounded queue (:class:`~rgbt_toolkit.jmmac.inputs.ReadAhead`,
:class:`~rgbt_toolkit.io.video.ThreadedVideoWriter`). Both run without the GIL for most of their work (PyAV, OpenCV),
so a second core takes them over; the results are the same frame for frame as with ``io_threads=False``, and both
threads are ended and joined before :func:`run_tracking` returns or raises.

This module holds the set-up, the loop (:func:`_frame_loop`) and the clean-up; each frame's steps (prepare, track,
draw, write) are methods of :class:`~rgbt_toolkit.jmmac.frame_steps.FrameSteps`.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from rgbt_toolkit import __version__
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.jmmac.annotate import Annotator, default_video_scale, tail_length
from rgbt_toolkit.jmmac.config import JmmacConfig
from rgbt_toolkit.jmmac.frame_steps import FrameSteps, RunTally, StageClock
from rgbt_toolkit.jmmac.inputs import ReadAhead, TrackInputs
from rgbt_toolkit.jmmac.outputs import TrackOutputs
from rgbt_toolkit.jmmac.pipeline import FrameResult, JmmacTracker
from rgbt_toolkit.jmmac.working_scale import ScaledTracker, sample_side, working_scale, working_size
from rgbt_toolkit.run_plots import plot_track


def run_tracking(inputs: TrackInputs, tracker: JmmacTracker, outdir: str | os.PathLike, *, video: bool = True,
                 show_weights: bool = False, progress: Callable[[int], None] | None = None,
                 max_frames: int | None = None, plot: bool = True, absent_rows: str = "hold", anti_uav: bool = False,
                 on_result: Callable[[FrameResult, np.ndarray, float], None] | None = None,
                 full_resolution: bool = False, io_threads: bool = True, video_scale: float | None = None,
                 video_preset: str = "ultrafast", video_crf: int = 23) -> dict:
    """Track through ``inputs`` and write ``boxes_rgb.txt``, ``boxes_t.txt``, ``track.json``, ``annotated.mp4`` and
    ``track.png`` (drawn from track.json's records once they are closed; skipped with ``plot=False``).

    ``on_result(result, box_t, time_s)`` sees every frame's full-precision result (the files hold rounded boxes);
    :func:`rgbt_toolkit.track` keeps them in memory through it. Returns the run summary (frames, frames/s, mean time
    per module, modes, paths, whether it was interrupted). ``absent_rows`` / ``anti_uav``: see
    :class:`~rgbt_toolkit.jmmac.outputs.TrackOutputs` (the Anti-UAV files are named after the input).

    Frames wider than 640 px are tracked, and drawn into the annotated video, at a working scale
    (:mod:`rgbt_toolkit.jmmac.working_scale`) unless ``full_resolution``; the box files are in full-resolution pixels.
    ``video_scale`` (0 < F <= 1) shrinks the annotated video further: drawn at F times the working frame's size
    (default: the largest F, at most 1, that keeps the panel of both views at most ``PANEL_MAX_WIDTH`` px wide);
    ``video_preset`` and ``video_crf`` are x264's speed preset and quality for it (see
    :class:`~rgbt_toolkit.jmmac.outputs.TrackOutputs`).

    ``io_threads``: decode ahead on a reader thread (not for live sources, whose reader already keeps only the newest
    pair) and encode the video on a writer thread; False runs everything on the calling thread.
    """
    if video_scale is not None and not (np.isfinite(video_scale) and 0.0 < video_scale <= 1.0):
        raise InputError(f"the video scale must be in (0, 1], got {video_scale}")
    config = tracker.config
    scale = 1.0 if full_resolution else working_scale(inputs.rgb_size, inputs.init_box,
                                                          sample_side=sample_side(tracker))
    if video_scale is None:
        video_scale = default_video_scale(working_size(inputs.rgb_size, scale), inputs.t_size)
    if scale < 1.0:
        tracker = ScaledTracker(tracker, scale)
        inputs.decode_for(scale)
    outputs = TrackOutputs(outdir, _run_meta(inputs, config, scale, video_scale), inputs.fps or 30.0, video=video,
                           keep_records=plot, absent_rows=absent_rows,
                           anti_uav_name=inputs.name if anti_uav else None, threaded_video=io_threads and video,
                           video_preset=video_preset, video_crf=video_crf)
    annotator = Annotator(tail_length(inputs.fps, config.max_tail), show_weights)  # the last second of frames
    steps = FrameSteps(inputs, tracker, outputs, annotator, scale=scale, video_scale=video_scale, video=video,
                       plot=plot, progress=progress, on_result=on_result)
    summary, written = _run_frames(steps, max_frames=max_frames, io_threads=io_threads)
    if plot and outputs.records:
        try:  # atomic: a Ctrl-C / SIGTERM while drawing leaves no picture, and the other files stand
            plot_track(outputs.records, Path(outdir) / "track.png", background=steps.first_rgb, title=inputs.name,
                       background_scale=scale)
            written["plot"] = Path(outdir) / "track.png"
        except KeyboardInterrupt:
            summary["interrupted"] = True
    summary["outputs"] = {k: str(Path(v)) for k, v in written.items()}
    return summary


def _run_meta(inputs: TrackInputs, config: JmmacConfig, scale: float, video_scale: float) -> dict:
    """The run's description at the head of track.json."""
    return {
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


def _run_frames(steps: FrameSteps, *, max_frames: int | None, io_threads: bool) -> tuple[dict, dict]:
    """Run the frame loop, then close every output however the loop ended: ``(summary, written paths)``.

    A Ctrl-C ends the run early (``interrupted``); another error is recorded in track.json and raised. Either way the
    reader thread, the live readers and the video writer are joined and the files closed first.
    """
    inputs, outputs = steps.inputs, steps.outputs
    interrupted, error, started = False, None, time.perf_counter()
    # live sources: their reader already drops stale pairs; reading ahead would hand the tracker old ones
    reader = ReadAhead(inputs.pairs, steps.prepare, limit=max_frames) if io_threads and inputs.live is None else None
    clock = StageClock()
    try:
        _frame_loop(reader if reader is not None else inputs.pairs, steps, clock, prepare=reader is None,
                    max_frames=max_frames)
    except KeyboardInterrupt:
        interrupted = True
    except Exception as exc:  # the files still close, and track.json says the run did not finish
        error = str(exc) or exc.__class__.__name__
        raise
    finally:
        read_seconds, ctrl_c_in_join = _join_reader(reader)
        interrupted = interrupted or ctrl_c_in_join
        if inputs.live is not None:  # stop the live readers (a run cut short by --max-frames, an error, Ctrl-C)
            inputs.live.close()
        # annotated.mp4 first (the writer's queue encoded, its thread joined), so the summary can say if it failed
        video_error = outputs.finish_video()
        if isinstance(video_error, KeyboardInterrupt):  # Ctrl-C while the encoder finished: the video is dropped
            interrupted, video_error = True, None
        elif video_error is not None and error is None:
            error = str(video_error)
        summary = _summary(steps.tally, clock.seconds, time.perf_counter() - started, io_threads=io_threads,
                           read_seconds=read_seconds, encode_seconds=outputs.encode_seconds, inputs=inputs,
                           interrupted=interrupted, error=error)
        written = outputs.close(summary)
    if video_error is not None and not interrupted:  # the loop ended cleanly but the video could not be finished
        raise video_error
    return summary, written


def _frame_loop(pairs: Iterable, steps: FrameSteps, clock: StageClock, *, prepare: bool,
                max_frames: int | None) -> None:
    """Track, draw and write each frame pair in turn; ``prepare``: the pairs come unprepared (no reader thread)."""
    for index, item in enumerate(pairs):
        clock.lap("read")
        if max_frames is not None and index >= max_frames:
            break
        if prepare:
            item = steps.prepare(item)
            clock.lap("prepare")
        rgb_work, thermal_aligned, rgb_video, thermal, stamp, camera = item
        if rgb_work is None:  # unreadable frame: keep the count, repeat the last box
            steps.skip(index, stamp)
            clock.restart()  # a skipped frame's bookkeeping counts in no stage
            continue
        result = steps.track(index, rgb_work, thermal_aligned, camera)
        clock.lap("track")
        box_t = steps.thermal_box(index, result)
        panel = steps.panel(index, result, rgb_video, thermal, box_t)
        clock.lap("annotate")
        steps.write(result, box_t, stamp, panel)
        clock.lap("write")


def _join_reader(reader: ReadAhead | None) -> tuple[float, bool]:
    """Stop and join the reader thread (it closes the input files): its busy seconds, and whether a Ctrl-C came
    during the join (the thread is told to stop already and the files must still close, so the join is finished)."""
    if reader is None:
        return 0.0, False
    try:
        reader.close()
    except KeyboardInterrupt:
        reader.close()
        return reader.busy_seconds, True
    return reader.busy_seconds, False


def _summary(tally: RunTally, stages: dict[str, float], elapsed: float, *, io_threads: bool, read_seconds: float,
             encode_seconds: float, inputs: TrackInputs, interrupted: bool, error: str | None) -> dict:
    """The run summary: what run_tracking returns and track.json ends with."""
    frames = tally.frames
    tracked = max(frames - 1, 1)
    return {
        "frames": frames,
        "seconds": round(elapsed, 3),
        "fps": round(frames / elapsed, 2) if elapsed > 0 else None,
        "tracker_ms_per_frame": {k: round(1000 * v / tracked, 2) for k, v in tally.tracker_seconds.items()},
        # the loop's wall time per frame: waiting for decoded frames, shrink + thermal warp, the tracker (first
        # frame included), "annotate" (the panel's drawing call prepared), writing the files (the video's drawing
        # and encoding included when they run on this thread)
        "loop_ms_per_frame": {k: round(1000 * v / max(frames, 1), 2) for k, v in stages.items()},
        # with io_threads, the reader's (decode, shrink, warp) and the writer's (draw, encode) busy time per frame:
        # off the loop above, whose "read" / "write" are then only the waits for them
        "io_threads": bool(io_threads),
        "background_ms_per_frame": {"read_prepare": round(1000 * read_seconds / max(frames, 1), 2),
                                    "encode": round(1000 * encode_seconds / max(frames, 1), 2)}
        if io_threads else {},
        "modes": tally.modes,
        "absent_frames": tally.absent,  # frames with present: false (the re-acquisition module judged the target lost)
        # live sources with --realtime: pairs replaced by newer ones while the tracker was busy (never tracked)
        "dropped_frames": inputs.live.dropped if inputs.live is not None else 0,
        "source_notes": list(inputs.live.notes) if inputs.live is not None else [],
        "interrupted": interrupted,
        "error": error,
    }
