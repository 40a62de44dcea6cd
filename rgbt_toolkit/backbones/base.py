"""The interface every frozen feature extractor offers, and the checks shared by their weight loaders.

The trackers (ECO deep features) and the fusion network (MFNet) only see this interface: a frozen network that maps a
batch of RGB images in [0, 1] to a dictionary of named feature maps, with the stride and channel count of each. A new
backbone (VGG-M with user weights, a larger EfficientNet) plugs in by subclassing :class:`Backbone` and registering a
factory in :mod:`rgbt_toolkit.backbones.registry`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import torch
from torch import nn

from rgbt_toolkit.errors import InputError, MissingFileError, WeightsError


class Backbone(nn.Module):
    """A frozen feature extractor with named outputs.

    Subclasses implement :meth:`_features` (normalised input -> dict of maps) and set ``strides``, ``channels``,
    ``mean`` and ``std``. The base class checks the input, normalises it, and runs without gradients.
    """

    name: str = "backbone"
    strides: dict[str, int]
    channels: dict[str, int]
    mean: tuple[float, float, float] = (0.485, 0.456, 0.406)
    std: tuple[float, float, float] = (0.229, 0.224, 0.225)

    def freeze(self) -> "Backbone":
        """Put the network in eval mode and stop gradients into its parameters (the paper never fine-tunes it)."""
        self.eval()
        for p in self.parameters():
            p.requires_grad_(False)
        return self

    def train(self, mode: bool = True) -> "Backbone":
        # A frozen backbone stays in eval mode (batch-norm statistics fixed) even inside a model put in train mode.
        return super().train(False)

    def normalise(self, images: torch.Tensor) -> torch.Tensor:
        """Map RGB in [0, 1] to the input statistics the weights were trained with."""
        mean = torch.tensor(self.mean, dtype=images.dtype, device=images.device).view(1, 3, 1, 1)
        std = torch.tensor(self.std, dtype=images.dtype, device=images.device).view(1, 3, 1, 1)
        return (images - mean) / std

    def extract(self, images: torch.Tensor, layers: tuple[str, ...] | None = None) -> dict[str, torch.Tensor]:
        """Feature maps of a batch of images.

        Parameters
        ----------
        images : torch.Tensor
            ``[B, 3, H, W]`` float32 RGB in [0, 1] (a grey/thermal image: repeat it on the three channels).
        layers : tuple of str, optional
            Names wanted (default: all of ``self.strides``); computation stops after the last one needed.

        Returns
        -------
        dict of str to torch.Tensor
            ``[B, channels[name], ceil(H / strides[name]), ceil(W / strides[name])]`` per name.
        """
        check_images(images)
        wanted = tuple(self.strides) if layers is None else tuple(layers)
        unknown = [n for n in wanted if n not in self.strides]
        if unknown:
            raise InputError(f"{self.name} has no layer {unknown[0]!r}; choose from {sorted(self.strides)}")
        with torch.no_grad():
            return self._features(self.normalise(images.float()), wanted)

    def _features(self, x: torch.Tensor, wanted: tuple[str, ...]) -> dict[str, torch.Tensor]:
        raise NotImplementedError


def check_images(images: torch.Tensor) -> None:
    """Raise :class:`InputError` unless ``images`` is a ``[B, 3, H, W]`` floating tensor."""
    if not isinstance(images, torch.Tensor):
        raise InputError(f"backbone input must be a torch.Tensor [B,3,H,W], got {type(images).__name__}")
    if images.ndim != 4 or images.shape[1] != 3:
        raise InputError(f"backbone input must be [B,3,H,W] RGB, got shape {tuple(images.shape)}")
    if not images.is_floating_point():
        raise InputError(f"backbone input must be float in [0,1], got dtype {images.dtype}; divide uint8 by 255")
    if images.shape[2] < 8 or images.shape[3] < 8:
        raise InputError(f"backbone input is too small ({images.shape[2]}x{images.shape[3]}); need at least 8x8")


def read_state_dict(path: str | Path) -> dict[str, torch.Tensor]:
    """Load a torch state dict from ``path`` with one-line errors for a missing or unreadable file."""
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: weight file not found; pass an existing .pt/.pth state dict")
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises many types (pickle, zip, runtime) for a corrupt file
        raise WeightsError(f"{path}: not a readable torch state dict ({type(exc).__name__}: {exc})") from None
    if isinstance(state, Mapping) and "state_dict" in state and isinstance(state["state_dict"], Mapping):
        state = state["state_dict"]
    if not isinstance(state, Mapping) or not all(isinstance(v, torch.Tensor) for v in state.values()):
        raise WeightsError(f"{path}: expected a mapping of parameter names to tensors (a torch state dict)")
    return dict(state)


def load_strict(module: nn.Module, state: Mapping[str, torch.Tensor], source: str) -> None:
    """``load_state_dict(strict=True)`` with a one-line :class:`WeightsError` naming the first misfit."""
    own = module.state_dict()
    missing = [k for k in own if k not in state]
    extra = [k for k in state if k not in own]
    if missing or extra:
        what = f"missing {missing[0]!r}" if missing else f"unexpected {extra[0]!r}"
        raise WeightsError(
            f"{source}: weights do not fit {type(module).__name__} ({len(missing)} missing, {len(extra)} unexpected "
            f"keys; first {what}); check the backbone name matches the file"
        )
    for k, v in own.items():
        if tuple(state[k].shape) != tuple(v.shape):
            raise WeightsError(
                f"{source}: shape of {k!r} is {tuple(state[k].shape)}, the model needs {tuple(v.shape)}; "
                "check the backbone name matches the file"
            )
    module.load_state_dict(state, strict=True)
