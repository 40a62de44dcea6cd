"""A heated calibration board seen by both cameras of a synthetic rig, for ``rgbt register --board`` tests.

The board is a chessboard (or a symmetric grid of dots) on a plate; its dark squares absorb light and warm up, so
the thermal camera sees the same pattern in reverse polarity, blurrier and noisier. Each view holds the board in
another pose (position, size, roll, tilt) in front of the RGB camera; the thermal camera sees it through the rig's
RGB->T homography (the same one :class:`~rgbt_toolkit.synth.SceneRenderer` uses for a scene of the same config), so a
calibration recovered from the frames can be checked against the truth written beside them.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.images import write_image
from rgbt_toolkit.synth.config import SceneConfig

SQUARE_PX = 24  # board texture resolution: pixels per square before warping (warps downsample it)
HOT, COLD, AMBIENT = 215.0, 95.0, 60.0  # thermal grey levels: dark squares / dots, white plate, the room behind
PATTERNS = ("chessboard", "circles")


def board_texture(cols: int, rows: int, pattern: str = "chessboard") -> tuple[np.ndarray, np.ndarray]:
    """The board's reflectance (white 1, black 0) and the board-frame positions of its ``cols x rows`` points.

    A chessboard of ``cols x rows`` inner corners has ``(cols + 1) x (rows + 1)`` squares; a circle grid has one dot
    per point. A white margin of one square surrounds the pattern (detectors need a quiet border).
    """
    if pattern not in PATTERNS:
        raise InputError(f"unknown board pattern '{pattern}'; choose {' or '.join(PATTERNS)}")
    s = SQUARE_PX
    nx, ny = cols + 1, rows + 1  # squares (chessboard) or cells around the dots
    height, width = (ny + 2) * s, (nx + 2) * s
    yy, xx = np.mgrid[0:height, 0:width]
    u, v = (xx + 0.5) / s - 1.0, (yy + 0.5) / s - 1.0  # board units: square (i, j) spans [i, i+1) x [j, j+1)
    inside = (u >= 0) & (u < nx) & (v >= 0) & (v < ny)
    if pattern == "chessboard":
        dark = inside & ((np.floor(u).astype(int) + np.floor(v).astype(int)) % 2 == 0)
    else:
        cu, cv = np.round(u).clip(1, cols), np.round(v).clip(1, rows)  # dot centres at the inner corners
        dark = inside & ((u - cu) ** 2 + (v - cv) ** 2 < 0.3 ** 2)
    gu, gv = np.meshgrid(np.arange(1, cols + 1), np.arange(1, rows + 1))
    points = (np.c_[gu.ravel(), gv.ravel()] + 1.0) * s - 0.5  # texture pixels (pixel centres at integers)
    return np.where(dark, 0.0, 1.0).astype(np.float32), points


def board_poses(rgb_size: tuple[int, int], texture_size: tuple[int, int], views: int,
                rng: np.random.Generator) -> list[np.ndarray]:
    """``views`` board -> RGB homographies: the board at 45-65 % of the frame width, spread over the view, rolled
    up to 15 degrees and tilted (perspective) a little, always wholly inside the frame."""
    w, h = rgb_size
    tw, th = texture_size
    poses = []
    while len(poses) < views:
        scale = rng.uniform(0.45, 0.65) * w / tw
        angle = np.deg2rad(rng.uniform(-15, 15))
        tilt = rng.uniform(-0.25, 0.25, 2) / np.array([tw, th])
        centre = np.array([w, h]) * (0.5 + rng.uniform(-0.18, 0.18, 2))
        c, s = scale * np.cos(angle), scale * np.sin(angle)
        to_centre = np.array([[1, 0, -tw / 2], [0, 1, -th / 2], [0, 0, 1.0]])
        perspective = np.array([[1, 0, 0], [0, 1, 0], [tilt[0], tilt[1], 1.0]])
        place = np.array([[c, -s, centre[0]], [s, c, centre[1]], [0, 0, 1.0]])
        pose = place @ perspective @ to_centre
        corners = cv2.perspectiveTransform(np.array([[[0, 0], [tw, 0], [tw, th], [0, th]]], np.float64), pose)[0]
        if (corners.min(axis=0) > 4).all() and (corners[:, 0] < w - 4).all() and (corners[:, 1] < h - 4).all():
            poses.append(pose)
    return poses


def render_board_pair(config: SceneConfig, cols: int, rows: int, views: int = 6, pattern: str = "chessboard",
                      ) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:
    """RGB (H x W x 3 uint8) and thermal (H x W uint8) frames of the board in ``views`` poses, and the rig's RGB->T
    homography (``config`` sets the sizes, the rig and, through ``seed``, the poses and noise)."""
    from rgbt_toolkit.synth.render import SceneRenderer

    if views < 1:
        raise InputError(f"board views must be at least 1, got {views}")
    rng = np.random.default_rng([config.seed, 7])
    rig = SceneRenderer(config).h_rgb_to_t
    texture, _ = board_texture(cols, rows, pattern)
    heat = np.where(texture > 0.5, COLD, HOT).astype(np.float32)
    rgb_frames, t_frames = [], []
    for pose in board_poses(config.rgb_size, texture.shape[::-1], views, rng):
        shade = cv2.warpPerspective(texture * 190 + 35, pose, config.rgb_size, flags=cv2.INTER_AREA,
                                    borderMode=cv2.BORDER_CONSTANT, borderValue=128.0)
        rgb = shade[:, :, None] * np.array([1.0, 0.97, 0.92]) + rng.normal(0, 2.0, (*shade.shape, 3))
        rgb_frames.append(np.clip(rgb, 0, 255).astype(np.uint8))
        warm = cv2.warpPerspective(heat, rig @ pose, config.t_size, flags=cv2.INTER_AREA,
                                   borderMode=cv2.BORDER_CONSTANT, borderValue=AMBIENT)
        warm = cv2.GaussianBlur(warm, (0, 0), 1.0) + rng.normal(0, 2.5, warm.shape)  # thermal optics and noise
        t_frames.append(np.clip(warm, 0, 255).astype(np.uint8))
    return rgb_frames, t_frames, rig


def write_board_pair(outdir: str | os.PathLike, config: SceneConfig, cols: int, rows: int, views: int = 6,
                     pattern: str = "chessboard", name: str = "board", *, force: bool = False) -> dict[str, Path]:
    """Write ``<name>_rgb/`` and ``<name>_t/`` (PNG frames) and ``<name>.json`` (the rig's RGB->T homography,
    the board and the sizes) into ``outdir``, all at once (staged, then moved); existing outputs need ``force``."""
    from rgbt_toolkit.synth.writer import _refuse_existing, _staged, check_name

    out = Path(outdir)
    check_name(name)
    entries = [out / f"{name}_rgb", out / f"{name}_t", out / f"{name}.json"]
    _refuse_existing(entries, force)
    rgb_frames, t_frames, rig = render_board_pair(config, cols, rows, views, pattern)
    with _staged(out, name) as stage:
        for k, (rgb, thermal) in enumerate(zip(rgb_frames, t_frames)):
            write_image(stage / f"{name}_rgb" / f"{k:05d}.png", rgb)
            write_image(stage / f"{name}_t" / f"{k:05d}.png", thermal)
        truth = {"board": f"{cols}x{rows}", "pattern": pattern, "views": len(rgb_frames),
                 "rgb_size": list(config.rgb_size), "thermal_size": list(config.t_size),
                 "h_rgb_to_t": [[float(v) for v in row] for row in rig / rig[2, 2]]}
        (stage / f"{name}.json").write_text(json.dumps(truth, indent=1), encoding="utf-8")
    return {"rgb": entries[0], "t": entries[1], "truth": entries[2]}
