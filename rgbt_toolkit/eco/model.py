"""Per-block constants of the ECO model and the map from image patches to Fourier samples.

A *block* is one feature map at its own resolution (fHOG, colour names, a deep layer). For each block the tracker
keeps its interpolation coefficients, cosine window, label (the Fourier coefficients of the Gaussian desired output)
and spatial-regularisation filter, all fixed at initialisation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.eco.fourier import cfft2
from rgbt_toolkit.eco.interp import interp_coefficients
from rgbt_toolkit.eco.params import EcoParams
from rgbt_toolkit.eco.regularization import reg_filter
from rgbt_toolkit.features.base import BlockSpec, Feature
from rgbt_toolkit.features.pooling import cells_at_scales


@dataclass(frozen=True)
class BlockModel:
    """Constants of one feature block (``n`` cells per side, ``ny`` x ``nxh`` half-layout coefficients)."""

    spec: BlockSpec
    n: int
    ny: int
    nxh: int
    interp: np.ndarray      # (ny, nxh) complex64
    window: np.ndarray      # (n, n) float32
    label: np.ndarray       # (ny, nxh) complex64
    reg: np.ndarray         # small real filter
    reg_energy: float


def build_features(params: EcoParams, colour: bool) -> list[Feature]:
    """Feature extractors named in ``params.features``; ``"colour"`` picks colour names or intensity by ``colour``."""
    from rgbt_toolkit.features.colornames import ColourNames, load_colour_table
    from rgbt_toolkit.features.fhog import FHog
    from rgbt_toolkit.features.intensity import Intensity

    out: list[Feature] = []
    for name in params.features:
        if name == "fhog":
            out.append(FHog(params.cell_size, params.fhog_dim))
        elif name == "colornames" or (name == "colour" and colour):
            table = load_colour_table(params.colour_table) if params.colour_table else None
            out.append(ColourNames(params.cell_size, params.colour_dim, table))
        elif name in ("intensity", "colour"):
            out.append(Intensity(params.cell_size, params.colour_dim, params.intensity_bins))
        elif name == "deep":
            from rgbt_toolkit.features.deep import DeepFeatures

            out.append(DeepFeatures(params.backbone, params.backbone_weights, params.deep_layers, params.deep_dims))
    return out


def _hann(n: int) -> np.ndarray:
    """ECO's cosine window: the inner ``n`` points of a Hann window of ``n + 2`` points."""
    return np.hanning(n + 2)[1:-1]


def label_coefficients(ny: int, nxh: int, sigma: float, period: float) -> np.ndarray:
    """Fourier coefficients of a periodic Gaussian ``exp(-|t|^2 / (2 sigma^2))`` with period ``period``."""
    ky = np.arange(ny) - (ny - 1) // 2
    kx = np.arange(nxh)
    g = lambda k: np.sqrt(2 * np.pi) * sigma / period * np.exp(-2 * (np.pi * sigma * k / period) ** 2)  # noqa: E731
    return (g(ky)[:, None] * g(kx)[None, :]).astype(np.complex64)


def build_blocks(features: list[Feature], params: EcoParams, patch: int, base_target: tuple[float, float]) -> list:
    """Block constants for a patch of side ``patch`` and a target of ``base_target`` (h, w) patch pixels."""
    sigma = np.sqrt(np.floor(base_target[0]) * np.floor(base_target[1])) * params.output_sigma_factor
    reg = reg_filter(patch, base_target, reg_min=params.reg_window_min, reg_edge=params.reg_window_edge,
                     power=params.reg_window_power, sparsity=params.reg_sparsity)
    blocks = []
    for feat in features:
        for spec in feat.blocks:
            n = -(-patch // spec.stride)  # ceil, as the backbones' "same" padding
            ny = n + 1 - n % 2
            nxh = (ny + 1) // 2
            c = interp_coefficients(n, params.interp_a, params.interp_centering)
            interp = (c[:, None] * c[None, (ny - 1) // 2 :]).astype(np.complex64)
            win = np.outer(_hann(n), _hann(n)).astype(np.float32) if params.cos_window else np.ones((n, n), np.float32)
            blocks.append(BlockModel(spec, n, ny, nxh, interp, win, label_coefficients(ny, nxh, sigma, patch),
                                     reg.astype(np.float32), float(np.sum(reg**2))))
    return blocks


def compute_blocks(features: list[Feature], patch: np.ndarray, ratios: np.ndarray, size: int) -> list[np.ndarray]:
    """Cell maps ``(S, n, n, dim)`` per block at each scale ``ratios`` (relative to the scale ``patch`` was cut at).

    ``patch`` is the single base patch of the frame; ``size`` the side of the tracker's sample patch (the period).
    Each map is pooled on its own: with the compiled cell reads, joining maps first only added a copy.
    """
    out: list[np.ndarray] = []
    for feat in features:
        cells = [cells_at_scales(fmap, ms, spec.stride, size, ratios, patch.shape[0])
                 for (fmap, ms), spec in zip(feat.maps(patch), feat.blocks)]
        out.extend(feat.finish(cells))
    return out


def base_patch_size(size: int, ratio: float, features: list[Feature]) -> int:
    """Side of the base patch covering ``ratio`` x ``size`` pixels, a multiple of the coarsest stride."""
    m = max(spec.stride for feat in features for spec in feat.blocks)
    return int(np.ceil(size * ratio / m - 1e-9) * m)


def normalise(x: np.ndarray, power: float) -> np.ndarray:
    """ECO's feature normalisation: per sample, mean of ``|x|^power`` over cells and channels becomes 1."""
    s = x.shape[0]
    flat = x.reshape(s, -1)
    # |x|^2 is x*x bit for bit (numpy squares for the exponent 2): one temporary fewer on every search
    energy = np.square(flat) if power == 2 else np.abs(flat) ** power
    norm = (np.sum(energy, axis=1) / x[0].size + 1e-12) ** (1.0 / power)
    return x / norm.astype(np.float32)[:, None, None, None]


def to_fourier(x: np.ndarray, block: BlockModel, power: float, projection: np.ndarray | None = None) -> np.ndarray:
    """``(S, n, n, D)`` feature map -> ``(S, C, ny, nxh)`` interpolated, centred Fourier coefficients.

    With ``projection`` (D, C) the channels are compressed first (in the spatial domain, which needs fewer FFTs).
    """
    x = normalise(x, power)
    x *= block.window[None, :, :, None]
    if projection is not None:
        x = x @ projection
    xf = cfft2(np.ascontiguousarray(x.transpose(0, 3, 1, 2)))
    return (xf * block.interp).astype(np.complex64, copy=False)
