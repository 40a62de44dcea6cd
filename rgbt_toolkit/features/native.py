"""The compiled feature loops (``_kernels.c``, built by ``pip install``), with a clear error when they are missing."""

from __future__ import annotations

from rgbt_toolkit._native import load_compiled

kernels = load_compiled("rgbt_toolkit.features._kernels")

__all__ = ["kernels"]
