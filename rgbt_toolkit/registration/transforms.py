"""Planar transforms between the RGB and thermal image planes, as 3x3 homography matrices.

Every transform here maps RGB pixel coordinates to thermal pixel coordinates, ``x_T ~ H @ [x_RGB, y_RGB, 1]``, with
pixel centres at integer coordinates (OpenCV's convention). Similarity and affine models are homographies whose last
row is ``[0, 0, 1]``; the model only restricts which entries the refinement may change.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import InputError

MODELS = ("homography", "affine", "similarity")


def check_model(model: str) -> str:
    """Return ``model`` if known, else raise an :class:`InputError` listing the choices."""
    if model not in MODELS:
        raise InputError(f"unknown transform model '{model}'; choose one of {', '.join(MODELS)}")
    return model


def parameter_basis(model: str) -> np.ndarray:
    """(P, 8) matrix: row p is the change of (h00, h01, h02, h10, h11, h12, h20, h21) per unit of parameter p.

    Similarity: (a, b, tx, ty) with ``[[1+a, -b, tx], [b, 1+a, ty]]``; affine: the six top entries; homography: all
    eight (h22 stays 1).
    """
    check_model(model)
    if model == "similarity":
        basis = np.zeros((4, 8))
        basis[0, [0, 4]] = 1.0
        basis[1, 1], basis[1, 3] = -1.0, 1.0
        basis[2, 2] = basis[3, 5] = 1.0
        return basis
    if model == "affine":
        return np.eye(6, 8)
    return np.eye(8)


def similarity(scale: float, angle: float, center_from, center_to, shift=(0.0, 0.0)) -> np.ndarray:
    """Similarity taking ``center_from`` to ``center_to + shift``, scaling by ``scale``, rotating by ``angle`` (rad)."""
    c, s = scale * np.cos(angle), scale * np.sin(angle)
    rot = np.array([[c, -s], [s, c]])
    matrix = np.eye(3)
    matrix[:2, :2] = rot
    matrix[:2, 2] = np.asarray(center_to, float) - rot @ np.asarray(center_from, float) + np.asarray(shift, float)
    return matrix


def scaling(fx: float, fy: float | None = None) -> np.ndarray:
    """Diagonal matrix that scales pixel coordinates (for moving a homography between pyramid levels)."""
    return np.diag([fx, fx if fy is None else fy, 1.0])


def pixel_scaling(factor_x: float, factor_y: float) -> np.ndarray:
    """Full-resolution -> resized pixel coordinates, pixel centres kept consistent (cv2.resize convention)."""
    return np.array([[factor_x, 0, 0.5 * factor_x - 0.5], [0, factor_y, 0.5 * factor_y - 0.5], [0, 0, 1.0]])


def normalize(matrix: np.ndarray) -> np.ndarray:
    """Scale a homography so that its bottom-right entry is 1."""
    matrix = np.asarray(matrix, float)
    if abs(matrix[2, 2]) < 1e-12:
        raise InputError("homography has a zero bottom-right entry (maps points to infinity)")
    return matrix / matrix[2, 2]


def project(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply a homography to (N, 2) points."""
    points = np.asarray(points, float).reshape(-1, 2)
    hom = np.c_[points, np.ones(len(points))] @ np.asarray(matrix, float).T
    return hom[:, :2] / hom[:, 2:3]


def corners(size: tuple[int, int]) -> np.ndarray:
    """The four outer corners (0,0), (w,0), (w,h), (0,h) of an image of ``size`` = (width, height)."""
    w, h = size
    return np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]])


def corner_error(estimate: np.ndarray, truth: np.ndarray, size: tuple[int, int]) -> float:
    """Mean distance (thermal pixels) between the RGB image corners mapped by ``estimate`` and by ``truth``.

    This is the usual "average corner error" of homography estimation; ``size`` is the RGB (width, height).
    """
    pts = corners(size)
    return float(np.linalg.norm(project(estimate, pts) - project(truth, pts), axis=1).mean())


def overlap_corner_error(estimate: np.ndarray, truth: np.ndarray, thermal_size: tuple[int, int]) -> float:
    """Mean distance (RGB pixels) between the thermal frame's corners mapped back by ``estimate`` and by ``truth``.

    Unlike :func:`corner_error` this measures the transform where the thermal camera sees, which is what matters when
    its view is narrower than the RGB one (the RGB corners then lie outside it and their error is extrapolation).
    """
    pts = corners(thermal_size)
    inv_e, inv_t = np.linalg.inv(estimate), np.linalg.inv(truth)
    return float(np.linalg.norm(project(inv_e, pts) - project(inv_t, pts), axis=1).mean())


def fit_model(matrix: np.ndarray, model: str, size: tuple[int, int]) -> np.ndarray:
    """The ``model`` transform closest to ``matrix`` over a grid of points of a ``size`` frame (least squares).

    Pyramid levels scale x and y by slightly different factors (integer frame sizes), which leaves a similarity with
    a 0.1 % anisotropy; this puts it back into its model's form.
    """
    check_model(model)
    if model == "homography":
        return normalize(matrix)
    w, h = size
    gx, gy = np.meshgrid(np.linspace(0, w, 5), np.linspace(0, h, 5))
    src = np.c_[gx.ravel(), gy.ravel()]
    dst = project(matrix, src)
    n = len(src)
    if model == "affine":
        design = np.zeros((2 * n, 6))
        design[0::2, 0:2], design[0::2, 2] = src, 1
        design[1::2, 3:5], design[1::2, 5] = src, 1
        p = np.linalg.lstsq(design, dst.ravel(), rcond=None)[0]
        return np.array([[p[0], p[1], p[2]], [p[3], p[4], p[5]], [0, 0, 1.0]])
    design = np.zeros((2 * n, 4))  # x' = a x - b y + tx, y' = b x + a y + ty
    design[0::2] = np.c_[src[:, 0], -src[:, 1], np.ones(n), np.zeros(n)]
    design[1::2] = np.c_[src[:, 1], src[:, 0], np.zeros(n), np.ones(n)]
    a, b, tx, ty = np.linalg.lstsq(design, dst.ravel(), rcond=None)[0]
    return np.array([[a, -b, tx], [b, a, ty], [0, 0, 1.0]])


def decompose(matrix: np.ndarray) -> dict[str, float]:
    """Scale, rotation (degrees) and shift of the linear part, for printing and plausibility checks."""
    matrix = normalize(matrix)
    linear = matrix[:2, :2]
    det = float(np.linalg.det(linear))
    scale = float(np.sqrt(abs(det)))
    angle = float(np.degrees(np.arctan2(linear[1, 0] - linear[0, 1], linear[0, 0] + linear[1, 1])))
    sv = np.linalg.svd(linear, compute_uv=False)
    return {
        "scale": scale,
        "rotation_deg": angle,
        "shift_x": float(matrix[0, 2]),
        "shift_y": float(matrix[1, 2]),
        "anisotropy": float(sv[0] / max(sv[1], 1e-12)),
        "mirrored": det < 0,
    }


def is_plausible(matrix: np.ndarray, size: tuple[int, int], *, max_anisotropy: float = 1.5) -> bool:
    """False for degenerate estimates: mirrored, strongly sheared or with the RGB frame folding over the horizon."""
    matrix = normalize(matrix)
    parts = decompose(matrix)
    if parts["mirrored"] or parts["anisotropy"] > max_anisotropy or not np.isfinite(matrix).all():
        return False
    hom = np.c_[corners(size), np.ones(4)] @ matrix.T
    return bool((hom[:, 2] > 0.2).all())
