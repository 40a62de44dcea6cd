"""Registration, image fusion and fusion metrics from Python: arrays or paths in, arrays and records out.

Thin wrappers over :mod:`rgbt_toolkit.registration`, :mod:`rgbt_toolkit.fusion` and :mod:`rgbt_toolkit.metrics`
that take what a notebook holds (numpy images) as well as what the CLI takes (files).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any, Union

import numpy as np

from rgbt_toolkit.api.frames import as_calibration, is_path
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.registration.calib import Calibration

Image = Union[str, os.PathLike, np.ndarray]


def load_calibration(path: str | os.PathLike) -> Calibration:
    """Read a calibration file written by :func:`register` (or ``rgbt register``)."""
    return as_calibration(path)


def _stream(source: Any, what: str, fps: float):
    """A re-iterable ``(grey frame, t)`` source from one image or a sequence of images (``fps`` apart)."""
    from rgbt_toolkit.registration.features import to_grey

    frames = [source] if isinstance(source, np.ndarray) and source.ndim == 2 or \
        isinstance(source, np.ndarray) and source.ndim == 3 and source.shape[2] in (3, 4) else list(source)
    if not frames:
        raise InputError(f"{what}: no frames to register")
    grey = [to_grey(np.asarray(frame)) for frame in frames]
    return lambda: iter([(frame, k / fps) for k, frame in enumerate(grey)])


def register(rgb: Image | Sequence[np.ndarray], thermal: Image | Sequence[np.ndarray], *, model: str = "homography",
             sync: bool = False, max_offset: float = 2.0, offset: float | None = None, pairs: int = 4,
             fps: float | None = None, rgb_fps: float | None = None, thermal_fps: float | None = None) -> Calibration:
    """Estimate how RGB pixels map to thermal pixels (and, with ``sync``, the clock offset), as ``rgbt register``.

    Parameters
    ----------
    rgb, thermal : path, image or sequence of images
        Two videos, frame folders or images; or numpy images (one each, or two lists of frames).
    model : {'homography', 'affine', 'similarity'}
    sync, max_offset, offset :
        Estimate the offset (searching +-``max_offset`` s), or give a known one (thermal time = RGB time + offset).
    pairs : int
        Frame pairs, spread over the recording, used for the spatial estimate.
    fps, rgb_fps, thermal_fps : float, optional
        Frame rates of frame folders or image lists (default 30).

    Returns
    -------
    Calibration
        ``matrix`` (3x3, RGB -> thermal pixels), sizes, offset, quality; ``save(path)`` writes the JSON file.

    Raises
    ------
    RegistrationError
        When the views cannot be registered (never a bad transform reported as good).
    """
    from rgbt_toolkit.registration.pipeline import MAX_PAIRS, RegisterSettings, register_paths, register_streams
    from rgbt_toolkit.registration.spatial import SpatialSettings
    from rgbt_toolkit.registration.transforms import MODELS

    if sync and offset is not None:
        raise InputError("give either --sync (estimate the offset) or --offset (a known one), not both")
    if model not in MODELS:
        raise InputError(f"model must be one of {', '.join(MODELS)}, got {model!r}")
    if not 1 <= pairs <= MAX_PAIRS:
        raise InputError(f"pairs must be between 1 and {MAX_PAIRS}, got {pairs}")
    settings = RegisterSettings(spatial=SpatialSettings(model=model), sync=sync, max_offset=max_offset,
                                max_pairs=pairs, offset=offset or 0.0)
    if is_path(rgb) and is_path(thermal):
        return register_paths(rgb, thermal, settings, fps=fps, rgb_fps=rgb_fps, thermal_fps=thermal_fps).calibration
    if is_path(rgb) or is_path(thermal):
        raise InputError("register: give two paths or two sets of numpy frames, not one of each")
    streams = _stream(rgb, "rgb", rgb_fps or fps or 30.0), _stream(thermal, "thermal", thermal_fps or fps or 30.0)
    return register_streams(*streams, settings).calibration


def _read(image: Image, what: str) -> np.ndarray:
    from rgbt_toolkit.io.images import read_image

    if is_path(image):
        return read_image(image)
    if not isinstance(image, np.ndarray):
        raise InputError(f"{what}: expected an image path or a numpy array, got {type(image).__name__}")
    return image


def fuse(vis: Image, ir: Image, *, weights: str | os.PathLike | None = None,
         calib: str | os.PathLike | Calibration | None = None, registered: bool = False, mode: str = "mfnet",
         net_side: int | None = None, backbone_weights: str | os.PathLike | None = None,
         return_weights: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Fuse a visible and an infrared image with MFNet: ``I_F = W_F * I_vis + (1 - W_F) * I_ir``, as ``rgbt fuse``.

    Parameters
    ----------
    vis, ir : path or ndarray
        Visible (grey or RGB) and infrared image.
    weights, backbone_weights : path, optional
        MFNet head weights (default: the shipped image-fusion heads); user backbone weights where needed.
    calib : path or Calibration, optional
        Aligns an unregistered pair (``rgbt register`` file, or JSON ``{"H": 3x3}`` infrared -> visible).
    registered : bool
        Same field of view, other resolution: resize the infrared image onto the visible grid.
    mode : {'mfnet', 'global', 'local'}
        Which weight heads to use (the paper's ablation).
    return_weights : bool
        Also return the weight map W_F (float32, H x W, weight of the visible image).

    Returns
    -------
    ndarray or (ndarray, ndarray)
        The fused uint8 image (grey, or RGB like a colour visible input); with ``return_weights`` also W_F.
    """
    import dataclasses

    from rgbt_toolkit.fusion.fuse_files import load_fusion_net
    from rgbt_toolkit.fusion.image_fusion import FuseSettings, fuse_images, grey_of
    from rgbt_toolkit.fusion.pairs import Alignment, read_calibration
    from rgbt_toolkit.io.pixels import as_uint8

    if registered and calib is not None:
        raise InputError("--registered and --calib exclude each other: --calib already aligns the pair")
    if mode not in ("mfnet", "global", "local"):
        raise InputError(f"mode must be 'mfnet', 'global' or 'local', got {mode!r}")
    if isinstance(calib, Calibration):
        alignment = Alignment(calib.inverse, rgb_size=tuple(calib.rgb_size), thermal_size=tuple(calib.thermal_size))
    else:
        alignment = read_calibration(calib) if calib is not None else Alignment(resize=registered)
    v = as_uint8(_read(vis, "vis"), "visible")
    i = grey_of(as_uint8(_read(ir, "ir"), "infrared"))
    i = alignment.apply(i, v.shape[:2], vis if is_path(vis) else "visible", ir if is_path(ir) else "infrared")
    settings = FuseSettings(use_global=mode != "local", use_local=mode != "global")
    if net_side is not None:
        settings = dataclasses.replace(settings, net_side=net_side)
    result = fuse_images(v, i, load_fusion_net(weights, backbone_weights), settings)
    return (result.fused, result.w_f) if return_weights else result.fused


def fusion_metrics(vis: Image, ir: Image, fused: Image, *, convention: str = "paper",
                   metrics: Sequence[str] | None = None) -> dict[str, float]:
    """Score a fused image against its sources with a published code family's definitions (``rgbt fusion-metrics``).

    Parameters
    ----------
    vis, ir, fused : path or ndarray
        Grey or colour images of one size.
    convention : {'paper', 'vifb', 'standard'}
        ``paper``: JMMAC/DenseFuse table code; ``vifb``: the VIFB benchmark; ``standard``: textbook definitions.
    metrics : sequence of str, optional
        Metric names (default: the convention's set).

    Returns
    -------
    dict
        Metric name -> value, in the order asked.
    """
    from rgbt_toolkit.metrics.conventions import score_triple
    from rgbt_toolkit.metrics.scoring import read_scored_image

    images = [read_scored_image(x) if is_path(x) else _read(x, what)
              for x, what in ((vis, "vis"), (ir, "ir"), (fused, "fused"))]
    return score_triple(*images, convention=convention, metrics=list(metrics) if metrics else None)
