"""Recordings read by time: only the frames a registration estimate pairs are decoded.

A registration estimate uses a few frame pairs (4 by default). Reading a whole recording to pick them costs more
than the estimate itself, so both sources here know their frames' times without decoding and decode only the frames
asked for:

- :class:`SeekableVideo`: times from the video's packets, each wanted frame decoded from the keyframe before it.
- :class:`SampledFolder`: a frame folder, file ``i`` at ``i / fps`` (as :class:`~rgbt_toolkit.io.frames.FrameSource`
  stamps it). The streaming path decodes every file to learn its time, and the RGB ones to exact BT.601 grey: on a
  101-frame 1920x1080 JPEG pair inside `rgbt track` that was 6.1 s of the estimate's 7.0 s (pyinstrument, loaded
  2-core machine). The estimate works on copies whose longer side is at most
  ``SpatialSettings.analysis_size``, so a JPEG is decoded straight to grey at the largest power-of-two reduction
  (libjpeg's DCT scaling) that keeps it at least that large.

Both tell what fetching a frame costs (:meth:`SeekableVideo.decode_cost`), so a caller can prefer cheap frames.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Callable, Iterable

import cv2
import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError
from rgbt_toolkit.io.images import list_images, read_image

JPEG_SUFFIXES = (".jpg", ".jpeg")
# OpenCV's grey JPEG decodes at 1/1, 1/2, 1/4, 1/8 of the size; EXIF orientation ignored, as read_image ignores it
_REDUCED_GREY = {1: cv2.IMREAD_GRAYSCALE, 2: cv2.IMREAD_REDUCED_GRAYSCALE_2, 4: cv2.IMREAD_REDUCED_GRAYSCALE_4,
                 8: cv2.IMREAD_REDUCED_GRAYSCALE_8}


def nearest_index(sorted_times: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Index of the frame nearest each of ``times`` among ``sorted_times`` (the earlier one on a tie)."""
    if len(sorted_times) == 1:
        return np.zeros(len(times), int)
    after = np.clip(np.searchsorted(sorted_times, times), 1, len(sorted_times) - 1)
    earlier = np.abs(sorted_times[after - 1] - times) <= np.abs(sorted_times[after] - times)
    return np.where(earlier, after - 1, after)


def reduction_for(size: tuple[int, int], longer: int) -> int:
    """The largest JPEG reduction (1, 2, 4 or 8) that keeps the longer side of a ``size`` (w, h) frame at least
    ``longer`` pixels: the estimate's analysis copy is then resampled from the reduced frame, never enlarged."""
    factor = 1
    while factor < 8 and max(size) / (2 * factor) >= longer:
        factor *= 2
    return factor


def image_size(path: str | os.PathLike) -> tuple[int, int]:
    """(width, height) of an image file from its header, without decoding its pixels."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            return image.size
    except (OSError, UnidentifiedImageError) as exc:
        raise FileFormatError(f"{path}: cannot read image header ({exc.__class__.__name__})") from None


class SampledFolder:
    """A frame folder whose frames are fetched by time (``times`` from the file list, no decoding).

    ``longer`` is the longest side the estimate analyses (``SpatialSettings.analysis_size``): JPEG frames are decoded
    reduced towards it. :attr:`size` is the full (width, height) of the frames, which the estimate's matrix refers
    to; a chosen file of another size is an :class:`InputError` naming it. ``on_frame`` is called per decoded file.
    """

    def __init__(self, path: str | os.PathLike, fps: float, longer: int,
                 on_frame: Callable[[], None] | None = None):
        self.path, self._on_frame = Path(path), on_frame
        self.files = list_images(self.path)
        if not self.files:
            raise InputError(f"{self.path}: folder holds no images")
        self.times = np.arange(len(self.files)) / float(fps)
        self.size = image_size(self.files[0])
        self.reduction = reduction_for(self.size, longer)

    def decode_cost(self, times: np.ndarray) -> np.ndarray:
        """Frames decoded to fetch the frame at each time: every file stands alone."""
        return np.ones(len(times), int)

    def frames_at(self, times: np.ndarray) -> dict[float, np.ndarray]:
        """{t: grey frame} for times taken from :attr:`times`; an unreadable file is left out with a warning (as
        the streaming path skips it)."""
        found = {}
        for index in nearest_index(self.times, np.asarray(times, float)):
            frame = self._read(self.files[index])
            if self._on_frame is not None:
                self._on_frame()
            if frame is not None:
                found[float(self.times[index])] = frame
        return found

    def _read(self, file: Path) -> np.ndarray | None:
        """One file as grey, JPEG reduced by :attr:`reduction`; None (warned) when it does not decode."""
        from rgbt_toolkit.io.video import CorruptFrameWarning

        try:
            size = image_size(file)
            if size != self.size:
                raise InputError(f"{file}: {size[0]}x{size[1]}, the other frames are {self.size[0]}x{self.size[1]}")
            if file.suffix.lower() in JPEG_SUFFIXES:
                frame = cv2.imread(str(file), _REDUCED_GREY[self.reduction] | cv2.IMREAD_IGNORE_ORIENTATION)
                if frame is None:
                    raise FileFormatError(f"{file}: cannot decode image")
                return frame
            return read_image(file, grey=True)  # PNG / TIFF (16-bit thermal kept) / BMP: no reduced decode
        except FileFormatError as exc:
            warnings.warn(f"{exc}; frame skipped", CorruptFrameWarning, stacklevel=3)
            return None


class SeekableVideo:
    """A video whose frames are fetched by time: timestamps from its packets (no decoding), then only the wanted
    frames decoded, each from the keyframe before it.

    The streaming path decodes every RGB frame to keep one per time chunk, and the thermal video up to the last
    partner: on a 4-s 1080p + 640x512 pair that was 40 % of the estimate inside `rgbt track`, and it grows with the
    length of the recording, while this grows with the keyframe interval. Also a frame stream of all its frames
    (``stream``, a :data:`~rgbt_toolkit.registration.pipeline.FrameStream`).
    """

    def __init__(self, path, stream: Callable[[], Iterable[tuple[np.ndarray, float]]],
                 on_frame: Callable[[], None] | None = None):
        self.path, self._stream, self._on_frame = str(path), stream, on_frame
        self._pts, self._keys, self._base = _packet_times(self.path)
        self.times = self._pts * float(self._base)

    def __call__(self):
        return self._stream()

    def decode_cost(self, times: np.ndarray) -> np.ndarray:
        """Frames decoded to fetch the frame nearest each time: those from the keyframe before it, in display order
        (an upper bound: frames no other frame refers to are skipped)."""
        index = nearest_index(self.times, times)
        keys = np.searchsorted(self._pts, self._keys)  # keyframes' positions among the frames
        before = np.searchsorted(keys, index, side="right") - 1
        return index - np.where(before >= 0, keys[np.maximum(before, 0)], 0) + 1

    def frames_at(self, times: np.ndarray) -> dict[float, np.ndarray]:
        """{t: grey frame} for frame times ``t`` taken from :attr:`times`; a frame that does not decode is left out
        with a warning (as the streaming path skips an undecodable packet)."""
        indices = {int(self._pts[i]): i for i in (int(np.argmin(np.abs(self.times - t))) for t in times)}
        found: dict[int, np.ndarray] = {}
        failed = self._decode(sorted(indices), found, seek=True)
        missing = sorted(set(indices) - set(found))
        if missing and not failed:  # a container whose seek landed past a wanted frame: read those from the start
            self._decode(missing, found, seek=False)
        return {float(self.times[indices[pts]]): frame for pts, frame in found.items()}

    def _decode(self, wanted: list[int], found: dict[int, np.ndarray], *, seek: bool) -> bool:
        """Decode the frames of presentation times ``wanted`` (sorted, stream units) into ``found``, seeking to the
        keyframe before each (``seek``) or reading from the start; True when a packet failed to decode."""
        import warnings

        import av

        from rgbt_toolkit.io.video import CorruptFrameWarning, frame_array

        failed = False
        with av.open(self.path) as container:
            video = container.streams.video[0]
            context = video.codec_context
            packets, position, wanted_set = None, None, set(wanted)
            for target in wanted:
                if target in found:  # came out while an earlier one was awaited (frames are reordered)
                    continue
                before = self._keys[self._keys <= target]
                key = int(before[-1]) if len(before) else int(self._pts[0])
                if packets is None or (seek and (position is None or key > position or target <= position)):
                    if seek:
                        container.seek(key, stream=video, backward=True, any_frame=False)  # flushes the decoder
                    packets = container.demux(video)
                try:
                    for packet in packets:
                        # a frame no other frame refers to is decoded only when it is wanted (about half the frames
                        # of an H.264 stream with B-frames; the wanted ones come out bit-identical, tested)
                        skip = packet.pts is not None and packet.pts not in wanted_set
                        context.skip_frame = "NONREF" if skip else "DEFAULT"
                        reached = False
                        for frame in packet.decode():
                            if self._on_frame is not None:
                                self._on_frame()
                            position = frame.pts
                            if frame.pts in wanted_set and frame.pts not in found:
                                found[frame.pts] = frame_array(frame, grey=True)
                            reached = reached or (frame.pts is not None and frame.pts >= target)
                        if reached:
                            break
                except av.error.FFmpegError as exc:
                    failed = True
                    when = float(target * self._base)
                    warnings.warn(f"{self.path}: skipped an undecodable packet before t = {when:.3f} s "
                                  f"({exc.__class__.__name__})", CorruptFrameWarning, stacklevel=3)
                    packets = None  # the next target starts afresh
        return failed


def video_timestamps(path) -> np.ndarray | None:
    """Presentation times of a video's frames from its packets, without decoding (None if the file has none).

    Decoding only to learn timestamps was a third of the time of registering a 10-s video pair.
    """
    import av

    try:
        pts, _, base = _packet_times(path)
    except (av.error.FFmpegError, IndexError):
        return None
    return pts * float(base) if len(pts) else None


def _packet_times(path):
    """``(pts, keyframe pts, time base)`` of a video's first video stream, read from its packets (no decoding);
    both arrays sorted, in stream units."""
    import av

    with av.open(str(path)) as container:
        video = container.streams.video[0]
        packets = [(p.pts, p.is_keyframe) for p in container.demux(video) if p.pts is not None and p.size]
        base = video.time_base
    pts = np.sort(np.asarray([t for t, _ in packets], np.int64))
    return pts, np.sort(np.asarray([t for t, key in packets if key], np.int64)), base
