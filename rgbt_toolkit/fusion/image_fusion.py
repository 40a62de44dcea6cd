"""Image fusion with MFNet (paper, "MFNet analysis on image fusion"): ``I_F = W_F * I_RGB + (1 - W_F) * I_T``.

The network runs on a copy of the pair reduced to ``FuseSettings.net_side`` pixels on the long side (the weight map
is smooth: stride-4 of the reduced input, then bilinear), and the blend runs at full resolution. A colour visible
image is fused in luminance (Y of YCrCb, BT.601) and keeps its chroma, so the output has the visible image's colours.

Any image size works: the reduced copy has sides that are multiples of 4 (the local head's output stride, so the
weight map covers it with whole cells) and is padded on the bottom and right by reflection to multiples of 16 (the
backbone's stride, which the ONNX export needs, see :mod:`rgbt_toolkit.fusion.onnx_model`); the weight map is cropped
back to the image before it is resized to full resolution. Both networks - the shipped ONNX export
(:class:`~rgbt_toolkit.fusion.onnx_model.OnnxMfnet`, the default of ``rgbt fuse``: no torch import) and a torch
:class:`~rgbt_toolkit.fusion.model.MFNet` (user ``.pt`` heads) - get the same padded input, so they give the same
weights; sizes already multiples of 16 (640x480 -> 192x144) are not padded at all.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Union

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.fusion.onnx_model import STRIDE, OnnxMfnet
from rgbt_toolkit.io.pixels import as_uint8

if TYPE_CHECKING:  # importing torch costs seconds; only the torch path (user .pt weights) pays it
    from rgbt_toolkit.fusion.model import MFNet

FusionNet = Union["OnnxMfnet", "MFNet"]
CELL = 4  # output stride of the local head: the weight map has one value per 4x4 network pixels


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
    """(h, w) of the network input: long side ``side`` (never upsampled), aspect kept to the nearest multiple of
    :data:`CELL` (so the weight map's cells tile it exactly), at least 16 px."""
    h, w = shape
    scale = min(1.0, side / max(h, w))
    return (max(16, CELL * round(h * scale / CELL)), max(16, CELL * round(w * scale / CELL)))


def pad_to_stride(image: np.ndarray, stride: int = STRIDE) -> np.ndarray:
    """``image`` extended on the bottom and right by reflection (no edge repeated) to sides that are multiples of
    ``stride``; unchanged if they already are. Reflection keeps the padded strip's texture and contrast like the
    image's, so it sways the global head's spatial mean less than a constant border would."""
    h, w = image.shape[:2]
    ph, pw = -h % stride, -w % stride
    if not (ph or pw):
        return image
    return cv2.copyMakeBorder(image, 0, ph, 0, pw, cv2.BORDER_REFLECT_101)


def _sigmoid(x: np.ndarray | float) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-np.asarray(x, dtype=np.float32)))


def network_logits(net: FusionNet, vis: np.ndarray, ir: np.ndarray) -> tuple[float, np.ndarray]:
    """Global logit and local logit map ``[h/4, w/4]`` (float32) of a padded uint8 pair, by ONNX Runtime or torch."""
    if isinstance(net, OnnxMfnet):
        return net.logits(vis, ir)
    import torch

    from rgbt_toolkit.fusion.model import to_tensor

    feats = net.features(torch.cat([to_tensor(vis), to_tensor(ir)]))
    with torch.no_grad():
        both = torch.cat([feats[:1], feats[1:]], dim=1)
        g, local = net.heads.global_head(both), net.heads.local_head(both)
    return float(g[0]), local[0].numpy().astype(np.float32, copy=False)


def fuse_images(vis: np.ndarray, ir: np.ndarray, net: FusionNet, settings: FuseSettings = FuseSettings()
                ) -> FusionResult:
    """Fuse a registered visible/infrared pair of any size.

    Parameters
    ----------
    vis : np.ndarray
        Visible image, grey ``[H,W]`` or RGB ``[H,W,3]`` (alpha dropped). Non-8-bit images are stretched by their
        used range, floats in [0, 1] scaled by 255 (:func:`rgbt_toolkit.io.pixels.as_uint8`).
    ir : np.ndarray
        Infrared image of the same size (a 3-channel IR file is turned to grey), same value rules.
    net : OnnxMfnet or MFNet
        The fusion network: the shipped ONNX export (``OnnxMfnet(IMAGE_ONNX)``, no torch) or a torch MFNet.
    settings : FuseSettings

    Returns
    -------
    FusionResult
        ``timings`` has the stages ``prepare`` (resize, pad), ``network`` (backbone and heads) and ``blend``.
    """
    vis, ir = as_uint8(vis, "visible"), as_uint8(ir, "infrared")
    ir = grey_of(ir)
    if vis.shape[:2] != ir.shape[:2]:
        raise InputError(
            f"visible {vis.shape[1]}x{vis.shape[0]} and infrared {ir.shape[1]}x{ir.shape[0]} differ in size; "
            "resize or register them first (rgbt fuse --registered or --calib calib.json)"
        )
    t0 = time.perf_counter()
    h, w = vis.shape[:2]
    nh, nw = net_size((h, w), settings.net_side)
    small_vis = cv2.resize(vis, (nw, nh), interpolation=cv2.INTER_AREA) if (nh, nw) != (h, w) else vis
    small_ir = cv2.resize(ir, (nw, nh), interpolation=cv2.INTER_AREA) if (nh, nw) != (h, w) else ir
    padded_vis, padded_ir = pad_to_stride(small_vis), pad_to_stride(small_ir)
    t1 = time.perf_counter()
    logit_g, local = network_logits(net, padded_vis, padded_ir)
    t2 = time.perf_counter()
    # the cells over the image (the padding cropped off); for EfficientNet exactly nh/4 x nw/4
    rows = max(1, round(local.shape[0] * nh / padded_vis.shape[0]))
    cols = max(1, round(local.shape[1] * nw / padded_vis.shape[1]))
    w_g = _sigmoid(logit_g) if settings.use_global else np.float32(1.0)
    w_l = _sigmoid(local[:rows, :cols]) if settings.use_local else np.ones((rows, cols), np.float32)
    weight = cv2.resize(w_g * w_l, (w, h), interpolation=cv2.INTER_LINEAR)
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
    t3 = time.perf_counter()
    times = {"prepare": t1 - t0, "network": t2 - t1, "blend": t3 - t2}
    return FusionResult(fused, weight, float(w_g), times)


def weight_heatmap(w_f: np.ndarray) -> np.ndarray:
    """RGB uint8 heat map of a weight map in [0,1] (viridis: dark = thermal dominates, yellow = visible)."""
    grey = np.clip(w_f * 255.0 + 0.5, 0, 255).astype(np.uint8)
    return cv2.cvtColor(cv2.applyColorMap(grey, cv2.COLORMAP_VIRIDIS), cv2.COLOR_BGR2RGB)
