"""The frame loop of ``rgbt track``: feed paired frames to the tracker, stream results to the output folder.

The loop owns I/O, timing and drawing; the tracker only sees frames. An interruption (Ctrl-C) or a failure mid-run
still closes every output as a complete file up to the last frame processed.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rgbt_toolkit import __version__
from rgbt_toolkit.jmmac.annotate import Annotator, tail_length
from rgbt_toolkit.jmmac.inputs import TrackInputs
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
                 full_resolution: bool = False) -> dict:
    """Track through ``inputs`` and write ``boxes_rgb.txt``, ``boxes_t.txt``, ``track.json``, ``annotated.mp4`` and
    ``track.png`` (drawn from track.json's records once they are closed; skipped with ``plot=False``).

    ``on_result(result, box_t, time_s)`` sees every frame's full-precision result (the files hold rounded boxes);
    :func:`rgbt_toolkit.track` keeps them in memory through it. Returns the run summary (frames, frames/s, mean time
    per module, modes, paths, whether it was interrupted). ``absent_rows`` / ``anti_uav``: see
    :class:`~rgbt_toolkit.jmmac.outputs.TrackOutputs` (the Anti-UAV files are named after the input).

    Frames wider than 640 px are tracked, and drawn into the annotated video, at a working scale
    (:mod:`rgbt_toolkit.jmmac.working_scale`) unless ``full_resolution``; the box files are in full-resolution pixels.
    """
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
        "box_convention": "x, y, w, h in each camera's pixels; x, y = first pixel column/row of the target",
    }
    outputs = TrackOutputs(outdir, meta, inputs.fps or 30.0, video=video, keep_records=plot, absent_rows=absent_rows,
                           anti_uav_name=inputs.name if anti_uav else None)
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

    mark = time.perf_counter()
    try:
        for index, (rgb, thermal, stamp) in enumerate(inputs.pairs):
            mark = lap("read", mark)
            if max_frames is not None and index >= max_frames:
                break
            if rgb is None or thermal is None:  # unreadable frame: keep the count, repeat the last box
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
            rgb_work = shrink(rgb, scale)  # the frame the tracker and the video see (rgb itself at scale 1)
            thermal_aligned = inputs.thermal_in_rgb(thermal, scale)
            mark = lap("prepare", mark)
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
                drawn = scale_box(result.box, scale)  # drawn on the working frame
                region = scale_box(np.array([centre[0] - side / 2, centre[1] - side / 2, side, side]), scale)
                panel = annotator.draw(rgb_work, thermal, drawn, box_t, result.mode, text, result.w_f, region,
                                       shift=None if shift is None else shift * scale, shift_t=shift_t)
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
        elapsed = time.perf_counter() - started
        if inputs.live is not None:  # stop the live readers (a run cut short by --max-frames, an error, Ctrl-C)
            inputs.live.close()
        tracked = max(frames - 1, 1)
        summary = {
            "frames": frames,
            "seconds": round(elapsed, 3),
            "fps": round(frames / elapsed, 2) if elapsed > 0 else None,
            "tracker_ms_per_frame": {k: round(1000 * v / tracked, 2) for k, v in totals.items()},
            # the loop's wall time per frame: waiting for decoded frames, shrink + thermal warp, the tracker (first
            # frame included), drawing, writing the files (the video encoder's share included)
            "loop_ms_per_frame": {k: round(1000 * v / max(frames, 1), 2) for k, v in stages.items()},
            "modes": modes,
            "absent_frames": absent,  # frames with present: false (the re-acquisition module judged the target lost)
            # live sources with --realtime: pairs replaced by newer ones while the tracker was busy (never tracked)
            "dropped_frames": inputs.live.dropped if inputs.live is not None else 0,
            "source_notes": list(inputs.live.notes) if inputs.live is not None else [],
            "interrupted": interrupted,
            "error": error,
        }
        written = outputs.close(summary)
    if plot and outputs.records:
        try:  # atomic: a Ctrl-C / SIGTERM while drawing leaves no picture, and the other files stand
            plot_track(outputs.records, Path(outdir) / "track.png", background=first_rgb, title=inputs.name,
                       background_scale=scale)
            written["plot"] = Path(outdir) / "track.png"
        except KeyboardInterrupt:
            summary["interrupted"] = True
    summary["outputs"] = {k: str(Path(v)) for k, v in written.items()}
    return summary


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
