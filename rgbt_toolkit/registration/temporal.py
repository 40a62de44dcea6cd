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
BLANK_STD = 0.005  # grey std (0-1 scale) below which a frame is blank: about 1 grey level
MIN_SIGNIFICANCE = 3.5  # z score of the offset's correlation peak; see estimate_offset
MIN_PEAK_RATIO = 1.4  # ... and its ratio to the next distinct peak's


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
    runner_up: float  # correlation of the next distinct peak (a local maximum more than ``separation`` away)
    lag_step: float  # resolution of the common clock, seconds
    significance: float = float("nan")  # the peak correlation over its chance spread (a z score)
    next_significance: float = float("nan")  # the same for the next distinct peak


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


def blank_frames(small_frames: list[np.ndarray]) -> np.ndarray:
    """True for frames without contrast (a camera warming up, a lens cap, a frozen grey screen)."""
    return np.array([float(np.std(f)) < BLANK_STD for f in small_frames], bool)


def motion_signal(small_frames: list[np.ndarray], times) -> tuple[np.ndarray, np.ndarray]:
    """Per-frame change energy and its timestamps (midpoints between consecutive frames).

    Each frame difference is divided by the frame's contrast so a thermal camera's automatic gain changes, or a
    dim RGB scene, do not dominate. Differences touching a blank frame are NaN: a camera switching from its
    warm-up screen to the scene is one huge "event" that the other camera never saw.
    """
    times = _check_times(times, "frame")
    if len(small_frames) != len(times):
        raise InputError(f"{len(small_frames)} frames but {len(times)} timestamps")
    if len(small_frames) < 2:
        return np.zeros(0), np.zeros(0)
    stack = np.stack(small_frames).astype(np.float32)
    contrast = stack.reshape(len(stack), -1).std(axis=1) + 1e-3
    diff = np.abs(np.diff(stack, axis=0)).reshape(len(stack) - 1, -1).mean(axis=1)
    energy = (diff / (0.5 * (contrast[1:] + contrast[:-1]))).astype(float)
    blank = blank_frames(small_frames)
    energy[blank[1:] | blank[:-1]] = np.nan
    return energy, 0.5 * (times[1:] + times[:-1])


def _highpass(x: np.ndarray, window: int) -> np.ndarray:
    """Log energy minus its moving average (NaN samples, from blank frames, are left out of both)."""
    x = np.log1p(50.0 * x)
    ok = np.isfinite(x)
    if window > 1 and len(x) > window:
        kernel = np.ones(window)
        total = np.convolve(np.pad(np.where(ok, x, 0.0), window // 2, mode="edge"), kernel, mode="same")
        count = np.convolve(np.pad(ok.astype(float), window // 2, mode="edge"), kernel, mode="same")
        cut = slice(window // 2, window // 2 + len(x))
        x = x - total[cut] / np.maximum(count[cut], 1.0)
    return x


def _samples_per_second(times: np.ndarray) -> int:
    return max(3, int(round(1.0 / max(frame_period(times), 1e-3))))


def _on_grid(grid: np.ndarray, times: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` resampled at ``grid``; NaN outside the samples and between a sample and a missing (NaN) one."""
    ok = np.isfinite(values)
    out = np.interp(grid, times, np.where(ok, values, 0.0), left=np.nan, right=np.nan)
    valid = np.interp(grid, times, ok.astype(float), left=0.0, right=0.0)
    out[valid < 1.0 - 1e-6] = np.nan
    return out


def correlation_curve(sa: np.ndarray, sb: np.ndarray, max_lag: int, min_samples: int) -> tuple[np.ndarray, np.ndarray]:
    """Pearson correlation of ``sa(t)`` with ``sb(t + lag)`` for lag = -max_lag..max_lag grid steps, and the number
    of grid points each was computed on.

    NaN where fewer than ``min_samples`` grid points of the two overlap (too little evidence to compare).
    """
    n = len(sa)
    lags = np.arange(-max_lag, max_lag + 1)
    corr = np.full(len(lags), np.nan)
    counts = np.zeros(len(lags), int)
    for i, lag in enumerate(lags):
        if abs(lag) >= n:
            continue
        x = sa[max(0, -lag): n - max(0, lag)]
        y = sb[max(0, lag): n - max(0, -lag)]
        ok = np.isfinite(x) & np.isfinite(y)
        counts[i] = int(ok.sum())
        if counts[i] < min_samples:
            continue
        xs, ys = x[ok] - x[ok].mean(), y[ok] - y[ok].mean()
        den = np.sqrt((xs * xs).sum() * (ys * ys).sum())
        if den > 1e-12:
            corr[i] = float((xs * ys).sum() / den)
    return corr, counts


def _autocorrelation(s: np.ndarray, max_lag: int) -> np.ndarray:
    """Autocorrelation of a signal with NaN gaps at lags 1..max_lag."""
    ok = np.isfinite(s)
    x = np.where(ok, s - np.nanmean(s), 0.0)
    w = ok.astype(float)
    var = float(np.nanvar(s)) + 1e-12
    out = np.zeros(max_lag)
    for k in range(1, min(max_lag, len(s) - 1) + 1):
        out[k - 1] = (x[:-k] * x[k:]).sum() / max((w[:-k] * w[k:]).sum(), 1.0) / var
    return out


def _significance(corr: np.ndarray, counts: np.ndarray, sa: np.ndarray, sb: np.ndarray, window: int) -> np.ndarray:
    """Correlation in units of its standard error under no relation (Bartlett's formula).

    Neighbouring samples of smoothed motion signals are alike, so a correlation over n samples varies by about
    sqrt((1 + 2 sum_k rho_a(k) rho_b(k)) / n), not 1/sqrt(n): a short clip of slow motion gives high correlations
    by chance, and this says how high.
    """
    inflation = 1.0 + 2.0 * float(np.sum(_autocorrelation(sa, window) * _autocorrelation(sb, window)))
    return corr * np.sqrt(counts / max(inflation, 1.0))


def _next_peak(corr: np.ndarray, k: int, separation: int) -> float:
    """Highest local maximum of ``corr`` more than ``separation`` steps from the peak ``k`` (-1 when none)."""
    c = np.where(np.isfinite(corr), corr, -np.inf)
    left = np.r_[-np.inf, c[:-1]]
    right = np.r_[c[1:], -np.inf]
    local = (c >= left) & (c >= right) & np.isfinite(c)
    local &= np.abs(np.arange(len(c)) - k) > separation
    return float(c[local].max()) if local.any() else -1.0


def estimate_offset(rgb_signal, rgb_times, thermal_signal, thermal_times, *, max_offset: float = 2.0,
                    min_correlation: float = 0.3, min_significance: float = MIN_SIGNIFICANCE,
                    min_ratio: float = MIN_PEAK_RATIO, separation: float = 0.25) -> OffsetEstimate:
    """Clock offset between two motion signals by normalised cross-correlation, refused unless the peak is clear.

    The correlation is computed at every lag where the two signals overlap for at least half the shorter one, also
    beyond ``max_offset``: a better match outside the allowed range, or a peak at its edge, means the true offset
    may be larger than allowed, and is refused rather than reported as the best allowed lag.

    Parameters
    ----------
    rgb_signal, rgb_times, thermal_signal, thermal_times : outputs of :func:`motion_signal` (NaN = blank frame).
    max_offset : largest |offset| accepted, seconds.
    min_correlation : smallest accepted peak correlation; below it the streams share too little motion.
    min_significance : smallest accepted z score of the peak (its correlation over the chance spread of a
        correlation between these signals, see :func:`_significance`).
    min_ratio : smallest accepted ratio of the peak's z score to the next distinct peak's (a local maximum more
        than ``separation`` away). Scenes whose only motion is a few objects give several similar peaks, one of
        them wrong. Both thresholds were set on generated scenes of known offset (docs/registration.md).
    separation : lags closer than this (seconds) to the peak belong to the peak.

    Raises
    ------
    RegistrationError
        When either stream is too short, blank or static, or the correlation peak is weak, ambiguous, at the edge
        of the allowed range or beaten by a lag outside it.
    """
    a, ta = np.asarray(rgb_signal, float), np.asarray(rgb_times, float)
    b, tb = np.asarray(thermal_signal, float), np.asarray(thermal_times, float)
    counts = (int(np.isfinite(a).sum()), int(np.isfinite(b).sum()))
    if min(counts) < MIN_SIGNAL_SAMPLES:
        blank = [name for name, sig, c in (("RGB", a, counts[0]), ("thermal", b, counts[1]))
                 if c < MIN_SIGNAL_SAMPLES and len(sig) >= MIN_SIGNAL_SAMPLES]
        why = f"; the {' and '.join(blank)} frames are blank" if blank else ""
        raise RegistrationError(
            f"cannot synchronise: the time offset needs at least {MIN_SIGNAL_SAMPLES + 1} frames with content per "
            f"stream (got {counts[0] + 1} RGB, {counts[1] + 1} thermal){why}; use longer videos, or register "
            "without --sync"
        )
    step = max(min(frame_period(ta), frame_period(tb)), 1e-3)
    grid = np.arange(min(ta[0], tb[0]), max(ta[-1], tb[-1]) + step / 2, step)
    # remove the 1-s trend (lighting drift, gain changes), keep motion events
    ha, hb = _highpass(a, _samples_per_second(ta)), _highpass(b, _samples_per_second(tb))
    for name, h in (("RGB", ha), ("thermal", hb)):
        if np.nanstd(h) < 1e-4:
            raise RegistrationError(
                f"cannot synchronise: the {name} video shows no motion (static scene or frozen frames); "
                "register without --sync"
            )
    sa, sb = _on_grid(grid, ta, ha), _on_grid(grid, tb, hb)
    min_samples = max(MIN_SIGNAL_SAMPLES, int(0.5 * min(np.isfinite(sa).sum(), np.isfinite(sb).sum())))
    reach = max(1, len(grid) - min_samples)  # every lag that can overlap by min_samples (the rest would be NaN)
    corr, overlap = correlation_curve(sa, sb, reach, min_samples)
    z = _significance(corr, overlap, sa, sb, max(1, int(round(1.0 / step))))
    lags = np.arange(-reach, reach + 1) * step
    allowed = (np.abs(lags) <= max_offset + 1e-9) & np.isfinite(z)
    if not allowed.any():
        raise RegistrationError(
            f"cannot synchronise: the videos do not overlap in time for long enough within ±{max_offset:g} s"
        )
    k = int(np.argmax(np.where(allowed, z, -np.inf)))
    peak = float(corr[k])
    frac = 0.0
    if 0 < k < len(lags) - 1 and np.isfinite(corr[k - 1]) and np.isfinite(corr[k + 1]):
        den = corr[k - 1] - 2 * peak + corr[k + 1]
        if den < 0:
            frac = float(np.clip(0.5 * (corr[k - 1] - corr[k + 1]) / den, -0.5, 0.5))
    sep = int(np.ceil(separation / step))
    next_z = _next_peak(z, k, sep)
    runner_up = _next_peak(corr, k, sep)
    result = OffsetEstimate(float(lags[k] + frac * step), peak, runner_up, float(step), float(z[k]), next_z)
    advice = "the offset is not determinable from these clips: use clips with more motion that both cameras see"
    outside = np.isfinite(z) & ~allowed
    better = outside & (z >= z[k])
    if better.any():
        j = int(np.argmax(np.where(better, z, -np.inf)))
        raise RegistrationError(
            f"cannot synchronise: the motion matches better at {lags[j]:+.2f} s (correlation {corr[j]:.2f}) than "
            f"anywhere within ±{max_offset:g} s (best {peak:.2f} at {lags[k]:+.2f} s); pass a larger --max-offset "
            f"(e.g. {np.ceil(abs(lags[j]) + 1):g})"
        )
    if peak < min_correlation:
        raise RegistrationError(
            f"cannot synchronise: the motion in the two videos correlates too weakly (peak {peak:.2f} < "
            f"{min_correlation}); the scene may be static, or the videos show different moments; {advice}"
        )
    if abs(abs(lags[k]) - max_offset) <= max(separation, 2 * step) and outside.any():
        raise RegistrationError(
            f"cannot synchronise: the best match ({lags[k]:+.2f} s) lies at the edge of the searched "
            f"±{max_offset:g} s, so the true offset may be larger; pass a larger --max-offset "
            f"(e.g. {np.ceil(max_offset + 1):g})"
        )
    if z[k] < min_significance or (next_z > 0 and z[k] < min_ratio * next_z):
        raise RegistrationError(
            f"cannot synchronise: no clear motion peak (best {peak:.2f} at {result.offset:+.2f} s, z {z[k]:.1f}; "
            f"next peak {runner_up:.2f}, z {next_z:.1f}; need z >= {min_significance:g} and {min_ratio:g}x the "
            f"next); {advice}"
        )
    return result
