"""Register two recordings end to end: read, (optionally) synchronise, pair, estimate, package a calibration.

Frames are streamed, never all held. The thermal source is read once for its timestamps (and, with ``sync``, the
small frames of the motion signal; the RGB source too); one pass over the RGB source then keeps, in each of
``max_pairs`` time chunks, the frame nearest in time to a thermal frame; a last pass over the thermal source, stopped
after the last needed instant, fetches those partners. A frame folder or single
image works the same way (a single image is a one-frame recording). Two videos without ``sync`` skip the passes:
the frames are chosen from packet timestamps and only they are decoded (:class:`SeekableVideo`).

Blank frames (a thermal camera's warm-up screen) carry neither motion nor edges: they leave the motion signal, and
the pairs handed to the spatial estimate are checked here, so that an error names the recording at fault.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.registration.calib import Calibration
from rgbt_toolkit.registration.features import BLANK_GRADIENT_RMS, gradient_rms, to_grey
from rgbt_toolkit.registration.overlays import blank_out, fitted, overlay_mask
from rgbt_toolkit.registration.sampled import SampledFolder, SeekableVideo, video_timestamps
from rgbt_toolkit.registration.spatial import SpatialResult, SpatialSettings, estimate_transform
from rgbt_toolkit.registration.temporal import (
    FramePairing, OffsetEstimate, blank_frames, estimate_offset, motion_signal, pair_frames, small_grey,
)

FrameStream = Callable[[], Iterable[tuple[np.ndarray, float]]]  # a re-iterable source of (frame, t) pairs
# the spatial estimate samples a fixed budget of pixels over all pairs: beyond a few dozen pairs each is sampled
# too sparsely to refine (80 pairs of a 320x240 clip already fail), and 4-8 spread pairs are as good as many
MAX_PAIRS = 32
# with a decode budget, a pair may be up to this much further apart in time than the best of its chunk when it is
# cheaper to decode (a keyframe): cameras of equal rates pair at 0 s anyway, and 5 ms moves a car at 20 m/s 10 cm
CHEAP_PAIR_SLACK = 0.005
MIN_BUDGET_PAIRS = 2  # pairs kept whatever the decode budget: with one, a single view of the scene decides alone


@dataclass(frozen=True)
class RegisterSettings:
    """Settings of :func:`register_streams`."""

    spatial: SpatialSettings = field(default_factory=SpatialSettings)
    sync: bool = False  # estimate the clock offset from motion (needs videos of a moving scene)
    max_offset: float = 2.0  # largest |offset| searched by sync, seconds
    max_pairs: int = 4  # frame pairs that the spatial estimate uses, spread evenly over the recording (<= MAX_PAIRS)
    offset: float = 0.0  # known clock offset (thermal = RGB + offset), seconds; used when not synchronising
    # Frames decoded per pair (both cameras, from the keyframe before each) above which a pair is left out, down to
    # MIN_BUDGET_PAIRS; None: every pair asked for. For videos read by time (two videos, or sampled folders)
    decode_budget: int | None = None
    # frame folders read by time too (SampledFolder): only the chosen files are decoded, JPEG at reduced size; an
    # unreadable file then still counts in rgb_frames / thermal_frames and the pairing
    sampled_folders: bool = False
    # look for burned-in overlays (on-screen text, clocks, reticles) in each camera's frames and leave them out of
    # the estimate (overlays.py): over a featureless scene they are all the two views share
    overlays: bool = True


@dataclass(frozen=True)
class Registration:
    """The calibration plus what it was computed from (for reports)."""

    calibration: Calibration
    spatial: SpatialResult
    offset: OffsetEstimate | None
    pairing: FramePairing
    rgb_frames: int
    thermal_frames: int
    rgb_times: np.ndarray
    thermal_times: np.ndarray
    preview_times: tuple[float, float] | None = None  # (RGB t, thermal t) of the used pair with the most structure


def _scan(stream: FrameStream, want_motion: bool, windows: np.ndarray | None = None, half_width: float = 0.2):
    """Timestamps of a stream, its small grey frames (for synchronisation) and the frames within ``windows``.

    Frames within ``half_width`` seconds of a window centre are kept so that, once the clock offset is known, the one
    nearest in time to a thermal frame can be chosen without reading the stream again (0.4 s covers every phase of
    two frame clocks at 25 fps and above).
    """
    times, smalls, kept = [], [], []
    for frame, t in stream():
        times.append(float(t))
        if want_motion:
            smalls.append(small_grey(frame))
        if windows is not None and np.min(np.abs(windows - t)) <= half_width:
            kept.append((float(t), frame))
    return np.asarray(times), smalls, kept


def _chunk_centres(times: np.ndarray, count: int) -> np.ndarray:
    lo, hi = times[0], times[-1]
    return lo + (np.arange(count) + 0.5) * (hi - lo) / count


def _nearest_gap(sorted_times: np.ndarray, t: float) -> float:
    pos = np.searchsorted(sorted_times, t)
    near = sorted_times[max(pos - 1, 0): pos + 1]
    return float(np.min(np.abs(near - t)))


def _choose_times(times: np.ndarray, partner_times: np.ndarray, count: int, cost: np.ndarray | None = None,
                  slack: float = 0.0) -> dict[int, tuple[float, None, float]]:
    """:func:`_select` from timestamps alone: per chunk, the time whose partner is nearest (the first on a tie).

    With ``cost`` (frames to decode per time), the cheapest of the times within ``slack`` seconds of the chunk's
    nearest gap is chosen instead (the first on a tie). Returns {chunk: (gap, None, t)}."""
    lo, hi = partner_times[0], partner_times[-1]
    width = (hi - lo) / count if hi > lo else 1.0
    pos = np.searchsorted(partner_times, times)
    before = partner_times[np.clip(pos - 1, 0, len(partner_times) - 1)]
    after = partner_times[np.clip(pos, 0, len(partner_times) - 1)]
    gaps = np.minimum(np.abs(times - before), np.abs(times - after))
    chunks = np.clip((times - lo) // width, 0, count - 1).astype(int)
    best = {}
    for chunk in np.unique(chunks):
        members = np.flatnonzero(chunks == chunk)
        k = members[np.argmin(gaps[members])]
        if cost is not None:
            close = members[gaps[members] <= gaps[k] + slack]
            k = close[np.argmin(cost[close])]
        best[int(chunk)] = (float(gaps[k]), None, float(times[k]))
    return best


def _affordable(chosen: dict[int, tuple], cost: dict[int, int], budget: int) -> dict[int, tuple]:
    """The chosen pairs whose decode ``cost`` is within ``budget``, and at least the :data:`MIN_BUDGET_PAIRS`
    cheapest ones (the earliest on a tie)."""
    ranked = sorted(chosen, key=lambda k: (cost[k], k))
    kept = {k for rank, k in enumerate(ranked) if rank < MIN_BUDGET_PAIRS or cost[k] <= budget}
    return {k: chosen[k] for k in sorted(kept)}


def _choose_sampled(rgb, thermal, offset: float, count: int,
                    budget: int | None) -> dict[int, tuple[float, None, float]]:
    """The RGB frames to pair, one per chunk, of two sources read by time (:class:`SeekableVideo`,
    :class:`SampledFolder`); with a decode ``budget``, cheap frames (keyframes) first and costly pairs left out."""
    if budget is None:
        return _choose_times(rgb.times, thermal.times - offset, count)
    cost = rgb.decode_cost(rgb.times) + thermal.decode_cost(rgb.times + offset)
    chosen = _choose_times(rgb.times, thermal.times - offset, count, cost, CHEAP_PAIR_SLACK)
    picked = np.array([t for _, _, t in chosen.values()])
    costs = rgb.decode_cost(picked) + thermal.decode_cost(picked + offset)
    return _affordable(chosen, dict(zip(chosen, costs.tolist())), budget)


def _select(stream: FrameStream, partner_times: np.ndarray, count: int):
    """One pass over ``stream``: per time chunk, the frame whose partner (shifted times) is nearest in time.

    The partner span is cut into ``count`` equal chunks so the pairs spread over the recording; within a chunk the
    frame with the smallest gap wins, because a moving camera or object is displaced between two exposures a
    fraction of a frame apart. Returns all timestamps and {chunk: (gap, frame, t)}.
    """
    lo, hi = partner_times[0], partner_times[-1]
    width = (hi - lo) / count if hi > lo else 1.0
    best: dict[int, tuple[float, np.ndarray, float]] = {}
    times = []
    for frame, t in stream():
        times.append(float(t))
        gap = _nearest_gap(partner_times, t)
        chunk = int(np.clip((t - lo) // width, 0, count - 1))
        if chunk not in best or gap < best[chunk][0]:
            best[chunk] = (gap, frame, float(t))
    return np.asarray(times), best


def _fetch(stream: FrameStream, wanted: np.ndarray, tolerance: float) -> dict[int, tuple[np.ndarray, float, int]]:
    """For each wanted time, the frame nearest to it (within ``tolerance``): {wanted position: (frame, t, index)}."""
    best: dict[int, tuple[np.ndarray, float, int]] = {}
    if len(wanted) == 0:
        return best
    last = wanted.max() + tolerance
    for index, (frame, t) in enumerate(stream()):
        pos = np.searchsorted(wanted, t)
        for k in (pos - 1, pos):
            if 0 <= k < len(wanted):
                gap = abs(t - wanted[k])
                if gap <= tolerance and (k not in best or gap < abs(best[k][1] - wanted[k])):
                    best[k] = (frame, float(t), index)
        if t > last:
            break
    return best


def _fetch_seeking(source, wanted: np.ndarray, tolerance: float):
    """:func:`_fetch` for a source read by time (:class:`SeekableVideo`, :class:`SampledFolder`): the nearest frame
    to each wanted time (within ``tolerance``), decoding only those. {wanted position: (frame, t, index)}."""
    picks = {}
    for k, t in enumerate(wanted):
        index = int(np.argmin(np.abs(source.times - t)))
        if abs(source.times[index] - t) <= tolerance:
            picks[k] = index
    frames = source.frames_at(source.times[list(picks.values())]) if picks else {}
    return {k: (frames[float(source.times[i])], float(source.times[i]), i) for k, i in picks.items()
            if float(source.times[i]) in frames}


def _counted(stream: FrameStream, on_frame: Callable[[], None] | None) -> FrameStream:
    if on_frame is None:
        return stream

    def frames():
        for item in stream():
            on_frame()
            yield item
    return frames


def _structure(frame: np.ndarray) -> float:
    """RMS gradient of a frame at half size: blank frames stay blank, at a quarter of the cost of full size."""
    grey = to_grey(frame)
    if min(grey.shape) >= 64:
        grey = cv2.resize(grey, (grey.shape[1] // 2, grey.shape[0] // 2), interpolation=cv2.INTER_AREA)
    return gradient_rms(grey)


def _without_overlays(frames: list[np.ndarray], hand_mask: np.ndarray | None, detect: bool) -> list[np.ndarray]:
    """One camera's paired frames with its overlays (found, and masked by hand) given no structure."""
    shape = frames[0].shape[:2]
    mask = fitted(hand_mask, shape) if hand_mask is not None else None
    if detect and len({f.shape[:2] for f in frames}) == 1:  # differing sizes are reported by _check_pairs
        found = overlay_mask(frames)
        mask = found if mask is None else mask | found
    if mask is None or not mask.any():
        return frames
    return [blank_out(f, mask) for f in frames]


def _check_pairs(rgb_frames, thermal_frames, names: tuple[str, str]) -> list[int]:
    """Indices of pairs where both frames show structure; a one-line error naming the recording otherwise."""
    for frames, name in zip((rgb_frames, thermal_frames), names):
        sizes = sorted({(f.shape[1], f.shape[0]) for f in frames})
        if len(sizes) > 1:
            raise InputError(
                f"{name}: frames differ in size ({', '.join(f'{w}x{h}' for w, h in sizes)}); a camera has one "
                "resolution, so remove or resize the odd frames"
            )
    rms_a = [_structure(f) for f in rgb_frames]
    rms_t = [_structure(f) for f in thermal_frames]
    for rms, name, which in ((rms_a, names[0], "RGB"), (rms_t, names[1], "thermal")):
        if max(rms) <= BLANK_GRADIENT_RMS:
            raise RegistrationError(
                f"{name}: the {len(rms)} {which} frame(s) paired for registration are blank (no edges to register); "
                "use a recording, or a part of it, that shows the scene"
            )
    usable = [i for i in range(len(rms_a)) if min(rms_a[i], rms_t[i]) > BLANK_GRADIENT_RMS]
    return sorted(usable, key=lambda i: -min(rms_a[i], rms_t[i]))


def register_streams(rgb: FrameStream, thermal: FrameStream,
                     settings: RegisterSettings = RegisterSettings(), *,
                     thermal_times: np.ndarray | None = None, names: tuple[str, str] = ("RGB", "thermal"),
                     on_frame: Callable[[], None] | None = None,
                     masks: tuple[np.ndarray | None, np.ndarray | None] = (None, None)) -> Registration:
    """Calibrate an RGB-thermal rig from two recordings.

    Parameters
    ----------
    rgb, thermal : callables returning a fresh iterator of ``(frame, t_seconds)`` each time (a
        :class:`rgbt_toolkit.io.frames.FrameSource`'s ``__iter__`` works, or ``lambda: iter(list_of_pairs)``); or
        both read by time (:class:`SeekableVideo`, :class:`SampledFolder`): only the chosen frames are decoded.
    settings : spatial settings, whether to synchronise (else ``settings.offset`` is used), how many frame pairs.
    thermal_times : the thermal timestamps if known without decoding (saves a pass when not synchronising).
    names : how errors name the two recordings (their paths, for :func:`register_paths`).
    on_frame : called once per decoded frame (a progress bar's update).
    masks : (RGB, thermal) images, non-zero where that camera's frames are to be left out (an overlay the detector
        misses, a logo, a part of the rig in view), at any size (resized to the frames); None: nothing by hand.
        With ``settings.overlays`` the overlays found in each camera (overlays.py) are left out as well.

    Raises
    ------
    InputError
        ``settings.max_pairs`` out of range, or frames of one recording differing in size.
    RegistrationError
        Sync on recordings too short, static or ambiguous, no frames overlapping in time, blank frames, or a failed
        spatial estimate.
    """
    if not 1 <= settings.max_pairs <= MAX_PAIRS:
        raise InputError(f"frame pairs must be between 1 and {MAX_PAIRS}, got {settings.max_pairs}")
    seekable = all(isinstance(s, (SeekableVideo, SampledFolder)) for s in (rgb, thermal)) and not settings.sync
    if seekable:
        thermal_times = thermal.times
    else:
        rgb, thermal = _counted(rgb, on_frame), _counted(thermal, on_frame)
    if settings.sync or thermal_times is None:
        thermal_times, thermal_small, _ = _scan(thermal, settings.sync)
    else:
        thermal_times, thermal_small = np.asarray(thermal_times, float), []
    if len(thermal_times) == 0:
        raise RegistrationError(f"{names[1]}: no decodable frames")
    offset_est = None
    if settings.sync:
        thermal_blank = blank_frames(thermal_small)
        content = thermal_times[~thermal_blank]
        windows = _chunk_centres(content if len(content) else thermal_times, settings.max_pairs)
        rgb_times, rgb_small, window_frames = _scan(rgb, True, windows)
        if len(rgb_times) < 2 or len(thermal_times) < 2:
            raise RegistrationError(
                f"--sync needs videos, but got {len(rgb_times)} RGB and {len(thermal_times)} thermal frame(s); "
                "a single frame carries no motion to synchronise on"
            )
        sig_a, t_a = motion_signal(rgb_small, rgb_times)
        sig_t, t_t = motion_signal(thermal_small, thermal_times)
        offset_est = estimate_offset(sig_a, t_a, sig_t, t_t, max_offset=settings.max_offset)
    offset = offset_est.offset if offset_est else float(settings.offset)
    if settings.sync:  # choose among the frames kept around the window centres: no second pass over the RGB video
        chosen = {}
        for t, frame in window_frames:
            k = int(np.argmin(np.abs(windows - t)))
            if thermal_blank[int(np.argmin(np.abs(thermal_times - offset - t)))] and len(content):
                continue  # its partner is a warm-up frame: no edges to register
            gap = _nearest_gap(thermal_times - offset, t)
            if k not in chosen or gap < chosen[k][0]:
                chosen[k] = (gap, frame, t)
    elif seekable:  # choose by packet (or file) timestamps, decode only the chosen frames (sampled.py)
        rgb_times = rgb.times
        chosen = _choose_sampled(rgb, thermal, offset, settings.max_pairs, settings.decode_budget)
        frames = rgb.frames_at(np.array([t for _, _, t in chosen.values()]))
        chosen = {k: (gap, frames[t], t) for k, (gap, _, t) in chosen.items() if t in frames}
    else:
        rgb_times, chosen = _select(rgb, thermal_times - offset, settings.max_pairs)
    if len(rgb_times) == 0:
        raise RegistrationError(f"{names[0]}: no decodable frames")
    stills = len(rgb_times) == 1 and len(thermal_times) == 1
    if stills:  # two still images: pair them whatever their nominal times
        pairing = FramePairing(np.zeros(1, int), np.zeros(1, int), np.zeros(1), 0.0, np.inf)
    else:
        pairing = pair_frames(rgb_times, thermal_times, offset)
    if len(pairing) == 0:
        raise RegistrationError(
            f"no RGB and thermal frames overlap in time (RGB {rgb_times[0]:.2f}-{rgb_times[-1]:.2f} s, thermal "
            f"{thermal_times[0]:.2f}-{thermal_times[-1]:.2f} s, offset {offset:+.3f} s)"
        )
    kept = [chosen[k] for k in sorted(chosen) if stills or chosen[k][0] <= pairing.tolerance]
    wanted = thermal_times[:1] if stills else np.array([t + offset for _, _, t in kept])
    partners = _fetch_seeking(thermal, wanted, pairing.tolerance) if seekable else \
        _fetch(thermal, wanted, pairing.tolerance)
    rgb_frames = [kept[k][1] for k in sorted(partners)]
    thermal_frames = [partners[k][0] for k in sorted(partners)]
    if not rgb_frames:
        raise RegistrationError("none of the sampled RGB frames has a thermal frame at the same instant")
    plain = rgb_frames, thermal_frames
    rgb_frames = _without_overlays(rgb_frames, masks[0], settings.overlays)
    thermal_frames = _without_overlays(thermal_frames, masks[1], settings.overlays)
    try:
        usable = _check_pairs(rgb_frames, thermal_frames, names)
    except RegistrationError as exc:
        if rgb_frames is plain[0] and thermal_frames is plain[1]:
            raise
        _check_pairs(*plain, names)  # blank already with their overlays: said as for any blank frames
        raise RegistrationError(f"{exc} (blank once their burned-in overlays, on-screen text or a reticle, are left "
                                "out: each camera draws its own, so they say nothing about how the views align)",
                                getattr(exc, "details", None)) from None
    times = [(kept[k][2], partners[k][1]) for k in sorted(partners)]
    spatial = estimate_transform(rgb_frames, thermal_frames, settings.spatial,
                                 sizes=(_full_size(rgb, rgb_frames), _full_size(thermal, thermal_frames)))
    calibration = Calibration(
        matrix=spatial.matrix, model=spatial.model, rgb_size=spatial.rgb_size, thermal_size=spatial.thermal_size,
        time_offset=offset, quality=spatial.quality, peak_ratio=spatial.peak_ratio, overlap=spatial.overlap,
        pairs_used=spatial.pairs_used, offset_correlation=offset_est.correlation if offset_est else None,
    )
    return Registration(calibration, spatial, offset_est, pairing, len(rgb_times), len(thermal_times),
                        rgb_times, thermal_times, times[usable[0]] if usable else None)


def _full_size(source, frames: list[np.ndarray]) -> tuple[int, int]:
    """(width, height) of a recording's frames: a :class:`SampledFolder` decodes JPEG frames reduced."""
    return source.size if isinstance(source, SampledFolder) else (frames[0].shape[1], frames[0].shape[0])


def _sampled(path, fps: float | None, longer: int, on_frame: Callable[[], None] | None):
    """A recording read by time: a video (:class:`SeekableVideo`) or a frame folder (:class:`SampledFolder`)."""
    from rgbt_toolkit.io.frames import DEFAULT_FOLDER_FPS, open_frames

    if Path(path).is_dir():
        return SampledFolder(path, fps or DEFAULT_FOLDER_FPS, longer, on_frame)
    source = open_frames(path, grey=True)
    return SeekableVideo(source.path, source.__iter__, on_frame) if source.kind == "video" else None


def _decoded_once(source) -> FrameStream:
    """The source's frame stream; a single image is decoded once however often the stream is walked (the
    pipeline walks the thermal stream twice: a 1280x1024 PNG costs 30-50 ms a decode)."""
    if source.kind != "image":
        return source.__iter__
    frames = list(source)
    return lambda: iter(frames)


def _is_image(path) -> bool:
    from rgbt_toolkit.io.images import IMAGE_SUFFIXES

    return Path(path).is_file() and Path(path).suffix.lower() in IMAGE_SUFFIXES


def _still(path) -> FrameStream:
    """A single image file as a one-frame stream at t = 0, read once.

    Opening it as a frame source reads it for its size and again for its pixels, and converts colour to grey
    exactly (BT.601 in float64): together 0.2 s of a 1280x1024 `rgbt register`. Registration compares edge
    orientations, not grey levels, so OpenCV's conversion does."""
    from rgbt_toolkit.io.images import read_image

    image = read_image(path)
    frames = [(cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image, 0.0)]
    return lambda: iter(frames)


def register_paths(rgb_path, thermal_path, settings: RegisterSettings = RegisterSettings(), *,
                   fps: float | None = None, rgb_fps: float | None = None, thermal_fps: float | None = None,
                   on_frame: Callable[[], None] | None = None,
                   masks: tuple[np.ndarray | None, np.ndarray | None] = (None, None)) -> Registration:
    """:func:`register_streams` on two videos, frame folders or images.

    ``rgb_fps`` / ``thermal_fps`` time a frame folder (or image) of that camera, ``fps`` both (default 30); videos
    carry their own timestamps. ``on_frame`` is called per decoded frame (progress); ``masks`` as for
    :func:`register_streams`. Two videos are read by time
    (:class:`SeekableVideo`), and with ``settings.sampled_folders`` frame folders too (:class:`SampledFolder`).
    """
    names = (str(rgb_path), str(thermal_path))
    if settings.sampled_folders and not settings.sync:
        longer = settings.spatial.analysis_size
        streams = [_sampled(path, camera_fps or fps, longer, on_frame)
                   for path, camera_fps in ((rgb_path, rgb_fps), (thermal_path, thermal_fps))]
        if all(stream is not None and len(stream.times) for stream in streams):
            return register_streams(*streams, settings, names=names, masks=masks)
    if _is_image(rgb_path) and _is_image(thermal_path):  # no video reader (importing PyAV alone takes 0.1 s)
        return register_streams(_still(rgb_path), _still(thermal_path), settings, names=names, on_frame=on_frame,
                                masks=masks)
    from rgbt_toolkit.io.frames import open_frames

    rgb_source = open_frames(rgb_path, fps=rgb_fps or fps, grey=True)  # every stage works on grey frames
    thermal_source = open_frames(thermal_path, fps=thermal_fps or fps, grey=True)
    if rgb_source.kind == "video" and thermal_source.kind == "video" and not settings.sync:
        streams = [SeekableVideo(source.path, source.__iter__, on_frame) for source in (rgb_source, thermal_source)]
        if all(len(video.times) for video in streams):
            return register_streams(*streams, settings, names=names, masks=masks)
    known = None
    if thermal_source.kind == "video" and not settings.sync:
        known = video_timestamps(thermal_source.path)
    # a folder is decoded for its times: an unreadable file is skipped, and must not count as a frame or pair
    return register_streams(_decoded_once(rgb_source), _decoded_once(thermal_source), settings, thermal_times=known,
                            names=names, on_frame=on_frame, masks=masks)


# The estimate inside `rgbt track`: frames read by time from folders as from videos, JPEG decoded
# reduced, and pairs that would need long runs of decoding left out (x264's default puts a keyframe every 250
# frames; one 1080p H.264 frame is 8 ms of CPU here, a 640x512 one 1 ms, so 16 frames a pair stay under 0.15 s).
# The coarse search scores the most textured pair alone, as for two stills (the acceptance thresholds were set on
# stills): on the frame pairs this reads from benchmarks/real_pair.py's pair (video and JPEG, 101 and 300 frames),
# estimate_transform returns the same matrices with evidence 13-15 instead of 14-20, in 0.30-0.34 s of CPU instead
# of 0.38-0.43 s (best of 3, one thread). Recordings refused that way are read again in full
TRACKING = RegisterSettings(spatial=SpatialSettings(coarse_pairs=1), decode_budget=16, sampled_folders=True)


def register_for_tracking(rgb_path, thermal_path, *, fps: float | None = None,
                          masks: tuple[np.ndarray | None, np.ndarray | None] = (None, None)) -> Registration:
    """:func:`register_paths` as ``rgbt track`` needs it: from the few frames :data:`TRACKING` decodes; when that
    answer is refused, from the full read, whose answer or refusal stands (as without the shortcut).

    A refusal on fewer frames is no proof that the recordings cannot be registered; an answer passes the same
    acceptance test whatever frames it came from. ``masks`` as for :func:`register_streams`.
    """
    try:
        return register_paths(rgb_path, thermal_path, TRACKING, fps=fps, masks=masks)
    except RegistrationError:
        return register_paths(rgb_path, thermal_path, fps=fps, masks=masks)


__all__ = ["MAX_PAIRS", "TRACKING", "RegisterSettings", "Registration", "register_for_tracking", "register_streams",
           "register_paths", "video_timestamps"]
