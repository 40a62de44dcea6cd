"""Image fusion with MFNet (paper, "MFNet analysis on image fusion"): ``I_F = W_F * I_RGB + (1 - W_F) * I_T``.

The network runs on a copy of the pair reduced to ``FuseSettings.net_side`` pixels on the long side (the weight map
is smooth: stride-4 of the reduced input, then bilinear), and the blend runs at full resolution. A colour visible
image is fused in luminance (Y of YCrCb, BT.601) and keeps its chroma, so the output has the visible image's colours.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import cv2
import numpy as np
import torch

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.fusion.model import MFNet, to_tensor
from rgbt_toolkit.io.pixels import as_uint8


@dataclass(frozen=True)
class FuseSettings:
    """Image-fusion settings."""

    net_side: int = 192  # long side of the network input; 192 keeps 640x480 at >= 25 pairs/s on 2 cores
    use_global: bool = True  # ablation switches (paper's MF-G / MF-L)
    use_local: bool = True


@dataclass
class FusionResult:
    """A fused image and the weights behind it."""

    fused: np.ndarray  # uint8, grey [H,W] or RGB [H,W,3] like the visible input
    w_f: np.ndarray  # float32 [H,W] in (0,1): weight of the visible image
    w_g: float  # global weight
    timings: dict[str, float] = field(default_factory=dict)  # seconds per stage


def grey_of(image: np.ndarray) -> np.ndarray:
    """Luminance of an RGB image (BT.601, like the Y of YCrCb); grey passes through."""
    return cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image


def net_size(shape: tuple[int, int], side: int) -> tuple[int, int]:
    """(h, w) of the network input: long side ``side`` (never upsampled), aspect kept, at least 16 px."""
    h, w = shape
    scale = min(1.0, side / max(h, w))
    return max(16, round(h * scale)), max(16, round(w * scale))


def fuse_images(vis: np.ndarray, ir: np.ndarray, net: MFNet, settings: FuseSettings = FuseSettings()) -> FusionResult:
    """Fuse a registered visible/infrared pair.

    Parameters
    ----------
    vis : np.ndarray
        Visible image, grey ``[H,W]`` or RGB ``[H,W,3]`` (alpha dropped). Non-8-bit images are stretched by their
        used range, floats in [0, 1] scaled by 255 (:func:`rgbt_toolkit.io.pixels.as_uint8`).
    ir : np.ndarray
        Infrared image of the same size (a 3-channel IR file is turned to grey), same value rules.
    net : MFNet
        The fusion network.
    settings : FuseSettings

    Returns
    -------
    FusionResult
    """
    vis, ir = as_uint8(vis, "visible"), as_uint8(ir, "infrared")
    ir = grey_of(ir)
    if vis.shape[:2] != ir.shape[:2]:
        raise InputError(
            f"visible {vis.shape[1]}x{vis.shape[0]} and infrared {ir.shape[1]}x{ir.shape[0]} differ in size; "
            "resize or register them first (rgbt fuse --registered or --calib calib.json)"
        )
    times = {}
    t0 = time.perf_counter()
    h, w = vis.shape[:2]
    nh, nw = net_size((h, w), settings.net_side)
    small_vis = cv2.resize(vis, (nw, nh), interpolation=cv2.INTER_AREA) if (nh, nw) != (h, w) else vis
    small_ir = cv2.resize(ir, (nw, nh), interpolation=cv2.INTER_AREA) if (nh, nw) != (h, w) else ir
    batch_rgb, batch_t = to_tensor(small_vis), to_tensor(small_ir)
    t1 = time.perf_counter()
    feats = net.features(torch.cat([batch_rgb, batch_t]))
    t2 = time.perf_counter()
    grid = (4 * feats.shape[2], 4 * feats.shape[3])  # native resolution of the local head
    with torch.no_grad():
        w_g, _, w_f = net.heads(feats[:1], feats[1:], grid, settings.use_global, settings.use_local)
    t3 = time.perf_counter()
    weight = cv2.resize(w_f[0].numpy().astype(np.float32), (w, h), interpolation=cv2.INTER_LINEAR)
    if vis.ndim == 3:
        ycrcb = cv2.cvtColor(vis, cv2.COLOR_RGB2YCrCb)
        y = ycrcb[:, :, 0]
    else:
        y = vis
    # T + W (Y - T) = W Y + (1 - W) T, one multiply; identical inputs give back exactly the input.
    fused_y = np.clip(ir + weight * (y.astype(np.float32) - ir) + 0.5, 0, 255).astype(np.uint8)
    if vis.ndim == 3:
        ycrcb[:, :, 0] = fused_y
        fused = cv2.cvtColor(ycrcb, cv2.COLOR_YCrCb2RGB)
    else:
        fused = fused_y
    t4 = time.perf_counter()
    times.update(prepare=t1 - t0, backbone=t2 - t1, heads=t3 - t2, blend=t4 - t3)
    return FusionResult(fused, weight, float(w_g[0]), times)


def weight_heatmap(w_f: np.ndarray) -> np.ndarray:
    """RGB uint8 heat map of a weight map in [0,1] (viridis: dark = thermal dominates, yellow = visible)."""
    grey = np.clip(w_f * 255.0 + 0.5, 0, 255).astype(np.uint8)
    return cv2.cvtColor(cv2.applyColorMap(grey, cv2.COLORMAP_VIRIDIS), cv2.COLOR_BGR2RGB)
