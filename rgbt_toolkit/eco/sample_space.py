"""ECO's generative sample space: a Gaussian mixture of at most ``n`` components (ECO Sec. 3.2, eq. 7 / Alg. 1).

Each component is a (projected, Fourier) training sample with a prior weight. A new sample either fills an empty slot,
replaces a component whose weight has decayed below ``min_weight``, is merged into its nearest component, or - when the
two closest existing components are nearer to each other than the new sample is to any - those two are merged and the
new sample takes the freed slot. Distances are exact full-spectrum squared distances, kept up to date through the Gram
matrix so each frame costs one matrix-vector product: a merged component is a weighted mean, so its inner products are
the same weighted mean of its parts' (as ECO's ``update_distance_matrix``), and the new sample's are computed once.
At 50 components of ECO-hc's size the store is 10 MB; each product reads all of it.
"""

from __future__ import annotations

import numpy as np


class SampleSpace:
    """Components stored flat as a ``(n, L)`` complex array; :attr:`weights` are the priors (sum 1)."""

    def __init__(self, n: int, length: int, ip_weights: np.ndarray, learning_rate: float, min_weight: float,
                 dtype=np.complex64) -> None:
        self.samples = np.zeros((n, length), dtype=dtype)
        self.weights = np.zeros(n)
        self.gram = np.zeros((n, n))
        self.distance = np.full((n, n), np.inf)
        self.count = 0
        self._w = ip_weights.astype(np.float32).ravel()
        self.lr = learning_rate
        self.min_weight = min_weight

    def _gram_column(self, x: np.ndarray) -> np.ndarray:
        """Full-spectrum inner products ``<s_j, x>`` with every stored component.

        ``Re <s_j, x> = Re (s_j . conj(x w))``: conjugating the vector instead of the ``(n, L)`` matrix saves a copy
        of the whole sample store per call (2x faster, the same numbers)."""
        return (self.samples @ np.conj(x * self._w)).real.astype(np.float64)

    def _set(self, idx: int, x: np.ndarray, gram_col: np.ndarray, norm: float) -> None:
        """Store ``x`` at ``idx`` given its inner products with the current components (before storing)."""
        self.samples[idx] = x
        self.gram[idx, :] = gram_col
        self.gram[:, idx] = gram_col
        self.gram[idx, idx] = norm
        d = np.maximum(np.diag(self.gram) + norm - 2 * gram_col, 0.0)
        d[self.count :] = np.inf
        d[idx] = np.inf
        self.distance[idx, :] = d
        self.distance[:, idx] = d

    def _merge(self, x1: np.ndarray, w1: float, x2: np.ndarray, w2: float) -> np.ndarray:
        return ((w1 * x1 + w2 * x2) / (w1 + w2)).astype(self.samples.dtype)

    def add(self, x: np.ndarray) -> dict:
        """Insert one flat sample; returns ``{"replaced": idx or None, "merged": idx or None, "new": idx or None}``."""
        n = len(self.weights)
        lr = self.lr
        col = self._gram_column(x)
        norm = float(np.sum(self._w * (np.abs(x) ** 2)))
        info = {"new": None, "merged": None}
        if self.count < n:
            idx = self.count
            self.count += 1
            if idx == 0:
                self.weights[0] = 1.0
            else:
                self.weights *= 1 - lr
                self.weights[idx] = lr
            self._set(idx, x, col, norm)
            info["new"] = idx
        else:
            low = int(np.argmin(self.weights))
            if self.weights[low] < self.min_weight:
                self.weights[low] = 0.0
                self.weights *= (1 - lr) / self.weights.sum()
                self.weights[low] = lr
                self._set(low, x, col, norm)
                info["new"] = low
            else:
                dist_new = np.maximum(np.diag(self.gram) + norm - 2 * col, 0.0)
                nearest = int(np.argmin(dist_new))
                pair = np.unravel_index(int(np.argmin(self.distance)), self.distance.shape)
                self.weights *= 1 - lr
                if dist_new[nearest] < self.distance[pair]:
                    w_old = self.weights[nearest]
                    merged = self._merge(self.samples[nearest], w_old, x, lr)
                    self.weights[nearest] += lr
                    self._set(nearest, merged, *self._merged_products(nearest, w_old, col, norm, lr))
                    info["merged"] = nearest
                else:
                    a, b = int(pair[0]), int(pair[1])
                    if self.weights[a] < self.weights[b]:
                        a, b = b, a
                    w_a, w_b = self.weights[a], self.weights[b]
                    merged = self._merge(self.samples[a], w_a, self.samples[b], w_b)
                    self.weights[a] += w_b
                    self.weights[b] = lr
                    self._set(a, merged, *self._merged_products(a, w_a, self.gram[:, b].copy(), self.gram[b, b], w_b))
                    col[a] = (w_a * col[a] + w_b * col[b]) / (w_a + w_b)  # x against the merged component
                    self._set(b, x, col, norm)
                    info["merged"], info["new"] = a, b
        self.weights /= self.weights.sum()
        return info

    def _merged_products(self, idx: int, w1: float, other_col: np.ndarray, other_norm: float,
                         w2: float) -> tuple[np.ndarray, float]:
        """Inner products and norm of ``(w1 s_idx + w2 y) / (w1 + w2)`` from those of ``s_idx`` and ``y`` (whose
        products with the components are ``other_col``, with ``<s_idx, y> = other_col[idx]``)."""
        a1, a2 = w1 / (w1 + w2), w2 / (w1 + w2)
        col = a1 * self.gram[:, idx] + a2 * other_col
        norm = a1 * a1 * self.gram[idx, idx] + a2 * a2 * other_norm + 2 * a1 * a2 * other_col[idx]
        return col, float(norm)
