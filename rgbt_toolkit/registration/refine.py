"""Sub-pixel refinement: enhanced correlation coefficient (ECC) maximisation on orientation fields.

ECC (Evangelidis & Psarakis, IEEE TPAMI 2008) maximises the zero-mean normalised correlation between a template and a
warped image, which makes it blind to gain and offset between the two. Here template and image are the two-channel
doubled-angle orientation fields of the RGB and thermal frames (``features.py``), so contrast reversal and unequal
edge strength between the modalities do not matter. Several frame pairs can be stacked: they share one transform and
the correlation is taken over all of their samples, which is the robust aggregation over a video.

The thermal field is sampled only at a grid of RGB sample points (``stride``), through ``cv2.remap``; its gradient
is precomputed once per level. Rotating an image by phi rotates its doubled-angle field by 2 phi; the warped thermal
channels are rotated back by the current estimate's angle so that the two fields stay comparable.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from rgbt_toolkit.registration.transforms import parameter_basis

MIN_SAMPLES = 200  # fewer overlapping samples (over all frame pairs) than this cannot constrain eight parameters


@dataclass(frozen=True)
class LevelResult:
    """Outcome of ECC at one pyramid level: the refined matrix (level pixels), its correlation and overlap."""

    matrix: np.ndarray
    correlation: float
    overlap: float  # fraction of RGB samples whose match lies inside the thermal frame
    iterations: int
    converged: bool


def _normaliser(shape: tuple[int, int]) -> np.ndarray:
    """Map pixel coordinates to about [-1, 1] around the frame centre (conditions the normal equations)."""
    h, w = shape
    s = max(h, w) / 2.0
    return np.array([[1 / s, 0, -(w - 1) / (2 * s)], [0, 1 / s, -(h - 1) / (2 * s)], [0, 0, 1.0]])


def _as_map(values: np.ndarray, width: int = 1024) -> np.ndarray:
    """Pack coordinates into a (rows, width) float32 map: cv2.remap limits each side to 32767."""
    rows = -(-len(values) // width)
    out = np.zeros(rows * width, np.float32)
    out[: len(values)] = values
    return out.reshape(rows, width)


def thermal_stack(field: np.ndarray) -> np.ndarray:
    """Field and its x/y derivatives as one (H, W, 6) array for a single remap per iteration.

    Callers refining several times at one level compute it once and pass it as the thermal "field".
    """
    if field.shape[2] == 6:
        return field
    gx = cv2.Sobel(field, cv2.CV_32F, 1, 0, ksize=3, scale=1 / 8)
    gy = cv2.Sobel(field, cv2.CV_32F, 0, 1, ksize=3, scale=1 / 8)
    return np.concatenate([field, gx, gy], axis=2)


def _normalised_problem(rgb_fields: list[np.ndarray], thermal_fields: list[np.ndarray], matrix: np.ndarray):
    """Both views' sizes, their normalising matrices, the thermal half-size and ``matrix`` in normalised coordinates
    (conditioned so one step size suits every parameter)."""
    h_a, w_a = rgb_fields[0].shape[:2]
    h_t, w_t = thermal_fields[0].shape[:2]
    n_a, n_t = _normaliser((h_a, w_a)), _normaliser((h_t, w_t))
    hn = n_t @ matrix @ np.linalg.inv(n_a)
    return (h_a, w_a), (h_t, w_t), n_a, n_t, max(h_t, w_t) / 2.0, hn / hn[2, 2]


def correlation_at(rgb_fields: list[np.ndarray], thermal_fields: list[np.ndarray], matrix: np.ndarray, *,
                   stride: int = 1, border: float = 2.0) -> float:
    """Zero-mean correlation of the orientation fields at ``matrix`` (level pixels), as :func:`ecc_refine` measures
    it before its first step (-1 when too few samples overlap), without the Jacobian: about half its cost, for
    scoring fixed transforms (the peak ratio's shifted copies)."""
    (h_a, w_a), (h_t, w_t), n_a, n_t, s_t, hn = _normalised_problem(rgb_fields, thermal_fields, matrix)
    ys, xs = np.mgrid[0:h_a:stride, 0:w_a:stride]
    u = (xs.ravel() - (w_a - 1) / 2) * n_a[0, 0]
    v = (ys.ravel() - (h_a - 1) / 2) * n_a[0, 0]
    _, _, _, xt, yt, valid = _positions(hn, u, v, (h_t, w_t), s_t, border)
    n_valid = int(valid.sum())
    if n_valid * len(rgb_fields) < MIN_SAMPLES:
        return -1.0
    rows, cols = ys.ravel()[valid], xs.ravel()[valid]
    map_x, map_y = _as_map(xt[valid]), _as_map(yt[valid])
    angle = np.arctan2(hn[1, 0] - hn[0, 1], hn[0, 0] + hn[1, 1])
    c2, s2 = np.cos(2 * angle), np.sin(2 * angle)
    img_parts, tpl_parts = [], []
    for rgb, thermal in zip(rgb_fields, thermal_fields):
        sampled = cv2.remap(thermal, map_x, map_y, cv2.INTER_LINEAR).reshape(-1, thermal.shape[2])[:n_valid]
        re, im = sampled[:, 0], sampled[:, 1]
        tpl = rgb[rows, cols]
        for c, img in enumerate((c2 * re + s2 * im, -s2 * re + c2 * im)):
            img_parts.append(img - img.mean())
            tpl_parts.append(tpl[:, c] - tpl[:, c].mean())
    img, tpl = np.concatenate(img_parts), np.concatenate(tpl_parts)
    corr = float(img.astype(np.float64) @ tpl)
    return corr / (float(np.linalg.norm(img)) * float(np.linalg.norm(tpl)) + 1e-12)


def _positions(hn: np.ndarray, u: np.ndarray, v: np.ndarray, shape_t: tuple[int, int], s_t: float, border: float):
    """Thermal positions of the normalised RGB samples (u, v) under ``hn``: the projective denominator, normalised
    and pixel coordinates, and which samples land inside the thermal frame (``border`` px from its edge)."""
    h_t, w_t = shape_t
    den = hn[2, 0] * u + hn[2, 1] * v + 1.0
    xn = (hn[0, 0] * u + hn[0, 1] * v + hn[0, 2]) / den
    yn = (hn[1, 0] * u + hn[1, 1] * v + hn[1, 2]) / den
    xt = xn * s_t + (w_t - 1) / 2
    yt = yn * s_t + (h_t - 1) / 2
    valid = (den > 1e-6) & (xt >= border) & (yt >= border) & (xt <= w_t - 1 - border) & (yt <= h_t - 1 - border)
    return den, xn, yn, xt, yt, valid


def ecc_refine(
    rgb_fields: list[np.ndarray],
    thermal_fields: list[np.ndarray],
    matrix: np.ndarray,
    model: str,
    *,
    iterations: int = 30,
    tolerance: float = 0.02,
    stride: int = 1,
    border: float = 2.0,
    anchor: np.ndarray | None = None,
    stiffness: float = 0.0,
) -> LevelResult:
    """Maximise the correlation of orientation fields over the parameters of ``model``, starting at ``matrix``.

    Parameters
    ----------
    rgb_fields, thermal_fields : (H, W, 2) orientation fields of the frame pairs at this level (one size per side);
        thermal ones may be given as :func:`thermal_stack` of the field.
    matrix : starting RGB->T homography in this level's pixels.
    model : "similarity", "affine" or "homography".
    tolerance : stop when an update moves points by less than about this many thermal pixels.
    stride : sample every ``stride``-th RGB pixel in each direction.
    border : thermal samples closer than this to the frame edge are dropped (their interpolation is incomplete).
    anchor, stiffness : a Tikhonov prior pulling every entry but the shift towards ``anchor`` (level pixels), with
        ``stiffness`` times the mean curvature of the data term. Real scenes are not planar: with a free homography
        the best fit depends on which part of the scene is in view, and extrapolates badly; the prior keeps the
        extra parameters for what the data clearly demand.
    """
    (h_a, w_a), (h_t, w_t), n_a, n_t, s_t, hn = _normalised_problem(rgb_fields, thermal_fields, matrix)
    basis = parameter_basis(model)
    anchor_n = None
    if anchor is not None and stiffness > 0:
        anchor_n = n_t @ anchor @ np.linalg.inv(n_a)
        anchor_n = anchor_n / anchor_n[2, 2]
        free_shift = np.array([1, 1, 0, 1, 1, 0, 1, 1.0]) @ basis.T  # no pull on the two shift entries
    ys, xs = np.mgrid[0:h_a:stride, 0:w_a:stride]
    xs = xs.ravel().astype(np.float64)
    ys = ys.ravel().astype(np.float64)
    u = (xs - (w_a - 1) / 2) * n_a[0, 0]
    v = (ys - (h_a - 1) / 2) * n_a[0, 0]
    templates = [f[ys.astype(int), xs.astype(int)] for f in rgb_fields]
    u32, v32 = u.astype(np.float32), v.astype(np.float32)
    basis_t = basis.T.astype(np.float32)  # rows: the 8 homography entries
    basis_x, basis_y, basis_tail = basis_t[0:3], basis_t[3:6], basis_t[6:8]
    stacks = [thermal_stack(f) for f in thermal_fields]
    correlation, overlap, converged, it = -1.0, 0.0, False, 0
    for it in range(1, iterations + 1):
        den, xn, yn, xt, yt, valid = _positions(hn, u, v, (h_t, w_t), s_t, border)
        overlap = float(valid.mean())
        if valid.sum() * len(templates) < MIN_SAMPLES:  # one sample grid, shared by every frame pair
            return LevelResult(np.linalg.inv(n_t) @ hn @ n_a, -1.0, overlap, it, False)
        # derivatives of the (normalised) thermal position with respect to the model's parameters: d x_t / d h is
        # [u, v, 1, 0, 0, 0, -x u, -x v] / den (y alike), projected on the model's basis; float32 halves the cost
        inv = (1.0 / den[valid]).astype(np.float32)
        ui, vi = u32[valid] * inv, v32[valid] * inv
        head = np.stack([ui, vi, inv], 1)
        tail = np.stack([ui, vi], 1)
        dx = head @ basis_x - (xn[valid].astype(np.float32)[:, None] * tail) @ basis_tail
        dy = head @ basis_y - (yn[valid].astype(np.float32)[:, None] * tail) @ basis_tail
        angle = np.arctan2(hn[1, 0] - hn[0, 1], hn[0, 0] + hn[1, 1])
        c2, s2 = np.cos(2 * angle), np.sin(2 * angle)
        map_x, map_y = _as_map(xt[valid]), _as_map(yt[valid])
        n_valid = int(valid.sum())
        # all frame pairs and both channels stacked: one row block each. The Jacobian is not centred block by block:
        # img and tpl are, so J^T img and J^T tpl are unchanged, and the Hessian of the centred J is J^T J minus
        # n mu mu^T per block (numpy's column means of an (n, 8) float32 array cost more than the product itself)
        blocks = 2 * len(templates)
        jac = np.empty((blocks * n_valid, dx.shape[1]), np.float32)
        img = np.empty(blocks * n_valid, np.float32)
        tpl = np.empty(blocks * n_valid, np.float32)
        centring = np.zeros((dx.shape[1], dx.shape[1]))
        block = 0
        # rotate the doubled-angle channels (value, d/dx, d/dy alike) back into the RGB frame's orientation, and scale
        # the derivatives to normalised units, in one small matrix product; then one contiguous row per channel
        turn = np.array([[c2, -s2], [s2, c2]])
        mix = np.kron(np.diag([1.0, s_t, s_t]), turn).astype(np.float32)
        for template, stack in zip(templates, stacks):
            sampled = cv2.remap(stack, map_x, map_y, cv2.INTER_LINEAR).reshape(-1, 6)[:n_valid]
            sampled = np.ascontiguousarray((sampled @ mix).T)  # rows: Re, Im, d/dx Re, d/dx Im, d/dy Re, d/dy Im
            tpl_valid = template[valid]
            for c in range(2):
                rows = slice(block * n_valid, (block + 1) * n_valid)
                block += 1
                gx, gy = sampled[2 + c], sampled[4 + c]
                part = jac[rows]
                np.multiply(gx[:, None], dx, out=part)
                part += gy[:, None] * dy
                mean = (gx @ dx + gy @ dy).astype(np.float64) / n_valid
                centring += n_valid * np.outer(mean, mean)
                img[rows] = sampled[c] - sampled[c].mean()
                tpl[rows] = tpl_valid[:, c] - tpl_valid[:, c].mean()
        hessian = (jac.T @ jac).astype(np.float64) - centring
        pull = np.zeros(len(hessian))
        if anchor_n is not None:
            weights = stiffness * np.trace(hessian) / len(hessian) * free_shift
            pull = weights * (((hn - anchor_n).ravel()[:8]) @ basis.T)
            hessian = hessian + np.diag(weights)
        img_norm, tpl_norm = float(np.linalg.norm(img)), float(np.linalg.norm(tpl))
        corr = float(img.astype(np.float64) @ tpl)
        correlation = corr / (img_norm * tpl_norm + 1e-12)
        try:
            h_inv = np.linalg.inv(hessian + 1e-9 * np.trace(hessian) * np.eye(len(hessian)))
        except np.linalg.LinAlgError:
            break
        img_proj = (jac.T @ img).astype(np.float64)
        tpl_proj = (jac.T @ tpl).astype(np.float64)
        img_proj_h = h_inv @ img_proj
        lam_d = corr - tpl_proj @ img_proj_h
        if lam_d <= 0:
            break
        lam = (img_norm**2 - img_proj @ img_proj_h) / lam_d
        delta = h_inv @ (lam * tpl_proj - img_proj - pull)  # J^T (lam tpl - img), by linearity
        step = np.append(delta @ basis, 0.0).reshape(3, 3)
        hn = hn + step
        if np.abs(step[:2, :3]).sum() * s_t < tolerance:
            converged = True
            break
    result = np.linalg.inv(n_t) @ hn @ n_a
    return LevelResult(result / result[2, 2], correlation, overlap, it, converged)
