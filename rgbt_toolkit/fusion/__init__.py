"""MFNet: learned fusion weights for RGB and thermal response maps (tracking) and images (``rgbt fuse``).

Parts, one job each: ``network`` (heads, ``fuse_responses``), ``model`` (backbone + heads), ``weights_io`` (files),
``image_fusion`` (``I_F = W_F I_RGB + (1 - W_F) I_T``), ``pixels`` (any input image -> uint8), ``pairs`` (inputs
and outputs of ``rgbt fuse``), ``fuse_files`` (its read / fuse / write loop), ``trainset`` (pairs
from images) / ``seqset`` (pairs from sequences) / ``sources`` (``--data`` folders) / ``responses`` / ``train``
(training, ``rgbt train-mfnet``).
"""

__all__ = ["HeadConfig", "MFNetHeads", "fuse_responses", "MFNet", "load_heads", "save_heads", "fuse_images"]


def __getattr__(name):  # lazy: `import rgbt_toolkit.fusion` must not import torch (3-4 s; the tracker runs ONNX)
    if name in ("HeadConfig", "MFNetHeads", "fuse_responses"):
        from rgbt_toolkit.fusion import network

        return getattr(network, name)
    if name == "MFNet":
        from rgbt_toolkit.fusion.model import MFNet

        return MFNet
    if name in ("load_heads", "save_heads"):
        from rgbt_toolkit.fusion import weights_io

        return getattr(weights_io, name)
    if name == "fuse_images":
        from rgbt_toolkit.fusion.image_fusion import fuse_images

        return fuse_images
    raise AttributeError(name)
