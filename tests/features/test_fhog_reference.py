"""fHOG's normalisation against a cell-by-cell transcription of Felzenszwalb et al. (PAMI 2010, Sec. 6.2 and
Piotr Dollar's fhog): the vectorised version must give the same 31 channels."""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.features.fhog import fhog_from_histograms


def _reference(hist: np.ndarray) -> np.ndarray:
    s, ny, nx, _ = hist.shape
    out = np.zeros((s, ny, nx, 31))
    h = hist.astype(np.float64)
    ins = h[..., :9] + h[..., 9:]
    energy = np.sum(ins**2, axis=-1)
    for i in range(s):
        for y in range(ny):
            for x in range(nx):
                e = lambda yy, xx: energy[i, min(max(yy, 0), ny - 1), min(max(xx, 0), nx - 1)]  # noqa: E731
                for k, (dy, dx) in enumerate(((-1, -1), (-1, 0), (0, -1), (0, 0))):
                    block = e(y + dy, x + dx) + e(y + dy + 1, x + dx) + e(y + dy, x + dx + 1) + e(y + dy + 1, x + dx + 1)
                    norm = 1.0 / np.sqrt(block + 1e-4)
                    sens = np.minimum(h[i, y, x] * norm, 0.2)
                    out[i, y, x, :18] += 0.5 * sens
                    out[i, y, x, 18:27] += 0.5 * np.minimum(ins[i, y, x] * norm, 0.2)
                    out[i, y, x, 27 + k] = 0.2357 * sens.sum()
    return out


def test_normalisation_matches_the_cell_by_cell_definition():
    rng = np.random.default_rng(4)
    hist = (rng.random((2, 5, 7, 18)) ** 3 * 3).astype(np.float32)
    hist[0, 2, 3] = 0  # an empty cell
    np.testing.assert_allclose(fhog_from_histograms(hist), _reference(hist), rtol=2e-5, atol=1e-6)
