"""Cubic interpolation kernel of the continuous-domain formulation, in the Fourier domain.

ECO (Danelljan et al. 2017, Sec. 3, eq. 1, after C-COT) turns each discrete feature channel into a continuous periodic
function by convolving its samples with an interpolation kernel ``b``. In the Fourier domain this is a product with the
kernel's transform, so only :func:`interp_coefficients` is needed by the tracker. The kernel is Keys' cubic
convolution kernel with ``a = -0.75`` (the authors' setting) and the optional half-sample "centering" shift.
"""

from __future__ import annotations

import numpy as np

# 24-point Gauss-Legendre rule: the kernel is a cubic polynomial on [0, 1] and [1, 2], so kernel * cos is smooth there
# and 24 nodes integrate it to float64 precision for |f| <= 1 (checked in the tests against a 10^5-point Riemann sum).
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(24)


def cubic_kernel(t: np.ndarray, a: float = -0.75) -> np.ndarray:
    """Keys' cubic convolution kernel ``b(t)`` (support [-2, 2], b(0) = 1, b(n) = 0 at other integers)."""
    t = np.abs(np.asarray(t, dtype=np.float64))
    inner = (a + 2) * t**3 - (a + 3) * t**2 + 1
    outer = a * t**3 - 5 * a * t**2 + 8 * a * t - 4 * a
    return np.where(t <= 1, inner, np.where(t < 2, outer, 0.0))


def cubic_kernel_fourier(f: np.ndarray, a: float = -0.75) -> np.ndarray:
    """Continuous Fourier transform ``B(f) = int b(t) exp(-i 2 pi f t) dt`` of :func:`cubic_kernel` (real, even).

    Computed by Gauss-Legendre quadrature on the two polynomial pieces rather than a hand-expanded closed form:
    the kernel is even, so ``B(f) = 2 int_0^2 b(t) cos(2 pi f t) dt``.
    """
    f = np.asarray(f, dtype=np.float64)
    total = np.zeros_like(f)
    for lo in (0.0, 1.0):
        t = lo + 0.5 * (_GL_NODES + 1.0)  # nodes mapped to [lo, lo + 1]
        w = 0.5 * _GL_WEIGHTS
        vals = cubic_kernel(t, a) * w
        total += np.cos(2 * np.pi * f[..., None] * t).dot(vals)
    return 2.0 * total


def interp_coefficients(n: int, a: float = -0.75, centering: bool = True) -> np.ndarray:
    """Per-frequency factor that turns the DFT of ``n`` samples into Fourier-series coefficients of the interpolant.

    Parameters
    ----------
    n : int
        Number of samples along the axis (the feature map height or width).
    a : float
        Cubic kernel parameter (ECO / JMMAC: -0.75).
    centering : bool
        Shift the interpolant so the centre of the sample grid, index ``(n - 1) / 2``, sits at ``t = 0``. With it the
        target centre of a sample patch is the origin of the periodic domain, where the label peaks and the spatial
        regularisation window is lowest.

    Returns
    -------
    numpy.ndarray
        complex128 of length ``n_odd`` (``n`` made odd), for frequencies ``k = -(n_odd-1)/2 .. (n_odd-1)/2``:
        ``B(k / n) / n * exp(i 2 pi k c / n)``, ``c = (n - 1) / 2`` when centering, else 0.
    """
    n_odd = n + 1 - n % 2
    k = np.arange(n_odd) - (n_odd - 1) // 2
    coef = cubic_kernel_fourier(k / n, a) / n
    if centering:
        coef = coef * np.exp(1j * np.pi * k * (n - 1) / n)
    return coef.astype(np.complex128)
