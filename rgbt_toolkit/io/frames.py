"""One entry point for "frames from somewhere": a video file, a folder of images, or a single image.

Callers (registration, trackers, the CLI) iterate ``(frame, t_seconds)`` pairs and do not care which it was.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.io.images import IMAGE_SUFFIXES, is_grey_picture, list_images, read_frame, read_image
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
        for index, file in enumerate(self._files or []):
            try:
                image = read_frame(file, grey=self.grey, luma=bool(grey) and not self.grey)
            except FileFormatError as exc:
                warnings.warn(f"{exc}; frame skipped", CorruptFrameWarning, stacklevel=2)
                if self.keep_gaps:
                    yield None, index / self.fps, str(file)
                continue
            if self.fixed_size and image.shape[1::-1] != self.size:  # trackers follow one geometry through a stream
                raise InputError(f"{file}: {image.shape[1]}x{image.shape[0]}, the other frames are "
                                 f"{self.size[0]}x{self.size[1]}")
            if grey is None:
                grey = image.ndim == 2 or is_grey_picture(image)
                image = image[..., 0].copy() if image.ndim == 3 and grey else image
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
        first = read_image(files[0])
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
