"""Human-perception metrics: Qcb (Chen-Blum), Qcv (Chen-Varshney) and pixel-domain VIF.

Qcb and Qcv follow Z. Liu's MATLAB (``metricChenBlum.m``, ``metricChen.m``) as VIFB ships them: images are
min-max stretched to rounded 0..255, contrast-sensitivity filters are applied in the centred frequency plane of
``freqspace``, and complex intermediate results are kept (MATLAB does) until a real score is taken.
"""

from __future__ import annotations

import numpy as np
from scipy import fft as sp_fft

from rgbt_toolkit.metrics._filters import as_float_image, check_same_shape, filter_valid, gaussian_kernel_1d, sobel_xy
from rgbt_toolkit.metrics.information import round_half_away


def _normalize1(image: np.ndarray) -> np.ndarray:
    """Z. Liu's ``normalize1``: min-max stretch to 0..255 and round (all-zero images pass unchanged)."""
    hi, lo = image.max(), image.min()
    if hi == 0 and lo == 0:
        return image.copy()
    with np.errstate(divide="ignore", invalid="ignore"):
        return round_half_away((image - lo) / (hi - lo) * 255.0)


def _freq_radius(shape: tuple[int, int], col_scale: float, row_scale: float) -> np.ndarray:
    """``r = sqrt(u^2 + v^2)`` on MATLAB's ``freqspace(shape, 'meshgrid')`` grid, scaled per axis."""
    rows, cols = shape
    u = (np.arange(cols) - cols // 2) * (2.0 / cols) * col_scale
    v = (np.arange(rows) - rows // 2) * (2.0 / rows) * row_scale
    return np.sqrt(u[None, :] ** 2 + v[:, None] ** 2)


def _filter_centred(image: np.ndarray, response: np.ndarray) -> np.ndarray:
    """``ifft2(ifftshift(fftshift(fft2(x)) .* H))`` with ``H`` defined on the centred grid; complex result."""
    return sp_fft.ifft2(sp_fft.fft2(image) * sp_fft.ifftshift(response))


def _chen_blum_kernels(shape: tuple[int, int]) -> tuple[tuple[int, int], list[np.ndarray]]:
    """Padded FFT size and spectra of ``metricChenBlum``'s unnormalised 31x31 Gaussians (sigma 2 and 4)."""
    x = np.arange(-15, 16, dtype=np.float64)
    size = (sp_fft.next_fast_len(shape[0] + 30), sp_fft.next_fast_len(shape[1] + 30))
    spectra = []
    for sigma in (2.0, 4.0):
        g = np.exp(-(x * x) / (2.0 * sigma * sigma))
        spectra.append(sp_fft.fft2(np.outer(g, g) / (2.0 * np.pi * sigma * sigma), s=size))
    return size, spectra


def _chen_blum_contrast(image: np.ndarray, kernels) -> np.ndarray:
    """``|filter2(G1, x, 'same') ./ filter2(G2, x, 'same') - 1|`` via one zero-padded FFT of ``x`` (linear, not
    circular, convolution: the padding is at least the kernel size)."""
    size, spectra = kernels
    rows, cols = image.shape
    spectrum = sp_fft.fft2(image, s=size)
    g1, g2 = (sp_fft.ifft2(spectrum * k)[15 : 15 + rows, 15 : 15 + cols] for k in spectra)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.abs(g1 / g2 - 1.0)


def qcb(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """Qcb (Chen & Blum 2009): contrast preservation after a DoG contrast-sensitivity filter, saliency-weighted."""
    check_same_shape(visible=a, infrared=b, fused=f)
    images = [_normalize1(as_float_image(x, name)) for x, name in ((a, "visible"), (b, "infrared"), (f, "fused"))]
    rows, cols = images[0].shape
    r = _freq_radius((rows, cols), cols / 30.0, rows / 30.0)
    sd = np.exp(-((r / 15.3870) ** 2)) - 0.7622 * np.exp(-((r / 1.3456) ** 2))
    cp = []
    kernels = _chen_blum_kernels((rows, cols))
    for image in images:
        contrast = _chen_blum_contrast(_filter_centred(image, sd), kernels)
        cp.append(contrast**3 / (contrast**2 + 0.0001))
    c1, c2, cf = cp
    with np.errstate(divide="ignore", invalid="ignore"):
        q1 = np.where(c1 < cf, c1 / cf, cf / c1)
        q2 = np.where(c2 < cf, c2 / cf, cf / c2)
        lam1 = c1 * c1 / (c1 * c1 + c2 * c2)
    return float(np.mean(lam1 * q1 + (1.0 - lam1) * q2))


def _block_reduce(values: np.ndarray, size: int, reducer) -> np.ndarray:
    """MATLAB ``blkproc(x, [size size], fun)``: zero-pad to whole blocks, apply ``reducer`` per block."""
    rows, cols = values.shape
    pr, pc = -rows % size, -cols % size
    padded = np.pad(values, ((0, pr), (0, pc)))
    blocks = padded.reshape(padded.shape[0] // size, size, padded.shape[1] // size, size)
    return reducer(blocks)


def qcv(a: np.ndarray, b: np.ndarray, f: np.ndarray, *, window: int = 16, alpha: float = 5.0) -> float:
    """Qcv (Chen & Varshney 2007): saliency-weighted CSF-filtered difference energy per 16x16 block.

    Lower is better. Mannos-Sakrison CSF, block saliency = sum of Sobel magnitude to the power ``alpha``.
    """
    check_same_shape(visible=a, infrared=b, fused=f)
    im1, im2, fused = (_normalize1(as_float_image(x, n)) for x, n in ((a, "visible"), (b, "infrared"), (f, "fused")))
    rows, cols = im1.shape
    saliency = []
    for image in (im1, im2):
        gx, gy = sobel_xy(image, pad="zero")
        g = np.sqrt(gx * gx + gy * gy)
        saliency.append(_block_reduce(g**alpha, window, lambda blk: blk.sum(axis=(1, 3))))
    r = _freq_radius((rows, cols), cols / 8.0, rows / 8.0)
    theta_m = 2.6 * (0.0192 + 0.144 * r) * np.exp(-((0.144 * r) ** 1.1))
    distortion = []
    for image in (im1, im2):
        filtered = _filter_centred(image - fused, theta_m)
        distortion.append(_block_reduce(filtered**2, window, lambda blk: blk.mean(axis=(1, 3))))
    lam1, lam2 = saliency
    d1, d2 = distortion
    q = np.sum(lam1 * d1 + lam2 * d2) / np.sum(lam1 + lam2)
    return float(np.real(q))


def _vif_pixel(ref: np.ndarray, dist: np.ndarray, sigma_nsq: float = 2.0) -> float:
    """Sheikh & Bovik's pixel-domain VIF (``vifp_mscale``): 4 scales of Gaussian windows."""
    num = den = 0.0
    for scale in range(1, 5):
        size = 2 ** (4 - scale + 1) + 1
        win = gaussian_kernel_1d(size, size / 5.0)
        if scale > 1:
            ref = filter_valid(ref, win)[::2, ::2]
            dist = filter_valid(dist, win)[::2, ::2]
        mu1, mu2 = filter_valid(ref, win), filter_valid(dist, win)
        s1 = np.maximum(filter_valid(ref * ref, win) - mu1 * mu1, 0.0)
        s2 = np.maximum(filter_valid(dist * dist, win) - mu2 * mu2, 0.0)
        s12 = filter_valid(ref * dist, win) - mu1 * mu2
        g = s12 / (s1 + 1e-10)
        sv = s2 - g * s12
        low1 = s1 < 1e-10
        g[low1] = 0.0
        sv[low1] = s2[low1]
        s1[low1] = 0.0
        low2 = s2 < 1e-10
        g[low2] = 0.0
        sv[low2] = 0.0
        neg = g < 0
        sv[neg] = s2[neg]
        g[neg] = 0.0
        sv[sv <= 1e-10] = 1e-10
        num += np.sum(np.log10(1.0 + g * g * s1 / (sv + sigma_nsq)))
        den += np.sum(np.log10(1.0 + s1 / sigma_nsq))
    return float(num / den) if den > 0 else float("nan")


def vif(a: np.ndarray, b: np.ndarray, f: np.ndarray) -> float:
    """VIF = VIFp(A, F) + VIFp(B, F), pixel-domain visual information fidelity (as in the SeAFusion family)."""
    check_same_shape(visible=a, infrared=b, fused=f)
    f = as_float_image(f, "fused")
    return _vif_pixel(as_float_image(a, "visible"), f) + _vif_pixel(as_float_image(b, "infrared"), f)
