"""The normal equations ECO solves, as operators for :func:`rgbt_toolkit.eco.cg.pcg`.

Notation (per feature block ``d``, half Fourier layout): ``X_d`` interpolated feature coefficients ``(D, Ny, Nxh)``,
``P_d`` the projection ``(D, C)``, ``Z_d = P_d^T X_d`` the compressed sample ``(C, Ny, Nxh)``, ``F_d`` the filter
``(C, Ny, Nxh)``. The score is ``S = sum_d pad(sum_c F_dc Z_dc)`` on the largest block's frequencies, the label ``Y``.

- :func:`filter_lhs` / :func:`filter_rhs`: ``sum_j w_j |S_j - Y|^2 + sum_d ||w . f_d||^2`` over the GMM components
  (ECO eq. 8; the projection is fixed), used every ``train_gap`` frames.
- :func:`joint_lhs` / :func:`joint_rhs`: one Gauss-Newton step of the factorised problem on the first frame (ECO
  eq. 4-6): unknowns ``F`` and ``dP``, linearised as ``S(F, P) + S(F0, dP)``, with ``lambda ||P + dP||^2``.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit._native import load_compiled
from rgbt_toolkit.eco.fourier import half_weights
from rgbt_toolkit.eco.regularization import apply_reg

_spectra = load_compiled("rgbt_toolkit.eco._spectra")


def _pad_add(acc: np.ndarray, part: np.ndarray) -> None:
    """Add a smaller half-layout array into the centre rows / first columns of ``acc`` in place."""
    py = (acc.shape[-2] - part.shape[-2]) // 2
    acc[..., py : py + part.shape[-2], : part.shape[-1]] += part


def _crop(acc: np.ndarray, ny: int, nxh: int) -> np.ndarray:
    py = (acc.shape[-2] - ny) // 2
    return acc[..., py : py + ny, :nxh]


def filter_inner(a: list, b: list) -> float:
    """Full-spectrum inner product of two lists of half-layout filter blocks."""
    total = 0.0
    for x, y in zip(a, b):
        p = np.conj(x) * y
        total += 2.0 * p.real.sum() - p[..., 0].real.sum()
    return float(total)


def joint_inner(a: list, b: list, n_blocks: int) -> float:
    """Inner product of ``[F_1..F_n, dP_1..dP_n]`` vectors: Fourier part full-spectrum, projection part Euclidean."""
    total = filter_inner(a[:n_blocks], b[:n_blocks])
    for x, y in zip(a[n_blocks:], b[n_blocks:]):
        total += float(np.sum(x * y))
    return total


def _both_complex64(*arrays: np.ndarray) -> bool:
    return all(a.dtype == np.complex64 for a in arrays)


def channel_products(z: np.ndarray, f: np.ndarray) -> np.ndarray:
    """``(z * f).sum(axis=-3)``: ``z`` ``(..., C, Ny, Nxh)`` against ``f`` ``(C, Ny, Nxh)``; compiled for complex64
    (one pass, no temporary, GIL released; the same numbers as numpy)."""
    if not _both_complex64(z, f) or z.shape[-3:] != f.shape:
        return (z * f).sum(axis=-3)
    c, ny, nxh = f.shape
    lead = z.shape[:-3]
    out = np.empty(lead + (ny, nxh), np.complex64)
    _spectra.channel_products(np.ascontiguousarray(z), np.ascontiguousarray(f), int(np.prod(lead)), c, ny * nxh, out)
    return out


def sample_backprojection(z: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``(conj(z) * p[:, None]).sum(axis=0)``: ``z`` ``(n, C, Ny, Nxh)``, ``p`` ``(n, Ny, Nxh)``; compiled for
    complex64 as :func:`channel_products`."""
    if not _both_complex64(z, p) or z.ndim != 4 or p.shape != z.shape[:1] + z.shape[2:]:
        return (np.conj(z) * p[:, None]).sum(axis=0)
    n, c, ny, nxh = z.shape
    out = np.empty((c, ny, nxh), np.complex64)
    _spectra.sample_backprojection(np.ascontiguousarray(z), np.ascontiguousarray(p), n, c, ny * nxh, out)
    return out


def scores(F: list, Z: list, out_shape: tuple[int, int]) -> np.ndarray:
    """``S = sum_d pad(sum_c F_dc Z_dc)``; ``Z_d`` may carry leading sample/scale axes before ``C``."""
    lead = Z[0].shape[:-3]
    acc = np.zeros(lead + out_shape, dtype=np.result_type(Z[0], F[0]))
    for f, z in zip(F, Z):
        _pad_add(acc, channel_products(z, f))
    return acc


def filter_rhs(Z: list, weights: np.ndarray, labels: list) -> list:
    """``sum_j w_j conj(Z_j) Y`` per block."""
    return [np.conj(np.tensordot(weights.astype(z.real.dtype), z, axes=1)) * y for z, y in zip(Z, labels)]


def filter_lhs(F: list, Z: list, weights: np.ndarray, regs: list, out_shape: tuple[int, int]) -> list:
    """``sum_j w_j Z_j^H (Z_j F) + W^H W F`` per block; ``Z_d`` has shape ``(n_samples, C, Ny, Nxh)``."""
    sh = scores(F, Z, out_shape)
    sh *= weights.astype(sh.real.dtype)[:, None, None]
    out = []
    for f, z, reg in zip(F, Z, regs):
        part = _crop(sh, *f.shape[-2:])
        out.append(sample_backprojection(z, part) + apply_reg(f, reg))
    return out


def project(P: list, X: list) -> list:
    """Compressed coefficients ``Z_d = P_d^T X_d`` (leading axes of ``X_d`` before ``D`` are kept)."""
    return [_mix(p, x) for p, x in zip(P, X)]


def _mix(p: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``p^T x`` over the channel axis (-3) of ``x``: ``(..., D, Ny, Nxh) -> (..., C, Ny, Nxh)``."""
    d, ny, nxh = x.shape[-3:]
    flat = x.reshape(x.shape[:-3] + (d, ny * nxh))
    out = np.matmul(p.T.astype(x.dtype), flat)
    return out.reshape(x.shape[:-3] + (p.shape[1], ny, nxh))


def _proj_grad(X: np.ndarray, G: np.ndarray) -> np.ndarray:
    """``Re sum_k w_k conj(X_dk) G_ck`` over the full spectrum: the ``(D, C)`` gradient block."""
    w = half_weights(*X.shape[-2:], dtype=X.real.dtype)
    xw = (np.conj(X) * w).reshape(X.shape[0], -1)
    return (xw @ G.reshape(G.shape[0], -1).T).real


def joint_lhs(v: list, X: list, Z: list, F0: list, regs: list, out_shape: tuple[int, int], proj_reg: float) -> list:
    """``J^H J [F; dP] + [W^H W F; lambda dP]`` for one sample (no sample axis)."""
    n = len(X)
    F, dP = v[:n], v[n:]
    sh = scores(F, Z, out_shape)
    for f0, x, dp in zip(F0, X, dP):
        _pad_add(sh, np.sum(f0 * _mix(dp, x), axis=0))
    out_f, out_p = [], []
    for f, f0, x, z, reg, dp in zip(F, F0, X, Z, regs, dP):
        part = _crop(sh, *f.shape[-2:])
        out_f.append(np.conj(z) * part + apply_reg(f, reg))
        out_p.append(_proj_grad(x, np.conj(f0) * part) + proj_reg * dp)
    return out_f + out_p


def joint_rhs(X: list, Z: list, F0: list, P: list, labels: list, proj_reg: float) -> list:
    """Right-hand side ``J^H Y - [0; lambda P]`` of the Gauss-Newton step."""
    out_f = [np.conj(z) * y for z, y in zip(Z, labels)]
    out_p = [_proj_grad(x, np.conj(f0) * y) - proj_reg * p for x, f0, y, p in zip(X, F0, labels, P)]
    return out_f + out_p


def preconditioner(sample_energy: list, reg_energy: list, data_param: float, reg_param: float) -> list:
    """ECO's diagonal preconditioner of the filter part (``precond_data_param``, ``precond_reg_param``)."""
    out = []
    for m, re in zip(sample_energy, reg_energy):
        mix = data_param * m + (1 - data_param) * m.mean(axis=0, keepdims=True)
        out.append((1 - reg_param) * mix + reg_param * re)
    return out


def pca_projection(features: np.ndarray, dim: int) -> np.ndarray:
    """Initial projection ``(D, dim)``: the leading principal directions of the ``(N, D)`` feature vectors."""
    centred = features - features.mean(axis=0, keepdims=True)
    cov = centred.T @ centred
    u, _, _ = np.linalg.svd(cov)
    return u[:, :dim].astype(np.float32)
