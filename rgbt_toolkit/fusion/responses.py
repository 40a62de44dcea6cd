"""Response sources for MFNet training: (training pair) -> (R_RGB, R_T) on a grid over the search patch.

The paper trains MFNet on the response maps of two ECO trackers. Training only needs *some* tracker whose response
fails in the way a degraded modality makes trackers fail, so the source is pluggable:

- :class:`DcfResponseSource` (default, cheap): a single-sample multi-channel discriminative correlation filter
  (MOSSE/KCF-style closed form) per modality on intensity/colour and gradient channels, learnt on the init patch and
  applied to the search patch. It is what the shipped weights were trained with.
- :class:`EcoResponseSource`: wraps ``rgbt_toolkit.eco.EcoTracker`` (``initialize(frame, box)``, ``predict(frame)``
  returning a ``TrackResult`` with ``response`` on the grid ``grid_origin + (j, i) * grid_step``), for training on
  real ECO responses as the paper does (``rgbt train-mfnet --source eco``; slower).

A source is any callable ``source(sample) -> (r_rgb, r_t)`` with a ``grid`` attribute ``(M, N)``; both maps are
float32 ``[M, N]`` covering the search patch, cell ``(i, j)`` centred at pixel ``((j + 0.5) * P / N, (i + 0.5) * P / M)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol

import cv2
import numpy as np

from rgbt_toolkit.fusion.trainset import Sample


class ResponseSource(Protocol):
    grid: tuple[int, int]

    def __call__(self, sample: Sample) -> tuple[np.ndarray, np.ndarray]: ...


def gaussian_label(box: np.ndarray, patch: int, grid: tuple[int, int], sigma_factor: float) -> np.ndarray:
    """Desired response ``Y``: a 2-D Gaussian (peak 1) at the box centre, sigma = sigma_factor * sqrt(w h)."""
    m, n = grid
    cx, cy = box[0] + box[2] / 2, box[1] + box[3] / 2
    sx, sy = patch / n, patch / m
    sigma = sigma_factor * np.sqrt(box[2] * box[3])
    xs = (np.arange(n) + 0.5) * sx
    ys = (np.arange(m) + 0.5) * sy
    gx = np.exp(-0.5 * ((xs - cx) / sigma) ** 2)
    gy = np.exp(-0.5 * ((ys - cy) / sigma) ** 2)
    return np.outer(gy, gx).astype(np.float32)


def _channels(patch: np.ndarray, grid: tuple[int, int]) -> np.ndarray:
    """DCF feature channels ``[C, M, N]``: normalised intensity (or colour) and x/y gradients, area-downsampled."""
    img = patch.astype(np.float32) / 255.0
    grey = cv2.cvtColor(img, cv2.COLOR_RGB2GRAY) if img.ndim == 3 else img
    gx = cv2.Sobel(grey, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(grey, cv2.CV_32F, 0, 1, ksize=3)
    chans = [img[:, :, c] for c in range(3)] if img.ndim == 3 else [grey]
    chans += [gx, gy, np.sqrt(gx * gx + gy * gy)]
    m, n = grid
    out = np.stack([cv2.resize(c, (n, m), interpolation=cv2.INTER_AREA) for c in chans])
    out -= out.mean(axis=(1, 2), keepdims=True)
    out /= out.reshape(len(out), -1).std(axis=1).reshape(-1, 1, 1) + 1e-3
    return out


@dataclass(frozen=True)
class DcfResponseSource:
    """Single-sample multi-channel correlation filter per modality (closed form, cosine window)."""

    grid: tuple[int, int] = (50, 50)  # stride 4 over a 200 px patch, like ECO's HOG cell
    patch: int = 200
    sigma_factor: float = 1.0 / 8.0  # label width for the filter (ECO: 1/12-1/16 of the target size)
    lam: float = 0.05  # ridge regularisation relative to the mean spectral energy

    def response(self, init_patch: np.ndarray, init_box: np.ndarray, search_patch: np.ndarray) -> np.ndarray:
        """Response of the filter learnt on ``init_patch`` (target in ``init_box``) over ``search_patch``."""
        m, n = self.grid
        window = np.outer(np.hanning(m + 2)[1:-1], np.hanning(n + 2)[1:-1]).astype(np.float32)
        x = np.fft.rfft2(_channels(init_patch, self.grid) * window)
        z = np.fft.rfft2(_channels(search_patch, self.grid) * window)
        y = np.fft.rfft2(gaussian_label(init_box, self.patch, self.grid, self.sigma_factor))
        energy = (x.real**2 + x.imag**2).sum(axis=0)
        filt = y * np.conj(x) / (energy + self.lam * energy.mean())
        return np.fft.irfft2((filt * z).sum(axis=0), s=(m, n)).astype(np.float32)

    def __call__(self, sample: Sample) -> tuple[np.ndarray, np.ndarray]:
        r_rgb = self.response(sample.init_rgb, sample.init_box, sample.search_rgb)
        r_t = self.response(sample.init_t, sample.init_box, sample.search_t)
        return r_rgb, r_t


class EcoResponseSource:
    """Responses of two ECO trackers (:mod:`rgbt_toolkit.eco`), resampled onto the training grid.

    Each tracker is initialised on the init patch and searches the search patch; its ``TrackResult.response`` lives on
    the grid ``grid_origin + (j, i) * grid_step`` (image pixels), which is resampled bilinearly at the centres of the
    training grid cells (zero outside the searched region).

    Parameters
    ----------
    make_tracker : callable, optional
        ``make_tracker(modality) -> tracker`` (``"rgb"`` or ``"t"``); default: ECO with ``preset_name`` on JMMAC's
        sample patch (the trackers whose responses MFNet fuses in ``rgbt track``).
    preset_name : str
        ECO preset for the default trackers.
    grid, patch : as :class:`DcfResponseSource`.
    """

    def __init__(self, make_tracker: Callable | None = None, preset_name: str = "hc",
                 grid: tuple[int, int] = (50, 50), patch: int = 200):
        if make_tracker is None:
            from rgbt_toolkit.eco import EcoTracker
            from rgbt_toolkit.jmmac.api import eco_params
            from rgbt_toolkit.jmmac.config import JmmacConfig

            params = eco_params(JmmacConfig(eco_preset=preset_name))  # the responses MFNet sees inside JMMAC
            make_tracker = lambda modality: EcoTracker(params)  # noqa: E731
        self.make_tracker, self.grid, self.patch = make_tracker, grid, patch

    def _one(self, modality: str, init: np.ndarray, box: np.ndarray, search: np.ndarray) -> np.ndarray:
        tracker = self.make_tracker(modality)
        tracker.initialize(init, np.asarray(box, dtype=np.float64))
        pred = tracker.predict(search)
        resp = np.asarray(pred.response, dtype=np.float32)
        m, n = self.grid
        origin, step = np.asarray(pred.grid_origin, dtype=np.float64), float(pred.grid_step)
        xs = ((np.arange(n) + 0.5) * self.patch / n - origin[0]) / step
        ys = ((np.arange(m) + 0.5) * self.patch / m - origin[1]) / step
        mx, my = np.meshgrid(xs.astype(np.float32), ys.astype(np.float32))
        return cv2.remap(resp, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)

    def __call__(self, sample: Sample) -> tuple[np.ndarray, np.ndarray]:
        return (
            self._one("rgb", sample.init_rgb, sample.init_box, sample.search_rgb),
            self._one("t", sample.init_t, sample.init_box, sample.search_t),
        )
