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

SAMPLE_BUDGET = 60000  # samples per evaluation over all frame pairs: 640x512 at every 3rd pixel is 36k (D46)


def field_planes(grey: np.ndarray, valid: np.ndarray | None, *, smooth: float = 1.0,
                 softness: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """The doubled-angle orientation field (``features.orientation_field``) as two contiguous planes, its softness
    set by the gradients inside ``valid`` only, so the part of the grid the other view does not cover does not
    change it.

    Taken once per evaluation of the dense objective at full analysis size: OpenCV filters a plane several times
    faster than an interleaved two-channel image, and merging the planes would cost as much as a blur.
    """
    g = cv2.GaussianBlur(grey, (0, 0), 1.0)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=1 / 8)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=1 / 8)
    cross = cv2.multiply(gx, gy, scale=2.0)
    np.multiply(gx, gx, out=gx)
    np.multiply(gy, gy, out=gy)
    power = cv2.add(gx, gy)
    mask = None if valid is None or not valid.any() else valid.view(np.uint8)
    s2 = softness * float(cv2.mean(power, mask=mask)[0]) + 1e-12
    np.add(power, np.float32(s2), out=power)
    np.subtract(gx, gy, out=gx)
    planes = cv2.divide(gx, power), cv2.divide(cross, power)
    if smooth > 0:
        planes = tuple(cv2.GaussianBlur(plane, (0, 0), smooth) for plane in planes)
    return planes


def _jacobian_rows(u: np.ndarray, v: np.ndarray, basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d x / d p and d y / d p (normalised units) of a small homography I + delta applied to (u, v)."""
    zeros, ones = np.zeros_like(u), np.ones_like(u)
    dx = np.stack([u, v, ones, zeros, zeros, zeros, -u * u, -u * v], 1) @ basis.T
    dy = np.stack([zeros, zeros, zeros, u, v, ones, -u * v, -v * v], 1) @ basis.T
    return dx.astype(np.float32), dy.astype(np.float32)


def _step_inverse(hessian: np.ndarray, cutoff: float, damping: float = 0.0) -> np.ndarray:
    """Inverse of the Gauss-Newton Hessian, damped and truncated along its weak directions.

    Directions whose curvature is under ``cutoff`` times the largest get no step: they keep the start's value.
    ``damping`` (Levenberg-Marquardt) adds that fraction of the largest curvature to every direction, so a weak
    direction moves a fraction of its Gauss-Newton step at each evaluation instead of none or all of it.

    Why: the perspective and shear terms have 1-3 % of the largest curvature on real pairs (less still in the
    correlation itself). Free, a 0.3 % gain in correlation from the two modalities' different edges moved the
    corners by 0.9 px when 4 px of border were cut off the thermal view; frozen, they keep the pyramid's answer,
    which depends on each camera's own pixel grid (D46). Damped by 0.005 they move most of the way to the dense
    optimum over 12 evaluations, and rig warps of real pairs agree with their unwarped fits far more often (D53).
    """
    values, vectors = np.linalg.eigh(hessian)
    largest = values[-1]
    keep = values > cutoff * largest if cutoff > 0 else values + damping * largest > 0
    return (vectors[:, keep] / (values[keep] + damping * largest)) @ vectors[:, keep].T


class _Problem:
    """One level of the dense refinement: the RGB frames' fields at a sample grid, the thermal frames to warp."""

    def __init__(self, rgb: list[np.ndarray], thermal: list[np.ndarray], thermal_per_rgb: float, basis: np.ndarray,
                 sample_budget: int, smooth: float = 1.0, cutoff: float = 1e-9, damping: float = 0.0):
        """Fields of the RGB frames at the sample grid and the thermal frames' pictures; ``smooth``, ``cutoff`` and
        ``damping`` as in :func:`dense_refine`."""
        self.smooth, self.cutoff, self.damping = smooth, cutoff, damping
        self.shape = rgb[0].shape
        h_a, w_a = self.shape
        self.n_a = _normaliser((h_a, w_a))
        self.half = 1.0 / self.n_a[0, 0]  # RGB pixels per normalised unit
        self.basis = basis
        stride = max(1, int(np.ceil(np.sqrt(len(rgb) * h_a * w_a / sample_budget))))
        self.grid = (slice(stride // 2, h_a, stride), slice(stride // 2, w_a, stride))  # a view, no gather
        ys, xs = np.mgrid[self.grid]
        # the same grid in a plane padded by one pixel, moved by -1, 0 and +1 pixels (Sobel's neighbours)
        self.grid_padded = tuple(
            [slice(start + 1 + d, start + 2 + d + stride * (count - 1), stride) for d in (-1, 0, 1)]
            for start, count in ((stride // 2, ys.shape[0]), (stride // 2, ys.shape[1])))
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
            self.rgb_fields.append([plane[self.grid].ravel() for plane in field_planes(grey, ok, smooth=smooth)])
            self.rgb_ok.append(np.ones(len(self.rows), bool) if ok is None else ok[self.grid].ravel())
        # the thermal frame's picture (not its no-data fill), blurred so that a finer thermal grid comes to the RGB
        # grid's resolution before it is resampled (no aliasing, and the same detail whatever the thermal zoom)
        sigma = 0.5 * np.sqrt(max(thermal_per_rgb ** 2 - 1.0, 0.0))
        self.sources = []
        for grey in thermal:
            fill = fill_mask(grey)
            picture = np.full(grey.shape, 255, np.uint8) if fill is None else (~fill).astype(np.uint8) * 255
            self.sources.append((cv2.GaussianBlur(grey, (0, 0), sigma) if sigma > 0.05 else grey, picture))

    def _at(self, padded: np.ndarray, dy: int, dx: int) -> np.ndarray:
        """Values of a plane padded by one pixel at the sample grid moved by (dy, dx) pixels, flattened."""
        return padded[self.grid_padded[0][dy + 1], self.grid_padded[1][dx + 1]].ravel()

    def _sampled(self, plane: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A field plane and its Sobel derivatives (``cv2.Sobel``, ksize 3, scale 1/8, reflected border) at the
        sample grid only: filtering the whole plane would compute them at stride^2 times as many pixels."""
        padded = cv2.copyMakeBorder(plane, 1, 1, 1, 1, cv2.BORDER_REFLECT_101)
        rows = [self._at(padded, dy, 1) - self._at(padded, dy, -1) for dy in (-1, 0, 1)]
        gx = (rows[0] + 2 * rows[1] + rows[2]) * np.float32(1 / 8)
        cols = [self._at(padded, 1, dx) - self._at(padded, -1, dx) for dx in (-1, 0, 1)]
        gy = (cols[0] + 2 * cols[1] + cols[2]) * np.float32(1 / 8)
        return self._at(padded, 0, 0), gx, gy

    def evaluate(self, matrix: np.ndarray, with_step: bool = True):
        """Correlation at ``matrix`` (RGB level pixels -> thermal pixels), the overlap and the ECC step there
        (parameters of a small transform of the RGB grid, normalised units; None when it cannot be taken).

        The sums over all pairs and both field components are accumulated part by part (no concatenated arrays).
        """
        h_a, w_a = self.shape
        reach = np.ones((2 * FILL_REACH + 3,) * 2, np.uint8)  # the field near the view's edge mixes in the border
        k = self.basis.shape[0]
        hessian, img_proj, tpl_proj = np.zeros((k, k)), np.zeros(k), np.zeros(k)
        img_sq = tpl_sq = corr = 0.0
        used = 0
        flags = cv2.WARP_INVERSE_MAP | cv2.INTER_LINEAR
        for (grey, picture), tpl_planes, ok in zip(self.sources, self.rgb_fields, self.rgb_ok):
            warped = cv2.warpPerspective(grey, matrix, (w_a, h_a), flags=flags, borderMode=cv2.BORDER_REPLICATE)
            inside = cv2.warpPerspective(picture, matrix, (w_a, h_a), flags=flags, borderValue=0)
            inside = cv2.erode((inside > 254).astype(np.uint8), reach, borderValue=0) > 0
            keep = inside[self.grid].ravel() & ok
            n = int(keep.sum())
            used += n
            if n == 0:
                continue
            every = n == len(keep)
            dx, dy = (self.dx, self.dy) if every else (self.dx[keep], self.dy[keep])
            for plane, tpl in zip(field_planes(warped, inside, smooth=self.smooth), tpl_planes):
                values, gx, gy = self._sampled(plane)
                if not every:
                    values, gx, gy, tpl = values[keep], gx[keep], gy[keep], tpl[keep]
                both = np.empty((n, 2), np.float32)  # centred image and template, side by side
                np.subtract(values, values.mean(dtype=np.float64), out=both[:, 0])
                np.subtract(tpl, tpl.mean(dtype=np.float64), out=both[:, 1])
                gram = both.T.astype(np.float64) @ both
                img_sq += gram[0, 0]
                tpl_sq += gram[1, 1]
                corr += gram[0, 1]
                if with_step:
                    jac = gx[:, None] * dx
                    jac += gy[:, None] * dy
                    # not centred: img and tpl are, so J^T img and J^T tpl are unchanged, and the Hessian of the
                    # centred J is J^T J minus n mu mu^T (refine.ecc_refine does the same)
                    mean = (gx @ dx + gy @ dy).astype(np.float64) / n  # a reduction along axis 0 is slower
                    hessian += (jac.T @ jac).astype(np.float64) - n * np.outer(mean, mean)
                    projections = jac.T @ both
                    img_proj += projections[:, 0]
                    tpl_proj += projections[:, 1]
        overlap = used / (len(self.rows) * len(self.sources))
        if used < MIN_SAMPLES:
            return -1.0, overlap, None
        correlation = corr / (np.sqrt(img_sq * tpl_sq) + 1e-12)
        if not with_step:
            return correlation, overlap, None
        try:
            h_inv = _step_inverse(hessian, self.cutoff, self.damping)
        except np.linalg.LinAlgError:
            return correlation, overlap, None
        img_proj_h = h_inv @ img_proj
        lam_d = corr - tpl_proj @ img_proj_h
        if lam_d <= 0:
            return correlation, overlap, None
        lam = (img_sq - img_proj @ img_proj_h) / lam_d
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


def _secant_scale(step: np.ndarray, before: np.ndarray, after: np.ndarray, largest: float) -> float:
    """How much longer than the Gauss-Newton step the next one should be (Barzilai-Borwein on the Gauss-Newton step).

    On real pairs ECC's Gauss-Newton steps fall short by a steady factor: the Hessian J^T J counts the gradients of
    every thermal edge, shared or not, while the correlation bends only with the shared ones, so a step covers a
    fraction k of the way left. Steps ``before`` and ``after`` a move ``step`` then differ by k x ``step``, which gives
    k; the next step is scaled by 1/k, within [1, ``largest``] (no curvature seen along the move: ``largest``).
    """
    change = before - after
    moved = float(step @ step)
    along = float(step @ change)
    if moved <= 0:
        return 1.0
    if along <= 0:
        return largest
    return float(np.clip(moved / along, 1.0, largest))


def dense_refine(rgb: list[np.ndarray], thermal: list[np.ndarray], matrix: np.ndarray, model: str, *,
                 iterations: int = 8, tolerance: float = 0.02, sample_budget: int = SAMPLE_BUDGET,
                 levels: tuple[float, ...] = (1.0,), max_scale: float = 1.0, smooth: float = 1.0,
                 cutoff: float = 1e-9, damping: float = 0.0) -> LevelResult:
    """Refine ``matrix`` (RGB -> thermal, these frames' pixels) over the parameters of ``model``.

    Parameters
    ----------
    rgb, thermal : float32 grey frames in [0, 1], one size per camera, paired by index; they share one transform.
    matrix : starting transform, close to the answer (within a pixel or two): the capture range is the fields'.
    iterations : correlation evaluations per level. A step that lowers the correlation is not taken; half of it is
        tried instead (the objective is not smooth at the scale of a pixel on real edges).
    tolerance : stop when a step moves the RGB frame's corners by less than this many RGB pixels.
    sample_budget : the sample grid's stride is chosen so that all pairs together give at most this many samples.
    levels : factors of the RGB frames' size, coarse to fine, at which to refine in turn (a coarser grid first
        widens the capture range).
    max_scale : longest step, in Gauss-Newton steps, that the secant estimate (:func:`_secant_scale`) may take; 1
        takes plain Gauss-Newton steps.
    smooth : Gaussian smoothing (level pixels) of both orientation fields.
    cutoff : directions whose Gauss-Newton curvature is under this fraction of the largest are not moved
        (:func:`_step_inverse`); 1e-9 moves all of them.
    damping : Levenberg-Marquardt damping, a fraction of the largest curvature added to every direction's
        (:func:`_step_inverse`); 0 takes Gauss-Newton steps.
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
        problem = _Problem(small, thermal, thermal_per_rgb / factor, basis, sample_budget, smooth, cutoff, damping)
        level = current @ np.linalg.inv(to_level)
        correlation, overlap, delta = problem.evaluate(level)
        converged, scale = False, 1.0
        for it in range(1, iterations + 1):
            if delta is None:
                break
            step = scale * delta
            update = problem.update(step)
            if problem.movement(update) < tolerance * factor:
                converged = True
                break
            trial = level @ update
            trial_corr, trial_overlap, trial_delta = problem.evaluate(trial / trial[2, 2])
            if trial_corr >= correlation:
                if trial_delta is not None and max_scale > 1:
                    scale = _secant_scale(step, delta, trial_delta, max_scale)
                level, correlation, overlap, delta = trial / trial[2, 2], trial_corr, trial_overlap, trial_delta
            else:
                scale /= 2
        current = level @ to_level
        current = current / current[2, 2]
    return LevelResult(current, correlation, overlap, it, converged)
