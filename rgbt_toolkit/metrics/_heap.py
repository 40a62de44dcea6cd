"""Keep freed image-sized temporaries in the process heap (glibc), so the metrics do not page-fault on every one.

The metrics allocate many image-sized float64 temporaries (2.4 MB for 640x480). glibc serves blocks above its
dynamic mmap threshold with fresh ``mmap`` calls and returns them on ``free``, so every such temporary is
page-faulted in again; in a virtual machine that was 40-50 % of the time of Qabf, Nabf, SSIM and MEF-SSIM
(13 000 faults per MEF-SSIM call). :func:`keep_freed_memory` raises the mmap and trim thresholds once per process
(``mallopt``), after which freed blocks are reused. Memory is then returned to the system only when a large
free block sits at the top of the heap; scoring processes are short-lived or stay at the same working set.
Elsewhere than on glibc it does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util

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
