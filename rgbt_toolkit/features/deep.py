"""Deep features from a frozen backbone: by default a shallow (high-resolution) and a deep (semantic) layer.

Mirrors ECO's use of VGG-M conv1 (stride 2, spatial detail) and conv5 (stride 16, robustness). Any backbone registered
in :mod:`rgbt_toolkit.backbones` works (EfficientNet-Lite0 with its packaged ImageNet weights by default; VGG-M with
user weights); it must return the named layers with ``strides`` and ``channels``. Asking for the shallow layer alone
runs the backbone only up to it: the deep stages are most of its cost. Layer sets whose ONNX export ships with the
package (EfficientNet-Lite0's shallow layer, and its shallow + deep pair, with its own weights) run in ONNX Runtime,
without importing torch (docs/decisions.md, D50).
"""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.features.base import BlockSpec, compute


class DeepFeatures:
    """The named blocks of a backbone (``"shallow"`` and ``"deep"`` by default), as ``(S, n, n, C)`` float32 arrays."""

    def __init__(self, backbone: str = "efficientnet-lite0", weights=None,
                 layers: tuple[str, ...] = ("shallow", "deep"), compressed_dims: tuple[int, ...] = (16, 64)) -> None:
        from rgbt_toolkit.fusion.onnx_model import shipped_layers

        if len(compressed_dims) != len(layers):  # zip would drop a layer without a width silently
            raise InputError(f"one compressed width per layer: layers {list(layers)}, widths {list(compressed_dims)}")
        self.layers = tuple(layers)
        self.export = shipped_layers(backbone, self.layers, weights)
        if self.export is not None:
            self.net = None
            strides = dict(zip(self.layers, self.export.strides))
            channels = dict(zip(self.layers, self.export.channels))
        else:
            from rgbt_toolkit.backbones import load_backbone

            self.net = load_backbone(backbone, weights)
            strides, channels = self.net.strides, self.net.channels
        missing = [n for n in layers if n not in strides]
        if missing:
            raise InputError(f"backbone {backbone!r} has no layer {missing[0]!r}; it has {sorted(strides)}")
        self.blocks = tuple(BlockSpec(f"deep:{n}", int(strides[n]), int(channels[n]), int(c))
                            for n, c in zip(layers, compressed_dims))

    def maps(self, patch: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """One backbone pass on one patch: ``[(map (h, w, C), stride)]`` per layer (grey is repeated to RGB)."""
        if self.export is not None:
            return [(m, b.stride) for m, b in zip(self.export.maps(patch, np.float32), self.blocks)]
        import torch

        if patch.ndim == 2:
            patch = np.repeat(patch[..., None], 3, axis=-1)
        x = torch.from_numpy(np.ascontiguousarray(patch)).permute(2, 0, 1)[None].float().div_(255.0)
        with torch.no_grad():
            out = self.net.extract(x, self.layers)
        return [(np.ascontiguousarray(out[n][0].permute(1, 2, 0).numpy(), dtype=np.float32), b.stride)
                for n, b in zip(self.layers, self.blocks)]

    def finish(self, cells: list[np.ndarray]) -> list[np.ndarray]:
        """Sampled activations are the feature."""
        return cells

    def compute(self, patches: np.ndarray) -> list[np.ndarray]:
        """``(S, P, P[, 3])`` uint8 -> one ``(S, P/stride, P/stride, C)`` array per layer."""
        return compute(self, patches)
