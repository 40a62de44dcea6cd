"""What ``rgbt track`` was given, resolved into paired frames in one geometry and a starting box.

Inputs are two videos / frame folders / images, or one benchmark sequence folder. Frames are paired by time
(different rates and clock offsets), the thermal frame is warped into the RGB camera's geometry with the rig's
RGB->T homography, and the target comes from ``--init``, the sequence's ``init.txt``, a ``<video stem>.init.txt``
file, or automatic selection of the most salient warm object, in that order.
"""

from __future__ import annotations

import itertools
import os
import queue
import threading
import time
import warnings
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path

import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError, RegistrationError, RgbtError
from rgbt_toolkit.io.frames import open_frames
from rgbt_toolkit.io.images import read_image
from rgbt_toolkit.io.live import is_live
from rgbt_toolkit.io.pixels import FixedRange
from rgbt_toolkit.io.pairing import pair_by_time
from rgbt_toolkit.io.video import CorruptFrameWarning
from rgbt_toolkit.io.sequences import detect_layout, read_sequence
from rgbt_toolkit.jmmac.autoinit import salient_warm_object
from rgbt_toolkit.jmmac.track_inputs import (  # TrackInputs, Paired, map_box, REMEDIES re-exported for callers
    REMEDIES, Paired, TrackInputs, check_input_box, first_init_box, map_box, unregistered_message)
from rgbt_toolkit.runtime import BACKGROUND_NICE, lower_thread_priority

__all__ = ["REMEDIES", "Paired", "ReadAhead", "TrackInputs", "map_box", "resolve_inputs", "unregistered_message"]


class ReadAhead:
    """Iterate ``items``, each mapped through ``prepare``, produced on a reader thread up to ``depth`` items ahead.

    Why: decoding (PyAV), the shrink to the working scale and the thermal warp (OpenCV) run without the GIL, so on a
    second core they overlap the tracker instead of adding to its time per frame. Items come out in order; an
    exception raised while reading or preparing (a Ctrl-C delivered as ``KeyboardInterrupt`` by a source included) is
    raised by ``__next__`` in the consumer's thread at the place it happened. At most ``limit`` items are read.
    :meth:`close` stops the thread, closes the source generator on it (its video files with it) and waits for it;
    use the object as a context manager so no thread outlives the loop. The thread runs ``nice`` steps nicer than
    the caller (Linux; 0: as the caller), so a busy consumer gets the cores first (``runtime.BACKGROUND_NICE``).
    """

    _END = object()

    def __init__(self, items: Iterable, prepare: Callable | None = None, *, depth: int = 4, limit: int | None = None,
                 nice: int = BACKGROUND_NICE):
        if depth < 1:
            raise ValueError(f"depth must be at least 1, got {depth}")
        self.busy_seconds = 0.0  # the reader thread's time reading and preparing
        self._queue: queue.Queue = queue.Queue(maxsize=depth)
        self._stop = threading.Event()
        self._done = False
        self._thread = threading.Thread(target=self._read, args=(items, prepare, limit, nice), name="rgbt-read-ahead",
                                        daemon=True)
        self._thread.start()

    def _read(self, items: Iterable, prepare: Callable | None, limit: int | None, nice: int) -> None:
        lower_thread_priority(nice)  # the tracker first (runtime.BACKGROUND_NICE)
        source = iter(items)
        try:
            count = 0
            while not self._stop.is_set() and (limit is None or count < limit):
                started = time.perf_counter()
                try:
                    item = next(source)
                except StopIteration:
                    break
                if prepare is not None:
                    item = prepare(item)
                self.busy_seconds += time.perf_counter() - started
                if not self._put((True, item)):
                    return
                count += 1
            self._put((True, self._END))
        except BaseException as exc:  # handed to the consumer, raised there
            self._put((False, exc))
        finally:
            close = getattr(source, "close", None)  # a generator: close it here, on the thread that runs it
            if close is not None:
                try:
                    close()
                except Exception as exc:  # an error while closing the source is reported, not lost
                    self._put((False, exc))

    def _put(self, entry) -> bool:
        """Queue ``entry`` unless the consumer has stopped reading; False when it has."""
        while not self._stop.is_set():
            try:
                self._queue.put(entry, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def __iter__(self) -> "ReadAhead":
        return self

    def __next__(self):
        if self._done:
            raise StopIteration
        while True:
            try:
                ok, value = self._queue.get(timeout=0.1)
                break
            except queue.Empty:
                if not self._thread.is_alive() and self._queue.empty():  # cannot happen unless close() ran
                    self._done = True
                    raise StopIteration from None
        if ok and value is not self._END:
            return value
        self._done = True
        if ok:
            raise StopIteration
        raise value

    def close(self) -> None:
        """Stop reading, drop what was read ahead and wait for the reader thread (idempotent)."""
        self._done = True
        self._stop.set()
        while self._thread.is_alive():  # short steps: a Ctrl-C is not held up by the join
            self._thread.join(0.1)
        while True:
            try:
                self._queue.get_nowait()
            except queue.Empty:
                break

    def __enter__(self) -> "ReadAhead":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _sequence_inputs(folder: Path, init: np.ndarray | None, init_modality: str) -> TrackInputs:
    seq = read_sequence(folder)
    first = read_image(seq.rgb_frames[0])
    size = (first.shape[1], first.shape[0])
    t_first = read_image(seq.t_frames[0])
    t_size = (t_first.shape[1], t_first.shape[0])
    # benchmark sequences are registered already; only the resolution may differ
    h = np.diag([t_size[0] / size[0], t_size[1] / size[1], 1.0])
    if init is not None:
        source = f"--init ({init_modality})"
        box = init if init_modality == "rgb" else map_box(np.linalg.inv(h), init)
    elif seq.init_box is not None:
        source, box = f"{seq.layout} ground truth", seq.init_box
    else:
        box = map_box(np.linalg.inv(h), salient_warm_object(FixedRange(str(folder))(t_first)))
        source = "automatic (most salient warm object)"
    fps = 30.0

    def pairs() -> Iterator[Paired]:
        to_8bit = FixedRange(str(folder)), FixedRange(str(folder))  # trackers take 8 bits (16-bit thermal PNGs)
        for k, (rgb_path, t_path) in enumerate(zip(seq.rgb_frames, seq.t_frames)):
            try:
                rgb_frame, t_frame = read_image(rgb_path), read_image(t_path)
            except FileFormatError as exc:  # keep the frame count: the harness repeats the last box
                warnings.warn(f"{exc}; frame {k} skipped", CorruptFrameWarning, stacklevel=2)
                yield None, None, k / fps
                continue
            for path, frame, expected in ((rgb_path, rgb_frame, size), (t_path, t_frame, t_size)):
                if frame.shape[1::-1] != expected:
                    raise InputError(f"{path}: {frame.shape[1]}x{frame.shape[0]}, the other frames are "
                                     f"{expected[0]}x{expected[1]}")
            yield to_8bit[0](rgb_frame, str(rgb_path)), to_8bit[1](t_frame, str(t_path)), k / fps

    return TrackInputs(seq.name, pairs(), size, t_size, fps, len(seq), h, check_input_box(box, size, str(folder)),
                       source, description={"sequence": str(folder), "layout": seq.layout})


def _init_file_beside(path: Path) -> Path | None:
    candidate = path.with_name(path.stem + ".init.txt") if path.is_file() else path / "init.txt"
    return candidate if candidate.is_file() else None


def _span(source) -> str:
    last = (source.frame_count - 1) / source.fps if source.frame_count and source.fps else float("nan")
    return f"0.00-{last:.2f} s" if np.isfinite(last) else "length unknown"


def _overlapping(pairs: Iterator[Paired], rgb_source, t_source, time_offset: float) -> Iterator[Paired]:
    """``pairs`` unchanged, or InputError now (before any output is made) when not one frame pair overlaps in time."""
    if not np.isfinite(time_offset):
        raise InputError(f"the thermal clock offset must be a finite number of seconds, got {-time_offset}")
    first = next(pairs, None)
    if first is None:
        raise InputError(f"no RGB and thermal frames overlap in time (RGB {_span(rgb_source)}, thermal "
                         f"{_span(t_source)}, offset {-time_offset + 0.0:+.3f} s); check --offset or the calibration's")
    return itertools.chain([first], pairs)


def resolve_inputs(rgb: str | os.PathLike, thermal: str | os.PathLike | None = None, *,
                   init: np.ndarray | None = None, init_modality: str = "rgb",
                   h_rgb_to_t: np.ndarray | None = None, time_offset: float = 0.0,
                   estimate_registration=None, assume_aligned: bool = False,
                   realtime: bool = False) -> TrackInputs:
    """Resolve the inputs of ``rgbt track``.

    The RGB->T transform is ``h_rgb_to_t`` (a calibration), else a resolution-only scaling when ``assume_aligned``
    (the user says the views are registered already), else ``estimate_registration(rgb_path, t_path) -> 3x3``. When
    none of these gives a transform a :class:`RegistrationError` says why and what to give: tracking with a guessed
    geometry would put every thermal box in the wrong place while the run looked fine. ``time_offset`` is added to
    thermal timestamps to bring them onto the RGB clock. Live sources (a URL, ``/dev/video*``, a named pipe), and
    every source with ``realtime``, are read once by :func:`~rgbt_toolkit.jmmac.live_inputs.resolve_live_inputs`.
    """
    if init_modality not in ("rgb", "t"):
        raise InputError(f"--init-modality must be 'rgb' or 't', got '{init_modality}'")
    if realtime or is_live(rgb) or (thermal is not None and is_live(thermal)):  # read once, forward only
        from rgbt_toolkit.jmmac.live_inputs import resolve_live_inputs

        return resolve_live_inputs(rgb, thermal, init=init, init_modality=init_modality, h_rgb_to_t=h_rgb_to_t,
                                   time_offset=time_offset, assume_aligned=assume_aligned, realtime=realtime)
    rgb = Path(rgb)
    if thermal is None:
        if not rgb.is_dir():
            raise InputError(f"{rgb}: give two inputs (RGB and thermal) or one benchmark sequence folder")
        detect_layout(rgb)
        return _sequence_inputs(rgb, init, init_modality)
    thermal = Path(thermal)
    # an unreadable RGB frame keeps its place (a skipped row); the nearest readable thermal frame stands in for one
    rgb_source = open_frames(rgb, keep_gaps=True, fixed_size=True)
    t_source = open_frames(thermal, fixed_size=True, auto_grey=True)  # a grey picture travels as one channel
    notes = []
    if init is not None and init_modality == "rgb":  # fail before the (slower) registration estimate
        check_input_box(np.asarray(init, dtype=float), rgb_source.size, str(rgb))
    if h_rgb_to_t is not None and assume_aligned:
        raise InputError("give either a calibration (--calib) or --assume-aligned, not both")
    if h_rgb_to_t is None and assume_aligned:
        h_rgb_to_t = np.diag([t_source.size[0] / rgb_source.size[0], t_source.size[1] / rgb_source.size[1], 1.0])
        notes.append("--assume-aligned: the views are taken as registered, differing only in resolution")
    elif h_rgb_to_t is None:
        if estimate_registration is None:
            raise RegistrationError(unregistered_message(rgb, thermal, "no calibration given"))
        try:
            h_rgb_to_t = np.asarray(estimate_registration(rgb, thermal), dtype=float)
        except RgbtError as exc:  # no silent fallback: a guessed geometry maps every box to the wrong place
            reason = str(exc) if str(exc).startswith("registration failed") else f"registration failed: {exc}"
            raise RegistrationError(unregistered_message(rgb, thermal, reason),
                                    getattr(exc, "details", None)) from None
        notes.append("RGB->T registration estimated from a few frame pairs (save one with `rgbt register` to reuse it)")
    h_rgb_to_t = np.asarray(h_rgb_to_t, dtype=float)

    if init is not None:
        box, source = (init if init_modality == "rgb" else map_box(np.linalg.inv(h_rgb_to_t), init)), \
            f"--init ({init_modality})"
    elif (found := _init_file_beside(rgb)) is not None:
        box, source = first_init_box(found, rgb_source.size), str(found)
    elif (found := _init_file_beside(thermal)) is not None:
        box, source = map_box(np.linalg.inv(h_rgb_to_t), first_init_box(found, t_source.size)), str(found)
    else:
        first_t, _ = next(iter(t_source))
        box = map_box(np.linalg.inv(h_rgb_to_t), salient_warm_object(first_t))
        source = "automatic (most salient warm object)"
    box = check_input_box(np.asarray(box, dtype=float), rgb_source.size, str(rgb))

    if rgb_source.kind == "video" and t_source.kind == "video" and abs(rgb_source.fps - t_source.fps) > 1e-3:
        notes.append(f"frame rates differ ({rgb_source.fps:.3g} vs {t_source.fps:.3g} fps): paired by time")
    pairs = _overlapping(((a, b, t) for a, b, t, _ in pair_by_time(rgb_source, t_source, offset=time_offset)),
                         rgb_source, t_source, time_offset)
    count = rgb_source.frame_count
    if t_source.frame_count and rgb_source.fps and t_source.fps:
        count = min(count, int(np.ceil(t_source.frame_count / t_source.fps * rgb_source.fps)) + 1)
        rgb_seconds = rgb_source.frame_count / rgb_source.fps
        t_seconds = t_source.frame_count / t_source.fps
        if rgb_source.frame_count and abs(rgb_seconds - t_seconds) > max(1 / rgb_source.fps, 1 / t_source.fps) + 1e-6:
            shorter = "thermal" if t_seconds < rgb_seconds else "RGB"
            notes.append(f"the {shorter} recording is shorter ({rgb_seconds:.2f} s RGB, {t_seconds:.2f} s thermal): "
                         "tracking stops where the two overlap")
    name = rgb.stem.removesuffix("_rgb").removesuffix("_visible") or rgb.stem
    given_t = np.asarray(init, dtype=float) if init is not None and init_modality == "t" else None
    return TrackInputs(name, pairs, rgb_source.size, t_source.size, rgb_source.fps, count, h_rgb_to_t, box, source,
                       notes, {"rgb": str(rgb), "t": str(thermal)}, given_t, sources=(rgb_source, t_source))
