"""Live and streamed sources: anything FFmpeg opens through PyAV, read forward only by reader threads.

A camera (``/dev/video0``), a stream (``rtsp://``, ``udp://``, ``srt://`` ...), a named pipe, or a file that is still
being written cannot be probed for a frame count, seeked, or read twice. Each source is decoded by its own thread into
a small bounded queue; a pairing thread matches the two cameras' frames by presentation time and hands pairs to the
tracking loop through a mailbox that either blocks the readers (nothing dropped: back-pressure) or, in real-time mode,
keeps only the newest pair and counts the ones the tracker never saw.

Timestamps are each stream's pts in seconds since its own first frame: the two streams are assumed to start at the
same instant, up to the ``offset`` the caller gives (``rgbt track --offset``, or the calibration's).
"""

from __future__ import annotations

import os
import re
import stat
import threading
import time
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import av
import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.io.pairing import pair_by_time
from rgbt_toolkit.io.pixels import FixedRange
from rgbt_toolkit.io.video import frame_array

_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.\-]*://")
STALL_SECONDS = 5.0  # no new data for this long: a live source counts as ended (a growing file has stopped growing)
OPEN_SECONDS = 10.0  # connecting to a network stream
QUEUE_FRAMES = 4  # decoded frames buffered per source before its reader waits
# small probe: a live stream's first frames should reach the tracker, not sit in FFmpeg's stream analysis
_LOW_LATENCY = {"probesize": "500000", "analyzeduration": "500000"}


def is_live(source: str | os.PathLike) -> bool:
    """Whether ``source`` is read forward only: a URL (``scheme://``), a V4L2 device (``/dev/video*``) or a named pipe."""
    text = os.fspath(source)
    if _SCHEME.match(text) or text.startswith("/dev/video"):
        return True
    try:
        return stat.S_ISFIFO(os.stat(text).st_mode)
    except OSError:
        return False


@dataclass
class _Failure:
    """An exception raised in a reader thread, handed to the consumer to raise there."""

    error: BaseException


_END = object()


class Mailbox:
    """A bounded hand-over between threads: ``keep_latest`` replaces an untaken item (counting it in ``dropped``)
    instead of making the producer wait."""

    def __init__(self, size: int = 2, keep_latest: bool = False):
        self._items: deque = deque()
        self._size, self._keep_latest = size, keep_latest
        self._cond = threading.Condition()
        self._closed = False
        self.dropped = 0

    def put(self, item, stop: threading.Event) -> bool:
        """Hand over ``item``; False when ``stop`` was set while waiting for room."""
        with self._cond:
            if self._keep_latest:
                self.dropped += len(self._items)
                self._items.clear()
            while len(self._items) >= self._size and not stop.is_set():
                self._cond.wait(0.05)
            if stop.is_set():
                return False
            self._items.append(item)
            self._cond.notify_all()
            return True

    def close(self, last=None) -> None:
        """No more items after those queued (and ``last``, kept even in keep-latest mode: an error or the end)."""
        with self._cond:
            if last is not None:
                self._items.append(last)
            self._closed = True
            self._cond.notify_all()

    def get(self):
        """The next item; ``_END`` once closed and empty."""
        with self._cond:
            while not self._items and not self._closed:
                self._cond.wait(0.05)
            if not self._items:
                return _END
            item = self._items.popleft()
            self._cond.notify_all()
            return item


@dataclass
class LiveSource:
    """One forward-only video source; :meth:`frames` decodes it once, yielding ``(frame, pts seconds)``."""

    url: str
    follow: bool = False  # a regular file still being written: read on at its end until it stops growing
    stall_seconds: float = STALL_SECONDS  # see open_live
    skipped_packets: int = 0
    ended_mid_frame: bool = False  # the last packet could not be decoded: the stream was cut inside a frame
    fps: float = 0.0
    notes: list[str] = field(default_factory=list)

    def _open(self, stop: threading.Event) -> av.container.InputContainer:
        fmt = "v4l2" if self.url.startswith("/dev/video") else None
        if not _SCHEME.match(self.url) and not os.path.exists(self.url):
            raise MissingFileError(f"{self.url}: no such file, device or pipe")
        # a growing file is read through _Followed, which waits at its end: the demuxer then sees a clean end of
        # file (and hands over its last buffered frames) once the file stops growing, not a read error
        source = _Followed(self.url, self.stall_seconds, stop) if self.follow else self.url
        self._followed = source if self.follow else None
        try:
            container = av.open(source, format=fmt, options=dict(_LOW_LATENCY),
                                timeout=(OPEN_SECONDS, self.stall_seconds * (2 if self.follow else 1)))
        except av.error.FFmpegError as exc:
            self._close_followed()
            raise FileFormatError(f"{self.url}: cannot open as a live video source "
                                  f"({exc.strerror or exc.__class__.__name__})") from None
        if not container.streams.video:
            container.close()
            self._close_followed()
            raise FileFormatError(f"{self.url}: contains no video stream")
        rate = container.streams.video[0].average_rate or container.streams.video[0].guessed_rate
        self.fps = float(rate) if rate else 0.0
        return container

    def frames(self, stop: threading.Event) -> Iterator[tuple[np.ndarray, float]]:
        """Decoded frames (RGB uint8; a grey stream of more than 8 bits mapped to uint8 with one fixed range) until
        the stream ends, is cut, stalls or ``stop`` is set. An undecodable packet is skipped and counted; one that
        is the last of the stream means it was cut inside a frame (:attr:`ended_mid_frame`)."""
        container = self._open(stop)
        to_8bit = FixedRange(self.url)
        try:
            stream = container.streams.video[0]
            stream.thread_type = "SLICE"  # frame threading would hold back several frames: latency
            last_failed = False
            packets = container.demux(stream)
            while not stop.is_set():
                try:
                    packet = next(packets)
                except StopIteration:
                    break
                except av.error.FFmpegError as exc:  # a network error or a stall: the source has ended
                    self.notes.append(f"{self.url}: stream ended ({exc.strerror or exc.__class__.__name__})")
                    break
                try:
                    decoded = packet.decode()
                except av.error.FFmpegError:
                    self.skipped_packets += 1
                    last_failed = packet.size > 0
                    continue
                last_failed = last_failed and packet.size == 0  # the end-of-stream flush keeps the verdict
                for frame in decoded:
                    t = float(frame.pts * frame.time_base) if frame.pts is not None else time.monotonic()
                    yield to_8bit(frame_array(frame)), t
            self.ended_mid_frame = last_failed
            if last_failed:
                self.notes.append(f"{self.url}: the stream ended inside a frame; that incomplete frame was dropped")
            elif self.skipped_packets:
                self.notes.append(f"{self.url}: {self.skipped_packets} undecodable packet(s) skipped")
        finally:
            container.close()
            self._close_followed()

    def _close_followed(self) -> None:
        if getattr(self, "_followed", None) is not None:
            self._followed.close()
            self._followed = None


class _Followed:
    """A regular file read while it is still being written: at its end, wait for more until it has not grown for
    ``stall_seconds`` (or ``stop`` is set), then report the end of file. No ``seek``: FFmpeg reads it as a stream."""

    def __init__(self, path: str, stall_seconds: float, stop: threading.Event):
        self._file = open(path, "rb")  # noqa: SIM115 - closed by LiveSource.frames when the container closes
        self._stall, self._stop = stall_seconds, stop

    def read(self, size: int = -1) -> bytes:
        waited_since = None
        while True:
            data = self._file.read(size)
            if data or self._stop.is_set():
                return data
            waited_since = time.monotonic() if waited_since is None else waited_since
            if time.monotonic() - waited_since > self._stall:
                return b""
            time.sleep(0.01)

    def close(self) -> None:
        self._file.close()


class LivePairs:
    """Time-paired frames of two live sources, read by background threads.

    Iterating yields ``(rgb, thermal, t)`` with ``t`` in seconds since the RGB stream's first frame. With
    ``realtime`` the consumer always gets the newest pair and :attr:`dropped` counts the pairs it never saw; without
    it the readers wait for the consumer (nothing is dropped, and a live source's own buffer absorbs the delay).
    """

    def __init__(self, rgb: LiveSource, thermal: LiveSource, *, offset: float = 0.0, realtime: bool = False,
                 max_gap: float | None = None):
        self.sources = (rgb, thermal)
        self.offset, self.realtime, self.max_gap = offset, realtime, max_gap
        self._stop = threading.Event()
        self._queues = (Mailbox(QUEUE_FRAMES), Mailbox(QUEUE_FRAMES))
        self._pairs = Mailbox(2, keep_latest=realtime)
        self._threads = [threading.Thread(target=self._decode, args=(k,), daemon=True, name=f"rgbt-live-{k}")
                         for k in range(2)]
        self._threads.append(threading.Thread(target=self._pair, daemon=True, name="rgbt-live-pairs"))
        self.paired = 0  # pairs handed over (the consumer took them, or real-time mode dropped them)
        for thread in self._threads:
            thread.start()

    @property
    def dropped(self) -> int:
        """Frame pairs replaced by newer ones before the tracker took them (real-time mode)."""
        return self._pairs.dropped

    @property
    def notes(self) -> list[str]:
        """How the sources ended (cut inside a frame, stalled, undecodable packets), one line each."""
        return [note for source in self.sources for note in source.notes]

    def _decode(self, which: int) -> None:
        queue = self._queues[which]
        try:
            for item in self.sources[which].frames(self._stop):
                if not queue.put(item, self._stop):
                    break
        except Exception as exc:  # any failure, re-raised in the consumer's thread
            queue.close(_Failure(exc))
            return
        queue.close()

    def _timed(self, which: int) -> Iterator[tuple[np.ndarray, float]]:
        """One source's frames with times in seconds since its first frame, until it ends."""
        first = None
        while True:
            item = self._queues[which].get()
            if item is _END:
                return
            if isinstance(item, _Failure):
                raise item.error
            frame, t = item
            first = t if first is None else first
            yield frame, t - first

    def _pair(self) -> None:
        try:
            fps_t = self.sources[1].fps or 30.0
            gap = self.max_gap if self.max_gap is not None else 0.5 / fps_t + 1e-3  # nearest within half a frame
            for rgb, thermal, t_rgb, _ in pair_by_time(self._timed(0), self._timed(1), offset=self.offset,
                                                       max_gap=gap):
                if not self._pairs.put((rgb, thermal, t_rgb), self._stop):
                    break
                self.paired += 1
        except Exception as exc:  # any failure, re-raised in the consumer's thread
            self._stop.set()
            self._pairs.close(_Failure(exc))
            return
        self._stop.set()  # one source ended: the other reader stops too
        self._pairs.close()

    def __iter__(self) -> Iterator[tuple[np.ndarray, np.ndarray, float]]:
        while True:
            item = self._pairs.get()
            if item is _END:
                return
            if isinstance(item, _Failure):
                raise item.error
            yield item

    def __enter__(self) -> "LivePairs":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self, wait: float = 2.0) -> None:
        """Stop the readers (a reader blocked on a silent source ends with it: the threads are daemons)."""
        self._stop.set()
        deadline = time.monotonic() + wait
        for thread in self._threads:
            thread.join(max(0.0, deadline - time.monotonic()))


def open_live(source: str | os.PathLike, *, follow: bool = False, stall_seconds: float | None = None) -> LiveSource:
    """A :class:`LiveSource` for ``source`` (checked, not opened: opening a pipe waits for its writer).

    ``follow``: a regular file still being written, read on at its end until it has not grown for ``stall_seconds``
    (default :data:`STALL_SECONDS`, which also ends a network stream that stops sending).
    """
    text = os.fspath(source)
    if not text:
        raise InputError("an empty source name")
    if follow and not Path(text).is_file():
        raise MissingFileError(f"{text}: no such file to follow")
    return LiveSource(text, follow=follow, stall_seconds=STALL_SECONDS if stall_seconds is None else stall_seconds)
