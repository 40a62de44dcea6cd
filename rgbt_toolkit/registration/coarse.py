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
import scipy.fft as sfft

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
    fft_shape = (sfft.next_fast_len(hb), sfft.next_fast_len(wb))
    spectra_a = []
    for g in rgb_small:
        z = orientation_field(g)
        z = z[..., 0] + 1j * z[..., 1]
        z = (z - z.mean()).astype(np.complex64)
        spectra_a.append((np.conj(sfft.fft2(z, fft_shape)), float(np.sum(np.abs(z) ** 2))))
    ones_a = np.conj(sfft.rfft2(np.ones((h, w), np.float32), fft_shape))
    c_small = _centre((h, w))
    c_t = _centre(thermal[0].shape)
    def score_scale(scale: float):
        """Best shift per angle at one scale, and the sum / sum of squares / count of all finite scores."""
        found, total, total_sq, count = [], 0.0, 0.0, 0
        # thermal resized so that one of its pixels is one working RGB pixel at this scale
        ft = f / scale
        t_small = [resize_to(g, min(ft, 4.0)) for g in thermal]
        # orientation fields once per scale; each angle warps them and turns their doubled angle (see below)
        t_fields = [orientation_field(g) for g in t_small]
        ht, wt = t_small[0].shape
        ftx, fty = wt / thermal[0].shape[1], ht / thermal[0].shape[0]
        c_ts = c_t * [ftx, fty]
        for angle in angles:
            # B-domain pixel j <-> working RGB pixel j - (mx, my) <-> thermal (resized) by rotation about the centres
            turn = similarity(1.0, angle, c_small, c_ts)
            rot = turn @ np.array([[1, 0, -mx], [0, 1, -my], [0, 0, 1.0]])
            mask = cv2.warpAffine(np.ones((ht, wt), np.float32), rot[:2], (wb, hb),
                                  flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP)
            mask = cv2.erode(mask, np.ones((5, 5), np.uint8))
            area_b = float(mask.sum())
            if area_b < 16:
                continue
            inside = mask > 0
            numerator = np.zeros(fft_shape, np.float64)
            energy_a = energy_b = 0.0
            # sampling T at R x rotates gradients by -angle, i.e. the doubled-angle field by -2 angle
            turn_field = np.complex64(np.exp(-2j * angle))
            for (spec_a, e_a), t_field in zip(spectra_a, t_fields):
                zb = cv2.warpAffine(t_field, rot[:2], (wb, hb), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
                zb = (zb[..., 0] + 1j * zb[..., 1]) * turn_field
                zb = ((zb - zb[inside].mean()) * mask).astype(np.complex64)
                numerator += sfft.ifft2(spec_a * sfft.fft2(zb, fft_shape)).real
                energy_a += e_a
                energy_b += float(np.sum(np.abs(zb) ** 2))
            overlap = sfft.irfft2(ones_a * sfft.rfft2(mask, fft_shape), fft_shape)
            score = numerator / np.sqrt(energy_a * energy_b + 1e-12)
            score[overlap < min_overlap * min(h * w, area_b)] = -np.inf
            # only shifts within the margin are meaningful (the rest wraps around)
            score[2 * my + 1:, :] = -np.inf
            score[:, 2 * mx + 1:] = -np.inf
            finite = score[np.isfinite(score)]
            total += float(finite.sum())
            total_sq += float((finite * finite).sum())
            count += finite.size
            k = np.unravel_index(int(np.argmax(score)), score.shape)
            if not np.isfinite(score[k]):
                continue
            shift = np.array([[1, 0, k[1] - mx], [0, 1, k[0] - my], [0, 0, 1.0]])
            matrix = np.diag([1 / ftx, 1 / fty, 1.0]) @ turn @ shift @ np.diag([fx, fy, 1.0])
            found.append((float(score[k]), scale, angle, matrix))
        return found, total, total_sq, count

    # scales are independent: OpenCV and the FFTs release the GIL, so the configured threads share them
    workers = max(1, min(cv2.getNumThreads(), len(scales)))
    if workers > 1:
        with ThreadPoolExecutor(workers) as pool:
            per_scale = list(pool.map(score_scale, scales))
    else:
        per_scale = [score_scale(scale) for scale in scales]
    results = [r for found, *_ in per_scale for r in found]
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


def _close(a: np.ndarray, b: np.ndarray, size: tuple[int, int], fraction: float) -> bool:
    return corner_error(a, b, size) < fraction * max(size)
