"""rgbt-toolkit: paired visible (RGB) and thermal (T) video and image processing.

The library half of the product: trackers, fusion, registration, metrics, evaluation and I/O. It never imports the
command-line interface, never prints and never configures logging. The public API (``track``, ``Tracker``,
``register``, ``load_calibration``, ``fuse``, ``fusion_metrics``, ``evaluate``; see ``docs/api.md``) loads on first
use, so ``import rgbt_toolkit`` stays fast and pulls in neither torch nor OpenCV.
"""

import importlib

from rgbt_toolkit.api import EXPORTS as _EXPORTS

__version__ = "0.1.0"
__all__ = ["__version__", *sorted(_EXPORTS)]


def __getattr__(name: str):
    """Import the public API lazily (torch and OpenCV load only when a function needs them)."""
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"rgbt_toolkit.api.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
