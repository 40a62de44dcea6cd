"""Video files through PyAV: streamed reading with presentation timestamps, and H.264 MP4 writing.

Frames are RGB uint8 arrays (H, W, 3), or on request grey (H, W) ones read from the luma plane; grey video of more
than 8 bits (raw thermal counts) gives (H, W) uint16 frames either way. Reading never loads
the whole file; writing goes to a temporary name that is renamed when the writer is closed cleanly, so an interrupted
run leaves no half-written file under the final name. :class:`ThreadedVideoWriter` does the encoding on a writer
thread behind a bounded queue (PyAV releases the GIL while it converts and encodes), so it overlaps the caller's work.
"""

from __future__ import annotations

import os
import queue
import threading
import time
import warnings
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Callable, Iterator

import av
import cv2
import numpy as np

from rgbt_toolkit.errors import FileFormatError, MissingFileError, RgbtError
from rgbt_toolkit.io.encoding import CRF_RANGE, X264_PRESETS
from rgbt_toolkit.io.images import is_grey_picture
from rgbt_toolkit.runtime import BACKGROUND_NICE, lower_thread_priority

VIDEO_SUFFIXES = (".mp4", ".avi", ".mkv", ".mov", ".webm", ".m4v", ".mpg", ".mpeg", ".ts")


class CorruptFrameWarning(UserWarning):
    """A frame in the middle of a video could not be decoded and was skipped."""


class VideoWriteError(RgbtError, OSError):
    """Encoding or writing an output video failed (a full disk, an encoder error); the message names the video.

    An :class:`OSError` too, so callers that handle unwritable outputs catch it; an :class:`RgbtError`, so the CLI
    prints it as one line."""


def video_write_error(path: Path, exc: BaseException) -> VideoWriteError:
    """``exc`` (raised while writing ``path``) as the one-line error that names the final file, not its temporary."""
    if isinstance(exc, VideoWriteError):
        return exc
    reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else (str(exc) or exc.__class__.__name__)
    return VideoWriteError(f"{path}: cannot write the video ({reason})")


def _raise_as_write_error(path: Path, exc: BaseException) -> None:
    error = video_write_error(path, exc)
    if error is exc:
        raise error
    raise error from exc


@dataclass(frozen=True)
class VideoInfo:
    """What a caller needs to pair and allocate frames before decoding them."""

    path: Path
    fps: float
    width: int
    height: int
    frame_count: int  # from the container; 0 when the container does not say
    duration: float  # seconds; 0.0 when unknown

    @property
    def size(self) -> tuple[int, int]:
        return self.width, self.height


def _open(path: Path) -> av.container.InputContainer:
    if not path.is_file():
        raise MissingFileError(f"{path}: no such file")
    if path.stat().st_size == 0:
        raise FileFormatError(f"{path}: file is empty (zero bytes), not a video")
    try:
        container = av.open(str(path))
    except av.error.FFmpegError as exc:
        raise FileFormatError(f"{path}: cannot open as a video ({exc.strerror or exc.__class__.__name__})") from None
    if not container.streams.video:
        container.close()
        raise FileFormatError(f"{path}: contains no video stream")
    return container


# 8-bit pixel formats whose first plane is the luma (Y) image, one byte per pixel
_LUMA_FIRST = {"yuv420p", "yuvj420p", "yuv422p", "yuvj422p", "yuv444p", "yuvj444p", "nv12", "nv21", "gray"}
_JPEG_RANGE = 2  # AVCOL_RANGE_JPEG: luma uses 0-255; otherwise video luma spans 16-235
# stretch limited-range luma to 0-255, as a conversion to RGB or grey would
_FULL_RANGE = np.clip(np.round((np.arange(256) - 16) * 255.0 / 219.0), 0, 255).astype(np.uint8)


def _high_bit_grey(frame: av.VideoFrame) -> bool:
    """A grey format of more than 8 bits (gray10le, gray12le, gray16le...; not float grey)."""
    name = frame.format.name
    return name.startswith("gray") and name != "gray" and not name.startswith("grayf")


def _luma(frame: av.VideoFrame) -> np.ndarray:
    """H x W grey image of a decoded frame: its Y plane where it has one, else converted.

    uint8 (0-255) for 8-bit and colour video; uint16 for grey video of more than 8 bits (a radiometric thermal
    camera's raw counts, e.g. FFV1 gray16le), whose few used levels would collapse to a blank frame at 8 bits. The
    caller stretches the used range (``registration.features.to_grey``, or ``io.pixels.FixedRange`` for trackers).
    """
    name = frame.format.name
    if _high_bit_grey(frame):
        return frame.to_ndarray(format="gray16le")
    if name not in _LUMA_FIRST:
        return frame.to_ndarray(format="gray")
    plane = frame.planes[0]
    rows = np.frombuffer(plane, np.uint8).reshape(frame.height, plane.line_size)[:, : frame.width]
    if name == "gray" or name.startswith("yuvj") or getattr(frame, "color_range", 0) == _JPEG_RANGE:
        return rows.copy()
    return cv2.LUT(rows, _FULL_RANGE)  # a new array: independent of the decoder's buffer


def frame_array(frame: av.VideoFrame, grey: bool = False) -> np.ndarray:
    """A decoded frame as the readers yield it: H x W x 3 RGB, or with ``grey`` its H x W luma; grey video of more
    than 8 bits stays 2-D uint16 either way (rgb24 would divide its counts by 257: a flat grey frame)."""
    return _luma(frame) if grey or _high_bit_grey(frame) else frame.to_ndarray(format="rgb24")


class VideoReader:
    """Stream frames of one video with their presentation timestamps in seconds.

    Iterating yields ``(frame, t)``; a frame that fails to decode mid-stream is skipped with a
    :class:`CorruptFrameWarning` so long recordings with one damaged packet still track.
    """

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        self.skipped_packets = 0  # undecodable packets met by the current (or last) pass of :meth:`frames`
        container = _open(self.path)
        try:
            stream = container.streams.video[0]
            rate = stream.average_rate or stream.guessed_rate or Fraction(0)
            fps = float(rate) if rate else 0.0
            duration = float(stream.duration * stream.time_base) if stream.duration and stream.time_base else 0.0
            if not duration and container.duration:
                duration = container.duration / av.time_base
            self.info = VideoInfo(
                path=self.path,
                fps=fps,
                width=stream.codec_context.width,
                height=stream.codec_context.height,
                frame_count=int(stream.frames or 0),
                duration=duration,
            )
        finally:
            container.close()
        if self.info.width <= 0 or self.info.height <= 0:
            raise FileFormatError(f"{self.path}: video stream has no frame size")

    @property
    def fps(self) -> float:
        return self.info.fps

    @property
    def size(self) -> tuple[int, int]:
        return self.info.size

    @property
    def frame_count(self) -> int:
        return self.info.frame_count

    def __iter__(self) -> Iterator[tuple[np.ndarray, float]]:
        return self.frames()

    def frames(self, grey: bool | str = False) -> Iterator[tuple[np.ndarray, float]]:
        """``(frame, t)`` pairs: H x W x 3 RGB frames, or with ``grey`` H x W luma frames; grey video of more than
        8 bits gives H x W uint16 frames either way (its raw counts; the caller maps them). ``grey="auto"``: luma
        frames when the first frame is a grey picture (:func:`is_grey_picture`), else RGB frames throughout.

        Grey frames of 8-bit YUV video are the decoder's own luma plane, stretched to 0-255 by a lookup table but
        never converted from colour: half the time of decoding to RGB at 640x480, and all that registration needs.
        """
        if grey not in (False, True, "auto"):
            raise ValueError(f"grey must be True, False or 'auto', got {grey!r}")
        container = _open(self.path)
        try:
            stream = container.streams.video[0]
            stream.thread_type = "AUTO"
            produced = 0
            self.skipped_packets = 0
            for packet in container.demux(stream):
                try:
                    frames = packet.decode()
                except av.error.FFmpegError as exc:
                    self.skipped_packets += 1
                    warnings.warn(
                        f"{self.path}: skipped an undecodable packet after frame {produced} ({exc.__class__.__name__})",
                        CorruptFrameWarning,
                        stacklevel=2,
                    )
                    continue
                for frame in frames:
                    t = float(frame.pts * frame.time_base) if frame.pts is not None else produced / (self.fps or 1.0)
                    produced += 1
                    if grey == "auto":
                        image = frame_array(frame)
                        grey = image.ndim == 2 or is_grey_picture(image)
                        yield (frame_array(frame, True) if grey and image.ndim == 3 else image), t
                        continue
                    yield frame_array(frame, grey), t
            if produced == 0:
                raise FileFormatError(f"{self.path}: video has no decodable frames")
        finally:
            container.close()

    def read_all(self) -> tuple[list[np.ndarray], np.ndarray]:
        """All frames and their timestamps; only for short clips (tests, samples)."""
        frames, times = [], []
        for frame, t in self:
            frames.append(frame)
            times.append(t)
        return frames, np.asarray(times)


class VideoWriter:
    """Write RGB frames to an H.264 MP4 (yuv420p, readable by common players) atomically.

    Use as a context manager; the file appears under its final name only after a clean close. On Ctrl-C
    (``KeyboardInterrupt``) the frames written so far are kept as a complete, shorter video when ``keep_partial``
    (``rgbt track`` keeps what it tracked); with ``keep_partial=False`` nothing is left, as for any other error
    (``rgbt synth``, whose partial video would not match its ground truth).
    """

    def __init__(self, path: str | os.PathLike, fps: float, *, crf: int = 23, preset: str = "veryfast",
                 keep_partial: bool = True, threads: int = 0):
        self.path = Path(path)
        self.keep_partial = keep_partial
        if fps <= 0:
            raise ValueError(f"{self.path}: frame rate must be positive, got {fps}")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._tmp = self.path.with_name(f".{self.path.stem}.partial{self.path.suffix or '.mp4'}")
        self._container = av.open(str(self._tmp), mode="w", format="mp4")
        if preset not in X264_PRESETS:
            raise ValueError(f"{self.path}: unknown x264 preset {preset!r}; choose one of {', '.join(X264_PRESETS)}")
        if not CRF_RANGE[0] <= int(crf) <= CRF_RANGE[1]:
            raise ValueError(f"{self.path}: x264 quality (crf) must be {CRF_RANGE[0]}-{CRF_RANGE[1]}, got {crf}")
        self._rate = Fraction(fps).limit_denominator(1001)
        self._stream = self._container.add_stream("libx264", rate=self._rate)
        self._stream.pix_fmt = "yuv420p"
        # threads: x264's own worker threads, 0 = its default (about 1.5 per core); `rgbt track` asks for one
        self._stream.options = {"crf": str(crf), "preset": preset, "threads": str(int(threads))}
        self._size: tuple[int, int] | None = None
        self.frames_written = 0

    def write(self, frame: np.ndarray | Callable[[], np.ndarray]) -> None:
        """Append one RGB uint8 frame, or a function that draws it (called here: on the writer thread of a
        :class:`ThreadedVideoWriter`); every frame must have the first frame's size."""
        if callable(frame):
            frame = frame()
        h, w = frame.shape[:2]
        if self._size is None:
            # yuv420p needs even dimensions; pad by one pixel rather than refuse odd sizes
            self._size = (w + w % 2, h + h % 2)
            self._stream.width, self._stream.height = self._size
        elif (w + w % 2, h + h % 2) != self._size:
            raise ValueError(f"{self.path}: frame size {w}x{h} differs from the first frame's {self._size}")
        if frame.ndim == 2:
            frame = np.repeat(frame[:, :, None], 3, axis=2)
        if (w, h) != self._size:
            frame = np.pad(frame, ((0, self._size[1] - h), (0, self._size[0] - w), (0, 0)), mode="edge")
        # OpenCV's RGB -> I420 gives swscale's BT.601 limited-range planes (mean difference 0.04 levels) 7x faster
        planes = cv2.cvtColor(np.ascontiguousarray(frame, dtype=np.uint8), cv2.COLOR_RGB2YUV_I420)
        video_frame = av.VideoFrame.from_ndarray(planes, format="yuv420p")
        for packet in self._stream.encode(video_frame):
            self._container.mux(packet)
        self.frames_written += 1

    def close(self) -> None:
        """Flush the encoder and move the file to its final name."""
        if self._container is None:
            return
        for packet in self._stream.encode():
            self._container.mux(packet)
        self._container.close()
        self._container = None
        os.replace(self._tmp, self.path)

    def abort(self) -> None:
        """Drop the output: nothing appears under the final name (also after an encoder or disk error)."""
        if self._container is not None:
            container, self._container = self._container, None
            try:
                container.close()
            except Exception:  # the file is being dropped; the error that led here is the one the caller reports
                pass
        self._tmp.unlink(missing_ok=True)

    def __enter__(self) -> "VideoWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None or (exc_type is KeyboardInterrupt and self.keep_partial and self.frames_written):
            self.close()
        else:
            self.abort()


_STOP = object()  # the writer thread's end-of-stream marker


class ThreadedVideoWriter:
    """:class:`VideoWriter`'s interface (``write``, ``close``, ``abort``, ``frames_written``, ``path``) with the
    colour conversion and H.264 encoding done on a writer thread.

    Why: encoding a frame costs as much as a fast tracker step, and PyAV runs it without the GIL, so on a second core
    it costs the caller only the hand-over. The queue is bounded (``queue_size`` frames) so memory stays constant and
    a slow encoder holds the caller back instead of piling up frames. The caller must not modify a frame after
    handing it over. A failure on the writer thread is raised in the caller's thread, as :class:`VideoWriteError`,
    by the next ``write`` or by ``close`` (which then drops the file); the thread never outlives ``close``/``abort``.
    The thread runs ``nice`` steps nicer than the caller (Linux; 0: as the caller): the caller's work comes first and
    the encoder takes the time left over (``runtime.BACKGROUND_NICE``).
    """

    def __init__(self, path: str | os.PathLike, fps: float, *, queue_size: int = 8, nice: int = BACKGROUND_NICE,
                 **options):
        if queue_size < 1:
            raise ValueError(f"queue_size must be at least 1, got {queue_size}")
        self._writer = VideoWriter(path, fps, **options)  # opened here: a bad path fails in the caller's thread
        self.path = self._writer.path
        self.frames_written = 0  # frames accepted by write(); all of them are in the file after a clean close()
        self.encode_seconds = 0.0  # the writer thread's busy time (the caller's saving, when a core is free)
        self._queue: queue.Queue = queue.Queue(maxsize=queue_size)
        self._error: BaseException | None = None
        self._cancel = threading.Event()
        self._finished = False
        self._thread = threading.Thread(target=self._encode, args=(nice,), name=f"rgbt-video-writer:{self.path.name}",
                                        daemon=True)
        self._thread.start()

    def _encode(self, nice: int) -> None:
        lower_thread_priority(nice)  # the caller's work first (runtime.BACKGROUND_NICE)
        try:
            while True:
                frame = self._queue.get()
                if frame is _STOP or self._cancel.is_set():
                    return
                started = time.perf_counter()
                self._writer.write(frame)
                self.encode_seconds += time.perf_counter() - started
        except BaseException as exc:  # reported to the caller; the thread ends here
            self._error = exc

    def _check(self) -> None:
        if self._error is not None:
            _raise_as_write_error(self.path, self._error)

    def _put(self, item) -> None:
        """Queue ``item``; the wait is bounded by the writer thread staying alive (no hang on a dead writer)."""
        while True:
            self._check()
            if not self._thread.is_alive():
                raise VideoWriteError(f"{self.path}: the video writer has stopped")
            try:
                self._queue.put(item, timeout=0.1)
                return
            except queue.Full:
                continue

    def _join(self) -> None:
        while self._thread.is_alive():  # join in short steps so Ctrl-C is seen at once
            self._thread.join(0.1)

    def write(self, frame: np.ndarray | Callable[[], np.ndarray]) -> None:
        """Hand one RGB uint8 frame, or a function that draws it, to the writer thread (waits while ``queue_size``
        frames are pending)."""
        if self._finished:
            raise ValueError(f"{self.path}: the writer is closed")
        self._put(frame)
        self.frames_written += 1

    def close(self) -> None:
        """Encode the pending frames, flush and move the file to its final name. On a writer failure, or a Ctrl-C
        while waiting for the encoder, the file is dropped instead and the error raised."""
        if self._finished:
            return
        self._finished = True
        try:
            self._put(_STOP)
            self._join()
            self._check()
            self._writer.close()
        except BaseException as exc:
            self.abort()
            if isinstance(exc, Exception):
                _raise_as_write_error(self.path, exc)
            raise

    def abort(self) -> None:
        """Drop the pending frames and the output: nothing appears under the final name."""
        self._finished = True
        try:
            self._stop()
        finally:
            if not self._thread.is_alive():  # (only a second Ctrl-C during the join leaves the hidden temporary)
                self._writer.abort()

    def _stop(self) -> None:
        """End the writer thread without encoding what is queued."""
        self._cancel.set()
        while True:  # make room for the end marker: the thread may be waiting on an empty queue
            try:
                self._queue.get_nowait()
            except queue.Empty:
                break
        try:
            self._queue.put_nowait(_STOP)
        except queue.Full:  # the thread is encoding; it sees the cancel flag before its next frame
            pass
        self._join()

    def __enter__(self) -> "ThreadedVideoWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None or (exc_type is KeyboardInterrupt and self._writer.keep_partial and self.frames_written):
            self.close()
        else:
            self.abort()


def write_video(path: str | os.PathLike, frames, fps: float) -> None:
    """Write an iterable of RGB frames as an H.264 MP4."""
    with VideoWriter(path, fps) as writer:
        for frame in frames:
            writer.write(frame)
