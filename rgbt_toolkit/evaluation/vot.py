"""VOT supervised (reset-based) experiment: accuracy, robustness and expected average overlap (EAO).

A VOT trajectory holds, per frame, a region or a marker: ``1`` the tracker was (re)initialised here, ``2`` it failed
here (no overlap with the ground truth), ``0`` the frame was skipped (the frames between a failure and the
re-initialisation ``skip_initialize`` frames later). The measures follow VOT's legacy MATLAB toolkit (version 7,
used for VOT2019-RGBT with ``stack_vot2019_rgbtir``: burn-in 10, re-initialisation 5 frames after a failure):

* accuracy ``A``: mean overlap over all valid frames of all sequences (pooled), ignoring marker frames and the
  ``burnin`` frames starting at every initialisation;
* robustness: failures per sequence; ``R`` as the VOT2019 report prints it is the reliability
  ``exp(-S * failures / frames)`` with ``S = 100`` (the JMMAC paper's R = 0.8235 is exp(-100 * 39 / 20083));
* EAO: every trajectory is cut into fragments, each starting at an initialisation; a fragment that ends in a failure
  is padded with zeros to the longest sequence length, the last one of a sequence is not. The expected overlap for
  length ``Ns`` averages, over fragments at least ``Ns`` long, the mean overlap of frames 2..Ns; EAO averages that
  curve over the interval ``[low, high]`` that holds half the density of the sequence lengths (kernel density
  estimate with Kristan's bandwidth, as the legacy ``gmm_estimate``).

Overlaps here are exact continuous polygon overlaps, optionally clipped to the image. The legacy toolkit rasterises
regions on the pixel grid (trax ``compute_polygon_overlap``); for regions with integer corners, as the VOT-RGBT
results and RGBT234-derived truths are, the pixel counts equal the exact areas, so the overlaps agree; fractional
corners can differ in the third decimal (the rasteriser truncates them).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from rgbt_toolkit.evaluation.polygons import region_overlaps
from rgbt_toolkit.io.boxes import VOT_FAILURE, VOT_INIT, VotEntry

__all__ = [
    "accuracy_overlaps",
    "eao_interval",
    "eao_score",
    "expected_overlap_curve",
    "failure_frames",
    "fragments",
    "region_overlaps",
    "reliability",
]


def _is_marker(entry: VotEntry, code: int) -> bool:
    return isinstance(entry, (int, np.integer)) and entry == code


def failure_frames(trajectory: Sequence[VotEntry]) -> np.ndarray:
    """0-based indices of the frames marked as failures (``2``)."""
    return np.array([i for i, e in enumerate(trajectory) if _is_marker(e, VOT_FAILURE)], dtype=int)


def burnin_mask(trajectory: Sequence[VotEntry], burnin: int) -> np.ndarray:
    """True on each initialisation frame and the ``burnin - 1`` frames after it."""
    n = len(trajectory)
    mask = np.zeros(n, dtype=bool)
    if burnin <= 0:
        return mask
    for i, e in enumerate(trajectory):
        if _is_marker(e, VOT_INIT):
            mask[i: i + burnin] = True
    return mask


def accuracy_overlaps(
    trajectory: Sequence[VotEntry],
    groundtruth: Sequence[VotEntry],
    burnin: int = 10,
    bounds: tuple[float, float] | None = None,
) -> np.ndarray:
    """Per-frame overlaps for accuracy: NaN on marker frames and in the burn-in after every initialisation."""
    return mask_burnin(region_overlaps(trajectory, groundtruth, bounds), trajectory, burnin)


def mask_burnin(overlaps: np.ndarray, trajectory: Sequence[VotEntry], burnin: int) -> np.ndarray:
    """A copy of ``overlaps`` with the burn-in frames after every initialisation set to NaN."""
    out = np.array(overlaps, dtype=float)
    out[burnin_mask(trajectory, burnin)[: len(out)]] = np.nan
    return out


def reliability(failures: float, frames: float, s: float = 100.0) -> float:
    """VOT reliability ``exp(-S * failures / frames)``: the chance of tracking S frames without failing."""
    return float(np.exp(-s * failures / frames))


def fragments(overlaps: np.ndarray, failures: np.ndarray, skip_initialize: int, length: int) -> np.ndarray:
    """Cut one trajectory's per-frame overlaps (no burn-in, NaN on markers) into EAO fragments.

    Returns a (F, length) array: a fragment that ends in a failure runs from its initialisation to the next
    initialisation (inclusive) and is zero-padded to ``length``; the last fragment is NaN beyond its end.
    """
    seg = np.asarray(overlaps, dtype=float)
    n = len(seg)
    restarts = [int(f) + skip_initialize for f in failures if int(f) + skip_initialize < n]
    points = [0] + restarts
    rows = []
    for start, stop in zip(points[:-1], points[1:]):
        row = np.zeros(length)
        o = np.nan_to_num(seg[start: stop + 1], nan=0.0)[:length]
        row[: len(o)] = o
        rows.append(row)
    row = np.full(length, np.nan)
    o = np.nan_to_num(seg[points[-1]:], nan=0.0)[:length]
    row[: len(o)] = o
    rows.append(row)
    return np.array(rows)


def expected_overlap_curve(frags: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Expected overlap for every sequence length 1..L from a (F, L) fragment array (index 0 is length 1).

    For length ``Ns`` the fragments not NaN at ``Ns`` are averaged (weighted) over frames 2..Ns; length 1 is 1.
    """
    f = np.asarray(frags, dtype=float)
    w = np.ones(len(f)) if weights is None else np.asarray(weights, dtype=float)
    n_len = f.shape[1]
    curve = np.ones(n_len)
    if n_len < 2:
        return curve
    tail = f[:, 1:]
    usable = ~np.isnan(tail)
    means = np.cumsum(np.nan_to_num(tail), axis=1) / np.arange(1, n_len)[None, :]
    weight = usable * w[:, None]
    total = weight.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        curve[1:] = np.where(total > 0, (means * weight).sum(axis=0) / np.where(total > 0, total, 1), np.nan)
    return curve


def _kristan_bandwidth(x: np.ndarray) -> float:
    """Variance of the Gaussian kernel for 1-D data, by Kristan's AMISE estimator (legacy ``gmm_estimate``)."""
    n = len(x)
    mu, var = x.mean(), x.var()
    if var <= 0:
        return 1.0
    z = (x - mu) / np.sqrt(var)  # sphered data, unit variance
    g = (4.0 / (3.0 * n)) ** (2.0 / 5.0)  # pilot bandwidth (variance)
    a = 1.0 / g
    m = (z[:, None] - z[None, :]) ** 2 * a
    f_t = np.sqrt(1.0 / (2.0 * np.pi)) * np.sqrt(a) * np.exp(-0.5 * m)
    c = 2.0 * a * a * (1.0 - 2.0 * m) + (1.0 - m) ** 2 * a * a
    rf2 = float((f_t * c).sum()) / n**2
    h_amise = (1.0 / n / (np.sqrt(4.0 * np.pi) * rf2)) ** (1.0 / 5.0)
    return h_amise**2 * var


def eao_interval(lengths: Sequence[int], density: float = 0.5) -> tuple[int, int, int]:
    """The sequence-length interval ``(low, high, peak)`` (1-based, inclusive) for averaging the EAO curve.

    A Gaussian kernel density of the sequence lengths is tabulated on 1..max(length); the interval grows from the
    peak, each step towards the denser side, until it holds ``density`` of the mass.
    """
    x = np.asarray(lengths, dtype=float)
    grid = np.arange(1, int(x.max()) + 1, dtype=float)
    h = _kristan_bandwidth(x)
    p = np.exp(-0.5 * (grid[:, None] - x[None, :]) ** 2 / h).sum(axis=1)
    p = p / p.sum()
    peak = int(np.argmax(p)) + 1
    low = high = peak
    size = len(p)
    for _ in range(size + 1):
        lo, hi = low - 1, high + 1
        at_lo, at_hi = lo <= 0, hi >= size
        lo, hi = max(lo, 1), min(hi, size)
        if at_lo and at_hi:
            low, high = lo, hi
            break
        if not at_lo and not at_hi:
            if p[lo - 1] > p[hi - 1]:
                low = lo
            else:
                high = hi
        elif not at_lo:
            low = lo
        else:
            high = hi
        if p[low - 1: high].sum() >= density:
            break
    return low, high, peak


def eao_score(curve: np.ndarray, low: int, high: int) -> float:
    """Mean of the expected-overlap curve over lengths ``low..high`` (1-based, inclusive), ignoring NaN."""
    part = np.asarray(curve, dtype=float)[low - 1: high]
    part = part[~np.isnan(part)]
    return float(part.mean()) if len(part) else float("nan")
