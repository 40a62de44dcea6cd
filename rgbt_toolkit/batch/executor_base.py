"""What every executor shares: the :class:`Executor` interface, the :class:`Outcome` of one call, and
:func:`call_item`, through which every executor runs the task function.

Why a module of its own: the local executors (:mod:`~rgbt_toolkit.batch.executors`, which also picks one for the
CLI) and the Dask executor (:mod:`~rgbt_toolkit.batch.dask_executor`) both build on these; kept in ``executors``,
that module and the Dask one would import each other.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
import traceback
import warnings
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

from rgbt_toolkit.errors import InputError, RgbtError

#: Environment variables read by the BLAS / OpenMP runtimes when they load; set in each worker before any import.
THREAD_ENV_VARS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMEXPR_NUM_THREADS",
                   "VECLIB_MAXIMUM_THREADS")

_threads_set_in_process: int | None = None


@dataclass(frozen=True)
class Outcome:
    """What one call of the task function gave: its value, or the error as text, and how long it took."""

    value: Any = None
    error: str | None = None  # "ExceptionType: message"; None on success
    details: str | None = None  # the formatted traceback, for logs
    seconds: float = 0.0
    cpu_seconds: float = 0.0  # CPU time of the process running the call (all its threads) during the call
    attempts: int = 1  # runs this outcome stands for (an item that crashed its pool, then crashed alone: 2)
    final: bool = False  # the library refused the item's input (RgbtError): running it again gives the same
    warnings: tuple[str, ...] = ()  # the warnings the call raised, one line each, for the CLI to print as it likes

    @property
    def ok(self) -> bool:
        return self.error is None


def cpu_count() -> int:
    """CPU cores this process may use (the affinity mask where the OS has one, else ``os.cpu_count``)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS / Windows
        return os.cpu_count() or 1


def threads_per_worker(workers: int, cores: int | None = None) -> int:
    """Threads each of ``workers`` processes may use so that together they fill, not oversubscribe, the cores."""
    cores = cpu_count() if cores is None else cores
    return max(1, cores // max(1, workers))


def limit_threads(threads: int) -> None:
    """Limit torch, OpenCV and BLAS to ``threads`` each, once per process.

    The thread environment variables are set first (``RGBT_THREADS`` too, so a task calling
    :func:`rgbt_toolkit.runtime.set_threads` with its default keeps the limit). When torch is already loaded this is
    :func:`~rgbt_toolkit.runtime.set_threads`; otherwise torch is not imported just for this (it costs 2-7 s per
    worker, and tasks such as fusion metrics never need it): it takes ``OMP_NUM_THREADS`` when a task loads it.
    """
    global _threads_set_in_process
    if _threads_set_in_process == threads:
        return
    if threads < 1:
        raise InputError(f"thread count must be at least 1, got {threads}")
    for name in (*THREAD_ENV_VARS, "RGBT_THREADS"):
        os.environ[name] = str(threads)
    if "torch" in sys.modules:
        from rgbt_toolkit.runtime import set_threads

        set_threads(threads)
    else:
        import cv2
        from threadpoolctl import threadpool_limits

        cv2.setNumThreads(threads)
        threadpool_limits(limits=threads)
    _threads_set_in_process = threads


def call_item(fn: Callable[[Any], Any], item: Any, threads: int | None = None) -> Outcome:
    """Run ``fn(item)`` and return its :class:`Outcome`; exceptions (not ``KeyboardInterrupt``) become text."""
    if threads is not None:
        limit_threads(threads)
    start, cpu_start = time.perf_counter(), time.process_time()
    # warnings are recorded, not printed by the worker (with a source line, interleaved with the progress bar);
    # the warning filters are one per process, so a worker running several items on threads (a Dask worker with
    # nthreads > 1) leaves them alone rather than mix up whose warning is whose
    recording = threading.current_thread() is threading.main_thread()
    with warnings.catch_warnings(record=True) if recording else contextlib.nullcontext([]) as caught:
        try:
            value = fn(item)
        except Exception as exc:  # any failure of one item is reported, never allowed to stop the batch
            message = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
            return Outcome(error=f"{type(exc).__name__}: {message}".rstrip(": "), details=traceback.format_exc(),
                           seconds=time.perf_counter() - start, cpu_seconds=time.process_time() - cpu_start,
                           final=isinstance(exc, RgbtError), warnings=_one_line(caught))
    return Outcome(value=value, seconds=time.perf_counter() - start, cpu_seconds=time.process_time() - cpu_start,
                   warnings=_one_line(caught))


def _one_line(caught: list) -> tuple[str, ...]:
    """Recorded warnings as their messages' first lines, each once, in order."""
    lines = []
    for record in caught:
        text = str(record.message).strip()
        line = text.splitlines()[0] if text else record.category.__name__
        if line not in lines:
            lines.append(line)
    return tuple(lines)


class Executor:
    """Runs a function over items; subclasses decide where. Use as a context manager to release resources."""

    name = "executor"
    workers = 1

    def map(self, fn: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[tuple[Any, Outcome]]:
        """Yield ``(item, Outcome)`` for every item, in completion order."""
        raise NotImplementedError

    def close(self) -> None:
        """Release workers or cluster connections; the executor cannot be used afterwards."""

    def abort(self) -> None:
        """Stop at once (Ctrl-C): items still running are abandoned; their outputs are never renamed into place."""
        self.close()

    def describe(self) -> str:
        return f"{self.name} ({self.workers} worker{'s' if self.workers != 1 else ''})"

    def __enter__(self) -> "Executor":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None and not issubclass(exc_type, Exception):  # KeyboardInterrupt, SystemExit
            self.abort()
        else:
            self.close()
