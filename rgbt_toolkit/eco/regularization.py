"""Spatial regularisation window (SRDCF / C-COT / ECO) as a small filter in the Fourier domain.

The filter energy far from the target is penalised by ``||w . f||^2`` with a quadratic bowl
``w(t) = (edge - min) * (|t_y / (h/2)|^p + |t_x / (w/2)|^p) + min``. In the Fourier domain the product becomes a
convolution with the window's Fourier coefficients; with ``p = 2`` only a 3x3 (or so) neighbourhood of coefficients is
above the sparsity threshold, so ``W^H W f`` is two tiny convolutions (ECO's ``get_reg_filter``).
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit._native import load_compiled
from rgbt_toolkit.eco.fourier import full_from_half

_spectra = load_compiled("rgbt_toolkit.eco._spectra")


def reg_filter(support: int, target_hw: tuple[float, float], *, reg_min: float, reg_edge: float, power: float,
               sparsity: float) -> np.ndarray:
    """Small real, symmetric Fourier-domain filter of the regularisation window.

    Parameters
    ----------
    support : int
        Sample patch side in pixels (the period ``T``).
    target_hw : (float, float)
        Target height and width in patch pixels; the window equals ``edge`` at the target border.
    reg_min, reg_edge, power, sparsity
        ECO's ``reg_window_min``, ``reg_window_edge``, ``reg_window_power``, ``reg_sparsity_threshold``.
    """
    g = np.arange(support) - (support - 1) / 2
    sy, sx = 0.5 * target_hw[0], 0.5 * target_hw[1]
    window = (reg_edge - reg_min) * (np.abs(g[:, None] / sy) ** power + np.abs(g[None, :] / sx) ** power) + reg_min
    dft = np.fft.fft2(np.fft.ifftshift(window)).real / window.size  # symmetric window: real coefficients
    dft[np.abs(dft) < sparsity * np.abs(dft).max()] = 0.0
    sparse_window = np.fft.ifft2(dft).real * window.size
    dft[0, 0] += reg_min - sparse_window.min()  # keep the thresholded window's minimum at reg_min (ECO)
    dft = np.fft.fftshift(dft)
    rows = np.flatnonzero(np.any(dft != 0, axis=1))
    cols = np.flatnonzero(np.any(dft != 0, axis=0))
    r = max(abs(rows - support // 2).max(), abs(cols - support // 2).max())
    c = support // 2
    return dft[c - r : c + r + 1, c - r : c + r + 1]


def _conv_full(x: np.ndarray, k: np.ndarray) -> np.ndarray:
    """2-D full convolution of the last two axes of ``x`` with a small kernel ``k`` (shift-and-add)."""
    kh, kw = k.shape
    out = np.zeros(x.shape[:-2] + (x.shape[-2] + kh - 1, x.shape[-1] + kw - 1), dtype=x.dtype)
    for i in range(kh):
        for j in range(kw):
            if k[i, j] != 0:
                out[..., i : i + x.shape[-2], j : j + x.shape[-1]] += k[i, j] * x
    return out


def _conv_valid(x: np.ndarray, k: np.ndarray) -> np.ndarray:
    """2-D valid convolution of the last two axes (kernel flipped; ``k`` is symmetric here)."""
    kh, kw = k.shape
    h, w = x.shape[-2] - kh + 1, x.shape[-1] - kw + 1
    out = np.zeros(x.shape[:-2] + (h, w), dtype=x.dtype)
    for i in range(kh):
        for j in range(kw):
            if k[i, j] != 0:
                out += k[kh - 1 - i, kw - 1 - j] * x[..., i : i + h, j : j + w]
    return out


def apply_reg(fh: np.ndarray, reg: np.ndarray) -> np.ndarray:
    """``W^H W f`` for half-layout filter coefficients ``fh`` (..., Ny, Nxh): full conv, then valid conv.

    complex64 spectra go through the compiled loop (``_spectra.regularisation``), which gives
    :func:`apply_reg_numpy`'s numbers bit for bit: ECO's conjugate gradient applies this to every block on every
    iteration, 200 of them per tracker on the first frame, and numpy's shift-and-add of small arrays took 4x as long.
    """
    if fh.dtype != np.complex64 or fh.ndim < 2 or reg.ndim != 2 or not (reg.shape[0] % 2 and reg.shape[1] % 2):
        return apply_reg_numpy(fh, reg)  # reg_filter's windows are odd-sized; anything else keeps numpy's code
    ny, nxh = fh.shape[-2:]
    kernel = np.ascontiguousarray(reg, dtype=np.float32)
    out = np.empty(fh.shape, np.complex64)
    _spectra.regularisation(np.ascontiguousarray(fh), kernel, int(np.prod(fh.shape[:-2], dtype=np.int64)), ny, nxh,
                            kernel.shape[0], kernel.shape[1], out)
    return out


def apply_reg_numpy(fh: np.ndarray, reg: np.ndarray) -> np.ndarray:
    """:func:`apply_reg` in numpy, for any dtype: the reference of the compiled loop."""
    r = reg.shape[1] // 2
    nxh = fh.shape[-1]
    # only the columns kx >= -2r of the full spectrum influence the kx >= 0 half after two convolutions
    full = full_from_half(fh)[..., nxh - 1 - min(2 * r, nxh - 1) :]
    out = _conv_valid(_conv_full(full, reg.astype(fh.real.dtype)), reg.astype(fh.real.dtype))
    return out[..., -nxh:]
