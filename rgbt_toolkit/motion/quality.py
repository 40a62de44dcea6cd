"""Reliability figures of a tracking response map: PSR and MAX-PSR (paper Eq. 4-5, after FCLT).

The paper defines ``PSR = (max R - mean R) / var R`` (the *variance*, as the authors' code also computes it) and the
reliability ``q = PSR * max R``. The FCLT tracker the paper cites, and most of the correlation-filter literature,
divide by the *standard deviation* instead. The two behave differently:

* variance form: ``q`` is invariant to the amplitude of ``R`` (scaling ``R`` by ``a`` scales the numerator and the
  denominator by ``a^2``), so it measures only the *shape* of the response: roughly the map's area over the peak's
  area. For an ideal Gaussian peak of standard deviation ``sigma`` cells on an ``M x N`` map, ``q = MN / (pi sigma^2)``.
* std form: ``q`` scales linearly with the amplitude of ``R``.

The switcher's thresholds (``q_hi = 210`` ...) are on the paper's variance-form scale; use :func:`max_psr` with the
default ``form="var"`` for them.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import InputError

PSR_FORMS = ("var", "std")


def _response(response) -> np.ndarray:
    if hasattr(response, "detach"):  # torch tensor
        response = response.detach().cpu().numpy()
    r = np.asarray(response, dtype=np.float64)
    if r.ndim < 2 or r.size < 2 or not np.all(np.isfinite(r)):
        raise InputError(f"response map must be a finite array of at least 2-D, got shape {r.shape}")
    return r


def psr(response, form: str = "var") -> float:
    """Peak-to-sidelobe ratio of a response map (all its elements; several scales may be stacked).

    Parameters
    ----------
    response : array_like or torch.Tensor
        The response map ``R`` (2-D, or stacked maps; every element counts).
    form : {"var", "std"}
        ``"var"``: ``(max - mean) / var`` (paper Eq. 5, authors' code). ``"std"``: ``(max - mean) / std`` (FCLT).

    Returns
    -------
    float
        The PSR; 0.0 for a constant map.
    """
    if form not in PSR_FORMS:
        raise InputError(f"unknown PSR form {form!r}; choose 'var' or 'std'")
    r = _response(response)
    spread = r.var() if form == "var" else r.std()
    if spread <= 0:
        return 0.0
    return float((r.max() - r.mean()) / spread)


def max_psr(response, form: str = "var") -> float:
    """MAX-PSR reliability ``q = PSR(R) * max(R)`` (paper Eq. 4); larger means a more reliable appearance result."""
    r = _response(response)
    return psr(r, form) * float(r.max())


def ideal_max_psr(shape: tuple[int, int], sigma: float) -> float:
    """``q`` of a noise-free unit Gaussian peak of std ``sigma`` cells on the central cell of a map of ``shape``.

    This is the best reliability a tracker with that response geometry can produce; its ratio between two trackers
    is the geometric part of putting their ``q`` values on a common scale (see :mod:`rgbt_toolkit.motion.switcher`).
    """
    if sigma <= 0 or min(shape) < 2:
        raise InputError(f"ideal_max_psr needs sigma > 0 and a map of at least 2x2, got {sigma}, {shape}")
    ys = np.arange(shape[0]) - shape[0] // 2
    xs = np.arange(shape[1]) - shape[1] // 2
    label = np.exp(-(ys[:, None] ** 2 + xs[None, :] ** 2) / (2.0 * sigma**2))
    return max_psr(label, "var")
