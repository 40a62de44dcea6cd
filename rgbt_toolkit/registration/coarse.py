"""Coarse global search for the RGB-to-thermal similarity transform.

Gradient-based refinement converges only from a few pixels away, while two real cameras can differ by a large
shift, a scale of 0.5-2x and a few degrees of roll. This module scans a grid of scales and rotations at a small
working size: the RGB orientation field (``features.py``) is turned once per angle and the thermal one resized once
per scale, each transformed to the Fourier domain once, and every (scale, angle) cell finds the best of all shifts at
once from one product of their spectra. Scores of several frame pairs are summed before the peak is taken, so a
video votes with all its sampled pairs.
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
    min_overlap : smallest overlap accepted, as a fraction of the smaller of the two (masked) frame areas.
    keep : number of distinct hypotheses returned (best first); distinct means more than 2 grid steps apart.
    second_pass : the first pass scores every other angle; the neighbours of its best ``2 * second_pass`` cells are
        scored next (about 60 % of the cost of the full grid, and as good on the registration benchmark).

    Notes
    -----
    The RGB field is turned once per angle and the thermal one resized once per scale, each with its spectrum, so a
    cell (scale, angle) costs only the products of two spectra and one inverse transform (a third of the time of
    warping the thermal field per cell: `rgbt register` on a 1280x1024 pair spent 60 % of its estimate here).
    """
    h_full, w_full = rgb[0].shape
    f = work_size / max(h_full, w_full)
    rgb_fields = [orientation_field(resize_to(g, f)) for g in rgb]
    h, w = rgb_fields[0].shape[:2]
    fx, fy = w / w_full, h / h_full
    mx, my = int(round(margin * w)), int(round(margin * h))
    # canvas holding the RGB view turned by any searched angle (centred), and the thermal domain: the canvas grown
    # by the margin on each side. Circular correlation on the padded domain is exact for shifts in [0, 2 margin]: the
    # canvas shifted by k stays inside the domain, so nothing wraps around
    spread = float(np.max(np.abs(angles))) if len(angles) else 0.0
    wg = int(np.ceil(w * np.cos(spread) + h * np.sin(spread)))
    hg = int(np.ceil(h * np.cos(spread) + w * np.sin(spread)))
    hd, wd = hg + 2 * my, wg + 2 * mx
    fft_shape = (cv2.getOptimalDFTSize(hd), cv2.getOptimalDFTSize(wd))
    c_small, c_g = _centre((h, w)), _centre((hg, wg))
    erode = np.ones((5, 5), np.uint8)

    def turned_rgb(a: int):
        """Spectra of the RGB fields turned by ``angles[a]`` into the canvas (zero-mean over their view), the
        view's integral image and area, and the fields' energy."""
        turn = similarity(1.0, angles[a], c_small, c_g)[:2]
        mask = cv2.erode(cv2.warpAffine(np.ones((h, w), np.float32), turn, (wg, hg), flags=cv2.INTER_NEAREST), erode)
        area = float(mask.sum())
        # turning an image by +angle turns its doubled-angle field by +2 angle
        c2, s2 = np.float32(np.cos(2 * angles[a])), np.float32(np.sin(2 * angles[a]))
        spectra, energy = [], 0.0
        for field in rgb_fields:
            zg = cv2.warpAffine(field, turn, (wg, hg), flags=cv2.INTER_LINEAR)
            re, im = zg[..., 0], zg[..., 1]
            chans = []
            for chan in (c2 * re - s2 * im, s2 * re + c2 * im):
                chan *= mask  # the mask is 0 / 1: mean over the view without boolean indexing
                chan -= (float(chan.sum()) / max(area, 1.0)) * mask
                energy += float(np.sum(chan * chan))
                chans.append(_spectrum(chan, fft_shape))
            spectra.append(chans)
        # float32 holds these whole-pixel counts exactly, and gathers from it are 10x faster than from float64
        return spectra, cv2.integral(mask, sdepth=cv2.CV_32F), area, energy

    def thermal_domain(k: int):
        """Spectra of the thermal fields resized so that one of their pixels is one working RGB pixel at scale
        ``scales[k]``, placed in the domain around its centre (zero-mean there); the placed rectangle, the offset
        (domain px = resized thermal px + offset), the resized size and the fields' energy."""
        ft = f / scales[k]
        t_small = [resize_to(g, min(ft, 4.0)) for g in thermal]
        ht, wt = t_small[0].shape
        offset = np.round(_centre((hd, wd)) - _centre((ht, wt))).astype(int)  # (x, y)
        x0, y0 = max(0, offset[0]), max(0, offset[1])
        x1, y1 = min(wd, offset[0] + wt), min(hd, offset[1] + ht)
        spectra, energy = [], 0.0
        for g in t_small:
            field = orientation_field(g)[y0 - offset[1]: y1 - offset[1], x0 - offset[0]: x1 - offset[0]]
            chans = []
            for c in range(2):
                part = field[..., c] - field[..., c].mean()
                energy += float(np.sum(part * part))
                placed = np.zeros(fft_shape, np.float32)
                placed[y0:y1, x0:x1] = part
                chans.append(cv2.dft(placed))
            spectra.append(chans)
        return spectra, (x0, y0, x1, y1), offset, (ht, wt), energy

    domain_cache: dict[int, tuple] = {}

    def thermal_once(k: int):
        if k not in domain_cache:  # each scale is handled by one thread at a time: no lock needed
            domain_cache[k] = thermal_domain(k)
        return domain_cache[k]

    ky, kx = np.arange(2 * my + 1), np.arange(2 * mx + 1)
    angle_cache: dict[int, tuple] = {}

    def score_scale(k: int, angle_ids):
        """Best shift per angle at scale ``scales[k]``, and the sum / sum of squares / count of all finite scores."""
        found, total, total_sq, count = [], 0.0, 0.0, 0
        t_spectra, (x0, y0, x1, y1), offset, (ht, wt), energy_b = thermal_once(k)
        area_b = float((x1 - x0) * (y1 - y0))
        if area_b < 16:
            return found, total, total_sq, count
        # canvas pixels u whose partner u + shift lies on the thermal rectangle: a box of the canvas per shift
        rows_0, rows_1 = np.clip(y0 - ky, 0, hg), np.clip(y1 - ky, 0, hg)
        cols_0, cols_1 = np.clip(x0 - kx, 0, wg), np.clip(x1 - kx, 0, wg)
        for a in angle_ids:
            a_spectra, box, area_a, energy_a = angle_cache[a]
            if area_a < 16:
                continue
            spectrum = None
            for t_chans, a_chans in zip(t_spectra, a_spectra):
                for spec_t, spec_a in zip(t_chans, a_chans):
                    term = cv2.mulSpectrums(spec_t, spec_a, 0, conjB=True)
                    spectrum = term if spectrum is None else spectrum + term
            # only the first 2 margin + 1 rows of the inverse are wanted: OpenCV then skips the others' column pass
            numerator = cv2.idft(spectrum, flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE,
                                 nonzeroRows=2 * my + 1)[: 2 * my + 1, : 2 * mx + 1]
            rows = box[rows_1] - box[rows_0]
            overlap = rows[:, cols_1] - rows[:, cols_0]
            score = numerator / np.sqrt(energy_a * energy_b + 1e-12)
            score[overlap < min_overlap * min(area_a, area_b)] = -np.inf
            finite = score[np.isfinite(score)]
            total += float(finite.sum())
            total_sq += float((finite * finite).sum())
            count += finite.size
            peak = np.unravel_index(int(np.argmax(score)), score.shape)
            if not np.isfinite(score[peak]):
                continue
            # canvas u = R (x - c) + c_g pairs with domain u + peak, i.e. resized thermal u + peak - offset
            turn = similarity(1.0, angles[a], c_small, c_g + np.array([peak[1], peak[0]]) - offset)
            matrix = np.diag([wt / thermal[0].shape[1], ht / thermal[0].shape[0], 1.0])
            matrix = np.linalg.inv(matrix) @ turn @ np.diag([fx, fy, 1.0])
            found.append((float(score[peak]), k, a, matrix))
        return found, total, total_sq, count

    def prepare(angle_ids) -> None:
        for a in angle_ids:
            if a not in angle_cache:
                angle_cache[a] = turned_rgb(a)

    # Two passes over the angles: every other grid angle first, then the skipped neighbours of the best cells (the
    # score varies smoothly over one angle step, so a peak between two first-pass angles still ranks high there).
    # Scales are independent: OpenCV and the FFTs release the GIL, so the configured threads share them.
    workers = max(1, min(cv2.getNumThreads(), len(scales)))
    pool = ThreadPoolExecutor(workers) if workers > 1 else None
    run = pool.map if pool else map
    first = list(range(0, len(angles), 2))
    try:
        prepare(first)
        per_scale = list(run(score_scale, range(len(scales)), [first] * len(scales)))
        found = sorted((r for p in per_scale for r in p[0]), key=lambda r: -r[0])
        second: dict[int, set[int]] = {}
        for _, k, a, _ in found[: 2 * second_pass]:
            second.setdefault(k, set()).update(n for n in (a - 1, a + 1) if 0 <= n < len(angles) and n % 2)
        todo = sorted(second)
        for k in [k for k in domain_cache if k not in second]:
            del domain_cache[k]  # spectra of scales not scored again (tens of MB for a video's pairs)
        prepare(sorted(set().union(*second.values())) if second else [])
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
