"""MFNet through ONNX Runtime: the tracker's per-frame fusion weights and ``rgbt fuse``, without importing torch.

Why: on the 2-core target machine ``import torch`` alone takes 3-4 s (more than the whole start-up budget of
``rgbt track``), and ONNX Runtime ran the two 128 px MFNet patches about 1.8x faster than torch with one thread each
(docs/benchmarks.md, "Speed"). The same holds for ``rgbt fuse``: one pair took 4.7 s with torch, mostly its import
and set-up, against a 1.5 s start-up goal; it runs :data:`IMAGE_ONNX` (the image-fusion heads). torch stays the
training and reference implementation: the shipped ``.onnx`` files are exported from it by :func:`export_onnx`
(``python -m rgbt_toolkit.fusion.onnx_model``), and tests check that both give the same weights
(tests/fusion/test_onnx_model.py, tests/fusion/test_image_fusion_onnx.py).

The backbone's TF-"SAME" paddings depend on each layer's input size, which the exporter would freeze at the
example's size; exports therefore use the paddings of inputs whose sides are multiples of the layer's stride
(``ConvBN.sizes_divisible``), and the runners here refuse other sizes rather than return shifted features.

The graph takes the RGB and the thermal patch as ``[1, 3, H, W]`` float32 in [0, 1] (grey repeated on three
channels) and returns the two heads' logits: the global one ``[1]`` and the local map ``[1, h, w]`` before it is
resized to the response grid; resizing and the sigmoids run here in numpy/OpenCV (bilinear, half-pixel centres, as
``torch.nn.functional.interpolate(..., align_corners=False)``).
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError, MissingFileError, WeightsError
from rgbt_toolkit.fusion.onnx_graph import optimise_export

TRACKING_ONNX = Path(__file__).resolve().parent / "weights" / "mfnet_tracking.onnx"
# the image-fusion heads (weights/mfnet_heads.pt) with the same backbone: the default network of `rgbt fuse`
IMAGE_ONNX = Path(__file__).resolve().parent / "weights" / "mfnet_heads.onnx"
STRIDE = 16  # the heads' backbone layer ("deep") stride: patch sides must be multiples of it (module docstring)
# EfficientNet-Lite0's "shallow" (stride 4) layer: the deep features of the DDIS template scorer (motion/parts.py)
SHALLOW_ONNX = Path(__file__).resolve().parent / "weights" / "efficientnet-lite0_shallow.onnx"
# its shallow (stride 4) and deep (stride 16) layers in one graph: the `deep` ECO preset's backbone features
SHALLOW_DEEP_ONNX = Path(__file__).resolve().parent / "weights" / "efficientnet-lite0_shallow_deep.onnx"
INPUTS = ("rgb", "t")
OUTPUTS = ("global_logit", "local_logits")


def _session(ort, path: Path, threads: int):
    """An ONNX Runtime CPU session with ``threads`` intra-op threads; a file ORT cannot load is a WeightsError."""
    options = ort.SessionOptions()
    options.intra_op_num_threads = max(1, int(threads))
    options.inter_op_num_threads = 1
    try:
        return ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    except Exception as exc:  # ORT raises its own types for corrupt or foreign files
        raise WeightsError(f"{path}: not a loadable ONNX model ({str(exc).splitlines()[0][:160]})") from None


def _check_multiple(shape, multiple: int, path: Path) -> None:
    if shape[0] % multiple or shape[1] % multiple:
        raise InputError(f"{path}: patch sides must be multiples of {multiple} for this export, got "
                         f"{shape[1]}x{shape[0]}")


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-x))


def to_input(patch: np.ndarray) -> np.ndarray:
    """A uint8 ``[H, W]`` or ``[H, W, 3]`` patch -> ``[1, 3, H, W]`` float32 in [0, 1] (grey on three channels)."""
    a = np.asarray(patch)
    if a.ndim == 2:
        a = a[:, :, None].repeat(3, axis=2)
    if a.ndim != 3 or a.shape[2] != 3:
        raise InputError(f"expected a grey [H,W] or colour [H,W,3] patch, got shape {a.shape}")
    scale = np.float32(1 / 255.0) if a.dtype == np.uint8 else np.float32(1.0)
    return np.ascontiguousarray(a.transpose(2, 0, 1)[None], dtype=np.float32) * scale


class OnnxMfnet:
    """An exported MFNet (backbone + heads) in an ONNX Runtime session.

    Parameters
    ----------
    path : path-like, optional
        The ``.onnx`` file (default: the shipped tracking network, :data:`TRACKING_ONNX`).
    threads : int
        Intra-op threads of the session (the tracker runs its parts on one thread each by default).
    """

    def __init__(self, path: str | os.PathLike | None = None, threads: int = 1) -> None:
        try:
            import onnxruntime as ort
        except ImportError:  # pragma: no cover - a dependency; kept as a message for broken installations
            raise WeightsError("onnxruntime is not installed; `pip install onnxruntime` (or pass torch weights: "
                               "rgbt track --mfnet-weights FILE.pt, rgbt fuse --weights FILE.pt)") from None
        self.path = Path(path) if path is not None else TRACKING_ONNX
        if not self.path.is_file():
            raise MissingFileError(f"{self.path}: MFNet ONNX file not found")
        self.session = _session(ort, self.path, threads)
        names = tuple(i.name for i in self.session.get_inputs())
        outs = tuple(o.name for o in self.session.get_outputs())
        if names != INPUTS or outs != OUTPUTS:
            raise WeightsError(f"{self.path}: not an MFNet export (inputs {names}, outputs {outs}; expected "
                               f"{INPUTS} -> {OUTPUTS}, as `python -m rgbt_toolkit.fusion.onnx_model` writes)")

    def logits(self, rgb: np.ndarray, thermal: np.ndarray) -> tuple[float, np.ndarray]:
        """The heads' raw outputs for one RGB and one thermal patch of the same size (sides multiples of
        :data:`STRIDE`): the global logit and the local logit map ``[H/4, W/4]`` float32, before any sigmoid."""
        a, b = to_input(rgb), to_input(thermal)
        _check_multiple(a.shape[2:], STRIDE, self.path)
        if a.shape != b.shape:
            raise InputError(f"RGB and T patches differ in size: {a.shape[2:]} vs {b.shape[2:]}")
        g, local = self.session.run(OUTPUTS, {"rgb": a, "t": b})
        return float(g.reshape(-1)[0]), local[0].astype(np.float32, copy=False)

    def patch_weights(self, rgb: np.ndarray, thermal: np.ndarray, grid: tuple[int, int]) -> tuple[float, np.ndarray]:
        """``(w_G, W_L)`` for one RGB and one thermal patch of the same size; ``W_L`` resized to ``grid`` (rows, cols)."""
        g, local = self.logits(rgb, thermal)
        logits = cv2.resize(local, (int(grid[1]), int(grid[0])), interpolation=cv2.INTER_LINEAR)
        return float(_sigmoid(g)), _sigmoid(logits.astype(np.float64))


class OnnxLayers:
    """Backbone layers exported by :func:`export_layers_onnx`: ``patch (uint8 [H, W] or [H, W, 3]) -> [h, w, C]``
    feature maps, one per layer, the same as ``Backbone.extract`` gives (without importing torch).

    ``strides``: each output's stride, in the export's output order (patch sides must be multiples of the largest).
    """

    def __init__(self, path: str | os.PathLike, strides: int | tuple[int, ...], threads: int = 1) -> None:
        import onnxruntime as ort

        self.path = Path(path)
        self.strides = (strides,) if isinstance(strides, int) else tuple(strides)
        if not self.path.is_file():
            raise MissingFileError(f"{self.path}: backbone ONNX file not found")
        self.session = _session(ort, self.path, threads)
        outputs = self.session.get_outputs()
        if len(outputs) != len(self.strides):
            raise WeightsError(f"{self.path}: {len(outputs)} outputs where {len(self.strides)} layers were expected")
        self.channels = tuple(int(o.shape[1]) for o in outputs)

    def maps(self, patch: np.ndarray, dtype=np.float64) -> list[np.ndarray]:
        """Every exported layer's ``[h, w, C]`` map of one patch."""
        x = to_input(patch)
        _check_multiple(x.shape[2:], max(self.strides), self.path)
        return [np.ascontiguousarray(out[0].transpose(1, 2, 0), dtype=dtype)
                for out in self.session.run(None, {"image": x})]

    def __call__(self, patch: np.ndarray, dtype=np.float64) -> np.ndarray:
        """The map of an export with one layer."""
        if len(self.strides) != 1:
            raise InputError(f"{self.path}: exports {len(self.strides)} layers; use maps()")
        return self.maps(patch, dtype)[0]


# backbone layers whose exports ship (with the backbone's own weights), by (backbone, layers): (file, strides)
SHIPPED_LAYERS = {("efficientnet-lite0", ("shallow",)): (SHALLOW_ONNX, (4,)),
                  ("efficientnet-lite0", ("shallow", "deep")): (SHALLOW_DEEP_ONNX, (4, 16))}


@functools.lru_cache(maxsize=None)
def _load_shipped(backbone: str, layers: tuple[str, ...]) -> OnnxLayers:
    path, strides = SHIPPED_LAYERS[(backbone, layers)]
    return OnnxLayers(path, strides)


def shipped_layers(backbone: str, layers: tuple[str, ...], weights=None) -> "OnnxLayers | None":
    """The shipped ONNX export of these backbone layers with the backbone's own weights (loaded once and shared), or
    None when none ships for them (other layers, user weights): then the caller runs torch. Why: ``import torch``
    alone costs 2-7 s of start-up, and with one thread ECO's hc+cnn preset tracked a real clip at 19.0 ms per frame
    from the export against 24.3 ms from torch, deep at 45.2 against 55.6 (docs/decisions.md, D50)."""
    layers = tuple(layers)
    if weights is not None or (backbone, layers) not in SHIPPED_LAYERS:
        return None
    return _load_shipped(backbone, layers)


def export_layers_onnx(backbone, layers: tuple[str, ...], path: str | os.PathLike, patch: int = 48) -> Path:
    """Write layers of a :class:`~rgbt_toolkit.backbones.Backbone` (input normalisation included) as one ONNX graph
    with an output per layer, in the order given."""
    import torch

    layers = tuple(layers)

    class Graph(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.backbone = backbone

        def forward(self, image):
            maps = self.backbone._features(self.backbone.normalise(image), layers)
            return tuple(maps[n] for n in layers)

    axes = {"image": {2: "height", 3: "width"}, **{n: {2: "rows", 3: "cols"} for n in layers}}
    return _export(Graph().eval(), (torch.rand(1, 3, patch, patch),), ("image",), layers, axes, path)


def _export(graph, example, inputs, outputs, axes, path) -> Path:
    import warnings

    import torch

    from rgbt_toolkit._atomic import atomic_path

    import importlib.util

    if importlib.util.find_spec("onnx") is None:  # torch.onnx.export needs it
        raise InputError("exporting to ONNX needs the onnx package: pip install onnx")
    padded = [m for m in graph.modules() if hasattr(m, "sizes_divisible")]
    try:
        for m in padded:
            m.sizes_divisible = True
        with atomic_path(path) as tmp, torch.no_grad(), warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the TorchScript exporter's deprecation and shape-inference notices
            torch.onnx.export(graph, example, str(tmp), input_names=list(inputs), output_names=list(outputs),
                              dynamic_axes=axes, opset_version=17, dynamo=False)
    finally:
        for m in padded:
            m.sizes_divisible = False
    optimise_export(path)
    return Path(path)


def export_onnx(net, path: str | os.PathLike, patch: int = 128) -> Path:
    """Write ``net`` (an :class:`~rgbt_toolkit.fusion.model.MFNet`) as an ONNX graph with free patch height/width.

    Needs torch and the ``onnx`` package (``pip install onnx``); only the people who train or ship weights export.
    """
    import torch

    class Graph(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.backbone, self.heads, self.layer = net.backbone, net.heads, net.config.layer

        def forward(self, rgb, t):
            x = self.backbone.normalise(torch.cat([rgb, t]))
            f = self.backbone._features(x, (self.layer,))[self.layer]
            feats = torch.cat([f[:1], f[1:]], dim=1)
            return self.heads.global_head(feats), self.heads.local_head(feats)

    example = (torch.rand(1, 3, patch, patch), torch.rand(1, 3, patch, patch))
    axes = {name: {2: "height", 3: "width"} for name in INPUTS}
    axes["local_logits"] = {1: "rows", 2: "cols"}
    return _export(Graph().eval(), example, INPUTS, OUTPUTS, axes, path)


def main(argv: list[str] | None = None) -> None:  # pragma: no cover - a maintainer's tool
    """``python -m rgbt_toolkit.fusion.onnx_model``: re-export the shipped networks (MFNet with the tracking heads,
    MFNet with the image-fusion heads, and the backbone layers of :data:`SHIPPED_LAYERS`); ``... HEADS.pt
    OUT.onnx``: export MFNet with your own heads for --mfnet-weights."""
    import sys

    from rgbt_toolkit.backbones import load_backbone
    from rgbt_toolkit.fusion.model import MFNet
    from rgbt_toolkit.fusion.weights_io import DEFAULT_WEIGHTS
    from rgbt_toolkit.fusion.shipped import TRACKING_HEADS

    args = sys.argv[1:] if argv is None else argv
    if len(args) == 2:
        written = [export_onnx(MFNet.from_file(args[0]), args[1])]
    elif not args:
        written = [export_onnx(MFNet.from_file(TRACKING_HEADS), TRACKING_ONNX),
                   export_onnx(MFNet.from_file(DEFAULT_WEIGHTS), IMAGE_ONNX),
                   *(export_layers_onnx(load_backbone("efficientnet-lite0"), layers, path)
                     for (_, layers), (path, _) in SHIPPED_LAYERS.items())]
    else:
        raise SystemExit("usage: python -m rgbt_toolkit.fusion.onnx_model [HEADS.pt OUT.onnx]")
    for out in written:
        print(f"wrote {out} ({out.stat().st_size / 1e6:.2f} MB)")


if __name__ == "__main__":  # pragma: no cover
    main()
