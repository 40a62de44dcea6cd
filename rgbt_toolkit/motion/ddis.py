"""Deformable Diversity Similarity (DDIS; Talmi, Mechrez and Zelnik-Manor, CVPR 2017) for the switcher's s_A, s_M.

DDIS compares a template ``T`` and a window ``Q``, each a grid of feature vectors. Every window point ``q_j`` takes its
nearest template point in appearance, ``t_i = NN_A(q_j, T)``. Two things make a good match: the matches are
*diverse* (many different template points are used; a window of background pointing to the same few template
points is penalised by ``exp(1 - kappa)``, where ``kappa(t_i)`` is how many window points chose ``t_i``), and they
are *in place* (the matched template point lies near where ``q_j`` lies in its window; penalised by ``1 / (1 + r_j)``
with ``r_j`` the spatial distance in grid cells):

    DDIS(Q, T) = c * sum_j  exp(1 - kappa(NN_A(q_j, T))) / (1 + r_j)

We take ``c = 100 / |Q|``, so a window identical to a textured template scores 100 (every point matches itself,
``kappa = 1``, ``r = 0``) and any other window less. The paper's thresholds (``s_hi = 15``, ``s_low = 17``,
``t_diff = 3``) are read on this percent scale; see :mod:`rgbt_toolkit.motion.switcher` for the calibration.

In JMMAC (paper Eq. 6-7), ``s_A = TM(T_1, T^A_t)`` and ``s_M = TM(T_1, T^M_t)``: the first-frame RGB template against
the target regions at the appearance tracker's and at the motion tracker's result. :class:`TemplateMatcher` keeps
``T_1``'s features and scores both windows.
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError


def _features(array, name: str) -> np.ndarray:
    if hasattr(array, "detach"):  # torch tensor
        array = array.detach().cpu().numpy()
    feats = np.asarray(array, dtype=np.float64)
    if feats.ndim == 2:
        feats = feats[:, :, None]
    if feats.ndim != 3 or min(feats.shape) < 1 or not np.all(np.isfinite(feats)):
        raise InputError(f"{name}: expected finite H x W x C features, got shape {feats.shape}")
    return feats


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.maximum(np.linalg.norm(vectors, axis=1, keepdims=True), 1e-12)


def nearest_neighbours(window: np.ndarray, template: np.ndarray) -> np.ndarray:
    """Index of the nearest template vector (Euclidean) for every window vector; (Nq, C), (Nt, C) -> (Nq,)."""
    dist = (window**2).sum(1)[:, None] + (template**2).sum(1)[None, :] - 2.0 * window @ template.T
    return np.argmin(dist, axis=1)


def ddis_score(template, window, *, normalize_features: bool = False) -> float:
    """DDIS of a window against a template, on a 0-100 scale (100 = the window is the textured template itself).

    Parameters
    ----------
    template, window : array_like or torch.Tensor
        Feature maps ``H x W x C`` (or ``H x W`` for one channel). They may differ in size: window positions are
        mapped onto the template grid by their relative position before measuring ``r_j``.
    normalize_features : bool
        L2-normalise every feature vector before the nearest-neighbour search (cosine matching); useful for deep
        features whose magnitude varies with contrast.

    Returns
    -------
    float
        ``100 / |Q| * sum_j exp(1 - kappa_j) / (1 + r_j)``.
    """
    tmpl = _features(template, "template features")
    win = _features(window, "window features")
    if tmpl.shape[2] != win.shape[2]:
        raise InputError(f"template has {tmpl.shape[2]} feature channels but the window has {win.shape[2]}")
    ht, wt, c = tmpl.shape
    hq, wq, _ = win.shape
    t_vec = tmpl.reshape(-1, c)
    q_vec = win.reshape(-1, c)
    if normalize_features:
        t_vec, q_vec = _unit(t_vec), _unit(q_vec)
    nn = nearest_neighbours(q_vec, t_vec)
    kappa = np.bincount(nn, minlength=len(t_vec))[nn]
    # window cell centres expressed in template cells
    qr, qc = np.divmod(np.arange(hq * wq), wq)
    q_rows = (qr + 0.5) * (ht / hq) - 0.5
    q_cols = (qc + 0.5) * (wt / wq) - 0.5
    t_rows, t_cols = np.divmod(nn, wt)
    r = np.hypot(q_rows - t_rows, q_cols - t_cols)
    return float(100.0 * np.mean(np.exp(1.0 - kappa) / (1.0 + r)))


def crop_window(image: np.ndarray, box: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """The image region of ``box = [x, y, w, h]`` resampled to ``size = (width, height)`` (bilinear, edges replicated).

    Regions partly or wholly outside the image are filled by replicating the border, so a box that left the frame
    still yields a window (and a low similarity) instead of an error.
    """
    box = np.asarray(box, dtype=np.float64)
    if box.shape != (4,) or box[2] <= 0 or box[3] <= 0 or not np.all(np.isfinite(box)):
        raise InputError(f"window box must be a finite [x, y, w, h] with positive size, got {box!r}")
    out_w, out_h = int(size[0]), int(size[1])
    sx, sy = box[2] / out_w, box[3] / out_h
    # output pixel (u, v) centre -> source x = box_x + (u + 0.5) * sx - 0.5
    affine = np.array([[sx, 0.0, box[0] + 0.5 * sx - 0.5], [0.0, sy, box[1] + 0.5 * sy - 0.5]])
    src = np.ascontiguousarray(image)
    return cv2.warpAffine(
        src, affine, (out_w, out_h), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE
    )


def colour_patch_features(patch: np.ndarray, cell: int = 3) -> np.ndarray:
    """DDIS's own appearance features: non-overlapping ``cell x cell`` colour patches, one vector per cell.

    A dependency-free default when no backbone features are at hand (the DDIS paper uses 3x3 RGB patches). Returns
    an ``(H // cell) x (W // cell) x (cell * cell * channels)`` float array scaled to [0, 1].
    """
    img = np.asarray(patch, dtype=np.float64)
    if img.ndim == 2:
        img = img[:, :, None]
    if img.dtype.kind in "ui" or img.max() > 1.0:
        img = img / 255.0
    h, w, ch = img.shape
    gh, gw = h // cell, w // cell
    if gh < 1 or gw < 1:
        raise InputError(f"patch {h}x{w} is smaller than one {cell}x{cell} cell")
    img = img[: gh * cell, : gw * cell]
    blocks = img.reshape(gh, cell, gw, cell, ch).transpose(0, 2, 1, 3, 4)
    return blocks.reshape(gh, gw, cell * cell * ch)


class TemplateMatcher:
    """Holds the first-frame template features ``T_1`` and scores windows against them with DDIS.

    Parameters
    ----------
    template_features : array_like or torch.Tensor
        ``H x W x C`` features of the first-frame target region (RGB, in the paper).
    normalize_features : bool
        Passed to :func:`ddis_score`.
    """

    def __init__(self, template_features, normalize_features: bool = False) -> None:
        self.template = _features(template_features, "template features")
        self.normalize_features = normalize_features

    def score(self, window_features) -> float:
        """DDIS of one window's features against the template (0-100)."""
        return ddis_score(self.template, window_features, normalize_features=self.normalize_features)

    def scores(self, appearance_features, motion_features) -> tuple[float, float]:
        """``(s_A, s_M)``: the appearance tracker's and the motion tracker's windows against ``T_1`` (Eq. 6-7)."""
        return self.score(appearance_features), self.score(motion_features)
