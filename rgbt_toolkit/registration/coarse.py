"""Coarse global search for the RGB-to-thermal similarity transform.

Gradient-based refinement converges only from a few pixels away, while two real cameras can differ by a large
shift, a scale of 0.5-2x and a few degrees of roll. This module scans a grid of scales and rotations at a small
working size; for each it warps the thermal frame into the RGB frame and finds the best shift of the orientation
fields (``features.py``) at once for all shifts by FFT cross-correlation. Scores of several frame pairs are summed
before the peak is taken, so a video votes with all its sampled pairs.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import cv2
import numpy as np

from rgbt_toolkit.registration.features import orientation_field, resize_to
from rgbt_toolkit.registration.transforms import corner_error, similarity


@dataclass(frozen=True)
class Candidate:
    """One coarse hypothesis: its score (zero-mean orientation correlation) and RGB->T homography (full pixels)."""

    score: float
    matrix: np.ndarray
    scale: float
    angle: float
    z: float  # score in standard deviations above the mean of all scores searched (how far it stands out)


def _centre(shape: tuple[int, int]) -> np.ndarray:
    h, w = shape
    return np.array([(w - 1) / 2.0, (h - 1) / 2.0])


def coarse_search(
    rgb: list[np.ndarray],
    thermal: list[np.ndarray],
    scales: np.ndarray,
    angles: np.ndarray,
    *,
    work_size: int = 128,
    margin: float = 0.3,
    min_overlap: float = 0.25,
    keep: int = 3,
    second_pass: int = 6,
) -> list[Candidate]:
    """Best similarity hypotheses for grey RGB/thermal frame pairs (all pairs share one transform).

    Parameters
    ----------
    rgb, thermal : equally long lists of float32 grey frames; all RGB frames share one size, as do thermal ones.
    scales : thermal pixels per RGB pixel to try.
    angles : rotations (radians) to try.
    work_size : longer side of the RGB frame during the search, in pixels.
    margin : largest shift searched, as a fraction of the RGB frame size on each side.
    min_overlap : smallest overlap accepted, as a fraction of the smaller of the two (warped) frame areas.
    keep : number of distinct hypotheses returned (best first); distinct means more than 2 grid steps apart.
    second_pass : the first pass scores every other angle; the neighbours of its best ``2 * second_pass`` cells are
        scored next (about 60 % of the cost of the full grid, and as good on the registration benchmark).
    """
    h_full, w_full = rgb[0].shape
    f = work_size / max(h_full, w_full)
    rgb_small = [resize_to(g, f) for g in rgb]
    h, w = rgb_small[0].shape
    fx, fy = w / w_full, h / h_full
    mx, my = int(round(margin * w)), int(round(margin * h))
    hb, wb = h + 2 * my, w + 2 * mx
    # circular correlation on the padded domain is exact for shifts in [-margin, +margin]: A (h x w) shifted by
    # k in [0, 2 margin] stays inside the (h + 2 my) x (w + 2 mx) domain, so nothing wraps around
    fft_shape = (cv2.getOptimalDFTSize(hb), cv2.getOptimalDFTSize(wb))
    # the real part of the complex correlation is the sum of the two channels' real correlations, which real FFTs
    # (half the work of complex ones) give; the spectra of all pairs are summed before the one inverse transform.
    # OpenCV's packed real DFT: as fast as scipy.fft here, and importing scipy.fft took 0.35-0.85 s of `rgbt register`
    spectra_a = []
    for g in rgb_small:
        z = orientation_field(g)
        z = z - z.reshape(-1, 2).mean(0)
        spectra_a.append(([_spectrum(z[..., c], fft_shape) for c in range(2)], float(np.sum(z * z))))
    c_small = _centre((h, w))
    c_t = _centre(thermal[0].shape)
    fields_cache: dict[int, tuple] = {}

    def thermal_fields(k: int):
        """Thermal frames resized so that one of their pixels is one working RGB pixel at scale ``scales[k]``, as
        orientation fields (computed once per scale; each angle warps them and turns their doubled angle)."""
        if k not in fields_cache:
            ft = f / scales[k]
            t_small = [resize_to(g, min(ft, 4.0)) for g in thermal]
            fields_cache[k] = ([orientation_field(g) for g in t_small], t_small[0].shape)
        return fields_cache[k]

    def score_scale(k: int, angle_ids):
        """Best shift per angle at scale ``scales[k]``, and the sum / sum of squares / count of all finite scores."""
        scale = scales[k]
        found, total, total_sq, count = [], 0.0, 0.0, 0
        t_fields, (ht, wt) = thermal_fields(k)
        ftx, fty = wt / thermal[0].shape[1], ht / thermal[0].shape[0]
        c_ts = c_t * [ftx, fty]
        for a in angle_ids:
            angle = angles[a]
            # B-domain pixel j <-> working RGB pixel j - (mx, my) <-> thermal (resized) by rotation about the centres
            turn = similarity(1.0, angle, c_small, c_ts)
            rot = turn @ np.array([[1, 0, -mx], [0, 1, -my], [0, 0, 1.0]])
            mask = cv2.warpAffine(np.ones((ht, wt), np.float32), rot[:2], (wb, hb),
                                  flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP)
            mask = cv2.erode(mask, np.ones((5, 5), np.uint8))
            area_b = float(mask.sum())
            if area_b < 16:
                continue
            spectrum = None
            energy_a = energy_b = 0.0
            # sampling T at R x rotates gradients by -angle, i.e. the doubled-angle field by -2 angle
            c2, s2 = np.float32(np.cos(2 * angle)), np.float32(np.sin(2 * angle))
            for (spec_a, e_a), t_field in zip(spectra_a, t_fields):
                zb = cv2.warpAffine(t_field, rot[:2], (wb, hb), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
                re, im = zb[..., 0], zb[..., 1]
                channels = (c2 * re + s2 * im, c2 * im - s2 * re)
                for chan, spec in zip(channels, spec_a):
                    chan = chan * mask  # the mask is 0 / 1: mean over the thermal view without boolean indexing
                    chan -= (float(chan.sum()) / area_b) * mask
                    energy_b += float(np.sum(chan * chan))
                    term = cv2.mulSpectrums(_spectrum(chan, fft_shape), spec, 0, conjB=True)
                    spectrum = term if spectrum is None else spectrum + term
                energy_a += e_a
            # only shifts within the margin are meaningful (the rest wraps around)
            numerator = cv2.idft(spectrum, flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE)[: 2 * my + 1, : 2 * mx + 1]
            # shared area per shift: box sums of the thermal mask over the RGB frame's extent
            box = cv2.integral(mask, sdepth=cv2.CV_64F)
            overlap = box[h:, w:] - box[:-h, w:] - box[h:, :-w] + box[:-h, :-w]
            overlap = overlap[: 2 * my + 1, : 2 * mx + 1]
            score = numerator / np.sqrt(energy_a * energy_b + 1e-12)
            score[overlap < min_overlap * min(h * w, area_b)] = -np.inf
            finite = score[np.isfinite(score)]
            total += float(finite.sum())
            total_sq += float((finite * finite).sum())
            count += finite.size
            peak = np.unravel_index(int(np.argmax(score)), score.shape)
            if not np.isfinite(score[peak]):
                continue
            shift = np.array([[1, 0, peak[1] - mx], [0, 1, peak[0] - my], [0, 0, 1.0]])
            matrix = np.diag([1 / ftx, 1 / fty, 1.0]) @ turn @ shift @ np.diag([fx, fy, 1.0])
            found.append((float(score[peak]), k, a, matrix))
        return found, total, total_sq, count

    # Two passes over the angles: every other grid angle first, then the skipped neighbours of the best cells (the
    # score varies smoothly over one angle step, so a peak between two first-pass angles still ranks high there).
    # Scales are independent: OpenCV and the FFTs release the GIL, so the configured threads share them.
    workers = max(1, min(cv2.getNumThreads(), len(scales)))
    pool = ThreadPoolExecutor(workers) if workers > 1 else None
    run = pool.map if pool else map
    first = list(range(0, len(angles), 2))
    try:
        per_scale = list(run(score_scale, range(len(scales)), [first] * len(scales)))
        found = sorted((r for p in per_scale for r in p[0]), key=lambda r: -r[0])
        second: dict[int, set[int]] = {}
        for _, k, a, _ in found[: 2 * second_pass]:
            second.setdefault(k, set()).update(n for n in (a - 1, a + 1) if 0 <= n < len(angles) and n % 2)
        todo = sorted(second)
        per_scale += list(run(score_scale, todo, [sorted(second[k]) for k in todo]))
    finally:
        if pool:
            pool.shutdown()
    results = [(score, scales[k], angles[a], matrix) for p in per_scale for score, k, a, matrix in p[0]]
    total = sum(p[1] for p in per_scale)
    total_sq = sum(p[2] for p in per_scale)
    count = sum(p[3] for p in per_scale)
    results.sort(key=lambda r: -r[0])
    candidates: list[Candidate] = []
    mean = total / max(count, 1)
    std = np.sqrt(max(total_sq / max(count, 1) - mean * mean, 1e-12))
    for score, scale, angle, matrix in results:
        if any(_close(matrix, c.matrix, (w_full, h_full), 0.08) for c in candidates):
            continue
        candidates.append(Candidate(score, matrix, float(scale), float(angle), float((score - mean) / std)))
        if len(candidates) >= keep:
            break
    return candidates


def _spectrum(image: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Packed (CCS) real DFT of ``image`` zero-padded to ``shape``: linear, so spectra of several pairs add up."""
    padded = np.zeros(shape, np.float32)
    padded[: image.shape[0], : image.shape[1]] = image
    return cv2.dft(padded)


def _close(a: np.ndarray, b: np.ndarray, size: tuple[int, int], fraction: float) -> bool:
    return corner_error(a, b, size) < fraction * max(size)
