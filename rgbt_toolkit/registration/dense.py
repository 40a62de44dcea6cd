"""Final refinement with the thermal frame resampled into the RGB frame's grid before its features are taken.

The pyramid's ECC (``refine.py``) computes each camera's orientation field in that camera's own pixels and samples
the thermal field through the transform. Its optimum then depends on the thermal camera's pixel grid: the field's
smoothing, its softness and the rotation of the doubled angle are all taken in thermal pixels, so a thermal camera
that sees the same scene zoomed, rolled or tilted prefers a slightly different transform wherever the scene is not
one plane (real rigs: parallax, lens distortion), by up to a few pixels. Here every iteration warps the thermal
*image* into the RGB grid with the current estimate and computes its orientation field there, so the objective
compares the two views in one geometry: registering a thermal view warped by W gives W composed with the answer
for the unwarped view, up to interpolation. The update is forward-compositional ECC (Evangelidis & Psarakis, IEEE
TPAMI 2008): the warped field's own gradient times the Jacobian of a small transform of the RGB grid.
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.registration.features import FILL_REACH, fill_mask
from rgbt_toolkit.registration.refine import MIN_SAMPLES, LevelResult, _normaliser
from rgbt_toolkit.registration.transforms import parameter_basis

SAMPLE_BUDGET = 60000  # samples per iteration over all frame pairs: 640x512 at every 2nd pixel is 82k


def masked_field(grey: np.ndarray, valid: np.ndarray | None, *, smooth: float = 1.0,
                 softness: float = 0.5) -> np.ndarray:
    """Doubled-angle orientation field (``features.orientation_field``) whose softness is set by the gradients
    inside ``valid`` only, so the part of the grid the other view does not cover does not change it."""
    g = cv2.GaussianBlur(grey, (0, 0), 1.0)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=1 / 8)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=1 / 8)
    m2 = gx * gx + gy * gy
    s2 = softness * float(m2[valid].mean() if valid is not None and valid.any() else m2.mean()) + 1e-12
    field = np.empty(grey.shape + (2,), np.float32)
    np.divide(gx * gx - gy * gy, m2 + s2, out=field[..., 0])
    np.divide(2.0 * gx * gy, m2 + s2, out=field[..., 1])
    return cv2.GaussianBlur(field, (0, 0), smooth) if smooth > 0 else field


def _jacobian_rows(u: np.ndarray, v: np.ndarray, basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d x / d p and d y / d p (normalised units) of a small homography I + delta applied to (u, v)."""
    zeros, ones = np.zeros_like(u), np.ones_like(u)
    dx = np.stack([u, v, ones, zeros, zeros, zeros, -u * u, -u * v], 1) @ basis.T
    dy = np.stack([zeros, zeros, zeros, u, v, ones, -u * v, -v * v], 1) @ basis.T
    return dx.astype(np.float32), dy.astype(np.float32)


class _Problem:
    """One level of the dense refinement: the RGB frames' fields at a sample grid, the thermal frames to warp."""

    def __init__(self, rgb: list[np.ndarray], thermal: list[np.ndarray], thermal_per_rgb: float, basis: np.ndarray,
                 sample_budget: int):
        self.shape = rgb[0].shape
        h_a, w_a = self.shape
        self.n_a = _normaliser((h_a, w_a))
        self.half = 1.0 / self.n_a[0, 0]  # RGB pixels per normalised unit
        self.basis = basis
        stride = max(1, int(np.ceil(np.sqrt(len(rgb) * h_a * w_a / sample_budget))))
        self.grid = (slice(stride // 2, h_a, stride), slice(stride // 2, w_a, stride))  # a view, no gather
        ys, xs = np.mgrid[self.grid]
        self.rows, self.cols = ys.ravel(), xs.ravel()
        u = (self.cols - (w_a - 1) / 2) * self.n_a[0, 0]
        v = (self.rows - (h_a - 1) / 2) * self.n_a[0, 0]
        self.dx, self.dy = _jacobian_rows(u, v, basis)
        self.dx *= np.float32(self.half)  # per RGB pixel, as the field's gradient is
        self.dy *= np.float32(self.half)
        grow = np.ones((2 * FILL_REACH + 1,) * 2, np.uint8)
        self.rgb_fields, self.rgb_ok = [], []
        for grey in rgb:  # the RGB side never moves: its field, and where it holds picture, once
            fill = fill_mask(grey)
            ok = None if fill is None else cv2.erode((~fill).astype(np.uint8), grow) > 0
            self.rgb_fields.append(masked_field(grey, ok)[self.grid].reshape(-1, 2))
            self.rgb_ok.append(np.ones(len(self.rows), bool) if ok is None else ok[self.grid].ravel())
        # the thermal frame's picture (not its no-data fill), blurred so that a finer thermal grid comes to the RGB
        # grid's resolution before it is resampled (no aliasing, and the same detail whatever the thermal zoom)
        sigma = 0.5 * np.sqrt(max(thermal_per_rgb ** 2 - 1.0, 0.0))
        self.sources = []
        for grey in thermal:
            fill = fill_mask(grey)
            picture = np.full(grey.shape, 255, np.uint8) if fill is None else (~fill).astype(np.uint8) * 255
            self.sources.append((cv2.GaussianBlur(grey, (0, 0), sigma) if sigma > 0.05 else grey, picture))

    def evaluate(self, matrix: np.ndarray, with_step: bool = True):
        """Correlation at ``matrix`` (RGB level pixels -> thermal pixels), the overlap and the ECC step there
        (parameters of a small transform of the RGB grid, normalised units; None when it cannot be taken)."""
        h_a, w_a = self.shape
        reach = np.ones((2 * FILL_REACH + 3,) * 2, np.uint8)  # the field near the view's edge mixes in the border
        jac_parts, img_parts, tpl_parts = [], [], []
        centring = np.zeros((self.basis.shape[0],) * 2)
        used = 0
        flags = cv2.WARP_INVERSE_MAP | cv2.INTER_LINEAR
        grid = self.grid
        for (grey, picture), tpl_field, ok in zip(self.sources, self.rgb_fields, self.rgb_ok):
            warped = cv2.warpPerspective(grey, matrix, (w_a, h_a), flags=flags, borderMode=cv2.BORDER_REPLICATE)
            inside = cv2.warpPerspective(picture, matrix, (w_a, h_a), flags=flags, borderValue=0)
            inside = cv2.erode((inside > 254).astype(np.uint8), reach, borderValue=0) > 0
            field = masked_field(warped, inside)
            keep = inside[grid].ravel() & ok
            n = int(keep.sum())
            used += n
            values = field[grid].reshape(-1, 2)[keep]
            tpl = tpl_field[keep]
            img_parts.append((values - values.mean(axis=0)).T.ravel() if n else values.T.ravel())
            tpl_parts.append((tpl - tpl.mean(axis=0)).T.ravel() if n else tpl.T.ravel())
            if with_step and n:
                gx = cv2.Sobel(field, cv2.CV_32F, 1, 0, ksize=3, scale=1 / 8)[grid].reshape(-1, 2)[keep]
                gy = cv2.Sobel(field, cv2.CV_32F, 0, 1, ksize=3, scale=1 / 8)[grid].reshape(-1, 2)[keep]
                dx, dy = self.dx[keep], self.dy[keep]
                for c in range(2):
                    jac = gx[:, c:c + 1] * dx
                    jac += gy[:, c:c + 1] * dy
                    # not centred: img and tpl are, so J^T img and J^T tpl are unchanged, and the Hessian of the
                    # centred J is J^T J minus n mu mu^T (refine.ecc_refine does the same)
                    mean = (gx[:, c] @ dx + gy[:, c] @ dy).astype(np.float64) / n
                    centring += n * np.outer(mean, mean)
                    jac_parts.append(jac)
        overlap = used / (len(self.rows) * len(self.sources))
        if used < MIN_SAMPLES:
            return -1.0, overlap, None
        img, tpl = np.concatenate(img_parts), np.concatenate(tpl_parts)
        img_norm, tpl_norm = float(np.linalg.norm(img)), float(np.linalg.norm(tpl))
        corr = float(img.astype(np.float64) @ tpl)
        correlation = corr / (img_norm * tpl_norm + 1e-12)
        if not with_step:
            return correlation, overlap, None
        jac = np.concatenate(jac_parts)
        hessian = (jac.T @ jac).astype(np.float64) - centring
        try:
            h_inv = np.linalg.inv(hessian + 1e-9 * np.trace(hessian) * np.eye(len(hessian)))
        except np.linalg.LinAlgError:
            return correlation, overlap, None
        img_proj = (jac.T @ img).astype(np.float64)
        tpl_proj = (jac.T @ tpl).astype(np.float64)
        img_proj_h = h_inv @ img_proj
        lam_d = corr - tpl_proj @ img_proj_h
        if lam_d <= 0:
            return correlation, overlap, None
        lam = (img_norm ** 2 - img_proj @ img_proj_h) / lam_d
        return correlation, overlap, h_inv @ (lam * tpl_proj - img_proj)

    def update(self, delta: np.ndarray) -> np.ndarray:
        """The small transform of the RGB grid (level pixels) that parameters ``delta`` describe."""
        step = np.eye(3) + np.append(delta @ self.basis, 0.0).reshape(3, 3)
        return np.linalg.inv(self.n_a) @ step @ self.n_a

    def movement(self, update: np.ndarray) -> float:
        """Largest displacement of the level's RGB frame corners under ``update``, in level pixels."""
        h_a, w_a = self.shape
        box = np.array([[0, 0, 1], [w_a, 0, 1], [w_a, h_a, 1], [0, h_a, 1.0]])
        moved = box @ update.T
        return float(np.abs(moved[:, :2] / moved[:, 2:] - box[:, :2]).max())


def dense_refine(rgb: list[np.ndarray], thermal: list[np.ndarray], matrix: np.ndarray, model: str, *,
                 iterations: int = 8, tolerance: float = 0.02, sample_budget: int = SAMPLE_BUDGET,
                 levels: tuple[float, ...] = (1.0,)) -> LevelResult:
    """Refine ``matrix`` (RGB -> thermal, these frames' pixels) over the parameters of ``model``.

    Parameters
    ----------
    rgb, thermal : float32 grey frames in [0, 1], one size per camera, paired by index; they share one transform.
    matrix : starting transform, close to the answer (within a pixel or two): the capture range is the fields'.
    iterations : correlation evaluations per level. A Gauss-Newton step that lowers the correlation is not taken;
        half of it is tried instead (the objective is not smooth at the scale of a pixel on real edges).
    tolerance : stop when a step moves the RGB frame's corners by less than this many RGB pixels.
    sample_budget : the sample grid's stride is chosen so that all pairs together give at most this many samples.
    levels : factors of the RGB frames' size, coarse to fine, at which to refine in turn (a coarser grid first
        widens the capture range).
    """
    basis = parameter_basis(model)
    current = np.asarray(matrix, float) / matrix[2, 2]
    thermal_per_rgb = float(np.sqrt(abs(np.linalg.det(current[:2, :2]))))
    correlation, overlap, converged, it = -1.0, 0.0, False, 0
    for factor in levels:
        small = [cv2.resize(g, None, fx=factor, fy=factor, interpolation=cv2.INTER_AREA) if factor < 1 else g
                 for g in rgb]
        to_level = np.diag([small[0].shape[1] / rgb[0].shape[1], small[0].shape[0] / rgb[0].shape[0], 1.0])
        to_level[:2, 2] = (np.diag(to_level)[:2] - 1) / 2  # pixel centres, as cv2.resize places them
        problem = _Problem(small, thermal, thermal_per_rgb / factor, basis, sample_budget)
        level = current @ np.linalg.inv(to_level)
        correlation, overlap, delta = problem.evaluate(level)
        converged = False
        for it in range(1, iterations + 1):
            if delta is None:
                break
            update = problem.update(delta)
            if problem.movement(update) < tolerance * factor:
                converged = True
                break
            trial = level @ update
            trial_corr, trial_overlap, trial_delta = problem.evaluate(trial / trial[2, 2])
            if trial_corr >= correlation:
                level, correlation, overlap, delta = trial / trial[2, 2], trial_corr, trial_overlap, trial_delta
            else:
                delta = delta / 2
        current = level @ to_level
        current = current / current[2, 2]
    return LevelResult(current, correlation, overlap, it, converged)
