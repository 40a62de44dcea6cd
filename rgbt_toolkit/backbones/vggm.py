"""VGG-M (Chatfield et al. 2014), the paper's backbone, for users who hold its weights.

The MatConvNet ImageNet weights are not redistributable, so none ship; ``load_backbone("vggm", weights=PATH)`` takes
a torch state dict with keys ``conv1.weight``, ``conv1.bias`` ... ``conv5.bias`` (torch layout ``[out, in, kh, kw]``).
MatConvNet-style names ``conv1f``/``conv1b`` with ``[kh, kw, in, out]`` filters are converted by :meth:`VGGM.map_keys`.
``shallow`` is conv1 (stride 2, 96 channels), ``deep`` is conv5 (stride 16, 512 channels), as in ECO and JMMAC.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

from rgbt_toolkit.backbones.base import Backbone

# (name, in, out, kernel, stride, padding): VGG-M as in MatConvNet's imagenet-vgg-m.
_LAYERS = (
    ("conv1", 3, 96, 7, 2, 0),
    ("conv2", 96, 256, 5, 2, 1),
    ("conv3", 256, 512, 3, 1, 1),
    ("conv4", 512, 512, 3, 1, 1),
    ("conv5", 512, 512, 3, 1, 1),
)


class VGGM(Backbone):
    """Truncated VGG-M (conv1-conv5) with LRN and max-pooling after conv1 and conv2."""

    name = "vggm"
    # MatConvNet VGG-M subtracts the ImageNet mean image on a 0-255 scale; per-channel mean, unit scale of 1/255.
    mean = (0.4850, 0.4580, 0.4076)
    std = (1.0 / 255.0, 1.0 / 255.0, 1.0 / 255.0)

    def __init__(self) -> None:
        super().__init__()
        for name, cin, cout, k, s, p in _LAYERS:
            setattr(self, name, nn.Conv2d(cin, cout, k, s, p))
        self.strides = {"shallow": 2, "conv4": 16, "deep": 16}
        self.channels = {"shallow": 96, "conv4": 512, "deep": 512}

    def _features(self, x: torch.Tensor, wanted: tuple[str, ...]) -> dict[str, torch.Tensor]:
        out = {}
        x = F.relu(self.conv1(x))
        if "shallow" in wanted:
            out["shallow"] = x
        if set(wanted) <= {"shallow"}:
            return out
        x = F.max_pool2d(F.local_response_norm(x, 5, alpha=5 * 1e-4, beta=0.75, k=2.0), 3, 2, ceil_mode=True)
        x = F.relu(self.conv2(x))
        x = F.max_pool2d(F.local_response_norm(x, 5, alpha=5 * 1e-4, beta=0.75, k=2.0), 3, 2, ceil_mode=True)
        x = F.relu(self.conv4(F.relu(self.conv3(x))))
        if "conv4" in wanted:
            out["conv4"] = x
        if "deep" in wanted:
            out["deep"] = F.relu(self.conv5(x))
        return out

    @staticmethod
    def map_keys(state: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """Accept torch names as they are and MatConvNet ``convNf``/``convNb`` (filters ``[kh,kw,in,out]``)."""
        out = {}
        for key, value in state.items():
            if len(key) == 6 and key.startswith("conv") and key[5] in "fb":
                if key[5] == "f":
                    out[f"{key[:5]}.weight"] = value.permute(3, 2, 0, 1).contiguous() if value.ndim == 4 else value
                else:
                    out[f"{key[:5]}.bias"] = value.reshape(-1)
            else:
                out[key] = value
        return out
