"""Register two recordings end to end: read, (optionally) synchronise, pair, estimate, package a calibration.

Frames are streamed, never all held: each source is read once to collect timestamps (and, with ``sync``, the small
frames of the motion signal) while an evenly thinned reservoir keeps a few full RGB frames; the thermal source is
then read again only up to the last needed instant to fetch each kept RGB frame's partner. A frame folder or single
image works the same way (a single image is a one-frame recording).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterable

import numpy as np

from rgbt_toolkit.errors import RegistrationError
from rgbt_toolkit.registration.calib import Calibration
from rgbt_toolkit.registration.spatial import SpatialResult, SpatialSettings, estimate_transform
from rgbt_toolkit.registration.temporal import (
    FramePairing, OffsetEstimate, estimate_offset, frame_period, motion_signal, pair_frames, small_grey,
)

FrameStream = Callable[[], Iterable[tuple[np.ndarray, float]]]  # a re-iterable source of (frame, t) pairs


@dataclass(frozen=True)
class RegisterSettings:
    """Settings of :func:`register_streams`."""

    spatial: SpatialSettings = field(default_factory=SpatialSettings)
    sync: bool = False  # estimate the clock offset from motion (needs videos of a moving scene)
    max_offset: float = 2.0  # largest |offset| searched by sync, seconds
    max_pairs: int = 4  # frame pairs that the spatial estimate uses, spread evenly over the recording


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


class _Reservoir:
    """Keeps at most ``2 * n`` evenly spaced items of a stream of unknown length (thinning by halves)."""

    def __init__(self, n: int):
        self.n, self.stride, self.items = max(1, n), 1, []

    def offer(self, index: int, item) -> None:
        if index % self.stride:
            return
        self.items.append((index, item))
        if len(self.items) > 2 * self.n:
            self.stride *= 2
            self.items = [(i, x) for i, x in self.items if i % self.stride == 0]

    def pick(self, count: int, cost: np.ndarray) -> list:
        """``count`` items spread over the stream: the lowest-``cost`` item of each of ``count`` equal chunks."""
        if len(self.items) <= count:
            return self.items
        chunks = np.array_split(np.arange(len(self.items)), count)
        return [self.items[int(chunk[np.argmin(cost[chunk])])] for chunk in chunks if len(chunk)]


def _scan(stream: FrameStream, keep: int, want_motion: bool):
    times, smalls, reservoir = [], [], _Reservoir(keep)
    for index, (frame, t) in enumerate(stream()):
        times.append(float(t))
        if want_motion:
            smalls.append(small_grey(frame))
        if keep:
            reservoir.offer(index, frame)
    return np.asarray(times), smalls, reservoir


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


def register_streams(rgb: FrameStream, thermal: FrameStream,
                     settings: RegisterSettings = RegisterSettings()) -> Registration:
    """Calibrate an RGB-thermal rig from two recordings.

    Parameters
    ----------
    rgb, thermal : callables returning a fresh iterator of ``(frame, t_seconds)`` each time (a
        :class:`rgbt_toolkit.io.frames.FrameSource`'s ``__iter__`` works, or ``lambda: iter(list_of_pairs)``).
    settings : spatial settings, whether to synchronise, how many frame pairs to use.

    Raises
    ------
    RegistrationError
        Sync on recordings too short or static, no frames overlapping in time, or a failed spatial estimate.
    """
    # keep 4x the frames needed, then use those whose thermal partner is nearest in time: a moving camera or
    # object is displaced between two exposures that are a fraction of a frame apart
    rgb_times, rgb_small, reservoir = _scan(rgb, 2 * settings.max_pairs, settings.sync)
    offset_est = None
    thermal_times, thermal_small, _ = _scan(thermal, 0, settings.sync)
    if settings.sync:
        if len(rgb_times) < 2 or len(thermal_times) < 2:
            raise RegistrationError(
                f"--sync needs videos, but got {len(rgb_times)} RGB and {len(thermal_times)} thermal frame(s); "
                "a single frame carries no motion to synchronise on"
            )
        sig_a, t_a = motion_signal(rgb_small, rgb_times)
        sig_t, t_t = motion_signal(thermal_small, thermal_times)
        offset_est = estimate_offset(sig_a, t_a, sig_t, t_t, max_offset=settings.max_offset)
    offset = offset_est.offset if offset_est else 0.0
    pairing = pair_frames(rgb_times, thermal_times, offset)
    if len(pairing) == 0:
        raise RegistrationError(
            f"no RGB and thermal frames overlap in time (RGB {rgb_times[0]:.2f}-{rgb_times[-1]:.2f} s, thermal "
            f"{thermal_times[0]:.2f}-{thermal_times[-1]:.2f} s, offset {offset:+.3f} s)"
        )
    tolerance = pairing.tolerance
    if len(rgb_times) == 1 and len(thermal_times) == 1:
        tolerance = np.inf  # two still images: pair them whatever their nominal times
    gaps = np.array([np.min(np.abs(thermal_times - (rgb_times[i] + offset))) for i, _ in reservoir.items])
    kept = reservoir.pick(settings.max_pairs, gaps)
    wanted = np.array([rgb_times[i] + offset for i, _ in kept])
    partners = _fetch(thermal, wanted, tolerance)
    rgb_frames = [kept[k][1] for k in sorted(partners)]
    thermal_frames = [partners[k][0] for k in sorted(partners)]
    if not rgb_frames:
        raise RegistrationError("none of the sampled RGB frames has a thermal frame at the same instant")
    spatial = estimate_transform(rgb_frames, thermal_frames, settings.spatial)
    calibration = Calibration(
        matrix=spatial.matrix, model=spatial.model, rgb_size=spatial.rgb_size, thermal_size=spatial.thermal_size,
        time_offset=offset, quality=spatial.quality, peak_ratio=spatial.peak_ratio, overlap=spatial.overlap,
        pairs_used=spatial.pairs_used, offset_correlation=offset_est.correlation if offset_est else None,
    )
    return Registration(calibration, spatial, offset_est, pairing, len(rgb_times), len(thermal_times),
                        rgb_times, thermal_times)


def register_paths(rgb_path, thermal_path, settings: RegisterSettings = RegisterSettings(), *,
                   fps: float | None = None) -> Registration:
    """:func:`register_streams` on two videos, frame folders or images (``fps`` times folders and images)."""
    from rgbt_toolkit.io.frames import open_frames

    rgb_source = open_frames(rgb_path, fps=fps)
    thermal_source = open_frames(thermal_path, fps=fps)
    return register_streams(rgb_source.__iter__, thermal_source.__iter__, settings)


__all__ = ["RegisterSettings", "Registration", "register_streams", "register_paths", "frame_period"]
