"""Process-wide CPU settings: threads of torch, OpenCV and BLAS, and the heap's handling of large temporaries.

On a 2-core machine these three pools fight each other; a Python ECO measured here ran 2x faster with one BLAS
thread. Every entry point (CLI, batch worker, benchmark) calls :func:`set_threads` once.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os

from rgbt_toolkit.errors import InputError


def set_threads(n: int | None = None) -> int:
    """Limit torch, OpenCV and BLAS to ``n`` threads each (default: ``RGBT_THREADS`` or 1); return ``n``."""
    if n is None:
        raw = os.environ.get("RGBT_THREADS", "1")
        try:
            n = int(raw)
        except ValueError:
            raise InputError(f"RGBT_THREADS={raw!r} is not a whole number of threads") from None
    if n < 1:
        raise InputError(f"thread count must be at least 1, got {n}")
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


# Image-sized float64 temporaries (2.4 MB at 640x480) are above glibc's dynamic mmap threshold, so each one is mapped
# fresh and page-faulted in again after it is freed; in a virtual machine that was 40-50 % of the time of the fusion
# metrics (13 000 faults per MEF-SSIM call). Raising the mmap and trim thresholds once per process lets freed blocks
# be reused. Entry points (the CLI, benchmarks) call it; the library itself never changes process settings.
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_done = False


def keep_freed_memory(mmap_threshold: int = 64 << 20, trim_threshold: int = 256 << 20) -> bool:
    """Set glibc's mmap threshold (blocks above it are mapped) and trim threshold; True when applied."""
    global _done
    if _done:
        return True
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):  # not glibc: nothing to tune
        return False
    _done = bool(mallopt(_M_MMAP_THRESHOLD, mmap_threshold)) and bool(mallopt(_M_TRIM_THRESHOLD, trim_threshold))
    return _done
