"""Frozen ImageNet feature extractors shared by ECO deep features and MFNet.

>>> from rgbt_toolkit.backbones import load_backbone
>>> bb = load_backbone("efficientnet-lite0")              # packaged ImageNet weights
>>> feats = bb.extract(images)                            # images: [B,3,H,W] float RGB in [0,1]
>>> feats["shallow"].shape[1] == bb.channels["shallow"]   # stride bb.strides["shallow"] (4)
"""

from rgbt_toolkit.backbones.base import Backbone
from rgbt_toolkit.backbones.registry import available, load_backbone, register

__all__ = ["Backbone", "available", "load_backbone", "register"]
