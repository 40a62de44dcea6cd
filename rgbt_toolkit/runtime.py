"""CPU thread settings shared by torch, OpenCV and the BLAS behind numpy.

On a 2-core machine these three pools fight each other; a Python ECO measured here ran 2x faster with one BLAS
thread. Every entry point (CLI, batch worker, benchmark) calls :func:`set_threads` once.
"""

from __future__ import annotations

import os


def set_threads(n: int | None = None) -> int:
    """Limit torch, OpenCV and BLAS to ``n`` threads each (default: ``RGBT_THREADS`` or 1); return ``n``."""
    if n is None:
        n = int(os.environ.get("RGBT_THREADS", "1"))
    if n < 1:
        raise ValueError(f"thread count must be at least 1, got {n}")
    import cv2
    from threadpoolctl import threadpool_limits

    cv2.setNumThreads(n)
    threadpool_limits(limits=n)
    try:
        import torch

        torch.set_num_threads(n)
    except ImportError:  # pragma: no cover - torch is a hard dependency, kept optional here for tooling
        pass
    return n
