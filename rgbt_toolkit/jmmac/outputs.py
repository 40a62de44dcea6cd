"""The files ``rgbt track`` leaves in its output folder, written as a stream in constant memory.

``boxes_rgb.txt`` / ``boxes_t.txt`` (x,y,w,h per frame in each camera's pixels), ``track.json`` (per-frame record)
and ``annotated.mp4``; ``track.png`` is drawn afterwards from the same records (:attr:`TrackOutputs.records`).
Each goes to a temporary name and is renamed on :meth:`TrackOutputs.close`; when a run is interrupted, ``close``
still completes every file up to the last frame written, so an interrupted run leaves valid files, never half-written
ones. A text file that cannot be written whole (a full disk) leaves no record at all: every temporary, and the
video closed for the run, is removed, and the error names the file. The video can be encoded on a writer thread
(``threaded_video``); a failure there (or of the encoder in the caller's thread) drops ``annotated.mp4``, removes its temporary and is raised as a
:class:`~rgbt_toolkit.io.video.VideoWriteError`, while the text files still close complete.
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path
from typing import Callable

import numpy as np

from rgbt_toolkit.io.video import ThreadedVideoWriter, VideoWriter, video_write_error
from rgbt_toolkit.run_plots import TRACK_FIELDS


def _number(value) -> float | None:
    value = float(value)
    return round(value, 4) if np.isfinite(value) else None


def named_os_error(exc: OSError, path: Path) -> OSError:
    """``exc`` naming ``path`` (the file the user asked for): a write that fails on a full disk names no file, and
    one on a temporary names the hidden name."""
    return OSError(exc.errno, exc.strerror or str(exc), str(path))


class _StreamedText:
    """A text file written line by line under a temporary name, renamed on :meth:`publish`.

    A failed write or close (a full disk) is raised naming the final path and kept as :attr:`error`, so its owner
    can discard the stream together with the files that go with it.
    """

    def __init__(self, path: Path):
        self.path = path
        self.tmp = path.with_name(f".{path.name}.partial")
        self.error: OSError | None = None  # the first failed write or close, naming ``path``
        try:
            self.handle = open(self.tmp, "w", encoding="utf-8")
        except OSError as exc:
            raise named_os_error(exc, path) from None

    def write(self, text: str) -> None:
        try:
            self.handle.write(text)
        except OSError as exc:
            self.error = self.error or named_os_error(exc, self.path)
            raise self.error from None

    def finish(self) -> None:
        """Flush and close the temporary (where a full disk shows when the last lines were buffered)."""
        try:
            self.handle.close()
        except OSError as exc:
            self.error = self.error or named_os_error(exc, self.path)
            raise self.error from None

    def publish(self) -> None:
        """Rename the finished temporary onto the final name."""
        try:
            os.replace(self.tmp, self.path)
        except OSError as exc:
            raise named_os_error(exc, self.path) from None

    def discard(self) -> None:
        """Close and remove the temporary, whatever state it is in (never raises)."""
        with contextlib.suppress(OSError):  # the file goes anyway; its error was raised where it happened
            self.handle.close()
        with contextlib.suppress(OSError):
            self.tmp.unlink(missing_ok=True)


class TrackOutputs:
    """Streams one tracking run's results into ``outdir``."""

    def __init__(self, outdir: str | os.PathLike, meta: dict, fps: float, video: bool = True,
                 keep_records: bool = False, absent_rows: str = "hold", anti_uav_name: str | None = None,
                 threaded_video: bool = False, video_preset: str = "ultrafast", video_crf: int = 23):
        """``absent_rows``: what the box files hold on frames whose record says ``present: false`` - ``hold`` (the
        tracker's box, the benchmarks' convention) or ``zeros`` (``0,0,0,0``). ``anti_uav_name``: also write
        ``<name>_RGB.json`` and ``<name>_IR.json`` in the Anti-UAV result format on close. ``threaded_video``:
        encode ``annotated.mp4`` on a writer thread (:class:`~rgbt_toolkit.io.video.ThreadedVideoWriter`).
        ``video_preset`` / ``video_crf``: x264's speed preset and quality (lower crf: better, larger). The default,
        ultrafast at crf 23, encodes a 1009x568 frame in a third of veryfast's time (10.7 against 30.6 ms, one
        thread) for a file 2.5x larger: the encoder is the largest cost after the tracker on 1080p input, and
        docs/benchmarks.md ("Speed") shows the run is held to decode + CSRT's pace only with it."""
        if absent_rows not in ("hold", "zeros"):
            raise ValueError(f"absent_rows must be 'hold' or 'zeros', got {absent_rows!r}")
        self.absent_rows, self.anti_uav_name = absent_rows, anti_uav_name
        self._anti_uav: tuple[list, list, list] = ([], [], [])  # RGB boxes, T boxes, present flags
        self.outdir = Path(outdir)
        self._made_outdir = not self.outdir.exists()  # removed again (if empty) when no record can be written
        self.outdir.mkdir(parents=True, exist_ok=True)
        self._streams: list[_StreamedText] = []
        try:
            for name in ("boxes_rgb.txt", "boxes_t.txt", "track.json"):
                self._streams.append(_StreamedText(self.outdir / name))
            self.boxes_rgb, self.boxes_t, self.track = self._streams
            self.track.write(json.dumps(meta, indent=1)[:-2] + ',\n "frames": [\n')
        except OSError:
            self._discard_text()
            raise
        writer = ThreadedVideoWriter if threaded_video else VideoWriter
        # one x264 thread: the tracker has the cores busy (8.3 -> 5.2 ms of CPU per 1262x418 frame), and the same
        # encoder settings on both paths give the same video with and without the writer thread
        self.video: VideoWriter | ThreadedVideoWriter | None = writer(
            self.outdir / "annotated.mp4", fps, threads=1, preset=video_preset, crf=video_crf) if video else None
        self.video_error: BaseException | None = None  # what stopped annotated.mp4 (it is then dropped)
        self.encode_seconds = 0.0  # the writer thread's encoding time (threaded_video)
        self._video_path: Path | None = None  # annotated.mp4 once closed complete
        self.frames = 0
        # the fields track.png draws of each record as written to track.json; kept only when a picture is drawn
        self.records: list[dict] | None = [] if keep_records else None

    def add(self, record: dict, box_rgb: np.ndarray, box_t: np.ndarray,
            panel: np.ndarray | Callable[[], np.ndarray] | None) -> None:
        """Append one frame: the annotated panel first (a video failure raises VideoWriteError before any of this
        frame is written; the writer thread reports its failures at the next hand-over), then its record for
        ``track.json`` and both boxes. ``panel`` may be a function that draws it (on the writer thread with
        ``threaded_video``); with ``threaded_video`` the panel and what it is drawn from must not be modified
        afterwards."""
        if self.video is not None and panel is not None:
            try:
                self.video.write(panel)
            except Exception as exc:
                error = video_write_error(self.video.path, exc)
                self._drop_video(error)
                if error is exc:
                    raise
                raise error from exc
        present = record.get("present", True) is not False
        if self.anti_uav_name is not None:
            for store, value in zip(self._anti_uav, (box_rgb, box_t, present)):
                store.append(value)
        if not present and self.absent_rows == "zeros":
            box_rgb = box_t = np.zeros(4)
        self.boxes_rgb.write(",".join(f"{v:.2f}" for v in box_rgb) + "\n")
        self.boxes_t.write(",".join(f"{v:.2f}" for v in box_t) + "\n")
        record = {k: (_number(v) if isinstance(v, (float, np.floating)) else v) for k, v in record.items()}
        self.track.write(("" if self.frames == 0 else ",\n") + "  " + json.dumps(record, separators=(",", ":")))
        if self.records is not None:
            self.records.append({k: record[k] for k in TRACK_FIELDS if k in record})
        self.frames += 1

    def _drop_video(self, error: BaseException) -> None:
        video, self.video = self.video, None
        self.video_error = self.video_error or error
        if video is not None:
            video.abort()

    def finish_video(self) -> BaseException | None:
        """Close ``annotated.mp4`` (the frames still queued for the writer thread encoded first), or drop it when no
        frame reached it. Returns what stopped the video (a :class:`VideoWriteError`, or a ``KeyboardInterrupt`` that
        came while the encoder finished), the file then dropped and its temporary removed; None when all is well.
        Never raises, so the text files can still be closed."""
        video, self.video = self.video, None
        if video is not None:
            try:
                if video.frames_written:
                    video.close()
                    self._video_path = video.path
                else:
                    video.abort()
            except BaseException as exc:  # reported by the caller; the other files must still close
                self.video_error = self.video_error or (exc if isinstance(exc, KeyboardInterrupt)
                                                        else video_write_error(video.path, exc))
                video.abort()
            self.encode_seconds = getattr(video, "encode_seconds", 0.0)
        return self.video_error

    def close(self, summary: dict | None = None) -> dict[str, Path]:
        """Finish every file (also after an interruption) and return their paths (``annotated.mp4`` when it was
        closed complete: see :meth:`finish_video`, called here unless the caller did first)."""
        self.finish_video()
        tail = {"frames_written": self.frames, **(summary or {})}
        written: dict[str, Path] = {}
        try:
            self._write_anti_uav(written)
        except OSError:
            self._discard(list(written.values()))
            raise
        self._finish_text(tail, list(written.values()))
        for name, stream in zip(("boxes_rgb", "boxes_t", "track"), self._streams):
            written[name] = stream.path
        if self._video_path is not None:
            written["video"] = self._video_path
        return written

    def _write_anti_uav(self, written: dict[str, Path]) -> None:
        """``<name>_RGB.json`` and ``<name>_IR.json`` (Anti-UAV results) when asked for and a frame was written; each
        goes into ``written`` as soon as it is, so a failure on the second leaves the first to be removed."""
        if self.anti_uav_name is None or not self._anti_uav[2]:
            return
        from rgbt_toolkit.io.anti_uav import write_anti_uav_result

        rgb, t, present = self._anti_uav
        for key, suffix, boxes in (("anti_uav_rgb", "RGB", rgb), ("anti_uav_ir", "IR", t)):
            path = self.outdir / f"{self.anti_uav_name}_{suffix}.json"
            write_anti_uav_result(path, np.array(boxes, dtype=float), np.array(present, dtype=bool))
            written[key] = path

    def _finish_text(self, tail: dict, companions: list[Path]) -> None:
        """End track.json with ``tail`` and put the three text files in place, all or none.

        When any of them cannot be written whole (a full disk, during the run or now), no record of the run is left:
        the temporaries, the ``companions`` written for the run and its closed video are removed, and the error,
        naming the file, is raised. Files that lost a line would no longer agree frame for frame.
        """
        published: list[Path] = []
        try:
            failed = [stream.error for stream in self._streams if stream.error is not None]
            if failed:
                raise failed[0]
            self.track.write("\n ],\n" + json.dumps({"summary": tail}, indent=1)[2:] + "\n")
            for stream in self._streams:
                stream.finish()
            for stream in self._streams:
                stream.publish()
                published.append(stream.path)
        except OSError:
            self._discard(companions + published)
            raise

    def _discard(self, paths: list[Path]) -> None:
        """Remove ``paths`` (files this run wrote), the closed video, every text temporary, and the output folder
        when this run made it and it is empty again. Never raises."""
        for path in paths + ([self._video_path] if self._video_path is not None else []):
            with contextlib.suppress(OSError):  # the error that stopped the run is the one to report
                path.unlink(missing_ok=True)
        self._video_path = None
        self._discard_text()

    def _discard_text(self) -> None:
        """Remove the text temporaries, and the output folder when this run made it and nothing else is in it."""
        for stream in self._streams:
            stream.discard()
        if self._made_outdir:
            with contextlib.suppress(OSError):  # not empty (other files of the run) or gone: left as it is
                self.outdir.rmdir()

    def frame_record(self, result, box_rgb: np.ndarray, box_t: np.ndarray, time_s: float) -> dict:
        """The per-frame ``track.json`` entry for a :class:`~rgbt_toolkit.jmmac.pipeline.FrameResult`."""
        return {
            "frame": result.index,
            "time": round(float(time_s), 4),
            "box_rgb": [_number(v) for v in box_rgb],
            "box_t": [_number(v) for v in box_t],
            "mode": result.mode,
            "present": bool(getattr(result, "present", True)),
            "confidence": getattr(result, "confidence", float("nan")),
            "q": result.q,
            "s_a": result.s_a,
            "s_m": result.s_m,
            "camera_motion": bool(result.camera_motion),
            "w_g": result.w_g,
            "refined": bool(result.refined),
            "timing_ms": {k: round(v * 1000, 2) for k, v in result.timings.items()},
        }
