"""Process-wide CPU settings: threads of torch, OpenCV and BLAS, and the heap's handling of large temporaries.

On a 2-core machine these three pools fight each other; a Python ECO measured here ran 2x faster with one BLAS
thread. Every entry point (CLI, batch worker, benchmark) calls :func:`set_threads` once.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import sys
import threading

from rgbt_toolkit.errors import InputError


def thread_count(n: int | None, default: int) -> int:
    """``n``, else ``RGBT_THREADS``, else ``default``; a clear error for a value that is not a positive integer."""
    if n is None:
        raw = os.environ.get("RGBT_THREADS", str(default))
        try:
            n = int(raw)
        except ValueError:
            raise InputError(f"RGBT_THREADS={raw!r} is not a whole number of threads") from None
    if n < 1:
        raise InputError(f"thread count must be at least 1, got {n}")
    return n


def set_threads(n: int | None = None) -> int:
    """Limit torch, OpenCV and BLAS to ``n`` threads each (default: ``RGBT_THREADS`` or 1); return ``n``."""
    n = thread_count(n, default=1)
    import cv2
    from threadpoolctl import threadpool_limits

    cv2.setNumThreads(n)
    threadpool_limits(limits=n)
    if "torch" in sys.modules:
        sys.modules["torch"].set_num_threads(n)
    else:  # importing torch costs 2-7 s, more than a whole `rgbt register`; it reads this when a command loads it
        os.environ["OMP_NUM_THREADS"] = os.environ["MKL_NUM_THREADS"] = str(n)
    return n


# How much nicer than the process the threads that only feed or drain the tracker run (the read-ahead decoder, the
# video writer). On two busy cores the tracking threads then get the CPU first and those threads the time left over;
# they stay ahead (reader) or catch up (writer) through their bounded queues. `rgbt track` on a 300-frame 1080p +
# 640x512 pair: 7.36-7.73 s against 7.77-7.93 s, four alternated pairs (docs/decisions.md, D18).
BACKGROUND_NICE = 10


def lower_thread_priority(increment: int = BACKGROUND_NICE) -> bool:
    """Make the calling thread ``increment`` nicer (at most 19); whether it could.

    Linux keeps a nice value per thread, so this touches no other thread (threads it starts later inherit it, e.g. a
    decoder's). Elsewhere nothing changes (False): ``setpriority`` there would apply to the whole process.
    """
    if increment <= 0 or not sys.platform.startswith("linux"):
        return False
    try:
        tid = threading.get_native_id()
        os.setpriority(os.PRIO_PROCESS, tid, min(19, os.getpriority(os.PRIO_PROCESS, tid) + increment))
    except (OSError, AttributeError):
        return False
    return True


def split_tracker_threads(n: int | None = None, *, io_threads: bool = False) -> tuple[int, bool]:
    """``(threads per library, parallel trackers)`` for a JMMAC run given ``n`` CPU threads in all.

    The RGB and the thermal ECO tracker run on two Python threads when at least two cores are theirs; each library
    (OpenCV, BLAS, ONNX Runtime, torch) then gets half of those cores, so two trackers never ask for more threads
    than there are cores (``--threads 2`` used to give every library two threads *and* run two trackers: four busy
    threads on two cores, 2x slower). ``io_threads``: a reader thread decodes ahead and a writer thread encodes the
    video (``rgbt track``'s default); one of the ``n`` cores is then theirs, so on two cores the trackers take turns
    on the other: on real 1080p footage that run ends 10 % sooner than two tracker threads beside the I/O threads
    (docs/decisions.md, D52). ``n = 1`` runs the tracker on one thread. Default ``n``: ``RGBT_THREADS``, else 2.
    """
    n = thread_count(n, default=2)
    tracker_cores = n - 1 if io_threads and n >= 2 else n
    return (max(1, tracker_cores // 2), True) if tracker_cores >= 2 else (1, False)


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
