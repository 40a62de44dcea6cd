"""Pair the frames of two cameras in time, and estimate a constant offset between their clocks.

Two cameras rarely share a frame rate (thermal cores run at 9, 25 or 30 Hz; RGB at 25-60 Hz) and are started a
fraction of a second apart. Frames are paired by presentation timestamp; the offset is estimated from what both
cameras see regardless of modality, namely *when things move*: the per-frame change energy (mean absolute
difference of consecutive small grey frames) rises and falls together in both streams. The two signals are
resampled to a common clock, high-pass filtered, and cross-correlated; the lag of the correlation peak is the offset.

Convention: ``offset`` is added to RGB times to get thermal times, ``t_thermal = t_rgb + offset``; a positive offset
means an event appears later in the thermal timestamps.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.registration.features import to_grey

MOTION_SIZE = 64  # longer side of the frames the change energy is computed on: motion, not detail, matters
MIN_SIGNAL_SAMPLES = 8


@dataclass(frozen=True)
class FramePairing:
    """Index pairs of RGB and thermal frames that show the same instant."""

    rgb_index: np.ndarray
    thermal_index: np.ndarray
    gap: np.ndarray  # t_thermal - (t_rgb + offset) per pair, seconds
    offset: float
    tolerance: float

    def __len__(self) -> int:
        return len(self.rgb_index)


@dataclass(frozen=True)
class OffsetEstimate:
    """A clock offset and how sure we are of it."""

    offset: float  # seconds, t_thermal = t_rgb + offset
    correlation: float  # Pearson correlation of the motion signals at the offset
    runner_up: float  # best correlation at lags more than ``separation`` away from the peak
    lag_step: float  # resolution of the common clock, seconds


def _check_times(times, name: str) -> np.ndarray:
    times = np.asarray(times, float).ravel()
    if times.size == 0:
        raise InputError(f"no {name} timestamps given")
    if not np.all(np.isfinite(times)) or np.any(np.diff(times) < 0):
        raise InputError(f"{name} timestamps must be finite and non-decreasing")
    return times


def frame_period(times: np.ndarray) -> float:
    """Median spacing of timestamps (seconds); 0 for a single frame."""
    return float(np.median(np.diff(times))) if len(times) > 1 else 0.0


def pair_frames(rgb_times, thermal_times, offset: float = 0.0, tolerance: float | None = None) -> FramePairing:
    """Pair frames by timestamp after shifting the RGB clock by ``offset``.

    The stream with the lower frame rate drives: each of its frames gets the other stream's nearest frame, so no
    frame of the slower stream is used twice. Pairs further apart than ``tolerance`` are dropped (default: half the
    longer frame period, i.e. the two exposures overlap in time).
    """
    ta = _check_times(rgb_times, "RGB")
    tt = _check_times(thermal_times, "thermal") - offset
    if tolerance is None:
        tolerance = 0.5 * max(frame_period(ta), frame_period(tt), 1e-3)
    rgb_drives = len(ta) <= len(tt)
    driver, other = (ta, tt) if rgb_drives else (tt, ta)
    pos = np.clip(np.searchsorted(other, driver), 1, max(len(other) - 1, 1))
    left = other[np.maximum(pos - 1, 0)]
    right = other[np.minimum(pos, len(other) - 1)]
    nearest = np.where(np.abs(driver - left) <= np.abs(right - driver), np.maximum(pos - 1, 0),
                       np.minimum(pos, len(other) - 1))
    if len(other) == 1:
        nearest = np.zeros(len(driver), int)
    drv_idx = np.arange(len(driver))
    gap = other[nearest] - driver
    ok = np.abs(gap) <= tolerance + 1e-9
    if rgb_drives:
        a_idx, t_idx, gaps = drv_idx[ok], nearest[ok], gap[ok]
    else:
        a_idx, t_idx, gaps = nearest[ok], drv_idx[ok], -gap[ok]
    return FramePairing(a_idx.astype(int), t_idx.astype(int), gaps, float(offset), float(tolerance))


def small_grey(frame: np.ndarray, size: int = MOTION_SIZE) -> np.ndarray:
    """Frame shrunk to ``size`` pixels on its longer side, grey float32 (what the motion signal is made of)."""
    grey = to_grey(frame)
    f = size / max(grey.shape)
    if f < 1:
        grey = cv2.resize(grey, (max(1, round(grey.shape[1] * f)), max(1, round(grey.shape[0] * f))),
                          interpolation=cv2.INTER_AREA)
    return grey


def motion_signal(small_frames: list[np.ndarray], times) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame change energy and its timestamps (midpoints between consecutive frames).

    Each frame difference is divided by the frame's contrast so a thermal camera's automatic gain changes, or a
    dim RGB scene, do not dominate.
    """
    times = _check_times(times, "frame")
    if len(small_frames) != len(times):
        raise InputError(f"{len(small_frames)} frames but {len(times)} timestamps")
    if len(small_frames) < 2:
        return np.zeros(0), np.zeros(0)
    stack = np.stack(small_frames).astype(np.float32)
    contrast = stack.reshape(len(stack), -1).std(axis=1) + 1e-3
    diff = np.abs(np.diff(stack, axis=0)).reshape(len(stack) - 1, -1).mean(axis=1)
    energy = diff / (0.5 * (contrast[1:] + contrast[:-1]))
    return energy, 0.5 * (times[1:] + times[:-1])


def _highpass(x: np.ndarray, window: int) -> np.ndarray:
    x = np.log1p(50.0 * x)
    if window > 1 and len(x) > window:
        kernel = np.ones(window) / window
        trend = np.convolve(np.pad(x, window // 2, mode="edge"), kernel, mode="same")[window // 2: window // 2 + len(x)]
        x = x - trend
    return x


def _samples_per_second(times: np.ndarray) -> int:
    return max(3, int(round(1.0 / max(frame_period(times), 1e-3))))


def estimate_offset(rgb_signal, rgb_times, thermal_signal, thermal_times, *, max_offset: float = 2.0,
                    min_correlation: float = 0.3, separation: float = 0.25) -> OffsetEstimate:
    """Clock offset between two motion signals by normalised cross-correlation.

    Parameters
    ----------
    rgb_signal, rgb_times, thermal_signal, thermal_times : outputs of :func:`motion_signal`.
    max_offset : largest |offset| searched, seconds.
    min_correlation : smallest accepted peak correlation; below it the streams share too little motion.
    separation : lags closer than this (seconds) to the peak do not count as a competing peak.

    Raises
    ------
    RegistrationError
        When either stream is too short or static, or the correlation peak is weak or ambiguous.
    """
    a, ta = np.asarray(rgb_signal, float), np.asarray(rgb_times, float)
    b, tb = np.asarray(thermal_signal, float), np.asarray(thermal_times, float)
    if len(a) < MIN_SIGNAL_SAMPLES or len(b) < MIN_SIGNAL_SAMPLES:
        raise RegistrationError(
            f"time offset needs at least {MIN_SIGNAL_SAMPLES + 1} frames per stream (got {len(a) + 1} RGB, "
            f"{len(b) + 1} thermal); use longer videos or register without --sync"
        )
    step = min(frame_period(ta), frame_period(tb))
    step = max(step, 1e-3)
    start, stop = min(ta[0], tb[0]), max(ta[-1], tb[-1])
    grid = np.arange(start, stop + step / 2, step)
    # remove the 1-s trend (lighting drift, gain changes), keep motion events
    ha, hb = _highpass(a, _samples_per_second(ta)), _highpass(b, _samples_per_second(tb))
    for name, h in (("RGB", ha), ("thermal", hb)):
        if np.std(h) < 1e-4:
            raise RegistrationError(
                f"cannot synchronise: the {name} video shows no motion (static scene or frozen frames); "
                "register without --sync"
            )
    sa = np.interp(grid, ta, ha, left=np.nan, right=np.nan)
    sb = np.interp(grid, tb, hb, left=np.nan, right=np.nan)
    max_lag = int(np.ceil(max_offset / step))
    lags = np.arange(-max_lag, max_lag + 1)
    corr = np.full(len(lags), -np.inf)
    n = len(grid)
    for i, lag in enumerate(lags):
        # r(lag) = corr(s_rgb(t), s_thermal(t + lag))
        x = sa[max(0, -lag): n - max(0, lag)]
        y = sb[max(0, lag): n - max(0, -lag) if lag < 0 else n]
        y = y[: len(x)]
        ok = np.isfinite(x) & np.isfinite(y)
        if ok.sum() < MIN_SIGNAL_SAMPLES:
            continue
        xs, ys = x[ok] - x[ok].mean(), y[ok] - y[ok].mean()
        den = np.sqrt((xs * xs).sum() * (ys * ys).sum())
        if den > 1e-12:
            corr[i] = float((xs * ys).sum() / den)
    if not np.isfinite(corr).any():
        raise RegistrationError("the videos do not overlap in time within the searched offset; widen --max-offset")
    k = int(np.argmax(corr))
    peak = corr[k]
    frac = 0.0
    if 0 < k < len(lags) - 1 and np.isfinite(corr[k - 1]) and np.isfinite(corr[k + 1]):
        den = corr[k - 1] - 2 * peak + corr[k + 1]
        if den < 0:
            frac = float(np.clip(0.5 * (corr[k - 1] - corr[k + 1]) / den, -0.5, 0.5))
    far = np.abs(lags - lags[k]) * step > separation
    runner_up = float(corr[far].max()) if far.any() and np.isfinite(corr[far]).any() else -1.0
    result = OffsetEstimate(float((lags[k] + frac) * step), float(peak), runner_up, float(step))
    if peak < min_correlation:
        raise RegistrationError(
            f"cannot synchronise: the motion in the two videos correlates too weakly (peak {peak:.2f} < "
            f"{min_correlation}); the scene may be static, or the videos show different moments"
        )
    if runner_up > 0.9 * peak:
        raise RegistrationError(
            f"cannot synchronise: the motion correlation has competing peaks ({peak:.2f} vs {runner_up:.2f}); "
            "periodic motion or too short a clip; register without --sync or use a longer clip"
        )
    return result
