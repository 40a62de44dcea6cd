"""Procedural backgrounds and shapes for the synthetic scene.

Both cameras see the same world layout (patches, roads, buildings) rendered through different intensity mappings,
so a cross-modal registration has real shared structure to find while pixel intensities differ.
"""

from __future__ import annotations

import cv2
import numpy as np


def smooth_noise(shape: tuple[int, int], cell: float, rng: np.random.Generator) -> np.ndarray:
    """Zero-mean, unit-peak noise with features about ``cell`` pixels wide (bicubic upsampled lattice)."""
    h, w = shape
    lattice = rng.standard_normal((max(2, int(h / cell) + 2), max(2, int(w / cell) + 2))).astype(np.float32)
    field = cv2.resize(lattice, (w, h), interpolation=cv2.INTER_CUBIC)
    return field / (np.abs(field).max() + 1e-6)


def world_background(shape: tuple[int, int], rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """An RGB reflectance image (H, W, 3) and a temperature image (H, W), both float32 in [0, 1]."""
    h, w = shape
    labels = np.zeros((h, w), np.uint8)
    n_labels = 7
    for _ in range(int(30 * h * w / (480 * 360))):
        x0, y0 = int(rng.uniform(-0.1, 1.0) * w), int(rng.uniform(-0.1, 1.0) * h)
        x1, y1 = x0 + int(rng.uniform(0.05, 0.3) * w), y0 + int(rng.uniform(0.05, 0.3) * h)
        cv2.rectangle(labels, (x0, y0), (x1, y1), int(rng.integers(1, n_labels - 1)), thickness=-1)
    for _ in range(3):  # roads: long bands across the world
        p0 = (int(rng.uniform(0, w)), 0)
        p1 = (int(rng.uniform(0, w)), h)
        cv2.line(labels, p0, p1, n_labels - 1, thickness=max(3, int(0.04 * w)))

    colours = rng.uniform(0.15, 0.8, (n_labels, 3)).astype(np.float32)
    colours[n_labels - 1] = (0.3, 0.3, 0.32)  # asphalt
    temperatures = rng.uniform(0.15, 0.5, n_labels).astype(np.float32)
    temperatures[n_labels - 1] = 0.45  # roads store the day's heat

    shading = 0.8 + 0.35 * smooth_noise(shape, 60, rng)
    fine = 0.08 * smooth_noise(shape, 3, rng)
    rgb = colours[labels] * shading[:, :, None] + fine[:, :, None]
    # mid and fine texture (vegetation, surface materials): thermal frames carry features SIFT can match, as real ones do
    heat = (temperatures[labels] + 0.06 * smooth_noise(shape, 40, rng) + 0.08 * smooth_noise(shape, 10, rng)
            + 0.04 * smooth_noise(shape, 4, rng))
    return np.clip(rgb, 0, 1).astype(np.float32), np.clip(heat, 0, 1).astype(np.float32)


def rounded_rect_sdf(x: np.ndarray, y: np.ndarray, centre: np.ndarray, half: np.ndarray, radius: float) -> np.ndarray:
    """Signed distance (pixels, negative inside) to an axis-aligned rounded rectangle."""
    qx = np.abs(x - centre[0]) - (half[0] - radius)
    qy = np.abs(y - centre[1]) - (half[1] - radius)
    outside = np.hypot(np.maximum(qx, 0), np.maximum(qy, 0))
    inside = np.minimum(np.maximum(qx, qy), 0)
    return outside + inside - radius


def rounded_rect_outline(centre: np.ndarray, half: np.ndarray, radius: float, per_corner: int = 16) -> np.ndarray:
    """Points on the outline of the rounded rectangle, (N, 2); its exact extent under any transform."""
    angles = np.linspace(0, np.pi / 2, per_corner)
    corners = [(1, 1, 0.0), (-1, 1, np.pi / 2), (-1, -1, np.pi), (1, -1, 1.5 * np.pi)]
    points = []
    for sx, sy, start in corners:
        arc_centre = centre + np.array([sx, sy]) * (half - radius)
        points.append(arc_centre + radius * np.stack([np.cos(start + angles), np.sin(start + angles)], axis=1))
    return np.concatenate(points)


def sky_background(shape: tuple[int, int], rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A low-texture sky (far_target): a smooth vertical gradient with faint large clouds, cold in thermal.

    Real drone and bird clips are mostly such sky, where a tracker has almost nothing but the target to lock on.
    """
    h, w = shape
    height = np.linspace(0.0, 1.0, h, dtype=np.float32)[:, None, None]  # 0 at the top of the world
    zenith, horizon = np.array([0.35, 0.55, 0.85], np.float32), np.array([0.75, 0.82, 0.9], np.float32)
    clouds = np.clip(smooth_noise(shape, 80, rng) + 0.3 * smooth_noise(shape, 25, rng), 0, None)
    rgb = zenith + height * (horizon - zenith) + 0.12 * clouds[:, :, None]
    heat = 0.12 + 0.08 * height[:, :, 0] + 0.05 * clouds  # clear sky is the coldest thing in view; clouds are warmer
    return np.clip(rgb, 0, 1).astype(np.float32), np.clip(heat, 0, 1).astype(np.float32)
