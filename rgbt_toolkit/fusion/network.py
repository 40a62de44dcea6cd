"""MFNet (JMMAC, section "Multimodal Fusion Network"): global and local fusion weights from RGB and T features.

A frozen shared backbone turns the RGB and thermal patches into deep features (VGG-M conv5 in the paper; our
EfficientNet-Lite0 stride-16 layer by default); they are concatenated and fed to two heads:

- global head: conv 3x3x256, ReLU, LRN; conv 9x9x1, LRN; spatial mean; sigmoid -> scalar ``w_G`` (modality importance);
- local head: deconv 3x3x256 (x2 up), ReLU; deconv 3x3x1 (x2 up); bilinear resize to the response size; sigmoid ->
  ``W_L`` (suppresses distractors within a modality).

``W_F = w_G * W_L`` weighs the RGB response, ``1 - W_F`` the thermal one.

Deviation from a literal reading of the paper, on purpose: the paper puts a ReLU after *every* layer, including the
last one of each head; a ReLU in front of the sigmoid confines ``w_G`` and ``W_L`` to [0.5, 1), so the thermal response
could never outweigh the RGB one, contradicting the paper's own Fig. 4 (``w_G`` swings both ways). The last layers
therefore have no ReLU; ``HeadConfig.final_relu=True`` restores the literal form.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from rgbt_toolkit.errors import InputError


@dataclass(frozen=True)
class HeadConfig:
    """Shape of the MFNet heads; stored in weight files so a mismatch is caught on load."""

    in_channels: int = 224  # 2 x 112: EfficientNet-Lite0 "deep" (stride 16) for RGB and for T, concatenated
    hidden: int = 256  # paper: 3x3x256 conv (global) and 3x3x256 deconv (local)
    global_kernel: int = 9  # paper: 9x9x1 conv
    backbone: str = "efficientnet-lite0"
    layer: str = "deep"  # backbone output used (paper: conv5)
    final_relu: bool = False  # paper-literal ReLU before the sigmoid (see module docstring)
    # Initial logit of W_L (bias of the last deconvolution). sigmoid(3) = 0.95: W_F = w_G * W_L then starts at the
    # trained global weight when the local stage begins, instead of halving it (sigmoid(0) = 0.5, the old start,
    # which left the local stage pushing W_L back towards 1). Only used when heads are created for training.
    local_init: float = 3.0

    def to_dict(self) -> dict:
        return asdict(self)


def _lrn() -> nn.LocalResponseNorm:
    # AlexNet/VGG-M LRN constants (MatConvNet defaults used by the paper's VGG-M era networks).
    return nn.LocalResponseNorm(size=5, alpha=1e-4, beta=0.75, k=2.0)


class GlobalHead(nn.Module):
    """Concatenated features ``[B, C, h, w]`` -> logit of ``w_G`` ``[B]``."""

    def __init__(self, cfg: HeadConfig):
        super().__init__()
        self.conv1 = nn.Conv2d(cfg.in_channels, cfg.hidden, 3, padding=1)
        self.conv2 = nn.Conv2d(cfg.hidden, 1, cfg.global_kernel, padding=cfg.global_kernel // 2)
        self.lrn1, self.lrn2 = _lrn(), _lrn()
        self.final_relu = cfg.final_relu

    def forward(self, feats: torch.Tensor) -> torch.Tensor:
        x = self.lrn1(F.relu(self.conv1(feats)))
        x = self.conv2(x)
        if self.final_relu:
            x = F.relu(x)
        return self.lrn2(x).mean(dim=(1, 2, 3))


class LocalHead(nn.Module):
    """Concatenated features ``[B, C, h, w]`` -> logit map of ``W_L`` ``[B, 4h, 4w]`` (before resizing)."""

    def __init__(self, cfg: HeadConfig):
        super().__init__()
        self.deconv1 = nn.ConvTranspose2d(cfg.in_channels, cfg.hidden, 3, stride=2, padding=1, output_padding=1)
        self.deconv2 = nn.ConvTranspose2d(cfg.hidden, 1, 3, stride=2, padding=1, output_padding=1)
        self.final_relu = cfg.final_relu

    def forward(self, feats: torch.Tensor) -> torch.Tensor:
        x = self.deconv2(F.relu(self.deconv1(feats)))
        if self.final_relu:
            x = F.relu(x)
        return x[:, 0]


class MFNetHeads(nn.Module):
    """The trainable part of MFNet: global and local heads on concatenated RGB/T features."""

    def __init__(self, cfg: HeadConfig | None = None):
        super().__init__()
        self.cfg = cfg or HeadConfig()
        self.global_head = GlobalHead(self.cfg)
        self.local_head = LocalHead(self.cfg)
        # Near-constant start: the 9x9x256 sum of the last global layer and the deconvolution sum otherwise saturate
        # the sigmoids before training starts and stall the gradients. w_G starts at sigmoid(0) = 0.5 (the fixed
        # average); W_L at sigmoid(cfg.local_init) (0.95 by default), so the local head starts as "no correction".
        for last in (self.global_head.conv2, self.local_head.deconv2):
            nn.init.normal_(last.weight, std=1e-4)
        nn.init.zeros_(self.global_head.conv2.bias)
        nn.init.constant_(self.local_head.deconv2.bias, self.cfg.local_init)

    def forward(
        self,
        feat_rgb: torch.Tensor,
        feat_t: torch.Tensor,
        out_size: tuple[int, int],
        use_global: bool = True,
        use_local: bool = True,
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Fusion weights from backbone features.

        Parameters
        ----------
        feat_rgb, feat_t : torch.Tensor
            ``[B, C/2, h, w]`` backbone features of the RGB and thermal patches (same grid).
        out_size : (int, int)
            ``(M, N)`` of the response map (or image) the weight is applied to.
        use_global, use_local : bool
            Ablations of the paper's table: a disabled head contributes a constant 1 (``w_G`` or ``W_L``).

        Returns
        -------
        w_g : ``[B]``, w_l : ``[B, M, N]``, w_f : ``[B, M, N]`` with ``w_f = w_g * w_l``, all in (0, 1) (1 if disabled).
        """
        if feat_rgb.shape != feat_t.shape:
            raise ValueError(f"RGB and T features differ in shape: {tuple(feat_rgb.shape)} vs {tuple(feat_t.shape)}")
        feats = torch.cat([feat_rgb, feat_t], dim=1)
        batch = feats.shape[0]
        if use_global:
            w_g = torch.sigmoid(self.global_head(feats))
        else:
            w_g = feats.new_ones(batch)
        if use_local:
            logits = self.local_head(feats)[:, None]
            logits = F.interpolate(logits, size=tuple(out_size), mode="bilinear", align_corners=False)
            w_l = torch.sigmoid(logits[:, 0])
        else:
            w_l = feats.new_ones((batch, *out_size))
        return w_g, w_l, w_g[:, None, None] * w_l


def fuse_responses(w_f, r_rgb, r_t):
    """Paper eq. (1): ``R_F = W_F * R_RGB + (1 - W_F) * R_T`` (numpy arrays or torch tensors).

    ``r_rgb`` and ``r_t`` must have the same shape and ``w_f`` must broadcast to it (a scalar, ``[M, N]`` or
    ``[B, M, N]``); anything else raises :class:`~rgbt_toolkit.errors.InputError` instead of silently broadcasting
    to a bigger map (or failing deep inside torch).
    """
    s_rgb, s_t = tuple(getattr(r_rgb, "shape", ())), tuple(getattr(r_t, "shape", ()))
    s_w = tuple(getattr(w_f, "shape", ()))
    if s_rgb != s_t:
        raise InputError(f"fuse_responses: RGB response {s_rgb} and thermal response {s_t} differ in shape")
    try:
        fits = np.broadcast_shapes(s_w, s_rgb) == s_rgb
    except ValueError:
        fits = False
    if not fits:
        raise InputError(f"fuse_responses: weight map {s_w} does not fit the responses {s_rgb}; resize W_F to the "
                         "response size (MFNet.weights(..., out_size))")
    return w_f * r_rgb + (1 - w_f) * r_t
