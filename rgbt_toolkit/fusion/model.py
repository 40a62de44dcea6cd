"""MFNet = frozen backbone + trained heads: fusion weights from an RGB and a thermal patch or image."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from rgbt_toolkit.backbones import Backbone, load_backbone
from rgbt_toolkit.errors import InputError, WeightsError
from rgbt_toolkit.fusion.network import HeadConfig, MFNetHeads
from rgbt_toolkit.fusion.weights_io import DEFAULT_WEIGHTS, load_heads


def to_tensor(images: np.ndarray | list[np.ndarray]) -> torch.Tensor:
    """uint8 (or float in [0,1]) images ``[H,W]``/``[H,W,3]`` (one or a list of same size) -> ``[B,3,H,W]`` float."""
    arrays = images if isinstance(images, (list, tuple)) else [images]
    out = []
    for a in arrays:
        a = np.asarray(a)
        if a.ndim == 2:
            a = np.repeat(a[:, :, None], 3, axis=2)
        if a.ndim != 3 or a.shape[2] != 3:
            raise InputError(f"expected a grey [H,W] or colour [H,W,3] image, got shape {a.shape}")
        t = torch.from_numpy(np.ascontiguousarray(a))
        t = t.float() / 255.0 if a.dtype == np.uint8 else t.float()
        out.append(t.permute(2, 0, 1))
    return torch.stack(out)


class MFNet:
    """Backbone and heads together; ``weights(rgb, t, size)`` gives ``(w_G, W_L, W_F)``.

    Parameters
    ----------
    heads : MFNetHeads, optional
        Default: the shipped weights (``rgbt_toolkit/fusion/weights/mfnet_heads.pt``).
    backbone : Backbone, optional
        Default: the one named in the heads' configuration, with its packaged weights.
    """

    def __init__(self, heads: MFNetHeads | None = None, backbone: Backbone | None = None):
        self.heads = (heads if heads is not None else load_heads()).eval()
        cfg = self.heads.cfg
        self.backbone = backbone if backbone is not None else load_backbone(cfg.backbone)
        if cfg.layer not in self.backbone.channels:
            raise InputError(f"MFNet heads use layer {cfg.layer!r}, which backbone {self.backbone.name} does not have "
                             f"(layers: {', '.join(sorted(self.backbone.channels))}); use heads trained for it")
        have = 2 * self.backbone.channels[cfg.layer]
        if have != cfg.in_channels:
            raise InputError(
                f"MFNet heads expect {cfg.in_channels} channels from layer {cfg.layer!r}, backbone "
                f"{self.backbone.name} gives {have}; use heads trained for this backbone"
            )

    @classmethod
    def from_file(cls, path: str | Path | None = None, backbone_weights: str | Path | None = None) -> "MFNet":
        """Heads from ``path`` (None: shipped), backbone named in the file with optional user weights."""
        name = path if path is not None else DEFAULT_WEIGHTS
        heads = load_heads(path)
        try:
            backbone = load_backbone(heads.cfg.backbone, weights=backbone_weights)
        except WeightsError:
            if backbone_weights is not None:
                raise
            raise WeightsError(f"{name}: heads trained on backbone {heads.cfg.backbone!r}, whose weights are not "
                               "shipped; pass them with --backbone-weights FILE (a torch state dict, see "
                               "docs/fusion.md)") from None
        except InputError as exc:  # e.g. a backbone name this installation does not know
            raise WeightsError(f"{name}: {exc}") from None
        try:
            return cls(heads, backbone)
        except InputError as exc:
            raise WeightsError(f"{name}: {exc}") from None

    @property
    def config(self) -> HeadConfig:
        return self.heads.cfg

    def features(self, images: torch.Tensor) -> torch.Tensor:
        """Backbone features of ``[B,3,H,W]`` images in [0,1] at the heads' layer."""
        return self.backbone.extract(images, (self.config.layer,))[self.config.layer]

    def weights(
        self,
        rgb: torch.Tensor,
        t: torch.Tensor,
        out_size: tuple[int, int],
        use_global: bool = True,
        use_local: bool = True,
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Fusion weights for RGB/T patches ``[B,3,H,W]`` in [0,1], resized to ``out_size``; no gradients."""
        if rgb.shape != t.shape:
            raise InputError(f"RGB and T patches differ in size: {tuple(rgb.shape)} vs {tuple(t.shape)}")
        feats = self.features(torch.cat([rgb, t]))
        n = rgb.shape[0]
        with torch.no_grad():
            return self.heads(feats[:n], feats[n:], out_size, use_global, use_local)
