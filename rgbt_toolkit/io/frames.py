"""One entry point for "frames from somewhere": a video file, a folder of images, or a single image.

Callers (registration, trackers, the CLI) iterate ``(frame, t_seconds)`` pairs and do not care which it was.
"""

from __future__ import annotations

import itertools
import os
import warnings
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.io.images import (IMAGE_SUFFIXES, decode_reduction, is_grey_picture, list_images, read_frame,
                                    read_image, shrink_to)
from rgbt_toolkit.io.pixels import FixedRange
from rgbt_toolkit.io.video import VIDEO_SUFFIXES, CorruptFrameWarning, VideoReader

DEFAULT_FOLDER_FPS = 30.0  # image folders carry no timing; benchmarks record at about this rate


@dataclass
class FrameSource:
    """A sized, re-iterable stream of RGB (or grey) frames with timestamps.

    Colour mode yields uint8 frames (a 16-bit or float stream mapped by :class:`~rgbt_toolkit.io.pixels.FixedRange`);
    ``grey`` mode yields frames as decoded (uint16 kept: registration stretches them itself). ``auto_grey`` (colour
    mode) yields H x W frames when the first frame is a grey picture stored as colour, as thermal cameras' files
    usually are: a third of the pixels to convert, warp and filter downstream, and the same picture.
    """

    path: Path
    kind: str  # "video", "folder" or "image"
    fps: float
    frame_count: int
    size: tuple[int, int]  # (width, height)
    _files: list[Path] | None = None
    _video: VideoReader | None = None
    grey: bool = False  # yield H x W grey frames (cheaper to decode; all that registration needs)
    keep_gaps: bool = False  # yield (None, t) for an unreadable frame instead of leaving it out (see __iter__)
    fixed_size: bool = False  # InputError naming the file for a folder frame whose size differs from the first's
    auto_grey: bool = False  # colour mode: H x W frames when the first frame's three channels are equal
    # folder frames from now on shrunk to this (w, h), no larger than ``size`` (:meth:`deliver_at`); None: as decoded
    target_size: tuple[int, int] | None = None

    def deliver_at(self, size: tuple[int, int] | None) -> None:
        """Yield the folder frames not yet read at ``size`` (w, h; None: as decoded), shrunk as they are decoded.

        Why: a tracker that works on shrunk frames need not have whole frames decoded. JPEGs are decoded at 1/2, 1/4
        or 1/8 of their size by libjpeg where that stays at least ``size``
        (:func:`~rgbt_toolkit.io.images.decode_reduction`): a 1920x1080 frame at 1/2 in half the time. The rest of
        the way is :func:`~rgbt_toolkit.io.images.shrink_to`; pixel centres map as ``(p + 0.5) * f - 0.5``. Videos
        and single images are yielded as decoded (their callers shrink them): H.264 has no cheaper reduced decode.
        """
        if size is not None:
            size = (int(size[0]), int(size[1]))
            if not (0 < size[0] <= self.size[0] and 0 < size[1] <= self.size[1]):
                raise ValueError(f"{self.path}: frames of {self.size[0]}x{self.size[1]} cannot be delivered at "
                                 f"{size[0]}x{size[1]}")
            if size == tuple(self.size):
                size = None
        self.target_size = size

    def __iter__(self) -> Iterator[tuple[np.ndarray | None, float]]:
        """``(frame, t)`` pairs. An unreadable frame (a corrupt file, an undecodable video packet) is left out with a
        :class:`CorruptFrameWarning`; with ``keep_gaps`` its place is kept as ``(None, t)`` instead, so a tracker can
        write a placeholder row and row N of its box file stays frame N."""
        # trackers take 8-bit frames: a 16-bit or float (radiometric) stream is mapped with one range for all frames
        to_8bit = None if self.grey else FixedRange(str(self.path))
        for frame, t, name in self._decoded():
            yield (to_8bit(frame, name) if to_8bit is not None and frame is not None else frame), t

    def _decoded(self) -> Iterator[tuple[np.ndarray | None, float, str]]:
        """``(frame, t, name)``: frames as decoded, with the file (or video) to name in errors."""
        if self._video is not None:
            yield from self._video_frames()
            return
        grey: bool | None = self.grey or (None if self.auto_grey else False)  # None: decided by the first frame
        flat = self.grey  # the frames come 2-D (a grey source, or grey JPEGs): reduced decoding keeps them so

        def read(file: Path) -> tuple[np.ndarray | FileFormatError, int]:
            reduce = decode_reduction(self.size, self.target_size) if self.target_size is not None else 1
            try:
                return read_frame(file, grey=self.grey, luma=(bool(grey) or flat) and not self.grey,
                                  reduce=reduce), reduce
            except FileFormatError as exc:
                return exc, reduce

        for index, (file, (image, reduce)) in enumerate(_read_ahead(self._files or [], read)):
            if isinstance(image, FileFormatError):
                warnings.warn(f"{image}; frame skipped", CorruptFrameWarning, stacklevel=2)
                if self.keep_gaps:
                    yield None, index / self.fps, str(file)
                continue
            expected = (self.size[0] // reduce, self.size[1] // reduce)
            if self.fixed_size and image.shape[1::-1] != expected:  # trackers follow one geometry through a stream
                shape = f"{image.shape[1]}x{image.shape[0]}" + (f" at 1/{reduce} size" if reduce > 1 else "")
                raise InputError(f"{file}: {shape}, the other frames are {self.size[0]}x{self.size[1]}")
            flat = flat or (index == 0 and image.ndim == 2)
            if grey is None:
                grey = image.ndim == 2 or is_grey_picture(image)
            if grey and image.ndim == 3:  # frames read before the first one said it was a grey picture
                image = image[..., 0].copy()
            if self.target_size is not None:
                image = shrink_to(image, self.target_size)
            yield image, index / self.fps, str(file)

    def _video_frames(self) -> Iterator[tuple[np.ndarray | None, float, str]]:
        """Decoded video frames; with ``keep_gaps`` frames lost to undecodable packets (which the reader counts and
        warns about) are filled with ``None`` frames at the nominal rate, at the next jump in the timestamps.

        Only lost packets open a gap: a variable-frame-rate video's long intervals are not missing frames.
        """
        previous, filled = None, 0
        for frame, t in self._video.frames(grey=self.grey or ("auto" if self.auto_grey else False)):
            lost = self._video.skipped_packets - filled
            if self.keep_gaps and lost > 0 and previous is not None and self.fps > 0 and t - previous > 1.5 / self.fps:
                missing = min(lost, int(round((t - previous) * self.fps)) - 1)
                for k in range(1, missing + 1):
                    yield None, previous + k / self.fps, str(self.path)
                filled += missing
            previous = t
            yield frame, t, str(self.path)

    def __len__(self) -> int:
        return self.frame_count

    def holds(self, path: str | os.PathLike) -> bool:
        """Whether ``path`` is this source's video or one of its frame files (so writing there would destroy input)."""
        path = Path(path)
        if not path.exists():
            return False
        return any(os.path.samefile(path, own) for own in ([self.path] if self._video is not None else self.files))

    @property
    def files(self) -> list[Path]:
        """Frame files of a folder or image source (empty for videos)."""
        return list(self._files or [])


def _read_ahead(files: list[Path], read, ahead: int = 3) -> Iterator[tuple[Path, object]]:
    """``(file, read(file))`` in order, the first file read here and the next ``ahead`` on two worker threads
    meanwhile.

    Why: decoding a frame file (OpenCV and Pillow release the GIL) is most of a folder's cost, and a reader that
    decodes one file at a time leaves a core idle whenever the consumer waits for it (a 1080p JPEG pair is about
    13 ms at half size). ``read`` is called for each file when it is handed to a worker, so settings changed by the
    consumer (:meth:`FrameSource.deliver_at`) apply to the files not yet handed out. The workers are shut down when
    the iteration ends, however it ends."""
    if not files:
        return
    yield files[0], read(files[0])  # the first frame decides what the rest are read as (grey, size)
    if len(files) == 1:
        return
    pool = ThreadPoolExecutor(max_workers=2, thread_name_prefix="rgbt-frame-read")
    try:
        pending: deque = deque()
        upcoming = iter(files[1:])
        for file in itertools.islice(upcoming, ahead):
            pending.append((file, pool.submit(read, file)))
        while pending:
            file, future = pending.popleft()
            result = future.result()
            following = next(upcoming, None)
            if following is not None:
                pending.append((following, pool.submit(read, following)))
            yield file, result
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def open_frames(path: str | os.PathLike, *, fps: float | None = None, grey: bool = False,
                keep_gaps: bool = False, fixed_size: bool = False, auto_grey: bool = False) -> FrameSource:
    """Open a video, an image folder or a single image as a :class:`FrameSource`.

    ``fps`` sets the frame rate of folders and single images (default 30); it is ignored for videos, whose own
    timestamps are used. ``grey`` makes the source yield H x W grey frames; ``keep_gaps`` makes it yield
    ``(None, t)`` where a frame cannot be decoded (see :meth:`FrameSource.__iter__`); ``fixed_size`` makes a folder
    frame of another size than the first an :class:`InputError` naming the file (``<file>: WxH, the other frames are
    WxH``) instead of passing it on; ``auto_grey`` makes a source whose first frame is a grey picture yield H x W
    frames (see :class:`FrameSource`).
    """
    path = Path(path)
    if not path.exists():
        raise MissingFileError(f"{path}: no such file or folder")
    if path.is_dir():
        files = list_images(path)
        if not files:
            raise InputError(f"{path}: folder holds no images ({', '.join(IMAGE_SUFFIXES)})")
        first = read_frame(files[0])  # only its size is kept (a JPEG decodes several times faster than by read_image)
        return FrameSource(path, "folder", fps or DEFAULT_FOLDER_FPS, len(files), (first.shape[1], first.shape[0]),
                           _files=files, grey=grey, keep_gaps=keep_gaps, fixed_size=fixed_size, auto_grey=auto_grey)
    suffix = path.suffix.lower()
    if suffix in IMAGE_SUFFIXES:
        image = read_image(path)
        return FrameSource(path, "image", fps or DEFAULT_FOLDER_FPS, 1, (image.shape[1], image.shape[0]),
                           _files=[path], grey=grey, keep_gaps=keep_gaps, fixed_size=fixed_size, auto_grey=auto_grey)
    if suffix in VIDEO_SUFFIXES or suffix == "":
        reader = VideoReader(path)
        return FrameSource(path, "video", reader.fps or DEFAULT_FOLDER_FPS, reader.frame_count, reader.size,
                           _video=reader, grey=grey, keep_gaps=keep_gaps, fixed_size=fixed_size, auto_grey=auto_grey)
    raise FileFormatError(f"{path}: unknown file type '{suffix}'; expected a video, an image or a folder of images")
