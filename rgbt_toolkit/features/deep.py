"""Deep features from a frozen backbone: a shallow (high-resolution) and a deep (semantic) layer.

Mirrors ECO's use of VGG-M conv1 (stride 2, spatial detail) and conv5 (stride 16, robustness). Any backbone registered
in :mod:`rgbt_toolkit.backbones` works (EfficientNet-Lite0 with its packaged ImageNet weights by default; VGG-M with
user weights); it must return the two named layers with ``strides`` and ``channels``.
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.features.base import BlockSpec, check_patches


class DeepFeatures:
    """Blocks ``"shallow"`` and ``"deep"`` of a backbone, as ``(S, n, n, C)`` float32 arrays."""

    def __init__(self, backbone: str = "efficientnet-lite0", weights=None,
                 layers: tuple[str, ...] = ("shallow", "deep"), compressed_dims: tuple[int, ...] = (16, 64)) -> None:
        from rgbt_toolkit.backbones import load_backbone

        self.net = load_backbone(backbone, weights)
        missing = [n for n in layers if n not in self.net.strides]
        if missing:
            raise InputError(f"backbone {backbone!r} has no layer {missing[0]!r}; it has {sorted(self.net.strides)}")
        self.layers = tuple(layers)
        self.blocks = tuple(BlockSpec(f"deep:{n}", int(self.net.strides[n]), int(self.net.channels[n]), int(c))
                            for n, c in zip(layers, compressed_dims))

    def compute(self, patches: np.ndarray) -> list[np.ndarray]:
        """``(S, P, P[, 3])`` uint8 -> one ``(S, P/stride, P/stride, C)`` array per layer (grey is repeated to RGB)."""
        import torch

        patches = check_patches(patches, max(b.stride for b in self.blocks))
        if patches.ndim == 3:
            patches = np.repeat(patches[..., None], 3, axis=-1)
        x = torch.from_numpy(np.ascontiguousarray(patches)).permute(0, 3, 1, 2).float().div_(255.0)
        with torch.no_grad():
            out = self.net.extract(x, self.layers)
        return [np.ascontiguousarray(out[n].permute(0, 2, 3, 1).numpy(), dtype=np.float32) for n in self.layers]
