"""Named metric conventions: which formula, scale, padding and colour handling each published code family uses.

A convention is data (a frozen spec), not branches: ``paper`` reproduces the JMMAC image-fusion table (the
DenseFuse MATLAB analysis code, including its MI = 2 * EN quirk, offered as a compatibility mode), ``vifb`` the
VIFB benchmark, ``standard`` textbook definitions on grey 8-bit images. Every metric function takes
``(visible, infrared, fused)`` 2-D float images on the 0-255 scale and returns a float.
See ``docs/fusion_metrics.md`` for the full table of differences.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from typing import Callable, Mapping

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.images import rgb_to_grey
from rgbt_toolkit.metrics import feature_mi as _fmi
from rgbt_toolkit.metrics import gradient as _grad
from rgbt_toolkit.metrics import information as _info
from rgbt_toolkit.metrics import perceptual as _perc
from rgbt_toolkit.metrics import spatial as _spat
from rgbt_toolkit.metrics import ssim as _ssim

MetricFn = Callable[[np.ndarray, np.ndarray, np.ndarray], float]


def _on_fused(fn: Callable[[np.ndarray], float]) -> MetricFn:
    def metric(a, b, f):
        return fn(f)

    metric.__doc__ = fn.__doc__
    return metric


def _mean_over_sources(fn: Callable[[np.ndarray, np.ndarray], float]) -> MetricFn:
    return lambda a, b, f: (fn(a, f) + fn(b, f)) / 2.0


# definitions shared by every convention unless overridden
_COMMON: dict[str, MetricFn] = {
    "EN": _on_fused(_info.entropy),
    "SD": _on_fused(_spat.standard_deviation),
    "SF": _on_fused(_spat.spatial_frequency),
    "AG": _on_fused(_spat.average_gradient),
    "EI": _on_fused(_spat.edge_intensity),
    "CE": _info.cross_entropy,
    "MI": partial(_info.fusion_mutual_information, normalise=False, base=2.0),
    "Qabf": partial(_grad.qabf, scale=1.0, legacy_tie=False),
    "Nabf": partial(_grad.nabf, scale=1.0),
    "FMI_w": partial(_fmi.fmi, feature="wavelet"),
    "FMI_dct": partial(_fmi.fmi, feature="dct"),
    "FMI_edge": partial(_fmi.fmi, feature="edge"),
    "FMI_pixel": partial(_fmi.fmi, feature="none"),
    "SSIM": lambda a, b, f: sum(_ssim.ssim_both(f, a, b)) / 2.0,
    "MS_SSIM": _mean_over_sources(_ssim.ms_ssim),
    "MEF_SSIM": lambda a, b, f: _ssim.mef_ssim([b, a], f),
    "PSNR": _spat.psnr,
    "RMSE": _spat.rmse,
    "CC": _spat.correlation_coefficient,
    "SCD": _spat.scd,
    "VIF": _perc.vif,
    "Qcb": _perc.qcb,
    "Qcv": _perc.qcv,
}

#: metrics where a larger value is worse (shown in docs and table headers)
LOWER_IS_BETTER = frozenset({"Nabf", "CE", "RMSE", "Qcv"})


@dataclass(frozen=True)
class Convention:
    """One code family's conventions.

    Attributes
    ----------
    name, description : str
        Identifier used by ``--convention`` and a one-line summary.
    colour : str
        ``'grey'``: colour inputs become MATLAB ``rgb2gray`` grey first; ``'per_channel'``: each metric runs on
        channel k of F against channel k of each source (a grey source serves every channel), then the channel
        values are averaged (VIFB).
    default_metrics : tuple of str
        Metrics reported when none are asked for.
    overrides : mapping
        Metric definitions that differ from the common (standard) ones.
    folded : frozenset of str
        Metrics computed once on the channels laid side by side instead of per channel (VIFB's SF).
    """

    name: str
    description: str
    colour: str
    default_metrics: tuple[str, ...]
    overrides: Mapping[str, MetricFn] = field(default_factory=dict)
    folded: frozenset = frozenset()

    def metric(self, name: str) -> MetricFn:
        """The function computing ``name`` under this convention."""
        table = {**_COMMON, **self.overrides}
        if name not in table:
            raise InputError(f"unknown metric {name!r}; available: {', '.join(self.available())}")
        return table[name]

    def available(self) -> list[str]:
        return list({**_COMMON, **self.overrides})


CONVENTIONS: dict[str, Convention] = {
    "paper": Convention(
        name="paper",
        description="JMMAC/DenseFuse MATLAB analysis code (compatibility mode: its MI is 2*EN(F))",
        colour="grey",
        default_metrics=("EN", "MI", "Qabf", "FMI_w", "Nabf", "SSIM", "MS_SSIM"),
        overrides={
            "MI": _info.paper_mutual_information,
            "Qabf": partial(_grad.qabf, scale=1.0 / 255.0, legacy_tie=True),
            "Nabf": partial(_grad.nabf, scale=1.0 / 255.0),
            "SSIM": lambda a, b, f: sum(_ssim.ssim_both(f, a, b, padding="same")) / 2.0,
            "MS_SSIM": lambda a, b, f: _ssim.mef_ssim([b, a], f),
        },
    ),
    "vifb": Convention(
        name="vifb",
        description="VIFB benchmark MATLAB code (per colour channel, averaged)",
        colour="per_channel",
        default_metrics=("AG", "CE", "EI", "EN", "MI", "PSNR", "Qabf", "Qcb", "Qcv", "RMSE", "SF", "SSIM", "SD"),
        overrides={
            "MI": partial(_info.fusion_mutual_information, normalise=True, base=np.e),
            "Qabf": partial(_grad.qabf, scale=255.0, legacy_tie=True),
            "SSIM": lambda a, b, f: sum(_ssim.ssim_both(f, a, b)),
            "PSNR": _spat.psnr_vifb,
            "RMSE": _spat.rmse_vifb,
        },
        folded=frozenset({"SF"}),
    ),
    "standard": Convention(
        name="standard",
        description="textbook definitions on grey 8-bit images (MI in bits summed, Wang's MS-SSIM, SSIM averaged)",
        colour="grey",
        default_metrics=("EN", "SD", "SF", "AG", "MI", "SCD", "VIF", "Qabf", "FMI_w", "Nabf", "SSIM", "MS_SSIM"),
    ),
}


def get_convention(name: str) -> Convention:
    """Look a convention up by name; :class:`InputError` lists the valid ones."""
    try:
        return CONVENTIONS[name]
    except KeyError:
        raise InputError(f"unknown convention {name!r}; choose one of {', '.join(CONVENTIONS)}") from None


def to_8bit_scale(image: np.ndarray, name: str = "image") -> np.ndarray:
    """Images as the MATLAB codes saw them: uint8 kept, 16-bit divided by 257 and rounded, floats must be 0-255."""
    image = np.asarray(image)
    if image.dtype == np.uint8:
        return image
    if image.dtype == np.uint16:
        return np.round(image / 257.0).astype(np.uint8)
    if np.issubdtype(image.dtype, np.floating):
        if image.size and (np.nanmin(image) < 0 or np.nanmax(image) > 255):
            raise InputError(f"{name}: float values outside 0..255; scale the image to 8 bits")
        return image
    raise InputError(f"{name}: unsupported pixel type {image.dtype}; use 8-bit or 16-bit images")


def _grey(image: np.ndarray) -> np.ndarray:
    return rgb_to_grey(image) if image.ndim == 3 else image


def _channel(image: np.ndarray, k: int) -> np.ndarray:
    return image[..., k] if image.ndim == 3 else image


def _fold(image: np.ndarray) -> np.ndarray:
    """MATLAB's ``x(:, :)`` on an H x W x C array: channels side by side, H x (W * C)."""
    return np.concatenate([image[..., k] for k in range(image.shape[2])], axis=1) if image.ndim == 3 else image


def score_triple(
    visible: np.ndarray,
    infrared: np.ndarray,
    fused: np.ndarray,
    convention: str | Convention = "paper",
    metrics: list[str] | tuple[str, ...] | None = None,
) -> dict[str, float]:
    """Score one fused image against its visible and infrared sources.

    Parameters
    ----------
    visible, infrared, fused : ndarray
        Grey (H x W) or colour (H x W x 3) images, uint8, uint16 or float on the 0-255 scale.
    convention : str or Convention
        'paper', 'vifb' or 'standard'.
    metrics : sequence of str, optional
        Metric names; defaults to the convention's set.

    Returns
    -------
    dict
        Metric name to value, in the order asked.
    """
    conv = get_convention(convention) if isinstance(convention, str) else convention
    names = list(metrics) if metrics else list(conv.default_metrics)
    fns = {name: conv.metric(name) for name in names}
    images = [to_8bit_scale(x, n) for x, n in ((visible, "visible"), (infrared, "infrared"), (fused, "fused"))]
    sizes = {n: x.shape[:2] for n, x in zip(("visible", "infrared", "fused"), images)}
    if len(set(sizes.values())) > 1:
        listed = ", ".join(f"{n} {s[1]}x{s[0]}" for n, s in sizes.items())
        need = "the fused image must have the sources' size" if sizes["visible"] == sizes["infrared"] else \
            "the visible and infrared images must be registered to one size first (rgbt register)"
        raise InputError(f"image sizes differ ({listed}); {need}")
    a, b, f = images
    if conv.colour == "grey":
        a, b, f = (np.asarray(_grey(x), dtype=np.float64) for x in (a, b, f))
        return {name: float(fn(a, b, f)) for name, fn in fns.items()}
    if f.ndim == 2:  # grey fused image: VIFB converts colour sources to grey
        a, b, f = (np.asarray(_grey(x), dtype=np.float64) for x in (a, b, f))
        return {name: float(fn(a, b, f)) for name, fn in fns.items()}
    channels = f.shape[2]
    as_float = lambda x: np.ascontiguousarray(x, dtype=np.float64)  # noqa: E731
    per_channel = [(as_float(_channel(a, k)), as_float(_channel(b, k)), as_float(f[..., k])) for k in range(channels)]
    out = {}
    for name, fn in fns.items():
        if name in conv.folded:
            a3, b3 = (x if x.ndim == 3 else np.repeat(x[..., None], channels, axis=2) for x in (a, b))
            out[name] = float(fn(*(as_float(_fold(x)) for x in (a3, b3, f))))
        else:
            out[name] = float(np.mean([fn(*triple) for triple in per_channel]))
    return out
