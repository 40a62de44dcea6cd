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
from rgbt_toolkit.io.images import IMAGE_SUFFIXES, list_images, read_image
from rgbt_toolkit.io.pixels import FixedRange
from rgbt_toolkit.io.video import VIDEO_SUFFIXES, CorruptFrameWarning, VideoReader

DEFAULT_FOLDER_FPS = 30.0  # image folders carry no timing; benchmarks record at about this rate


@dataclass
class FrameSource:
    """A sized, re-iterable stream of RGB (or grey) frames with timestamps.

    Colour mode yields uint8 frames (a 16-bit or float stream mapped by :class:`~rgbt_toolkit.io.pixels.FixedRange`);
    ``grey`` mode yields frames as decoded (uint16 kept: registration stretches them itself).
    """

    path: Path
    kind: str  # "video", "folder" or "image"
    fps: float
    frame_count: int
    size: tuple[int, int]  # (width, height)
    _files: list[Path] | None = None
    _video: VideoReader | None = None
    grey: bool = False  # yield H x W grey frames (cheaper to decode; all that registration needs)

    def __iter__(self) -> Iterator[tuple[np.ndarray, float]]:
        # trackers take 8-bit frames: a 16-bit or float (radiometric) stream is mapped with one range for all frames
        to_8bit = None if self.grey else FixedRange(str(self.path))
        for frame, t, name in self._decoded():
            yield (to_8bit(frame, name) if to_8bit is not None else frame), t

    def _decoded(self) -> Iterator[tuple[np.ndarray, float, str]]:
        """``(frame, t, name)``: frames as decoded, with the file (or video) to name in errors."""
        if self._video is not None:
            for frame, t in self._video.frames(grey=self.grey):
                yield frame, t, str(self.path)
            return
        for index, file in enumerate(self._files or []):
            try:
                image = read_image(file, grey=self.grey)
            except FileFormatError as exc:
                warnings.warn(f"{exc}; frame skipped", CorruptFrameWarning, stacklevel=2)
                continue
            yield image, index / self.fps, str(file)

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


def open_frames(path: str | os.PathLike, *, fps: float | None = None, grey: bool = False) -> FrameSource:
    """Open a video, an image folder or a single image as a :class:`FrameSource`.

    ``fps`` sets the frame rate of folders and single images (default 30); it is ignored for videos, whose own
    timestamps are used. ``grey`` makes the source yield H x W grey frames.
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
                           _files=files, grey=grey)
    suffix = path.suffix.lower()
    if suffix in IMAGE_SUFFIXES:
        image = read_image(path)
        return FrameSource(path, "image", fps or DEFAULT_FOLDER_FPS, 1, (image.shape[1], image.shape[0]),
                           _files=[path], grey=grey)
    if suffix in VIDEO_SUFFIXES or suffix == "":
        reader = VideoReader(path)
        return FrameSource(path, "video", reader.fps or DEFAULT_FOLDER_FPS, reader.frame_count, reader.size,
                           _video=reader, grey=grey)
    raise FileFormatError(f"{path}: unknown file type '{suffix}'; expected a video, an image or a folder of images")
