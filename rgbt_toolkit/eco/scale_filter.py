"""Optional fDSST scale filter (Danelljan et al., "Discriminative Scale Space Tracking", PAMI 2017).

ECO's authors offer it as an alternative to searching scales inside the translation filter; the JMMAC code uses the
in-filter search (the default here). A one-dimensional correlation filter over ``n_scales`` fHOG samples of the
target at geometrically spaced sizes, compressed by a QR basis of the template, with the response interpolated to
``n_interp`` scales in the Fourier domain.
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.features.fhog import fhog_from_histograms, orientation_votes
from rgbt_toolkit.features.pooling import pixel_prefilter, sample_map

CELL = 4


class ScaleFilter:
    """State of the fDSST scale filter; ``estimate`` reads it, ``update`` learns."""

    def __init__(self, target_hw, *, n_scales: int = 17, n_interp: int = 33, step: float = 1.02,
                 sigma_factor: float = 1.0 / 16, reg: float = 1e-2, learning_rate: float = 0.025,
                 max_area: float = 32.0 * 16.0) -> None:
        self.n, self.n_interp, self.reg, self.lr = n_scales, n_interp, reg, learning_rate
        half = (n_scales - 1) // 2
        exps = (np.arange(n_scales) - half) * n_interp / n_scales
        sigma = n_interp * sigma_factor
        self.label_f = np.fft.fft(np.exp(-0.5 * np.roll(exps, -half) ** 2 / sigma**2))
        self.factors = step**exps  # 17 samples spanning the 33 interpolated steps
        ih = (n_interp - 1) // 2
        self.interp_factors = step ** np.roll(np.arange(n_interp) - ih, -ih)
        self.window = np.hanning(n_scales + 2)[1:-1]
        h, w = float(target_hw[0]), float(target_hw[1])
        f = min(1.0, np.sqrt(max_area / (h * w)))
        self.model_hw = (max(2 * CELL, int(round(h * f / CELL)) * CELL), max(2 * CELL, int(round(w * f / CELL)) * CELL))
        self.num = None

    def _samples(self, frame: np.ndarray, center_yx, target_hw) -> np.ndarray:
        """``(D, n_scales)`` fHOG columns of the target region at each scale, resized to the model size."""
        mh, mw = self.model_hw
        cols = []
        for f in self.factors:
            sy, sx = target_hw[0] * f / mh, target_hw[1] * f / mw
            m = np.array([[sx, 0.0, center_yx[1] - (mw - 1) / 2 * sx], [0.0, sy, center_yx[0] - (mh - 1) / 2 * sy]])
            patch = cv2.warpAffine(frame, m, (mw, mh), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                   borderMode=cv2.BORDER_REPLICATE)
            votes = pixel_prefilter(orientation_votes(patch))
            cy = CELL * np.arange(mh // CELL) + (CELL - 1) / 2
            cx = CELL * np.arange(mw // CELL) + (CELL - 1) / 2
            cols.append(sample_map(votes, 1, cy[None], cx[None]))
        hog = fhog_from_histograms(np.concatenate(cols))
        return hog.reshape(self.n, -1).T.astype(np.float64)

    def _project(self, x: np.ndarray, basis: np.ndarray) -> np.ndarray:
        return np.fft.fft((basis.T @ x) * self.window[None], axis=1)

    def initialize(self, frame: np.ndarray, center_yx, target_hw) -> None:
        """Learn the first scale model at ``center_yx`` for a target of ``target_hw`` image pixels."""
        self.num = None
        self.update(frame, center_yx, target_hw)

    def estimate(self, frame: np.ndarray, center_yx, target_hw) -> float:
        """Relative scale change (multiply the target size by it); the model is not changed."""
        xs = self._samples(frame, center_yx, target_hw)
        xf = self._project(xs, self.basis)
        resp_f = np.sum(self.num_f * xf, axis=0) / (self.den + self.reg)
        # zero-pad the spectrum to n_interp samples (trigonometric interpolation of the response)
        half = (self.n + 1) // 2
        padded = np.zeros(self.n_interp, complex)
        padded[:half] = resp_f[:half]
        padded[-(self.n - half):] = resp_f[half:]
        resp = np.fft.ifft(padded).real
        return float(self.interp_factors[int(np.argmax(resp))])

    def update(self, frame: np.ndarray, center_yx, target_hw) -> None:
        """Running-average template and denominator with learning rate ``learning_rate`` (fDSST)."""
        xs = self._samples(frame, center_yx, target_hw)
        first = self.num is None
        self.num = xs if first else (1 - self.lr) * self.num + self.lr * xs
        self.basis = np.linalg.qr(self.num)[0]
        basis_den = np.linalg.qr(xs)[0]
        self.num_f = self.label_f[None] * np.conj(self._project(self.num, self.basis))
        xf = self._project(xs, basis_den)
        den = np.sum((xf * np.conj(xf)).real, axis=0)
        self.den = den if first else (1 - self.lr) * self.den + self.lr * den
